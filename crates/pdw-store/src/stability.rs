//! The basin-stability file of `pdw-sweep basin --over NAME=A:B:N`: at each of N values of a
//! model parameter, the fraction of one fixed box of section states that reaches each
//! attractor (basin stability, Menck, Heitzig, Marwan & Kurths, Nature Physics 9, 89, 2013),
//! falls, or neither.
//!
//! ```text
//! /                  attrs: format ("pdw-sweep basin-stability v1"), version, command, created,
//!                           model, parameter (name varied), params (JSON object: the other
//!                           parameters), box (JSON: the two axes with their ranges and cell
//!                           counts, the fixed coordinates, and where the box came from),
//!                           max_strides, elapsed_s, one JSON text attribute setting_NAME per
//!                           entry of `settings`
//! /parameter         f64 [N] the parameter values
//! /fractions         f64 [N, C] fraction of the box per column; attrs columns (JSON list of the
//!                    C names: the attractors met at any value, by name, then "fall",
//!                    "timeout", "other"), kinds (JSON list: "attractor", "fall", "timeout",
//!                    "other"); each row sums to 1
//! /outcome_fractions f64 [N, 13] the fixed basin outcomes (gait, other, fall_forward, …,
//!                    fall_rolls_back, by code) before attractors are told apart; attr columns
//! /values/NNN        attrs parameter, attractors (JSON list, one object per attractor found at
//!                    that value: name, period_strides (0 = chaotic), period_time, points,
//!                    multipliers [[re, im], …], validity ("valid", "invalid", "not
//!                    checked"), invalid_reasons)
//! ```
//! Written whole to a temporary sibling and renamed into place.

use std::path::Path;

use hdf5::File;
use ndarray::Array2;

use crate::h5util::{
    get_attr, get_str, matrix, open_file, put, set_attr, set_str, write_h5_atomically, At,
};
use crate::{time, Result, StoreError};

/// Value of the root attribute `format` of a basin-stability file.
pub const STABILITY_FORMAT: &str = "pdw-sweep basin-stability v1";
const KIND: &str = "pdw-sweep basin-stability";

/// An attractor found at one parameter value.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StabilityAttractor {
    pub name: String,
    /// Strides per period; 0 for a chaotic attractor (its `points` are a sample of it).
    pub period_strides: u32,
    /// Duration of the period (NaN for a chaotic attractor; written as null).
    pub period_time: Option<f64>,
    /// Section points of the orbit (or a sample of the chaotic attractor).
    pub points: Vec<Vec<f64>>,
    /// Multipliers `[re, im]` of the period map (empty for a chaotic attractor).
    pub multipliers: Vec<[f64; 2]>,
    /// Physical validity of the orbit: `valid`, `invalid` or `not checked` (empty in files
    /// written before it was recorded).
    #[serde(default)]
    pub validity: String,
    /// What fails on the orbit when `invalid`.
    #[serde(default)]
    pub invalid_reasons: Vec<String>,
}

impl StabilityAttractor {
    /// Its orbit is physically invalid.
    pub fn invalid(&self) -> bool {
        self.validity == "invalid"
    }
}

impl StabilityData {
    /// The column `name` is an attractor found physically invalid at some value.
    pub fn invalid_column(&self, name: &str) -> bool {
        self.attractors
            .iter()
            .flatten()
            .any(|a| a.name == name && a.invalid())
    }
}

