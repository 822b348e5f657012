//! Trajectories: the time series of a walk of `N` steps from one initial state.
//!
//! A step runs from the post-impact state on the Poincaré section to the next firing of the
//! section reset ([`pdw_hybrid::Section::section_guard`]), through every intermediate reset (a knee strike),
//! exactly as one application of the stride map ([`crate::StrideMap`]) does. Along the way
//! [`simulate`] records, per sample,
//!
//! * the time `t` and the full state `x = (q, q̇)` in the model's state order, and its mode;
//! * the stance-foot ground reaction (normal, tangential, friction coefficient needed) and the
//!   knee-lock torques, where the model computes them ([`Walker::constraint_forces`]);
//! * the validity flags ([`Walker::step_flags`]) as a bit mask ([`FLAG_NORMAL_NEGATIVE`], …);
//! * the total mechanical energy, where the model defines one ([`model_energy`]); it is conserved
//!   by the flow between impacts and drops at each plastic impact.
//!
//! # Sampling
//! Without an output step (`dt_out = None`) a sample is taken at the start, after every accepted
//! integrator step, and on both sides of every event: the pre-impact state (old mode) and the
//! post-impact state (new mode) share the event time. The integrator restarts at every event
//! from the state alone.
//! With `dt_out = Some(h)` the samples are exactly at `t = k h` (the integrator is stopped at
//! each of these times); events are then only in [`Trajectory::events`], with their pre- and
//! post-impact states, unless [`TrajectoryOptions::event_samples`] asks for both sides of every
//! event among the samples too (the grid and the impacts, for plots).
//!
//! A walk that falls, times out or fails numerically ends early; [`Trajectory::outcome`] says
//! how (a [`StrideOutcome`], [`StrideOutcome::Ok`] when all `N` steps were completed).

use crate::error::LimitError;
use crate::stride::{StrideOutcome, StrideStop, MAX_EVENTS_PER_STRIDE};
use pdw_hybrid::{Integrator, Options, Scratch, StopReason};
use pdw_model::Walker;

/// Why a trajectory could not be started.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TrajectoryError {
    /// Invalid options or integrator settings.
    #[error(transparent)]
    Limit(#[from] LimitError),
    /// The initial state does not fit the model.
    #[error("initial state: {0}")]
    State(String),
    /// The walk would record more than [`TrajectoryOptions::max_samples`] samples.
    #[error(
        "the trajectory would hold more than {max_samples} samples ({bytes_per_sample} bytes \
         each) after {steps_done} of {steps} steps; give a larger output step, fewer steps or a \
         larger integrator step"
    )]
    TooManySamples {
        max_samples: usize,
        bytes_per_sample: usize,
        steps_done: usize,
        steps: usize,
    },
}

/// Bytes one trajectory sample takes for a state of `dim` components: time, state, mode, step,
/// energy, ground reaction (normal, tangential, friction), two knee torques, flags.
pub fn bytes_per_sample(dim: usize) -> usize {
    8 * (dim + 1) + 4 + 4 + 8 + 3 * 8 + 2 * 8 + 1
}

/// Flag bit: the normal ground reaction on the stance foot is negative (the foot would lift off).
pub const FLAG_NORMAL_NEGATIVE: u8 = 1;
/// Flag bit: a locked knee needs a locking torque of the wrong sign (it would unlock).
pub const FLAG_KNEE_UNLOCKS: u8 = 2;
/// Flag bit: the swing foot is below ground after mid-stance (it scuffs).
pub const FLAG_SWING_FOOT_SCUFFS: u8 = 4;

/// Integration tolerance of trajectories (DOP853, `rtol = atol`), the one the CLI's validity
/// check has always used.
pub const TRAJECTORY_TOL: f64 = 1e-10;

/// What to simulate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrajectoryOptions {
    /// Steps (heel strike to heel strike), at least 1.
    pub steps: usize,
    /// Output step (model time units); `None`: every accepted integrator step and every event.
    pub dt_out: Option<f64>,
    /// Integrator.
    pub integrator: Options,
    /// Most samples to record (`usize::MAX`: no bound). A walk that would record more stops
    /// with [`TrajectoryError::TooManySamples`] instead of growing without bound (a tiny
    /// `dt_out` or fixed integrator step); front ends set it from the memory available.
    pub max_samples: usize,
    /// With `dt_out`: also sample both sides of every event (the pre-impact state in the old
    /// mode and the post-impact state in the new one, at the event time). Without `dt_out`
    /// events are always sampled.
    pub event_samples: bool,
}

