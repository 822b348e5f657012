//! The parameter-sweep (continuation) file of `pdw-sweep fixedpoint --sweep`.
//!
//! ```text
//! /                  attrs: format ("pdw-sweep sweep v1"), version, command, created, model,
//!                           parameter (name swept), params (JSON object: the other parameters),
//!                           section_names (JSON list of the d section coordinates)
//! /branches/NNN      one group per branch (000, 001, …); attrs name, period_strides;
//!                    parameter f64 [n], section f64 [n, d], multipliers_re / multipliers_im
//!                    f64 [n, m] (by decreasing modulus), stable u8 [n] (1 = all |λ| < 1)
//! /bifurcations/NNN  attrs kind ("period-doubling", "fold", "neimark-sacker", …), parameter,
//!                    branch (index); section f64 [d]
//! /orbit             optional brute-force orbit diagram: parameter f64 [n], points f64 [n, s]
//!                    (s section samples after transients; NaN where the walker fell);
//!                    attr coordinate (section coordinate sampled)
//! ```
//! The file is written whole to a temporary sibling and renamed into place, so an existing file
//! is replaced only by a complete one (and only with `force`).

use std::path::Path;

use hdf5::{File, Group};
use ndarray::Array2;

use crate::h5util::{
    check_target, create_file, get_attr, get_str, open_file, rename_into_place, set_attr, set_str,
    temp_sibling, At,
};
use crate::{time, Result, StoreError};

/// Value of the root attribute `format` of a sweep file.
pub const SWEEP_FORMAT: &str = "pdw-sweep sweep v1";
const KIND: &str = "pdw-sweep sweep";

/// One continuation branch: fixed points (or period-k orbits) along the swept parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Branch {
    /// e.g. `"period-1"`, `"period-2"`, `"unstable gait"`.
    pub name: String,
    /// Strides per period of the orbits on this branch.
    pub period_strides: u32,
    /// (n) parameter value per point.
    pub parameter: Vec<f64>,
    /// (n × d) section state per point.
    pub section: Vec<Vec<f64>>,
    /// (n × m) Floquet multipliers `(re, im)` per point, by decreasing modulus.
    pub multipliers: Vec<Vec<(f64, f64)>>,
    /// (n) all |λ| < 1.
    pub stable: Vec<bool>,
}

/// A bifurcation detected on a branch.
#[derive(Clone, Debug, PartialEq)]
pub struct Bifurcation {
    /// `"period-doubling"` (λ = −1), `"fold"` (λ = +1), `"neimark-sacker"` (complex |λ| = 1).
    pub kind: String,
    /// Parameter value at the bifurcation.
    pub parameter: f64,
    /// Index into [`SweepData::branches`].
    pub branch: usize,
    /// (d) section state at the bifurcation.
    pub section: Vec<f64>,
}

/// A brute-force orbit diagram: section samples after transients at each parameter value.
#[derive(Clone, Debug, PartialEq)]
pub struct OrbitDiagram {
    /// Section coordinate sampled, e.g. `"theta"`.
    pub coordinate: String,
    /// (n) parameter values.
    pub parameter: Vec<f64>,
    /// (n × s) samples; rows may contain NaN (fell / no sample).
    pub points: Vec<Vec<f64>>,
}

/// Everything a sweep file holds.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepData {
    pub command: String,
    pub model: String,
    /// Name of the swept parameter, e.g. `"slope"`.
    pub parameter: String,
    /// The other parameters as a JSON object text.
    pub params: String,
    /// The d section coordinate names.
    pub section_names: Vec<String>,
    pub branches: Vec<Branch>,
    pub bifurcations: Vec<Bifurcation>,
    pub orbit: Option<OrbitDiagram>,
}

