//! Continuation of fixed-point branches of the stride map in one model parameter μ (the slope by
//! default), bifurcation detection and location, and branch switching at period doublings.
//!
//! # The extended system
//! A period-k orbit is a fixed point of `P^k`: `G(s, μ) = P^k(s; μ) − s = 0`, `n = d_s`
//! equations in the `n + 1` unknowns `y = (s, μ)`. Its Jacobian `[DP^k − I | G_μ]` (n × (n+1))
//! uses `DP^k = DP(s_{k−1}) ⋯ DP(s_0)` from the variational equations
//! ([`crate::dp_variational_with`], step sizes set by the state alone, so that `G` itself is the
//! plain stride map's, bit for bit, like the fixed points of [`crate::find_fixed_point`]) and
//! `G_μ = (P^k(s; μ+h) − P^k(s; μ−h)) / 2h` by central differences on μ (the model is rebuilt at
//! μ ± h by the caller's model family).
//!
//! # Corrector
//! Newton on the square system `[G(y); c·y − σ] = 0` with the Jacobian `[[DP^k − I, G_μ]; cᵀ]`
//! (Keller 1977; Allgower & Georg, "Numerical Continuation Methods", 1990, ch. 2):
//! - natural-parameter continuation: `c = e_μ` (μ fixed, s corrected);
//! - pseudo-arclength: `c = t_a` (unit tangent at the previous point `y_a`), `σ = t_a·y_a + Δs`.
//!
//! The tangent at a point is the unit null vector of `[DP^k − I | G_μ]`, from
//! `[[DP^k − I, G_μ]; t_prevᵀ] t = e_{n+1}`, oriented so that `t·t_prev > 0`. Coordinates are not
//! scaled: `Δs` is measured in the plain Euclidean norm of `(s, μ)`.
//!
//! # Step-size control
//! A step is accepted when Newton converges (‖G‖∞ ≤ `newton_tol`) within `max_newton` iterations
//! and the tangent turns by less than `max_turn` (cos t_a·t_b ≥ cos max_turn); then Δs grows by
//! 1.5 (≤ 2 Newton iterations) or 1.2 (≤ 4), or shrinks by 0.7 (≥ 7), within `[ds_min, ds_max]`. A
//! rejected step halves Δs; below `ds_min` the branch ends with a typed [`BranchEnd`].
//! Natural continuation cannot pass a fold: when it fails there and the last point has a real
//! multiplier near +1, the end is [`BranchEnd::FoldSuspected`].
//!
//! # Test functions (evaluated on the multipliers λ_i of DP^k at every point)
//! - period doubling: `ψ_PD = det(DP^k + I) = Π (λ_i + 1)` — changes sign when a real multiplier
//!   crosses −1 (a complex pair contributes |λ + 1|² > 0);
//! - fold: the μ-component of the tangent changes sign (the parameter turns); along the way
//!   `det(DP^k − I)` changes sign too (a real multiplier crosses +1). A sign change of
//!   `det(DP^k − I)` *without* a turn is reported as a [`BifurcationKind::BranchPoint`];
//! - Neimark–Sacker: `ψ_NS = Π_{i<j} (λ_i λ_j − 1)` (the bialternate-product determinant,
//!   Kuznetsov, "Elements of Applied Bifurcation Theory", §10.2) — a sign change with a complex
//!   pair of modulus 1 at the located point.
//!
//! A sign change between two accepted points is located by the Illinois variant of regula falsi
//! on the constraint value σ between them (each evaluation is one corrector solve), until the
//! bracket in μ is below `locate_tol` or the test function vanishes.
//!
//! # Branch switching at a period doubling
//! At a period doubling of the period-k branch, the period-2k branch leaves the period-k branch
//! (both are fixed points of `P^{2k}`) along `(v, 0)`, with `v` the eigenvector of `DP^k` for
//! the multiplier −1 (computed by inverse iteration). [`switch_period_doubling`] corrects the
//! predictor `y_PD + ε (v, 0)` on `G_{2k} = 0` with the constraint `v·(s − s_PD) = ε`, checks that
//! the result is not a period-k point, and continues the new branch by pseudo-arclength.
//!
//! # Both ways from a point inside the range
//! [`continue_both_ways`] continues from the same corrected first point towards `mu_min` and
//! towards `mu_max` and joins the halves ([`join_halves`]): one branch in the direction
//! `opts.direction`, the start point once, every tangent along the joined order, the
//! bifurcations of both halves re-indexed into it.

use crate::error::LimitError;
use crate::family::{Built, ModelFamily};
use crate::floquet::{is_stable, multipliers, Multiplier};
use crate::jacobian::dp_variational_with;
use crate::stride::StrideMap;
use crate::variational::ErrorControl;
use pdw_hybrid::{Options, Section};
use std::fmt::Display;

/// Natural-parameter or pseudo-arclength continuation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContinuationMethod {
    /// μ stepped, s corrected (cannot pass folds).
    Natural,
    /// Keller's pseudo-arclength.
    PseudoArclength,
}

/// Options of [`continue_branch`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContinuationOptions {
    /// Integrator of every stride.
    pub integrator: Options,
    pub method: ContinuationMethod,
    /// Initial direction in μ: `+1.0` or `−1.0`.
    pub direction: f64,
    /// First step (arclength, or |Δμ| for natural continuation).
    pub ds_init: f64,
    pub ds_min: f64,
    pub ds_max: f64,
    /// Largest number of accepted points (the start point included).
    pub max_points: usize,
    /// The branch ends when μ leaves `[mu_min, mu_max]`.
    pub mu_min: f64,
    pub mu_max: f64,
    /// Newton tolerance on ‖P^k(s) − s‖∞.
    pub newton_tol: f64,
    /// Newton iterations per corrector solve.
    pub max_newton: usize,
    /// Central-difference step on μ for `G_μ`.
    pub dmu: f64,
    /// Largest turn of the tangent per step (radians).
    pub max_turn: f64,
    /// Detect and locate bifurcations.
    pub detect: bool,
    /// Location accuracy in μ.
    pub locate_tol: f64,
    /// Branch-switching offset ε along the −1 eigenvector (section units).
    pub switch_eps: f64,
    /// End the branch at the first located bifurcation of this kind
    /// ([`BranchEnd::Stopped`]); `None` to continue through all.
    pub stop_at: Option<BifurcationKind>,
}