impl TrajectoryOptions {
    /// `steps` steps sampled at every accepted step of DOP853 at [`TRAJECTORY_TOL`].
    pub fn new(steps: usize) -> Self {
        Self {
            steps,
            dt_out: None,
            integrator: Options::dop853(TRAJECTORY_TOL),
            max_samples: usize::MAX,
            event_samples: false,
        }
    }

    fn validate(&self) -> Result<(), TrajectoryError> {
        if self.steps == 0 {
            return Err(LimitError::InvalidOption {
                name: "steps",
                value: 0.0,
                allowed: "an integer >= 1",
            }
            .into());
        }
        if let Some(h) = self.dt_out {
            if !(h.is_finite() && h > 0.0) {
                return Err(LimitError::InvalidOption {
                    name: "dt_out",
                    value: h,
                    allowed: "a positive finite time step",
                }
                .into());
            }
        }
        self.integrator.validate().map_err(LimitError::from)?;
        Ok(())
    }
}

/// One event along a trajectory.
#[derive(Clone, Debug, PartialEq)]
pub struct TrajectoryEvent {
    /// Event time.
    pub t: f64,
    /// Step during which it happened (0-based).
    pub step: usize,
    /// The guard's name (e.g. `"heel_strike"`, `"knee_strike"`), or for a fall the fall's name
    /// ([`pdw_hybrid::FallKind::name`]).
    pub kind: String,
    /// True for the reset that ends a step (the section event).
    pub ends_step: bool,
    /// True for a terminal guard (a fall).
    pub fall: bool,
    /// Index of the guard in the guards of `mode_before` ([`pdw_hybrid::HybridSystem::guards`]),
    /// for the model's impact report ([`Walker::impact_report`]).
    pub guard: usize,
    /// Mode before the event.
    pub mode_before: usize,
    /// Mode after the event (`mode_before` for a fall).
    pub mode_after: usize,
    /// State just before the event.
    pub pre: Vec<f64>,
    /// State just after the event (equal to `pre` for a fall).
    pub post: Vec<f64>,
}

/// Stance-foot ground reaction and knee-lock torques per sample.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ForceSeries {
    /// Normal ground reaction `(n)`; positive: the ground pushes up.
    pub normal: Vec<f64>,
    /// Tangential ground reaction along the slope, downhill positive `(n)`.
    pub tangential: Vec<f64>,
    /// Friction coefficient the ground must supply, `|f_t / f_n|` `(n)`.
    pub friction_required: Vec<f64>,
    /// Knee-lock torques `[stance knee, swing knee]` per sample, `(n × 2)` row-major; NaN where
    /// the knee is free or absent. Negative: the knee would unlock.
    pub knee_torque: Vec<f64>,
}

/// Units of every column of a [`Trajectory`].
#[derive(Clone, Debug, PartialEq)]
pub struct TrajectoryUnits {
    pub time: String,
    /// One per state component.
    pub state: Vec<String>,
    pub force: String,
    pub torque: String,
    pub energy: String,
}

/// A simulated walk. Sample arrays have one entry per sample (`n`), states `n × d` row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// State component names (`d`).
    pub state_names: Vec<String>,
    /// Sample times `(n)`.
    pub t: Vec<f64>,
    /// States `(n × d)`, row-major.
    pub x: Vec<f64>,
    /// Mode per sample `(n)`.
    pub mode: Vec<u32>,
    /// Step index per sample `(n)`.
    pub step: Vec<u32>,
    /// Ground reaction and knee torques, if the model computes them.
    pub forces: Option<ForceSeries>,
    /// Validity flag bits per sample `(n)`, if the model computes them.
    pub flags: Option<Vec<u8>>,
    /// Total mechanical energy per sample `(n)`, if the model defines it.
    pub energy: Option<Vec<f64>>,
    /// Every event, in time order.
    pub events: Vec<TrajectoryEvent>,
    /// How the walk ended: `Ok` when all requested steps were completed.
    pub outcome: StrideOutcome,
    /// Completed steps.
    pub steps_done: usize,
    /// Section state after each completed step (`steps_done × d_s`, row-major).
    pub section: Vec<f64>,
    pub units: TrajectoryUnits,
}

impl Trajectory {
    /// State dimension `d`.
    pub fn dim(&self) -> usize {
        self.state_names.len()
    }

