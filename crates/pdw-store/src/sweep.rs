//! The parameter-sweep (continuation) file of `pdw-sweep fixedpoint --sweep`.
//!
//! ```text
//! /                  attrs: format ("pdw-sweep sweep v2"), version, command, created, model,
//!                           parameter (name swept), params (JSON object: the other parameters),
//!                           section_names (JSON list of the d section coordinates),
//!                           elapsed_s (wall time of the computation, seconds), and one JSON text
//!                           attribute setting_NAME per entry of `settings` (e.g.
//!                           setting_continuation, setting_integrator; read back sorted by name)
//! /branches/NNN      one group per branch (000, 001, …); attrs name, period_strides (K);
//!                    parameter f64 [n], section f64 [n, d] (the orbit's first point),
//!                    multipliers_re / multipliers_im f64 [n, m] (of the K-stride map, by
//!                    decreasing modulus, signed), stable u8 [n] (1 = all |λ| < 1); measured
//!                    branches also hold orbit f64 [n, K, d] (the K section points in stride
//!                    order, orbit[i, 0] = section[i]), period f64 [n] (the K strides' time),
//!                    step_length f64 [n, K] (per stride, NaN if the model reports none),
//!                    speed f64 [n] (K step lengths / period), and per stride [n, K]:
//!                    validity_checked, valid, normal_force_negative, knee_unlocks,
//!                    swing_foot_scuffs, impact_violation (u8, 1 = yes), min_normal_force,
//!                    max_friction_required, min_knee_torque, min_clearance, scuff_depth,
//!                    min_impact_margin, min_relative_margin (f64, NaN where not defined),
//!                    binding_criterion (u8; attr legend: JSON code → name, see
//!                    [`BINDING_CRITERIA`]); the last six are absent from older files
//! /bifurcations/NNN  attrs kind ("period-doubling", "fold", "neimark-sacker", …), parameter,
//!                    branch (index); section f64 [d]
//! /orbit             optional brute-force orbit diagram: parameter f64 [n], points f64 [n, s]
//!                    (s section samples after transients; NaN where the walker fell);
//!                    attr coordinate (section coordinate sampled)
//! ```
//! Version 1 files (without the measured datasets, `elapsed_s` and settings) read with those
//! left empty. The file is written whole to a temporary sibling and renamed into place, so an
//! existing file is replaced only by a complete one (and only with `force`).

use std::path::Path;

use hdf5::{File, Group};
use ndarray::{Array2, Array3};

use crate::h5util::{
    get_attr, get_str, matrix, open_file, put, set_attr, set_str, write_h5_atomically,
    write_text_atomically, At,
};
use crate::{time, Result, StoreError};

/// Value of the root attribute `format` of a sweep file.
pub const SWEEP_FORMAT: &str = "pdw-sweep sweep v2";
/// The previous format, still read.
const SWEEP_FORMAT_V1: &str = "pdw-sweep sweep v1";
const KIND: &str = "pdw-sweep sweep";

/// Validity of one stride of a branch point (what pdw-limit's `Validity` reports along it).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct StrideValidity {
    /// False where the model computes no constraint forces (the flags below are then false and
    /// the forces NaN).
    pub checked: bool,
    /// No flag raised.
    pub valid: bool,
    pub normal_force_negative: bool,
    pub knee_unlocks: bool,
    pub swing_foot_scuffs: bool,
    pub min_normal_force: f64,
    pub max_friction_required: f64,
    /// Smallest knee-lock torque; NaN without locked knees.
    pub min_knee_torque: f64,
    /// An impact needs a pulling contact or stop (a negative impulse margin).
    pub impact_violation: bool,
    /// Smallest interior clearance of the swing foot where the model's clearance rule checks
    /// it (length units); NaN where the foot only rises and falls, or without a swing foot.
    pub min_clearance: f64,
    /// Deepest point of the swing foot below the slope anywhere in the swing (0 if never).
    pub scuff_depth: f64,
    /// Smallest impact margin (model units of its entry); NaN without impact reports.
    pub min_impact_margin: f64,
    /// Smallest margin relative to its natural scale (the binding criterion's); NaN without.
    pub min_relative_margin: f64,
    /// The binding criterion, an index into [`BINDING_CRITERIA`].
    pub binding: u8,
}

