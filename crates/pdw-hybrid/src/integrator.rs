//! The scalar integrator: one trajectory, one mode at a time, stopping at guards.
//!
//! Every call of [`Integrator::integrate`] starts afresh from `(t, x)`: it evaluates `f(x)`,
//! chooses the first step (`h_init`, or the HNW II.4 heuristic), and resets the step-size
//! controller. Nothing is carried over from an earlier call except the work counters, so the
//! result of a call is a function of `(sys, mode, t, x, t_end, options)` alone — the property the
//! batched runner relies on to reproduce it bit for bit in any lane. After a reset the caller
//! calls `integrate` again from the event time — or [`Integrator::resume`], which differs only in
//! the first step: the one the controller proposed when the previous call stopped
//! ([`Options::warm_restart`](crate::Options::warm_restart)); guard values within
//! [`HybridSystem::guard_tolerance`] of zero at the start count as zero, so the event just
//! handled is not reported again (see the [`crate::event`] module).

use crate::engine::{self, After, Ctl, LaneScratch, Store};
use crate::event;
use crate::options::{Method, Options, Stats, StopReason};
use crate::tableau::Tableau;
use crate::{HybridError, HybridSystem};

/// Most guards a mode may have for the register loop ([`Integrator::run_registers`]).
const FAST_GUARDS: usize = 8;

/// Callback receiving `(t, x)`.
/// Called at the start, after accepted steps and at the stop; `false` ends the call
/// ([`Integrator::integrate_observed_while`]).
pub(crate) type Observer<'a> = &'a mut dyn FnMut(f64, &[f64]) -> bool;

/// Scalar integrator owning its workspace (sized for `dim` at construction; the guard scratch
/// grows on first use with a system that has more guards, then never allocates again).
pub struct Integrator {
    opts: Options,
    tab: &'static Tableau,
    st: Store,
    sc: LaneScratch,
    ctl: Ctl,
    /// Take the register loop where it applies (see [`Integrator::set_register_loop`]).
    registers: bool,
}

impl Integrator {
    /// Workspace for states of dimension `dim`; rejects invalid options.
    pub fn new(dim: usize, opts: Options) -> Result<Self, HybridError> {
        opts.validate()?;
        if dim == 0 {
            return Err(HybridError::ZeroDimension { dim });
        }
        let tab = engine::tableau_for(&opts);
        Ok(Self {
            opts,
            tab,
            st: Store::new(dim, 1, 0, tab),
            sc: LaneScratch::new(dim, 0),
            ctl: Ctl::default(),
            registers: true,
        })
    }

    /// The options this integrator was built with.
    pub fn options(&self) -> &Options {
        &self.opts
    }

    /// State dimension.
    pub fn dim(&self) -> usize {
        self.st.dim
    }

    /// Counters accumulated since construction (or the last [`reset_stats`](Self::reset_stats)).
    pub fn stats(&self) -> Stats {
        self.ctl.stats
    }

    /// The model scratch this integrator passes to every model call (for the caller's own
    /// model calls between integrations, e.g. resets, so that they allocate nothing either).
    pub fn scratch(&mut self) -> &mut crate::Scratch {
        &mut self.sc.ev.model
    }

    /// Use the register loop for DOPRI5 and DOP853 at dimensions 2, 4 and 6 (the default), or
    /// always the general step loop. Both give the same bits, the same stops and the same
    /// counters; the switch exists so that tests and benchmarks can compare them.
    pub fn set_register_loop(&mut self, on: bool) {
        self.registers = on;
    }

    /// Zero the counters.
    pub fn reset_stats(&mut self) {
        self.ctl.stats = Stats::default();
    }

    /// Check that the system fits this workspace and grow the guard scratch if needed.
    fn fit<S: HybridSystem + ?Sized>(&mut self, sys: &S, mode: usize, x: &[f64]) {
        let d = self.st.dim;
        assert_eq!(
            sys.dim(),
            d,
            "system dimension differs from the integrator's"
        );
        assert_eq!(
            x.len(),
            d,
            "state length differs from the integrator's dimension"
        );
        assert!(mode < sys.n_modes(), "mode {mode} out of range");
        self.st.err_dim = sys.error_dim().clamp(1, d);
        let ng = sys.guards(mode).len();
        if ng > self.st.ng {
            self.st.ng = ng;
            self.st.g = vec![0.0; ng];
            self.st.gr = vec![0.0; ng];
            self.st.g1 = vec![0.0; ng];
            self.st.r1 = vec![0.0; ng];
            self.sc.ev.reserve_guards(ng);
        }
    }

