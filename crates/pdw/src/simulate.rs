//! A walk of N steps, written once for `pdw-sweep simulate` and Python's `simulate`: where it
//! starts (a given state, or a gait of the model found as `fixedpoint` finds it), the
//! trajectory options (output spacing, integrator, the sample budget the memory allows), the
//! check that a walk from a gait fits that budget before it is computed, and the walk itself
//! ([`pdw_limit::trajectory::simulate`]). Files, printing and Python's arrays are the front
//! end's.

use crate::gaits::{model_guesses, search, Failed};
use crate::input::InputError;
use crate::model::BuiltModel;
use pdw_hybrid::{Method, Options};
use pdw_limit::trajectory::{self, Trajectory, TrajectoryOptions};
use pdw_limit::LimitError;

/// Residual tolerance of the gait a walk starts from.
pub const GAIT_TOL: f64 = 1e-12;

/// The names a front end gives the options in its messages (`--steps` or `steps`, …).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimulateFlags {
    pub steps: &'static str,
    pub dt_out: &'static str,
    pub state: &'static str,
    pub gait: &'static str,
    /// The fixed step of rk4, named when a walk from a gait would exceed the sample budget.
    pub rk4_step: &'static str,
}

/// Which of the model's period-one gaits a walk starts from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GaitKind {
    Stable,
    Unstable,
}

impl GaitKind {
    /// `"stable"` or `"unstable"`, as the front ends spell it.
    pub fn name(self) -> &'static str {
        match self {
            GaitKind::Stable => "stable",
            GaitKind::Unstable => "unstable",
        }
    }

    /// `stable` or `unstable`; anything else is refused naming `flag`.
    pub fn parse(s: &str, flag: &str) -> Result<GaitKind, InputError> {
        match s {
            "stable" => Ok(GaitKind::Stable),
            "unstable" => Ok(GaitKind::Unstable),
            other => Err(InputError(format!(
                "{flag}: '{other}' is not one of stable, unstable"
            ))),
        }
    }
}

/// Where a walk starts.
#[derive(Clone, Debug, PartialEq)]
pub enum Start {
    /// Section coordinates (lifted with [`pdw_hybrid::Section::lift`]) or a full state just
    /// after a heel strike ([`trajectory::initial_state`]).
    State(Vec<f64>),
    /// A period-one gait of the model from its own guesses.
    Gait(GaitKind),
}

/// The walk's first state, how it was chosen (for the file's `start` attribute) and, from a
/// gait, the gait's period (it bounds the samples ahead, [`check_samples`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Walk {
    pub x0: Vec<f64>,
    pub label: String,
    pub period: Option<f64>,
}

/// Why a walk has no start.
#[derive(Debug)]
pub enum StartError {
    /// The given state does not fit the model.
    Input(InputError),
    /// No gait of the asked kind came out of the model's guesses: how many were tried and
    /// each failure (for [`crate::gaits::no_gait_message`] or the CLI's own lines).
    NoGait {
        which: GaitKind,
        tried: usize,
        failed: Vec<Failed>,
    },
    /// The search itself failed.
    Limit(LimitError),
}

/// Refuses zero steps and an output spacing that is not a positive time step.
pub fn check_request(
    steps: usize,
    dt_out: Option<f64>,
    flags: &SimulateFlags,
) -> Result<(), InputError> {
    if steps == 0 {
        return Err(InputError(format!(
            "{}: 0 must be an integer >= 1",
            flags.steps
        )));
    }
    if let Some(h) = dt_out {
        if !(h.is_finite() && h > 0.0) {
            return Err(InputError(format!(
                "{}: {h} must be a positive time step",
                flags.dt_out
            )));
        }
    }
    Ok(())
}

/// The first state of a walk from `start` (see [`Start`]); a gait is searched for with
/// residual tolerance [`GAIT_TOL`] from the model's guesses, the first of the kind asked taken.
pub fn start(m: &BuiltModel, start: &Start, flags: &SimulateFlags) -> Result<Walk, StartError> {
    let w = m.walker.as_ref();
    match start {
        Start::State(v) => {
            let x0 = trajectory::initial_state(w, v)
                .map_err(|e| StartError::Input(InputError(format!("{}: {e}", flags.state))))?;
            Ok(Walk {
                x0,
                label: format!("state {v:?}"),
                period: None,
            })
        }
        Start::Gait(which) => {
            let guesses = model_guesses(w);
            let (found, failed) = search(m, &guesses, GAIT_TOL).map_err(StartError::Limit)?;
            let stable = *which == GaitKind::Stable;
            let Some(g) = found.iter().find(|f| f.fp.stable == stable) else {
                return Err(StartError::NoGait {
                    which: *which,
                    tried: guesses.len(),
                    failed,
                });
            };
            Ok(Walk {
                x0: g.fp.state.clone(),
                label: format!("{} gait {:?}", which.name(), g.fp.section),
                period: Some(g.fp.metrics.period),
            })
        }
    }
}

