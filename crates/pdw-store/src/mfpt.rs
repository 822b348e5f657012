//! The mean-first-passage-time file of `pdw-sweep mfpt`: how many steps walkers on random
//! terrain take before they fall (Byl & Tedrake, "Metastable walking machines", IJRR 2009).
//!
//! ```text
//! /                 attrs: format ("pdw-sweep mfpt v1"), version, command, created, model,
//!                          params (JSON object of the model's parameters at the mean slope)
//! /mfpt             attrs: method ("monte carlo"), terrain ("slope" or "step-down"),
//!                          terrain_unit (of mean and sd: "rad" for slopes, the model's length
//!                          unit for step heights; "rad" when absent), distribution (of the
//!                          standardised draws ξ, slope = mean + sd ξ: "normal", "uniform on
//!                          [-sqrt 3, sqrt 3] (variance 1)" or "file:PATH (…)" with the file's
//!                          count, mean and sd; "normal" when absent), mean, sd,
//!                          seed, walkers, max_steps, falls, censored, total_steps, mfpt,
//!                          stderr (steps / falls and its standard error), restricted_mean,
//!                          restricted_stderr (mean of min(T, max_steps)), estimator (text),
//!                          elapsed_s; with the Markov chain (method "monte carlo + markov
//!                          chain") also chain_* numbers (chain_mfpt_coarse, chain_mfpt_fine,
//!                          chain_mesh_coarse, …: see `MfptData::chain`)
//! /mfpt/survival    f64 [K + 1] fraction of walkers that completed at least k steps, k = 0 … K,
//!                   K the longest walk (at most max_steps heel strikes; 0 beyond K)
//! /mfpt/failures    u64 [F] falls per kind; attr kinds (JSON list of the F kinds' names)
//! /mfpt/start       f64 [d] the section state the walkers start from; attr names (JSON list)
//! ```
//! Written whole to a temporary sibling and renamed into place.

use std::path::Path;

use hdf5::{File, Group};

use crate::h5util::{
    get_attr, get_str, open_file, put, set_attr, set_str, write_h5_atomically, At,
};
use crate::{time, Result, StoreError};

/// Value of the root attribute `format` of an MFPT file.
pub const MFPT_FORMAT: &str = "pdw-sweep mfpt v1";
const KIND: &str = "pdw-sweep mfpt";

/// Everything an MFPT file holds.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct MfptData {
    pub command: String,
    pub model: String,
    /// The model's parameters (JSON object text).
    pub params: String,
    /// `"monte carlo"`.
    pub method: String,
    /// `"slope"` or `"step-down"`.
    pub terrain: String,
    /// The distribution of the standardised draws, in words (module docs).
    pub distribution: String,
    /// The unit of `mean` and `sd`: `"rad"`, or the model's length unit for step heights.
    pub terrain_unit: String,
    pub mean: f64,
    pub sd: f64,
    pub seed: u64,
    pub walkers: u64,
    pub max_steps: u64,
    pub falls: u64,
    pub censored: u64,
    pub total_steps: u64,
    pub mfpt: f64,
    pub stderr: f64,
    pub restricted_mean: f64,
    pub restricted_stderr: f64,
    /// How `mfpt` and `stderr` were estimated, in words.
    pub estimator: String,
    /// The survival fractions for k = 0 … K, K the longest walk (at most `max_steps`).
    pub survival: Vec<f64>,
    /// Fall kinds and their counts.
    pub failures: Vec<(String, u64)>,
    pub start: Vec<f64>,
    pub start_names: Vec<String>,
    pub elapsed_s: f64,
    /// The Markov chain's numbers as `(name, value)`, stored as the attributes `chain_NAME` of
    /// `/mfpt` (empty without the chain).
    pub chain: Vec<(String, f64)>,
}

