//! The integration tests of pdw-hybrid, built as one test binary: one link and one set of generic
//! instantiations instead of one per file. Each file is a module; run one with
//! `cargo test --release -p pdw-hybrid --test hybrid <file>::`.
//! Built apart (Cargo.toml): `alloc` (counts allocations with its own global allocator).

mod batch;
mod common;
mod events;
mod integrator;
