//! Two-parameter continuation of a codimension-one bifurcation of the period-one gait: the curve
//! of period doublings (a multiplier at −1) or folds (a multiplier at +1) in a plane of two model
//! parameters, one stepped (`p_step`), one free (`p_free`).
//!
//! # The minimally augmented system
//! At each value of `p_step` the unknowns are `y = (x, p_free)` (the section state and the free
//! parameter, `n + 1` numbers) and the equations are
//!
//! ```text
//! P(x; p) − x = 0        (n equations: x is a fixed point of the stride map)
//! g(x; p)     = 0        (1 equation: A = DP(x; p) − λ_c I is singular)
//! ```
//!
//! with `λ_c = −1` for a period doubling (`A = DP + I`) and `λ_c = +1` for a fold
//! (`A = DP − I`). The scalar test function `g` is the last component of the solution of the
//! bordered system (Govaerts, "Numerical Methods for Bifurcations of Dynamical Equilibria",
//! SIAM 2000, §4.4; Kuznetsov, "Elements of Applied Bifurcation Theory", 3rd ed., §10.2.2):
//!
//! ```text
//! [ A   b ] [ v ]   [ 0 ]            [ Aᵀ  c ] [ w ]   [ 0 ]
//! [ cᵀ  0 ] [ g ] = [ 1 ]    and     [ bᵀ  0 ] [ g ] = [ 1 ]
//! ```
//!
//! By Cramer's rule `g = det A / det M`, so `g = 0` exactly where `A` is singular, and the
//! bordered matrix `M` stays regular there as long as the borders `b`, `c` are not orthogonal to
//! the left and right null vectors of `A`. The borders are the unit left and right null vectors
//! `w`, `v` of the previous accepted point (at the start: the eigenvectors of `DP` and `DPᵀ` for
//! `λ_c` at the one-parameter detection, by inverse iteration), which keeps `M` as well
//! conditioned as possible along the curve.
//!
//! # Jacobian
//! `DP(x)` is exact (variational equations with saltation matrices, [`dp_variational`]). The
//! column `∂P/∂p_free` and the row `∇g` are central differences with the step
//! `h_j = dtest_rel · max(|y_j|, 1)` (one variational stride at `y ± h_j e_j` gives both `P` and
//! `g` there): `2(n + 1) + 1` variational strides per Newton iteration. The formula
//! `g_z = −wᵀ A_z v` would need second derivatives of the stride map, which the project does
//! not compute. Measured accuracy (test `gradient_of_the_test_function_is_accurate`): against
//! the Richardson extrapolation of steps 1e-4 / 5e-5, the default step 1e-5 is accurate to
//! 5e-7 relative at the compass gait's period doubling. Newton only needs a few digits of the
//! Jacobian (3-6 iterations per point measured); the accuracy of the solution is set by the
//! residual `F` alone.
//!
//! # Corrector and stepping
//! Newton on `F(y) = [P(x) − x; g] = 0` runs through argmin with the project's damped Newton
//! solver ([`Newton`]: LU, backtracking on ‖F‖₂; a trial whose stride falls or whose free
//! parameter leaves `[free_min, free_max]` counts as a failed trial). An accepted point is
//! re-checked independently: a fresh stride (plain, not variational: the two integrations differ
//! at the integrator's tolerance) gives `‖P(x) − x‖∞ ≤ 10 · tol · min(1, ‖y‖∞)` and the
//! real multiplier nearest `λ_c` lies within `critical_tol` of it.
//!
//! Natural-parameter continuation in `p_step` over the caller's values: the predictor is the
//! secant through the last two accepted points (the first step uses the start point itself). A
//! failed step is halved (the intermediate points are solved but not reported) down to
//! `min_step_fraction` of the nominal spacing; then the curve ends with a typed reason
//! ([`CurveEnd::Lost`] with a [`LostReason`]: the gait falls, the free parameter leaves its
//! domain, Newton does not converge, the point found is not critical, …). Nothing panics and
//! no NaN is reported.
//!
//! # Regions
//! [`region_map`] classifies a coarse grid of the parameter plane by what the period-one gait
//! does there (stable period one, or what the stride map reaches from the nudged unstable gait:
//! period two, period ≥ 3, no detected period, fall), for the two-parameter bifurcation diagram.

use crate::continuation::{real_eigenvector, Bifurcation};
use crate::error::LimitError;
use crate::family::{Built, ModelFamily, ModelFamily2};
use crate::floquet::{multipliers, Multiplier};
use crate::jacobian::dp_variational;
use crate::newton::{find_fixed_point, residual_scale, Newton, NewtonOptions, NewtonState};
use crate::orbit::{OrbitOptions, OrbitStart};
use crate::stride::{StrideMap, StrideOutcome};
use argmin::core::{Error as ArgminError, Executor, Jacobian, Operator, State, TerminationReason};
use faer::prelude::*;
use faer::Mat;
use pdw_hybrid::{Options, Section};
use std::cell::RefCell;
use std::fmt::{self, Display};