/// The most samples a walk of a `dim`-state model may record: those that fit in half the
/// memory available (a tiny output spacing or rk4 step is refused when the walk reaches the
/// bound, not killed for lack of memory).
pub fn sample_budget(dim: usize) -> usize {
    (pdw_limit::resources::memory_available() / 2 / pdw_limit::bytes_per_sample(dim) as u64)
        .min(usize::MAX as u64) as usize
}

/// The trajectory options of a walk of `steps` steps of `m`: samples every `dt_out` (else at
/// every accepted step and event), the integrator given, the budget of [`sample_budget`].
pub fn options(
    m: &BuiltModel,
    steps: usize,
    dt_out: Option<f64>,
    integrator: Options,
) -> TrajectoryOptions {
    TrajectoryOptions {
        dt_out,
        integrator,
        max_samples: sample_budget(m.walker.dim()),
        ..TrajectoryOptions::new(steps)
    }
}

/// The integrator a walk uses when the front end gives none (that of [`TrajectoryOptions`]).
pub fn default_integrator() -> Options {
    TrajectoryOptions::new(1).integrator
}

/// From a gait its period tells the samples ahead: refuses, before computing, a walk whose
/// steps would record more samples than `opts.max_samples`, naming the option to change.
pub fn check_samples(
    walk: &Walk,
    opts: &TrajectoryOptions,
    flags: &SimulateFlags,
) -> Result<(), InputError> {
    let spacing = match (opts.dt_out, opts.integrator.method) {
        (Some(h), _) => Some((h, flags.dt_out)),
        (None, Method::Rk4 { h }) => Some((h, flags.rk4_step)),
        _ => None,
    };
    let (Some(period), Some((h, flag))) = (walk.period, spacing) else {
        return Ok(());
    };
    let n = period / h * opts.steps as f64;
    if n > opts.max_samples as f64 {
        return Err(InputError(format!(
            "{flag}: {} steps of this gait (period {period:.4}) would record about {n:.2e} \
             samples, more than the {} that fit in half the memory available; give a larger \
             step or fewer {}",
            opts.steps, opts.max_samples, flags.steps
        )));
    }
    Ok(())
}

/// The walk: [`pdw_limit::trajectory::simulate`] from the walk's first state (a fall is an
/// outcome in the trajectory, not an error; errors are options the walk cannot honour).
pub fn run(
    m: &BuiltModel,
    walk: &Walk,
    opts: &TrajectoryOptions,
) -> Result<Trajectory, InputError> {
    trajectory::simulate(m.walker.as_ref(), &walk.x0, opts).map_err(|e| InputError(e.to_string()))
}

/// The total mechanical energy of a walk in one fixed frame: the model's own energy has its
/// potential zero at the current stance foot, which moves down the slope at every heel strike,
/// so its series jumps up by the drop at each foot change. Measured from the first stance
/// foot instead, `E_fixed = E − m g Σ_{k<j} L_k sin γ` on step `j`, with `L_k` the step
/// length of step `k` (the distance between the feet at its heel strike, along the slope) and
/// `m g` the total weight (the model's [`Scales`](pdw_model::Scales)): constant between
/// impacts, it drops at each impact by what the impact dissipates — on a gait, by the
/// `m g L sin γ` one step on the slope releases (Garcia et al. 1998 §4: the energy balance of
/// a passive gait).
///
/// `None` where the model defines no energy or scales, and for round feet (the contact point
/// rolls along the foot during stance, so the stance frame's origin is not a fixed point of
/// the slope between strikes).
pub fn fixed_frame_energy(m: &BuiltModel, tr: &Trajectory) -> Option<Vec<f64>> {
    let w = m.walker.as_ref();
    let (energy, scales) = (tr.energy.as_ref()?, w.scales()?);
    let round = m
        .params
        .iter()
        .any(|(n, v)| n == "foot_radius" && *v != 0.0);
    let slope = m.slope();
    if round || !slope.is_finite() {
        return None;
    }
    // Height of the stance foot below the first one after each completed step.
    let drops: Vec<f64> = tr
        .events
        .iter()
        .filter(|e| e.ends_step)
        .scan(0.0, |h, e| {
            *h += w.step_length(&e.pre) * slope.sin();
            Some(*h)
        })
        .collect();
    let weight = scales.force();
    Some(
        energy
            .iter()
            .zip(&tr.step)
            .map(|(&e, &j)| {
                let below = (j as usize)
                    .checked_sub(1)
                    .and_then(|k| drops.get(k))
                    .copied()
                    .unwrap_or(0.0);
                e - weight * below
            })
            .collect(),
    )
}
