//! Sweep and continuation files (`pdw-sweep fixedpoint --sweep`): the branches as a
//! bifurcation diagram, and a branch point's gait — its multipliers and a walk of a few periods
//! from its section state, by the file's model at that parameter value.

use crate::error::ApiError;
use pdw::store::SweepData;
use serde_json::{json, Value};
use std::path::Path;

/// Periods of a branch point's orbit the walk shows.
pub const PERIODS_WALKED: usize = 4;

/// Reads the sweep file at `path`.
pub fn load(path: &Path) -> Result<SweepData, ApiError> {
    pdw::store::read_sweep(path).map_err(|e| ApiError::unprocessable(e.to_string()))
}

/// The page's JSON of the branches (parameter, section states, stability, multipliers, period).
pub fn to_json(d: &SweepData) -> Value {
    let branches: Vec<Value> = d
        .branches
        .iter()
        .map(|b| {
            json!({"name": b.name, "period_strides": b.period_strides, "parameter": b.parameter,
                   "section": b.section, "stable": b.stable, "period": b.period,
                   "multipliers": b.multipliers})
        })
        .collect();
    json!({"kind": "sweep", "model": d.model, "parameter": d.parameter,
           "section_names": d.section_names, "branches": branches})
}

/// The gait at point `i` of branch `branch`: the model rebuilt at that parameter value (the
/// file's other parameters), and a walk of [`PERIODS_WALKED`] periods from its section state
/// with `simulate`'s integrator. `spec`: the file's resolved walker spec, if it records one.
pub fn gait(d: &SweepData, spec: Option<&str>, branch: usize, i: usize) -> Result<Value, ApiError> {
    let b = d.branches.get(branch).ok_or_else(|| {
        ApiError::not_found(format!("no branch {branch} of {}", d.branches.len()))
    })?;
    if i >= b.parameter.len() {
        return Err(ApiError::not_found(format!(
            "no point {i} on branch '{}' ({} points)",
            b.name,
            b.parameter.len()
        )));
    }
    let params: serde_json::Map<String, Value> = serde_json::from_str(&d.params)
        .map_err(|_| ApiError::unprocessable("the file's params attribute is not a JSON object"))?;
    let mut ov: Vec<(String, f64)> = params
        .iter()
        .filter(|(n, _)| **n != d.parameter)
        .filter_map(|(n, v)| Some((n.clone(), v.as_f64()?)))
        .collect();
    ov.push((d.parameter.clone(), b.parameter[i]));
    let m = pdw::build_recorded(&d.model, spec, &ov)
        .map_err(|e| ApiError::unprocessable(format!("the file's model '{}': {}", d.model, e.0)))?;
    let steps = PERIODS_WALKED * b.period_strides.max(1) as usize;
    let integ = pdw::simulate::default_integrator();
    let tr = crate::walk::walk_model(&m, integ, &b.section[i], steps)?;
    Ok(json!({
        "branch": b.name, "point": i, "parameter": d.parameter, "value": b.parameter[i],
        "section": b.section[i], "section_names": d.section_names, "stable": b.stable[i],
        "multipliers": b.multipliers[i], "period": b.period[i],
        "period_strides": b.period_strides,
        "walk": crate::walk::walk_json(&m, &tr),
    }))
}
