//! The Monte Carlo ensemble of walkers on random ground, in batched lockstep: every walker is a
//! lane of the batched engine ([`pdw_hybrid::run_batch_par`]), as a basin's cells are; a lane that
//! completes a stride starts the walker's next one on its own line, and a lane whose walker
//! fell or reached the step limit takes the next walker of the queue.
//!
//! # One model for every slope
//! A lane integrates the model of the **mean** slope `s̄`, whatever line its walker is on. The
//! flow does not see the ground line (gravity is physical): the model at slope `s`, in the frame
//! of line `s`, at state `y` has the flow of the model at `s̄` at `z = y − σ (s − s̄) e_a`, the
//! same configuration measured from the mean line's normal ([`Walker::terrain_frame`]: index
//! `a`, sign `σ`; module docs of [`crate::terrain`]). The lane's state is `z` — the walk's own
//! Markov state, in the mean slope's frame — with the slope `s` of the walker's current line
//! appended as one more component, constant along the flow ([`LineFrame`]). Only the guards,
//! their admissibility and the impacts see the line: they are the model's, evaluated at
//! `y = z + σ (s − s̄) e_a`, with the admissibility of the model at slope `s`
//! ([`Walker::admissible_on_slope`]: the chain walkers' `stance_reverses` counts only while the
//! stance leg is behind the vertical, `q₀ > s`); an impact's result is shifted back,
//! `z⁺ = R(y⁻) − σ (s − s̄) e_a`. Every model's guards and impacts were checked for the slope:
//! the simplest walker's and the rimless wheel's guards and impacts are angles measured from
//! the line (no slope parameter enters them); the chain walkers' guards are the swing foot's
//! height above the line and state components, their impacts are the impulse equations of the
//! chain (inertia and geometry, no gravity), and only the admissibility above uses the slope.
//!
//! The shifts are the scalar walk's own expressions ([`SlopeWalk::stride`]): only the flow
//! is evaluated at `z` instead of `y`, so a lockstep walk agrees with the scalar one up to the
//! rounding of the flow's angle (and the step sizes that follow from it), not bit for bit.
//!
//! # Reproducibility
//! Walker `i`'s slope at step `k` is the counter-based draw of `(seed, i, k)`
//! ([`SlopeTerrain::slope`]), and a lane's arithmetic does not depend on its lane, its
//! neighbours, the lane count, the chunk size or the thread count (module docs of
//! [`pdw_hybrid::batch`]): a walker's fate is the same however the walk is run.
//!
//! # Step heights
//! A random step height ([`TerrainKind::StepDown`]) changes no frame: the model at
//! `step_down = h` has the flow of the model at the mean height `h̄` (the dynamics see angles
//! only; module docs of [`crate::terrain`], "Step heights"), and only its guards, their
//! admissibility and its impacts see the foothold. So a lane integrates the model of `h̄` with
//! the height `h` of its walker's next foothold appended as one more constant component
//! ([`StepFrame`]), and its guards, admissibility and impacts are the model's at `h`
//! ([`Walker::step_height`], [`StepHeight`]: the model's own methods, which the model itself
//! calls at its `step_down`, so that they are the scalar walk's bit for bit); an impact keeps
//! `h`, and the heel strike that ends a stride writes the walker's next draw there. The
//! simplest walker's heel strike onto a step is not affine in the state, so the lanes sample
//! it as the scalar walk does at `h ≠ 0` (unless every height is the mean, `σ = 0`, where the
//! model of `h̄` answers). The walk agrees with the scalar one
//! ([`crate::terrain::monte_carlo_scalar`], the reference of the tests) up to the arithmetic
//! of the batched flow (step sizes and the order of a lane's sums), not bit for bit; the
//! draws, the counting of heel strikes, censoring and fall kinds are the same
//! (`WalkDriver` drives both terrains). A model without the hook walks step heights one walker
//! at a time; every shipped model has it (the simplest walker since the event detection finds
//! its strikes onto a step down just after mid-stance, which can be narrower than the five
//! sub-intervals of a step: both walks used to miss different ones; docs/cli.md).