/// Names of [`StrideValidity::binding`] by code (the `legend` attribute of the
/// `binding_criterion` dataset): `impact` is any entry of an impact report.
pub const BINDING_CRITERIA: [&str; 6] = [
    "none",
    "normal_force",
    "stance_knee_torque",
    "swing_knee_torque",
    "swing_clearance",
    "impact",
];

impl StrideValidity {
    /// Not checked (the model computes no constraint forces).
    pub fn unchecked() -> Self {
        Self {
            min_normal_force: f64::NAN,
            max_friction_required: f64::NAN,
            min_knee_torque: f64::NAN,
            min_clearance: f64::NAN,
            scuff_depth: f64::NAN,
            min_impact_margin: f64::NAN,
            min_relative_margin: f64::NAN,
            ..Self::default()
        }
    }
}

/// One continuation branch: fixed points (or period-k orbits) along the swept parameter.
///
/// `orbit`, `period`, `step_length`, `speed` and `validity` are either all empty (not measured)
/// or hold one entry per point.
#[derive(Clone, Debug, PartialEq, Default)]
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
    /// (n × K × d) the K section points of each orbit in stride order (`orbit[i][0]` is
    /// `section[i]`).
    pub orbit: Vec<Vec<Vec<f64>>>,
    /// (n) duration of the K strides together.
    pub period: Vec<f64>,
    /// (n × K) step length of each stride (NaN if the model reports none).
    pub step_length: Vec<Vec<f64>>,
    /// (n) sum of the K step lengths / `period`.
    pub speed: Vec<f64>,
    /// (n × K) validity along each stride.
    pub validity: Vec<Vec<StrideValidity>>,
}