    /// Integrate from `(t, x)` in `mode` until a guard fires or `t` reaches `t_end`. On return
    /// `t` and `x` hold the stop point (for `Guard`: the event point, pre-reset).
    ///
    /// Panics if `x.len()` or `sys.dim()` differs from the integrator's dimension or `mode` is
    /// out of range (programming errors).
    pub fn integrate<S: HybridSystem + ?Sized>(
        &mut self,
        sys: &S,
        mode: usize,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
    ) -> StopReason {
        self.run(sys, mode, t, x, t_end, false, None)
    }

    /// Same, calling `obs(t, x)` at the start, after every accepted step that does not end the
    /// integration, and once at the stop point.
    pub fn integrate_observed<S: HybridSystem + ?Sized>(
        &mut self,
        sys: &S,
        mode: usize,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
        obs: &mut dyn FnMut(f64, &[f64]),
    ) -> StopReason {
        let mut all = |t: f64, x: &[f64]| {
            obs(t, x);
            true
        };
        self.run(sys, mode, t, x, t_end, false, Some(&mut all))
    }

    /// [`integrate_observed`](Self::integrate_observed) with an observer that can end the
    /// call: when `obs` returns `false` (at the start or after an accepted step) the
    /// integration stops at that point with [`StopReason::MaxSteps`] — the observer's budget is
    /// spent (a recorder that is full) — and `obs` is called once more at the stop point.
    #[allow(clippy::too_many_arguments)]
    pub fn integrate_observed_while<S: HybridSystem + ?Sized>(
        &mut self,
        sys: &S,
        mode: usize,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
        obs: &mut dyn FnMut(f64, &[f64]) -> bool,
    ) -> StopReason {
        self.run(sys, mode, t, x, t_end, false, Some(obs))
    }

    /// [`resume`](Self::resume) with the observer of
    /// [`integrate_observed_while`](Self::integrate_observed_while).
    #[allow(clippy::too_many_arguments)]
    pub fn resume_observed_while<S: HybridSystem + ?Sized>(
        &mut self,
        sys: &S,
        mode: usize,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
        obs: &mut dyn FnMut(f64, &[f64]) -> bool,
    ) -> StopReason {
        self.run(sys, mode, t, x, t_end, true, Some(obs))
    }

    /// [`integrate`](Self::integrate) for a segment that continues the trajectory of the
    /// previous call on this integrator (after a reset, or from an `EndTime` stop): with
    /// [`Options::warm_restart`] it starts with the step the controller proposed when that call
    /// stopped instead of the starting-step heuristic — what the batched runner does on
    /// [`Control::Continue`](crate::Control::Continue), with the same bits. The result is then a
    /// function of the previous call's stop as well; everything else starts afresh.
    pub fn resume<S: HybridSystem + ?Sized>(
        &mut self,
        sys: &S,
        mode: usize,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
    ) -> StopReason {
        self.run(sys, mode, t, x, t_end, true, None)
    }

    /// [`resume`](Self::resume) with the observer of
    /// [`integrate_observed`](Self::integrate_observed).
    pub fn resume_observed<S: HybridSystem + ?Sized>(
        &mut self,
        sys: &S,
        mode: usize,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
        obs: &mut dyn FnMut(f64, &[f64]),
    ) -> StopReason {
        let mut all = |t: f64, x: &[f64]| {
            obs(t, x);
            true
        };
        self.run(sys, mode, t, x, t_end, true, Some(&mut all))
    }

    /// The general loop is compiled per instruction set (pdw-simd) with the step kernels
    /// inlined; the register loop once, for the baseline (its vectors are one state, a few
    /// elements wide). Same bits on every path.
    #[allow(clippy::too_many_arguments)]
    #[allow(clippy::too_many_arguments)]
    fn run<S: HybridSystem + ?Sized>(
        &mut self,
        sys: &S,
        mode: usize,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
        resume: bool,
        obs: Option<Observer<'_>>,
    ) -> StopReason {
        sys.integrate_concrete(self, mode, t, x, t_end, resume, obs)
    }

