//! "Save": a refined window written as a normal basin file by pdw-store's [`BasinWriter`] (the
//! writer of `pdw-sweep basin`), with its header, provenance, units, metrics and attractors, so
//! that every tool that reads basin files (h5py, `merge`, the explorer itself) reads it. The
//! file name is the server's: `explore-<model>-<nx>x<ny>-<n>.h5` in the save directory, never a
//! path from the page.

use crate::error::ApiError;
use crate::jobs::Refined;
use crate::source::BasinSource;
use pdw::limit::basin::{basin_metrics_slices, DEFAULT_ENTROPY_BOX};
use pdw::store::format::{UnitContext, BASIN};
use pdw::store::{Attractor, BasinHeader, BasinMetrics, BasinWriter};
use std::path::{Path, PathBuf};

/// The header of window `w`: the run's model, integrator and options (the attractor
/// discovery's among them), the window's grid: the header `pdw-sweep basin` writes
/// ([`pdw::basin::file_header`]).
pub fn header(src: &BasinSource, w: &Refined) -> BasinHeader {
    let (r, g) = (&w.rebuilt, &w.grid);
    pdw::basin::file_header(
        (
            format!("pdw-sweep explore: a window of {}", file_name(&src.path)),
            src.data.header.model.clone(),
        ),
        &r.m,
        &r.plan,
        (&r.set, r.seeds),
        pdw::basin::FileGrid {
            x: (g.x.name.clone(), g.x.values.clone()),
            y: (g.y.name.clone(), g.y.values.clone()),
            z: None,
        },
        None,
    )
}

/// The file name of `p` alone (no directories).
fn file_name(p: &Path) -> String {
    p.file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
}

/// A fresh file name in `dir` for window `w`: the first `explore-…-<n>.h5` where nothing
/// exists, a link included (a dangling link is not free: writing through it is refused).
fn fresh_path(dir: &Path, model: &str, nx: usize, ny: usize) -> PathBuf {
    let model: String = model
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    (1..)
        .map(|n| dir.join(format!("explore-{model}-{nx}x{ny}-{n}.h5")))
        .find(|p| std::fs::symlink_metadata(p).is_err())
        .expect("a free name")
}

/// The provenance's options of the window (the integrator as `basin` writes it, so that the
/// saved file can itself be explored and walked).
fn options(w: &Refined) -> serde_json::Value {
    let (r, g) = (&w.rebuilt, &w.grid);
    let o = &r.plan.opts;
    serde_json::json!({
        "integrator": pdw::integrator_json(&o.integrator),
        "max_strides": o.max_strides, "tol_gait": o.tol_gait, "confirm": o.confirm,
        "tol_recur": o.tol_recur, "max_period": o.max_period, "lanes": o.lanes, "chunk": o.chunk,
        "grid": [g.nx(), g.ny()],
        "x": {"name": g.x.name, "lo": g.x.values[0], "hi": g.x.values[g.nx() - 1]},
        "y": {"name": g.y.name, "lo": g.y.values[0], "hi": g.y.values[g.ny() - 1]},
        "overrides": r.overrides.iter().map(|(n, v)| (n.clone(), serde_json::json!(v))).collect::<serde_json::Map<_, _>>(),
        "attractors": r.set.attractors.iter().map(|a| a.name.clone()).collect::<Vec<_>>(),
        "entropy_box": DEFAULT_ENTROPY_BOX,
    })
}

/// Writes window `w` of `src` into `dir`; returns the path written.
pub fn save(src: &BasinSource, w: &Refined, dir: &Path) -> Result<PathBuf, ApiError> {
    let g = &w.grid;
    let (nx, ny) = (g.nx(), g.ny());
    let path = fresh_path(dir, &src.data.header.model, nx, ny);
    // the one claim every writer goes through (pdw::output): the file is not the basin it
    // refines, the directory takes writes, and no other writer holds the name; then handed to
    // the basin writer, which locks it itself
    let mut claim = pdw::output::claim(
        &[pdw::output::Output {
            flag: "save",
            path: &path,
            format: pdw::output::Format::Hdf5,
            may_exist: false,
        }],
        &[pdw::output::Input {
            flag: "the explored file",
            path: &src.path,
        }],
        false,
    )
    .map_err(|e| ApiError::internal(format!("saving: {}", e.0)))?;
    claim.hand_over(&path);
    let failed = |e: pdw::store::StoreError| ApiError::internal(format!("saving: {e}"));
    let h = header(src, w);
    let mut writer = BasinWriter::create(&path, &h, false).map_err(failed)?;
    let mut prov = pdw::provenance(&h.command, &options(w));
    prov.model_spec = w
        .rebuilt
        .m
        .info
        .spec()
        .map(|s| s.to_toml())
        .unwrap_or_default();
    let units = units(w);
    let coordinates = w.rebuilt.m.coordinates_json();
    writer
        .annotate(&pdw::store::Annotations {
            provenance: Some(&prov),
            units: &BASIN.units(&units),
            slice: None,
            scales: &pdw::store::provenance::basin_scales(),
            coordinates: Some(&coordinates),
        })
        .map_err(failed)?;
    writer
        .write_rows(0, &g.outcome, &g.strides, &w.final_state)
        .map_err(failed)?;
    let m = basin_metrics_slices(&g.outcome, nx, ny, 1, DEFAULT_ENTROPY_BOX)
        .map_err(|e| ApiError::internal(format!("metrics: {e}")))?;
    let defined = nx >= m.box_size && ny >= m.box_size;
    let or_nan = |v: f64| if defined { v } else { f64::NAN };
    let metrics = BasinMetrics {
        fractions: h
            .legend
            .iter()
            .map(|(c, n)| {
                let f = m.fractions.iter().find(|f| f.0 == *c).map_or(0.0, |f| f.2);
                (n.clone(), f)
            })
            .collect(),
        basin_entropy: or_nan(m.basin_entropy),
        boundary_entropy: or_nan(m.boundary_entropy),
        entropy_box: m.box_size,
    };
    let attractors: Vec<Attractor> = w
        .rebuilt
        .set
        .attractors
        .iter()
        .map(pdw::basin::store_attractor)
        .collect();
    writer.finish(&metrics, &attractors).map_err(failed)?;
    pdw::store::annotate(
        &path,
        &pdw::store::Annotations {
            provenance: None,
            units: &BASIN.units(&units),
            slice: None,
            scales: &[],
            coordinates: None,
        },
    )
    .map_err(failed)?;
    Ok(path)
}

/// The units of the saved file ([`pdw::store::format::BASIN`]'s rules, as `basin` labels them).
fn units(w: &Refined) -> UnitContext {
    let names = &w.rebuilt.m.info.section_names;
    let axis = |n: &str| names.iter().position(|s| s == n).unwrap_or(usize::MAX);
    let axes = [axis(&w.grid.x.name), axis(&w.grid.y.name)];
    pdw::basin::file_units(&w.rebuilt.m, &axes)
}