impl Branch {
    /// True if the per-point measurements (orbit, period, step length, speed, validity) are held.
    pub fn measured(&self) -> bool {
        !self.orbit.is_empty()
    }
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
#[derive(Clone, Debug, PartialEq, Default)]
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
    /// Root attributes describing the run, name → JSON text (e.g. `continuation`,
    /// `integrator`, `tolerances`).
    pub settings: Vec<(String, String)>,
    /// Wall time of the computation in seconds (NaN if unknown).
    pub elapsed_s: f64,
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
            if b.measured() {
                let k = b.period_strides as usize;
                if b.orbit.len() != n
                    || b.orbit
                        .iter()
                        .any(|o| o.len() != k || o.iter().any(|p| p.len() != d))
                    || b.period.len() != n
                    || b.speed.len() != n
                    || b.step_length.len() != n
                    || b.step_length.iter().any(|v| v.len() != k)
                    || b.validity.len() != n
                    || b.validity.iter().any(|v| v.len() != k)
                {
                    return Err(StoreError::invalid(
                        "sweep",
                        format!(
                            "branch {:?}: measured points need n × {k} × {d} orbit values, n \
                             periods and speeds, n × {k} step lengths and validity entries",
                            b.name
                        ),
                    ));
                }
            } else if !(b.period.is_empty()
                && b.speed.is_empty()
                && b.step_length.is_empty()
                && b.validity.is_empty())
            {
                return Err(StoreError::invalid(
                    "sweep",
                    format!(
                        "branch {:?}: period, step length, speed and validity need the orbit",
                        b.name
                    ),
                ));
            }
        }
        for (k, v) in &self.settings {
            if serde_json::from_str::<serde_json::Value>(v).is_err() {
                return Err(StoreError::invalid(
                    "sweep",
                    format!("setting {k:?} is not JSON text: {v:?}"),
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

/// Writes `data` to `path` (refused if it exists, unless `force`).
pub fn write_sweep(path: impl AsRef<Path>, force: bool, data: &SweepData) -> Result<()> {
    let path = path.as_ref();
    data.validate()?;
    write_h5_atomically(path, force, |tmp, f| fill(tmp, f, data))
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
    set_attr(p, f, "elapsed_s", &data.elapsed_s)?;
    for (k, v) in &data.settings {
        set_str(p, f, &format!("setting_{k}"), v)?;
    }
    let gb = f.create_group("branches").at(p, "creating /branches")?;
    for (i, b) in data.branches.iter().enumerate() {
        let g = gb
            .create_group(&format!("{i:03}"))
            .at(p, "creating a branch")?;
        set_str(p, &g, "name", &b.name)?;
        set_attr(p, &g, "period_strides", &b.period_strides)?;
        let m = b.multipliers.first().map_or(0, |v| v.len());
        put(p, &g, "parameter", &b.parameter)?;
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
        put(p, &g, "stable", &st)?;
        if b.measured() {
            write_measured(p, &g, b, d)?;
        }
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
        put(p, &g, "section", &z.section)?;
    }
    if let Some(o) = &data.orbit {
        let g = f.create_group("orbit").at(p, "creating /orbit")?;
        set_str(p, &g, "coordinate", &o.coordinate)?;
        put(p, &g, "parameter", &o.parameter)?;
        let s = o.points.first().map_or(0, |r| r.len());
        put(p, &g, "points", &matrix(&o.points, s))?;
    }
    Ok(())
}

/// The per-stride validity fields, in file order: flags (u8) then forces (f64).
type FlagOf = fn(&StrideValidity) -> bool;
type ForceOf = fn(&StrideValidity) -> f64;
const FLAGS: [(&str, FlagOf); 6] = [
    ("validity_checked", |v| v.checked),
    ("valid", |v| v.valid),
    ("normal_force_negative", |v| v.normal_force_negative),
    ("knee_unlocks", |v| v.knee_unlocks),
    ("swing_foot_scuffs", |v| v.swing_foot_scuffs),
    ("impact_violation", |v| v.impact_violation),
];
const FORCES: [(&str, ForceOf); 7] = [
    ("min_normal_force", |v| v.min_normal_force),
    ("max_friction_required", |v| v.max_friction_required),
    ("min_knee_torque", |v| v.min_knee_torque),
    ("min_clearance", |v| v.min_clearance),
    ("scuff_depth", |v| v.scuff_depth),
    ("min_impact_margin", |v| v.min_impact_margin),
    ("min_relative_margin", |v| v.min_relative_margin),
];
/// Fields added after the first files of this format: absent from older files, read as
/// unchecked.
const ADDED: [&str; 6] = [
    "impact_violation",
    "min_clearance",
    "scuff_depth",
    "min_impact_margin",
    "min_relative_margin",
    "binding_criterion",
];

fn flag_mut<'a>(e: &'a mut StrideValidity, name: &str) -> &'a mut bool {
    match name {
        "validity_checked" => &mut e.checked,
        "valid" => &mut e.valid,
        "normal_force_negative" => &mut e.normal_force_negative,
        "knee_unlocks" => &mut e.knee_unlocks,
        "impact_violation" => &mut e.impact_violation,
        _ => &mut e.swing_foot_scuffs,
    }
}

fn force_mut<'a>(e: &'a mut StrideValidity, name: &str) -> &'a mut f64 {
    match name {
        "min_normal_force" => &mut e.min_normal_force,
        "max_friction_required" => &mut e.max_friction_required,
        "min_clearance" => &mut e.min_clearance,
        "scuff_depth" => &mut e.scuff_depth,
        "min_impact_margin" => &mut e.min_impact_margin,
        "min_relative_margin" => &mut e.min_relative_margin,
        _ => &mut e.min_knee_torque,
    }
}

