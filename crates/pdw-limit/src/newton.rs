//! Fixed points of the stride map, `F(s) = P(s) − s = 0`, as an argmin problem solved by a
//! damped Newton method that implements argmin's [`Solver`] trait; argmin's [`Executor`] owns
//! the iteration limit and the termination reason.
//!
//! # Newton step
//! With `J = DP(s) − I` (d_s × d_s, from [`dp_variational`] or [`dp_finite_difference`]), solve
//! `J δ = −F(s)` by LU with partial pivoting (faer). Near a regular root (`J` non-singular, i.e.
//! no multiplier equal to 1) the iteration converges quadratically.
//!
//! With the variational Jacobian, `F` and `DP` come from one integration of the variational
//! equations per point ([`FixedPointProblem`]): each iterate costs one variational stride, and
//! the Jacobian of the converged point (for its multipliers) is the one its last evaluation
//! gave. That integration controls the step size on the state alone
//! ([`ErrorControl::State`]): its state part takes the plain integration's steps, events and
//! resets, so the `F` Newton sees is the plain stride map's bit for bit, and the tangent
//! columns ride on those steps (their accuracy against finite differences and the fully
//! controlled `DP` is tested). Acceptance is decided on the plain stride map (below).
//!
//! # Globalisation
//! Backtracking on `‖F‖₂` (Armijo, Dennis & Schnabel §6.3): accept `s + λδ` with the first
//! `λ ∈ {1, ½, ¼, …}` such that the trial stride reaches the section and
//! `‖F(s + λδ)‖₂ ≤ (1 − 10⁻⁴ λ) ‖F(s)‖₂`. A trial stride that falls counts as a failed trial.
//!
//! # Acceptance
//! Convergence is relative to the gait's scale: `‖F(s)‖∞ ≤ tol · σ(s)` with
//! `σ(s) = min(1, ‖s‖∞)`. For order-one states this is the absolute test `‖F‖∞ ≤ tol`; for small
//! states it tightens with them, so that a residual of 10⁻¹² on a state of 10⁻⁵ (a walker barely
//! moving, whose stride map is the identity to within 10⁻⁷) is not mistaken for a solution.
//! The solver reports convergence on that test; [`find_fixed_point`] never trusts it: it
//! re-runs the stride from the returned point on the plain stride map `P` with a fresh
//! integrator and accepts only if `‖P(s) − s‖∞ ≤ tol · σ(s)`. With the variational Jacobian the
//! solver converged on the variational integration's `P`, which is the plain `P` bit for bit
//! as long as the model's [`flow_with_jacobian`](pdw_hybrid::HybridSystem::flow_with_jacobian)
//! gives its flow bit for bit; a model that breaks that contract makes the two maps differ, and
//! when the difference exceeds `tol` and the solver did converge, up to four chord steps
//! `s ← s − (DP − I)⁻¹(P(s) − s)` on the plain map, with the `DP` of the last iterate, finish
//! the convergence (each counted as an iteration, its residual appended to the history). If
//! the test still fails it returns [`LimitError::NoConvergence`] with the residual history and
//! the last iterate.
//!
//! # Degenerate gaits
//! On a level floor (slope 0) the passive walkers lose energy at every heel strike and have no
//! gait, but their stride map has a continuum of near-fixed points shrinking to standing still:
//! `P(s) = s − O(‖s‖³)`, so Newton creeps towards `s = 0` with ever smaller residuals. A fixed
//! point whose step length is below [`NewtonOptions::min_step_length`] is rejected as degenerate
//! (the walker does not travel), with a message saying so.

use crate::error::LimitError;
use crate::floquet::{is_stable, multipliers, Multiplier};
use crate::jacobian::{dp_finite_difference, dp_variational, dp_variational_with, FdScheme};
use crate::metrics::GaitMetrics;
use crate::stride::StrideMap;
use crate::variational::ErrorControl;
use argmin::core::{
    Error as ArgminError, Executor, IterState, Jacobian, Operator, OptimizationResult, Problem,
    Solver, State, TerminationReason, TerminationStatus, KV,
};
use faer::prelude::*;
use faer::Mat;

