//! The mean first-passage time over a model parameter (`pdw-sweep mfpt --over PARAM=A:B:N`),
//! the metastability companion of `basin --over`: at each value the stable period-one gait of
//! the model, its Monte Carlo MFPT on the same terrain (the same walkers and seed, so common
//! random numbers across the values), and its gait sensitivity norm ([`crate::gsn`]); a value
//! without a stable gait is kept and marked. The rank correlation of the two measures says how
//! well the cheap one orders the expensive one.

use crate::input::{InputError, Sweep};
use crate::mfpt::{self, MfptFlags, MfptPlan};
use crate::model::{build_with, BuiltModel, ModelChoice};
use pdw_limit::gsn::Indicator;
use pdw_limit::terrain::{MfptEstimate, SlopeTerrain};

/// The `N` evenly spaced values of `sw` (both ends included).
pub fn values(sw: &Sweep) -> Vec<f64> {
    (0..sw.n)
        .map(|i| sw.lo + (sw.hi - sw.lo) * i as f64 / (sw.n - 1) as f64)
        .collect()
}

/// The model of `choice` with `name` set to `value`, checked for random terrain.
pub fn model_at_value(
    choice: &ModelChoice,
    name: &str,
    value: f64,
) -> Result<BuiltModel, InputError> {
    let m = build_with(choice, &[(name.to_string(), value)])?;
    mfpt::check_model(&m)?;
    Ok(m)
}

/// The model `model` with the overrides `ov` and then `name` set to `value`, checked for random
/// terrain (Python's route, which holds its overrides as values).
pub fn model_with(
    model: &str,
    ov: &[(String, f64)],
    name: &str,
    value: f64,
) -> Result<BuiltModel, InputError> {
    let mut all = ov.to_vec();
    all.push((name.to_string(), value));
    let m = crate::model::build(model, &all)?;
    mfpt::check_model(&m)?;
    Ok(m)
}

/// One value's results: the stable gait (section coordinates) or why there is none, the Monte
/// Carlo estimate, the chain's MFPT at two meshes (NaN without it) and the GSN (NaN when it
/// has none, with the reason in `note`).
#[derive(Clone, Debug)]
pub struct OverRow {
    pub value: f64,
    pub mean: f64,
    pub gait: Option<Vec<f64>>,
    pub est: Option<MfptEstimate>,
    pub chain: [f64; 2],
    pub gsn: f64,
    pub note: Option<String>,
}

impl OverRow {
    /// A value without a stable gait (or without a run): everything NaN, the reason kept.
    pub fn missing(value: f64, mean: f64, note: String) -> Self {
        Self {
            value,
            mean,
            gait: None,
            est: None,
            chain: [f64::NAN; 2],
            gsn: f64::NAN,
            note: Some(note),
        }
    }
}

/// The plan at one value: `plan`'s walkers, steps, seed and standard deviation around the
/// model's own slope, checked.
pub fn plan_at(m: &BuiltModel, plan: &MfptPlan, flags: &MfptFlags) -> Result<MfptPlan, InputError> {
    let p = MfptPlan {
        terrain: SlopeTerrain {
            mean: m.slope(),
            ..plan.terrain.clone()
        },
        ..plan.clone()
    };
    mfpt::check_plan(&p, flags)?;
    Ok(p)
}

/// The GSN of `m`'s gait `s` for `ind`, or NaN and the reason.
pub fn gsn_at(m: &BuiltModel, s: &[f64], ind: &[Indicator]) -> (f64, Option<String>) {
    match crate::gsn::gait_sensitivity(m, s, ind, crate::gsn::default_integrator()) {
        Ok((_, g)) => (g.norm, None),
        Err(e) => (f64::NAN, Some(e.to_string())),
    }
}

/// Ranks of `v` (1-based), ties given their average rank.
fn ranks(v: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut r = vec![0.0; v.len()];
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && v[idx[j + 1]] == v[idx[i]] {
            j += 1;
        }
        for &k in &idx[i..=j] {
            r[k] = (i + j) as f64 / 2.0 + 1.0;
        }
        i = j + 1;
    }
    r
}

/// Spearman's rank correlation of the pairs where both are finite: the Pearson correlation of
/// their ranks (Spearman, Am. J. Psychol. 15, 1904), NaN with fewer than 3 pairs or a constant
/// side.
pub fn spearman(x: &[f64], y: &[f64]) -> f64 {
    let (xs, ys): (Vec<f64>, Vec<f64>) = x
        .iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, b)| (*a, *b))
        .unzip();
    if xs.len() < 3 {
        return f64::NAN;
    }
    let (rx, ry) = (ranks(&xs), ranks(&ys));
    let n = rx.len() as f64;
    let (mx, my) = (rx.iter().sum::<f64>() / n, ry.iter().sum::<f64>() / n);
    let cov: f64 = rx.iter().zip(&ry).map(|(a, b)| (a - mx) * (b - my)).sum();
    let vx: f64 = rx.iter().map(|a| (a - mx).powi(2)).sum();
    let vy: f64 = ry.iter().map(|b| (b - my).powi(2)).sum();
    if vx == 0.0 || vy == 0.0 {
        return f64::NAN;
    }
    cov / (vx * vy).sqrt()
}

/// One value's row without the chain: the stable gait of `m` (none: a marked row), the Monte
/// Carlo run of `p` from it, and its GSN for `ind`.
pub fn row(
    m: &BuiltModel,
    value: f64,
    p: &MfptPlan,
    ind: &[Indicator],
    pool: &rayon::ThreadPool,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<(OverRow, Option<Vec<f64>>), pdw_limit::LimitError> {
    let Ok((x0, s)) = mfpt::start(m) else {
        return Ok((
            OverRow::missing(value, m.slope(), "no stable gait".into()),
            None,
        ));
    };
    let (_, est) = mfpt::run(m, p, &x0, pool, progress)?;
    let (gsn, note) = gsn_at(m, &s, ind);
    let r = OverRow {
        value,
        mean: m.slope(),
        gait: Some(s),
        est: Some(est),
        chain: [f64::NAN; 2],
        gsn,
        note,
    };
    Ok((r, Some(x0)))
}
