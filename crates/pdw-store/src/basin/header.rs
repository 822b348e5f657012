//! The header of a basin file: what identifies a run ([`BasinHeader`], [`ZAxis`]), its checks,
//! and the legend as the file stores it.

use std::collections::BTreeMap;
use std::path::Path;

use super::{block_count, KIND, NOT_COMPUTED, NOT_COMPUTED_NAME};
use crate::shard::{grid_shard_rows, ShardSpec};
use crate::{Result, StoreError};

/// Everything that identifies a basin run: what `resume` and `merge` compare.
///
/// Floating-point fields are compared bit for bit; `params` and `tolerances` as JSON text, so
/// serialise them the same way each time (e.g. `serde_json::to_string` of the same value).
/// `command` is recorded but not compared (a resumed run's command line differs).
#[derive(Clone, Debug, PartialEq)]
pub struct BasinHeader {
    /// The command line that made the file.
    pub command: String,
    /// Model name, e.g. `"simplest"`.
    pub model: String,
    /// Slope γ in radians.
    pub slope: f64,
    /// Model parameters as a JSON object text.
    pub params: String,
    /// The fully resolved model, one `key = value` line per quantity (the walker's
    /// fingerprint): two files continue each other only if it is equal, so a spec whose
    /// expressions changed under the same parameter values is a different run. Empty in files
    /// written before it was stored.
    pub model_resolved: String,
    /// Integrator name, e.g. `"dopri5"`.
    pub integrator: String,
    /// Integrator tolerances as a JSON object text, e.g. `{"rtol":1e-10,"atol":1e-12}`.
    pub tolerances: String,
    /// Stride budget per cell.
    pub max_strides: u32,
    /// Section coordinate along x, e.g. `"theta"`.
    pub x_name: String,
    /// Grid abscissae (nx), finite.
    pub x: Vec<f64>,
    /// Section coordinate along y, e.g. `"thetadot"`.
    pub y_name: String,
    /// Grid ordinates (ny), finite.
    pub y: Vec<f64>,
    /// The third axis of a 3-D grid (`None`: a 2-D grid). Its cells are stored `[nz, ny, nx]`,
    /// and the writer's rows are the grid's (z, y) pairs, row `k·ny + i` for `(z[k], y[i])`.
    pub z: Option<ZAxis>,
    /// Names of the d section coordinates stored in `/basin/final`.
    pub state_names: Vec<String>,
    /// Outcome codes and names, e.g. `(0, "gait")`; codes unique and not [`NOT_COMPUTED`].
    pub legend: Vec<(u8, String)>,
    /// `Some` for a shard file holding only [`shard_rows`](crate::shard::shard_rows)`(ny, index, count)`.
    pub shard: Option<ShardSpec>,
}

impl BasinHeader {
    /// Number of grid columns.
    pub fn nx(&self) -> usize {
        self.x.len()
    }
    /// Number of grid rows.
    pub fn ny(&self) -> usize {
        self.y.len()
    }
    /// Number of z-slices: 1 for a 2-D grid.
    pub fn nz(&self) -> usize {
        self.z.as_ref().map_or(1, |z| z.values.len())
    }
    /// Rows of nx cells the writer handles: ny for a 2-D grid, nz·ny for a 3-D one (row
    /// `k·ny + i` is `(z[k], y[i])`).
    pub fn rows(&self) -> usize {
        self.nz() * self.ny()
    }
    /// Chunk blocks of the grid ([`block_count`]).
    pub fn blocks(&self) -> usize {
        block_count(self.ny(), self.nz())
    }
    /// Dimension of the stored section state.
    pub fn d(&self) -> usize {
        self.state_names.len()
    }
    /// Outcome name of `code`, if in the legend.
    pub fn outcome_name(&self, code: u8) -> Option<&str> {
        self.legend
            .iter()
            .find(|(c, _)| *c == code)
            .map(|(_, n)| n.as_str())
    }
    /// Rows this file is responsible for: all rows, or its shard's.
    pub fn own_rows(&self) -> Vec<usize> {
        match self.shard {
            None => (0..self.rows()).collect(),
            Some(s) => grid_shard_rows(self.ny(), self.nz(), s.index, s.count).unwrap_or_default(),
        }
    }