use crate::error::LimitError;
use crate::stride::{StrideOutcome, StrideStop, MAX_EVENTS_PER_STRIDE};
use crate::terrain::{Fate, SlopeTerrain, SlopeWalk, TerrainKind};
use faer::{MatMut, MatRef};
use pdw_hybrid::{
    run_batch_par, BatchOptions, Control, GuardSpec, HybridSystem, LaneDriver, Scratch, Section,
    StopReason,
};
use pdw_model::{StepHeight, Walker};

/// Lanes of one lockstep batch by default (the basin's).
pub const LANES: usize = 256;

/// Walkers claimed at a time from the shared queue by default: small, so that the threads
/// share the walkers evenly however long each walks (and the progress bar moves).
pub const CHUNK: usize = 16;

/// The flow of a system whose state is `model`'s followed by components constant along the
/// flow (a line's slope, a foothold's height, a count): the model's flow on its own
/// components, zero on the others.
pub(crate) fn flow_with_constants(
    model: &dyn Walker,
    ws: &mut Scratch,
    mode: usize,
    x: &[f64],
    dx: &mut [f64],
) {
    let d = model.dim();
    model.flow(ws, mode, &x[..d], &mut dx[..d]);
    dx[d..].fill(0.0);
}

/// [`flow_with_constants`] over lanes: the model's batched flow on its columns, zero columns
/// after them.
pub(crate) fn flow_batch_with_constants(
    model: &dyn Walker,
    ws: &mut Scratch,
    mode: usize,
    x: MatRef<'_, f64>,
    mut dx: MatMut<'_, f64>,
) {
    let d = model.dim();
    model.flow_batch(
        ws,
        mode,
        x.subcols(0, d),
        faer::reborrow::ReborrowMut::rb_mut(&mut dx).subcols_mut(0, d),
    );
    for j in d..x.ncols() {
        for l in 0..x.nrows() {
            dx[(l, j)] = 0.0;
        }
    }
}

/// The model of the mean slope as a system of every line (module docs, "One model for every
/// slope"): state `(z, s)`, `z` the model's state in the mean slope's frame, `s` the slope of
/// the walker's current line (constant along the flow).
pub struct LineFrame<'a> {
    model: &'a dyn Walker,
    mean: f64,
    absolute: usize,
    sign: f64,
    d: usize,
}

/// The model's scratch and the line-frame copies of the state.
struct FrameScratch {
    inner: Scratch,
    /// One state in the line's frame `(d)`.
    y: Vec<f64>,
    /// All lanes' states in their lines' frames, column-major `(lanes × d)`.
    cols: Vec<f64>,
}

impl<'a> LineFrame<'a> {
    /// The system of `model` (the model at the mean slope `mean`); [`LimitError::Model`] when
    /// it has no terrain frame.
    pub fn new(model: &'a dyn Walker, mean: f64) -> Result<Self, LimitError> {
        let (absolute, sign) = model.terrain_frame().ok_or_else(|| LimitError::Model {
            param: mean,
            message: "the model does not walk on random terrain (round feet?)".into(),
        })?;
        Ok(Self {
            model,
            mean,
            absolute,
            sign,
            d: model.dim(),
        })
    }

    /// `y = z + σ (s − s̄) e_a`, the state in the frame of its line (the shift of
    /// [`SlopeWalk::shift`] from the mean line to line `s = x[d]`).
    fn to_line(&self, x: &[f64], y: &mut [f64]) {
        y[..self.d].copy_from_slice(&x[..self.d]);
        y[self.absolute] += self.sign * (x[self.d] - self.mean);
    }