/// The bifurcation followed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Codim2Kind {
    /// A real multiplier at −1 (`A = DP + I`).
    PeriodDoubling,
    /// A real multiplier at +1 (`A = DP − I`).
    Fold,
}

impl Codim2Kind {
    /// The critical multiplier `λ_c`.
    pub fn critical(self) -> f64 {
        match self {
            Codim2Kind::PeriodDoubling => -1.0,
            Codim2Kind::Fold => 1.0,
        }
    }

    /// Short name: `pd`, `fold`.
    pub fn name(self) -> &'static str {
        match self {
            Codim2Kind::PeriodDoubling => "pd",
            Codim2Kind::Fold => "fold",
        }
    }
}

/// Options of [`follow_curve`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Codim2Options {
    /// Integrator of every stride.
    pub integrator: Options,
    /// Newton tolerance on `‖[P(x) − x; g]‖∞` (relative to `min(1, ‖y‖∞)`, as in
    /// [`find_fixed_point`]).
    pub newton_tol: f64,
    /// Newton iterations per point.
    pub max_newton: u64,
    /// Step halvings of the Newton line search.
    pub max_backtracks: usize,
    /// Relative step of the central differences of `P` in `p_free` and of `g`.
    pub dtest_rel: f64,
    /// Domain of the free parameter; a point outside ends the curve.
    pub free_min: f64,
    pub free_max: f64,
    /// Smallest step in `p_step`, as a fraction of the spacing of the requested values.
    pub min_step_fraction: f64,
    /// Largest `|λ − λ_c|` of the nearest real multiplier at an accepted point.
    pub critical_tol: f64,
}

impl Codim2Options {
    /// Defaults for the free-parameter domain `[free_min, free_max]`: DOP853 at 1e-13, Newton to
    /// 1e-11 in ≤ 12 iterations, difference step 1e-5, steps down to 1/256 of the spacing,
    /// critical multiplier within 1e-6.
    pub fn new(free_min: f64, free_max: f64) -> Self {
        Self {
            integrator: Options::dop853(1e-13),
            newton_tol: 1e-11,
            max_newton: 12,
            max_backtracks: 12,
            dtest_rel: 1e-5,
            free_min,
            free_max,
            min_step_fraction: 1.0 / 256.0,
            critical_tol: 1e-6,
        }
    }

    fn validate(&self) -> Result<(), LimitError> {
        self.integrator.validate()?;
        let bad = |name, value: f64, allowed| {
            Err(LimitError::InvalidOption {
                name,
                value,
                allowed,
            })
        };
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !pos(self.newton_tol) {
            return bad("newton_tol", self.newton_tol, "must be finite and > 0");
        }
        if self.max_newton < 1 {
            return bad("max_newton", 0.0, "must be >= 1");
        }
        if !pos(self.dtest_rel) {
            return bad("dtest_rel", self.dtest_rel, "must be finite and > 0");
        }
        if !(self.free_min.is_finite()
            && self.free_max.is_finite()
            && self.free_min < self.free_max)
        {
            return bad("free_min", self.free_min, "need finite free_min < free_max");
        }
        if !(pos(self.min_step_fraction) && self.min_step_fraction <= 1.0) {
            return bad(
                "min_step_fraction",
                self.min_step_fraction,
                "must be in (0, 1]",
            );
        }
        if !pos(self.critical_tol) {
            return bad("critical_tol", self.critical_tol, "must be finite and > 0");
        }
        Ok(())
    }
}

/// Why the curve could not be continued to the next value of `p_step`.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LostReason {
    /// A stride did not reach the next heel strike: the gait falls (or times out) there.
    #[error("the gait does not complete a stride at free parameter {p_free}: {outcome}")]
    Fall { outcome: StrideOutcome, p_free: f64 },
    /// Newton drove the free parameter out of its domain.
    #[error("the free parameter left its domain [{min}, {max}] (Newton asked for {value})")]
    FreeOutOfDomain { value: f64, min: f64, max: f64 },
    /// The model family could not build the model.
    #[error("the model cannot be built there: {message}")]
    Model { message: String },
    /// Newton did not reach the tolerance.
    #[error("Newton did not converge: {reason} (last ‖F‖∞ = {residual:.3e})")]
    NoConvergence { reason: String, residual: f64 },
    /// The converged point has no real multiplier at `λ_c` (within `critical_tol`), or fails
    /// the independent residual check.
    #[error("the point found is not a bifurcation point: {detail}")]
    NotCritical { detail: String },
    /// The bordered matrix is singular (the borders lost the null vectors).
    #[error("the bordered matrix [[A, b], [cᵀ, 0]] is singular")]
    Singular,
    /// Any other failure of the stride computation.
    #[error("{message}")]
    Failed { message: String },
}

