//! A basin file as the explorer serves it, and its run rebuilt from the file alone.
//!
//! The file is read with pdw-store's own readers ([`pdw::store::read_basin`], the run's
//! provenance and `coordinates`); a shard reads as its part (rows it does not own are
//! `not_computed`). The run is rebuilt the way `pdw-sweep basin` builds it: the model by name
//! with the file's parameters ([`pdw::build`]), the integrator from the provenance's
//! `integrator` object through [`pdw::integrator()`] on the basin's default, the stride budget,
//! the axes and the fixed coordinates from the header, then the same [`BasinPlan`], gait search
//! and attractor discovery. Discovery seeds are fixed, so the attractors and the legend come
//! out as the file's; [`rebuild`] checks that (and the grid values, bit for bit) and refuses a
//! file it cannot reproduce.

use crate::error::ApiError;
use pdw::basin::{Axis, AxisFlags, BasinPlan, BasinRequest};
use pdw::input::AxisRange;
use pdw::limit::basin::BasinOptions;
use pdw::limit::AttractorSet;
use pdw::store::{BasinData, BasinHeader};
use pdw::BuiltModel;
use std::path::{Path, PathBuf};

/// Axis names in the explorer's messages.
pub const FLAGS: AxisFlags = AxisFlags {
    x: "x",
    y: "y",
    z: "z",
};

/// A basin file read whole, with what the page needs to label it.
pub struct BasinSource {
    pub path: PathBuf,
    pub data: BasinData,
    /// Units of the x, y (and z) axes (`grid/x`, `grid/y`, `grid/z` `units`).
    pub units: Vec<String>,
    /// The `coordinates` attribute: state name → meaning.
    pub coordinates: serde_json::Value,
    /// The provenance's `options` (every numerical option of the run).
    pub options: serde_json::Value,
    /// The provenance's resolved walker spec (`model_spec`), which rebuilds a user's own walker
    /// without its spec file; `None` for closed-form models and older files.
    pub model_spec: Option<String>,
}

/// Reads the basin file at `path`; a file that is not one (or is damaged) is a clear error.
pub fn load(path: &Path) -> Result<BasinSource, ApiError> {
    // The store's messages name the file already.
    let bad = ApiError::unprocessable;
    let data = pdw::store::read_basin(path).map_err(|e| bad(e.to_string()))?;
    let (prov, coords) =
        pdw::store::provenance::read_run_description(path).map_err(|e| bad(e.to_string()))?;
    let options = prov
        .as_ref()
        .map(|p| serde_json::from_str(&p.options).unwrap_or_default())
        .unwrap_or_default();
    let model_spec = prov.map(|p| p.model_spec).filter(|s| !s.is_empty());
    let coordinates = coords
        .and_then(|c| serde_json::from_str(&c).ok())
        .unwrap_or_else(|| serde_json::json!({}));
    let mut units = Vec::new();
    let axes = if data.header.z.is_some() {
        &["grid/x", "grid/y", "grid/z"][..]
    } else {
        &["grid/x", "grid/y"][..]
    };
    for ds in axes {
        let u = pdw::store::provenance::read_units(path, ds).map_err(|e| bad(e.to_string()))?;
        units.push(u.unwrap_or_default());
    }
    Ok(BasinSource {
        path: path.to_path_buf(),
        data,
        units,
        coordinates,
        options,
        model_spec,
    })
}

/// A basin run rebuilt: the model, the plan of its box and the attractors.
pub struct Rebuilt {
    pub m: BuiltModel,
    pub req: BasinRequest,
    pub plan: BasinPlan,
    pub set: AttractorSet,
    /// Parameter overrides on top of the file's (the page's sliders).
    pub overrides: Vec<(String, f64)>,
    /// Seeds the attractor discovery tried (the header's `attractor_seeds`).
    pub seeds: usize,
}

