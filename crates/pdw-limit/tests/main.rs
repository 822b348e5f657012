//! The integration tests of pdw-limit on model-free systems (closed-form maps, a mass on a
//! spring, the crate's helpers), built as one test binary. Run one file with
//! `cargo test --release --workspace --test limit <file>::`. The analysis on the walker models
//! (simplest, rimless, compass, kneed, seed5) is tested in the workspace's `tests` crate
//! (`--test limit_walkers`), so that this crate depends on no model catalogue.

mod branch_grid;
mod cloud;
mod continuation_closed_form;
mod continuation_maps;
mod internals;
mod section_frame;
mod standing_still;
