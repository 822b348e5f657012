//! Design-search files (`pdw-sweep design`): the designs table (the free parameters, the
//! status in the search picture's legend words, every measure the file stores, the gait's
//! section state, each with its units), and a design's gait walked — the model rebuilt as the
//! search built it (the file's fixed values with the design's free values on top,
//! [`pdw::design::search`]) and a few strides simulated from the stored gait.

use crate::error::ApiError;
use pdw::store::DesignData;
use serde_json::{json, Value};
use std::path::Path;

/// Strides of a design's gait the walk shows.
pub const STRIDES_WALKED: usize = 4;

/// A design file read whole, with the units of its datasets.
pub struct DesignFile {
    pub data: DesignData,
    /// Units of each free parameter (in `free_names`' order).
    pub param_units: Vec<String>,
    /// Units of each section coordinate.
    pub section_units: Vec<String>,
    /// Units of each measure column (in `data.columns`' order).
    pub column_units: Vec<String>,
    /// The file's resolved walker spec (`/provenance/model_spec`), if it records one: a design
    /// of a user's own walker walks without its spec file.
    pub model_spec: Option<String>,
}

/// A JSON list of units as the file stores them (`["rad","rad/s"]`), or `n` empty ones.
fn units_list(path: &Path, ds: &str, n: usize) -> Vec<String> {
    pdw::store::provenance::read_units(path, ds)
        .ok()
        .flatten()
        .and_then(|u| serde_json::from_str::<Vec<String>>(&u).ok())
        .filter(|u| u.len() == n)
        .unwrap_or_else(|| vec![String::new(); n])
}

/// Reads the design file at `path`: every measure of [`pdw::design::COLUMNS`] it holds.
pub fn load(path: &Path) -> Result<DesignFile, ApiError> {
    let present: Vec<&str> = pdw::design::COLUMNS
        .iter()
        .copied()
        .filter(|c| pdw::store::provenance::read_units(path, c).is_ok())
        .collect();
    let data = pdw::store::read_design(path, &present)
        .map_err(|e| ApiError::unprocessable(e.to_string()))?;
    let column_units = present
        .iter()
        .map(|c| {
            pdw::store::provenance::read_units(path, c)
                .ok()
                .flatten()
                .unwrap_or_default()
        })
        .collect();
    Ok(DesignFile {
        param_units: units_list(path, "params", data.free_names.len()),
        section_units: units_list(path, "section", 3),
        column_units,
        data,
        model_spec: pdw::store::provenance::read_model_spec(path).ok().flatten(),
    })
}

/// The search's settings as JSON (model, fixed values, objective …).
fn settings(d: &DesignData) -> Result<serde_json::Map<String, Value>, ApiError> {
    serde_json::from_str(&d.settings)
        .map_err(|_| ApiError::unprocessable("the file's settings attribute is not a JSON object"))
}

/// A status code in the words of the search picture's legend (`no gait`, `bad model`).
pub fn status_word(d: &DesignData, code: u8) -> String {
    d.status_names
        .get(code as usize)
        .map_or_else(|| format!("code {code}"), |n| n.replace('_', " "))
}

/// The model's section coordinate names, or `section 0..2` when the model does not build.
fn section_names(model: &str, spec: Option<&str>, fixed: &[(String, f64)]) -> Vec<String> {
    pdw::build_recorded(model, spec, fixed)
        .map(|m| m.info.section_names.iter().map(|s| s.to_string()).collect())
        .unwrap_or_else(|_| (0..3).map(|i| format!("section {i}")).collect())
}

/// The page's JSON of the designs table: one column per free parameter, the status, one per
/// measure and one per section coordinate (`gait <name>`), each `{name, units, values}`
/// (NaN → null), the status codes and their legend words, and each design's reason.
pub fn to_json(f: &DesignFile) -> Result<Value, ApiError> {
    let d = &f.data;
    let s = settings(d)?;
    let model = s.get("model").and_then(Value::as_str).unwrap_or_default();
    let fixed = fixed_values(&s);
    let col = |name: String, units: &str, values: Vec<f64>| json!({"name": name, "units": units, "values": values});
    let mut columns: Vec<Value> = d
        .free_names
        .iter()
        .enumerate()
        .map(|(k, n)| {
            col(
                n.clone(),
                &f.param_units[k],
                d.params.iter().map(|p| p[k]).collect(),
            )
        })
        .collect();
    for ((name, v), u) in d.columns.iter().zip(&f.column_units) {
        columns.push(col(name.clone(), u, v.clone()));
    }
    for (k, n) in section_names(model, f.model_spec.as_deref(), &fixed)
        .iter()
        .enumerate()
        .take(3)
    {
        let v = d.section.iter().map(|s| s[k]).collect();
        columns.push(col(format!("gait {n}"), &f.section_units[k], v));
    }
    let words: Vec<String> = d.status.iter().map(|&c| status_word(d, c)).collect();
    Ok(json!({
        "kind": "design", "model": model, "objective": s.get("objective"),
        "free_names": d.free_names, "designs": d.params.len(), "columns": columns,
        "status": d.status, "status_words": words, "reasons": d.reasons,
    }))
}

/// The file's fixed parameter values (`settings.fixed`).
fn fixed_values(s: &serde_json::Map<String, Value>) -> Vec<(String, f64)> {
    s.get("fixed")
        .and_then(Value::as_object)
        .map(|o| {
            o.iter()
                .filter_map(|(n, v)| Some((n.clone(), v.as_f64()?)))
                .collect()
        })
        .unwrap_or_default()
}

/// Design `i` walked: its model (the file's fixed values, the design's free values on top),
/// [`STRIDES_WALKED`] strides from its stored gait with `simulate`'s integrator. A design
/// without a gait is a 422 naming its status and reason.
pub fn walk(f: &DesignFile, i: usize) -> Result<Value, ApiError> {
    let d = &f.data;
    let n = d.params.len();
    let p = d
        .params
        .get(i)
        .ok_or_else(|| ApiError::not_found(format!("no design {i}: the file has {n}")))?;
    let sec = d.section[i];
    if sec.iter().any(|x| !x.is_finite()) {
        let why = if d.reasons[i].is_empty() {
            String::new()
        } else {
            format!(": {}", d.reasons[i])
        };
        return Err(ApiError::unprocessable(format!(
            "design {i} has no gait to walk (status {}{why})",
            status_word(d, d.status[i])
        )));
    }
    let s = settings(d)?;
    let model = s.get("model").and_then(Value::as_str).unwrap_or_default();
    let mut ov: Vec<(String, f64)> = fixed_values(&s)
        .into_iter()
        .filter(|(n, _)| !d.free_names.contains(n))
        .collect();
    ov.extend(d.free_names.iter().cloned().zip(p.iter().copied()));
    let m = pdw::build_recorded(model, f.model_spec.as_deref(), &ov)
        .map_err(|e| ApiError::unprocessable(format!("design {i}'s model '{model}': {}", e.0)))?;
    let integ = pdw::simulate::default_integrator();
    let tr = crate::walk::walk_model(&m, integ, &sec, STRIDES_WALKED)?;
    let params: serde_json::Map<String, Value> = d
        .free_names
        .iter()
        .cloned()
        .zip(p.iter().map(|v| json!(v)))
        .collect();
    Ok(json!({
        "design": i, "params": params, "status": d.status[i],
        "status_word": status_word(d, d.status[i]), "section": sec,
        "section_names": m.info.section_names, "walk": crate::walk::walk_json(&m, &tr),
    }))
}