/// Carries a [`LostReason`] through argmin's error type.
#[derive(Debug)]
struct Lost(LostReason);

impl Display for Lost {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

impl std::error::Error for Lost {}

/// The start of a curve: a point near the bifurcation at the first value of `p_step`.
#[derive(Clone, Debug, PartialEq)]
pub struct CurveStart {
    pub section: Vec<f64>,
    pub p_free: f64,
    /// `DP` there (row-major), for the initial borders.
    pub dp: Vec<f64>,
}

impl CurveStart {
    /// From a bifurcation located by [`crate::continue_branch`] in the free parameter.
    pub fn from_bifurcation(b: &Bifurcation) -> Self {
        Self {
            section: b.section.clone(),
            p_free: b.param,
            dp: b.dp.clone(),
        }
    }
}

/// One accepted point of the curve.
#[derive(Clone, Debug, PartialEq)]
pub struct CurvePoint {
    pub p_step: f64,
    pub p_free: f64,
    /// Section state of the (critical) period-one gait.
    pub section: Vec<f64>,
    /// Its full post-heel-strike state `L(x)`.
    pub state: Vec<f64>,
    /// Multipliers of `DP`, by decreasing modulus.
    pub multipliers: Vec<Multiplier>,
    /// The real multiplier nearest `λ_c`.
    pub critical: f64,
    /// Stride duration.
    pub period: f64,
    /// `g` at the point.
    pub test_value: f64,
    /// Independently re-computed `‖P(x) − x‖∞`.
    pub residual: f64,
    pub newton_iters: u64,
}

/// How the curve ended.
#[derive(Clone, Debug, PartialEq)]
pub enum CurveEnd {
    /// Every requested value of `p_step` has its point.
    Complete,
    /// The curve was lost between the last accepted `p_step` (`None`: not even the first
    /// point) and `tried`, the value where the smallest step failed.
    Lost {
        last: Option<f64>,
        tried: f64,
        reason: LostReason,
    },
}

/// A followed curve.
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    pub kind: Codim2Kind,
    /// One point per requested value of `p_step` reached, in order.
    pub points: Vec<CurvePoint>,
    pub end: CurveEnd,
    /// Corrector solves attempted (requested and intermediate values, failures included).
    pub solves: usize,
}

/// A model of the two-parameter family `family(p_step, p_free)`.
fn build2<'m>(
    family: &dyn ModelFamily2<'m>,
    p_step: f64,
    p_free: f64,
) -> Result<Box<dyn Built + 'm>, LostReason> {
    family
        .build(p_step, p_free)
        .map_err(|message| LostReason::Model { message })
}

fn from_limit(e: LimitError, p_free: f64) -> LostReason {
    match e {
        LimitError::StrideFailed { outcome, .. } => LostReason::Fall { outcome, p_free },
        LimitError::Model { message, .. } => LostReason::Model { message },
        e => LostReason::Failed {
            message: e.to_string(),
        },
    }
}

/// Solves the row-major `m × m` system `a x = rhs` (LU with partial pivoting); `None` when the
/// solution is not finite.
fn lu_solve(m: usize, a: &[f64], rhs: &[f64]) -> Option<Vec<f64>> {
    let am = Mat::<f64>::from_fn(m, m, |i, j| a[i * m + j]);
    let b = Mat::<f64>::from_fn(m, 1, |i, _| rhs[i]);
    let x = am.partial_piv_lu().solve(&b);
    let x: Vec<f64> = (0..m).map(|i| x[(i, 0)]).collect();
    x.iter().all(|v| v.is_finite()).then_some(x)
}

fn normalized(v: &[f64]) -> Vec<f64> {
    let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    v.iter().map(|x| x / n).collect()
}

fn norm_inf(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// Everything known at one evaluation of the augmented system.
#[derive(Clone, Debug)]
pub struct Evaluation {
    /// `[P(x) − x; g]`.
    pub f: Vec<f64>,
    /// `DP(x)`, row-major.
    pub dp: Vec<f64>,
    /// `P(x)` (from the variational integration).
    pub next: Vec<f64>,
    pub period: f64,
    /// Right and left null-vector approximations `v`, `w` of `A` (bordered solutions).
    pub v: Vec<f64>,
    pub w: Vec<f64>,
}

/// The minimally augmented system at one value of `p_step` with fixed borders (see the module
/// docs); the argmin problem of the corrector.
pub struct Codim2System<'f, 'r, 'm> {
    family: &'f (dyn ModelFamily2<'m> + 'f),
    kind: Codim2Kind,
    p_step: f64,
    b: Vec<f64>,
    c: Vec<f64>,
    opts: Codim2Options,
    n: usize,
    /// The last failure seen by `apply` (to report why Newton stopped).
    failure: &'r RefCell<Option<LostReason>>,
}