    fn scratch<'s>(&self, ws: &'s mut Scratch) -> &'s mut FrameScratch {
        let d = self.d;
        ws.get_or_init(
            || FrameScratch {
                inner: Scratch::new(),
                y: vec![0.0; d],
                cols: Vec::new(),
            },
            |s| s.y.len() == d,
        )
    }
}

impl HybridSystem for LineFrame<'_> {
    fn dim(&self) -> usize {
        self.d + 1
    }

    /// The model's: the slope component is constant and never enters the step-size control.
    fn error_dim(&self) -> usize {
        self.model.error_dim().clamp(1, self.d)
    }

    fn n_modes(&self) -> usize {
        self.model.n_modes()
    }

    fn guards(&self, mode: usize) -> &[GuardSpec] {
        self.model.guards(mode)
    }

    fn flow(&self, ws: &mut Scratch, mode: usize, x: &[f64], dx: &mut [f64]) {
        flow_with_constants(self.model, &mut self.scratch(ws).inner, mode, x, dx);
    }

    fn flow_batch(&self, ws: &mut Scratch, mode: usize, x: MatRef<'_, f64>, dx: MatMut<'_, f64>) {
        flow_batch_with_constants(self.model, &mut self.scratch(ws).inner, mode, x, dx);
    }

    fn guard(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64]) -> f64 {
        let FrameScratch { inner, y, .. } = self.scratch(ws);
        self.to_line(x, y);
        self.model.guard(inner, mode, k, y)
    }

    fn guards_with_rates(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        f: &[f64],
        g: &mut [f64],
        rate: &mut [f64],
    ) {
        let FrameScratch { inner, y, .. } = self.scratch(ws);
        self.to_line(x, y);
        self.model
            .guards_with_rates(inner, mode, y, &f[..self.d], g, rate);
    }

    /// The lanes' states copied into their lines' frames (the expression of `to_line`, lane by
    /// lane), then the model's batched guards on them.
    fn guards_with_rates_batch(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: MatRef<'_, f64>,
        f: MatRef<'_, f64>,
        g: MatMut<'_, f64>,
        rate: MatMut<'_, f64>,
    ) {
        let (d, a, lanes) = (self.d, self.absolute, x.nrows());
        let FrameScratch { inner, cols, .. } = self.scratch(ws);
        cols.resize(lanes * d, 0.0);
        for j in 0..d {
            for l in 0..lanes {
                cols[j * lanes + l] = x[(l, j)];
            }
        }
        for l in 0..lanes {
            cols[a * lanes + l] += self.sign * (x[(l, d)] - self.mean);
        }
        let y = MatRef::from_column_major_slice(cols, lanes, d);
        self.model
            .guards_with_rates_batch(inner, mode, y, f.subcols(0, d), g, rate);
    }

    fn guard_is_linear(&self, mode: usize, k: usize) -> bool {
        self.model.guard_is_linear(mode, k)
    }

    fn admissible(&self, mode: usize, k: usize, x: &[f64]) -> bool {
        let mut buf = [0.0; 32];
        let mut heap = Vec::new();
        let y: &mut [f64] = if self.d <= buf.len() {
            &mut buf[..self.d]
        } else {
            heap.resize(self.d, 0.0);
            &mut heap
        };
        self.to_line(x, y);
        self.model.admissible_on_slope(mode, k, y, x[self.d])
    }

    fn guard_tolerance(&self, mode: usize, k: usize) -> f64 {
        self.model.guard_tolerance(mode, k)
    }

    /// The model's impact in the line's frame, shifted back to the mean slope's frame
    /// (`SlopeWalk::shift`'s expression); the slope component is kept.
    fn reset(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], out: &mut [f64]) -> usize {
        let FrameScratch { inner, y, .. } = self.scratch(ws);
        self.to_line(x, y);
        let next = self.model.reset(inner, mode, k, y, &mut out[..self.d]);
        out[self.absolute] += self.sign * (self.mean - x[self.d]);
        out[self.d] = x[self.d];
        next
    }

    /// The model's gradient in the line's frame; `∂g/∂s = σ ∂g/∂y_a`.
    fn guard_gradient(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], grad: &mut [f64]) {
        let FrameScratch { inner, y, .. } = self.scratch(ws);
        self.to_line(x, y);
        self.model
            .guard_gradient(inner, mode, k, y, &mut grad[..self.d]);
        grad[self.d] = self.sign * grad[self.absolute];
    }
}