    /// The integration loop compiled once for `dyn HybridSystem` (every flow and guard call
    /// virtual), for systems that implement [`IntegrateConcrete`](crate::IntegrateConcrete)
    /// with [`integrate_through_dyn!`](crate::integrate_through_dyn).
    #[doc(hidden)]
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    pub fn run_dyn(
        &mut self,
        sys: &dyn HybridSystem,
        mode: usize,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
        resume: bool,
        obs: Option<Observer<'_>>,
    ) -> StopReason {
        self.run_concrete(sys, mode, t, x, t_end, resume, obs)
    }

    /// The integration loop itself, compiled for the system's concrete type: reached through
    /// [`IntegrateConcrete`](crate::IntegrateConcrete), so that a system held as a trait object
    /// pays one virtual call per segment and its flow is inlined into the steps.
    #[doc(hidden)]
    #[allow(clippy::too_many_arguments)]
    pub fn run_concrete<S: HybridSystem + ?Sized>(
        &mut self,
        sys: &S,
        mode: usize,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
        resume: bool,
        obs: Option<Observer<'_>>,
    ) -> StopReason {
        let d = self.st.dim;
        let registers = self.registers
            && !matches!(self.opts.method, Method::Rk4 { .. })
            && sys.dim() == d
            && sys.error_dim() == d
            && mode < sys.n_modes()
            && sys.guards(mode).len() <= FAST_GUARDS
            && matches!(d, 2 | 4 | 6); // the dimensions `run_inner` instantiates
        if registers {
            self.run_inner::<S, true>(sys, mode, t, x, t_end, resume, obs)
        } else {
            pdw_simd::dispatch(
                #[inline(always)]
                || self.run_inner::<S, false>(sys, mode, t, x, t_end, resume, obs),
            )
        }
    }