impl ContinuationOptions {
    /// Defaults for a parameter range `[mu_min, mu_max]`: pseudo-arclength, DOP853 at 1e-13,
    /// Δs ∈ [1e-9, 1e-2] starting at 1e-3, Newton tolerance 1e-11 in ≤ 10 iterations, `dmu = 1e-6`,
    /// location to 1e-10 in μ, at most 2000 points, max turn 0.3 rad, ε = 1e-3.
    pub fn new(mu_min: f64, mu_max: f64) -> Self {
        Self {
            integrator: Options::dop853(1e-13),
            method: ContinuationMethod::PseudoArclength,
            direction: 1.0,
            ds_init: 1e-3,
            ds_min: 1e-9,
            ds_max: 1e-2,
            max_points: 2000,
            mu_min,
            mu_max,
            newton_tol: 1e-11,
            max_newton: 10,
            dmu: 1e-6,
            max_turn: 0.3,
            detect: true,
            locate_tol: 1e-10,
            switch_eps: 1e-3,
            stop_at: None,
        }
    }

    fn validate(&self) -> Result<(), LimitError> {
        let bad = |name, value: f64, allowed| {
            Err(LimitError::InvalidOption {
                name,
                value,
                allowed,
            })
        };
        self.integrator.validate()?;
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !(self.direction == 1.0 || self.direction == -1.0) {
            return bad("direction", self.direction, "must be +1 or -1");
        }
        if !(pos(self.ds_min)
            && self.ds_min <= self.ds_init
            && self.ds_init <= self.ds_max
            && self.ds_max.is_finite())
        {
            return bad(
                "ds_init",
                self.ds_init,
                "need finite 0 < ds_min <= ds_init <= ds_max",
            );
        }
        if !(self.mu_min.is_finite() && self.mu_max.is_finite() && self.mu_min < self.mu_max) {
            return bad("mu_min", self.mu_min, "need finite mu_min < mu_max");
        }
        if self.max_points < 1 {
            return bad("max_points", 0.0, "must be >= 1");
        }
        if !pos(self.newton_tol) {
            return bad("newton_tol", self.newton_tol, "must be finite and > 0");
        }
        if self.max_newton < 1 {
            return bad("max_newton", 0.0, "must be >= 1");
        }
        if !pos(self.dmu) {
            return bad("dmu", self.dmu, "must be finite and > 0");
        }
        if !(pos(self.max_turn) && self.max_turn < std::f64::consts::PI) {
            return bad("max_turn", self.max_turn, "must be in (0, pi)");
        }
        if !pos(self.locate_tol) {
            return bad("locate_tol", self.locate_tol, "must be finite and > 0");
        }
        if !pos(self.switch_eps) {
            return bad("switch_eps", self.switch_eps, "must be finite and > 0");
        }
        Ok(())
    }
}

/// One accepted point of a branch.
#[derive(Clone, Debug, PartialEq)]
pub struct BranchPoint {
    /// Parameter value μ.
    pub param: f64,
    /// Section state s (the first point of the orbit).
    pub section: Vec<f64>,
    /// The k section states of the orbit, `orbit[0] = section`.
    pub orbit: Vec<Vec<f64>>,
    /// Multipliers of `DP^k`, by decreasing modulus.
    pub multipliers: Vec<Multiplier>,
    /// Duration of the k strides.
    pub period: f64,
    /// All |λ| < 1.
    pub stable: bool,
    /// Unit tangent `(ds, dμ)` of the branch (n + 1 components).
    pub tangent: Vec<f64>,
    /// ‖P^k(s) − s‖∞.
    pub residual: f64,
    /// Newton iterations of the corrector.
    pub newton_iters: usize,
}

/// Kind of a detected bifurcation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BifurcationKind {
    /// A real multiplier crosses −1.
    PeriodDoubling,
    /// The branch turns in μ (a real multiplier crosses +1).
    Fold,
    /// A real multiplier crosses +1 without a turn (transcritical or pitchfork).
    BranchPoint,
    /// A complex pair crosses the unit circle.
    NeimarkSacker,
}

impl BifurcationKind {
    /// The kind's name in files, JSON and Python: `period_doubling`, `fold`, `branch_point`,
    /// `neimark_sacker`.
    pub fn name(self) -> &'static str {
        match self {
            BifurcationKind::PeriodDoubling => "period_doubling",
            BifurcationKind::Fold => "fold",
            BifurcationKind::BranchPoint => "branch_point",
            BifurcationKind::NeimarkSacker => "neimark_sacker",
        }
    }
}

/// A located bifurcation.
#[derive(Clone, Debug, PartialEq)]
pub struct Bifurcation {
    pub kind: BifurcationKind,
    /// Located parameter value.
    pub param: f64,
    /// Width in μ of the final bracket (the location uncertainty of the root of the test
    /// function; the integration error adds to it).
    pub param_bracket: f64,
    /// Section state at the located point.
    pub section: Vec<f64>,
    /// Multipliers of `DP^k` there.
    pub multipliers: Vec<Multiplier>,
    /// Test function value there.
    pub test_value: f64,
    /// The bifurcation lies between points `index − 1` and `index` of the branch.
    pub index: usize,
    /// Period k (strides) of the branch it was found on.
    pub period_strides: usize,
    /// `DP^k` (row-major) at the located point.
    pub dp: Vec<f64>,
}

/// Why a branch ended.
#[derive(Clone, Debug, PartialEq)]
pub enum BranchEnd {
    /// μ left `[mu_min, mu_max]` (the last point is the first one outside, kept).
    ParamBound { param: f64 },
    /// `max_points` points.
    MaxPoints,
    /// Natural continuation failed next to a point with a real multiplier near +1: a fold
    /// (turning point) is ahead, which only pseudo-arclength passes.
    FoldSuspected {
        /// Last converged μ.
        param: f64,
        /// The real multiplier closest to +1 there.
        multiplier: f64,
        reason: String,
    },
    /// A bifurcation of the kind [`ContinuationOptions::stop_at`] was located (the last point
    /// is the first one past it).
    Stopped { kind: BifurcationKind, param: f64 },
    /// The corrector failed with Δs at `ds_min` (a stride failed, Newton diverged, or the
    /// Jacobian was singular).
    CorrectorFailed { param: f64, reason: String },
}

