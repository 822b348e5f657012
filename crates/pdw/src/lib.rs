//! The library under both front ends (the `pdw-sweep` CLI and the Python package): what a run
//! needs before and around the analysis — building a model by name or spec file with its
//! parameter overrides ([`model`]), reading the values people type ([`input`]), choosing the
//! integrator ([`integrator()`]) and finding the gaits to start from ([`gaits`]) — and the
//! computations of the runs themselves, as typed plans and their steps: a basin of attraction
//! ([`basin`]), basin stability over a parameter ([`basin_over`]), a continuation over a
//! parameter grid and its orbit diagram ([`sweep`]), a bifurcation curve in two parameters
//! ([`follow`]), a design search ([`design`]), a walk of N steps ([`simulate`]), the animation
//! of a gait ([`animate`]), the linear stability data of a gait ([`linear`]). A front end parses its own syntax into
//! these types and prints, writes or returns the results; it builds no model, checks no range and
//! names nothing on its own.

pub mod animate;
pub mod animate_trajectory;
pub mod basin;
pub mod basin_over;
pub mod design;
pub mod design_command;
pub mod disturb;
pub mod follow;
pub mod gaits;
pub mod gsn;
pub mod input;
pub mod integrator;
pub mod linear;
pub mod memory;
pub mod mfpt;
pub mod mfpt_over;
pub mod model;
pub mod output;
pub mod pipeline;
pub mod simulate;
pub mod simulate_file;
pub mod sweep;
pub mod validity;

// The crates under this one, re-exported: every front end (the CLI, the explorer, the Python
// package) depends on `pdw` alone and names their items as `pdw::store::…`, `pdw::limit::…` and
// so on — one dependency for every front end, one version of each crate they see.
// `tools/check-front-end-deps` fails when a front end depends on one of them directly.

/// The hybrid-system integrator and its events (`pdw-hybrid`).
pub use pdw_hybrid as hybrid;
/// Fixed points, continuation, basins and trajectories (`pdw-limit`).
pub use pdw_limit as limit;
/// The SIMD path chosen at run time and the numeric contract (`pdw-simd`).
pub use pdw_simd as simd;
/// The HDF5 files, their provenance and the plots (`pdw-store`).
pub use pdw_store as store;
/// The walker models and their spec files (`pdw-walkers`).
pub use pdw_walkers as walkers;

pub use input::InputError;
pub use integrator::{integrator, integrator_json, integrator_text, IntegratorChoice};
pub use model::{build, build_model, build_recorded, build_with, BuiltModel, ModelChoice};

/// A run's provenance: build (version, commit, profile), the SIMD path chosen at run time and
/// the numeric contract all paths keep, host, `command` (the command line, or the Python call)
/// and `options` (every numerical option of the run, a JSON object).
pub fn provenance(command: &str, options: &serde_json::Value) -> pdw_store::Provenance {
    let mut p = pdw_store::Provenance::new(command, pdw_simd::path().name(), options);
    p.numerics = pdw_simd::NUMERICS.to_string();
    p
}