fn write_measured(p: &Path, g: &Group, b: &Branch, d: usize) -> Result<()> {
    let n = b.parameter.len();
    let k = b.period_strides as usize;
    let flat: Vec<f64> = b.orbit.iter().flatten().flatten().copied().collect();
    let orbit = Array3::from_shape_vec((n, k, d), flat).expect("shape validated");
    put(p, g, "orbit", &orbit)?;
    put(p, g, "period", &b.period)?;
    put(p, g, "step_length", &matrix(&b.step_length, k))?;
    put(p, g, "speed", &b.speed)?;
    for (name, f) in FLAGS {
        let flat: Vec<u8> = b
            .validity
            .iter()
            .flatten()
            .map(|v| u8::from(f(v)))
            .collect();
        let a = Array2::from_shape_vec((n, k), flat).expect("shape validated");
        put(p, g, name, &a)?;
    }
    for (name, f) in FORCES {
        let rows: Vec<Vec<f64>> = b
            .validity
            .iter()
            .map(|v| v.iter().map(f).collect())
            .collect();
        put(p, g, name, &matrix(&rows, k))?;
    }
    let codes: Vec<u8> = b.validity.iter().flatten().map(|v| v.binding).collect();
    let a = Array2::from_shape_vec((n, k), codes).expect("shape validated");
    let ds = put(p, g, "binding_criterion", &a)?;
    let legend: serde_json::Map<String, serde_json::Value> = BINDING_CRITERIA
        .iter()
        .enumerate()
        .map(|(i, n)| (i.to_string(), serde_json::Value::from(*n)))
        .collect();
    set_str(
        p,
        &ds,
        "legend",
        &serde_json::Value::Object(legend).to_string(),
    )?;
    Ok(())
}