impl<'f, 'r, 'm> Codim2System<'f, 'r, 'm> {
    /// The system at `p_step` with borders `b` (column) and `c` (row), both of length `n`;
    /// `family` is any closure `(p_step, p_free) ↦ Result<Box<model>, error>`.
    pub fn new(
        family: &'f (dyn ModelFamily2<'m> + 'f),
        kind: Codim2Kind,
        p_step: f64,
        b: Vec<f64>,
        c: Vec<f64>,
        opts: Codim2Options,
        failure: &'r RefCell<Option<LostReason>>,
    ) -> Self {
        let n = b.len();
        Self {
            family,
            kind,
            p_step,
            b,
            c,
            opts,
            n,
            failure,
        }
    }

    /// `F(y)`, `DP`, `P(x)` and the bordered solutions at `y = (x, p_free)`.
    pub fn evaluate(&self, y: &[f64]) -> Result<Evaluation, LostReason> {
        let n = self.n;
        let (x, p) = (&y[..n], y[n]);
        if !(p >= self.opts.free_min && p <= self.opts.free_max) {
            return Err(LostReason::FreeOutOfDomain {
                value: p,
                min: self.opts.free_min,
                max: self.opts.free_max,
            });
        }
        if !x.iter().all(|v| v.is_finite()) {
            return Err(LostReason::Failed {
                message: "non-finite section state".into(),
            });
        }
        let model = build2(self.family, self.p_step, p)?;
        let map =
            StrideMap::new(model.section(), self.opts.integrator).map_err(|e| from_limit(e, p))?;
        let (stride, dp) = dp_variational(&map, x).map_err(|e| from_limit(e, p))?;
        // M = [[A, b], [cᵀ, 0]], A = DP − λ_c I.
        let m = n + 1;
        let lc = self.kind.critical();
        let mut mm = vec![0.0; m * m];
        for i in 0..n {
            for j in 0..n {
                mm[i * m + j] = dp[i * n + j] - if i == j { lc } else { 0.0 };
            }
            mm[i * m + n] = self.b[i];
            mm[n * m + i] = self.c[i];
        }
        let mut e = vec![0.0; m];
        e[n] = 1.0;
        let vg = lu_solve(m, &mm, &e).ok_or(LostReason::Singular)?;
        let mt: Vec<f64> = (0..m * m).map(|k| mm[(k % m) * m + k / m]).collect();
        let wg = lu_solve(m, &mt, &e).ok_or(LostReason::Singular)?;
        let mut f: Vec<f64> = stride.next.iter().zip(x).map(|(a, b)| a - b).collect();
        f.push(vg[n]);
        Ok(Evaluation {
            f,
            dp,
            next: stride.next,
            period: stride.period,
            v: vg[..n].to_vec(),
            w: wg[..n].to_vec(),
        })
    }

    /// The Jacobian of `F` (row-major `(n+1) × (n+1)`): `[DP − I, ∂P/∂p; ∇g]` with the
    /// difference step `h_j = rel · max(|y_j|, 1)` (see the module docs).
    pub fn jacobian_with_step(&self, y: &[f64], rel: f64) -> Result<Vec<f64>, LostReason> {
        let n = self.n;
        let m = n + 1;
        let at = self.evaluate(y)?;
        let mut jac = vec![0.0; m * m];
        for i in 0..n {
            for j in 0..n {
                jac[i * m + j] = at.dp[i * n + j] - if i == j { 1.0 } else { 0.0 };
            }
        }
        for j in 0..m {
            let h = rel * y[j].abs().max(1.0);
            let mut yp = y.to_vec();
            yp[j] += h;
            let mut ym = y.to_vec();
            ym[j] -= h;
            let ep = self.evaluate(&yp)?;
            let em = self.evaluate(&ym)?;
            jac[n * m + j] = (ep.f[n] - em.f[n]) / (2.0 * h);
            if j == n {
                for i in 0..n {
                    jac[i * m + n] = (ep.next[i] - em.next[i]) / (2.0 * h);
                }
            }
        }
        Ok(jac)
    }

    fn record<T>(&self, r: Result<T, LostReason>) -> Result<T, ArgminError> {
        r.map_err(|e| {
            *self.failure.borrow_mut() = Some(e.clone());
            ArgminError::from(Lost(e))
        })
    }
}

impl Operator for Codim2System<'_, '_, '_> {
    type Param = Vec<f64>;
    type Output = Vec<f64>;

    fn apply(&self, y: &Vec<f64>) -> Result<Vec<f64>, ArgminError> {
        self.record(self.evaluate(y).map(|e| e.f))
    }
}

