//! The file of `pdw-sweep mfpt --over PARAM=A:B:N`: the mean first-passage time on random
//! slopes and the gait sensitivity norm of the stable gait at each value of a model parameter.
//!
//! ```text
//! /              attrs: format ("pdw-sweep mfpt over v1"), version, command, created, model,
//!                       params (JSON object of the model's parameters at the first value)
//! /over          attrs: param (the parameter's name), terrain ("slope"), distribution (as in
//!                       the mfpt file), sd (rad), seed,
//!                       walkers, max_steps, estimator, indicators (of the norm, comma
//!                       separated), chain_mesh_coarse, chain_mesh_fine (0 without the chain),
//!                       spearman (rank correlation of GSN and MFPT over the values with both)
//! /over/values   f64 [N] the parameter's values
//! /over/mean     f64 [N] the mean slope at each value (rad)
//! /over/stable   u64 [N] 1 where the model has a stable period-one gait, else 0 (every
//!                       other column is NaN / 0 there)
//! /over/mfpt, /over/stderr, /over/restricted_mean, /over/chain_mfpt_coarse,
//! /over/chain_mfpt_fine, /over/gsn      f64 [N]
//! /over/falls, /over/censored, /over/total_steps     u64 [N]
//! ```
//! Written whole to a temporary sibling and renamed into place.

use std::path::Path;

use crate::h5util::{
    get_attr, get_str, open_file, put, set_attr, set_str, write_h5_atomically, At,
};
use crate::{time, Result, StoreError};

/// Value of the root attribute `format` of an MFPT-over-a-parameter file.
pub const MFPT_OVER_FORMAT: &str = "pdw-sweep mfpt over v1";
const KIND: &str = "an mfpt over file";

/// The contents of an MFPT-over-a-parameter file (module docs).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct MfptOverData {
    pub command: String,
    pub model: String,
    pub params: String,
    pub param: String,
    pub terrain: String,
    /// The distribution of the standardised draws ([`crate::MfptData::distribution`]).
    pub distribution: String,
    pub sd: f64,
    pub seed: u64,
    pub walkers: u64,
    pub max_steps: u64,
    pub estimator: String,
    pub indicators: String,
    pub chain_mesh: [u64; 2],
    pub spearman: f64,
    pub values: Vec<f64>,
    pub mean: Vec<f64>,
    pub mfpt: Vec<f64>,
    pub stderr: Vec<f64>,
    pub restricted_mean: Vec<f64>,
    pub chain_mfpt_coarse: Vec<f64>,
    pub chain_mfpt_fine: Vec<f64>,
    pub gsn: Vec<f64>,
    pub stable: Vec<u64>,
    pub falls: Vec<u64>,
    pub censored: Vec<u64>,
    pub total_steps: Vec<u64>,
}

impl MfptOverData {
    /// The `f64` columns by name, in file order.
    fn columns(&self) -> [(&'static str, &Vec<f64>); 8] {
        [
            ("values", &self.values),
            ("mean", &self.mean),
            ("mfpt", &self.mfpt),
            ("stderr", &self.stderr),
            ("restricted_mean", &self.restricted_mean),
            ("chain_mfpt_coarse", &self.chain_mfpt_coarse),
            ("chain_mfpt_fine", &self.chain_mfpt_fine),
            ("gsn", &self.gsn),
        ]
    }

    /// The count columns by name.
    fn counts(&self) -> [(&'static str, &Vec<u64>); 4] {
        [
            ("stable", &self.stable),
            ("falls", &self.falls),
            ("censored", &self.censored),
            ("total_steps", &self.total_steps),
        ]
    }
}

/// Writes `data` to `path` (refused if it exists, unless `force`); every column must have one
/// value per parameter value.
pub fn write_mfpt_over(path: impl AsRef<Path>, force: bool, data: &MfptOverData) -> Result<()> {
    let n = data.values.len();
    let lens = data.columns().map(|c| c.1.len());
    let counts = data.counts().map(|c| c.1.len());
    if n == 0 || lens.iter().chain(&counts).any(|&l| l != n) {
        return Err(StoreError::invalid(
            "mfpt over",
            "every column needs one value per parameter value",
        ));
    }
    write_h5_atomically(path.as_ref(), force, |p, f| {
        for (k, v) in [
            ("format", MFPT_OVER_FORMAT),
            ("version", env!("CARGO_PKG_VERSION")),
            ("command", &data.command),
            ("created", &time::now_rfc3339()),
            ("model", &data.model),
            ("params", &data.params),
        ] {
            set_str(p, f, k, v)?;
        }
        let g = f.create_group("over").at(p, "creating /over")?;
        for (k, v) in [
            ("param", &data.param),
            ("terrain", &data.terrain),
            ("distribution", &data.distribution),
            ("estimator", &data.estimator),
            ("indicators", &data.indicators),
        ] {
            set_str(p, &g, k, v)?;
        }
        set_attr(p, &g, "sd", &data.sd)?;
        set_attr(p, &g, "spearman", &data.spearman)?;
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

/// Reads a file written by [`write_mfpt_over`] (refused if its `format` is another).
pub fn read_mfpt_over(path: impl AsRef<Path>) -> Result<MfptOverData> {
    let p = path.as_ref();
    let f = open_file(p, false)?;
    let fmt = get_str(p, KIND, &f, "format")?;
    if fmt != MFPT_OVER_FORMAT {
        return Err(StoreError::Format {
            path: p.to_path_buf(),
            expected: KIND,
            detail: format!("format is {fmt:?}, expected {MFPT_OVER_FORMAT:?}"),
        });
    }
    let g = f.group("over").at(p, "opening /over")?;
    let f64s = |k: &str| -> Result<Vec<f64>> {
        g.dataset(k)
            .at(p, &format!("opening /over/{k}"))?
            .read_raw()
            .at(p, &format!("reading /over/{k}"))
    };
    let u64s = |k: &str| -> Result<Vec<u64>> {
        g.dataset(k)
            .at(p, &format!("opening /over/{k}"))?
            .read_raw()
            .at(p, &format!("reading /over/{k}"))
    };
    let u = |k: &str| get_attr::<u64>(p, KIND, &g, k);
    let s = |k: &str| get_str(p, KIND, &g, k);
    Ok(MfptOverData {
        command: get_str(p, KIND, &f, "command")?,
        model: get_str(p, KIND, &f, "model")?,
        params: get_str(p, KIND, &f, "params")?,
        param: s("param")?,
        terrain: s("terrain")?,
        distribution: crate::mfpt::distribution(p, KIND, &g)?,
        estimator: s("estimator")?,
        indicators: s("indicators")?,
        sd: get_attr::<f64>(p, KIND, &g, "sd")?,
        spearman: get_attr::<f64>(p, KIND, &g, "spearman")?,
        seed: u("seed")?,
        walkers: u("walkers")?,
        max_steps: u("max_steps")?,
        chain_mesh: [u("chain_mesh_coarse")?, u("chain_mesh_fine")?],
        values: f64s("values")?,
        mean: f64s("mean")?,
        mfpt: f64s("mfpt")?,
        stderr: f64s("stderr")?,
        restricted_mean: f64s("restricted_mean")?,
        chain_mfpt_coarse: f64s("chain_mfpt_coarse")?,
        chain_mfpt_fine: f64s("chain_mfpt_fine")?,
        gsn: f64s("gsn")?,
        stable: u64s("stable")?,
        falls: u64s("falls")?,
        censored: u64s("censored")?,
        total_steps: u64s("total_steps")?,
    })
}
