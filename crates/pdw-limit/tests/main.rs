//! The integration tests of pdw-limit, built as one test binary: one link and one set of generic
//! instantiations instead of one per file. Each file is a module; run one with
//! `cargo test --release -p pdw-limit --test limit <file>::`.
//! Built apart (Cargo.toml): `simd_paths` (switches the process-wide instruction-set path).

mod attractors_simplest;
mod basin_measure;
mod basin_simplest;
mod branch_grid;
mod chain_walker_gaits;
mod codim2;
mod continuation_closed_form;
mod continuation_garcia;
mod continuation_maps;
mod continuation_measure;
mod design;
mod internals;
mod orbit_garcia;
mod period_k;
mod rimless_wheel;
mod simplest_gaits;
mod standing_still;
mod trajectory;
mod validity_continuous;
mod variational_engine;