impl Jacobian for Codim2System<'_, '_, '_> {
    type Param = Vec<f64>;
    type Jacobian = Mat<f64>;

    fn jacobian(&self, y: &Vec<f64>) -> Result<Mat<f64>, ArgminError> {
        let m = self.n + 1;
        let jac = self.record(self.jacobian_with_step(y, self.opts.dtest_rel))?;
        Ok(Mat::from_fn(m, m, |i, j| jac[i * m + j]))
    }
}

/// A converged and verified point with the next borders.
struct Solved {
    point: CurvePoint,
    y: Vec<f64>,
    b: Vec<f64>,
    c: Vec<f64>,
}

/// Newton at `p_step` from `y0` with borders `b`, `c`, then the independent checks.
#[allow(clippy::too_many_arguments)]
fn solve_point(
    family: &dyn ModelFamily2<'_>,
    kind: Codim2Kind,
    p_step: f64,
    y0: &[f64],
    b: &[f64],
    c: &[f64],
    opts: &Codim2Options,
) -> Result<Solved, LostReason> {
    let n = b.len();
    let failure = RefCell::new(None);
    let sys = Codim2System::new(
        family,
        kind,
        p_step,
        b.to_vec(),
        c.to_vec(),
        *opts,
        &failure,
    );
    let (y, iters) = run_newton(sys, y0, opts, &failure)?;
    // Independent checks: the fixed point with a fresh stride, the critical multiplier.
    let sys = Codim2System::new(
        family,
        kind,
        p_step,
        b.to_vec(),
        c.to_vec(),
        *opts,
        &failure,
    );
    let ev = sys.evaluate(&y)?;
    let p = y[n];
    let model = build2(family, p_step, p)?;
    let map = StrideMap::new(model.section(), opts.integrator).map_err(|e| from_limit(e, p))?;
    let next = map.apply(&y[..n]).map_err(|e| from_limit(e, p))?;
    let residual = norm_inf(
        &next
            .iter()
            .zip(&y[..n])
            .map(|(a, b)| a - b)
            .collect::<Vec<_>>(),
    );
    if residual.is_nan() || residual > 10.0 * opts.newton_tol * residual_scale(&y) {
        return Err(LostReason::NotCritical {
            detail: format!(
                "a fresh stride gives ‖P(x) − x‖∞ = {residual:.3e}, above the tolerance"
            ),
        });
    }
    let mult = multipliers(&ev.dp, n).map_err(|e| from_limit(e, p))?;
    let critical = critical_multiplier(&mult, kind, opts)?;
    Ok(Solved {
        point: CurvePoint {
            p_step,
            p_free: p,
            section: y[..n].to_vec(),
            state: map.lift(&y[..n]),
            multipliers: mult,
            critical,
            period: ev.period,
            test_value: ev.f[n],
            residual,
            newton_iters: iters,
        },
        b: normalized(&ev.w),
        c: normalized(&ev.v),
        y,
    })
}

/// Newton (argmin) on the augmented system `sys` from `y0`: the converged point and the
/// iterations taken. A run that did not converge is lost, as the fall or the leaving of the
/// free parameter's domain its last trials met (`failure`) where there was one.
fn run_newton(
    sys: Codim2System<'_, '_, '_>,
    y0: &[f64],
    opts: &Codim2Options,
    failure: &RefCell<Option<LostReason>>,
) -> Result<(Vec<f64>, u64), LostReason> {
    let solver =
        Newton::new(opts.newton_tol, opts.max_backtracks).map_err(|e| LostReason::Failed {
            message: e.to_string(),
        })?;
    let start = y0.to_vec();
    let run = Executor::new(sys, solver)
        .configure(|s| s.param(start).max_iters(opts.max_newton))
        .timer(false)
        .run();
    let res = match run {
        Ok(r) => r,
        Err(e) => {
            return Err(match e.downcast::<Lost>() {
                Ok(Lost(r)) => r,
                Err(e) => LostReason::Failed {
                    message: e.to_string(),
                },
            })
        }
    };
    let state: &NewtonState = res.state();
    let y = state
        .get_best_param()
        .or(state.get_param())
        .cloned()
        .unwrap_or_else(|| y0.to_vec());
    let converged = matches!(
        state.get_termination_reason(),
        Some(TerminationReason::SolverConverged)
    );
    let iters = state.get_iter();
    if !converged {
        let why = state
            .get_termination_reason()
            .map(|r| r.text().to_string())
            .unwrap_or_else(|| "not terminated".into());
        // A failed line search after trials that fell or left the domain: say so.
        if let Some(f) = failure.borrow().clone() {
            if matches!(
                f,
                LostReason::Fall { .. } | LostReason::FreeOutOfDomain { .. }
            ) {
                return Err(f);
            }
        }
        return Err(LostReason::NoConvergence {
            reason: why,
            residual: state.get_cost(),
        });
    }
    Ok((y, iters))
}

