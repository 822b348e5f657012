//! Period-K orbits of the stride map: fixed points of `P^K`, `F(s) = P^K(s) − s = 0`, solved by
//! the same damped Newton method as period-one gaits ([`Newton`], run through argmin).
//!
//! # The K-step map and its Jacobian
//! `P^K(s) = P(s_{K−1})` with `s_0 = s`, `s_{j+1} = P(s_j)`. By the chain rule its Jacobian is
//! the product of the per-stride Jacobians along the orbit, `DP^K(s) = DP(s_{K−1}) ⋯ DP(s_0)`;
//! with [`DpMethod::Variational`] every factor is exact (variational equations with saltation
//! matrices, [`crate::dp_variational_with`] with state-only error control, so that the strides
//! are the plain map's bit for bit). The multipliers of a period-K orbit are the eigenvalues of
//! `DP^K` at any of its points (the products in another cyclic order are similar matrices).
//!
//! # Acceptance
//! As for period one ([`crate::newton`]): the solver's convergence is never trusted; the orbit is
//! re-integrated from the returned point with a fresh integrator and accepted only if
//! `‖P^K(s) − s‖∞ ≤ tol · σ(s)` and every one of its K strides travels at least
//! [`NewtonOptions::min_step_length`]. A fixed point of `P^K` may be an orbit of a smaller
//! period q dividing K (a period-one gait is a fixed point of `P²`); such a solution is rejected
//! with a message naming q, so `--period 2` never reports the period-one gait twice over.

use crate::error::LimitError;
use crate::floquet::{is_stable, multipliers, Multiplier};
use crate::jacobian::{dp_finite_difference, dp_variational_with};
use crate::metrics::GaitMetrics;
use crate::newton::{
    chord_polish, residual_scale, DpMethod, KeptJacobian, Newton, NewtonOptions, NewtonState,
    RunEnd,
};
use crate::stride::StrideMap;
use crate::variational::ErrorControl;
use argmin::core::{Error as ArgminError, Executor, Jacobian, Operator, OptimizationResult};
use faer::Mat;

/// The argmin problem `F(s) = P^K(s) − s` with Jacobian `DP^K(s) − I`.
///
/// As for period one ([`crate::FixedPointProblem`]): with [`DpMethod::Variational`] an
/// evaluation of `F` integrates the variational equations along the K strides once, giving
/// `P^K(s)` and `DP^K(s)` together; the Jacobian at that `s` is kept.
pub struct PeriodKProblem<'m, 'a> {
    pub map: &'m StrideMap<'a>,
    /// K ≥ 1.
    pub k: usize,
    pub dp: DpMethod,
    /// `DP^K(s)` of the last variational evaluation of `F`.
    kept: KeptJacobian,
}

/// `C = A · B` for row-major `n × n` matrices.
#[doc(hidden)]
pub fn matmul(a: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let mut c = vec![0.0; n * n];
    for i in 0..n {
        for l in 0..n {
            let ail = a[i * n + l];
            for j in 0..n {
                c[i * n + j] += ail * b[l * n + j];
            }
        }
    }
    c
}

