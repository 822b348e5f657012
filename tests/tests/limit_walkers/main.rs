//! pdw-limit's analysis on the walker models (simplest, rimless, compass, kneed, seed5, spec
//! files), built as one test binary: one link and one set of generic instantiations instead of
//! one per file. Each file is a module; run one with
//! `cargo test --release --workspace --test limit_walkers <file>::`.
//! Built apart: `simd_paths` (switches the process-wide instruction-set path).

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