/// The real multiplier of `mult` nearest the critical value of `kind` (+1 for a fold, −1 for
/// a period doubling); lost when none is within `critical_tol` of it.
fn critical_multiplier(
    mult: &[Multiplier],
    kind: Codim2Kind,
    opts: &Codim2Options,
) -> Result<f64, LostReason> {
    let lc = kind.critical();
    let critical = mult
        .iter()
        .filter(|m| m.im == 0.0)
        .map(|m| m.re)
        .min_by(|a, b| (a - lc).abs().total_cmp(&(b - lc).abs()));
    critical
        .filter(|l| (l - lc).abs() <= opts.critical_tol)
        .ok_or_else(|| LostReason::NotCritical {
            detail: format!(
                "no real multiplier within {:e} of {lc} (multipliers {:?})",
                opts.critical_tol,
                mult.iter().map(|m| (m.re, m.im)).collect::<Vec<_>>()
            ),
        })
}

/// Follow the curve of `kind` points through `start` (near the curve at `step_values[0]`) over
/// the values `step_values` of the stepped parameter (strictly monotone, at least one value).
/// `family(p_step, p_free)` builds the model.
///
/// Returns the points reached; a curve lost on the way ends with [`CurveEnd::Lost`] (not an
/// error). Errors are invalid options or inputs.
pub fn follow_curve<S, E, F>(
    family: &F,
    kind: Codim2Kind,
    start: &CurveStart,
    step_values: &[f64],
    opts: &Codim2Options,
) -> Result<Curve, LimitError>
where
    S: Section + ?Sized,
    E: Display,
    F: Fn(f64, f64) -> Result<Box<S>, E>,
{
    follow_erased(family, kind, start, step_values, opts)
}

/// [`follow_curve`] on the family as a trait object.
fn follow_erased(
    family: &dyn ModelFamily2<'_>,
    kind: Codim2Kind,
    start: &CurveStart,
    step_values: &[f64],
    opts: &Codim2Options,
) -> Result<Curve, LimitError> {
    opts.validate()?;
    let n = start.section.len();
    if n == 0 || start.dp.len() != n * n {
        return Err(LimitError::SectionDim {
            expected: n * n,
            got: start.dp.len(),
        });
    }
    let dir = step_direction(step_values)?;
    let (b0, c0) = start_borders(start, kind)?;
    let mut y0 = start.section.clone();
    y0.push(start.p_free);
    let mut solves = 1;
    let first = match solve_point(family, kind, step_values[0], &y0, &b0, &c0, opts) {
        Ok(s) => s,
        Err(reason) => {
            return Ok(Curve {
                kind,
                points: Vec::new(),
                end: CurveEnd::Lost {
                    last: None,
                    tried: step_values[0],
                    reason,
                },
                solves,
            })
        }
    };
    let mut points = vec![first.point.clone()];
    // Accepted (p_step, y) for the secant predictor.
    let mut hist: Vec<(f64, Vec<f64>)> = vec![(step_values[0], first.y.clone())];
    let (mut b, mut c) = (first.b, first.c);
    let mut cur = step_values[0];
    let mut next_idx = 1;
    let mut h_fac = 1.0f64; // current step as a fraction of the nominal spacing
    let end = loop {
        if next_idx >= step_values.len() {
            break CurveEnd::Complete;
        }
        let target = step_values[next_idx];
        let spacing = (target - step_values[next_idx - 1]).abs();
        let remaining = (target - cur).abs();
        let step = (h_fac * spacing).min(remaining);
        let to = if step >= remaining * (1.0 - 1e-12) {
            target
        } else {
            cur + dir * step
        };
        let pred = secant_prediction(&hist, to);
        solves += 1;
        match solve_point(family, kind, to, &pred, &b, &c, opts) {
            Ok(sol) => {
                hist.push((to, sol.y.clone()));
                if hist.len() > 2 {
                    hist.remove(0);
                }
                b = sol.b;
                c = sol.c;
                cur = to;
                if to == target {
                    points.push(sol.point);
                    next_idx += 1;
                }
                h_fac = (2.0 * h_fac).min(1.0);
            }
            Err(reason) => {
                h_fac *= 0.5;
                if h_fac < opts.min_step_fraction {
                    break CurveEnd::Lost {
                        last: Some(cur),
                        tried: to,
                        reason,
                    };
                }
            }
        }
    };
    Ok(Curve {
        kind,
        points,
        end,
        solves,
    })
}