impl MfptData {
    /// Checks the counts and the survival curve (from 1, not increasing, in [0, 1]).
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(StoreError::invalid("mfpt", m));
        // the curve ends at the longest walk (at most max_steps heel strikes)
        if self.survival.is_empty() || self.survival.len() as u64 > self.max_steps.saturating_add(1)
        {
            return bad(format!(
                "survival has {} values for max_steps {} (1 to max_steps + 1 allowed)",
                self.survival.len(),
                self.max_steps
            ));
        }
        if self.falls + self.censored != self.walkers
            || self.failures.iter().map(|f| f.1).sum::<u64>() != self.falls
        {
            return bad("falls, censored walkers and fall kinds do not add up".into());
        }
        let monotone = self.survival.windows(2).all(|w| w[1] <= w[0]);
        if !monotone || self.survival.iter().any(|s| !(0.0..=1.0).contains(s)) {
            return bad("the survival curve must fall from at most 1 to at least 0".into());
        }
        if self.start.len() != self.start_names.len() {
            return bad("start and start_names differ in length".into());
        }
        Ok(())
    }
}

/// Writes `data` to `path` (refused if it exists, unless `force`).
pub fn write_mfpt(path: impl AsRef<Path>, force: bool, data: &MfptData) -> Result<()> {
    let path = path.as_ref();
    data.validate()?;
    write_h5_atomically(path, force, |tmp, f| fill(tmp, f, data))
}

fn json_list(v: &[String]) -> String {
    serde_json::to_string(v).unwrap_or_default()
}

fn fill(p: &Path, f: &File, d: &MfptData) -> Result<()> {
    for (k, v) in [
        ("format", MFPT_FORMAT),
        ("version", env!("CARGO_PKG_VERSION")),
        ("command", &d.command),
        ("created", &time::now_rfc3339()),
        ("model", &d.model),
        ("params", &d.params),
    ] {
        set_str(p, f, k, v)?;
    }
    let g = f.create_group("mfpt").at(p, "creating /mfpt")?;
    for (k, v) in [
        ("method", &d.method),
        ("terrain", &d.terrain),
        ("distribution", &d.distribution),
        ("terrain_unit", &d.terrain_unit),
        ("estimator", &d.estimator),
    ] {
        set_str(p, &g, k, v)?;
    }
    for (k, v) in [
        ("seed", d.seed),
        ("walkers", d.walkers),
        ("max_steps", d.max_steps),
        ("falls", d.falls),
        ("censored", d.censored),
        ("total_steps", d.total_steps),
    ] {
        set_attr(p, &g, k, &v)?;
    }
    for (k, v) in [
        ("mean", d.mean),
        ("sd", d.sd),
        ("mfpt", d.mfpt),
        ("stderr", d.stderr),
        ("restricted_mean", d.restricted_mean),
        ("restricted_stderr", d.restricted_stderr),
        ("elapsed_s", d.elapsed_s),
    ] {
        set_attr(p, &g, k, &v)?;
    }
    for (k, v) in &d.chain {
        set_attr(p, &g, &format!("chain_{k}"), v)?;
    }
    put_curve(p, &g, "survival", &d.survival)?;
    let counts: Vec<u64> = d.failures.iter().map(|x| x.1).collect();
    let kinds: Vec<String> = d.failures.iter().map(|x| x.0.clone()).collect();
    let fd = put(p, &g, "failures", counts.as_slice())?;
    set_str(p, &fd, "kinds", &json_list(&kinds))?;
    let sd = put(p, &g, "start", d.start.as_slice())?;
    set_str(p, &sd, "names", &json_list(&d.start_names))?;
    Ok(())
}

/// Values per chunk of a long curve ([`put_curve`]).
const CURVE_CHUNK: usize = 1 << 16;

/// Deflate level of a long curve (the basin's, [`crate::basin`]).
const CURVE_DEFLATE: u8 = 4;

