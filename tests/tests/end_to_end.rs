//! The end-to-end and reference tests, one test binary with a module per file (one link and one
//! set of generic instantiations instead of one per file); run one module with
//! `cargo test --release --workspace --test end_to_end <module>::`. The two tests that change
//! process-wide state (`interrupt`, `simd_paths`) are binaries of their own.

mod compass_closed_form;
mod limit_walkers;
mod round_foot_kneed_reference;
mod seed5_pi;