fn dist_inf(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

impl PeriodKProblem<'_, '_> {
    /// `P^K(s)`, or [`LimitError::StrideFailed`] if a stride does not reach the section.
    pub fn iterate(&self, s: &[f64]) -> Result<Vec<f64>, LimitError> {
        let mut x = s.to_vec();
        for _ in 0..self.k {
            x = self.map.apply(&x)?;
        }
        Ok(x)
    }

    /// `DP^K(s) = DP(s_{K−1}) ⋯ DP(s_0)` (row-major) by the configured method (the one kept
    /// from the evaluation of `F` at exactly this `s`, if there was one).
    pub fn dp_k(&self, s: &[f64]) -> Result<Vec<f64>, LimitError> {
        match self.kept_at(s) {
            Some(dp) => Ok(dp),
            None => Ok(self.orbit_and_dp(s)?.1),
        }
    }

    /// The `DP^K` kept from the variational evaluation of `F` at exactly `s`, if the last one
    /// was there.
    pub fn kept_at(&self, s: &[f64]) -> Option<Vec<f64>> {
        self.kept.at(s)
    }

    /// `s_K` along the strides the Jacobian is taken on (the variational integration's, or the
    /// plain map's with finite differences) and `DP^K(s)`.
    fn orbit_and_dp(&self, s: &[f64]) -> Result<(Vec<f64>, Vec<f64>), LimitError> {
        let n = s.len();
        let mut prod: Vec<f64> = (0..n * n)
            .map(|i| if i % (n + 1) == 0 { 1.0 } else { 0.0 })
            .collect();
        let mut x = s.to_vec();
        for _ in 0..self.k {
            let (next, dp) = match self.dp {
                DpMethod::Variational => {
                    let (st, dp) = dp_variational_with(self.map, &x, ErrorControl::State)?;
                    (st.next, dp)
                }
                DpMethod::FiniteDifference { scheme, lanes } => {
                    let dp = dp_finite_difference(self.map, &x, scheme, lanes)?;
                    (self.map.apply(&x)?, dp)
                }
            };
            prod = matmul(&dp, &prod, n);
            x = next;
        }
        Ok((x, prod))
    }
}

impl<'m, 'a> PeriodKProblem<'m, 'a> {
    /// The K-step problem on `map` with the Jacobian from `dp`.
    pub fn new(map: &'m StrideMap<'a>, k: usize, dp: DpMethod) -> Self {
        Self {
            map,
            k,
            dp,
            kept: KeptJacobian::default(),
        }
    }
}

impl Operator for PeriodKProblem<'_, '_> {
    type Param = Vec<f64>;
    type Output = Vec<f64>;

    fn apply(&self, s: &Vec<f64>) -> Result<Vec<f64>, ArgminError> {
        let p = match self.dp {
            DpMethod::Variational => {
                let (p, dp) = self.orbit_and_dp(s)?;
                self.kept.keep(s, dp);
                p
            }
            DpMethod::FiniteDifference { .. } => self.iterate(s)?,
        };
        Ok(p.iter().zip(s).map(|(a, b)| a - b).collect())
    }
}

impl Jacobian for PeriodKProblem<'_, '_> {
    type Param = Vec<f64>;
    type Jacobian = Mat<f64>;

    fn jacobian(&self, s: &Vec<f64>) -> Result<Mat<f64>, ArgminError> {
        let n = s.len();
        let dp = self.dp_k(s)?;
        Ok(Mat::from_fn(n, n, |i, j| {
            dp[i * n + j] - if i == j { 1.0 } else { 0.0 }
        }))
    }
}

/// A verified period-K orbit of the stride map.
#[derive(Clone, Debug, PartialEq)]
pub struct PeriodicOrbit {
    /// K, the strides per period (the orbit's minimal period).
    pub period_k: usize,
    /// The K section states in stride order, `orbit[j+1] = P(orbit[j])`.
    pub orbit: Vec<Vec<f64>>,
    /// The full post-reset state `L(s_j)` of every orbit point.
    pub states: Vec<Vec<f64>>,
    /// Metrics of each of the K strides.
    pub strides: Vec<GaitMetrics>,
    /// Duration of the K strides together.
    pub period: f64,
    /// `DP^K` at `orbit[0]`, row-major `d_s × d_s`.
    pub dp: Vec<f64>,
    /// Multipliers of the K-step map, by decreasing modulus.
    pub multipliers: Vec<Multiplier>,
    /// All |λ| < 1.
    pub stable: bool,
    /// Independently re-computed `‖P^K(s) − s‖∞`.
    pub residual: f64,
    /// Newton iterations.
    pub iterations: u64,
    /// argmin's termination reason.
    pub termination: String,
    /// `‖P^K(s) − s‖∞` at the guess and after every iteration.
    pub residual_history: Vec<f64>,
}

impl PeriodicOrbit {
    /// Sum of the K step lengths (if the map reports step lengths).
    pub fn total_step_length(&self) -> Option<f64> {
        self.strides.iter().map(|m| m.step_length).sum()
    }

    /// Mean progression speed over the K strides: total step length / total time.
    pub fn speed(&self) -> Option<f64> {
        self.total_step_length().map(|l| l / self.period)
    }

    /// True if `s` is within `tol` (∞-norm) of a point of the orbit.
    pub fn contains(&self, s: &[f64], tol: f64) -> bool {
        self.orbit.iter().any(|p| dist_inf(p, s) <= tol)
    }
}

/// Separation below which two points of a candidate period-K orbit count as the same point:
/// `‖s_q − s_0‖∞ ≤ max(10·tol, min(10⁴·tol, 10⁻³), 10⁻¹⁰) · σ(s_0)` means the orbit has period
/// q. With the default tol = 1e-12 this is 1e-8, far below the splitting of a period-doubled
/// orbit a measurable distance past its bifurcation (it grows like √|μ − μ_PD|); it never
/// exceeds 10⁻³ unless the residual tolerance itself is that loose.
fn same_point_tol(tol: f64, s: &[f64]) -> f64 {
    (1e4 * tol).min(1e-3).max(10.0 * tol).max(1e-10) * residual_scale(s)
}

/// The orbit of `s` under K strides with a fresh integrator: the K + 1 section states and the
/// K strides' metrics, or the failing stride's error.
fn integrate_orbit(
    map: &StrideMap<'_>,
    s: &[f64],
    k: usize,
) -> Result<(Vec<Vec<f64>>, Vec<GaitMetrics>), LimitError> {
    let mut pts = vec![s.to_vec()];
    let mut metrics = Vec::with_capacity(k);
    for _ in 0..k {
        let from = pts.last().expect("non-empty").clone();
        let st = map.stride(&from)?;
        if !st.outcome.is_ok() {
            return Err(LimitError::StrideFailed {
                from,
                outcome: st.outcome,
            });
        }
        metrics.push(GaitMetrics::from_stride(&st));
        pts.push(st.next);
    }
    Ok((pts, metrics))
}

/// Finds a period-`k` orbit of `map` by Newton on `P^k − id` from `guess`, verifies it (see the
/// module docs) and measures it (multipliers of `DP^k`, per-stride metrics). `k = 1` solves the
/// same equation as [`crate::find_fixed_point`].
pub fn find_periodic_orbit(
    map: &StrideMap<'_>,
    guess: &[f64],
    k: usize,
    opts: &NewtonOptions,
) -> Result<PeriodicOrbit, LimitError> {
    if k == 0 || k > 64 {
        return Err(LimitError::InvalidOption {
            name: "period",
            value: k as f64,
            allowed: "the period K must be in 1..=64 strides",
        });
    }
    map.check_dim(guess)?;
    let res = run_period_k(map, guess, k, opts)?;
    let RunEnd {
        mut iterations,
        converged,
        termination,
        mut history,
        mut last,
    } = RunEnd::of(&res, guess);
    // Independent check on the plain stride map, with fresh integrators; chord steps on it
    // where the solver's (variational) map differs from it by more than tol (see
    // `crate::newton`).
    let mut orbit_end = integrate_orbit(map, &last, k)?;
    let mut residual = dist_inf(&orbit_end.0[k], &orbit_end.0[0]);
    if let Some(dpk) = res
        .problem
        .problem
        .as_ref()
        .filter(|_| converged)
        .and_then(|p| p.kept_at(&last))
    {
        iterations += chord_polish(
            &dpk,
            opts.tol,
            &mut last,
            &mut orbit_end,
            &mut residual,
            &mut history,
            |(pts, _)| &pts[k],
            |s| {
                let e = integrate_orbit(map, s, k).ok()?;
                let r = dist_inf(&e.0[k], &e.0[0]);
                Some((e, r))
            },
        );
    }
    let (pts, metrics) = orbit_end;
    let fail = |reason: String, last: Vec<f64>| LimitError::NoConvergence {
        reason,
        iterations,
        last,
        history: history.clone(),
    };
    if !(residual.is_finite() && residual <= opts.tol * residual_scale(&last)) {
        return Err(fail(
            format!("‖P^{k}(s) − s‖∞ = {residual:.3e} at the last iterate ({termination})"),
            last,
        ));
    }
    if let Some(l) = metrics
        .iter()
        .filter_map(|m| m.step_length.map(f64::abs))
        .find(|l| l.is_nan() || *l < opts.min_step_length)
    {
        return Err(fail(
            format!(
                "degenerate orbit: a stride's step length is {l:.3e}, below {:e}; steps that \
                 short are not resolved as an orbit",
                opts.min_step_length
            ),
            last,
        ));
    }
    // Minimal period: the smallest q | k with s_q = s_0.
    let same = same_point_tol(opts.tol, &last);
    if let Some(q) = (1..k).find(|&q| k.is_multiple_of(q) && dist_inf(&pts[q], &pts[0]) <= same) {
        return Err(fail(
            format!(
                "converged to an orbit of period {q} (‖P^{q}(s) − s‖∞ = {:.3e}), a divisor of \
                 the requested period {k}: not a period-{k} orbit",
                dist_inf(&pts[q], &pts[0])
            ),
            last,
        ));
    }
    let dp = match res.problem.problem.as_ref() {
        Some(p) if p.dp == opts.dp_report => p.dp_k(&last)?,
        _ => PeriodKProblem::new(map, k, opts.dp_report).dp_k(&last)?,
    };
    let mult = multipliers(&dp, last.len())?;
    let orbit: Vec<Vec<f64>> = pts[..k].to_vec();
    Ok(PeriodicOrbit {
        period_k: k,
        states: orbit.iter().map(|s| map.lift(s)).collect(),
        orbit,
        period: metrics.iter().map(|m| m.period).sum(),
        strides: metrics,
        stable: is_stable(&mult),
        multipliers: mult,
        dp,
        residual,
        iterations,
        termination,
        residual_history: history,
    })
}

/// The argmin run of [`Newton`] on `P^k − id` from `guess`; a run that could not start (the
/// guess gives no complete `k` strides) is an error.
fn run_period_k<'m, 'a>(
    map: &'m StrideMap<'a>,
    guess: &[f64],
    k: usize,
    opts: &NewtonOptions,
) -> Result<OptimizationResult<PeriodKProblem<'m, 'a>, Newton, NewtonState>, LimitError> {
    let problem = PeriodKProblem::new(map, k, opts.dp);
    let solver = Newton::new(opts.tol, opts.max_backtracks)?;
    let run = Executor::new(problem, solver)
        .configure(|s| s.param(guess.to_vec()).max_iters(opts.max_iters))
        .timer(false)
        .run();
    match run {
        Ok(r) => Ok(r),
        Err(e) => Err(match e.downcast::<LimitError>() {
            Ok(le) => le,
            Err(e) => LimitError::NoConvergence {
                reason: e.to_string(),
                iterations: 0,
                last: guess.to_vec(),
                history: Vec::new(),
            },
        }),
    }
}

/// True if orbits `a` and `b` are the same cycle: `b`'s first point is within
/// `1e-8·(1 + |x|)` of a point of `a` in every coordinate (the orbits may start at different
/// points of the cycle).
pub fn same_orbit(a: &[Vec<f64>], b: &[Vec<f64>]) -> bool {
    a.len() == b.len()
        && b.first().is_some_and(|b0| {
            a.iter().any(|p| {
                p.iter()
                    .zip(b0)
                    .all(|(x, y)| (x - y).abs() <= 1e-8 * (1.0 + x.abs()))
            })
        })
}

/// The cycle `orbit` rotated to start at its lexicographically smallest point (first coordinate,
/// then the next…), so that the same cycle is stored the same way whichever point Newton found.
pub fn canonical_start(orbit: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let start = (0..orbit.len())
        .min_by(|&i, &j| {
            orbit[i]
                .iter()
                .zip(&orbit[j])
                .map(|(a, b)| a.total_cmp(b))
                .find(|o| o.is_ne())
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .unwrap_or(0);
    orbit[start..]
        .iter()
        .chain(&orbit[..start])
        .cloned()
        .collect()
}

/// `s` after `n` strides of `map`, or `None` if a stride fails on the way.
pub fn iterate_map(map: &StrideMap<'_>, s: &[f64], n: usize) -> Option<Vec<f64>> {
    let mut integ = pdw_hybrid::Integrator::new(map.system().dim(), *map.options()).ok()?;
    let mut x = s.to_vec();
    for _ in 0..n {
        let st = map.stride_with(&mut integ, &x).ok()?;
        if !st.outcome.is_ok() || !st.next.iter().all(|v| v.is_finite()) {
            return None;
        }
        x = st.next;
    }
    Some(x)
}