/// A survival curve as a 1-D dataset: contiguous up to [`CURVE_CHUNK`] values, else chunked,
/// byte-shuffled and deflated — a curve of a long walk (`--max-steps` 2·10⁶: 16 MB raw) holds
/// long runs of equal fractions `k / walkers`, which compress to a small part of that. Readers
/// see the same values either way (HDF5 undoes the filters).
fn put_curve(p: &Path, g: &hdf5::Group, name: &str, v: &[f64]) -> Result<hdf5::Dataset> {
    if v.len() <= CURVE_CHUNK {
        return put(p, g, name, v);
    }
    g.new_dataset_builder()
        .chunk(CURVE_CHUNK)
        .shuffle()
        .deflate(CURVE_DEFLATE)
        .with_data(v)
        .create(name)
        .at(p, &format!("writing {}/{name}", g.name()))
}

/// Reads an MFPT file.
pub fn read_mfpt(path: impl AsRef<Path>) -> Result<MfptData> {
    let p = path.as_ref();
    let f = open_file(p, false)?;
    let fmt = get_str(p, KIND, &f, "format")?;
    if fmt != MFPT_FORMAT {
        return Err(StoreError::Format {
            path: p.to_path_buf(),
            expected: KIND,
            detail: format!("format is {fmt:?}, expected {MFPT_FORMAT:?}"),
        });
    }
    let g = f.group("mfpt").at(p, "opening /mfpt")?;
    let mut d = read_group(p, &g)?;
    let mut names = g.attr_names().at(p, "listing attributes")?;
    names.sort();
    for a in names {
        if let Some(k) = a.strip_prefix("chain_") {
            d.chain
                .push((k.to_string(), get_attr::<f64>(p, KIND, &g, &a)?));
        }
    }
    d.command = get_str(p, KIND, &f, "command")?;
    d.model = get_str(p, KIND, &f, "model")?;
    d.params = get_str(p, KIND, &f, "params")?;
    Ok(d)
}

/// The `/mfpt` group's attributes and datasets.
fn read_group(p: &Path, g: &Group) -> Result<MfptData> {
    let json = |text: String, what: &str| -> Result<Vec<String>> {
        serde_json::from_str(&text).map_err(|e| StoreError::Format {
            path: p.to_path_buf(),
            expected: KIND,
            detail: format!("{what}: {e}"),
        })
    };
    let read = |name: &str| -> Result<hdf5::Dataset> {
        g.dataset(name).at(p, &format!("opening /mfpt/{name}"))
    };
    let (fd, sd) = (read("failures")?, read("start")?);
    let counts: Vec<u64> = fd.read_raw().at(p, "reading /mfpt/failures")?;
    let kinds = json(get_str(p, KIND, &fd, "kinds")?, "failure kinds")?;
    let u = |k: &str| get_attr::<u64>(p, KIND, g, k);
    let x = |k: &str| get_attr::<f64>(p, KIND, g, k);
    Ok(MfptData {
        method: get_str(p, KIND, g, "method")?,
        terrain: get_str(p, KIND, g, "terrain")?,
        distribution: distribution(p, KIND, g)?,
        terrain_unit: terrain_unit(p, KIND, g)?,
        estimator: get_str(p, KIND, g, "estimator")?,
        mean: x("mean")?,
        sd: x("sd")?,
        seed: u("seed")?,
        walkers: u("walkers")?,
        max_steps: u("max_steps")?,
        falls: u("falls")?,
        censored: u("censored")?,
        total_steps: u("total_steps")?,
        mfpt: x("mfpt")?,
        stderr: x("stderr")?,
        restricted_mean: x("restricted_mean")?,
        restricted_stderr: x("restricted_stderr")?,
        elapsed_s: x("elapsed_s")?,
        survival: read("survival")?
            .read_raw()
            .at(p, "reading /mfpt/survival")?,
        failures: kinds.into_iter().zip(counts).collect(),
        start: sd.read_raw().at(p, "reading /mfpt/start")?,
        start_names: json(get_str(p, KIND, &sd, "names")?, "start names")?,
        ..MfptData::default()
    })
}

/// Value of the root attribute `format` of an MFPT-against-disturbance file.
pub const MFPT_CURVE_FORMAT: &str = "pdw-sweep mfpt curve v1";
const CURVE_KIND: &str = "pdw-sweep mfpt curve";