/// How the Newton matrix `DP − I` is obtained.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DpMethod {
    /// Variational equations with saltation matrices (exact).
    Variational,
    /// Finite differences, perturbed strides batched over `lanes` lanes.
    FiniteDifference { scheme: FdScheme, lanes: usize },
}

/// Options of [`find_fixed_point`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonOptions {
    /// Target `‖P(s) − s‖∞` (also the independent acceptance test).
    pub tol: f64,
    /// Newton iterations (argmin `max_iters`).
    pub max_iters: u64,
    /// Step halvings per iteration before giving up.
    pub max_backtracks: usize,
    /// Jacobian used by the Newton step.
    pub dp: DpMethod,
    /// Jacobian reported with the fixed point (for the multipliers).
    pub dp_report: DpMethod,
    /// Smallest step length (model length units, legs are O(1)) of an accepted gait; shorter
    /// ones are degenerate (standing still). Applies only to maps that report a step length.
    pub min_step_length: f64,
}

/// The Jacobian an evaluation of `F` produced on the way, keyed by the exact point `s`.
#[derive(Default)]
pub(crate) struct KeptJacobian(std::cell::RefCell<Option<(Vec<f64>, Vec<f64>)>>);

impl KeptJacobian {
    /// Keep `dp` as the Jacobian at `s` (replacing the previous one).
    pub(crate) fn keep(&self, s: &[f64], dp: Vec<f64>) {
        *self.0.borrow_mut() = Some((s.to_vec(), dp));
    }

    /// The kept Jacobian if it was taken at exactly `s`.
    pub(crate) fn at(&self, s: &[f64]) -> Option<Vec<f64>> {
        self.0
            .borrow()
            .as_ref()
            .filter(|(at, _)| at.as_slice() == s)
            .map(|(_, dp)| dp.clone())
    }
}

/// Chord steps on the plain stride map after the solver converged on the variational one.
const MAX_POLISH: usize = 4;

/// Up to [`MAX_POLISH`] chord steps `s ← s − (DP − I)⁻¹(P(s) − s)` on a plain map with a fixed
/// `dp` (row-major), from `last` with its evaluation `eval_last` (image `image(eval_last)`) and
/// residual `residual`, while `residual > tol · σ(s)`; a step is kept only if it lowers the
/// residual. `eval(s)` gives the evaluation at `s` and its residual (None: the map failed).
/// Returns the number of steps kept (their residuals are appended to `history`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn chord_polish<T>(
    dp: &[f64],
    tol: f64,
    last: &mut Vec<f64>,
    eval_last: &mut T,
    residual: &mut f64,
    history: &mut Vec<f64>,
    image: impl Fn(&T) -> &Vec<f64>,
    eval: impl Fn(&[f64]) -> Option<(T, f64)>,
) -> u64 {
    let n = last.len();
    if !residual.is_finite() || *residual <= tol * residual_scale(last) || dp.len() != n * n {
        return 0;
    }
    let jac = Mat::from_fn(n, n, |i, k| dp[i * n + k] - if i == k { 1.0 } else { 0.0 });
    let lu = jac.partial_piv_lu();
    let mut kept = 0;
    for _ in 0..MAX_POLISH {
        let rhs = Mat::<f64>::from_fn(n, 1, |i, _| last[i] - image(eval_last)[i]);
        let delta = lu.solve(&rhs);
        let trial: Vec<f64> = (0..n).map(|i| last[i] + delta[(i, 0)]).collect();
        let Some((e, r)) = eval(&trial) else { break };
        if r.is_nan() || r >= *residual {
            break;
        }
        (*last, *eval_last, *residual) = (trial, e, r);
        history.push(r);
        kept += 1;
        if r <= tol * residual_scale(last) {
            break;
        }
    }
    kept
}

/// Default [`NewtonOptions::min_step_length`]: a millionth of a leg.
pub const MIN_STEP_LENGTH: f64 = 1e-6;

/// The scale `σ(s) = min(1, ‖s‖∞)` of the relative convergence test (see the module docs).
pub fn residual_scale(s: &[f64]) -> f64 {
    norm_inf(s).min(1.0)
}

impl Default for NewtonOptions {
    fn default() -> Self {
        Self {
            tol: 1e-12,
            max_iters: 40,
            max_backtracks: 30,
            dp: DpMethod::Variational,
            dp_report: DpMethod::Variational,
            min_step_length: MIN_STEP_LENGTH,
        }
    }
}

