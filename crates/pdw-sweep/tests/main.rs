//! The integration tests of pdw-sweep, built as one test binary: one link and one set of generic
//! instantiations instead of one per file. Each file is a module; run one with
//! `cargo test --release -p pdw-sweep --test sweep <file>::`.

mod animate;
mod basin3d;
mod basin_stability;
mod cascade;
mod clear_cli;
mod cli;
mod common;
mod design;
mod explore;
mod follow;
mod formats;
mod hostile;
mod integrator_check;
mod kneed_latched;
mod lock;
mod mfpt;
mod mfpt_over;
mod own_walker;
mod resume_model;
mod safety;
mod search;
mod seed5_latched;
mod self_describing;
mod simulate;
mod sweep_output;
mod units;