/// The direction (±1) of the stepped parameter's values `step_values`, checked: at least one
/// value, all finite, strictly monotone.
fn step_direction(step_values: &[f64]) -> Result<f64, LimitError> {
    if step_values.is_empty() || !step_values.iter().all(|v| v.is_finite()) {
        return Err(LimitError::InvalidOption {
            name: "step_values",
            value: step_values.len() as f64,
            allowed: "need at least one finite value",
        });
    }
    let dir = if step_values.len() > 1 {
        (step_values[1] - step_values[0]).signum()
    } else {
        1.0
    };
    if step_values
        .windows(2)
        .any(|w| (w[1] - w[0]) * dir <= 0.0 || !(w[1] - w[0]).is_finite())
    {
        return Err(LimitError::InvalidOption {
            name: "step_values",
            value: f64::NAN,
            allowed: "must be strictly monotone",
        });
    }
    Ok(dir)
}

/// The borders of the first corrector at `start`: the left (`b`) and right (`c`) real
/// eigenvectors of its `DP` for the critical multiplier of `kind`.
fn start_borders(start: &CurveStart, kind: Codim2Kind) -> Result<(Vec<f64>, Vec<f64>), LimitError> {
    let n = start.section.len();
    let lc = kind.critical();
    let mut dpt = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            dpt[i * n + j] = start.dp[j * n + i];
        }
    }
    let c0 = real_eigenvector(&start.dp, n, lc).ok_or(LimitError::Singular {
        at: start.section.clone(),
    })?;
    let b0 = real_eigenvector(&dpt, n, lc).ok_or(LimitError::Singular {
        at: start.section.clone(),
    })?;
    Ok((b0, c0))
}

/// The predictor at `to` from the accepted points `hist` (`(p_step, y)`, the last two):
/// linear extrapolation through both (secant), or the last point alone.
fn secant_prediction(hist: &[(f64, Vec<f64>)], to: f64) -> Vec<f64> {
    match hist.len() {
        0 | 1 => hist[hist.len() - 1].1.clone(),
        k => {
            let (t0, y0) = &hist[k - 2];
            let (t1, y1) = &hist[k - 1];
            let s = (to - t1) / (t1 - t0);
            y1.iter().zip(y0).map(|(a, b)| a + s * (a - b)).collect()
        }
    }
}

/// What the stride map does in one cell of a [`region_map`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Region {
    /// The period-one gait exists and is stable.
    StablePeriodOne,
    /// From the nudged unstable (or missing) period-one gait, the map settles on a period-2
    /// orbit.
    PeriodTwo,
    /// … on an orbit of period ≥ 3 (4, 8, … after a cascade).
    PeriodHigher,
    /// It keeps walking without a detected period (chaos, quasi-periodicity, or not settled).
    Other,
    /// It falls (or times out).
    Fall,
}

impl Region {
    /// Every region, in code order.
    pub const ALL: [Region; 5] = [
        Region::StablePeriodOne,
        Region::PeriodTwo,
        Region::PeriodHigher,
        Region::Other,
        Region::Fall,
    ];

    /// Code in a region map file.
    pub fn code(self) -> u8 {
        self as u8
    }

    /// Name in a legend.
    pub fn name(self) -> &'static str {
        match self {
            Region::StablePeriodOne => "stable period-1",
            Region::PeriodTwo => "period-2",
            Region::PeriodHigher => "period-4+ (period >= 3)",
            Region::Other => "no period (chaotic or not settled)",
            Region::Fall => "falls",
        }
    }
}

/// Options of [`region_map`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegionOptions {
    /// Newton for the period-one gait in each cell.
    pub newton: NewtonOptions,
    /// Integrator of the Newton solves.
    pub integrator: Options,
    /// The iteration from the nudged gait (transient, record, period detection).
    pub orbit: OrbitOptions,
    /// Nudge of the unstable gait's first coordinate before iterating.
    pub nudge: f64,
}

impl Default for RegionOptions {
    /// Newton to 1e-10 (DOP853 at 1e-12); 200 transient and 32 recorded strides (DOP853 at
    /// 1e-10), periods ≤ 16 detected to 1e-7; nudge 1e-5.
    fn default() -> Self {
        Self {
            newton: NewtonOptions {
                tol: 1e-10,
                max_iters: 20,
                ..NewtonOptions::default()
            },
            integrator: Options::dop853(1e-12),
            orbit: OrbitOptions {
                transient: 200,
                record: 32,
                max_period: 16,
                chunk: 4,
                ..OrbitOptions::default()
            },
            nudge: 1e-5,
        }
    }
}