/// The argmin problem `F(s) = P(s) − s` with Jacobian `DP(s) − I`.
///
/// With [`DpMethod::Variational`] every evaluation of `F` integrates the variational equations
/// once: one integration gives both `P(s)` (the state part, under error control together with
/// the tangent block) and `DP(s)`, which is kept for the Jacobian at that same `s` (the Newton
/// step from an accepted point, and the multipliers of the converged point, cost no extra
/// integration). The plain stride map `P` decides acceptance in [`find_fixed_point`].
pub struct FixedPointProblem<'m, 'a> {
    pub map: &'m StrideMap<'a>,
    pub dp: DpMethod,
    /// `DP(s)` of the last variational evaluation of `F`.
    kept: KeptJacobian,
}

impl<'m, 'a> FixedPointProblem<'m, 'a> {
    /// The problem on `map` with the Jacobian from `dp`.
    pub fn new(map: &'m StrideMap<'a>, dp: DpMethod) -> Self {
        Self {
            map,
            dp,
            kept: KeptJacobian::default(),
        }
    }

    /// The `DP` kept from the variational evaluation of `F` at exactly `s`, if the last one
    /// was there.
    pub fn kept_at(&self, s: &[f64]) -> Option<Vec<f64>> {
        self.kept.at(s)
    }

    /// `DP(s)` (row-major) by the configured method (the one kept from the evaluation of `F`
    /// at exactly this `s`, if there was one).
    pub fn dp(&self, s: &[f64]) -> Result<Vec<f64>, LimitError> {
        if let Some(dp) = self.kept_at(s) {
            return Ok(dp);
        }
        match self.dp {
            DpMethod::Variational => Ok(dp_variational(self.map, s)?.1),
            DpMethod::FiniteDifference { scheme, lanes } => {
                dp_finite_difference(self.map, s, scheme, lanes)
            }
        }
    }
}

impl Operator for FixedPointProblem<'_, '_> {
    type Param = Vec<f64>;
    type Output = Vec<f64>;

    fn apply(&self, s: &Vec<f64>) -> Result<Vec<f64>, ArgminError> {
        let p = match self.dp {
            DpMethod::Variational => {
                let (stride, dp) = dp_variational_with(self.map, s, ErrorControl::State)?;
                self.kept.keep(s, dp);
                stride.next
            }
            DpMethod::FiniteDifference { .. } => self.map.apply(s)?,
        };
        Ok(p.iter().zip(s).map(|(a, b)| a - b).collect())
    }
}

impl Jacobian for FixedPointProblem<'_, '_> {
    type Param = Vec<f64>;
    type Jacobian = Mat<f64>;

    fn jacobian(&self, s: &Vec<f64>) -> Result<Mat<f64>, ArgminError> {
        let n = s.len();
        let dp = self.dp(s)?;
        Ok(Mat::from_fn(n, n, |i, j| {
            dp[i * n + j] - if i == j { 1.0 } else { 0.0 }
        }))
    }
}

/// argmin state used by [`Newton`]: parameter `Vec<f64>`, Jacobian `Mat<f64>`, residuals
/// `F(s)` as `Vec<f64>`, cost `‖F‖∞`.
pub type NewtonState = IterState<Vec<f64>, (), Mat<f64>, (), Vec<f64>, f64>;

/// What an argmin run of [`Newton`] left: its iterations, the termination's text, the solver's
/// residual history and the best (else the last) iterate, `guess` when there is none.
pub(crate) struct RunEnd {
    pub iterations: u64,
    /// The solver's own convergence test passed.
    pub converged: bool,
    pub termination: String,
    pub history: Vec<f64>,
    pub last: Vec<f64>,
}

impl RunEnd {
    /// The end of run `res`, started from `guess`.
    pub(crate) fn of<O>(
        res: &argmin::core::OptimizationResult<O, Newton, NewtonState>,
        guess: &[f64],
    ) -> Self {
        let state = res.state();
        RunEnd {
            iterations: state.get_iter(),
            converged: state.get_termination_reason() == Some(&TerminationReason::SolverConverged),
            termination: state
                .get_termination_reason()
                .map(|r| r.text().to_string())
                .unwrap_or_else(|| "not terminated".into()),
            history: res.solver().history.clone(),
            last: state
                .get_best_param()
                .or(state.get_param())
                .cloned()
                .unwrap_or_else(|| guess.to_vec()),
        }
    }
}