    /// Rejects empty or non-finite grids, empty names, a malformed legend, non-JSON params.
    pub fn validate(&self) -> Result<()> {
        for (axis, name, v) in [("x", &self.x_name, &self.x), ("y", &self.y_name, &self.y)] {
            if name.is_empty() {
                return Err(StoreError::invalid(
                    "grid",
                    format!("{axis} axis has no name"),
                ));
            }
            if v.is_empty() {
                return Err(StoreError::invalid(
                    "grid",
                    format!("{axis} axis ({name}) has no points"),
                ));
            }
            if let Some(bad) = v.iter().find(|a| !a.is_finite()) {
                return Err(StoreError::invalid(
                    "grid",
                    format!("{axis} axis ({name}) holds {bad}"),
                ));
            }
        }
        if let Some(z) = &self.z {
            z.validate(&self.x_name, &self.y_name)?;
        }
        if self.state_names.is_empty() || self.state_names.iter().any(|n| n.is_empty()) {
            return Err(StoreError::invalid(
                "state names",
                format!(
                    "need at least one non-empty name, got {:?}",
                    self.state_names
                ),
            ));
        }
        if self.legend.is_empty() {
            return Err(StoreError::invalid("legend", "empty"));
        }
        for (i, (c, n)) in self.legend.iter().enumerate() {
            if *c == NOT_COMPUTED {
                return Err(StoreError::invalid(
                    "legend",
                    format!("code {NOT_COMPUTED} is reserved for cells not computed ({n})"),
                ));
            }
            if n.is_empty() || n.contains('/') {
                return Err(StoreError::invalid(
                    "legend",
                    format!("bad outcome name {n:?}"),
                ));
            }
            if self.legend[..i].iter().any(|(c2, n2)| c2 == c || n2 == n) {
                return Err(StoreError::invalid(
                    "legend",
                    format!("duplicate code {c} or name {n:?}"),
                ));
            }
        }
        for (what, text) in [("params", &self.params), ("tolerances", &self.tolerances)] {
            match serde_json::from_str::<serde_json::Value>(text) {
                Ok(serde_json::Value::Object(_)) => {}
                _ => {
                    return Err(StoreError::invalid(
                        "header",
                        format!("{what} must be a JSON object, got {text:?}"),
                    ))
                }
            }
        }
        if !self.slope.is_finite() {
            return Err(StoreError::invalid(
                "header",
                format!("slope {}", self.slope),
            ));
        }
        if let Some(s) = self.shard {
            s.validate()?;
        }
        Ok(())
    }

    /// The first field in which `found` (read from `path`) differs from `self`, as an error.
    pub(crate) fn check_matches(&self, found: &BasinHeader, path: &Path) -> Result<()> {
        let mism = |field: &str, f: String, e: String| StoreError::Mismatch {
            path: path.to_path_buf(),
            field: field.to_string(),
            found: f,
            expected: e,
        };
        let bits = |v: &[f64]| v.iter().map(|a| a.to_bits()).collect::<Vec<_>>();
        if found.model != self.model {
            return Err(mism("model", found.model.clone(), self.model.clone()));
        }
        if found.slope.to_bits() != self.slope.to_bits() {
            return Err(mism(
                "slope",
                found.slope.to_string(),
                self.slope.to_string(),
            ));
        }
        if found.params != self.params {
            return Err(mism("params", found.params.clone(), self.params.clone()));
        }
        if let Some((f, e)) =
            crate::first_line_difference(&found.model_resolved, &self.model_resolved)
        {
            let absent = |s: String| {
                if s.is_empty() {
                    "(absent)".to_string()
                } else {
                    s
                }
            };
            return Err(mism("resolved model", absent(f), absent(e)));
        }
        if found.integrator != self.integrator {
            return Err(mism(
                "integrator",
                found.integrator.clone(),
                self.integrator.clone(),
            ));
        }
        if found.tolerances != self.tolerances {
            return Err(mism(
                "tolerances",
                found.tolerances.clone(),
                self.tolerances.clone(),
            ));
        }
        if found.max_strides != self.max_strides {
            return Err(mism(
                "max_strides",
                found.max_strides.to_string(),
                self.max_strides.to_string(),
            ));
        }
        for (axis, fname, fv, ename, ev) in [
            ("x", &found.x_name, &found.x, &self.x_name, &self.x),
            ("y", &found.y_name, &found.y, &self.y_name, &self.y),
        ] {
            if fname != ename {
                return Err(mism(
                    &format!("{axis} coordinate"),
                    fname.clone(),
                    ename.clone(),
                ));
            }
            if bits(fv) != bits(ev) {
                let (field, f, e) = axis_difference(&format!("{axis} grid"), fv, ev);
                return Err(mism(&field, f, e));
            }
        }
        check_z_matches(&found.z, &self.z, path)?;
        if found.state_names != self.state_names {
            return Err(mism(
                "section coordinates",
                format!("{:?}", found.state_names),
                format!("{:?}", self.state_names),
            ));
        }
        if found.legend != self.legend {
            return Err(mism(
                "legend",
                legend_json(&found.legend),
                legend_json(&self.legend),
            ));
        }
        if found.shard != self.shard {
            let show = |s: Option<ShardSpec>| s.map_or("no shard".to_string(), |s| s.to_string());
            return Err(mism("shard", show(found.shard), show(self.shard)));
        }
        Ok(())
    }
}