/// Why a branch ended, in plain words for a console line: "the parameter left the range at
/// 0.0191", "the corrector failed after 0.0151: …".
impl std::fmt::Display for BranchEnd {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BranchEnd::ParamBound { param } => {
                write!(f, "the parameter left the range at {param}")
            }
            BranchEnd::MaxPoints => f.write_str("the branch reached the most points it may have"),
            BranchEnd::FoldSuspected {
                param,
                multiplier,
                reason,
            } => write!(
                f,
                "a fold is suspected after {param} (a multiplier at {multiplier:.6}, near +1): \
                 {reason}"
            ),
            BranchEnd::Stopped { kind, param } => {
                write!(f, "stopped at the {} at {param}", kind.name())
            }
            BranchEnd::CorrectorFailed { param, reason } => {
                write!(f, "the corrector failed after {param}: {reason}")
            }
        }
    }
}

/// A continued branch of period-k orbits.
#[derive(Clone, Debug, PartialEq)]
pub struct Branch {
    /// k: the branch consists of fixed points of `P^k`.
    pub period_strides: usize,
    pub points: Vec<BranchPoint>,
    pub bifurcations: Vec<Bifurcation>,
    pub end: BranchEnd,
}

// ---------------------------------------------------------------------------------------------
// Small dense linear algebra (n ≤ a few tens): Gaussian elimination with partial pivoting.
// ---------------------------------------------------------------------------------------------