/// Damped Newton solver for square systems (see the module docs).
#[derive(Clone, Debug)]
pub struct Newton {
    tol: f64,
    max_backtracks: usize,
    /// `‖F‖∞` at the initial point and after every iteration.
    pub history: Vec<f64>,
    exit: Option<String>,
}

impl Newton {
    /// Solver with target `‖F‖∞ ≤ tol` and at most `max_backtracks` halvings per step.
    pub fn new(tol: f64, max_backtracks: usize) -> Result<Self, LimitError> {
        if !(tol.is_finite() && tol > 0.0) {
            return Err(LimitError::InvalidOption {
                name: "tol",
                value: tol,
                allowed: "finite and > 0",
            });
        }
        Ok(Self {
            tol,
            max_backtracks,
            history: Vec::new(),
            exit: None,
        })
    }
}

fn norm_inf(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

fn norm2(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

impl<O> Solver<O, NewtonState> for Newton
where
    O: Operator<Param = Vec<f64>, Output = Vec<f64>>
        + Jacobian<Param = Vec<f64>, Jacobian = Mat<f64>>,
{
    fn name(&self) -> &str {
        "Newton (LU, backtracking on ‖F‖₂)"
    }

    fn init(
        &mut self,
        problem: &mut Problem<O>,
        state: NewtonState,
    ) -> Result<(NewtonState, Option<KV>), ArgminError> {
        let x = state
            .get_param()
            .cloned()
            .ok_or_else(|| ArgminError::msg("Newton needs an initial parameter"))?;
        let f = problem.apply(&x)?;
        let c = norm_inf(&f);
        self.history.push(c);
        Ok((state.residuals(f).cost(c), None))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        mut state: NewtonState,
    ) -> Result<(NewtonState, Option<KV>), ArgminError> {
        if pdw_hybrid::interrupt::requested() {
            return Err(LimitError::interrupted().into());
        }
        let x = state.take_param().expect("param set in init");
        let f = state.take_residuals().expect("residuals set in init");
        let n = x.len();
        let j = problem.jacobian(&x)?;
        let rhs = Mat::<f64>::from_fn(n, 1, |i, _| -f[i]);
        let delta = j.partial_piv_lu().solve(&rhs);
        let delta: Vec<f64> = (0..n).map(|i| delta[(i, 0)]).collect();
        if delta.iter().any(|v| !v.is_finite()) {
            self.exit = Some("DP − I is singular (non-finite Newton step)".into());
            let c = norm_inf(&f);
            return Ok((state.param(x).residuals(f).cost(c).jacobian(j), None));
        }
        let f2 = norm2(&f);
        let mut lambda = 1.0;
        for _ in 0..=self.max_backtracks {
            let trial: Vec<f64> = x.iter().zip(&delta).map(|(a, b)| a + lambda * b).collect();
            if let Ok(ft) = problem.apply(&trial) {
                if ft.iter().all(|v| v.is_finite()) && norm2(&ft) <= (1.0 - 1e-4 * lambda) * f2 {
                    let c = norm_inf(&ft);
                    self.history.push(c);
                    let kv = argmin::kv!("lambda" => lambda;);
                    return Ok((
                        state.param(trial).residuals(ft).cost(c).jacobian(j),
                        Some(kv),
                    ));
                }
            }
            lambda *= 0.5;
        }
        self.exit = Some(format!(
            "line search failed: no decrease of ‖P(s)−s‖ after {} step halvings",
            self.max_backtracks
        ));
        let c = norm_inf(&f);
        Ok((state.param(x).residuals(f).cost(c).jacobian(j), None))
    }

    fn terminate(&mut self, state: &NewtonState) -> TerminationStatus {
        if let Some(msg) = &self.exit {
            return TerminationStatus::Terminated(TerminationReason::SolverExit(msg.clone()));
        }
        let scale = state.get_param().map_or(1.0, |x| residual_scale(x));
        if state.get_cost() <= self.tol * scale {
            return TerminationStatus::Terminated(TerminationReason::SolverConverged);
        }
        TerminationStatus::NotTerminated
    }
}

/// A verified period-one gait.
#[derive(Clone, Debug, PartialEq)]
pub struct FixedPoint {
    /// Section coordinates `s*` (in `section_names` order).
    pub section: Vec<f64>,
    /// Full post-reset state `L(s*)` (in the model's state order).
    pub state: Vec<f64>,
    /// Period, step length, speed.
    pub metrics: GaitMetrics,
    /// `DP(s*)`, row-major `d_s × d_s`.
    pub dp: Vec<f64>,
    /// Floquet multipliers, by decreasing modulus.
    pub multipliers: Vec<Multiplier>,
    /// All |λ| < 1.
    pub stable: bool,
    /// Independently re-computed `‖P(s*) − s*‖∞`.
    pub residual: f64,
    /// Newton iterations.
    pub iterations: u64,
    /// argmin's termination reason.
    pub termination: String,
    /// `‖P(s) − s‖∞` at the guess and after every iteration.
    pub residual_history: Vec<f64>,
}

/// Finds a fixed point of `map` from `guess`, verifies it, and measures it (multipliers,
/// period, step length, speed).
pub fn find_fixed_point(
    map: &StrideMap<'_>,
    guess: &[f64],
    opts: &NewtonOptions,
) -> Result<FixedPoint, LimitError> {
    map.check_dim(guess)?;
    let res = run_newton(map, guess, opts)?;
    let RunEnd {
        mut iterations,
        converged,
        termination,
        mut history,
        mut last,
    } = RunEnd::of(&res, guess);
    // The iterates collapsed towards the standing state s = 0 (a level floor has no gait).
    let shrunk = norm_inf(&last) < 0.25 * norm_inf(guess);
    // Independent check on the plain stride map, with a fresh integrator.
    let mut check = match map.stride(&last) {
        Ok(c) => c,
        Err(e) if shrunk => {
            let why = e.to_string();
            return Err(collapsed(guess, why, &last, iterations, &history));
        }
        Err(e) => return Err(e),
    };
    let mut residual = plain_residual(&check, &last);
    // The solver converged on the variational integration's map, the plain map's bit for bit
    // unless the model's one-pass flow differs from its flow; where that makes the residual
    // exceed `tol`, chord steps on the plain map with the DP kept at the last iterate finish
    // the job.
    // Only after the solver converged: an iteration limit stays a failure.
    if let Some(dp) = res
        .problem
        .problem
        .as_ref()
        .filter(|_| converged)
        .and_then(|p| p.kept_at(&last))
    {
        iterations += chord_polish(
            &dp,
            opts.tol,
            &mut last,
            &mut check,
            &mut residual,
            &mut history,
            |c| &c.next,
            |s| {
                let c = map.stride(s).ok()?;
                let r = plain_residual(&c, s);
                Some((c, r))
            },
        );
    }
    let accepted = residual.is_finite() && residual <= opts.tol * residual_scale(&last);
    let step = check
        .outcome
        .is_ok()
        .then_some(check.step_length)
        .flatten()
        .map(f64::abs);
    if let Some(l) = step.filter(|l| l.is_nan() || *l < opts.min_step_length) {
        return Err(LimitError::NoConvergence {
            reason: format!(
                "degenerate gait: the iterate's step length is {l:.3e}, below {:e}; steps that \
                 short are not resolved as a gait (on a level or near-level floor a passive \
                 walker stops; a model can have steps that short, e.g. a rimless wheel with very \
                 many spokes; or the integrator is too coarse to follow the stride)",
                opts.min_step_length
            ),
            iterations,
            last,
            history,
        });
    }
    if !accepted {
        // Say so when the iterates were shrinking towards standing still (no gait exists).
        let reason = match shrinking_steps(map, guess, step) {
            Some((g, l)) => format!(
                "degenerate: the iterates shrink towards standing still (step length {g:.3e} at \
                 the guess, {l:.3e} at the last iterate), so there is no gait to converge to \
                 ({termination})"
            ),
            None if shrunk => {
                return Err(collapsed(guess, termination, &last, iterations, &history))
            }
            None => termination,
        };
        return Err(LimitError::NoConvergence {
            reason,
            iterations,
            last,
            history,
        });
    }
    // DP at the converged point: kept from the solver's last evaluation when it was there and
    // by the same method, else computed.
    let dp = match res.problem.problem.as_ref() {
        Some(p) if p.dp == opts.dp_report => p.dp(&last)?,
        _ => FixedPointProblem::new(map, opts.dp_report).dp(&last)?,
    };
    let ds = last.len();
    let mult = multipliers(&dp, ds)?;
    Ok(FixedPoint {
        state: map.lift(&last),
        section: last,
        metrics: GaitMetrics::from_stride(&check),
        stable: is_stable(&mult),
        multipliers: mult,
        dp,
        residual,
        iterations,
        termination,
        residual_history: history,
    })
}

/// The argmin run of [`Newton`] on `map` from `guess`. A guess that gives no complete stride
/// (the run's init failed) is an error, named degenerate when the stride failed from an
/// iterate far smaller than the guess.
fn run_newton<'m, 'a>(
    map: &'m StrideMap<'a>,
    guess: &[f64],
    opts: &NewtonOptions,
) -> Result<OptimizationResult<FixedPointProblem<'m, 'a>, Newton, NewtonState>, LimitError> {
    let problem = FixedPointProblem::new(map, opts.dp);
    let solver = Newton::new(opts.tol, opts.max_backtracks)?;
    let guess_v = guess.to_vec();
    let run = Executor::new(problem, solver)
        .configure(|s| s.param(guess_v).max_iters(opts.max_iters))
        .timer(false)
        .run();
    if pdw_hybrid::interrupt::requested() {
        return Err(LimitError::interrupted());
    }
    match run {
        Ok(r) => Ok(r),
        Err(e) => {
            // The guess itself did not give a complete stride (init failed).
            Err(match e.downcast::<LimitError>() {
                // A stride from an iterate far smaller than the guess: the iterates collapsed
                // towards standing still (see "Degenerate gaits").
                Ok(LimitError::StrideFailed { from, outcome })
                    if norm_inf(&from) < 0.25 * norm_inf(guess) =>
                {
                    LimitError::NoConvergence {
                        reason: format!(
                            "degenerate: the iterates shrink towards standing still (‖s‖∞ from \
                             {:.3e} at the guess to {:.3e}, where the stride fails: {outcome}), \
                             so there is no gait to converge to",
                            norm_inf(guess),
                            norm_inf(&from)
                        ),
                        iterations: 0,
                        last: from,
                        history: Vec::new(),
                    }
                }
                Ok(le) => le,
                Err(e) => LimitError::NoConvergence {
                    reason: e.to_string(),
                    iterations: 0,
                    last: guess.to_vec(),
                    history: Vec::new(),
                },
            })
        }
    }
}

/// The error of a run whose iterates collapsed towards the standing state `s = 0` (a level
/// floor has no gait): from `guess` to `last`, after `iterations`, failing for `why`.
fn collapsed(
    guess: &[f64],
    why: String,
    last: &[f64],
    iterations: u64,
    history: &[f64],
) -> LimitError {
    LimitError::NoConvergence {
        reason: format!(
            "degenerate: the iterates shrink towards standing still (‖s‖∞ from {:.3e} at \
             the guess to {:.3e}), so there is no gait to converge to ({why})",
            norm_inf(guess),
            norm_inf(last)
        ),
        iterations,
        last: last.to_vec(),
        history: history.to_vec(),
    }
}

/// `‖P(s) − s‖∞` of the plain stride `c` from `s`; infinite when the stride did not complete.
fn plain_residual(c: &crate::stride::Stride, s: &[f64]) -> f64 {
    if c.outcome.is_ok() {
        c.next
            .iter()
            .zip(s)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
    } else {
        f64::INFINITY
    }
}

/// The step lengths `(at the guess, at the last iterate)` when the last iterate's `step` is
/// under a quarter of the guess's: the iterates were shrinking towards standing still.
fn shrinking_steps(map: &StrideMap<'_>, guess: &[f64], step: Option<f64>) -> Option<(f64, f64)> {
    let at_guess = map
        .stride(guess)
        .ok()
        .filter(|g| g.outcome.is_ok())
        .and_then(|g| g.step_length)
        .map(f64::abs);
    match (at_guess, step) {
        (Some(g), Some(l)) if l < 0.25 * g => Some((g, l)),
        _ => None,
    }
}