/// The model of header `h` (from the file's resolved spec `spec` where it records one,
/// [`pdw::build_recorded`]) with its parameters, then `extra` on top.
pub fn model(
    h: &BasinHeader,
    spec: Option<&str>,
    extra: &[(String, f64)],
) -> Result<BuiltModel, ApiError> {
    let params: serde_json::Map<String, serde_json::Value> = serde_json::from_str(&h.params)
        .map_err(|_| ApiError::unprocessable("the file's params attribute is not a JSON object"))?;
    let mut ov: Vec<(String, f64)> = params
        .iter()
        .filter_map(|(n, v)| Some((n.clone(), v.as_f64()?)))
        .filter(|(n, _)| !extra.iter().any(|(e, _)| e == n))
        .collect();
    ov.extend_from_slice(extra);
    pdw::build_recorded(&h.model, spec, &ov).map_err(|e| {
        ApiError::unprocessable(format!(
            "the file's model '{}' cannot be built here: {}",
            h.model, e.0
        ))
    })
}

/// The cells' integrator from the provenance's `integrator` object, through the CLI's route
/// ([`pdw::integrator()`] on [`BasinOptions::default_integrator`]).
pub fn integrator(options: &serde_json::Value) -> Result<pdw::hybrid::Options, ApiError> {
    let j = &options["integrator"];
    let method = j["method"].as_str().ok_or_else(|| {
        ApiError::unprocessable("the file has no provenance integrator; it cannot be rebuilt")
    })?;
    let rk4 = method == "rk4";
    let choice = pdw::IntegratorChoice {
        integrator: Some(method.to_string()),
        rtol: if rk4 { None } else { j["rtol"].as_f64() },
        atol: if rk4 { None } else { j["atol"].as_f64() },
        rk4_step: if rk4 { j["h"].as_f64() } else { None },
        cold_restarts: !j["warm_restart"].as_bool().unwrap_or(false),
        controller: j["controller"].as_str().map(str::to_string),
    };
    pdw::integrator(&choice, BasinOptions::default_integrator())
        .map_err(|e| ApiError::unprocessable(format!("the file's integrator: {}", e.0)))
}

/// Axis `name` over `lo..=hi` resolved against the model's section.
fn axis(m: &BuiltModel, name: &str, lo: f64, hi: f64, flag: &str) -> Result<Axis, ApiError> {
    let range = AxisRange {
        name: name.to_string(),
        lo,
        hi,
    };
    pdw::basin::resolve_axis(&m.info, Some(range), flag)
        .map_err(|e| ApiError::bad_request(e.0))?
        .ok_or_else(|| ApiError::bad_request(format!("{flag}: no axis")))
}

/// What a rebuild is asked for: the file's box, or a box of it (`window`) at another
/// resolution, a 3-D file's slice held fixed, and parameter overrides.
#[derive(Clone, Debug, Default)]
pub struct Window {
    /// `(x_lo, x_hi, y_lo, y_hi)`; `None`: the file's own box.
    pub bounds: Option<(f64, f64, f64, f64)>,
    /// Cells along x and y of a box.
    pub grid: Option<(usize, usize)>,
    /// The z value a box of a 3-D file holds fixed.
    pub z_fixed: Option<f64>,
    pub overrides: Vec<(String, f64)>,
}