/// Solve `a x = b` (row-major `m × m`), or `None` if singular / non-finite.
fn solve(m: usize, a: &[f64], b: &[f64]) -> Option<Vec<f64>> {
    let mut a = a.to_vec();
    let mut x = b.to_vec();
    for col in 0..m {
        let p = (col..m).max_by(|&i, &j| a[i * m + col].abs().total_cmp(&a[j * m + col].abs()))?;
        if a[p * m + col] == 0.0 || !a[p * m + col].is_finite() {
            return None;
        }
        if p != col {
            for j in 0..m {
                a.swap(p * m + j, col * m + j);
            }
            x.swap(p, col);
        }
        let piv = a[col * m + col];
        for i in col + 1..m {
            let f = a[i * m + col] / piv;
            if f != 0.0 {
                for j in col..m {
                    a[i * m + j] -= f * a[col * m + j];
                }
                x[i] -= f * x[col];
            }
        }
    }
    for i in (0..m).rev() {
        let mut acc = x[i];
        for j in i + 1..m {
            acc -= a[i * m + j] * x[j];
        }
        x[i] = acc / a[i * m + i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Determinant of a row-major `m × m` matrix.
fn det(m: usize, a: &[f64]) -> f64 {
    let mut a = a.to_vec();
    let mut d = 1.0;
    for col in 0..m {
        let p = (col..m)
            .max_by(|&i, &j| a[i * m + col].abs().total_cmp(&a[j * m + col].abs()))
            .unwrap_or(col);
        if a[p * m + col] == 0.0 {
            return 0.0;
        }
        if p != col {
            for j in 0..m {
                a.swap(p * m + j, col * m + j);
            }
            d = -d;
        }
        let piv = a[col * m + col];
        d *= piv;
        for i in col + 1..m {
            let f = a[i * m + col] / piv;
            for j in col..m {
                a[i * m + j] -= f * a[col * m + j];
            }
        }
    }
    d
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm_inf(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

fn normalize(v: &mut [f64]) {
    let n = dot(v, v).sqrt();
    for x in v.iter_mut() {
        *x /= n;
    }
}

/// `ψ_NS = Π_{i<j} (λ_i λ_j − 1)` (real for a real matrix).
fn ns_test(m: &[Multiplier]) -> f64 {
    let (mut re, mut im) = (1.0, 0.0);
    for i in 0..m.len() {
        for j in i + 1..m.len() {
            let (a, b) = (m[i], m[j]);
            let pr = a.re * b.re - a.im * b.im - 1.0;
            let pi = a.re * b.im + a.im * b.re;
            let nr = re * pr - im * pi;
            im = re * pi + im * pr;
            re = nr;
        }
    }
    re
}

// ---------------------------------------------------------------------------------------------
// The extended system.
// ---------------------------------------------------------------------------------------------

/// Everything known at a corrected point.
#[derive(Clone, Debug)]
struct Solved {
    y: Vec<f64>,
    /// `[DP^k − I | G_μ]`, row-major n × (n+1).
    jac: Vec<f64>,
    dp: Vec<f64>,
    orbit: Vec<Vec<f64>>,
    period: f64,
    residual: f64,
    iters: usize,
}

struct Ctx<'f, M: ?Sized> {
    family: &'f M,
    opts: ContinuationOptions,
    k: usize,
    n: usize,
}

impl<'f, 'm, M> Ctx<'f, M>
where
    M: ModelFamily<'m> + ?Sized,
{
    fn build(&self, mu: f64) -> Result<Box<dyn Built + 'm>, LimitError> {
        self.family
            .build(mu)
            .map_err(|message| LimitError::Model { param: mu, message })
    }

    /// `P^k(s; μ)` (scalar strides).
    fn iterate(&self, s: &[f64], mu: f64) -> Result<Vec<f64>, LimitError> {
        let model = self.build(mu)?;
        let map = StrideMap::new(model.section(), self.opts.integrator)?;
        let mut s = s.to_vec();
        for _ in 0..self.k {
            s = map.apply(&s)?;
        }
        Ok(s)
    }

    /// G, `[DP^k − I | G_μ]`, DP^k, orbit and period at `y = (s, μ)`.
    fn evaluate(&self, y: &[f64]) -> Result<(Vec<f64>, Solved), LimitError> {
        let n = self.n;
        let (s0, mu) = (&y[..n], y[n]);
        let model = self.build(mu)?;
        let map = StrideMap::new(model.section(), self.opts.integrator)?;
        let mut dp = vec![0.0; n * n];
        for i in 0..n {
            dp[i * n + i] = 1.0;
        }
        let mut s = s0.to_vec();
        let mut orbit = Vec::with_capacity(self.k);
        let mut period = 0.0;
        for _ in 0..self.k {
            orbit.push(s.clone());
            let (stride, d) = dp_variational_with(&map, &s, ErrorControl::State)?;
            let mut prod = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    prod[i * n + j] = (0..n).map(|l| d[i * n + l] * dp[l * n + j]).sum();
                }
            }
            dp = prod;
            period += stride.period;
            s = stride.next;
        }
        let g: Vec<f64> = s.iter().zip(s0).map(|(a, b)| a - b).collect();
        // G_μ by central differences; where the model cannot be built (or strided) on one side
        // — at the physical end of a parameter's range, e.g. a mass reaching 0 — by the
        // one-sided difference on the other (O(dmu) instead of O(dmu²))
        let h = self.opts.dmu;
        let (gp, gm) = (self.iterate(s0, mu + h), self.iterate(s0, mu - h));
        let (hi, lo, width) = match (gp, gm) {
            (Ok(p), Ok(m)) => (p, m, 2.0 * h),
            (Ok(p), Err(_)) => (p, s.clone(), h),
            (Err(_), Ok(m)) => (s.clone(), m, h),
            (Err(e), Err(_)) => return Err(e),
        };
        let mut jac = vec![0.0; n * (n + 1)];
        for i in 0..n {
            for j in 0..n {
                jac[i * (n + 1) + j] = dp[i * n + j] - if i == j { 1.0 } else { 0.0 };
            }
            jac[i * (n + 1) + n] = (hi[i] - lo[i]) / width;
        }
        let residual = norm_inf(&g);
        Ok((
            g,
            Solved {
                y: y.to_vec(),
                jac,
                dp,
                orbit,
                period,
                residual,
                iters: 0,
            },
        ))
    }

    /// Newton on `[G(y); c·y − sigma] = 0` from `y0`.
    fn correct(&self, y0: &[f64], c: &[f64], sigma: f64) -> Result<Solved, String> {
        let n = self.n;
        let m = n + 1;
        let mut y = y0.to_vec();
        let mut last_res = f64::INFINITY;
        for it in 0..=self.opts.max_newton {
            let (g, mut sol) = self.evaluate(&y).map_err(|e| e.to_string())?;
            let cres = dot(c, &y) - sigma;
            let scale = norm_inf(&y).max(1.0);
            if sol.residual <= self.opts.newton_tol && cres.abs() <= 1e-13 * scale {
                sol.iters = it;
                return Ok(sol);
            }
            if it == self.opts.max_newton {
                return Err(format!(
                    "Newton did not converge in {} iterations (‖G‖∞ = {:.3e})",
                    self.opts.max_newton, sol.residual
                ));
            }
            if it >= 2 && sol.residual > 2.0 * last_res {
                return Err(format!(
                    "Newton diverging at iteration {it} (‖G‖∞ {:.3e} after {:.3e})",
                    sol.residual, last_res
                ));
            }
            last_res = sol.residual;
            let mut a = sol.jac.clone();
            a.extend_from_slice(c);
            let mut rhs: Vec<f64> = g.iter().map(|v| -v).collect();
            rhs.push(-cres);
            let delta = solve(m, &a, &rhs)
                .ok_or_else(|| "singular extended Jacobian (fold or branch point)".to_string())?;
            for (yi, di) in y.iter_mut().zip(&delta) {
                *yi += di;
            }
        }
        unreachable!("the loop returns")
    }

    /// Unit null vector of `jac` oriented along `t_prev`.
    fn tangent(&self, jac: &[f64], t_prev: &[f64]) -> Option<Vec<f64>> {
        let m = self.n + 1;
        let mut a = jac.to_vec();
        a.extend_from_slice(t_prev);
        let mut rhs = vec![0.0; m];
        rhs[m - 1] = 1.0;
        let mut t = solve(m, &a, &rhs)?;
        normalize(&mut t);
        if dot(&t, t_prev) < 0.0 {
            t.iter_mut().for_each(|v| *v = -*v);
        }
        Some(t)
    }

    fn point(&self, sol: &Solved, tangent: Vec<f64>) -> Result<BranchPoint, LimitError> {
        let mult = multipliers(&sol.dp, self.n)?;
        Ok(BranchPoint {
            param: sol.y[self.n],
            section: sol.y[..self.n].to_vec(),
            orbit: sol.orbit.clone(),
            stable: is_stable(&mult),
            multipliers: mult,
            period: sol.period,
            tangent,
            residual: sol.residual,
            newton_iters: sol.iters,
        })
    }

    fn tests(&self, dp: &[f64], mult: &[Multiplier], tangent: &[f64]) -> [f64; 4] {
        let n = self.n;
        let mut a = dp.to_vec();
        let mut b = dp.to_vec();
        for i in 0..n {
            a[i * n + i] += 1.0;
            b[i * n + i] -= 1.0;
        }
        [det(n, &a), tangent[n], det(n, &b), ns_test(mult)]
    }

    /// Locate the root of test `which` between accepted points `a` and `b` (Illinois on σ).
    #[allow(clippy::too_many_arguments)]
    fn locate(
        &self,
        ya: &[f64],
        yb: &[f64],
        c: &[f64],
        t_ref: &[f64],
        which: usize,
        fa: f64,
        fb: f64,
    ) -> Result<(Solved, Vec<Multiplier>, f64, f64), String> {
        let n = self.n;
        let (sa, sb) = (dot(c, ya), dot(c, yb));
        let (mut lo, mut hi, mut flo, mut fhi) = (0.0f64, 1.0f64, fa, fb);
        let mut side = 0i32;
        let mut best: Option<(Solved, Vec<Multiplier>, f64)> = None;
        let mut mu_lo = ya[n];
        let mut mu_hi = yb[n];
        for _ in 0..100 {
            let w = if fhi != flo {
                (lo * fhi - hi * flo) / (fhi - flo)
            } else {
                0.5 * (lo + hi)
            };
            let w = if w > lo && w < hi { w } else { 0.5 * (lo + hi) };
            let pred: Vec<f64> = ya.iter().zip(yb).map(|(a, b)| a + w * (b - a)).collect();
            let sol = self.correct(&pred, c, sa + w * (sb - sa))?;
            let mult = multipliers(&sol.dp, n).map_err(|e| e.to_string())?;
            let tan = self
                .tangent(&sol.jac, t_ref)
                .ok_or_else(|| "singular tangent system during location".to_string())?;
            let f = self.tests(&sol.dp, &mult, &tan)[which];
            let mu = sol.y[n];
            if (f > 0.0) == (flo > 0.0) {
                lo = w;
                flo = f;
                mu_lo = mu;
                if side == -1 {
                    fhi *= 0.5;
                }
                side = -1;
            } else {
                hi = w;
                fhi = f;
                mu_hi = mu;
                if side == 1 {
                    flo *= 0.5;
                }
                side = 1;
            }
            let done = f == 0.0 || (mu_hi - mu_lo).abs() <= self.opts.locate_tol || hi - lo < 1e-15;
            best = Some((sol, mult, f));
            if done {
                break;
            }
        }
        let (sol, mult, f) = best.expect("at least one iteration");
        Ok((sol, mult, f, (mu_hi - mu_lo).abs()))
    }

    /// The predictor from the corrected point `cur` with tangent `t_cur` and step `ds`, with
    /// its constraint `c · y = sigma`: a step of `ds` in μ along the tangent at fixed-μ
    /// constraint (natural continuation), or a step of `ds` along the tangent on the
    /// pseudo-arclength constraint `t_cur · y = t_cur · y_cur + ds` (Keller 1977).
    fn predict(&self, cur: &Solved, t_cur: &[f64], ds: f64) -> (Vec<f64>, Vec<f64>, f64) {
        let n = self.n;
        let mu = cur.y[n];
        if self.opts.method == ContinuationMethod::Natural {
            let dmu = ds * t_cur[n].signum();
            let slope = 1.0 / t_cur[n];
            let pred: Vec<f64> = cur
                .y
                .iter()
                .zip(t_cur)
                .map(|(y, t)| y + t * slope * dmu)
                .collect();
            let mut c = vec![0.0; n + 1];
            c[n] = 1.0;
            (pred, c, mu + dmu)
        } else {
            let pred: Vec<f64> = cur.y.iter().zip(t_cur).map(|(y, t)| y + ds * t).collect();
            let sigma = dot(t_cur, &cur.y) + ds;
            (pred, t_cur.to_vec(), sigma)
        }
    }

    /// The corrected point from the predictor `pred` on the constraint `c · y = sigma`, with
    /// its tangent oriented along `t_cur`; an error when the tangent turned by more than
    /// `max_turn` (pseudo-arclength) or the parameter turned (natural: a fold between steps).
    fn step(
        &self,
        pred: &[f64],
        c: &[f64],
        sigma: f64,
        t_cur: &[f64],
    ) -> Result<(Solved, Vec<f64>), String> {
        let n = self.n;
        let natural = self.opts.method == ContinuationMethod::Natural;
        let cos_turn = self.opts.max_turn.cos();
        let sol = self.correct(pred, c, sigma)?;
        let t = self
            .tangent(&sol.jac, t_cur)
            .ok_or_else(|| "singular tangent system".to_string())?;
        if !natural && dot(&t, t_cur) < cos_turn {
            return Err(format!(
                "tangent turned by {:.3} rad (> max_turn)",
                dot(&t, t_cur).clamp(-1.0, 1.0).acos()
            ));
        }
        if natural && t[n].signum() != t_cur[n].signum() {
            return Err("the parameter turned (fold) between natural steps".to_string());
        }
        Ok((sol, t))
    }

    /// The bifurcations between the accepted points `ya` and `yb` (constraint `c`, tangent
    /// `t_ref`) where a test function changes sign (`psi`: the tests at both), each located
    /// (see [`Self::locate`]) and numbered `index`. A sign change of the Neimark–Sacker test
    /// without a complex pair on the unit circle is a neutral saddle and is dropped.
    fn detect(
        &self,
        ya: &[f64],
        yb: &[f64],
        c: &[f64],
        t_ref: &[f64],
        psi: (&[f64; 4], &[f64; 4]),
        index: usize,
    ) -> Vec<Bifurcation> {
        let n = self.n;
        let natural = self.opts.method == ContinuationMethod::Natural;
        let (psi, psi_new) = psi;
        let sign_change = |i: usize| (psi[i] > 0.0) != (psi_new[i] > 0.0) && psi[i] != 0.0;
        let mut found: Vec<(BifurcationKind, usize)> = Vec::new();
        if sign_change(0) {
            found.push((BifurcationKind::PeriodDoubling, 0));
        }
        if !natural && sign_change(1) {
            found.push((BifurcationKind::Fold, 1));
        } else if sign_change(2) {
            found.push((BifurcationKind::BranchPoint, 2));
        }
        if sign_change(3) {
            found.push((BifurcationKind::NeimarkSacker, 3));
        }
        let mut bifs = Vec::new();
        for (kind, which) in found {
            let located = self.locate(ya, yb, c, t_ref, which, psi[which], psi_new[which]);
            let Ok((lsol, lmult, f, bracket)) = located else {
                continue;
            };
            if kind == BifurcationKind::NeimarkSacker {
                let pair = lmult
                    .iter()
                    .any(|m| m.im.abs() > 1e-8 && (m.modulus() - 1.0).abs() < 1e-4);
                if !pair {
                    continue; // a neutral saddle (λ_i λ_j = 1 with real λ), not a bifurcation
                }
            }
            bifs.push(Bifurcation {
                kind,
                param: lsol.y[n],
                param_bracket: bracket,
                section: lsol.y[..n].to_vec(),
                multipliers: lmult,
                test_value: f,
                index,
                period_strides: self.k,
                dp: lsol.dp.clone(),
            });
        }
        bifs
    }
}

fn check_start(s: &[f64], model: &dyn Section) -> Result<(), LimitError> {
    if s.len() != model.section_dim() {
        return Err(LimitError::SectionDim {
            expected: model.section_dim(),
            got: s.len(),
        });
    }
    Ok(())
}

/// Continue the branch of period-`period_strides` orbits through the guess `s0` at `mu0`
/// (first corrected at fixed μ), in the direction `opts.direction`, until μ leaves
/// `[mu_min, mu_max]`, `max_points` points, or a failure (see [`BranchEnd`]).
///
/// `family(μ)` builds the model at parameter value μ (e.g.
/// `|g| pdw_walkers::build("simplest", &[("slope", g)])`).
pub fn continue_branch<S, E, F>(
    family: &F,
    s0: &[f64],
    mu0: f64,
    period_strides: usize,
    opts: &ContinuationOptions,
) -> Result<Branch, LimitError>
where
    S: Section + ?Sized,
    E: Display,
    F: Fn(f64) -> Result<Box<S>, E>,
{
    continue_erased(family, s0, mu0, period_strides, opts)
}

/// [`continue_branch`] on the erased family.
fn continue_erased<'m>(
    family: &dyn ModelFamily<'m>,
    s0: &[f64],
    mu0: f64,
    period_strides: usize,
    opts: &ContinuationOptions,
) -> Result<Branch, LimitError> {
    opts.validate()?;
    if period_strides == 0 {
        return Err(LimitError::InvalidOption {
            name: "period_strides",
            value: 0.0,
            allowed: "must be >= 1",
        });
    }
    let ctx = Ctx {
        family,
        opts: *opts,
        k: period_strides,
        n: s0.len(),
    };
    check_start(s0, ctx.build(mu0)?.section())?;
    let n = ctx.n;
    let mut y0 = s0.to_vec();
    y0.push(mu0);
    let mut e_mu = vec![0.0; n + 1];
    e_mu[n] = 1.0;
    let first = ctx
        .correct(&y0, &e_mu, mu0)
        .map_err(|reason| LimitError::NoConvergence {
            reason,
            iterations: opts.max_newton as u64,
            last: s0.to_vec(),
            history: Vec::new(),
        })?;
    let mut t_dir = e_mu.clone();
    t_dir[n] = opts.direction;
    let t0 = ctx
        .tangent(&first.jac, &t_dir)
        .ok_or(LimitError::Singular {
            at: first.y[..n].to_vec(),
        })?;
    run_branch(&ctx, first, t0, None)
}

