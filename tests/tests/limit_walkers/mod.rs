//! pdw-limit's analysis on the walker models (simplest, rimless, compass, kneed, seed5, spec
//! files), a module per file of the `end_to_end` binary; run one with
//! `cargo test --release --workspace --test end_to_end limit_walkers::<file>::`.

mod attractors_simplest;
mod basin_simplest;
mod cascade_garcia;
mod chain_walker_gaits;
mod codim2;
mod continuation_garcia;
mod design;
mod newton_simplest;
mod orbit_garcia;
mod period_k;
mod rimless_wheel;
mod scan;
mod simplest_gaits;
mod trajectory;
mod validity_continuous;
mod variational_engine;