/// Everything a basin-stability file holds.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct StabilityData {
    pub command: String,
    pub model: String,
    /// Name of the parameter varied.
    pub parameter: String,
    /// The other parameters as a JSON object text.
    pub params: String,
    /// The box of initial conditions as JSON text.
    pub box_json: String,
    pub max_strides: u32,
    /// (N) parameter values.
    pub values: Vec<f64>,
    /// (C) column names of `fractions`.
    pub columns: Vec<String>,
    /// (C) `"attractor"`, `"fall"`, `"timeout"` or `"other"` per column.
    pub kinds: Vec<String>,
    /// (N × C) fractions; each row sums to 1.
    pub fractions: Vec<Vec<f64>>,
    /// (10) names of the fixed basin outcomes.
    pub outcome_columns: Vec<String>,
    /// (N × 10) fractions of the fixed basin outcomes.
    pub outcome_fractions: Vec<Vec<f64>>,
    /// (N) the attractors found at each value.
    pub attractors: Vec<Vec<StabilityAttractor>>,
    /// Run settings, name → JSON text.
    pub settings: Vec<(String, String)>,
    /// Wall time of the computation (s).
    pub elapsed_s: f64,
}

impl StabilityData {
    /// Checks shapes, kinds and that every row of `fractions` sums to 1 (to 1e-9).
    pub fn validate(&self) -> Result<()> {
        let n = self.values.len();
        let c = self.columns.len();
        let bad = |m: String| Err(StoreError::invalid("basin stability", m));
        if n == 0 || c == 0 {
            return bad("needs at least one parameter value and one column".into());
        }
        if self.kinds.len() != c
            || self
                .kinds
                .iter()
                .any(|k| !matches!(k.as_str(), "attractor" | "fall" | "timeout" | "other"))
        {
            return bad(format!("kinds {:?} for {c} columns", self.kinds));
        }
        if self.fractions.len() != n || self.fractions.iter().any(|r| r.len() != c) {
            return bad(format!("fractions need {n} × {c} values"));
        }
        if self.attractors.len() != n {
            return bad(format!("attractors need {n} lists"));
        }
        let k = self.outcome_columns.len();
        if self.outcome_fractions.len() != n || self.outcome_fractions.iter().any(|r| r.len() != k)
        {
            return bad(format!("outcome fractions need {n} × {k} values"));
        }
        for (i, r) in self.fractions.iter().enumerate() {
            let s: f64 = r.iter().sum();
            let sums_to_one = (s - 1.0).abs() <= 1e-9; // false for NaN
            if !sums_to_one || r.iter().any(|f| !(0.0..=1.0).contains(f)) {
                return bad(format!(
                    "the fractions at {} = {} sum to {s}, not 1",
                    self.parameter, self.values[i]
                ));
            }
        }
        for (name, text) in [("params", &self.params), ("box", &self.box_json)] {
            if serde_json::from_str::<serde_json::Value>(text).is_err() {
                return bad(format!("{name} is not JSON text: {text:?}"));
            }
        }
        Ok(())
    }
}

/// Writes `data` to `path` (refused if it exists, unless `force`).
pub fn write_stability(path: impl AsRef<Path>, force: bool, data: &StabilityData) -> Result<()> {
    let path = path.as_ref();
    data.validate()?;
    write_h5_atomically(path, force, |tmp, f| fill(tmp, f, data))
}

fn json_list(v: &[String]) -> String {
    serde_json::to_string(v).unwrap_or_default()
}

fn fill(p: &Path, f: &File, d: &StabilityData) -> Result<()> {
    for (k, v) in [
        ("format", STABILITY_FORMAT),
        ("version", env!("CARGO_PKG_VERSION")),
        ("command", &d.command),
        ("created", &time::now_rfc3339()),
        ("model", &d.model),
        ("parameter", &d.parameter),
        ("params", &d.params),
        ("box", &d.box_json),
    ] {
        set_str(p, f, k, v)?;
    }
    set_attr(p, f, "max_strides", &d.max_strides)?;
    set_attr(p, f, "elapsed_s", &d.elapsed_s)?;
    for (k, v) in &d.settings {
        set_str(p, f, &format!("setting_{k}"), v)?;
    }
    put(p, f, "parameter", &d.values)?;
    let fr = put(p, f, "fractions", &matrix(&d.fractions, d.columns.len()))?;
    set_str(p, &fr, "columns", &json_list(&d.columns))?;
    set_str(p, &fr, "kinds", &json_list(&d.kinds))?;
    let of = put(
        p,
        f,
        "outcome_fractions",
        &matrix(&d.outcome_fractions, d.outcome_columns.len()),
    )?;
    set_str(p, &of, "columns", &json_list(&d.outcome_columns))?;
    let gv = f.create_group("values").at(p, "creating /values")?;
    for (i, (mu, ats)) in d.values.iter().zip(&d.attractors).enumerate() {
        let g = gv
            .create_group(&format!("{i:03}"))
            .at(p, "creating a value group")?;
        set_attr(p, &g, "parameter", mu)?;
        set_str(
            p,
            &g,
            "attractors",
            &serde_json::to_string(ats).unwrap_or_default(),
        )?;
    }
    Ok(())
}