/// The continuation loop from a corrected point `first` with tangent `t0`.
fn run_branch<'m>(
    ctx: &Ctx<'_, dyn ModelFamily<'m> + '_>,
    first: Solved,
    t0: Vec<f64>,
    prefix: Option<BranchPoint>,
) -> Result<Branch, LimitError> {
    let opts = ctx.opts;
    let n = ctx.n;
    let natural = opts.method == ContinuationMethod::Natural;
    let mut points: Vec<BranchPoint> = prefix.into_iter().collect();
    let mut bifs = Vec::new();
    let mut cur = first;
    let mut t_cur = t0;
    let p0 = ctx.point(&cur, t_cur.clone())?;
    let mut psi = ctx.tests(&cur.dp, &p0.multipliers, &t_cur);
    points.push(p0);
    let mut ds = opts.ds_init;
    let end = loop {
        if points.len() >= opts.max_points {
            break BranchEnd::MaxPoints;
        }
        let mu = cur.y[n];
        if mu < opts.mu_min || mu > opts.mu_max {
            break BranchEnd::ParamBound { param: mu };
        }
        let (pred, c, sigma) = ctx.predict(&cur, &t_cur, ds);
        let (sol, t_new) = match ctx.step(&pred, &c, sigma, &t_cur) {
            Ok(v) => v,
            Err(reason) => {
                // A step that fails beyond the range's end (where the model may not even be
                // built, e.g. a mass that becomes negative past it) ends the branch at the end
                // itself when the point there corrects: the range is covered to its end.
                if let Some(end) = end_point(ctx, &cur, &t_cur, pred[n]) {
                    let param = end.0.y[n];
                    points.push(ctx.point(&end.0, end.1)?);
                    break BranchEnd::ParamBound { param };
                }
                ds *= 0.5;
                if ds < opts.ds_min {
                    let last = points.last().expect("at least the first point");
                    break failed_end(last, natural, mu, reason);
                }
                continue;
            }
        };
        let pt = ctx.point(&sol, t_new.clone())?;
        let psi_new = ctx.tests(&sol.dp, &pt.multipliers, &t_new);
        let index = points.len();
        if opts.detect {
            bifs.extend(ctx.detect(&cur.y, &sol.y, &c, &t_cur, (&psi, &psi_new), index));
        }
        let iters = sol.iters;
        cur = sol;
        t_cur = t_new;
        psi = psi_new;
        points.push(pt);
        if let Some(kind) = opts.stop_at {
            if let Some(b) = bifs.iter().find(|b| b.kind == kind && b.index == index) {
                break BranchEnd::Stopped {
                    kind,
                    param: b.param,
                };
            }
        }
        ds = adapted_step(ds, iters, &opts);
    };
    Ok(Branch {
        period_strides: ctx.k,
        points,
        bifurcations: bifs,
        end,
    })
}

