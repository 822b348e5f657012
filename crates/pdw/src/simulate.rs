//! A walk of N steps, written once for `pdw-sweep simulate` and Python's `simulate`: where it
//! starts (a given state, or a gait of the model found as `fixedpoint` finds it), the
//! trajectory options (output spacing, integrator, the sample budget the memory allows), the
//! check that a walk from a gait fits that budget before it is computed, and the walk itself
//! ([`pdw_limit::trajectory::simulate`]). Files, printing and Python's arrays are the front
//! end's.

use crate::gaits::{model_guesses, search, Failed};
use crate::input::InputError;
use crate::model::{BuiltModel, ModelChoice};
use crate::pipeline::{CommandError, Preview, Report, Sink, Spelling};
use crate::IntegratorChoice;
use pdw_hybrid::{Method, Options};
use pdw_limit::trajectory::{self, Trajectory, TrajectoryOptions};
use pdw_limit::LimitError;
use serde::Serialize;
use std::path::PathBuf;

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

/// Samples per step of the default output spacing from a gait: `dt_out = period / 100`.
pub const SAMPLES_PER_STEP: f64 = 100.0;

/// Samples per natural time unit of the default output spacing from a state (no period known):
/// `dt_out = T / 50`, `T = √(L/g)` from the model's [`Scales`](pdw_walkers::Scales).
pub const SAMPLES_PER_TIME_SCALE: f64 = 50.0;

/// The output spacing a front end asks for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DtOut {
    /// Not given: dense and scale free ([`spacing`]).
    Default,
    /// `steps`: a sample at every accepted integrator step and both sides of every event.
    Steps,
    /// A given time step (model time units).
    Every(f64),
}

impl DtOut {
    /// `steps` or a positive time step; anything else is refused naming `flag`.
    pub fn parse(s: &str, flag: &str) -> Result<DtOut, InputError> {
        let t = s.trim();
        if t == "steps" {
            return Ok(DtOut::Steps);
        }
        match t.parse::<f64>() {
            Ok(h) if h.is_finite() && h > 0.0 => Ok(DtOut::Every(h)),
            _ => Err(InputError(format!(
                "{flag}: '{s}' is neither a positive time step nor the word steps"
            ))),
        }
    }

    /// The given time step, if one was given.
    pub fn every(self) -> Option<f64> {
        match self {
            DtOut::Every(h) => Some(h),
            _ => None,
        }
    }
}

/// The output spacing a walk uses and where it came from (for the file's `dt_out` and
/// `dt_out_source` attributes and Python's dict).
#[derive(Clone, Debug, PartialEq)]
pub struct Spacing {
    /// The time step of the samples; `None`: every accepted integrator step and event.
    pub dt_out: Option<f64>,
    /// Whether both sides of every event are samples too (the default's dense grid).
    pub event_samples: bool,
    /// Where the spacing came from, in words.
    pub source: String,
}

/// The output spacing of a walk: the one asked for, else the default — from a gait `period /`
/// [`SAMPLES_PER_STEP`] (100 samples per step), from a state `T /` [`SAMPLES_PER_TIME_SCALE`]
/// with `T = √(L/g)` the model's natural time scale; a model without scales falls back to
/// every accepted step and event. The default also samples both sides of every event, so that
/// the impacts are in the series.
pub fn spacing(m: &BuiltModel, walk: &Walk, asked: DtOut) -> Spacing {
    let steps = |source: String| Spacing {
        dt_out: None,
        event_samples: true,
        source,
    };
    match asked {
        DtOut::Steps => steps("asked: every accepted integrator step and event".into()),
        DtOut::Every(h) => Spacing {
            dt_out: Some(h),
            event_samples: false,
            source: "asked".into(),
        },
        DtOut::Default => match (walk.period, m.walker.scales()) {
            (Some(p), _) => Spacing {
                dt_out: Some(p / SAMPLES_PER_STEP),
                event_samples: true,
                source: format!(
                    "default: the gait's period {p:?} / {SAMPLES_PER_STEP}, and every event"
                ),
            },
            (None, Some(sc)) => {
                let t = (sc.length / sc.gravity).sqrt();
                Spacing {
                    dt_out: Some(t / SAMPLES_PER_TIME_SCALE),
                    event_samples: true,
                    source: format!(
                        "default: T / {SAMPLES_PER_TIME_SCALE} with T = sqrt(L/g) = {t:?} the \
                         model's time scale, and every event"
                    ),
                }
            }
            (None, None) => steps(
                "default: every accepted integrator step and event (the model has no natural \
                 scales)"
                    .into(),
            ),
        },
    }
}

