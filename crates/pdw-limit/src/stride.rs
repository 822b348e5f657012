//! The stride map `P: s ↦ s'` on the post-heel-strike Poincaré section.
//!
//! A stride starts from the lifted section state `x₀ = L(s)` in the section mode at `t = 0`,
//! integrates through every intermediate reset (e.g. a knee strike), and ends at the next firing
//! of the section reset `(mode, guard)` = [`Section::section_guard`]; then `s' = Π(R(x⁻))`
//! with `Π` = [`Section::project`]. `P` is a pure function of the model's parameters and `s`
//! (and the integrator options). A stride that ends otherwise — a terminal guard (a fall), the
//! time budget [`Section::max_stride_time`], a non-finite state, a step-size or step-count
//! failure — is an outcome ([`StrideOutcome`]), not an error; [`StrideOutcome::end`] names it
//! in the vocabulary the basin, the walks and the files share ([`crate::end`]). "Stride" is
//! heel strike to heel strike; "step" is the integrator's.
//!
//! The same [`EventDriver`] runs a stride through the scalar integrator
//! ([`pdw_hybrid::run_scalar_with`]) and as one lane of a batch ([`pdw_hybrid::run_batch`]), so
//! batched strides are bit-identical to scalar ones.

use crate::end::End;
use crate::error::LimitError;
use pdw_hybrid::{
    run_batch, run_batch_par, run_scalar_with, BatchOptions, Control, FallKind, GuardKind,
    GuardSpec, HybridSystem, Integrator, LaneDriver, Options, Scratch, Section, StopReason,
};
use std::fmt;

/// Intermediate resets allowed in one stride before it is declared a failure (guards against a
/// chattering sequence of events).
pub const MAX_EVENTS_PER_STRIDE: usize = 64;

/// How a stride ended, with its detail (the fall's guard, which integrator failure);
/// [`StrideOutcome::end`] names it in the one vocabulary of strides and cells ([`End`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StrideOutcome {
    /// Reached the section: a complete stride.
    Ok,
    /// A terminal guard fired: a fall of model-defined kind `code` (guard index `guard`).
    Fall { kind: FallKind, guard: usize },
    /// No heel strike (no section event) within the stride time budget
    /// [`Section::max_stride_time`]. Not a basin cell's `timeout` (a cell not classified within
    /// its stride budget): its end is [`End::FallNoHeelStrike`].
    NoHeelStrike,
    /// The state became non-finite.
    NonFinite,
    /// The integrator's step size collapsed.
    StepTooSmall,
    /// The integrator's step budget ran out.
    MaxSteps,
    /// More than [`MAX_EVENTS_PER_STRIDE`] intermediate resets.
    TooManyEvents,
}

/// What a stride does at a stop of its integration: apply the reset guard `guard` (the stride
/// goes on, or ends at the section), or end with an outcome. One mapping for every driver of
/// strides (the stride map, trajectories, the lockstep walkers).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StrideStop {
    /// A reset guard fired: the driver applies the reset.
    Reset { guard: usize },
    /// The stride ends: a terminal guard (a fall) or the integrator stopped.
    End(StrideOutcome),
}

impl StrideStop {
    /// The meaning of `stop` in a mode whose guards are `guards`: a terminal guard is a fall of
    /// its kind, the integrator's own stops are [`StrideOutcome::NoHeelStrike`] (the end time, the
    /// stride time budget),
    /// [`StrideOutcome::NonFinite`], [`StrideOutcome::StepTooSmall`], [`StrideOutcome::MaxSteps`].
    pub fn of(stop: StopReason, guards: &[GuardSpec]) -> Self {
        StrideStop::End(match stop {
            StopReason::Guard { guard } => match guards[guard].kind {
                GuardKind::Reset => return StrideStop::Reset { guard },
                GuardKind::Terminal(kind) => StrideOutcome::Fall { kind, guard },
            },
            StopReason::EndTime => StrideOutcome::NoHeelStrike,
            StopReason::NonFinite => StrideOutcome::NonFinite,
            StopReason::StepTooSmall => StrideOutcome::StepTooSmall,
            StopReason::MaxSteps => StrideOutcome::MaxSteps,
        })
    }
}

impl StrideOutcome {
    /// True for [`StrideOutcome::Ok`].
    pub fn is_ok(&self) -> bool {
        matches!(self, StrideOutcome::Ok)
    }