    /// Number of samples `n`.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True without samples (never the case for a trajectory returned by [`simulate`]).
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// State of sample `i`.
    pub fn state(&self, i: usize) -> &[f64] {
        let d = self.dim();
        &self.x[i * d..(i + 1) * d]
    }
}

/// The unit of `w`'s total mechanical energy ([`Walker::energy`]), `None` for a model without
/// one.
pub fn model_energy(w: &dyn Walker) -> Option<String> {
    let x = vec![0.0; w.dim()];
    w.energy(&x).map(|_| w.energy_unit().to_string())
}

/// Units of the columns of a trajectory of `w`, from the model's own [`Walker::units`]: time in
/// its time unit, angles in rad, rates in rad per time unit, forces and torques in its units.
pub fn units(w: &dyn Walker, energy_unit: &str) -> TrajectoryUnits {
    let mu = w.units();
    let time = mu.time.to_string();
    let state = w
        .state_names()
        .iter()
        .map(|n| {
            if n.ends_with("_rate") || n.ends_with("dot") {
                format!("rad/{time}")
            } else {
                "rad".to_string()
            }
        })
        .collect();
    TrajectoryUnits {
        time,
        state,
        force: mu.force.to_string(),
        torque: mu.torque.to_string(),
        energy: energy_unit.into(),
    }
}

/// The full initial state from `values`: section coordinates (length `d_s`, lifted with
/// [`pdw_hybrid::Section::lift`]) or a full state (length `d`, taken as the state just after a
/// heel strike, in the section mode).
pub fn initial_state(w: &dyn Walker, values: &[f64]) -> Result<Vec<f64>, TrajectoryError> {
    let (ds, d) = (w.section_dim(), w.dim());
    if values.iter().any(|v| !v.is_finite()) {
        return Err(TrajectoryError::State(format!(
            "{values:?} has a non-finite value"
        )));
    }
    if values.len() == ds {
        let mut x = vec![0.0; d];
        w.lift(values, &mut x);
        Ok(x)
    } else if values.len() == d {
        Ok(values.to_vec())
    } else {
        Err(TrajectoryError::State(format!(
            "{} values given; model '{}' takes {ds} section coordinates ({}) or a full state of \
             {d} ({})",
            values.len(),
            w.name(),
            w.section_names().join(", "),
            w.state_names().join(", ")
        )))
    }
}

/// Per-sample recorder.
struct Recorder<'a> {
    w: &'a dyn Walker,
    energy: bool,
    tr: Trajectory,
    forces_ok: bool,
    flags_ok: bool,
    /// [`TrajectoryOptions::max_samples`]
    max_samples: usize,
    /// A sample was refused: the walk is over the bound.
    full: bool,
    /// The model's scratch, reused by every sample.
    ws: Scratch,
}

impl<'a> Recorder<'a> {
    /// An empty recorder of a walk of `w` under `opts`.
    fn new(w: &'a dyn Walker, opts: &TrajectoryOptions) -> Self {
        let energy = model_energy(w);
        let units = units(w, energy.as_deref().unwrap_or(""));
        Recorder {
            w,
            energy: energy.is_some(),
            tr: Trajectory {
                state_names: w.state_names().iter().map(|s| s.to_string()).collect(),
                t: Vec::new(),
                x: Vec::new(),
                mode: Vec::new(),
                step: Vec::new(),
                forces: None,
                flags: None,
                energy: None,
                events: Vec::new(),
                outcome: StrideOutcome::Ok,
                steps_done: 0,
                section: Vec::new(),
                units,
            },
            forces_ok: true,
            flags_ok: true,
            max_samples: opts.max_samples.max(1),
            full: false,
            ws: Scratch::new(),
        }
    }
}