/// How a branch ends when its step size fell below `ds_min` at parameter `mu` after the
/// corrector failed for `reason`: a suspected fold when natural continuation stopped with a
/// real multiplier of the `last` point within 0.1 of +1 (the parameter cannot pass a fold),
/// else the corrector's failure.
fn failed_end(last: &BranchPoint, natural: bool, mu: f64, reason: String) -> BranchEnd {
    let near_one = last
        .multipliers
        .iter()
        .filter(|m| m.im == 0.0)
        .map(|m| m.re)
        .min_by(|a, b| (a - 1.0).abs().total_cmp(&(b - 1.0).abs()));
    match near_one {
        Some(l) if natural && (l - 1.0).abs() < 0.1 => BranchEnd::FoldSuspected {
            param: mu,
            multiplier: l,
            reason,
        },
        _ => BranchEnd::CorrectorFailed { param: mu, reason },
    }
}

/// The next step size after a step whose corrector took `iters` iterations: grown after a
/// quick convergence, shrunk after a slow one, within `[ds_min, ds_max]`.
fn adapted_step(ds: f64, iters: usize, opts: &ContinuationOptions) -> f64 {
    if iters <= 2 {
        (ds * 1.5).min(opts.ds_max)
    } else if iters <= 4 {
        (ds * 1.2).min(opts.ds_max)
    } else if iters >= 7 {
        (ds * 0.7).max(opts.ds_min)
    } else {
        ds
    }
}

/// Where a step predicted to parameter `mu_pred` beyond the range `[mu_min, mu_max]` failed:
/// the point at the range's end it crossed, corrected at that parameter (natural constraint)
/// from the current point `cur` moved along its tangent `t` to it, with its tangent; `None`
/// when `mu_pred` is inside the range, `cur` is at the end already, or the point does not
/// correct.
fn end_point<'m>(
    ctx: &Ctx<'_, dyn ModelFamily<'m> + '_>,
    cur: &Solved,
    t: &[f64],
    mu_pred: f64,
) -> Option<(Solved, Vec<f64>)> {
    let (opts, n) = (&ctx.opts, ctx.n);
    let mu = cur.y[n];
    let bound = if mu_pred > opts.mu_max {
        opts.mu_max
    } else if mu_pred < opts.mu_min {
        opts.mu_min
    } else {
        return None;
    };
    if mu == bound || t[n] == 0.0 || !(opts.mu_min..=opts.mu_max).contains(&mu) {
        return None;
    }
    let along = (bound - mu) / t[n];
    let pred: Vec<f64> = cur.y.iter().zip(t).map(|(y, ti)| y + ti * along).collect();
    let mut c = vec![0.0; n + 1];
    c[n] = 1.0;
    let sol = ctx.correct(&pred, &c, bound).ok()?;
    let t_end = ctx.tangent(&sol.jac, t)?;
    Some((sol, t_end))
}