/// The MFPT at each of several slope standard deviations (`pdw-sweep mfpt --sd A:B:N`), one
/// Monte Carlo run per value with the same seed (the same standard normals scaled by each σ),
/// and the Markov chain's MFPT at two meshes where it ran (NaN where not):
///
/// ```text
/// /                 attrs: format ("pdw-sweep mfpt curve v1"), version, command, created, model,
///                          params (JSON object)
/// /curve            attrs: terrain, terrain_unit, distribution (as in the mfpt file), mean,
///                          seed, walkers,
///                          max_steps, estimator,
///                          chain_mesh_coarse, chain_mesh_fine (0 without the chain)
/// /curve/sd         f64 [N] the standard deviations (terrain_unit)
/// /curve/mfpt, /curve/stderr, /curve/restricted_mean, /curve/chain_mfpt_coarse,
/// /curve/chain_mfpt_fine       f64 [N]
/// /curve/falls, /curve/censored, /curve/total_steps       u64 [N]
/// ```
#[derive(Clone, Debug, PartialEq, Default)]
pub struct MfptCurveData {
    pub command: String,
    pub model: String,
    pub params: String,
    pub terrain: String,
    /// [`MfptData::distribution`].
    pub distribution: String,
    /// The unit of `mean` and `sd` ([`MfptData::terrain_unit`]).
    pub terrain_unit: String,
    pub mean: f64,
    pub seed: u64,
    pub walkers: u64,
    pub max_steps: u64,
    pub estimator: String,
    pub chain_mesh: [u64; 2],
    pub sd: Vec<f64>,
    pub mfpt: Vec<f64>,
    pub stderr: Vec<f64>,
    pub restricted_mean: Vec<f64>,
    pub chain_mfpt_coarse: Vec<f64>,
    pub chain_mfpt_fine: Vec<f64>,
    pub falls: Vec<u64>,
    pub censored: Vec<u64>,
    pub total_steps: Vec<u64>,
}