impl SweepData {
    /// Checks shapes: per branch n points with d section values, equal multiplier counts, and
    /// bifurcations pointing at existing branches.
    pub fn validate(&self) -> Result<()> {
        let d = self.section_names.len();
        if d == 0 || self.parameter.is_empty() {
            return Err(StoreError::invalid(
                "sweep",
                "needs a parameter name and section names",
            ));
        }
        if serde_json::from_str::<serde_json::Map<String, serde_json::Value>>(&self.params).is_err()
        {
            return Err(StoreError::invalid(
                "sweep",
                format!("params is not a JSON object: {:?}", self.params),
            ));
        }
        for b in &self.branches {
            let n = b.parameter.len();
            let m = b.multipliers.first().map_or(0, |v| v.len());
            if b.section.len() != n
                || b.multipliers.len() != n
                || b.stable.len() != n
                || b.section.iter().any(|s| s.len() != d)
                || b.multipliers.iter().any(|v| v.len() != m)
            {
                return Err(StoreError::invalid(
                    "sweep",
                    format!("branch {:?}: need n parameter values, n × {d} section values, n × m multipliers and n flags", b.name),
                ));
            }
        }
        for z in &self.bifurcations {
            if z.branch >= self.branches.len() || z.section.len() != d {
                return Err(StoreError::invalid(
                    "sweep",
                    format!(
                        "bifurcation {} at {}: bad branch index or section length",
                        z.kind, z.parameter
                    ),
                ));
            }
        }
        if let Some(o) = &self.orbit {
            let s = o.points.first().map_or(0, |r| r.len());
            if o.points.len() != o.parameter.len() || o.points.iter().any(|r| r.len() != s) {
                return Err(StoreError::invalid(
                    "sweep",
                    "orbit diagram: need n × s points",
                ));
            }
        }
        Ok(())
    }
}

fn matrix(rows: &[Vec<f64>], ncols: usize) -> Array2<f64> {
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    Array2::from_shape_vec((rows.len(), ncols), flat).expect("shape validated")
}

fn put(path: &Path, g: &Group, name: &str, a: &Array2<f64>) -> Result<()> {
    g.new_dataset_builder()
        .with_data(a)
        .create(name)
        .map(|_| ())
        .at(path, &format!("writing {}/{name}", g.name()))
}

fn put1<T: hdf5::H5Type>(path: &Path, g: &Group, name: &str, v: &[T]) -> Result<()> {
    g.new_dataset_builder()
        .with_data(v)
        .create(name)
        .map(|_| ())
        .at(path, &format!("writing {}/{name}", g.name()))
}

