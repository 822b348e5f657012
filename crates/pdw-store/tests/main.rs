//! The integration tests of pdw-store, built as one test binary: one link and one set of generic
//! instantiations instead of one per file. Each file is a module; run one with
//! `cargo test --release -p pdw-store --test store <file>::`.

mod basin_file;
mod common;
mod formats;
mod integrity;
mod internals;
mod kill_resume;
mod shard_merge;
mod sweep_and_plots;