/// [`options`] with the walk's [`Spacing`].
pub fn options_spaced(
    m: &BuiltModel,
    steps: usize,
    sp: &Spacing,
    integrator: Options,
) -> TrajectoryOptions {
    TrajectoryOptions {
        event_samples: sp.event_samples,
        ..options(m, steps, sp.dt_out, integrator)
    }
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
/// `m g` the total weight (the model's [`Scales`](pdw_walkers::Scales)): constant between
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
    let round = round_feet(m);
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

/// Where the positions of a walk are measured: one fixed frame of the slope for the whole
/// walk (the file's `positions_frame` attribute).
pub const POSITIONS_FRAME: &str = "slope frame fixed for the whole walk: x along the slope \
    (downhill positive), y along the slope normal (up), origin at the first stance foot; each \
    step's stance foot lies the previous steps' step lengths down the slope. World frame \
    (X horizontal, forward; Y vertical, up): X = x cos(slope) + y sin(slope), \
    Y = -x sin(slope) + y cos(slope)";

/// The walker's named points and centre of mass along a walk, in [`POSITIONS_FRAME`].
#[derive(Clone, Debug, PartialEq)]
pub struct Positions {
    /// Point names ([`pdw_walkers::BodyPoints::names`]), `P` of them.
    pub names: Vec<String>,
    /// `n × P × 2` values, row-major (sample, point, x/y).
    pub points: Vec<f64>,
    /// `n × 2` values: the centre of mass per sample.
    pub com: Vec<f64>,
}

/// Where the stance foot of each step lies along the slope from the first one: `Σ_{k<j} L_k`
/// for step `j`, `L_k` the step length of step `k` at its heel strike (the bookkeeping of
/// [`fixed_frame_energy`]).
fn stance_offsets(m: &BuiltModel, tr: &Trajectory) -> Vec<f64> {
    let w = m.walker.as_ref();
    let mut v = vec![0.0];
    for e in tr.events.iter().filter(|e| e.ends_step) {
        let last = *v.last().unwrap_or(&0.0);
        v.push(last + w.step_length(&e.pre));
    }
    v
}

/// Whether the model has round feet (a non-zero `foot_radius`).
fn round_feet(m: &BuiltModel) -> bool {
    m.params
        .iter()
        .any(|(n, v)| n == "foot_radius" && *v != 0.0)
}

/// The walker's named points ([`pdw_walkers::Walker::body_points`]) and centre of mass at every
/// sample of `tr`, in the fixed frame of [`POSITIONS_FRAME`]: the stance frame of the sample
/// shifted down the slope by its step's stance-foot offset. `Err` says why there are none: the
/// model gives no points, or round feet (the contact point rolls along the foot during
/// stance, so the stance frame's origin is not a fixed point of the slope between strikes).
pub fn positions(m: &BuiltModel, tr: &Trajectory) -> Result<Positions, String> {
    let w = m.walker.as_ref();
    if round_feet(m) {
        return Err(
            "left out for round feet: the contact point rolls along the foot during \
                    stance, so the stance frame is not fixed on the slope between strikes"
                .into(),
        );
    }
    let none = || "left out: the model gives no body points".to_string();
    // one kernel scratch for every sample
    let mut ws = pdw_hybrid::Scratch::new();
    let first = w.body_points_in(&mut ws, tr.state(0)).ok_or_else(none)?;
    let offsets = stance_offsets(m, tr);
    let n = tr.len();
    let np = first.names.len();
    let (mut points, mut com) = (Vec::with_capacity(n * np * 2), Vec::with_capacity(n * 2));
    for i in 0..n {
        let b = w.body_points_in(&mut ws, tr.state(i)).ok_or_else(none)?;
        let dx = offsets
            .get(tr.step[i] as usize)
            .or(offsets.last())
            .copied()
            .unwrap_or(0.0);
        for p in b.points.iter().take(np) {
            points.extend_from_slice(&[p[0] + dx, p[1]]);
        }
        com.extend_from_slice(&[b.com[0] + dx, b.com[1]]);
    }
    Ok(Positions {
        names: first.names,
        points,
        com,
    })
}

// ---- the command: plan → run → report (crate::pipeline)

/// The names of `simulate`'s options on the command line.
const CLI_FLAGS: SimulateFlags = SimulateFlags {
    steps: "--strides",
    dt_out: "--dt-out",
    state: "--state",
    gait: "--gait",
    rk4_step: "--rk4-step",
};

/// The names of `simulate`'s keyword arguments in Python.
const PYTHON_FLAGS: SimulateFlags = SimulateFlags {
    steps: "strides",
    dt_out: "dt_out",
    state: "state",
    gait: "gait",
    rk4_step: "rk4_step",
};

/// The option names of front end `sp`.
pub fn flags(sp: Spelling) -> &'static SimulateFlags {
    match sp {
        Spelling::Cli => &CLI_FLAGS,
        Spelling::Python => &PYTHON_FLAGS,
    }
}

