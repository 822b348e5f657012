//! Continuation of the period-one gait in one parameter over an output grid of N values, as
//! both front ends run it (the CLI's `fixedpoint --sweep NAME=A:B:N`, Python's
//! `continuation`): the plan ([`SweepPlan`]) names the model, the swept parameter's grid, the
//! gait to start from and the integrator; the steps are
//!
//! 1. [`find_start`]: the gait to start from — at the plan's [`SweepPlan::from`] if given,
//!    else at A (Newton from the guesses there, [`start_gait`]; failing that a scan of the
//!    section, [`pdw_limit::scan`]) and, when A has no gait, at the grid values inward from A
//!    (the middle, then the quarter points);
//! 2. [`continuation`]: [`pdw_limit::sweep::sweep`] — pseudo-arclength continuation (both
//!    ways from a start inside the range) with period-doubling, fold and Neimark–Sacker
//!    detection, the cascade followed down to [`SweepPlan::max_period`] (on each period-k
//!    branch the switch onto the period-2k branch at its first period doubling), every branch
//!    corrected and measured on the grid;
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
    /// The value of the swept parameter to find the start gait at (within A..B); `None`: A,
    /// or inward from A when A has no gait ([`find_start`]).
    pub from: Option<f64>,
    /// The longest period followed down the period-doubling cascade (a power of two, 1 to 64;
    /// 2: the period-2 branch only).
    pub max_period: usize,
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

    /// The sweep's range, from the gait at `from`, down the cascade to the plan's period.
    pub fn spec(&self, from: f64) -> pdw_limit::SweepSpec {
        pdw_limit::SweepSpec {
            from,
            max_period: self.max_period,
            ..pdw_limit::SweepSpec::new(self.grid.lo, self.grid.hi, self.grid.n)
        }
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

/// Newton from `guesses` on `m0` (the model at a value of the swept parameter) and the section state of the gait of
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

/// Starts of the section scan that looks for a start gait where the guesses find none.
pub const START_SCAN_STARTS: usize = 64;

/// Newton iterations per start of that scan: a start far from every gait gives up early
/// instead of spending long variational strides (the scan's default allows 40).
pub const START_SCAN_NEWTON_ITERS: u64 = 12;

/// The gait a sweep starts from.
#[derive(Clone, Debug)]
pub struct StartGait {
    /// Its section state.
    pub section: Vec<f64>,
    /// The value of the swept parameter it is at.
    pub param: f64,
    /// How it was found: `the guesses` or `a scan of the section (64 starts)`.
    pub how: String,
}

/// No start gait anywhere tried: the values tried in order and the failed guesses at the
/// first of them.
#[derive(Clone, Debug)]
pub struct NoStart {
    pub tried: Vec<f64>,
    pub failed: Vec<Failed>,
}

/// The values at which [`find_start`] looks for a gait: the plan's `from`, else A and then the
/// grid values nearest the middle and the quarter points of the range (each once).
pub fn start_values(plan: &SweepPlan) -> Vec<f64> {
    if let Some(mu) = plan.from {
        return vec![mu];
    }
    let g = &plan.grid;
    let params = pdw_limit::linspace(g.lo, g.hi, g.n);
    let last = g.n - 1;
    let mut idx = vec![0, last / 2, last / 4, (3 * last) / 4];
    idx.dedup();
    let mut out: Vec<f64> = Vec::new();
    for i in idx {
        if !out.contains(&params[i]) {
            out.push(params[i]);
        }
    }
    out
}

/// Step 1: the start gait (see the module docs): at each of [`start_values`] in turn, Newton
/// from the guesses (`user`'s section state, else the model's own at that value), then a scan
/// of the model's section box ([`START_SCAN_STARTS`] starts, Newton capped at
/// [`START_SCAN_NEWTON_ITERS`] iterations); the first gait of the plan's choice found wins.
pub fn find_start(
    plan: &SweepPlan,
    user: Option<&[f64]>,
    pool: &rayon::ThreadPool,
) -> Result<Result<StartGait, NoStart>, LimitError> {
    let tried = start_values(plan);
    let mut failed_first = None;
    for &mu in &tried {
        let m = plan.model_at(mu).map_err(|e| LimitError::Model {
            param: mu,
            message: e.to_string(),
        })?;
        let guesses = match user {
            Some(g) => vec![("guess".to_string(), g.to_vec())],
            None => crate::gaits::model_guesses(m.walker.as_ref()),
        };
        let (found, failed) = start_gait(plan, &m, &guesses)?;
        failed_first.get_or_insert(failed);
        if let Some(section) = found {
            let how = "the guesses".to_string();
            return Ok(Ok(StartGait {
                section,
                param: mu,
                how,
            }));
        }
        if let Some(section) = scan_start(plan, &m, pool)? {
            let how = format!("a scan of the section ({START_SCAN_STARTS} starts)");
            return Ok(Ok(StartGait {
                section,
                param: mu,
                how,
            }));
        }
    }
    let failed = failed_first.unwrap_or_default();
    Ok(Err(NoStart { tried, failed }))
}

/// A gait of the plan's choice from a modest scan of `m`'s section box, if it has one.
fn scan_start(
    plan: &SweepPlan,
    m: &BuiltModel,
    pool: &rayon::ThreadPool,
) -> Result<Option<Vec<f64>>, LimitError> {
    let Some((lo, hi)) = m.walker.section_box() else {
        return Ok(None);
    };
    let opts = pdw_limit::scan::ScanOptions {
        integrator: plan.fixed_point_integrator(),
        newton_max_iters: START_SCAN_NEWTON_ITERS,
        ..pdw_limit::scan::ScanOptions::new(START_SCAN_STARTS, plan.newton_tol())
    };
    let b = pdw_limit::scan::ScanBox { lo, hi };
    let sc = pdw_limit::scan::scan(m.walker.as_ref(), &b, &opts, pool)?;
    let gait = match plan.start {
        StartChoice::Unstable => sc.gaits.iter().find(|g| !g.fp.stable),
        StartChoice::Stable => sc
            .gaits
            .iter()
            .find(|g| g.fp.stable)
            .or_else(|| sc.gaits.first()),
    };
    Ok(gait.map(|g| g.fp.section.clone()))
}

/// Step 2: the branches from section state `start` at `from` (a value in A..B, usually the
/// [`StartGait::param`] of [`find_start`]), on the grid, on `pool`.
pub fn continuation<P: Progress>(
    plan: &SweepPlan,
    start: &[f64],
    from: f64,
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
        &plan.spec(from),
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