pdw_hybrid::integrate_through_dyn!(LineFrame<'_>);

impl Section for LineFrame<'_> {
    fn section_dim(&self) -> usize {
        self.model.section_dim()
    }
    fn section_names(&self) -> &[&'static str] {
        self.model.section_names()
    }
    fn section_mode(&self) -> usize {
        self.model.section_mode()
    }
    fn section_guard(&self) -> (usize, usize) {
        self.model.section_guard()
    }
    /// The model's lift on the mean line.
    fn lift(&self, s: &[f64], x: &mut [f64]) {
        self.model.lift(s, &mut x[..self.d]);
        x[self.d] = self.mean;
    }
    fn project(&self, x: &[f64], s: &mut [f64]) {
        self.model.project(&x[..self.d], s);
    }
    fn max_stride_time(&self) -> f64 {
        self.model.max_stride_time()
    }
}

/// The model of the mean step height as a system of every height (module docs, "Step
/// heights"): state `(x, h)`, `x` the model's state, `h` the height of the walker's next
/// foothold (constant along the flow).
pub struct StepFrame<'a> {
    model: &'a dyn Walker,
    heights: &'a dyn StepHeight,
    /// The model's own (the mean) height `h̄`.
    mean: f64,
    /// Every lane at the model's own height (`σ = 0`): the model's linearity of its guards.
    fixed: bool,
    d: usize,
}

/// The model's scratch and one lane's copies for the lane-by-lane guards.
struct StepScratch {
    inner: Scratch,
    /// One lane's state, flow, guards and rates `(d, d, n_guards, n_guards)`.
    x: Vec<f64>,
    f: Vec<f64>,
    g: Vec<f64>,
    rate: Vec<f64>,
}

impl<'a> StepFrame<'a> {
    /// The system of `model` (the model at the mean height `mean`), whose heights are all its
    /// own when `fixed`; [`LimitError::Model`] when the model has no [`Walker::step_height`].
    pub fn new(model: &'a dyn Walker, mean: f64, fixed: bool) -> Result<Self, LimitError> {
        let heights = model.step_height().ok_or_else(|| LimitError::Model {
            param: mean,
            message: "the model does not walk on random step heights in lockstep".into(),
        })?;
        Ok(Self {
            model,
            heights,
            mean,
            fixed,
            d: model.dim(),
        })
    }

    fn scratch<'s>(&self, ws: &'s mut Scratch) -> &'s mut StepScratch {
        let d = self.d;
        ws.get_or_init(
            || StepScratch {
                inner: Scratch::new(),
                x: vec![0.0; d],
                f: vec![0.0; d],
                g: Vec::new(),
                rate: Vec::new(),
            },
            |s| s.x.len() == d,
        )
    }
}

