//! The integration tests of pdw-hybrid, built as one test binary: one link and one set of generic
//! instantiations instead of one per file. Each file is a module; run one with
//! `cargo test --release -p pdw-hybrid --test hybrid <file>::`.
//! Built apart (Cargo.toml): `alloc` (counts allocations with its own global allocator).
//! Also run here: the library's internals (`internals`) and pdw-simd's tests (`simd`), so that
//! neither library is compiled a second time for unit tests.

mod batch;
mod common;
mod events;
mod integrator;
mod internals;
mod simd;