/// The third axis of a 3-D basin grid: a section coordinate and its values.
#[derive(Clone, Debug, PartialEq)]
pub struct ZAxis {
    /// Section coordinate along z, e.g. `"hip_rate"`.
    pub name: String,
    /// The nz values of the grid's z-slices, finite.
    pub values: Vec<f64>,
}

impl ZAxis {
    /// Rejects an empty name or values, a non-finite value, and a coordinate already an axis.
    fn validate(&self, x: &str, y: &str) -> Result<()> {
        let bad = |d: String| Err(StoreError::invalid("grid", d));
        if self.name.is_empty() {
            return bad("z axis has no name".into());
        }
        if self.values.is_empty() {
            return bad(format!("z axis ({}) has no points", self.name));
        }
        if let Some(v) = self.values.iter().find(|a| !a.is_finite()) {
            return bad(format!("z axis ({}) holds {v}", self.name));
        }
        if self.name == x || self.name == y {
            return bad(format!("z axis ({}) is also the x or y axis", self.name));
        }
        Ok(())
    }
}

/// The first difference of the z axes `found` (read from `path`) and `expected`, as an error.
fn check_z_matches(found: &Option<ZAxis>, expected: &Option<ZAxis>, path: &Path) -> Result<()> {
    let show = |z: &Option<ZAxis>| match z {
        None => "no z axis (a 2-D grid)".to_string(),
        Some(z) => format!(
            "{}: {} points {}..{}",
            z.name,
            z.values.len(),
            z.values.first().copied().unwrap_or(f64::NAN),
            z.values.last().copied().unwrap_or(f64::NAN)
        ),
    };
    let bits = |z: &Option<ZAxis>| {
        z.as_ref().map(|z| {
            let v: Vec<u64> = z.values.iter().map(|a| a.to_bits()).collect();
            (z.name.clone(), v)
        })
    };
    if bits(found) == bits(expected) {
        return Ok(());
    }
    let (field, found, expected) = match (found, expected) {
        (Some(f), Some(e)) if f.name == e.name => axis_difference("z grid", &f.values, &e.values),
        _ => ("z grid".into(), show(found), show(expected)),
    };
    Err(StoreError::Mismatch {
        path: path.to_path_buf(),
        field,
        found,
        expected,
    })
}

/// How two axes that differ bit for bit differ, as `(field, found, expected)` of a
/// [`StoreError::Mismatch`]: their sizes and ends where those differ, else the first point that
/// differs, by index, with both values in full (the shortest text that reads back to each
/// double): "y grid is point 17 = -0.19980000000000003 in the file but point 17 = -0.1998 here
/// (of 40 points -0.25..-0.15)".
fn axis_difference(field: &str, found: &[f64], expected: &[f64]) -> (String, String, String) {
    let desc = |v: &[f64]| {
        format!(
            "{} points {}..{}",
            v.len(),
            v.first().copied().unwrap_or(f64::NAN),
            v.last().copied().unwrap_or(f64::NAN)
        )
    };
    let differs = |i: usize| found[i].to_bits() != expected[i].to_bits();
    match (0..found.len().min(expected.len())).find(|&i| differs(i)) {
        Some(i) if found.len() == expected.len() => (
            field.to_string(),
            format!("point {i} = {:?}", found[i]),
            format!("point {i} = {:?} (of {})", expected[i], desc(expected)),
        ),
        _ => (field.to_string(), desc(found), desc(expected)),
    }
}

/// The legend as a JSON object, code → name.
pub(crate) fn legend_json(legend: &[(u8, String)]) -> String {
    let m: BTreeMap<String, serde_json::Value> = legend
        .iter()
        .map(|(c, n)| (c.to_string(), serde_json::Value::String(n.clone())))
        .collect();
    serde_json::to_string(&m).unwrap_or_default()
}

/// The `legend` attribute as written: the outcome codes and the fill value
/// [`NOT_COMPUTED`] = `"not_computed"` (a cell no run has written yet).
pub(crate) fn file_legend_json(legend: &[(u8, String)]) -> String {
    let mut all = legend.to_vec();
    all.push((NOT_COMPUTED, NOT_COMPUTED_NAME.to_string()));
    legend_json(&all)
}

/// The legend read from a file: its outcome codes, without the fill value.
pub(super) fn parse_legend(path: &Path, text: &str) -> Result<Vec<(u8, String)>> {
    let bad = |d: String| StoreError::Format {
        path: path.to_path_buf(),
        expected: KIND,
        detail: format!("legend {text:?}: {d}"),
    };
    let m: BTreeMap<String, String> = serde_json::from_str(text).map_err(|e| bad(e.to_string()))?;
    let mut v = m
        .into_iter()
        .map(|(k, n)| {
            k.parse::<u8>()
                .map(|c| (c, n))
                .map_err(|e| bad(e.to_string()))
        })
        .collect::<Result<Vec<_>>>()?;
    v.retain(|(c, _)| *c != NOT_COMPUTED);
    v.sort_by_key(|(c, _)| *c);
    Ok(v)
}
