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
use crate::model::{BuiltModel, ModelChoice};
use crate::pipeline::{CommandError, Report, Sink, Spelling};
use crate::IntegratorChoice;
use pdw_hybrid::Options;
use pdw_limit::terrain::{SlopeWalk, TerrainKind};
use pdw_limit::{LimitError, StrideOutcome};
use serde::Serialize;

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

// ---- the command: plan → run → report (crate::pipeline)

/// The most strides a walk accepts: every stride's deviation is kept (8 bytes a stride) and each
/// is a stride to integrate — a million bounds both (8 MB; minutes for the slowest walker).
pub const MAX_STRIDES: usize = 1_000_000;

/// How far `--largest` looks, on each terrain: 1.5 rad of slope, 1000 length units of step.
fn reach(kind: TerrainKind) -> f64 {
    match kind {
        TerrainKind::Slope => 1.5,
        TerrainKind::StepDown => 1e3,
    }
}

/// The two directions `--largest` bisects, by sign (+1 first).
fn directions(kind: TerrainKind) -> [&'static str; 2] {
    match kind {
        TerrainKind::Slope => ["steeper", "shallower"],
        TerrainKind::StepDown => ["step down", "step up"],
    }
}

/// The unit of the terrain parameter: radians of slope, the model's length of step.
pub fn terrain_unit(m: &BuiltModel, kind: TerrainKind) -> String {
    match kind {
        TerrainKind::Slope => "rad".into(),
        TerrainKind::StepDown => m.walker.units().length.to_string(),
    }
}

/// `disturb`'s inputs as the user gave them.
#[derive(Clone, Debug, PartialEq)]
pub struct DisturbInput {
    pub model: ModelChoice,
    pub integrator: IntegratorChoice,
    /// `step-down` or `slope`.
    pub terrain: String,
    /// The disturbance of stride 1 as typed (a slope may carry its unit, `0.5deg`); `None` with
    /// `largest`.
    pub once: Option<String>,
    /// Bisect for the largest disturbance survived, both ways.
    pub largest: bool,
    /// Strides walked after the disturbance that count as surviving it.
    pub strides: usize,
    /// With `largest`: the bisection's tolerance (the disturbance's unit).
    pub tol: f64,
}

impl Default for DisturbInput {
    /// The CLI's and Python's defaults: the simplest walker, a step down, 200 strides, 1e-5.
    fn default() -> Self {
        DisturbInput {
            model: ModelChoice {
                model: "simplest".into(),
                slope: None,
                set: Vec::new(),
            },
            integrator: IntegratorChoice::default(),
            terrain: TerrainKind::StepDown.name().into(),
            once: None,
            largest: false,
            strides: 200,
            tol: 1e-5,
        }
    }
}

/// What a planned `disturb` does.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Asked {
    Once(f64),
    Largest { tol: f64 },
}

/// A checked `disturb`: the model built, the terrain, the integrator, what to walk.
pub struct DisturbPlan {
    pub model: BuiltModel,
    pub kind: TerrainKind,
    pub integrator: Options,
    pub strides: usize,
    asked: Asked,
}

/// Checks `input` and builds its model; messages name the options as `sp` spells them.
pub fn plan(input: &DisturbInput, sp: Spelling) -> Result<DisturbPlan, CommandError> {
    let f = |name: &str| sp.flag(name);
    if !(1..=MAX_STRIDES).contains(&input.strides) {
        return Err(InputError(format!(
            "{}: {} is outside 1..={MAX_STRIDES} (strides walked after the disturbance)",
            f("strides"),
            input.strides
        ))
        .into());
    }
    let kind = crate::mfpt::parse_terrain(&input.terrain, &f("terrain"))?;
    let once = match (&input.once, input.largest) {
        (Some(s), false) => Some(match kind {
            TerrainKind::Slope => crate::input::parse_slope_for(s, &f("once"))?,
            TerrainKind::StepDown => crate::mfpt::parse_height(s, &f("once"))?,
        }),
        (None, true) => None,
        _ => {
            return Err(InputError(format!(
                "give {} D or {} (one of them)",
                f("once"),
                f("largest")
            ))
            .into())
        }
    };
    let integrator = crate::integrator(&input.integrator, crate::mfpt::default_integrator())?;
    let model = crate::build_model(&input.model)?;
    check(&model, kind)?;
    crate::integrator::check_integrator(&model, &integrator)?;
    let asked = match once {
        Some(d) => Asked::Once(d),
        None if input.tol.is_finite() && input.tol > 0.0 => Asked::Largest { tol: input.tol },
        None => return Err(InputError(format!("{}: {} must be > 0", f("tol"), input.tol)).into()),
    };
    Ok(DisturbPlan {
        model,
        kind,
        integrator,
        strides: input.strides,
        asked,
    })
}

/// One disturbance's outcome, as reported.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OnceReport {
    /// The disturbance of stride 1.
    pub disturbance: f64,
    /// Fell within the walk.
    pub fell: bool,
    /// Heel strikes completed (the disturbed one included) before the fall, or all strides.
    pub strides: usize,
    /// How the fall happened (`None`: walked all strides).
    pub fall: Option<String>,
    /// The deviation from the gait after each heel strike (∞-norm of the section coordinates).
    pub deviation: Vec<f64>,
    /// The first heel strike after which the deviation is below `return_tol`.
    pub returned_after: Option<usize>,
    /// [`RETURN_TOL`].
    pub return_tol: f64,
}

