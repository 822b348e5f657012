//! "Save": a refined window written as a normal basin file by pdw-store's [`BasinWriter`] (the
//! writer of `pdw-sweep basin`), with its header, provenance, units, metrics and attractors, so
//! that every tool that reads basin files (h5py, `merge`, the explorer itself) reads it. The
//! file name is the server's: `explore-<model>-<nx>x<ny>-<n>.h5` in the save directory, never a
//! path from the page.

use crate::error::ApiError;
use crate::jobs::Refined;
use crate::source::BasinSource;
use pdw::limit::basin::{basin_metrics_slices, DEFAULT_ENTROPY_BOX};
use pdw::store::{Attractor, BasinHeader, BasinMetrics, BasinWriter};
use std::path::{Path, PathBuf};

/// The header of window `w`: the run's model, integrator and options (the attractor
/// discovery's among them, as `pdw-sweep basin` writes them), the window's grid.
pub fn header(src: &BasinSource, w: &Refined) -> BasinHeader {
    let (r, g) = (&w.rebuilt, &w.grid);
    let disc = pdw::limit::attractors::DiscoveryOptions::default();
    let h = &src.data.header;
    let opts = &r.plan.opts;
    let names = &r.m.info.section_names;
    let fixed: serde_json::Map<String, serde_json::Value> = r
        .plan
        .fixed
        .iter()
        .map(|(i, v)| (names[*i].clone(), serde_json::json!(v)))
        .collect();
    BasinHeader {
        command: format!("pdw-sweep explore: a window of {}", file_name(&src.path)),
        model: h.model.clone(),
        slope: r.m.slope(),
        params: r.m.params_json().to_string(),
        model_resolved: r.m.walker.fingerprint(),
        integrator: pdw::integrator_text(&opts.integrator),
        tolerances: serde_json::json!({
            "rtol": opts.integrator.rtol, "atol": opts.integrator.atol,
            "tol_gait": opts.tol_gait, "tol_recur": opts.tol_recur,
            "confirm": opts.confirm, "max_period": opts.max_period,
            "fixed_point_residual": r.plan.gait().map(|fp| fp.residual),
            "attractor_seeds": r.seeds, "seed_strides": disc.seed_strides,
            "chaos_radius": disc.chaos_radius, "chaos_sample": disc.cloud_points,
            "fixed": fixed,
        })
        .to_string(),
        max_strides: u32::from(opts.max_strides),
        x_name: g.x.name.clone(),
        x: g.x.values.clone(),
        y_name: g.y.name.clone(),
        y: g.y.values.clone(),
        z: None,
        state_names: names.clone(),
        legend: r.set.legend(),
        shard: None,
    }
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
    let units = units(src, &w.rebuilt);
    let coordinates = w.rebuilt.m.coordinates_json();
    writer
        .annotate(&pdw::store::Annotations {
            provenance: Some(&prov),
            units: &units,
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
            units: &units,
            slice: None,
            scales: &[],
            coordinates: None,
        },
    )
    .map_err(failed)?;
    Ok(path)
}

/// The unit of every dataset of the saved file, by path (as `basin` labels them).
fn units(src: &BasinSource, r: &crate::source::Rebuilt) -> impl Fn(&str) -> Option<String> {
    let sec = pdw::model::section_units(&r.m);
    let list = pdw::model::units_list(&sec);
    let (ux, uy) = (
        src.units.first().cloned().unwrap_or_default(),
        src.units.get(1).cloned().unwrap_or_default(),
    );
    move |p: &str| match p {
        "grid/x" => Some(ux.clone()),
        "grid/y" => Some(uy.clone()),
        "basin/outcome" | "basin/strides" | "basin/rows_done" | "basin/block_digest" => {
            Some("1".into())
        }
        "basin/final" => Some(list.clone()),
        _ if p.starts_with("attractors/") && p.ends_with("/section") => Some(list.clone()),
        _ if p.starts_with("attractors/") && p.contains("/multipliers_") => Some("1".into()),
        _ => None,
    }
}