impl Recorder<'_> {
    fn push(&mut self, t: f64, x: &[f64], mode: usize, step: usize) {
        if self.tr.t.len() >= self.max_samples {
            self.full = true;
            return;
        }
        let tr = &mut self.tr;
        tr.t.push(t);
        tr.x.extend_from_slice(x);
        tr.mode.push(mode as u32);
        tr.step.push(step as u32);
        if let Some(e) = self
            .energy
            .then(|| self.w.energy_in(&mut self.ws, x))
            .flatten()
        {
            tr.energy.get_or_insert_with(Vec::new).push(e);
        }
        match (
            self.forces_ok,
            self.w.constraint_forces_in(&mut self.ws, mode, x),
        ) {
            (true, Some(cf)) => {
                let f = tr.forces.get_or_insert_with(ForceSeries::default);
                f.normal.push(cf.normal);
                f.tangential.push(cf.tangential);
                f.friction_required.push(cf.friction_required);
                f.knee_torque
                    .extend(cf.knee_torque.iter().map(|k| k.unwrap_or(f64::NAN)));
            }
            _ => {
                self.forces_ok = false;
                tr.forces = None;
            }
        }
        match (self.flags_ok, self.w.step_flags_in(&mut self.ws, mode, x)) {
            (true, Some(fl)) => {
                let bit = |on: bool, b: u8| if on { b } else { 0 };
                let bits = bit(fl.normal_force_negative, FLAG_NORMAL_NEGATIVE)
                    | bit(fl.knee_unlocks, FLAG_KNEE_UNLOCKS)
                    | bit(fl.swing_foot_scuffs, FLAG_SWING_FOOT_SCUFFS);
                tr.flags.get_or_insert_with(Vec::new).push(bits);
            }
            _ => {
                self.flags_ok = false;
                tr.flags = None;
            }
        }
    }
}

/// Simulates `opts.steps` steps of `w` from the full state `x0` (just after a heel strike, in the
/// section mode; see [`initial_state`]) at `t = 0`. A fall or a numerical failure ends the walk
/// early and is reported in [`Trajectory::outcome`], not as an error.
pub fn simulate(
    w: &dyn Walker,
    x0: &[f64],
    opts: &TrajectoryOptions,
) -> Result<Trajectory, TrajectoryError> {
    opts.validate()?;
    let d = w.dim();
    if x0.len() != d {
        return Err(TrajectoryError::State(format!(
            "{} values given; model '{}' has a state of {d}",
            x0.len(),
            w.name()
        )));
    }
    let mut rec = Recorder::new(w, opts);
    let mut walk = Walk {
        integ: Integrator::new(d, opts.integrator).map_err(LimitError::from)?,
        t: 0.0,
        x: x0.to_vec(),
        mode: w.section_mode(),
        buf: vec![0.0; d],
        s: vec![0.0; w.section_dim()],
        k_out: 0,
        resume: false,
        sample_events: opts.dt_out.is_some() && opts.event_samples,
    };
    match opts.dt_out {
        None => rec.push(walk.t, &walk.x, walk.mode, 0),
        Some(_) => {
            rec.push(walk.t, &walk.x, walk.mode, 0);
            walk.k_out = 1;
        }
    }
    'steps: for step in 0..opts.steps {
        let t_budget = walk.t + w.max_stride_time();
        let mut events = 0;
        loop {
            let stop = walk.segment(w, &mut rec, opts.dt_out, t_budget, step);
            if rec.full {
                return Err(TrajectoryError::TooManySamples {
                    max_samples: opts.max_samples,
                    bytes_per_sample: bytes_per_sample(d),
                    steps_done: step,
                    steps: opts.steps,
                });
            }
            let outcome = match StrideStop::of(stop, w.guards(walk.mode)) {
                StrideStop::Reset { guard } => {
                    if walk.reset(w, &mut rec, opts.dt_out, guard, step) {
                        continue 'steps;
                    }
                    events += 1;
                    if events > MAX_EVENTS_PER_STRIDE {
                        StrideOutcome::TooManyEvents
                    } else {
                        continue;
                    }
                }
                StrideStop::End(StrideOutcome::Fall { kind: fall, guard }) => {
                    rec.tr.events.push(TrajectoryEvent {
                        t: walk.t,
                        step,
                        kind: fall.name().to_string(),
                        ends_step: false,
                        fall: true,
                        guard,
                        mode_before: walk.mode,
                        mode_after: walk.mode,
                        pre: walk.x.clone(),
                        post: walk.x.clone(),
                    });
                    StrideOutcome::Fall { kind: fall, guard }
                }
                StrideStop::End(outcome) => outcome,
            };
            if opts.dt_out.is_some() && rec.tr.t.last() != Some(&walk.t) {
                // The stop point closes the series.
                rec.push(walk.t, &walk.x, walk.mode, step);
            }
            rec.tr.outcome = outcome;
            break 'steps;
        }
    }
    if rec.full {
        return Err(TrajectoryError::TooManySamples {
            max_samples: opts.max_samples,
            bytes_per_sample: bytes_per_sample(d),
            steps_done: rec.tr.steps_done,
            steps: opts.steps,
        });
    }
    Ok(rec.tr)
}

