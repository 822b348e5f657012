//! The integration tests of pdw-walkers, built as one test binary: one link and one set of generic
//! instantiations instead of one per file. Each file is a module; run one with
//! `cargo test --release -p pdw-walkers --test walkers <file>::`.
//! Built apart (Cargo.toml): `chain_walker_alloc` (counts allocations with its own global allocator).

mod chain_common;
mod chain_walker;
mod common;
mod compass;
mod impacts;
mod internals;
mod kneed;
mod rimless_physics;
mod round_feet;
mod seed5;
mod simplest_physics;
mod simplest_trajectory;
mod step_down;
mod units;