/// The largest disturbance survived one way, as reported.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LargestReport {
    /// `step down`, `step up`, `steeper` or `shallower`.
    pub direction: &'static str,
    /// The largest disturbance survived (signed).
    pub survived: f64,
    /// The nearest disturbance found that falls (signed); `|falls_at − survived| ≤ tol` unless
    /// `at_double_spacing`.
    pub falls_at: f64,
    /// The bisection stopped at adjacent doubles, wider apart than `tol`.
    pub at_double_spacing: bool,
}

/// `disturb`'s report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DisturbReport {
    pub model: String,
    /// `step-down` or `slope`.
    pub terrain: &'static str,
    /// The terrain parameter's nominal value ([`nominal`]) and its name and unit.
    pub parameter: &'static str,
    pub nominal: f64,
    pub unit: String,
    /// Strides that count as surviving.
    pub strides: usize,
    /// With `once`: the response.
    pub once: Option<OnceReport>,
    /// With `largest`: both directions, and the tolerance.
    pub largest: Vec<LargestReport>,
    pub tol: Option<f64>,
}

impl DisturbPlan {
    /// Walks the disturbance, or bisects both ways (two phases of bisection steps on `sink`).
    pub fn run(&self, _sink: &dyn Sink) -> Result<DisturbReport, InputError> {
        let m = &self.model;
        let mut report = DisturbReport {
            model: m.info.name.to_string(),
            terrain: self.kind.name(),
            parameter: self.kind.param(),
            nominal: nominal(m, self.kind),
            unit: terrain_unit(m, self.kind),
            strides: self.strides,
            once: None,
            largest: Vec::new(),
            tol: None,
        };
        match self.asked {
            Asked::Once(d) => {
                let r = respond(m, self.kind, d, self.strides, self.integrator)?;
                report.once = Some(OnceReport {
                    disturbance: r.disturbance,
                    fell: !r.survived(),
                    strides: r.steps,
                    fall: r.fall.map(|o| o.to_string()),
                    deviation: r.deviation,
                    returned_after: r.returned_after,
                    return_tol: RETURN_TOL,
                });
            }
            Asked::Largest { tol } => {
                report.tol = Some(tol);
                for (direction, sign) in directions(self.kind).into_iter().zip([1.0, -1.0]) {
                    let (survived, falls_at) = largest(
                        m,
                        self.kind,
                        sign,
                        tol,
                        reach(self.kind),
                        self.strides,
                        self.integrator,
                    )?;
                    report.largest.push(LargestReport {
                        direction,
                        survived,
                        falls_at,
                        at_double_spacing: (falls_at - survived).abs() > tol,
                    });
                }
            }
        }
        Ok(report)
    }
}

impl Report for DisturbReport {
    fn text(&self) -> String {
        let unit = &self.unit;
        let mut t = format!(
            "model {}  nominal {} {} {unit}; one disturbed stride, then {} nominal strides at \
             most\n",
            self.model,
            self.parameter,
            self.nominal,
            self.strides - 1
        );
        if let Some(r) = &self.once {
            once_text(&mut t, r, unit);
        }
        let tol = self.tol.unwrap_or(0.0);
        for l in &self.largest {
            t += &format!(
                "largest {} survived: {:.6e} {unit} (falls at {:.6e}; tolerance {tol:e}, \
                 surviving = {} strides without a fall)\n",
                l.direction, l.survived, l.falls_at, self.strides
            );
            if l.at_double_spacing {
                t += &format!(
                    "note: the bisection stopped at the spacing of doubles: {:e} and {:e} are \
                     adjacent, {:e} {unit} apart, wider than the tolerance {tol:e}; no smaller \
                     tolerance can be met here\n",
                    l.survived,
                    l.falls_at,
                    (l.falls_at - l.survived).abs()
                );
            }
        }
        t
    }
}

/// One disturbance's lines: the outcome, the return, the first deviations.
fn once_text(t: &mut String, r: &OnceReport, unit: &str) {
    let d = crate::output::number(r.disturbance);
    *t += &match &r.fall {
        Some(o) => format!(
            "disturbance {d} {unit}: fell after {} heel strikes ({o})\n",
            r.strides
        ),
        None => format!("disturbance {d} {unit}: walked all {} strides\n", r.strides),
    };
    *t += &match r.returned_after {
        Some(k) => format!(
            "back within {:e} of the gait after {k} strides\n",
            r.return_tol
        ),
        None => format!("not back within {:e} of the gait\n", r.return_tol),
    };
    let shown: Vec<String> = r
        .deviation
        .iter()
        .take(12)
        .map(|d| format!("{d:.2e}"))
        .collect();
    *t += &format!(
        "deviation from the gait after each stride (section, inf-norm): {}{}\n",
        shown.join(" "),
        if r.deviation.len() > 12 { " …" } else { "" }
    );
}
