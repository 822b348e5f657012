//! Trajectory files (`pdw-sweep simulate`): time series of named columns with units, and the
//! events along the walk, as HDF5 or CSV.
//!
//! # HDF5 schema (`format = "pdw-sweep trajectory v1"`)
//! ```text
//! /                  attrs: format, version, created, and the run's attributes (model, slope,
//!                           params, command, steps, steps_done, outcome, integrator, dt_out…)
//! /COLUMN            one dataset per column, [n] or [n, k] (row = sample); attrs `units`, and
//!                    `components` (JSON list of the k names) for a 2-D column. f64, or u32 for
//!                    integer columns (mode, step, flags)
//! /events/t          f64 [m] event times
//! /events/kind       u8  [m]; attr `legend` = JSON object code → name ("heel_strike", a fall…)
//! /events/step       u32 [m] step during which the event happened (0-based)
//! /events/mode_before, /events/mode_after   u32 [m]
//! /events/pre, /events/post                 f64 [m, d] states just before and after the event
//! ```
//! # CSV
//! Comment lines (`# `) first: `# key: value` for every attribute, `# units: NAME=UNIT,…`,
//! `# event: t,step,kind,mode_before,mode_after` lines; then one header row of column names (a
//! 2-D column gives one column per component, named after the component) and one row per
//! sample. `numpy.genfromtxt(path, delimiter=",", names=True)` and
//! `pandas.read_csv(path, comment="#")` read it.

use crate::h5util::{
    get_str, open_file, put, set_str, write_h5_atomically, write_text_atomically, At,
};
use crate::{time, Result, StoreError};
use hdf5::{File, Group};
use ndarray::Array2;
use std::io::Write;
use std::path::Path;

/// The `format` attribute of a trajectory file.
pub const TRAJECTORY_FORMAT: &str = "pdw-sweep trajectory v1";
const KIND: &str = "trajectory";

/// One column of a trajectory: `width` values per sample, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct TrajColumn {
    pub name: String,
    pub units: String,
    /// `n × width` values, row-major.
    pub values: Vec<f64>,
    /// Values per sample (1 for a scalar column).
    pub width: usize,
    /// Component names when `width > 1` (also the CSV column names).
    pub components: Vec<String>,
    /// Stored as u32 in HDF5 (mode, step, flags); the values must be small non-negative integers.
    pub integer: bool,
}

impl TrajColumn {
    /// A scalar f64 column.
    pub fn scalar(name: &str, units: &str, values: Vec<f64>) -> Self {
        Self {
            name: name.into(),
            units: units.into(),
            values,
            width: 1,
            components: Vec::new(),
            integer: false,
        }
    }
}

/// Events along the walk (`m` of them; states of dimension `d`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TrajEvents {
    pub t: Vec<f64>,
    pub step: Vec<u32>,
    pub kind: Vec<String>,
    pub mode_before: Vec<u32>,
    pub mode_after: Vec<u32>,
    /// `m × d`, row-major.
    pub pre: Vec<f64>,
    /// `m × d`, row-major.
    pub post: Vec<f64>,
}

/// Everything a trajectory file holds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TrajectoryData {
    /// Root attributes, in order (strings; JSON where structured).
    pub attrs: Vec<(String, String)>,
    /// Columns, `t` first.
    pub columns: Vec<TrajColumn>,
    pub events: TrajEvents,
    /// State dimension `d` of `events.pre` / `events.post`.
    pub dim: usize,
}

impl TrajectoryData {
    /// Number of samples (the length of the first column).
    pub fn len(&self) -> usize {
        self.columns
            .first()
            .map_or(0, |c| c.values.len() / c.width.max(1))
    }

    /// True without samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The column called `name`.
    pub fn column(&self, name: &str) -> Option<&TrajColumn> {
        self.columns.iter().find(|c| c.name == name)
    }

    fn validate(&self) -> Result<()> {
        let n = self.len();
        let bad = |detail: String| StoreError::invalid("trajectory data", detail);
        for c in &self.columns {
            if c.width == 0 || c.values.len() != n * c.width {
                return Err(bad(format!(
                    "column {} has {} values, expected {n} × {}",
                    c.name,
                    c.values.len(),
                    c.width
                )));
            }
            if c.width > 1 && c.components.len() != c.width {
                return Err(bad(format!(
                    "column {} needs {} component names",
                    c.name, c.width
                )));
            }
        }
        let e = &self.events;
        let m = e.t.len();
        if [
            e.step.len(),
            e.kind.len(),
            e.mode_before.len(),
            e.mode_after.len(),
        ]
        .iter()
        .any(|&l| l != m)
            || e.pre.len() != m * self.dim
            || e.post.len() != m * self.dim
        {
            return Err(bad(format!("event arrays of unequal lengths ({m} events)")));
        }
        Ok(())
    }
}