impl HybridSystem for StepFrame<'_> {
    fn dim(&self) -> usize {
        self.d + 1
    }

    /// The model's: the height component is constant and never enters the step-size control.
    fn error_dim(&self) -> usize {
        self.model.error_dim().clamp(1, self.d)
    }

    fn n_modes(&self) -> usize {
        self.model.n_modes()
    }

    fn guards(&self, mode: usize) -> &[GuardSpec] {
        self.model.guards(mode)
    }

    fn flow(&self, ws: &mut Scratch, mode: usize, x: &[f64], dx: &mut [f64]) {
        flow_with_constants(self.model, &mut self.scratch(ws).inner, mode, x, dx);
    }

    fn flow_batch(&self, ws: &mut Scratch, mode: usize, x: MatRef<'_, f64>, dx: MatMut<'_, f64>) {
        flow_batch_with_constants(self.model, &mut self.scratch(ws).inner, mode, x, dx);
    }

    fn guard(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64]) -> f64 {
        let s = self.scratch(ws);
        self.heights
            .guard_at(&mut s.inner, mode, k, &x[..self.d], x[self.d])
    }

    fn guards_with_rates(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        f: &[f64],
        g: &mut [f64],
        rate: &mut [f64],
    ) {
        let s = self.scratch(ws);
        let d = self.d;
        self.heights
            .guards_with_rates_at(&mut s.inner, mode, &x[..d], &f[..d], g, rate, x[d]);
    }

    /// Lane by lane: each lane's guards at its own height (the expressions of
    /// `guards_with_rates`).
    fn guards_with_rates_batch(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: MatRef<'_, f64>,
        f: MatRef<'_, f64>,
        mut g: MatMut<'_, f64>,
        mut rate: MatMut<'_, f64>,
    ) {
        let (d, ng) = (self.d, g.ncols());
        let StepScratch {
            inner,
            x: xi,
            f: fi,
            g: gi,
            rate: ri,
        } = self.scratch(ws);
        gi.resize(ng, 0.0);
        ri.resize(ng, 0.0);
        for l in 0..x.nrows() {
            for j in 0..d {
                xi[j] = x[(l, j)];
                fi[j] = f[(l, j)];
            }
            self.heights
                .guards_with_rates_at(inner, mode, xi, fi, gi, ri, x[(l, d)]);
            for k in 0..ng {
                g[(l, k)] = gi[k];
                rate[(l, k)] = ri[k];
            }
        }
    }

    /// The model's where every height is its own; else affine only if affine at every height.
    fn guard_is_linear(&self, mode: usize, k: usize) -> bool {
        if self.fixed {
            self.model.guard_is_linear(mode, k)
        } else {
            self.heights.guard_is_linear_at_every_height(mode, k)
        }
    }

    fn admissible(&self, mode: usize, k: usize, x: &[f64]) -> bool {
        self.heights.admissible_at(mode, k, &x[..self.d], x[self.d])
    }

    fn guard_tolerance(&self, mode: usize, k: usize) -> f64 {
        self.model.guard_tolerance(mode, k)
    }

    /// The model's impact at the lane's height; the height component is kept.
    fn reset(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], out: &mut [f64]) -> usize {
        let s = self.scratch(ws);
        let d = self.d;
        let next = self
            .heights
            .reset_at(&mut s.inner, mode, k, &x[..d], &mut out[..d], x[d]);
        out[d] = x[d];
        next
    }

    /// The model's gradient at the lane's height; a guard's change with the height itself is
    /// not a change along the flow (the height is constant), so `∂g/∂h` is left 0.
    fn guard_gradient(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], grad: &mut [f64]) {
        let s = self.scratch(ws);
        let d = self.d;
        self.heights
            .guard_gradient_at(&mut s.inner, mode, k, &x[..d], &mut grad[..d], x[d]);
        grad[d] = 0.0;
    }
}

pdw_hybrid::integrate_through_dyn!(StepFrame<'_>);

impl Section for StepFrame<'_> {
    fn section_dim(&self) -> usize {
        self.model.section_dim()
    }
    fn section_names(&self) -> &[&'static str] {
        self.model.section_names()
    }
    fn section_mode(&self) -> usize {
        self.model.section_mode()
    }
    fn section_guard(&self) -> (usize, usize) {
        self.model.section_guard()
    }
    /// The model's lift at its own (the mean) height.
    fn lift(&self, s: &[f64], x: &mut [f64]) {
        self.model.lift(s, &mut x[..self.d]);
        x[self.d] = self.mean;
    }
    fn project(&self, x: &[f64], s: &mut [f64]) {
        self.model.project(&x[..self.d], s);
    }
    fn max_stride_time(&self) -> f64 {
        self.model.max_stride_time()
    }
}