/// One column of a region map: the period-one gait found by Newton along `free_values`, marching
/// out from the index nearest `hint.1` with `hint.0` as the first guess, each solve starting
/// from the previous cell's gait. Returns per cell the start state of the iteration and whether
/// the gait there is stable.
fn column_gaits(
    family: &dyn ModelFamily2<'_>,
    p_step: f64,
    free_values: &[f64],
    hint: &(Vec<f64>, f64),
    opts: &RegionOptions,
) -> Vec<(Vec<f64>, bool)> {
    let k0 = free_values
        .iter()
        .enumerate()
        .min_by(|a, b| (a.1 - hint.1).abs().total_cmp(&(b.1 - hint.1).abs()))
        .map_or(0, |(k, _)| k);
    let mut out: Vec<(Vec<f64>, bool)> = vec![(hint.0.clone(), false); free_values.len()];
    let order: [Vec<usize>; 2] = [(k0..free_values.len()).collect(), (0..k0).rev().collect()];
    for ks in order {
        let mut guess = hint.0.clone();
        for k in ks {
            let found = build2(family, p_step, free_values[k]).ok().and_then(|m| {
                let map = StrideMap::new(m.section(), opts.integrator).ok()?;
                find_fixed_point(&map, &guess, &opts.newton).ok()
            });
            match found {
                Some(fp) => {
                    guess = fp.section.clone();
                    out[k] = (fp.section, fp.stable);
                }
                None => out[k] = (guess.clone(), false),
            }
        }
    }
    out
}

/// Classifies the cells `(step_values[i], free_values[j])` (row `j`, column `i` of the result,
/// `free_values.len() × step_values.len()`): [`Region::StablePeriodOne`] where Newton finds a
/// stable period-one gait (continued cell to cell from `hints[i] = (section, p_free)`, a gait
/// near column `i`); elsewhere the stride map is iterated from the unstable gait nudged by
/// `opts.nudge` (or from the nearest gait found, where none exists) and the cell is labelled by
/// the period detected after the transient ([`orbit_diagram`](crate::orbit_diagram)) or the fall. `progress(1)` is
/// called once per column and phase (`2 × step_values.len()` calls in all, from any thread).
/// Identical results for any thread count (every cell's computation is independent of the
/// scheduling).
pub fn region_map<S, E, F>(
    family: &F,
    step_values: &[f64],
    free_values: &[f64],
    hints: &[(Vec<f64>, f64)],
    opts: &RegionOptions,
    pool: &rayon::ThreadPool,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Vec<Vec<Region>>, LimitError>
where
    S: Section + ?Sized,
    E: Display,
    F: Fn(f64, f64) -> Result<Box<S>, E> + Sync,
{
    region_erased(
        family,
        step_values,
        free_values,
        hints,
        opts,
        pool,
        progress,
    )
}

/// The one-parameter family `p_free ↦ family(p_step, p_free)`.
struct AtStep<'a, 'm> {
    family: &'a (dyn ModelFamily2<'m> + Sync + 'a),
    p_step: f64,
}

impl<'m> ModelFamily<'m> for AtStep<'_, 'm> {
    fn build(&self, mu: f64) -> Result<Box<dyn Built + 'm>, String> {
        self.family.build(self.p_step, mu)
    }
}

/// [`region_map`] on the family as a trait object.
fn region_erased(
    family: &(dyn ModelFamily2<'_> + Sync),
    step_values: &[f64],
    free_values: &[f64],
    hints: &[(Vec<f64>, f64)],
    opts: &RegionOptions,
    pool: &rayon::ThreadPool,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Vec<Vec<Region>>, LimitError> {
    if hints.len() != step_values.len() {
        return Err(LimitError::InvalidOption {
            name: "hints",
            value: hints.len() as f64,
            allowed: "one (section, p_free) hint per step value",
        });
    }
    use rayon::prelude::*;
    // Phase 1: the period-one gait in every cell, one column per task (a column's Newton
    // solves march from cell to cell, so they are sequential within it).
    let gaits: Vec<Vec<(Vec<f64>, bool)>> = pool.install(|| {
        step_values
            .par_iter()
            .zip(hints.par_iter())
            .map(|(&ps, hint)| {
                let g = column_gaits(family, ps, free_values, hint, opts);
                progress(1);
                g
            })
            .collect()
    });
    // Phase 2: iterate from the nudged gaits, column by column (cells of a column in parallel).
    let mut grid = vec![vec![Region::Fall; step_values.len()]; free_values.len()];
    for (i, &ps) in step_values.iter().enumerate() {
        let starts: Vec<Vec<f64>> = gaits[i]
            .iter()
            .map(|(s, _)| {
                let mut v = s.clone();
                v[0] += opts.nudge;
                v
            })
            .collect();
        let fam1 = AtStep { family, p_step: ps };
        let cols = crate::orbit::diagram_erased(
            &fam1,
            free_values,
            &OrbitStart::PerParam(starts),
            &opts.orbit,
            pool,
        )?;
        for (j, (col, (_, stable))) in cols.iter().zip(&gaits[i]).enumerate() {
            grid[j][i] = if *stable {
                Region::StablePeriodOne
            } else if col.fall.is_some() {
                Region::Fall
            } else {
                match col.period {
                    Some(1) => Region::StablePeriodOne,
                    Some(2) => Region::PeriodTwo,
                    Some(_) => Region::PeriodHigher,
                    None => Region::Other,
                }
            };
        }
        progress(1);
    }
    Ok(grid)
}
