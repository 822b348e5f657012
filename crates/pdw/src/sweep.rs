//! Continuation of the period-one gait in one parameter over an output grid of N values, as
//! both front ends run it (the CLI's `fixedpoint --sweep NAME=A:B:N`, Python's
//! `continuation`): the plan ([`SweepPlan`]) names the model, the swept parameter's grid, the
//! gait to start from and the integrator; the steps are
//!
//! 1. [`start_gait`]: the gait at A (Newton from the guesses there);
//! 2. [`continuation`]: [`pdw_limit::sweep::sweep`] — pseudo-arclength continuation with
//!    period-doubling, fold and Neimark–Sacker detection, the switch onto the period-2 branch
//!    at the first period doubling, every branch corrected and measured on the grid;
//! 3. [`orbit_diagram`] (the CLI's): the stride map iterated at each grid value from the
//!    continued gait.

use crate::gaits::Failed;
use crate::input::{InputError, Sweep};
use crate::model::{build, BuiltModel};
use pdw_hybrid::Options;
use pdw_limit::sweep::{Silent, SweepProgress};
use pdw_limit::{ContinuationOptions, LimitError, OrbitColumn, OrbitOptions, OrbitStart};

/// The gait a sweep starts from when several are found at A.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StartChoice {
    /// The first unstable gait found.
    Unstable,
    /// The first stable gait, else the first found.
    Stable,
}

/// A checked sweep.
pub struct SweepPlan {
    /// Model name or spec file.
    pub model: String,
    /// Overrides of the other parameters (the swept one is set on top, value by value).
    pub fixed: Vec<(String, f64)>,
    /// The swept parameter and its N values A..B.
    pub grid: Sweep,
    pub start: StartChoice,
    /// Residual tolerance of the gait search at A (at least 1e-12 is used).
    pub tol: f64,
    /// One integrator for every stride of the sweep (gait search, continuation, orbit
    /// diagram); `None`: each stage's default.
    pub integrator: Option<Options>,
}

impl SweepPlan {
    /// The model at swept value `mu`.
    pub fn model_at(&self, mu: f64) -> Result<BuiltModel, InputError> {
        let mut ov = self.fixed.clone();
        ov.push((self.grid.name.clone(), mu));
        build(&self.model, &ov)
    }

    /// The model at A, once both ends of the range are known to make models.
    pub fn start_model(&self) -> Result<BuiltModel, InputError> {
        let m0 = self.model_at(self.grid.lo)?;
        self.model_at(self.grid.hi)?;
        Ok(m0)
    }

    /// Newton tolerance of the gait search.
    pub fn newton_tol(&self) -> f64 {
        self.tol.max(1e-12)
    }

    /// Integrator of the gait search: the plan's, else the search's default at its tolerance.
    pub fn fixed_point_integrator(&self) -> Options {
        self.integrator
            .unwrap_or_else(|| pdw_limit::gaits::default_integrator(self.newton_tol()))
    }

    /// The continuation's options: steps of at most one grid spacing
    /// ([`pdw_limit::grid_options`]), with the plan's integrator.
    pub fn continuation_options(&self) -> ContinuationOptions {
        let mut opts = pdw_limit::grid_options(self.grid.lo, self.grid.hi, self.grid.n);
        if let Some(i) = self.integrator {
            opts.integrator = i;
        }
        opts
    }

    /// The orbit diagram's options: 300 transient strides, 64 recorded, the plan's integrator.
    pub fn orbit_options(&self) -> OrbitOptions {
        let mut oo = OrbitOptions {
            transient: 300,
            record: 64,
            ..OrbitOptions::default()
        };
        if let Some(i) = self.integrator {
            oo.integrator = i;
        }
        oo
    }
}

/// Progress of a sweep: its stages ([`SweepProgress`]) and every model built during the
/// continuation, at the parameter value reached.
pub trait Progress: SweepProgress {
    fn at(&self, _mu: f64) {}
}

impl Progress for Silent {}

/// Step 1: Newton from `guesses` on `m0` (the model at A) and the section state of the gait of
/// the plan's choice, with the failed guesses.
pub fn start_gait(
    plan: &SweepPlan,
    m0: &BuiltModel,
    guesses: &[(String, Vec<f64>)],
) -> Result<(Option<Vec<f64>>, Vec<Failed>), LimitError> {
    let (found, failed) = crate::gaits::search_with(
        m0,
        guesses,
        plan.newton_tol(),
        &plan.fixed_point_integrator(),
    )?;
    let start = match plan.start {
        StartChoice::Unstable => found.iter().find(|f| !f.fp.stable),
        StartChoice::Stable => found.iter().find(|f| f.fp.stable).or_else(|| found.first()),
    };
    Ok((start.map(|f| f.fp.section.clone()), failed))
}

/// Step 2: the branches from section state `start` at A, on the grid, on `pool`.
pub fn continuation<P: Progress>(
    plan: &SweepPlan,
    start: &[f64],
    pool: &rayon::ThreadPool,
    progress: &P,
) -> Result<pdw_limit::Sweep, LimitError> {
    let family = |mu: f64| {
        progress.at(mu);
        plan.model_at(mu).map(|m| m.walker)
    };
    let g = &plan.grid;
    pdw_limit::sweep::sweep(
        &family,
        &g.name,
        start,
        (g.lo, g.hi, g.n),
        &plan.continuation_options(),
        pool,
        progress,
    )
}

/// Step 3: the orbit diagram over the grid values of `sweep`. Each value starts from the
/// continued period-one gait at the nearest parameter (`fallback` without one), nudged by 1e-6
/// in its first coordinate so that an unstable gait is left for whatever attracts beyond it.
pub fn orbit_diagram<P: Progress>(
    plan: &SweepPlan,
    sweep: &pdw_limit::Sweep,
    fallback: &[f64],
    pool: &rayon::ThreadPool,
    progress: &P,
) -> Result<Vec<OrbitColumn>, LimitError> {
    let main = &sweep.continued[0].1;
    let starts: Vec<Vec<f64>> = sweep
        .params
        .iter()
        .map(|&mu| {
            let mut v = main
                .points
                .iter()
                .min_by(|p, q| (p.param - mu).abs().total_cmp(&(q.param - mu).abs()))
                .map(|p| p.section.clone())
                .unwrap_or_else(|| fallback.to_vec());
            v[0] += 1e-6;
            v
        })
        .collect();
    progress.stage("orbit diagram", sweep.params.len() as u64, None);
    let counted = |mu: f64| {
        progress.inc();
        plan.model_at(mu).map(|m| m.walker)
    };
    pdw_limit::orbit_diagram(
        &counted,
        &sweep.params,
        &OrbitStart::PerParam(starts),
        &plan.orbit_options(),
        pool,
    )
}