/// Lane driver of the walk: an item is a walker's index; its lane runs the walker's strides
/// one after another until it falls or completes `max_steps`.
struct WalkDriver<'t> {
    terrain: &'t SlopeTerrain,
    x0: &'t [f64],
    max_steps: usize,
    section_guard: (usize, usize),
    start_mode: usize,
    t_max: f64,
}

/// Per-lane bookkeeping of a walk.
#[derive(Default)]
struct WalkLane {
    /// Reset output `(d + 1)`.
    buf: Vec<f64>,
    /// Heel strikes completed.
    steps: usize,
    /// Intermediate resets in the current stride.
    events: usize,
    /// Time at which the current stride started.
    t0: f64,
    end: Option<StrideOutcome>,
}

impl<'a> LaneDriver<dyn Section + 'a> for WalkDriver<'_> {
    type Item = u64;
    type Output = Fate;
    type Lane = WalkLane;

    fn start(
        &self,
        _sys: &(dyn Section + 'a),
        item: &u64,
        lane: &mut WalkLane,
        x: &mut [f64],
    ) -> (usize, f64) {
        let d = self.x0.len();
        x[..d].copy_from_slice(self.x0);
        x[d] = self.terrain.slope(*item, 1);
        lane.buf.resize(x.len(), 0.0);
        (self.start_mode, self.t_max)
    }

    /// The stride's stops as [`crate::stride::EventDriver`] handles them; at a heel strike the
    /// walker counts it and, below the step limit, starts its next stride on the line of its
    /// next draw, with the stride's own time budget.
    fn on_stop(
        &self,
        sys: &(dyn Section + 'a),
        ws: &mut Scratch,
        item: &u64,
        lane: &mut WalkLane,
        stop: StopReason,
        mode: usize,
        t: f64,
        x: &mut [f64],
    ) -> Control {
        let outcome = match StrideStop::of(stop, sys.guards(mode)) {
            StrideStop::Reset { guard } => {
                let new_mode = sys.reset(ws, mode, guard, x, &mut lane.buf);
                if (mode, guard) == self.section_guard {
                    x.copy_from_slice(&lane.buf);
                    lane.steps += 1;
                    if lane.steps >= self.max_steps {
                        return Control::Finish;
                    }
                    x[x.len() - 1] = self.terrain.slope(*item, lane.steps as u64 + 1);
                    (lane.events, lane.t0) = (0, t);
                    return Control::Continue {
                        mode: self.start_mode,
                        t_end: t + self.t_max,
                    };
                }
                if lane.events >= MAX_EVENTS_PER_STRIDE {
                    StrideOutcome::TooManyEvents
                } else {
                    lane.events += 1;
                    x.copy_from_slice(&lane.buf);
                    return Control::Continue {
                        mode: new_mode,
                        t_end: lane.t0 + self.t_max,
                    };
                }
            }
            StrideStop::End(outcome) => outcome,
        };
        lane.end = Some(outcome);
        Control::Finish
    }

    fn finish(
        &self,
        _sys: &(dyn Section + 'a),
        _item: &u64,
        lane: WalkLane,
        _t: f64,
        _x: &[f64],
    ) -> Fate {
        Fate {
            steps: lane.steps,
            end: lane.end,
        }
    }
}

/// How the lockstep walk is batched: lanes per batch and walkers per claim from the queue
/// (neither changes a result).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lockstep {
    pub lanes: usize,
    pub chunk: usize,
}

impl Lockstep {
    /// [`LANES`] lanes, but no more than each thread's share of the walkers (so that one
    /// batch does not claim them all); chunks of [`CHUNK`] walkers.
    pub fn for_pool(walkers: usize, threads: usize) -> Self {
        Self {
            lanes: LANES.min(walkers.div_ceil(threads.max(1))).max(1),
            chunk: CHUNK,
        }
    }
}

/// `walkers` walkers (0, 1, …) from `x0` (full state just after a heel strike, in the mean
/// slope's frame) on random slopes or step heights, in lockstep (module docs), at most
/// `max_steps` strides each; fates in walker order, identical for any thread count, lane count
/// and chunk size. `progress` gets the number of walkers done. Step heights need the model's
/// [`Walker::step_height`] and a model at both ends of the heights' range (the mean ±
/// [`crate::terrain::TerrainDist::max_abs`] standard deviations); else [`LimitError::Model`].
#[allow(clippy::too_many_arguments)]
pub fn monte_carlo_lockstep(
    walk: &SlopeWalk,
    terrain: &SlopeTerrain,
    x0: &[f64],
    walkers: usize,
    max_steps: usize,
    pool: &rayon::ThreadPool,
    batch: Lockstep,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Vec<Fate>, LimitError> {
    let model = walk.model(walk.mean())?;
    check_walk(walk, terrain, x0, model.as_ref())?;
    if max_steps == 0 {
        return Ok(vec![
            Fate {
                steps: 0,
                end: None
            };
            walkers
        ]);
    }
    let run = |sys: &dyn Section| {
        let driver = WalkDriver {
            terrain,
            x0,
            max_steps,
            section_guard: sys.section_guard(),
            start_mode: sys.section_mode(),
            t_max: sys.max_stride_time(),
        };
        let items: Vec<u64> = (0..walkers as u64).collect();
        let opts = BatchOptions {
            lanes: batch.lanes,
            integrator: walk.options(),
        };
        run_batch_par(sys, &driver, &items, &opts, pool, batch.chunk, progress)
    };
    Ok(match terrain.kind {
        TerrainKind::Slope => run(&LineFrame::new(model.as_ref(), walk.mean())?)?,
        TerrainKind::StepDown => {
            let fixed = terrain.sd == 0.0;
            run(&StepFrame::new(model.as_ref(), walk.mean(), fixed)?)?
        }
    })
}

/// [`LimitError::Model`] unless the walk and the terrain draw the same quantity, the
/// walkers' start state has the model's components and, on step heights, the model exists at
/// both ends of the heights' range ([`check_heights`]).
pub(crate) fn check_walk(
    walk: &SlopeWalk,
    terrain: &SlopeTerrain,
    x0: &[f64],
    model: &dyn Walker,
) -> Result<(), LimitError> {
    if terrain.kind != walk.kind() {
        return Err(LimitError::Model {
            param: terrain.mean,
            message: format!(
                "the terrain draws a {} per step, the walk is on random {}s",
                terrain.kind.param(),
                walk.kind().param()
            ),
        });
    }
    check_start(x0, model.dim(), walk.mean())?;
    if terrain.kind == TerrainKind::StepDown {
        check_heights(walk, terrain)?;
    }
    Ok(())
}

/// [`LimitError::Model`] unless the walkers' start state has the model's `d` components.
fn check_start(x0: &[f64], d: usize, mean: f64) -> Result<(), LimitError> {
    if x0.len() == d {
        return Ok(());
    }
    Err(LimitError::Model {
        param: mean,
        message: format!(
            "the walkers' start state has {} components, the model's state {d}",
            x0.len()
        ),
    })
}

/// The model's error for a height at either end of the range the terrain draws from (the
/// lockstep lanes evaluate the model's guards at any height in it without building the model
/// there).
fn check_heights(walk: &SlopeWalk, terrain: &SlopeTerrain) -> Result<(), LimitError> {
    let reach = terrain.dist.max_abs() * terrain.sd;
    for h in [terrain.mean - reach, terrain.mean + reach] {
        walk.model(h)?;
    }
    Ok(())
}