/// Eigenvector of `dp` (row-major n × n) for the real eigenvalue closest to `lambda`, by inverse
/// iteration with the shift `lambda` (nudged when exactly singular); unit 2-norm.
pub fn real_eigenvector(dp: &[f64], n: usize, lambda: f64) -> Option<Vec<f64>> {
    let mut v = vec![1.0; n];
    normalize(&mut v);
    let mut shift = lambda;
    for _ in 0..8 {
        let mut a = dp.to_vec();
        for i in 0..n {
            a[i * n + i] -= shift;
        }
        match solve(n, &a, &v) {
            Some(mut w) => {
                normalize(&mut w);
                let same = dot(&w, &v).abs();
                v = w;
                if same > 1.0 - 1e-15 {
                    break;
                }
            }
            None => shift += 1e-12 * lambda.abs().max(1.0),
        }
    }
    Some(v)
}

/// Switch from a period doubling of a period-k branch onto the period-2k branch and continue
/// it (see the module docs). `opts.direction` is ignored: the new branch is followed away from
/// the period-doubling point.
pub fn switch_period_doubling<S, E, F>(
    family: &F,
    bif: &Bifurcation,
    opts: &ContinuationOptions,
) -> Result<Branch, LimitError>
where
    S: Section + ?Sized,
    E: Display,
    F: Fn(f64) -> Result<Box<S>, E>,
{
    switch_erased(family, bif, opts)
}

/// [`switch_period_doubling`] on the erased family.
fn switch_erased<'m>(
    family: &dyn ModelFamily<'m>,
    bif: &Bifurcation,
    opts: &ContinuationOptions,
) -> Result<Branch, LimitError> {
    opts.validate()?;
    if bif.kind != BifurcationKind::PeriodDoubling {
        return Err(LimitError::InvalidOption {
            name: "bifurcation",
            value: bif.param,
            allowed: "branch switching needs a period doubling",
        });
    }
    let n = bif.section.len();
    let k2 = 2 * bif.period_strides;
    let ctx = Ctx {
        family,
        opts: *opts,
        k: k2,
        n,
    };
    let v = real_eigenvector(&bif.dp, n, -1.0).ok_or(LimitError::Singular {
        at: bif.section.clone(),
    })?;
    let mut y_pd = bif.section.clone();
    y_pd.push(bif.param);
    let mut c = v.clone();
    c.push(0.0);
    let mut eps = opts.switch_eps;
    let mut last_reason = String::new();
    for _ in 0..12 {
        let pred: Vec<f64> = y_pd.iter().zip(&c).map(|(y, cv)| y + eps * cv).collect();
        let sigma = dot(&c, &y_pd) + eps;
        match ctx.correct(&pred, &c, sigma) {
            Ok(sol) => {
                // Not a period-k point: P^k(s) must differ from s by much more than the tolerance.
                let half = Ctx {
                    family,
                    opts: *opts,
                    k: bif.period_strides,
                    n,
                };
                let pk = half.iterate(&sol.y[..n], sol.y[n])?;
                let gap = norm_inf(
                    &pk.iter()
                        .zip(&sol.y[..n])
                        .map(|(a, b)| a - b)
                        .collect::<Vec<_>>(),
                );
                if gap > 1e3 * opts.newton_tol.max(1e-12) && gap > 0.1 * eps {
                    let away: Vec<f64> = sol.y.iter().zip(&y_pd).map(|(a, b)| a - b).collect();
                    let t0 = ctx.tangent(&sol.jac, &away).ok_or(LimitError::Singular {
                        at: sol.y[..n].to_vec(),
                    })?;
                    return run_branch(&ctx, sol, t0, None);
                }
                last_reason = format!(
                    "converged back onto the period-{} orbit (ε = {eps:e})",
                    bif.period_strides
                );
            }
            Err(r) => last_reason = r,
        }
        eps *= 0.5;
    }
    Err(LimitError::NoConvergence {
        reason: format!(
            "branch switching at the period doubling μ = {}: {last_reason}",
            bif.param
        ),
        iterations: 12,
        last: bif.section.clone(),
        history: Vec::new(),
    })
}

/// Follow a period-doubling cascade: continue the period-k branch from `(s0, mu0)` in
/// `opts.direction` up to its first period doubling (`opts.stop_at` is overridden), switch
/// there, and repeat `levels` times. Returns
/// the located period doublings in order (period 1→2, 2→4, …) and the branches.
pub fn period_doubling_cascade<S, E, F>(
    family: &F,
    s0: &[f64],
    mu0: f64,
    levels: usize,
    opts: &ContinuationOptions,
) -> Result<(Vec<Bifurcation>, Vec<Branch>), LimitError>
where
    S: Section + ?Sized,
    E: Display,
    F: Fn(f64) -> Result<Box<S>, E>,
{
    let mut pds = Vec::new();
    let mut branches = Vec::new();
    let mut o = *opts;
    o.stop_at = Some(BifurcationKind::PeriodDoubling);
    let opts = &o;
    let mut branch = continue_erased(family, s0, mu0, 1, opts)?;
    for level in 0..levels {
        let Some(pd) = branch
            .bifurcations
            .iter()
            .find(|b| b.kind == BifurcationKind::PeriodDoubling)
            .cloned()
        else {
            branches.push(branch);
            break;
        };
        pds.push(pd.clone());
        branches.push(branch);
        if level + 1 == levels {
            break;
        }
        branch = switch_erased(family, &pd, opts)?;
    }
    Ok((pds, branches))
}

/// Continue the branch of period-`period_strides` orbits through the guess `s0` at `mu0` both
/// ways: towards `opts.mu_min` and towards `opts.mu_max` (two runs of [`continue_branch`] from
/// the same first point, `opts.direction` set to −1 and +1), joined into one branch ordered in
/// the direction `opts.direction` ([`join_halves`]). The start point appears once; the
/// bifurcations of both halves are kept, in the joined order.
pub fn continue_both_ways<S, E, F>(
    family: &F,
    s0: &[f64],
    mu0: f64,
    period_strides: usize,
    opts: &ContinuationOptions,
) -> Result<Branch, LimitError>
where
    S: Section + ?Sized,
    E: Display,
    F: Fn(f64) -> Result<Box<S>, E>,
{
    let towards = |direction: f64| {
        let mut o = *opts;
        o.direction = direction;
        continue_erased(family, s0, mu0, period_strides, &o)
    };
    let back = towards(-opts.direction)?;
    let ahead = towards(opts.direction)?;
    Ok(join_halves(back, ahead))
}

