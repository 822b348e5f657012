//! The integration tests of pdw-soa, built as one test binary: one link and one set of generic
//! instantiations instead of one per file. Each file is a module; run one with
//! `cargo test --release -p pdw-soa --test soa <file>::`.
//! Built apart (Cargo.toml): `derivatives` (counts allocations with its own global allocator).

mod batch_equals_scalar;
mod common;
mod constraints;
mod dynamics_agree;
mod errors;
mod kinematics_energy;
mod unilateral;