/// Writes `data` as HDF5 to `path` (refused if it exists, unless `force`); the file appears
/// complete or not at all (written beside and renamed into place).
pub fn write_trajectory_h5(
    path: impl AsRef<Path>,
    force: bool,
    data: &TrajectoryData,
) -> Result<()> {
    let path = path.as_ref();
    data.validate()?;
    write_h5_atomically(path, force, |tmp, f| fill(tmp, f, data))
}

/// `v` (rows of `cols` values, row-major) as the 2-D dataset `name` of `g`.
fn put_rows(p: &Path, g: &Group, name: &str, v: &[f64], cols: usize) -> Result<hdf5::Dataset> {
    let rows = v.len().checked_div(cols).unwrap_or(0);
    let a = Array2::from_shape_vec((rows, cols), v.to_vec()).map_err(|e| StoreError::Format {
        path: p.to_path_buf(),
        expected: KIND,
        detail: format!("{name}: {e}"),
    })?;
    put(p, g, name, &a)
}

fn fill(p: &Path, f: &File, data: &TrajectoryData) -> Result<()> {
    set_str(p, f, "format", TRAJECTORY_FORMAT)?;
    set_str(p, f, "version", env!("CARGO_PKG_VERSION"))?;
    set_str(p, f, "created", &time::now_rfc3339())?;
    for (k, v) in &data.attrs {
        set_str(p, f, k, v)?;
    }
    for c in &data.columns {
        let ds = match (c.integer, c.width) {
            (true, 1) => {
                let v: Vec<u32> = c.values.iter().map(|&x| x as u32).collect();
                put(p, f, &c.name, &v)?
            }
            (false, 1) => put(p, f, &c.name, &c.values)?,
            _ => {
                let ds = put_rows(p, f, &c.name, &c.values, c.width)?;
                let names = serde_json::to_string(&c.components).unwrap_or_default();
                set_str(p, &ds, "components", &names)?;
                ds
            }
        };
        set_str(p, &ds, "units", &c.units)?;
    }
    let g = f.create_group("events").at(p, "creating /events")?;
    let e = &data.events;
    let mut names: Vec<&str> = Vec::new();
    let codes: Vec<u8> = e
        .kind
        .iter()
        .map(|k| match names.iter().position(|n| n == k) {
            Some(i) => i as u8,
            None => {
                names.push(k);
                (names.len() - 1) as u8
            }
        })
        .collect();
    let legend: serde_json::Map<String, serde_json::Value> = names
        .iter()
        .enumerate()
        .map(|(i, n)| (i.to_string(), serde_json::json!(n)))
        .collect();
    let time_units = data.column("t").map_or("", |c| c.units.as_str());
    let ds = put(p, &g, "t", &e.t)?;
    set_str(p, &ds, "units", time_units)?;
    let ds = put(p, &g, "kind", &codes)?;
    set_str(
        p,
        &ds,
        "legend",
        &serde_json::Value::Object(legend).to_string(),
    )?;
    put(p, &g, "step", &e.step)?;
    put(p, &g, "mode_before", &e.mode_before)?;
    put(p, &g, "mode_after", &e.mode_after)?;
    put_rows(p, &g, "pre", &e.pre, data.dim)?;
    put_rows(p, &g, "post", &e.post, data.dim)?;
    Ok(())
}