/// The request of `src`'s run, or of `w`'s box of it.
fn request(src: &BasinSource, m: &BuiltModel, w: &Window) -> Result<BasinRequest, ApiError> {
    let h = &src.data.header;
    let (x0, x1) = (h.x[0], h.x[h.nx() - 1]);
    let (y0, y1) = (h.y[0], h.y[h.ny() - 1]);
    let (xl, xh, yl, yh) = w.bounds.unwrap_or((x0, x1, y0, y1));
    let names = &m.info.section_names;
    let fixed_json = serde_json::from_str::<serde_json::Value>(&h.tolerances)
        .map(|t| t["fixed"].clone())
        .unwrap_or_default();
    let mut fixed = Vec::new();
    if let Some(obj) = fixed_json.as_object() {
        for (n, v) in obj {
            let i = names.iter().position(|s| s == n).ok_or_else(|| {
                ApiError::unprocessable(format!("the file fixes '{n}', not a coordinate"))
            })?;
            fixed.push((i, v.as_f64().unwrap_or(f64::NAN)));
        }
    }
    let mut z = None;
    if let Some(za) = &h.z {
        let (zl, zh) = (za.values[0], za.values[za.values.len() - 1]);
        match w.z_fixed {
            Some(v) => {
                let iz = axis(m, &za.name, zl, zh, "z")?.index;
                fixed.push((iz, v));
            }
            None => z = Some((axis(m, &za.name, zl, zh, "z")?, za.values.len())),
        }
    }
    Ok(BasinRequest {
        grid: w.grid.unwrap_or((h.nx(), h.ny())),
        x: Some(axis(m, &h.x_name, xl, xh, "x")?),
        y: Some(axis(m, &h.y_name, yl, yh, "y")?),
        z,
        fixed,
        max_strides: u16::try_from(h.max_strides).unwrap_or(u16::MAX),
        integrator: integrator(&src.options)?,
    })
}

/// The run of `src` (or of window `w` of it) rebuilt on `pool`: model, plan, gaits and
/// attractors, as `pdw-sweep basin` makes them.
pub fn rebuild(
    src: &BasinSource,
    w: &Window,
    pool: &rayon::ThreadPool,
) -> Result<Rebuilt, ApiError> {
    rebuild_with(src, w, pool, &|_| true).map(|r| r.expect("a rebuild told to go on finishes"))
}

/// [`rebuild`], asking `go_on` as the gait search and the attractor discovery start and once
/// they end (`false`: stop there, `None`).
pub fn rebuild_with(
    src: &BasinSource,
    w: &Window,
    pool: &rayon::ThreadPool,
    go_on: &dyn Fn(crate::jobs::Phase) -> bool,
) -> Result<Option<Rebuilt>, ApiError> {
    use crate::jobs::Phase;
    let m = model(&src.data.header, src.model_spec.as_deref(), &w.overrides)?;
    let req = request(src, &m, w)?;
    let failed = |e: pdw::limit::LimitError| ApiError::internal(format!("gait search: {e}"));
    if !go_on(Phase::GaitSearch) {
        return Ok(None);
    }
    let gaits = pdw::basin::find_gaits(&m).map_err(failed)?;
    let centre = pdw::basin::grid_centre(&m, &gaits, true)
        .ok_or_else(|| ApiError::unprocessable("the model has no guess to centre on"))?;
    let bx = pdw::basin::choose_box(&req, &m.info.section_names, &centre, FLAGS, "box")
        .map_err(|e| ApiError::bad_request(e.0))?;
    let plan = BasinPlan::new(&req, bx, gaits, centre);
    if !go_on(Phase::Attractors) {
        return Ok(None);
    }
    let (set, seeds) = plan
        .attractors(&m, pool)
        .map_err(|e| ApiError::internal(format!("attractor discovery: {e}")))?;
    Ok(Some(Rebuilt {
        m,
        req,
        plan,
        set,
        overrides: w.overrides.clone(),
        seeds,
    }))
}

/// Refuses a rebuild of the file's own box that does not reproduce its grid and legend.
pub fn check_same_run(src: &BasinSource, r: &Rebuilt) -> Result<(), ApiError> {
    let h = &src.data.header;
    let bits = |a: &[f64], b: &[f64]| {
        a.len() == b.len() && a.iter().zip(b).all(|(u, v)| u.to_bits() == v.to_bits())
    };
    if !bits(&r.plan.xs, &h.x) || !bits(&r.plan.ys, &h.y) {
        return Err(ApiError::unprocessable(
            "the file's grid values are not those its axes give (edited or foreign file); \
             its cells cannot be walked",
        ));
    }
    if r.set.legend() != h.legend {
        return Err(ApiError::unprocessable(format!(
            "the attractors found again ({}) differ from the file's legend; its cells cannot \
             be walked with this build",
            r.set
                .legend()
                .iter()
                .map(|(_, n)| n.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    Ok(())
}