/// `simulate`'s inputs as the user gave them.
#[derive(Clone, Debug, PartialEq)]
pub struct SimulateInput {
    pub model: ModelChoice,
    pub integrator: IntegratorChoice,
    /// Strides to walk (heel strike to heel strike).
    pub strides: usize,
    /// The output spacing.
    pub dt_out: DtOut,
    /// Section coordinates, or a full state just after a heel strike; `None`: from `gait`.
    pub state: Option<Vec<f64>>,
    /// `stable` or `unstable` (`None`: stable); not with `state`.
    pub gait: Option<String>,
    /// The file to write (`.h5`, `.hdf5` or `.csv`); `None`: none (Python returns the arrays).
    pub out: Option<PathBuf>,
    /// Replace an existing `out`.
    pub force: bool,
    /// The command as run (the CLI's command line, Python's call), for the file.
    pub command: String,
}

/// A checked `simulate`: the model built, the integrator, where the walk starts, the file.
pub struct SimulatePlan {
    pub model: BuiltModel,
    pub integrator: Options,
    pub strides: usize,
    pub dt_out: DtOut,
    pub start: Start,
    out: Option<(PathBuf, crate::simulate_file::Format)>,
    force: bool,
    command: String,
    model_name: String,
    spelling: Spelling,
    flags: &'static SimulateFlags,
}

/// Checks `input` and builds its model, naming the options as `sp` spells them.
pub fn plan(input: &SimulateInput, sp: Spelling) -> Result<SimulatePlan, CommandError> {
    let flags = flags(sp);
    let out = match &input.out {
        Some(p) => Some((
            p.clone(),
            crate::simulate_file::Format::of(p, &sp.flag("out"))?,
        )),
        None => None,
    };
    check_request(input.strides, input.dt_out.every(), flags)?;
    let start = match (&input.state, &input.gait) {
        (Some(v), None) => Start::State(v.clone()),
        (None, g) => Start::Gait(GaitKind::parse(
            g.as_deref().unwrap_or("stable"),
            flags.gait,
        )?),
        (Some(_), Some(_)) => {
            return Err(InputError(format!(
                "give {} or {} (one of them)",
                flags.state, flags.gait
            ))
            .into())
        }
    };
    let integrator = crate::integrator(&input.integrator, default_integrator())?;
    let model = crate::build_model(&input.model)?;
    crate::integrator::check_integrator(&model, &integrator)?;
    Ok(SimulatePlan {
        model,
        integrator,
        strides: input.strides,
        dt_out: input.dt_out,
        start,
        out,
        force: input.force,
        command: input.command.clone(),
        model_name: input.model.model.clone(),
        spelling: sp,
        flags,
    })
}

impl SimulatePlan {
    /// What the plan states before the walk: the file it writes.
    pub fn preview(&self) -> Preview {
        Preview {
            outputs: self.out.iter().map(|(p, _)| p.clone()).collect(),
            warnings: Vec::new(),
            memory_bytes: None,
        }
    }