    /// The stride's end in the one vocabulary of strides and cells ([`crate::end`]): a
    /// complete stride is [`End::HeelStrike`], a fall the end of its kind
    /// ([`End::of_fall`]), no heel strike within the time budget [`End::FallNoHeelStrike`],
    /// the three integrator failures (step size, step budget, too many events)
    /// [`End::IntegratorFailure`]. A basin cell whose stride ends so ends the same way.
    pub fn end(&self) -> End {
        match *self {
            StrideOutcome::Ok => End::HeelStrike,
            StrideOutcome::Fall { kind, .. } => End::of_fall(kind),
            StrideOutcome::NoHeelStrike => End::FallNoHeelStrike,
            StrideOutcome::NonFinite => End::NonFinite,
            StrideOutcome::StepTooSmall
            | StrideOutcome::MaxSteps
            | StrideOutcome::TooManyEvents => End::IntegratorFailure,
        }
    }
}

impl fmt::Display for StrideOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StrideOutcome::Ok => write!(f, "ok"),
            // The fall by name ("fell backward"); the guard index is a model detail kept in the
            // value, not in the message.
            StrideOutcome::Fall { kind, .. } => write!(f, "{}", kind.name()),
            StrideOutcome::NoHeelStrike => {
                write!(f, "no heel strike within the stride time budget")
            }
            StrideOutcome::NonFinite => write!(f, "non-finite state"),
            StrideOutcome::StepTooSmall => write!(f, "integrator step size too small"),
            StrideOutcome::MaxSteps => write!(f, "integrator step budget exhausted"),
            StrideOutcome::TooManyEvents => write!(f, "too many events in one stride"),
        }
    }
}

/// Raw result of one run of an [`EventDriver`] (full states).
#[derive(Clone, Debug, PartialEq)]
pub struct StrideEnd {
    pub outcome: StrideOutcome,
    /// Time at the stop (the stride period when `outcome` is `Ok`).
    pub t: f64,
    /// State at the stop point before any reset (the pre-impact state on the section guard).
    pub pre: Vec<f64>,
    /// State after the section reset (`Ok`), or the stop state otherwise.
    pub post: Vec<f64>,
    /// Intermediate resets applied (not counting the section reset).
    pub events: usize,
}

/// Lane driver for one stride of any [`HybridSystem`] (the model itself or its
/// [`Variational`](crate::variational::Variational) extension): items are full initial states.
pub struct EventDriver {
    /// `(mode, guard)` whose reset ends the stride.
    pub section_guard: (usize, usize),
    /// Mode at `t = 0`.
    pub start_mode: usize,
    /// Stride time budget.
    pub t_max: f64,
}

/// Per-lane bookkeeping of an [`EventDriver`].
#[derive(Default)]
pub struct EventLane {
    /// Reset output buffer `(dim)`.
    buf: Vec<f64>,
    /// Pre-event state `(dim)`, filled at the final stop.
    pre: Vec<f64>,
    outcome: Option<StrideOutcome>,
    events: usize,
}

impl<H: HybridSystem + ?Sized> LaneDriver<H> for EventDriver {
    type Item = Vec<f64>;
    type Output = StrideEnd;
    type Lane = EventLane;

    fn start(
        &self,
        _sys: &H,
        item: &Vec<f64>,
        lane: &mut EventLane,
        x: &mut [f64],
    ) -> (usize, f64) {
        x.copy_from_slice(item);
        lane.buf.resize(x.len(), 0.0);
        (self.start_mode, self.t_max)
    }

    fn on_stop(
        &self,
        sys: &H,
        ws: &mut Scratch,
        _item: &Vec<f64>,
        lane: &mut EventLane,
        stop: StopReason,
        mode: usize,
        _t: f64,
        x: &mut [f64],
    ) -> Control {
        let outcome = match StrideStop::of(stop, sys.guards(mode)) {
            StrideStop::Reset { guard } => {
                let new_mode = sys.reset(ws, mode, guard, x, &mut lane.buf);
                if (mode, guard) == self.section_guard {
                    lane.pre = x.to_vec();
                    x.copy_from_slice(&lane.buf);
                    StrideOutcome::Ok
                } else if lane.events >= MAX_EVENTS_PER_STRIDE {
                    StrideOutcome::TooManyEvents
                } else {
                    lane.events += 1;
                    x.copy_from_slice(&lane.buf);
                    return Control::Continue {
                        mode: new_mode,
                        t_end: self.t_max,
                    };
                }
            }
            StrideStop::End(outcome) => outcome,
        };
        if lane.pre.is_empty() {
            lane.pre = x.to_vec();
        }
        lane.outcome = Some(outcome);
        Control::Finish
    }