/// One branch from two halves continued from the same start point in opposite directions:
/// `back`'s points reversed (their tangents turned round, so that every tangent points along
/// the joined order), then `ahead`'s from its second point on. A bifurcation between points
/// `j − 1` and `j` of `back` lies between the joined points `m − j` and `m − j + 1` (`m + 1`
/// points in `back`), one of `ahead` between `m + j − 1` and `m + j`; the joined list holds
/// `back`'s in reverse, then `ahead`'s. The joined branch ends as `ahead` does.
pub fn join_halves(back: Branch, ahead: Branch) -> Branch {
    let m = back.points.len().saturating_sub(1);
    let mut points: Vec<BranchPoint> = back
        .points
        .into_iter()
        .skip(1)
        .rev()
        .map(|mut p| {
            p.tangent.iter_mut().for_each(|t| *t = -*t);
            p
        })
        .collect();
    points.extend(ahead.points);
    let mut bifurcations: Vec<Bifurcation> = back
        .bifurcations
        .into_iter()
        .rev()
        .map(|mut b| {
            b.index = m + 1 - b.index;
            b
        })
        .collect();
    bifurcations.extend(ahead.bifurcations.into_iter().map(|mut b| {
        b.index += m;
        b
    }));
    Branch {
        period_strides: ahead.period_strides,
        points,
        bifurcations,
        end: ahead.end,
    }
}

/// One point of a branch at a requested parameter value ([`branch_at_params`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SampledPoint {
    /// Index of the requested value in the `params` given.
    pub index: usize,
    /// The point, corrected at exactly that value, or why the correction failed.
    pub point: Result<BranchPoint, String>,
}

/// The points of `branch` at the parameter values `params` (e.g. N evenly spaced values), in
/// the branch's own order: wherever the branch crosses a requested value μ_j between two of its
/// accepted points `a`, `b`, the linear interpolation of `(s, μ)` between them is corrected at
/// fixed μ = μ_j (natural-parameter corrector, `c = e_μ`; Allgower & Georg 1990, ch. 2) to
/// `‖P^k(s) − s‖∞ ≤ newton_tol`, and measured as every accepted point is (multipliers, period,
/// the k orbit points in stride order). A branch that does not turn in μ crosses each value in
/// its range once; one that folds crosses some values two or more times and yields a point per
/// crossing. Values outside the branch's μ range yield nothing (a branch switched onto at a
/// period doubling begins at its first corrected point, a switching offset past the
/// bifurcation, where μ − μ_PD ~ ε²).
///
/// The continuation's own steps are whatever its step control needed; this puts its output on
/// the user's grid. A correction that fails (Newton diverging right at a fold, where the fixed-μ
/// Jacobian `DP^k − I` is singular), or that lands farther from the interpolated guess than
/// ten times the segment's length plus 10⁻⁶ (onto another branch), is returned as an `Err`
/// message, not dropped. Independent corrections run on `pool`; the result does not depend on
/// the number of threads.
pub fn branch_at_params<S, E, F>(
    family: &F,
    branch: &Branch,
    params: &[f64],
    opts: &ContinuationOptions,
    pool: &rayon::ThreadPool,
) -> Result<Vec<SampledPoint>, LimitError>
where
    S: Section + ?Sized,
    E: Display,
    F: Fn(f64) -> Result<Box<S>, E> + Sync,
{
    sample_erased(family, branch, params, opts, pool)
}

/// [`branch_at_params`] on the erased family.
fn sample_erased<'m>(
    family: &(dyn ModelFamily<'m> + Sync),
    branch: &Branch,
    params: &[f64],
    opts: &ContinuationOptions,
    pool: &rayon::ThreadPool,
) -> Result<Vec<SampledPoint>, LimitError> {
    use rayon::prelude::*;
    opts.validate()?;
    let Some(first) = branch.points.first() else {
        return Ok(Vec::new());
    };
    let n = first.section.len();
    let ctx = Ctx {
        family,
        opts: *opts,
        k: branch.period_strides,
        n,
    };
    // (index into params, segment start) in branch order, values in the traversal direction.
    let mut jobs: Vec<(usize, usize)> = Vec::new();
    let pts = &branch.points;
    for i in 0..pts.len() {
        let mu_a = pts[i].param;
        let mut here: Vec<usize> = if i + 1 < pts.len() {
            let mu_b = pts[i + 1].param;
            (0..params.len())
                .filter(|&j| {
                    let (da, db) = (mu_a - params[j], mu_b - params[j]);
                    da == 0.0 || (db != 0.0 && (da < 0.0) != (db < 0.0))
                })
                .collect()
        } else {
            (0..params.len()).filter(|&j| params[j] == mu_a).collect()
        };
        let up = i + 1 >= pts.len() || pts[i + 1].param >= mu_a;
        here.sort_by(|&x, &y| {
            let o = params[x].total_cmp(&params[y]);
            if up {
                o
            } else {
                o.reverse()
            }
        });
        jobs.extend(here.into_iter().map(|j| (j, i)));
    }
    let mut e_mu = vec![0.0; n + 1];
    e_mu[n] = 1.0;
    let solve_one = |&(j, i): &(usize, usize)| -> SampledPoint {
        let a = &pts[i];
        let b = pts.get(i + 1).unwrap_or(a);
        let mu = params[j];
        let w = if b.param != a.param {
            (mu - a.param) / (b.param - a.param)
        } else {
            0.0
        };
        let mut guess: Vec<f64> = a
            .section
            .iter()
            .zip(&b.section)
            .map(|(x, y)| x + w * (y - x))
            .collect();
        guess.push(mu);
        let mut t_ref: Vec<f64> = a
            .tangent
            .iter()
            .zip(&b.tangent)
            .map(|(x, y)| x + w * (y - x))
            .collect();
        if dot(&t_ref, &t_ref) > 0.0 {
            normalize(&mut t_ref);
        } else {
            t_ref = a.tangent.clone();
        }
        let seg = norm_inf(
            &a.section
                .iter()
                .zip(&b.section)
                .map(|(x, y)| x - y)
                .collect::<Vec<_>>(),
        );
        let point = ctx.correct(&guess, &e_mu, mu).and_then(|sol| {
            let jump = norm_inf(
                &sol.y[..n]
                    .iter()
                    .zip(&guess[..n])
                    .map(|(x, y)| x - y)
                    .collect::<Vec<_>>(),
            );
            if jump > 10.0 * seg + 1e-6 {
                return Err(format!(
                    "the corrector left the branch at μ = {mu} (moved {jump:.3e}, the segment \
                     is {seg:.3e} long)"
                ));
            }
            let t = ctx.tangent(&sol.jac, &t_ref).unwrap_or(t_ref.clone());
            ctx.point(&sol, t).map_err(|e| e.to_string())
        });
        SampledPoint { index: j, point }
    };
    Ok(pool.install(|| jobs.par_iter().map(solve_one).collect()))
}