/// The state of a walk being simulated: the integrator, where the walk is, and the output
/// grid's bookkeeping.
struct Walk {
    integ: Integrator,
    t: f64,
    x: Vec<f64>,
    mode: usize,
    /// The post-impact state of a reset.
    buf: Vec<f64>,
    /// The section coordinates of a completed stride.
    s: Vec<f64>,
    /// Next output time (index k of t = k h) when sampling on a grid.
    k_out: u64,
    /// Every segment after the first continues the same trajectory (`Integrator::resume`).
    resume: bool,
    /// Both sides of every event among the grid's samples (without a grid they always are).
    sample_events: bool,
}

impl Walk {
    /// Integrates the current mode of stride `step` on to its next event or to `t_budget`,
    /// sampling into `rec` every accepted step (`dt_out = None`) or at the grid times `k h`
    /// (`dt_out = Some(h)`).
    fn segment(
        &mut self,
        w: &dyn Walker,
        rec: &mut Recorder<'_>,
        dt_out: Option<f64>,
        t_budget: f64,
        step: usize,
    ) -> StopReason {
        match dt_out {
            None => {
                let mut first = true;
                let m0 = self.mode;
                // A full recorder ends the call (a walk over the sample bound stops
                // there instead of integrating on to the end of its stride).
                let mut obs = |ts: f64, xs: &[f64]| {
                    if !std::mem::take(&mut first) {
                        rec.push(ts, xs, m0, step);
                    }
                    !rec.full
                };
                let (t, x) = (&mut self.t, &mut self.x);
                if std::mem::replace(&mut self.resume, true) {
                    self.integ
                        .resume_observed_while(w, self.mode, t, x, t_budget, &mut obs)
                } else {
                    self.integ
                        .integrate_observed_while(w, self.mode, t, x, t_budget, &mut obs)
                }
            }
            Some(h) => loop {
                let t_next = self.k_out as f64 * h;
                let t_end = t_next.min(t_budget);
                let stop = if std::mem::replace(&mut self.resume, true) {
                    self.integ
                        .resume(w, self.mode, &mut self.t, &mut self.x, t_end)
                } else {
                    self.integ
                        .integrate(w, self.mode, &mut self.t, &mut self.x, t_end)
                };
                if stop != StopReason::EndTime || t_end == t_budget {
                    break stop;
                }
                // A grid time on an event already sampled (a gait's period / N) is not
                // sampled twice.
                if !(self.sample_events && rec.tr.t.last() == Some(&self.t)) {
                    rec.push(self.t, &self.x, self.mode, step);
                }
                self.k_out += 1;
                if rec.full {
                    break stop;
                }
            },
        }
    }

    /// The reset by `guard` of the current mode in stride `step`: the event recorded (both
    /// sides sampled without a grid or where the options ask for it) and the walk moved to the
    /// post-impact state; true when the reset ends the stride (the section guard).
    fn reset(
        &mut self,
        w: &dyn Walker,
        rec: &mut Recorder<'_>,
        dt_out: Option<f64>,
        guard: usize,
        step: usize,
    ) -> bool {
        let spec = w.guards(self.mode)[guard];
        let new_mode = w.reset(
            self.integ.scratch(),
            self.mode,
            guard,
            &self.x,
            &mut self.buf,
        );
        let ends_step = (self.mode, guard) == w.section_guard();
        if self.sample_events && rec.tr.t.last() != Some(&self.t) {
            rec.push(self.t, &self.x, self.mode, step);
        }
        rec.tr.events.push(TrajectoryEvent {
            t: self.t,
            step,
            kind: spec.name.to_string(),
            ends_step,
            fall: false,
            guard,
            mode_before: self.mode,
            mode_after: new_mode,
            pre: self.x.clone(),
            post: self.buf.clone(),
        });
        self.x.copy_from_slice(&self.buf);
        self.mode = new_mode;
        let sampled = dt_out.is_none() || self.sample_events;
        if ends_step {
            rec.tr.steps_done = step + 1;
            w.project(&self.x, &mut self.s);
            rec.tr.section.extend_from_slice(&self.s);
            if sampled {
                rec.push(self.t, &self.x, self.mode, step + 1);
            }
            return true;
        }
        if sampled {
            rec.push(self.t, &self.x, self.mode, step);
        }
        false
    }
}

pub use crate::validity::Validity;