    /// One integration (see [`integrate`](Self::integrate)); `REGISTERS`: take the register
    /// loop (the caller has checked that it applies).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn run_inner<S: HybridSystem + ?Sized, const REGISTERS: bool>(
        &mut self,
        sys: &S,
        mode: usize,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
        resume: bool,
        mut obs: Option<Observer<'_>>,
    ) -> StopReason {
        self.fit(sys, mode, x);
        let d = self.st.dim;
        let opts = self.opts;
        let method = opts.method;
        let tab = self.tab;
        self.st.x.copy_from_slice(x);
        let stop = 'outer: {
            if let Some(r) = engine::start_segment(
                sys,
                &opts,
                tab,
                &mut self.st,
                0,
                &mut self.ctl,
                mode,
                *t,
                t_end,
                resume,
                &mut self.sc,
            ) {
                break 'outer r;
            }
            if let Some(o) = obs.as_mut() {
                if !o(self.ctl.t, &self.st.x) {
                    break 'outer StopReason::MaxSteps;
                }
            }
            if REGISTERS {
                // The shipped point-mass and two- and three-link models (rimless wheel, simplest
                // walker, compass, kneed): each dimension is a copy of the loop per model type.
                match d {
                    2 => break 'outer self.run_registers::<S, 2>(sys, mode, &mut obs),
                    4 => break 'outer self.run_registers::<S, 4>(sys, mode, &mut obs),
                    6 => break 'outer self.run_registers::<S, 6>(sys, mode, &mut obs),
                    _ => {}
                }
            }
            loop {
                match engine::prepare(&opts, &mut self.ctl) {
                    Ok(h) => self.st.h[0] = h,
                    Err(r) => break 'outer r,
                }
                self.attempt(sys, mode);
                match engine::after_attempt::<S, false>(
                    sys,
                    method,
                    tab,
                    &opts,
                    &mut self.st,
                    0,
                    &mut self.ctl,
                    &mut self.sc,
                ) {
                    After::Rejected => {}
                    After::Accepted => {
                        if let Some(o) = obs.as_mut() {
                            if !o(self.ctl.t, &self.st.x) {
                                break 'outer StopReason::MaxSteps;
                            }
                        }
                    }
                    After::Stop(r) => break 'outer r,
                }
            }
        };
        *t = self.ctl.t;
        x.copy_from_slice(&self.st.x[..d]);
        if let Some(o) = obs.as_mut() {
            o(*t, x);
        }
        stop
    }

    /// The step loop of [`run_inner`](Self::run_inner) for DOPRI5 and DOP853 at a compile-time
    /// dimension `D` (error control on every component, at most [`FAST_GUARDS`] guards), with
    /// the accepted state, the stages and the guard values in local arrays (registers) instead
    /// of the workspace, and the method's stage rows unrolled. Every value is computed by the
    /// functions the general loop uses (`row_fixed`, `error_norm_fixed`, `decide`,
    /// `may_cross`), on the same operands in the same order, so the two loops give the same
    /// bits. A step that may hold an event, or ends the segment, is written to the
    /// workspace and finished by the general code (`after_accept`), after which the loop reloads
    /// the committed state. Returns the stop reason with the stop state in `st.x`.
    #[inline(always)]
    fn run_registers<S: HybridSystem + ?Sized, const D: usize>(
        &mut self,
        sys: &S,
        mode: usize,
        obs: &mut Option<Observer<'_>>,
    ) -> StopReason {
        let Self {
            opts,
            tab,
            st,
            sc,
            ctl,
            ..
        } = self;
        let (opts, tab) = (*opts, *tab);
        let method = opts.method;
        let ns = tab.n_stages;
        let last = ns - 1;
        let ng = sys.guards(mode).len();
        let mut x: [f64; D] = st.x[..D].try_into().expect("D values");
        let mut k = [[0.0f64; D]; 13];
        k[0].copy_from_slice(&st.k[..D]);
        let (mut g, mut gr) = ([0.0f64; FAST_GUARDS], [0.0f64; FAST_GUARDS]);
        g[..ng].copy_from_slice(&st.g[..ng]);
        gr[..ng].copy_from_slice(&st.gr[..ng]);
        let (mut g1, mut r1) = ([0.0f64; FAST_GUARDS], [0.0f64; FAST_GUARDS]);
        loop {
            let h = match engine::prepare(&opts, ctl) {
                Ok(h) => h,
                Err(r) => {
                    st.x[..D].copy_from_slice(&x);
                    return r;
                }
            };
            let x1 = stages_fixed::<S, D>(sys, &mut sc.ev.model, mode, method, &x, h, &mut k);
            let (err, q) =
                engine::error_norm_fixed::<D>(&x, &x1, k.as_flattened(), h, method, tab, &opts);
            let mut cand = 0u8;
            if ng > 0 {
                sys.guards_with_rates(
                    &mut sc.ev.model,
                    mode,
                    &x1,
                    &k[last],
                    &mut g1[..ng],
                    &mut r1[..ng],
                );
                let specs = sys.guards(mode);
                for i in 0..ng {
                    if event::may_cross(g[i], g1[i], gr[i], r1[i], h)
                        && !event::clears_direction(specs[i].crossing, g[i], g1[i], gr[i], r1[i], h)
                    {
                        cand |= event::guard_bit(i);
                    }
                }
            }
            ctl.stats.rhs_evals += (ns - 1) as u64;
            match engine::decide(method, tab, &opts, ctl, err, q) {
                After::Rejected => continue,
                After::Stop(r) => {
                    st.x[..D].copy_from_slice(&x);
                    return r;
                }
                After::Accepted => {}
            }
            if cand == 0 && !ctl.last {
                // No guard can cross inside the step: commit x₀ ← x₁, f(x₀) ← f(x₁) and the
                // guard values at x₁ (what `after_accept` and `event::locate` do here).
                x = x1;
                k[0] = k[last];
                g = g1;
                gr = r1;
                ctl.t += h;
                ctl.h_full = h;
                if let Some(o) = obs.as_mut() {
                    if !o(ctl.t, &x) {
                        st.x[..D].copy_from_slice(&x);
                        return StopReason::MaxSteps;
                    }
                }
                continue;
            }
            st.x[..D].copy_from_slice(&x);
            st.xn[..D].copy_from_slice(&x1);
            st.k[..ns * D].copy_from_slice(k[..ns].as_flattened());
            st.g[..ng].copy_from_slice(&g[..ng]);
            st.gr[..ng].copy_from_slice(&gr[..ng]);
            st.g1[..ng].copy_from_slice(&g1[..ng]);
            st.r1[..ng].copy_from_slice(&r1[..ng]);
            st.cand[0] = cand;
            st.h[0] = h;
            match engine::after_accept(sys, method, tab, st, 0, ctl, sc) {
                After::Accepted => {
                    x.copy_from_slice(&st.x[..D]);
                    k[0].copy_from_slice(&st.k[..D]);
                    g[..ng].copy_from_slice(&st.g[..ng]);
                    gr[..ng].copy_from_slice(&st.gr[..ng]);
                    if let Some(o) = obs.as_mut() {
                        if !o(ctl.t, &x) {
                            return StopReason::MaxSteps;
                        }
                    }
                }
                After::Stop(r) => return r,
                After::Rejected => unreachable!("after_accept accepts or stops"),
            }
        }
    }

    /// Stages and error norm of one attempt (one lane, stride 1: blocks are contiguous vectors).
    #[inline(always)]
    fn attempt<S: HybridSystem + ?Sized>(&mut self, sys: &S, mode: usize) {
        let tab = self.tab;
        let d = self.st.dim;
        for q in 1..tab.n_stages {
            engine::stage_input(&mut self.st, tab, 1, q);
            let input = if q + 1 == tab.n_stages {
                &self.st.xn
            } else {
                &self.st.y
            };
            sys.flow(
                &mut self.sc.ev.model,
                mode,
                &input[..d],
                &mut self.st.k[q * d..(q + 1) * d],
            );
        }
        engine::error_norm(&mut self.st, self.opts.method, tab, &self.opts, 1);
        // Guard values and rates at x₁ (the batch does this column-wise), then the test of
        // `engine::mark_near`: may a guard cross inside the step?
        let specs = sys.guards(mode);
        let ng = specs.len();
        if ng > 0 {
            let last = tab.n_stages - 1;
            let st = &mut self.st;
            sys.guards_with_rates(
                &mut self.sc.ev.model,
                mode,
                &st.xn[..d],
                &st.k[last * d..(last + 1) * d],
                &mut st.g1[..ng],
                &mut st.r1[..ng],
            );
            engine::mark_near(st, specs, 0, 1);
        }
    }
}