/// Reads a basin-stability file.
pub fn read_stability(path: impl AsRef<Path>) -> Result<StabilityData> {
    let p = path.as_ref();
    let f = open_file(p, false)?;
    let fmt = get_str(p, KIND, &f, "format")?;
    if fmt != STABILITY_FORMAT {
        return Err(StoreError::Format {
            path: p.to_path_buf(),
            expected: KIND,
            detail: format!("format is {fmt:?}, expected {STABILITY_FORMAT:?}"),
        });
    }
    let json = |text: String, what: &str| -> Result<Vec<String>> {
        serde_json::from_str(&text).map_err(|e| StoreError::Format {
            path: p.to_path_buf(),
            expected: KIND,
            detail: format!("{what}: {e}"),
        })
    };
    let rows =
        |a: Array2<f64>| -> Vec<Vec<f64>> { a.rows().into_iter().map(|r| r.to_vec()).collect() };
    let fr = f.dataset("fractions").at(p, "opening /fractions")?;
    let of = f
        .dataset("outcome_fractions")
        .at(p, "opening /outcome_fractions")?;
    let values: Vec<f64> = f
        .dataset("parameter")
        .and_then(|d| d.read_raw::<f64>())
        .at(p, "reading /parameter")?;
    let mut attractors = Vec::with_capacity(values.len());
    let gv = f.group("values").at(p, "opening /values")?;
    for i in 0..values.len() {
        let g = gv
            .group(&format!("{i:03}"))
            .at(p, "opening a value group")?;
        let text = get_str(p, KIND, &g, "attractors")?;
        attractors.push(serde_json::from_str(&text).map_err(|e| StoreError::Format {
            path: p.to_path_buf(),
            expected: KIND,
            detail: format!("attractors of value {i}: {e}"),
        })?);
    }
    let mut settings = Vec::new();
    let mut names = f.attr_names().at(p, "listing attributes")?;
    names.sort();
    for a in names {
        if let Some(name) = a.strip_prefix("setting_") {
            settings.push((name.to_string(), get_str(p, KIND, &f, &a)?));
        }
    }
    Ok(StabilityData {
        command: get_str(p, KIND, &f, "command")?,
        model: get_str(p, KIND, &f, "model")?,
        parameter: get_str(p, KIND, &f, "parameter")?,
        params: get_str(p, KIND, &f, "params")?,
        box_json: get_str(p, KIND, &f, "box")?,
        max_strides: get_attr(p, KIND, &f, "max_strides")?,
        values,
        columns: json(get_str(p, KIND, &fr, "columns")?, "columns")?,
        kinds: json(get_str(p, KIND, &fr, "kinds")?, "kinds")?,
        fractions: rows(fr.read_2d::<f64>().at(p, "reading /fractions")?),
        outcome_columns: json(get_str(p, KIND, &of, "columns")?, "outcome columns")?,
        outcome_fractions: rows(of.read_2d::<f64>().at(p, "reading /outcome_fractions")?),
        attractors,
        settings,
        elapsed_s: get_attr(p, KIND, &f, "elapsed_s")?,
    })
}