fn read_measured(p: &Path, g: &Group, b: &mut Branch) -> Result<()> {
    if !g.link_exists("orbit") {
        return Ok(());
    }
    let o = g
        .dataset("orbit")
        .and_then(|d| d.read::<f64, ndarray::Ix3>())
        .at(p, "orbit")?;
    b.orbit = o
        .outer_iter()
        .map(|m| m.rows().into_iter().map(|r| r.to_vec()).collect())
        .collect();
    let r1 = |n: &str| g.dataset(n).and_then(|d| d.read_raw::<f64>()).at(p, n);
    let r2 = |n: &str| g.dataset(n).and_then(|d| d.read_2d::<f64>()).at(p, n);
    b.period = r1("period")?;
    b.speed = r1("speed")?;
    b.step_length = rows(r2("step_length")?);
    let (n, k) = (b.orbit.len(), b.period_strides as usize);
    let mut v = vec![vec![StrideValidity::unchecked(); k]; n];
    let absent = |name: &str| ADDED.contains(&name) && !g.link_exists(name);
    for (name, _) in FLAGS {
        if absent(name) {
            continue;
        }
        let a = g
            .dataset(name)
            .and_then(|d| d.read_2d::<u8>())
            .at(p, name)?;
        for ((i, j), &x) in a.indexed_iter() {
            if let Some(e) = v.get_mut(i).and_then(|r| r.get_mut(j)) {
                *flag_mut(e, name) = x != 0;
            }
        }
    }
    for (name, _) in FORCES {
        if absent(name) {
            continue;
        }
        let a = r2(name)?;
        for ((i, j), &x) in a.indexed_iter() {
            if let Some(e) = v.get_mut(i).and_then(|r| r.get_mut(j)) {
                *force_mut(e, name) = x;
            }
        }
    }
    if !absent("binding_criterion") {
        let name = "binding_criterion";
        let a = g
            .dataset(name)
            .and_then(|d| d.read_2d::<u8>())
            .at(p, name)?;
        for ((i, j), &x) in a.indexed_iter() {
            if let Some(e) = v.get_mut(i).and_then(|r| r.get_mut(j)) {
                e.binding = x;
            }
        }
    }
    b.validity = v;
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
    if fmt != SWEEP_FORMAT && fmt != SWEEP_FORMAT_V1 {
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
        let mut b = Branch {
            name: get_str(p, KIND, &g, "name")?,
            period_strides: get_attr(p, KIND, &g, "period_strides")?,
            parameter: r1(&g, "parameter")?,
            section: rows(r2(&g, "section")?),
            multipliers,
            stable,
            ..Branch::default()
        };
        read_measured(p, &g, &mut b)?;
        branches.push(b);
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
    let elapsed_s = if f
        .attr_names()
        .at(p, "listing attributes")?
        .iter()
        .any(|a| a == "elapsed_s")
    {
        get_attr(p, KIND, &f, "elapsed_s")?
    } else {
        f64::NAN
    };
    const BUILTIN: [&str; 9] = [
        "format",
        "version",
        "command",
        "created",
        "model",
        "parameter",
        "params",
        "section_names",
        "elapsed_s",
    ];
    let mut settings = Vec::new();
    let mut names = f.attr_names().at(p, "listing attributes")?;
    names.sort();
    for a in names {
        if BUILTIN.contains(&a.as_str()) {
            continue;
        }
        // Settings are the setting_NAME attributes (provenance adds its own, others).
        if let Some(name) = a.strip_prefix("setting_") {
            settings.push((name.to_string(), get_str(p, KIND, &f, &a)?));
        }
    }
    Ok(SweepData {
        settings,
        elapsed_s,
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

/// The name of a [`StrideValidity::binding`] code.
pub fn binding_name(code: u8) -> &'static str {
    BINDING_CRITERIA
        .get(code as usize)
        .copied()
        .unwrap_or("none")
}

/// The columns of [`write_sweep_csv`]: `param, branch, branch_name, period_k, point`, the d
/// section coordinates, `period, step_length, speed, stable`, the validity fields
/// (`validity_checked, valid, normal_force_negative, knee_unlocks, swing_foot_scuffs,
/// impact_violation, min_normal_force, max_friction_required, min_knee_torque, min_clearance,
/// scuff_depth, min_impact_margin, min_relative_margin, binding_criterion` — the binding
/// criterion by name), then `lambda{i}_re, lambda{i}_im`
/// for each of the m multipliers (i = 1..m, by decreasing modulus).
pub fn sweep_csv_columns(data: &SweepData) -> Vec<String> {
    let m = data
        .branches
        .iter()
        .find_map(|b| b.multipliers.first().map(|v| v.len()))
        .unwrap_or(0);
    let mut c: Vec<String> = ["param", "branch", "branch_name", "period_k", "point"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    c.extend(data.section_names.iter().cloned());
    c.extend(["period", "step_length", "speed", "stable"].map(String::from));
    c.extend(FLAGS.iter().map(|(n, _)| n.to_string()));
    c.extend(FORCES.iter().map(|(n, _)| n.to_string()));
    c.push("binding_criterion".into());
    for i in 1..=m {
        c.push(format!("lambda{i}_re"));
        c.push(format!("lambda{i}_im"));
    }
    c
}

/// Writes the branches of `data` as CSV, one row per orbit point of every branch point (a
/// period-K point gives K rows, `point` = 0..K−1 in stride order; `period`, `speed`, `stable`
/// and the multipliers belong to the whole orbit and repeat on its K rows, `step_length` and
/// the validity fields to the stride from that point). Comment lines (`# key: value`) first,
/// then the header ([`sweep_csv_columns`]). Numbers are written in Rust's shortest form that
/// reads back to the same double (`NaN` where not defined); flags as 0/1. Branches without
/// measurements give one row per point with `point` 0 and NaN measurements.
pub fn write_sweep_csv(
    path: impl AsRef<Path>,
    force: bool,
    data: &SweepData,
    comments: &[(String, String)],
) -> Result<()> {
    use std::io::Write;
    let path = path.as_ref();
    data.validate()?;
    write_text_atomically(path, force, |w| {
        writeln!(w, "# format: {SWEEP_FORMAT} (csv)")?;
        writeln!(w, "# version: {}", env!("CARGO_PKG_VERSION"))?;
        writeln!(w, "# model: {}", data.model)?;
        writeln!(w, "# parameter: {}", data.parameter)?;
        for (k, v) in comments {
            writeln!(w, "# {k}: {}", v.replace('\n', " "))?;
        }
        writeln!(w, "{}", sweep_csv_columns(data).join(","))?;
        let num = |v: f64| format!("{v:?}");
        let flag = |b: bool| if b { "1" } else { "0" };
        for (bi, b) in data.branches.iter().enumerate() {
            let k = if b.measured() {
                b.period_strides as usize
            } else {
                1
            };
            for i in 0..b.parameter.len() {
                for j in 0..k {
                    let mut row: Vec<String> = vec![
                        num(b.parameter[i]),
                        bi.to_string(),
                        b.name.replace(',', ";"),
                        b.period_strides.to_string(),
                        j.to_string(),
                    ];
                    let s = b.orbit.get(i).map_or(&b.section[i], |o| &o[j]);
                    row.extend(s.iter().map(|&v| num(v)));
                    let nan = f64::NAN;
                    row.push(num(b.period.get(i).copied().unwrap_or(nan)));
                    row.push(num(b.step_length.get(i).map_or(nan, |v| v[j])));
                    row.push(num(b.speed.get(i).copied().unwrap_or(nan)));
                    row.push(flag(b.stable[i]).into());
                    let v = b
                        .validity
                        .get(i)
                        .map_or(StrideValidity::unchecked(), |v| v[j]);
                    row.extend(FLAGS.iter().map(|(_, f)| flag(f(&v)).to_string()));
                    row.extend(FORCES.iter().map(|(_, f)| num(f(&v))));
                    row.push(binding_name(v.binding).into());
                    for z in &b.multipliers[i] {
                        row.push(num(z.0));
                        row.push(num(z.1));
                    }
                    writeln!(w, "{}", row.join(","))?;
                }
            }
        }
        Ok(())
    })
}

/// The sweep as one JSON object: `model`, `parameter`, `params`, `section_names`, `elapsed_s`,
/// `settings` (name → value), `branches` (each with `id`, `name`, `period_k` and `points`, one
/// object per point: `param`, `section`, `orbit` (K points), `period`, `step_length` (K),
/// `speed`, `stable`, `multipliers` [{re, im}], `validity` (K objects)), `bifurcations` (`kind`,
/// `parameter`, `branch`, `section`) and `orbit_diagram` (`coordinate`, `parameter`,
/// `points`). NaN is written as `null`.
pub fn sweep_json(data: &SweepData) -> serde_json::Value {
    use serde_json::json;
    let validity = |v: &StrideValidity| {
        let mut o = serde_json::Map::new();
        for (n, f) in FLAGS {
            o.insert(n.into(), json!(f(v)));
        }
        for (n, f) in FORCES {
            o.insert(n.into(), json!(f(v)));
        }
        o.insert("binding_criterion".into(), json!(binding_name(v.binding)));
        serde_json::Value::Object(o)
    };
    let branches: Vec<serde_json::Value> = data
        .branches
        .iter()
        .enumerate()
        .map(|(bi, b)| {
            let points: Vec<serde_json::Value> = (0..b.parameter.len())
                .map(|i| {
                    json!({
                        "param": b.parameter[i],
                        "section": b.section[i],
                        "orbit": b.orbit.get(i),
                        "period": b.period.get(i),
                        "step_length": b.step_length.get(i),
                        "speed": b.speed.get(i),
                        "stable": b.stable[i],
                        "multipliers": b.multipliers[i].iter().map(|z| json!({"re": z.0, "im": z.1})).collect::<Vec<_>>(),
                        "validity": b.validity.get(i).map(|v| v.iter().map(validity).collect::<Vec<_>>()),
                    })
                })
                .collect();
            json!({
                "id": bi,
                "name": b.name,
                "period_k": b.period_strides,
                "points": points,
            })
        })
        .collect();
    let settings: serde_json::Map<String, serde_json::Value> = data
        .settings
        .iter()
        .map(|(k, v)| {
            (
                k.clone(),
                serde_json::from_str(v).unwrap_or(serde_json::Value::Null),
            )
        })
        .collect();
    json!({
        "format": SWEEP_FORMAT,
        "model": data.model,
        "parameter": data.parameter,
        "params": serde_json::from_str::<serde_json::Value>(&data.params).unwrap_or_default(),
        "section_names": data.section_names,
        "elapsed_s": data.elapsed_s,
        "settings": settings,
        "branches": branches,
        "bifurcations": data.bifurcations.iter().map(|z| json!({
            "kind": z.kind, "parameter": z.parameter, "branch": z.branch, "section": z.section,
        })).collect::<Vec<_>>(),
        "orbit_diagram": data.orbit.as_ref().map(|o| json!({
            "coordinate": o.coordinate, "parameter": o.parameter, "points": o.points,
        })),
    })
}