impl Method {
    /// Order of the method's solution (4, 5, 8).
    pub fn order(&self) -> u32 {
        match self {
            Method::Rk4 { .. } => 4,
            Method::Dopri5 => 5,
            Method::Dop853 => 8,
        }
    }
}

/// The stages of one DOPRI5 or DOP853 attempt from `x` with step `h` at a compile-time dimension
/// `D`: `k[q] = f(x + h·Σ_p a_{qp} k_p)` for q = 1 … s − 1 (`k[0] = f(x)` given), the last
/// stage's input (row b) returned as x₁. The rows are the tableau's constant rows, summed by
/// [`engine::row_fixed`] as in the general loop.
#[inline(always)]
fn stages_fixed<S: HybridSystem + ?Sized, const D: usize>(
    sys: &S,
    ws: &mut crate::Scratch,
    mode: usize,
    method: Method,
    x: &[f64; D],
    h: f64,
    k: &mut [[f64; D]; 13],
) -> [f64; D] {
    use crate::tableau::*;
    macro_rules! stage {
        ($q:expr, $w:expr) => {{
            let y = engine::row_fixed::<D, _>(x, h, k.as_flattened(), &$w);
            sys.flow(ws, mode, &y, &mut k[$q]);
            y
        }};
    }
    match method {
        Method::Dopri5 => {
            stage!(1, DP5_A1);
            stage!(2, DP5_A2);
            stage!(3, DP5_A3);
            stage!(4, DP5_A4);
            stage!(5, DP5_A5);
            stage!(6, DP5_A6)
        }
        Method::Dop853 => {
            stage!(1, DOP_A1);
            stage!(2, DOP_A2);
            stage!(3, DOP_A3);
            stage!(4, DOP_A4);
            stage!(5, DOP_A5);
            stage!(6, DOP_A6);
            stage!(7, DOP_A7);
            stage!(8, DOP_A8);
            stage!(9, DOP_A9);
            stage!(10, DOP_A10);
            stage!(11, DOP_A11);
            stage!(12, DOP_A12)
        }
        Method::Rk4 { .. } => unreachable!("the register loop runs DOPRI5 and DOP853"),
    }
}