/// Reads a trajectory file written by [`write_trajectory_h5`] (columns as f64; `created` and
/// `version` are among the attributes).
pub fn read_trajectory_h5(path: impl AsRef<Path>) -> Result<TrajectoryData> {
    let p = path.as_ref();
    let f = open_file(p, false)?;
    let fmt = get_str(p, KIND, &f, "format")?;
    if fmt != TRAJECTORY_FORMAT {
        return Err(StoreError::Format {
            path: p.to_path_buf(),
            expected: KIND,
            detail: format!("format is {fmt:?}, expected {TRAJECTORY_FORMAT:?}"),
        });
    }
    let mut attrs = Vec::new();
    for name in f.attr_names().at(p, "listing attributes")? {
        if name != "format" {
            attrs.push((name.clone(), get_str(p, KIND, &f, &name)?));
        }
    }
    let mut columns = Vec::new();
    for name in f.member_names().at(p, "listing datasets")? {
        // Groups are not columns: `/events`, and `/provenance` (see [`crate::provenance`]).
        if name == "events" || f.group(&name).is_ok() {
            continue;
        }
        let ds = f.dataset(&name).at(p, &name)?;
        let units = get_str(p, KIND, &ds, "units")?;
        let integer = ds.dtype().at(p, &name)?.is::<u32>();
        let shape = ds.shape();
        let values: Vec<f64> = if integer {
            ds.read_raw::<u32>()
                .at(p, &name)?
                .into_iter()
                .map(f64::from)
                .collect()
        } else {
            ds.read_raw::<f64>().at(p, &name)?
        };
        let (width, components) = if shape.len() == 2 {
            let c = get_str(p, KIND, &ds, "components")?;
            let comps: Vec<String> = serde_json::from_str(&c).map_err(|e| StoreError::Format {
                path: p.to_path_buf(),
                expected: KIND,
                detail: format!("{name}/components: {e}"),
            })?;
            (shape[1], comps)
        } else {
            (1, Vec::new())
        };
        columns.push(TrajColumn {
            name,
            units,
            values,
            width,
            components,
            integer,
        });
    }
    // `t` first, as written.
    if let Some(i) = columns.iter().position(|c| c.name == "t") {
        let t = columns.remove(i);
        columns.insert(0, t);
    }
    let g = f.group("events").at(p, "opening /events")?;
    let kind_ds = g.dataset("kind").at(p, "events/kind")?;
    let legend_text = get_str(p, KIND, &kind_ds, "legend")?;
    let legend: std::collections::BTreeMap<String, String> = serde_json::from_str(&legend_text)
        .map_err(|e| StoreError::Format {
            path: p.to_path_buf(),
            expected: KIND,
            detail: format!("events/kind legend: {e}"),
        })?;
    let codes = g
        .dataset("kind")
        .and_then(|d| d.read_raw::<u8>())
        .at(p, "events/kind")?;
    let r32 = |n: &str| g.dataset(n).and_then(|d| d.read_raw::<u32>()).at(p, n);
    let pre_ds = g.dataset("pre").at(p, "events/pre")?;
    let dim = pre_ds.shape().get(1).copied().unwrap_or(0);
    let events = TrajEvents {
        t: g.dataset("t")
            .and_then(|d| d.read_raw::<f64>())
            .at(p, "events/t")?,
        step: r32("step")?,
        kind: codes
            .iter()
            .map(|c| legend.get(&c.to_string()).cloned().unwrap_or_default())
            .collect(),
        mode_before: r32("mode_before")?,
        mode_after: r32("mode_after")?,
        pre: pre_ds.read_raw::<f64>().at(p, "events/pre")?,
        post: g
            .dataset("post")
            .and_then(|d| d.read_raw::<f64>())
            .at(p, "events/post")?,
    };
    Ok(TrajectoryData {
        attrs,
        columns,
        events,
        dim,
    })
}

/// Writes `data` as CSV to `path` (refused if it exists, unless `force`). Floats are written
/// with Rust's shortest round-trip formatting: reading them back gives the same bits.
pub fn write_trajectory_csv(
    path: impl AsRef<Path>,
    force: bool,
    data: &TrajectoryData,
) -> Result<()> {
    let path = path.as_ref();
    data.validate()?;
    write_text_atomically(path, force, |w| {
        writeln!(w, "# format: {TRAJECTORY_FORMAT}")?;
        writeln!(w, "# version: {}", env!("CARGO_PKG_VERSION"))?;
        for (k, v) in &data.attrs {
            writeln!(w, "# {k}: {v}")?;
        }
        let mut header = Vec::new();
        let mut units = Vec::new();
        for c in &data.columns {
            if c.width == 1 {
                header.push(c.name.clone());
                units.push(format!("{}={}", c.name, c.units));
            } else {
                for comp in &c.components {
                    header.push(comp.clone());
                    units.push(format!("{comp}={}", c.units));
                }
            }
        }
        writeln!(w, "# units: {}", units.join(","))?;
        let e = &data.events;
        writeln!(w, "# events: t,step,kind,mode_before,mode_after")?;
        for i in 0..e.t.len() {
            writeln!(
                w,
                "# event: {:?},{},{},{},{}",
                e.t[i], e.step[i], e.kind[i], e.mode_before[i], e.mode_after[i]
            )?;
        }
        writeln!(w, "{}", header.join(","))?;
        let mut line = String::new();
        for i in 0..data.len() {
            line.clear();
            for c in &data.columns {
                for v in &c.values[i * c.width..(i + 1) * c.width] {
                    if !line.is_empty() {
                        line.push(',');
                    }
                    if c.integer {
                        line.push_str(&format!("{}", *v as u32));
                    } else {
                        line.push_str(&format!("{v:?}"));
                    }
                }
            }
            writeln!(w, "{line}")?;
        }
        Ok(())
    })
}