impl MfptCurveData {
    /// The `f64` columns by name, in file order.
    fn columns(&self) -> [(&'static str, &Vec<f64>); 6] {
        [
            ("sd", &self.sd),
            ("mfpt", &self.mfpt),
            ("stderr", &self.stderr),
            ("restricted_mean", &self.restricted_mean),
            ("chain_mfpt_coarse", &self.chain_mfpt_coarse),
            ("chain_mfpt_fine", &self.chain_mfpt_fine),
        ]
    }

    /// The count columns by name.
    fn counts(&self) -> [(&'static str, &Vec<u64>); 3] {
        [
            ("falls", &self.falls),
            ("censored", &self.censored),
            ("total_steps", &self.total_steps),
        ]
    }
}

/// Writes `data` to `path` (refused if it exists, unless `force`); every column must have one
/// value per standard deviation.
pub fn write_mfpt_curve(path: impl AsRef<Path>, force: bool, data: &MfptCurveData) -> Result<()> {
    let n = data.sd.len();
    let lens = data.columns().map(|c| c.1.len());
    let counts = data.counts().map(|c| c.1.len());
    if n == 0 || lens.iter().chain(&counts).any(|&l| l != n) {
        return Err(StoreError::invalid(
            "mfpt curve",
            "every column needs one value per standard deviation",
        ));
    }
    write_h5_atomically(path.as_ref(), force, |p, f| {
        for (k, v) in [
            ("format", MFPT_CURVE_FORMAT),
            ("version", env!("CARGO_PKG_VERSION")),
            ("command", &data.command),
            ("created", &time::now_rfc3339()),
            ("model", &data.model),
            ("params", &data.params),
        ] {
            set_str(p, f, k, v)?;
        }
        let g = f.create_group("curve").at(p, "creating /curve")?;
        set_str(p, &g, "terrain", &data.terrain)?;
        set_str(p, &g, "terrain_unit", &data.terrain_unit)?;
        set_str(p, &g, "distribution", &data.distribution)?;
        set_str(p, &g, "estimator", &data.estimator)?;
        set_attr(p, &g, "mean", &data.mean)?;
        for (k, v) in [
            ("seed", data.seed),
            ("walkers", data.walkers),
            ("max_steps", data.max_steps),
            ("chain_mesh_coarse", data.chain_mesh[0]),
            ("chain_mesh_fine", data.chain_mesh[1]),
        ] {
            set_attr(p, &g, k, &v)?;
        }
        for (k, v) in data.columns() {
            put(p, &g, k, v.as_slice())?;
        }
        for (k, v) in data.counts() {
            put(p, &g, k, v.as_slice())?;
        }
        Ok(())
    })
}

/// Reads an MFPT-against-disturbance file.
pub fn read_mfpt_curve(path: impl AsRef<Path>) -> Result<MfptCurveData> {
    let p = path.as_ref();
    let f = open_file(p, false)?;
    let fmt = get_str(p, CURVE_KIND, &f, "format")?;
    if fmt != MFPT_CURVE_FORMAT {
        return Err(StoreError::Format {
            path: p.to_path_buf(),
            expected: CURVE_KIND,
            detail: format!("format is {fmt:?}, expected {MFPT_CURVE_FORMAT:?}"),
        });
    }
    let g = f.group("curve").at(p, "opening /curve")?;
    let f64s = |k: &str| -> Result<Vec<f64>> {
        g.dataset(k)
            .at(p, &format!("opening /curve/{k}"))?
            .read_raw()
            .at(p, &format!("reading /curve/{k}"))
    };
    let u64s = |k: &str| -> Result<Vec<u64>> {
        g.dataset(k)
            .at(p, &format!("opening /curve/{k}"))?
            .read_raw()
            .at(p, &format!("reading /curve/{k}"))
    };
    let u = |k: &str| get_attr::<u64>(p, CURVE_KIND, &g, k);
    Ok(MfptCurveData {
        command: get_str(p, CURVE_KIND, &f, "command")?,
        model: get_str(p, CURVE_KIND, &f, "model")?,
        params: get_str(p, CURVE_KIND, &f, "params")?,
        terrain: get_str(p, CURVE_KIND, &g, "terrain")?,
        terrain_unit: terrain_unit(p, CURVE_KIND, &g)?,
        distribution: distribution(p, CURVE_KIND, &g)?,
        estimator: get_str(p, CURVE_KIND, &g, "estimator")?,
        mean: get_attr::<f64>(p, CURVE_KIND, &g, "mean")?,
        seed: u("seed")?,
        walkers: u("walkers")?,
        max_steps: u("max_steps")?,
        chain_mesh: [u("chain_mesh_coarse")?, u("chain_mesh_fine")?],
        sd: f64s("sd")?,
        mfpt: f64s("mfpt")?,
        stderr: f64s("stderr")?,
        restricted_mean: f64s("restricted_mean")?,
        chain_mfpt_coarse: f64s("chain_mfpt_coarse")?,
        chain_mfpt_fine: f64s("chain_mfpt_fine")?,
        falls: u64s("falls")?,
        censored: u64s("censored")?,
        total_steps: u64s("total_steps")?,
    })
}

/// The `terrain_unit` attribute of `g`, `"rad"` in files written before step heights existed.
/// The `distribution` attribute of `g`, `"normal"` in files written before it was recorded.
pub(crate) fn distribution(p: &Path, kind: &'static str, g: &Group) -> Result<String> {
    if g.attr("distribution").is_ok() {
        get_str(p, kind, g, "distribution")
    } else {
        Ok("normal".into())
    }
}

fn terrain_unit(p: &Path, kind: &'static str, g: &Group) -> Result<String> {
    if g.attr("terrain_unit").is_ok() {
        get_str(p, kind, g, "terrain_unit")
    } else {
        Ok("rad".into())
    }
}
