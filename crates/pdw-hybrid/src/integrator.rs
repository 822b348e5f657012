//! The scalar integrator: one trajectory, one mode at a time, stopping at guards.
//!
//! Every call of [`Integrator::integrate`] starts afresh from `(t, x)`: it evaluates `f(x)`,
//! chooses the first step (`h_init`, or the HNW II.4 heuristic), and resets the step-size
//! controller. Nothing is carried over from an earlier call except the work counters, so the
//! result of a call is a function of `(sys, mode, t, x, t_end, options)` alone — the property the
//! batched runner relies on to reproduce it bit for bit in any lane. After a reset the caller
//! calls `integrate` again from the event time; guard values within
//! [`HybridSystem::guard_tolerance`] of zero at the start count as zero, so the event just
//! handled is not reported again (see the [`event`](crate::event) module).

use crate::engine::{self, After, Ctl, LaneScratch, Store};
use crate::options::{Method, Options, Stats, StopReason};
use crate::tableau::Tableau;
use crate::{HybridError, HybridSystem};

/// Callback receiving `(t, x)`.
type Observer<'a> = &'a mut dyn FnMut(f64, &[f64]);

/// Scalar integrator owning its workspace (sized for `dim` at construction; the guard scratch
/// grows on first use with a system that has more guards, then never allocates again).
pub struct Integrator {
    opts: Options,
    tab: &'static Tableau,
    st: Store,
    sc: LaneScratch,
    ctl: Ctl,
}

impl Integrator {
    /// Workspace for states of dimension `dim`; rejects invalid options.
    pub fn new(dim: usize, opts: Options) -> Result<Self, HybridError> {
        opts.validate()?;
        if dim == 0 {
            return Err(HybridError::ZeroDimension { dim });
        }
        let tab = engine::tableau_of(opts.method);
        Ok(Self {
            opts,
            tab,
            st: Store::new(dim, 1, 0, tab),
            sc: LaneScratch::new(dim, 0),
            ctl: Ctl::default(),
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
            self.sc.ev.gv = vec![0.0; ng * (crate::event::N_SAMPLES + 2)];
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
        self.run(sys, mode, t, x, t_end, None)
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
        self.run(sys, mode, t, x, t_end, Some(obs))
    }

    /// Compiled per instruction set (pdw-simd) with the step kernels inlined; same bits on
    /// every path.
    fn run<S: HybridSystem + ?Sized>(
        &mut self,
        sys: &S,
        mode: usize,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
        obs: Option<Observer<'_>>,
    ) -> StopReason {
        pdw_simd::dispatch(
            #[inline(always)]
            || self.run_inner(sys, mode, t, x, t_end, obs),
        )
    }

    #[inline(always)]
    fn run_inner<S: HybridSystem + ?Sized>(
        &mut self,
        sys: &S,
        mode: usize,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
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
                &mut self.sc,
            ) {
                break 'outer r;
            }
            if let Some(o) = obs.as_mut() {
                o(self.ctl.t, &self.st.x);
            }
            loop {
                match engine::prepare(&opts, &mut self.ctl) {
                    Ok(h) => self.st.h[0] = h,
                    Err(r) => break 'outer r,
                }
                self.attempt(sys, mode);
                match engine::after_attempt(
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
                            o(self.ctl.t, &self.st.x);
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