    fn finish(&self, _sys: &H, _item: &Vec<f64>, lane: EventLane, t: f64, x: &[f64]) -> StrideEnd {
        StrideEnd {
            outcome: lane.outcome.unwrap_or(StrideOutcome::NonFinite),
            t,
            pre: lane.pre,
            post: x.to_vec(),
            events: lane.events,
        }
    }
}

/// One stride in section coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct Stride {
    pub outcome: StrideOutcome,
    /// `P(s)` (when `outcome` is `Ok`; otherwise the projection of the stop state).
    pub next: Vec<f64>,
    /// Stride duration (model time units).
    pub period: f64,
    /// Full state just before the section reset (or at the stop).
    pub pre_event: Vec<f64>,
    /// Full state just after the section reset (or at the stop).
    pub post_event: Vec<f64>,
    /// Step length from the model's step-length function, if one was given.
    pub step_length: Option<f64>,
    /// Intermediate resets in this stride.
    pub events: usize,
}

/// Model-provided step length from the pre-impact state.
pub type StepLengthFn<'a> = &'a (dyn Fn(&[f64]) -> f64 + Sync);

/// The stride map of a model with a section. The model is held as `&dyn Section`, so the
/// analysis built on the map (Newton, continuation, basins, …) is compiled once for every model
/// type; the integrator calls the model's flow through its vtable, once per batched stage
/// evaluation of all lanes (measured cost in the crate's README).
pub struct StrideMap<'a> {
    sys: &'a dyn Section,
    opts: Options,
    step_length: Option<StepLengthFn<'a>>,
}

impl<'a> StrideMap<'a> {
    /// Stride map of `sys` (any section model: a concrete type or a trait object) integrated
    /// with `opts` (validated here).
    pub fn new<S: Section + ?Sized>(sys: &'a S, opts: Options) -> Result<Self, LimitError> {
        opts.validate()?;
        Ok(Self {
            sys: sys.as_section(),
            opts,
            step_length: None,
        })
    }

    /// Attach the model's step-length function (`x_pre ↦ length`), e.g.
    /// `|x| walker.step_length(x)`.
    pub fn with_step_length(mut self, f: StepLengthFn<'a>) -> Self {
        self.step_length = Some(f);
        self
    }