/// Writes `data` to `path` (refused if it exists, unless `force`).
pub fn write_sweep(path: impl AsRef<Path>, force: bool, data: &SweepData) -> Result<()> {
    let path = path.as_ref();
    data.validate()?;
    check_target(path, force)?;
    let tmp = temp_sibling(path);
    let res = (|| -> Result<()> {
        let (f, _lock) = create_file(&tmp, true, false, 0)?;
        match fill(&tmp, &f, data).and_then(|()| f.flush().at(&tmp, "flushing")) {
            Ok(()) => f.close().at(&tmp, "closing"),
            Err(e) => {
                // Closing after a failed write can crash HDF5: leave the handle unclosed (the
                // temporary file is removed below).
                std::mem::forget(f);
                Err(e)
            }
        }
    })();
    match res {
        Ok(()) => rename_into_place(&tmp, path),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

fn fill(p: &Path, f: &File, data: &SweepData) -> Result<()> {
    let d = data.section_names.len();
    let names = serde_json::to_string(&data.section_names).unwrap_or_default();
    for (k, v) in [
        ("format", SWEEP_FORMAT),
        ("version", env!("CARGO_PKG_VERSION")),
        ("command", &data.command),
        ("created", &time::now_rfc3339()),
        ("model", &data.model),
        ("parameter", &data.parameter),
        ("params", &data.params),
        ("section_names", &names),
    ] {
        set_str(p, f, k, v)?;
    }
    let gb = f.create_group("branches").at(p, "creating /branches")?;
    for (i, b) in data.branches.iter().enumerate() {
        let g = gb
            .create_group(&format!("{i:03}"))
            .at(p, "creating a branch")?;
        set_str(p, &g, "name", &b.name)?;
        set_attr(p, &g, "period_strides", &b.period_strides)?;
        let m = b.multipliers.first().map_or(0, |v| v.len());
        put1(p, &g, "parameter", &b.parameter)?;
        put(p, &g, "section", &matrix(&b.section, d))?;
        let re: Vec<Vec<f64>> = b
            .multipliers
            .iter()
            .map(|v| v.iter().map(|z| z.0).collect())
            .collect();
        let im: Vec<Vec<f64>> = b
            .multipliers
            .iter()
            .map(|v| v.iter().map(|z| z.1).collect())
            .collect();
        put(p, &g, "multipliers_re", &matrix(&re, m))?;
        put(p, &g, "multipliers_im", &matrix(&im, m))?;
        let st: Vec<u8> = b.stable.iter().map(|&s| u8::from(s)).collect();
        put1(p, &g, "stable", &st)?;
    }
    let gz = f
        .create_group("bifurcations")
        .at(p, "creating /bifurcations")?;
    for (i, z) in data.bifurcations.iter().enumerate() {
        let g = gz
            .create_group(&format!("{i:03}"))
            .at(p, "creating a bifurcation")?;
        set_str(p, &g, "kind", &z.kind)?;
        set_attr(p, &g, "parameter", &z.parameter)?;
        set_attr(p, &g, "branch", &(z.branch as u64))?;
        put1(p, &g, "section", &z.section)?;
    }
    if let Some(o) = &data.orbit {
        let g = f.create_group("orbit").at(p, "creating /orbit")?;
        set_str(p, &g, "coordinate", &o.coordinate)?;
        put1(p, &g, "parameter", &o.parameter)?;
        let s = o.points.first().map_or(0, |r| r.len());
        put(p, &g, "points", &matrix(&o.points, s))?;
    }
    Ok(())
}

fn sorted_groups(p: &Path, g: &Group) -> Result<Vec<Group>> {
    let mut v = g.groups().at(p, "listing groups")?;
    v.sort_by_key(|x| x.name());
    Ok(v)
}

fn rows(a: Array2<f64>) -> Vec<Vec<f64>> {
    a.rows().into_iter().map(|r| r.to_vec()).collect()
}

/// Reads a sweep file.
pub fn read_sweep(path: impl AsRef<Path>) -> Result<SweepData> {
    let p = path.as_ref();
    let f = open_file(p, false)?;
    let fmt = get_str(p, KIND, &f, "format")?;
    if fmt != SWEEP_FORMAT {
        return Err(StoreError::Format {
            path: p.to_path_buf(),
            expected: KIND,
            detail: format!("format is {fmt:?}, expected {SWEEP_FORMAT:?}"),
        });
    }
    let names_text = get_str(p, KIND, &f, "section_names")?;
    let section_names: Vec<String> =
        serde_json::from_str(&names_text).map_err(|e| StoreError::Format {
            path: p.to_path_buf(),
            expected: KIND,
            detail: format!("section_names: {e}"),
        })?;
    let r2 = |g: &Group, n: &str| g.dataset(n).and_then(|d| d.read_2d::<f64>()).at(p, n);
    let r1 = |g: &Group, n: &str| g.dataset(n).and_then(|d| d.read_raw::<f64>()).at(p, n);
    let mut branches = Vec::new();
    for g in sorted_groups(p, &f.group("branches").at(p, "opening /branches")?)? {
        let re = r2(&g, "multipliers_re")?;
        let im = r2(&g, "multipliers_im")?;
        let multipliers = re
            .rows()
            .into_iter()
            .zip(im.rows())
            .map(|(a, b)| a.iter().copied().zip(b.iter().copied()).collect())
            .collect();
        let stable = g
            .dataset("stable")
            .and_then(|d| d.read_raw::<u8>())
            .at(p, "stable")?
            .into_iter()
            .map(|s| s != 0)
            .collect();
        branches.push(Branch {
            name: get_str(p, KIND, &g, "name")?,
            period_strides: get_attr(p, KIND, &g, "period_strides")?,
            parameter: r1(&g, "parameter")?,
            section: rows(r2(&g, "section")?),
            multipliers,
            stable,
        });
    }
    let mut bifurcations = Vec::new();
    for g in sorted_groups(p, &f.group("bifurcations").at(p, "opening /bifurcations")?)? {
        bifurcations.push(Bifurcation {
            kind: get_str(p, KIND, &g, "kind")?,
            parameter: get_attr(p, KIND, &g, "parameter")?,
            branch: get_attr::<u64>(p, KIND, &g, "branch")? as usize,
            section: r1(&g, "section")?,
        });
    }
    let orbit = if f.link_exists("orbit") {
        let g = f.group("orbit").at(p, "opening /orbit")?;
        Some(OrbitDiagram {
            coordinate: get_str(p, KIND, &g, "coordinate")?,
            parameter: r1(&g, "parameter")?,
            points: rows(r2(&g, "points")?),
        })
    } else {
        None
    };
    Ok(SweepData {
        command: get_str(p, KIND, &f, "command")?,
        model: get_str(p, KIND, &f, "model")?,
        parameter: get_str(p, KIND, &f, "parameter")?,
        params: get_str(p, KIND, &f, "params")?,
        section_names,
        branches,
        bifurcations,
        orbit,
    })
}
