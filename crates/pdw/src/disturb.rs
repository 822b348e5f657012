//! One deterministic disturbance: the walker on its stable gait meets one step of another slope
//! or another height, then nominal ground again — does it fall, after how many steps, and how
//! fast does it return to the gait; and the largest such disturbance it survives, found by
//! bisection ("largest step-down survived", the robustness measure of Schwab & Wisse 2001 and
//! Hobbelen & Wisse 2007). Written once for `pdw-sweep disturb` and the Python package; the
//! stride on terrain and its conventions are [`pdw_limit::terrain`]'s.
//!
//! A disturbance `d` of a slope terrain makes step 1 land on a line of slope `s̄ + d` (the model's
//! own slope `s̄` before and after); of a step-down terrain, on a foothold `h̄ + d` below the
//! stance foot (`h̄` the model's `step_down`, 0 by default; `d > 0` a step down). Steps 2, 3, …
//! are nominal.

use crate::input::InputError;
use crate::mfpt::{model_at_param, start};
use crate::model::BuiltModel;
use pdw_hybrid::Options;
use pdw_limit::terrain::{SlopeWalk, TerrainKind};
use pdw_limit::{LimitError, StrideOutcome};

/// The deviation from the gait (∞-norm over the section coordinates) below which the walker
/// counts as back on it.
pub const RETURN_TOL: f64 = 1e-6;

/// What one disturbance did.
#[derive(Clone, Debug, PartialEq)]
pub struct Response {
    /// The disturbance (added to the nominal slope or step down of step 1).
    pub disturbance: f64,
    /// Heel strikes completed (the disturbed one included) before a fall, or `steps` without.
    pub steps: usize,
    /// How the fall happened (`None`: walked all `steps`).
    pub fall: Option<StrideOutcome>,
    /// The deviation from the gait after each completed heel strike (∞-norm of the section
    /// coordinates, in the nominal ground's frame).
    pub deviation: Vec<f64>,
    /// The first heel strike after which the deviation is below [`RETURN_TOL`] (`None`: not
    /// within the walk).
    pub returned_after: Option<usize>,
}

impl Response {
    /// Walked every step without a fall.
    pub fn survived(&self) -> bool {
        self.fall.is_none()
    }
}

/// The nominal value of the terrain parameter: the model's slope or its `step_down` (0 when the
/// model has none).
pub fn nominal(m: &BuiltModel, kind: TerrainKind) -> f64 {
    let p = kind.param();
    m.params.iter().find(|q| q.0 == p).map_or(0.0, |q| q.1)
}

/// Refuses a model that cannot meet a disturbance of kind `kind` (as [`crate::mfpt`] refuses it
/// random terrain of that kind).
pub fn check(m: &BuiltModel, kind: TerrainKind) -> Result<(), InputError> {
    crate::mfpt::check_model_for(m, kind)
}

/// The walker of `m` from its stable gait meets disturbance `d` at step 1, then walks nominal
/// ground for `steps − 1` more steps (at most), integrated with `integrator`. A disturbance the
/// model cannot take (a step beyond the rimless wheel's reach) is an error naming the model's
/// reason.
pub fn respond(
    m: &BuiltModel,
    kind: TerrainKind,
    d: f64,
    steps: usize,
    integrator: Options,
) -> Result<Response, InputError> {
    let (x0, s0) = start(m)?;
    respond_from(m, kind, d, steps, integrator, &x0, &s0)
}

/// [`respond`] from the gait `(x0, s0)` (full state and section), found once by the caller.
pub fn respond_from(
    m: &BuiltModel,
    kind: TerrainKind,
    d: f64,
    steps: usize,
    integrator: Options,
    x0: &[f64],
    s0: &[f64],
) -> Result<Response, InputError> {
    let err = |e: LimitError| InputError(e.to_string());
    let at = model_at_param(m, kind.param());
    let mean = nominal(m, kind);
    let walk = SlopeWalk::with_kind(&at, kind, mean, integrator).map_err(err)?;
    let mut integ = walk.integrator(x0.len()).map_err(err)?;
    let base = walk.model(mean).map_err(err)?;
    let mut x = x0.to_vec();
    let mut r = Response {
        disturbance: d,
        steps,
        fall: None,
        deviation: Vec::new(),
        returned_after: None,
    };
    let mut sec = vec![0.0; s0.len()];
    // the walker stands on a line of the nominal slope (round feet on slopes: the stride
    // depends on it, SlopeWalk::stride_from)
    let mut last = mean;
    for k in 0..steps {
        let value = if k == 0 { mean + d } else { mean };
        let st = walk.stride_from(&mut integ, &x, last, value).map_err(err)?;
        last = value;
        if !st.outcome.is_ok() {
            r.steps = k;
            r.fall = Some(st.outcome);
            break;
        }
        x = st.post;
        // after a nominal stride (and the disturbed one, shifted back) x is in the nominal frame
        base.project(&x, &mut sec);
        let dev = sec
            .iter()
            .zip(s0)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        r.deviation.push(dev);
        if r.returned_after.is_none() && dev < RETURN_TOL {
            r.returned_after = Some(k + 1);
        }
    }
    Ok(r)
}

/// The largest disturbance of sign `sign` (+1: step down / steeper; −1: step up / shallower)
/// that the walker survives for `steps` steps, to within `tol`: `(survived, fell)` with
/// `fell − survived ≤ tol` (in magnitude), both walked ([`respond_from`]). The bracket grows by
/// doubling from `tol` until a walk falls (or the model refuses the disturbance, which counts as
/// a fall; up to `limit`), then bisects. Survival need not be monotone in the disturbance: the
/// result is the edge of the survived interval that contains 0. A `tol` below the spacing of
/// doubles at the edge cannot be met: the bisection stops when `survived` and `fell` are
/// adjacent doubles, and `fell − survived` then exceeds `tol` (the caller can tell, and says so).
#[allow(clippy::too_many_arguments)]
pub fn largest(
    m: &BuiltModel,
    kind: TerrainKind,
    sign: f64,
    tol: f64,
    limit: f64,
    steps: usize,
    integrator: Options,
) -> Result<(f64, f64), InputError> {
    let (x0, s0) = start(m)?;
    let falls = |d: f64| -> Result<bool, InputError> {
        // a disturbance the model refuses (beyond its reach) counts as a fall
        match respond_from(m, kind, d, steps, integrator, &x0, &s0) {
            Ok(r) => Ok(!r.survived()),
            Err(_) if d.abs() > 0.0 => Ok(true),
            Err(e) => Err(e),
        }
    };
    let (mut lo, mut hi) = (0.0, tol);
    while !falls(sign * hi)? {
        lo = hi;
        hi *= 2.0;
        if hi > limit {
            if falls(sign * limit)? {
                hi = limit;
                break;
            }
            return Err(InputError(format!(
                "the gait survives a disturbance of {} (the largest tried): no edge below it",
                sign * limit
            )));
        }
    }
    while hi - lo > tol {
        let mid = 0.5 * (lo + hi);
        // lo and hi adjacent doubles: the interval cannot shrink further (a tolerance below
        // the spacing of doubles at the edge would never be met)
        if mid <= lo || mid >= hi {
            break;
        }
        if falls(sign * mid)? {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Ok((sign * lo, sign * hi))
}
