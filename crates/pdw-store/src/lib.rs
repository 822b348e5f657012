//! HDF5 files and plots for pdw-sweep.
//!
//! * [`basin`]: the basin-of-attraction file (`pdw-sweep basin`): written row block by row block
//!   as the grid is computed, flushed after each block, resumable after a kill, split into
//!   shards and merged back ([`shard`]).
//! * [`sweep`]: the parameter-continuation file (`pdw-sweep fixedpoint --sweep`): branches of
//!   fixed points, their Floquet multipliers and stability, detected bifurcations and an optional
//!   brute-force orbit diagram.
//! * [`stability`]: basin stability over a parameter (`pdw-sweep basin --over`): per value, the
//!   fraction of one box of initial conditions reaching each attractor.
//! * [`curve`]: the two-parameter bifurcation-curve file (`pdw-sweep fixedpoint --follow`): the
//!   curve's points, the critical gait at each, and an optional region map of the plane.
//! * [`trajectory`]: time series of a simulated walk (`pdw-sweep simulate`), HDF5 or CSV.
//! * [`plot`]: PNG heatmaps of basins, two-panel bifurcation diagrams, line charts (log axes for
//!   work-precision charts) and animated GIFs of a gait, drawn with `plotters`' pure-Rust bitmap
//!   backend and an embedded DejaVu font (no system libraries).
//!
//! # Boundary
//! This crate does not depend on the dynamics crates. It defines plain result types
//! ([`BasinHeader`], [`BasinMetrics`], [`Attractor`], [`SweepData`], [`Frame`]) that the CLI fills
//! from the limit-cycle crate's results. That keeps the one crate linking HDF5 (a C library built
//! from source) off the critical path of the numerical crates: both build in parallel, and the
//! kernel's tests never wait for HDF5. Plots take the same plain types, so they can be redrawn
//! from a file without linking the kernel.
//!
//! # File formats
//! Every format is declared once, in [`format`]: each dataset and attribute with its type,
//! unit, meaning and the digest covering it ([`format::BASIN`], …). The `units` attributes are
//! written from it ([`format::Format::units`]) and `docs/hdf5.md`'s tables are generated from it.
//!
//! A 3-D grid ([`BasinHeader::z`]) adds `/grid/z` (f64 `[nz]`, attr `name`; the scale of
//! dimension 0) and stores its cells in z, y, x order: outcome and strides [nz, ny, nx], final
//! [nz, ny, nx, d], chunked by blocks of [`BLOCK_ROWS`] rows within one z-slice; rows_done is
//! [nz·ny] and block_digest [nz·⌈ny/16⌉] over the grid's (z, y) rows, row `k·ny + i` for
//! `(z[k], y[i])`. `/slice` then also records the z-slice the picture draws (attrs `z`,
//! `z_index`, `z_value`; dataset `outcome` [ny, nx]; see
//! [`provenance::write_slice_view`]).
//! Every dataset carries a `units` attribute (written by the caller through
//! [`provenance::annotate`] with [`format::Format::units`]: the writers do not know the model).
//! `outcome`, `strides` and `final` are chunked by blocks of [`BLOCK_ROWS`] rows and
//! deflate-compressed (`strides` and `final` byte-shuffled first). Row `i` of every 2-D dataset
//! belongs to `y[i]`, column `j` to `x[j]`. Files are created with HDF5's file-space strategy
//! `NONE` (see [`basin`] on crash safety), which HDF5 ≥ 1.10 reads (checked with h5py 3.16 /
//! HDF5 2.0 and Debian's h5dump 1.10.8); `experiments/read_basin.py` reads and checks a file
//! with h5py.
//!
//! # Example
//! ```no_run
//! use pdw_store::{BasinHeader, BasinMetrics, BasinWriter};
//! # fn header() -> BasinHeader { unimplemented!() }
//! # fn compute_row(i: usize) -> (Vec<u8>, Vec<u16>, Vec<f64>) { unimplemented!() }
//! let h: BasinHeader = header();
//! let mut w = BasinWriter::create("basin.h5", &h, false)?; // or BasinWriter::resume(path, &h)
//! for i in w.rows_todo() {
//!     let (outcome, strides, final_state) = compute_row(i); // nx, nx, nx·d values
//!     w.write_rows(i, &outcome, &strides, &final_state)?;
//! }
//! let outcome = w.read_outcome()?; // (ny × nx), for the metrics
//! # let metrics: BasinMetrics = unimplemented!();
//! w.finish(&metrics, &[])?;
//! # Ok::<(), pdw_store::StoreError>(())
//! ```

pub mod basin;
/// The ndarray crate of the arrays read and written here.
pub use ndarray;
pub mod curve;
pub mod design;
mod error;
pub mod format;
mod h5util;
pub mod mfpt;
pub mod mfpt_over;
pub mod plot;
pub mod provenance;
pub mod shard;
pub mod stability;
pub mod sweep;
mod time;
#[doc(hidden)] // pub for the crate's tests (tests/internals.rs), not part of the API
pub use time::rfc3339;
pub mod trajectory;

pub use basin::{
    read_basin, read_basin_header, read_basin_outcome, Attractor, BasinData, BasinHeader,
    BasinMetrics, BasinWriter, OrbitCheck, ZAxis, BLOCK_ROWS, NOT_COMPUTED,
};
pub use curve::{plot_curve, read_curve_points, write_curve, CurveData, RegionMap, CURVE_FORMAT};
pub use design::{
    read_design, read_design_commands, write_design, write_design_annotated, DesignData,
    DESIGN_FORMAT,
};
pub use error::StoreError;
pub use h5util::{check_input, read_text_input, remove_stale_partials, MAX_TEXT_INPUT};
pub use mfpt::{
    read_mfpt, read_mfpt_curve, write_mfpt, write_mfpt_curve, MfptCurveData, MfptData,
    MFPT_CURVE_FORMAT, MFPT_FORMAT,
};
pub use mfpt_over::{read_mfpt_over, write_mfpt_over, MfptOverData};
pub use plot::{
    animate_gif, invalid_reasons, outcome_colours, plot_basin, plot_basin_attractors,
    plot_basin_stability, plot_bifurcation, plot_lines, plot_lines_marked, Frame, MarkerShape,
    Markers,
};
pub use provenance::{annotate, annotate_file, Annotations, Provenance, ScaleAttach, Slice};
pub use shard::{grid_shard_rows, merge, shard_rows, ShardSpec};
pub use stability::{
    read_stability, write_stability, StabilityAttractor, StabilityData, STABILITY_FORMAT,
};
pub use sweep::{
    binding_name, read_sweep, sweep_csv_columns, sweep_json, write_sweep, write_sweep_csv,
    Bifurcation, Branch, OrbitDiagram, StrideValidity, SweepData, BINDING_CRITERIA,
};
pub use trajectory::{
    read_trajectory_h5, write_trajectory_csv, write_trajectory_h5, TrajColumn, TrajEvents,
    TrajectoryData, TRAJECTORY_FORMAT,
};

/// Result type of this crate.
pub type Result<T> = std::result::Result<T, StoreError>;

/// The first line in which two multi-line texts differ (e.g. two resolved models), as
/// `(found, expected)` with an empty string for a missing line; `None` if they are equal.
pub fn first_line_difference(found: &str, expected: &str) -> Option<(String, String)> {
    let (mut f, mut e) = (found.lines(), expected.lines());
    loop {
        match (f.next(), e.next()) {
            (None, None) => return None,
            (a, b) if a == b => continue,
            (a, b) => return Some((a.unwrap_or("").to_string(), b.unwrap_or("").to_string())),
        }
    }
}
