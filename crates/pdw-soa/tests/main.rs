//! The integration tests of pdw-soa, built as one test binary: one link and one set of generic
//! instantiations instead of one per file. Each file is a module; run one with
//! `cargo test --release -p pdw-soa --test soa <file>::`.
//! The binary's global allocator (`derivatives`) counts allocations per thread, so that the
//! allocation checks there see only their own thread's; the library's internals run here too
//! (`internals`).

mod batch_equals_scalar;
mod common;
mod constraints;
mod derivatives;
mod dynamics_agree;
mod errors;
mod internals;
mod kinematics_energy;
mod unilateral;