    /// The model.
    pub fn system(&self) -> &'a dyn Section {
        self.sys
    }

    /// Integrator options.
    pub fn options(&self) -> &Options {
        &self.opts
    }

    /// Section dimension d_s.
    pub fn section_dim(&self) -> usize {
        self.sys.section_dim()
    }

    /// The driver that runs one stride of this model (or of its variational extension).
    pub fn driver(&self) -> EventDriver {
        EventDriver {
            section_guard: self.sys.section_guard(),
            start_mode: self.sys.section_mode(),
            t_max: self.sys.max_stride_time(),
        }
    }

    pub(crate) fn check_dim(&self, s: &[f64]) -> Result<(), LimitError> {
        let expected = self.sys.section_dim();
        if s.len() == expected {
            Ok(())
        } else {
            Err(LimitError::SectionDim {
                expected,
                got: s.len(),
            })
        }
    }

    /// Full section state `L(s)`.
    pub fn lift(&self, s: &[f64]) -> Vec<f64> {
        let mut x = vec![0.0; self.sys.dim()];
        self.sys.lift(s, &mut x);
        x
    }

    /// Section coordinates and metrics of a finished run.
    pub(crate) fn to_stride(&self, end: StrideEnd) -> Stride {
        let mut next = vec![0.0; self.sys.section_dim()];
        self.sys.project(&end.post, &mut next);
        let step_length = match (end.outcome, self.step_length) {
            (StrideOutcome::Ok, Some(f)) => Some(f(&end.pre)),
            _ => None,
        };
        Stride {
            outcome: end.outcome,
            next,
            period: end.t,
            pre_event: end.pre,
            post_event: end.post,
            step_length,
            events: end.events,
        }
    }

    /// One stride from section state `s` (scalar integrator).
    pub fn stride(&self, s: &[f64]) -> Result<Stride, LimitError> {
        let mut integ = Integrator::new(self.sys.dim(), self.opts)?;
        self.stride_with(&mut integ, s)
    }

    /// One stride with a caller-owned integrator (built for `sys.dim()` and these options).
    pub fn stride_with(&self, integ: &mut Integrator, s: &[f64]) -> Result<Stride, LimitError> {
        self.check_dim(s)?;
        let end = run_scalar_with(integ, self.sys, &self.driver(), &self.lift(s))?;
        Ok(self.to_stride(end))
    }

    /// `P(s)`, or [`LimitError::StrideFailed`] if the stride does not reach the section.
    pub fn apply(&self, s: &[f64]) -> Result<Vec<f64>, LimitError> {
        let st = self.stride(s)?;
        if st.outcome.is_ok() {
            Ok(st.next)
        } else {
            Err(LimitError::StrideFailed {
                from: s.to_vec(),
                outcome: st.outcome,
            })
        }
    }

    /// One stride from each section state, `lanes` strides in lockstep (serial).
    pub fn strides(&self, states: &[Vec<f64>], lanes: usize) -> Result<Vec<Stride>, LimitError> {
        self.check_all(states)?;
        let opts = BatchOptions {
            lanes,
            integrator: self.opts,
        };
        Ok(run_batch(self.sys, &self.section_driver(), states, &opts)?)
    }

    /// [`strides`](Self::strides) on a rayon pool in chunks of `chunk` states; results are
    /// identical for any thread count, lane count and chunk size.
    pub fn strides_par(
        &self,
        states: &[Vec<f64>],
        lanes: usize,
        pool: &rayon::ThreadPool,
        chunk: usize,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<Vec<Stride>, LimitError> {
        self.check_all(states)?;
        let opts = BatchOptions {
            lanes,
            integrator: self.opts,
        };
        Ok(run_batch_par(
            self.sys,
            &self.section_driver(),
            states,
            &opts,
            pool,
            chunk,
            progress,
        )?)
    }

    /// The batched strides' driver: section states lifted in the lane, strides finished there.
    fn section_driver(&self) -> SectionDriver<'_, 'a> {
        SectionDriver {
            map: self,
            inner: self.driver(),
        }
    }

    fn check_all(&self, states: &[Vec<f64>]) -> Result<(), LimitError> {
        states.iter().try_for_each(|s| self.check_dim(s))
    }
}

/// Lane driver of the batched stride map: an item is a section state `s`, lifted to `L(s)`
/// in the lane when it starts (no lifted copy of the whole input), and a lane's result is the
/// finished [`Stride`], projected by the thread that ran it. Resets and stops are those of the
/// [`EventDriver`], so a batched stride has the bits of a scalar one.
struct SectionDriver<'m, 'a> {
    map: &'m StrideMap<'a>,
    inner: EventDriver,
}

impl<'a> LaneDriver<dyn Section + 'a> for SectionDriver<'_, 'a> {
    type Item = Vec<f64>;
    type Output = Stride;
    type Lane = EventLane;

    fn start(
        &self,
        sys: &(dyn Section + 'a),
        item: &Vec<f64>,
        lane: &mut EventLane,
        x: &mut [f64],
    ) -> (usize, f64) {
        // As `StrideMap::lift`: L(s) written over zeros.
        x.fill(0.0);
        sys.lift(item, x);
        lane.buf.resize(x.len(), 0.0);
        (self.inner.start_mode, self.inner.t_max)
    }

    fn on_stop(
        &self,
        sys: &(dyn Section + 'a),
        ws: &mut Scratch,
        item: &Vec<f64>,
        lane: &mut EventLane,
        stop: StopReason,
        mode: usize,
        t: f64,
        x: &mut [f64],
    ) -> Control {
        <EventDriver as LaneDriver<dyn Section + 'a>>::on_stop(
            &self.inner,
            sys,
            ws,
            item,
            lane,
            stop,
            mode,
            t,
            x,
        )
    }

    fn finish(
        &self,
        sys: &(dyn Section + 'a),
        item: &Vec<f64>,
        lane: EventLane,
        t: f64,
        x: &[f64],
    ) -> Stride {
        let end = <EventDriver as LaneDriver<dyn Section + 'a>>::finish(
            &self.inner,
            sys,
            item,
            lane,
            t,
            x,
        );
        self.map.to_stride(end)
    }
}