    /// Claims the file, finds the start (a gait: Newton from the model's guesses), checks the
    /// samples fit, walks and writes. A fall is an outcome of the walk (the report's
    /// `outcome`), not an error; no gait of the kind asked is an input error naming the
    /// option that gives a start instead.
    pub fn run(&self, _sink: &dyn Sink) -> Result<SimulateRun, CommandError> {
        let m = &self.model;
        let _claim = self.claim()?;
        let walk = match start(m, &self.start, self.flags) {
            Ok(walk) => walk,
            Err(StartError::Input(e)) => return Err(e.into()),
            Err(StartError::Limit(e)) => return Err(e.into()),
            Err(StartError::NoGait {
                which,
                tried,
                failed,
            }) => {
                let msg = crate::gaits::no_gait_message(m, which.name(), tried, &failed);
                let hint = format!("; give a starting point with {}", self.flags.state);
                // the hint goes on the first line, before the failed guesses
                let msg = match msg.split_once('\n') {
                    Some((first, rest)) => format!("{first}{hint}\n{rest}"),
                    None => msg + &hint,
                };
                return Err(InputError(msg).into());
            }
        };
        let spacing = spacing(m, &walk, self.dt_out);
        let opts = options_spaced(m, self.strides, &spacing, self.integrator);
        check_samples(&walk, &opts, self.flags)?;
        let trajectory = run(m, &walk, &opts)?;
        if let Some((path, format)) = &self.out {
            let data = crate::simulate_file::to_store(
                m,
                &trajectory,
                &opts,
                &spacing,
                &walk.label,
                &self.command,
            );
            let mut prov = crate::provenance(
                &self.command,
                &crate::simulate_file::options_json(&opts, &spacing),
            );
            prov.model_spec = crate::model::spec_toml(&self.model_name).unwrap_or_default();
            crate::simulate_file::write(path, *format, data, m, &prov)
                .map_err(|e| InputError(e.to_string()))?;
        }
        let report = SimulateReport::of(self, &walk, &trajectory, &spacing);
        Ok(SimulateRun {
            report,
            trajectory,
            spacing,
        })
    }

    /// Claims `out` (refused if it exists without `force`, or if it is the model's spec file).
    fn claim(&self) -> Result<Option<crate::output::Claim>, InputError> {
        let Some((path, format)) = &self.out else {
            return Ok(None);
        };
        let inputs: Vec<_> = crate::output::model_input(&self.model_name)
            .into_iter()
            .collect();
        crate::output::claim(
            &[crate::output::Output {
                flag: match self.spelling {
                    Spelling::Cli => "--out",
                    Spelling::Python => "out",
                },
                path,
                format: format.claimed(),
                may_exist: false,
            }],
            &inputs,
            self.force,
        )
        .map(Some)
    }
}

/// A walk's result: the report, and the trajectory and its spacing for a front end that
/// returns the arrays (Python).
pub struct SimulateRun {
    pub report: SimulateReport,
    pub trajectory: Trajectory,
    pub spacing: Spacing,
}

/// `simulate`'s report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SimulateReport {
    pub model: String,
    pub slope: f64,
    /// Where the walk started (`stable gait [..]`, `state [..]`).
    pub start: String,
    /// Strides asked and done.
    pub strides: usize,
    pub strides_done: usize,
    /// Samples and events recorded.
    pub samples: usize,
    pub event_count: usize,
    /// `ok`, or how the walk ended early (a fall by name).
    pub outcome: String,
    /// The walk ended in a fall.
    pub fell: bool,
    /// The output spacing and where it came from.
    pub dt_out: Option<f64>,
    pub dt_out_source: String,
    /// The file written.
    pub out: Option<PathBuf>,
}

impl SimulateReport {
    fn of(p: &SimulatePlan, walk: &Walk, tr: &Trajectory, sp: &Spacing) -> Self {
        SimulateReport {
            model: p.model.info.name.to_string(),
            slope: p.model.slope(),
            start: walk.label.clone(),
            strides: p.strides,
            strides_done: tr.steps_done,
            samples: tr.len(),
            event_count: tr.events.len(),
            outcome: match tr.outcome {
                pdw_limit::StrideOutcome::Ok => "ok".to_string(),
                pdw_limit::StrideOutcome::Fall { kind, .. } => kind.name().to_string(),
                o => o.to_string(),
            },
            fell: matches!(tr.outcome, pdw_limit::StrideOutcome::Fall { .. }),
            dt_out: sp.dt_out,
            dt_out_source: sp.source.clone(),
            out: p.out.as_ref().map(|(path, _)| path.clone()),
        }
    }
}

impl Report for SimulateReport {
    fn text(&self) -> String {
        let ended = match self.outcome.as_str() {
            "ok" => "all strides done".to_string(),
            o if self.fell => format!("fell ({o})"),
            o => o.to_string(),
        };
        let mut t = format!(
            "model {}  slope {} rad  from {}\n{} of {} strides, {} samples, {} events; ended: \
             {ended}\n",
            self.model,
            self.slope,
            self.start,
            self.strides_done,
            self.strides,
            self.samples,
            self.event_count
        );
        if let Some(p) = &self.out {
            t += &format!("wrote {}\n", p.display());
        }
        t
    }
}
