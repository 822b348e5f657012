//! The gait sensitivity norm (GSN) of Hobbelen & Wisse ("A disturbance rejection measure for
//! limit cycle walkers: the gait sensitivity norm", IEEE T-RO 23(6), 2007): the H2 norm of the
//! linearised transfer from a terrain disturbance to chosen gait indicators.
//!
//! # The linear system
//! With the frame change of [`crate::terrain`] a stride depends on the section state `σ` in the
//! frame of the line just landed on **and** on that line's slope (the state [`crate::markov`]'s
//! chain uses): from `(σ_k, e_k)` the stride landing on the line inclined `s̄ + e_{k+1}` starts
//! from `L(σ_k)` carried from frame `s̄ + e_k` to frame `s̄ + e_{k+1}` and ends at `σ_{k+1}` in
//! the new line's frame. At a period-one gait `σ*` of the mean slope `s̄` the stride
//! `σ' = F(σ, e, e')` and its gait indicators `g = G(σ, e, e')` are linearised as
//!
//! ```text
//! x_{k+1} = A x_k + B e_{k+1}      x = (σ − σ*, e)   (n = d_s + 1 coordinates)
//! g_{k+1} = C x_k + D e_{k+1}      g = the indicators of the stride minus their gait values
//!
//! A = [ F_σ  F_e ]   B = [ F_e' ]   C = [ G_σ  G_e ]   D = G_e'
//!     [  0    0  ]       [  1   ]
//! ```
//!
//! `F_σ = DP(σ*)` is the exact variational Jacobian ([`crate::dp_variational`]). The slope
//! columns and `G` are Richardson-extrapolated central differences of the stride in
//! `(σ, e, e')` (steps `h` and `h/2`, `D = (4 D(h/2) − D(h)) / 3`, error `O(h⁴)`): the models
//! take the slope as a parameter of their vector field, so the variational equations have no
//! `∂/∂slope`. The same differences of the `σ` columns give `F_σ` once more; the largest gap to
//! the variational one is returned as the measured accuracy of the differences
//! ([`Linearisation::fd_error`]).
//!
//! # The norm
//! The transfer `H(z) = D + C (zI − A)⁻¹ B` has the impulse response `h₀ = D`,
//! `h_k = C A^{k−1} B`, and (Hobbelen & Wisse 2007, eq. 7; the H2 norm of a discrete system)
//!
//! ```text
//! GSN² = Σ_i ‖H_i‖₂² = Σ_k ‖h_k‖² = trace(C P Cᵀ + D Dᵀ),   P = A P Aᵀ + B Bᵀ
//! ```
//!
//! with `P` the controllability Gramian, the solution of the discrete Lyapunov equation, solved
//! here directly as the linear system `(I − A ⊗ A) vec P = vec(B Bᵀ)` (`n²` unknowns, `n ≤ 7`).
//! The norm exists only for a stable gait (spectral radius of `A` below 1); otherwise
//! [`GsnError::Unstable`].

use crate::error::LimitError;
use crate::floquet::multipliers;
use crate::jacobian::dp_variational;
use crate::stride::{StrideMap, StrideOutcome};
use crate::terrain::SlopeWalk;
use faer::prelude::*;
use faer::Mat;
use pdw_hybrid::run_scalar_with;

/// A gait indicator of one stride (Hobbelen & Wisse 2007, Sec. III: step time and step length
/// are their defaults).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Indicator {
    /// The stride's duration (model time units).
    StepTime,
    /// The distance between the feet at the heel strike ([`pdw_model::Walker::step_length`]).
    StepLength,
    /// Step length over step time.
    Speed,
}

impl Indicator {
    /// Every indicator, in the order of [`Indicator::name`].
    pub const ALL: [Indicator; 3] = [Indicator::StepTime, Indicator::StepLength, Indicator::Speed];
    /// The default set: step time and step length.
    pub const DEFAULT: [Indicator; 2] = [Indicator::StepTime, Indicator::StepLength];

    /// Its name on the command line and in files: `step-time`, `step-length`, `speed`.
    pub fn name(&self) -> &'static str {
        match self {
            Indicator::StepTime => "step-time",
            Indicator::StepLength => "step-length",
            Indicator::Speed => "speed",
        }
    }

    /// The indicator named `name` (also with underscores), if any.
    pub fn parse(name: &str) -> Option<Self> {
        let n = name.trim().replace('_', "-");
        Self::ALL.into_iter().find(|i| i.name() == n)
    }

    /// Its value for a stride of duration `t` and step length `l`.
    pub fn value(&self, t: f64, l: f64) -> f64 {
        match self {
            Indicator::StepTime => t,
            Indicator::StepLength => l,
            Indicator::Speed => l / t,
        }
    }
}

/// Why there is no gait sensitivity norm.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GsnError {
    /// A stride or a Jacobian failed.
    #[error(transparent)]
    Limit(#[from] LimitError),
    /// The gait is not asymptotically stable: a disturbance's effect never dies out and the
    /// H2 norm is infinite.
    #[error(
        "the gait is unstable (largest Floquet multiplier |λ| = {radius:.6}, not below 1): a \
         disturbance never dies out and its gait sensitivity norm is infinite"
    )]
    Unstable { radius: f64 },
    /// The Lyapunov equation's linear system is singular or gave non-finite values.
    #[error("the discrete Lyapunov equation P = A P Aᵀ + B Bᵀ has no finite solution")]
    Lyapunov,
}

/// The linearised terrain stride at a gait (module docs): row-major matrices.
#[derive(Clone, Debug, PartialEq)]
pub struct Linearisation {
    /// The linear system's dimension `n = d_s + 1`: the section coordinates, then the slope
    /// deviation of the line last landed on.
    pub n: usize,
    /// The indicators, in the rows of `C` and `D`.
    pub indicators: Vec<Indicator>,
    /// `A` (`n × n`).
    pub a: Vec<f64>,
    /// `B` (`n × 1`): the state's change per radian of the next landing line's slope.
    pub b: Vec<f64>,
    /// `C` (`m × n`).
    pub c: Vec<f64>,
    /// `D` (`m × 1`): the indicators' change per radian of the landing line's slope.
    pub d: Vec<f64>,
    /// The gait's indicator values.
    pub g0: Vec<f64>,
    /// The measured accuracy of the differences: max |F_σ by differences − DP variational|.
    pub fd_error: f64,
}

/// Relative step of the state differences (`h_j = REL_STEP · max(|σ_j|, 10⁻³)`, as
/// [`crate::FdScheme`]'s default).
pub const REL_STEP: f64 = 1e-4;
/// Step of the slope differences (rad).
pub const SLOPE_STEP: f64 = 1e-5;

/// One terrain stride from section state `sigma` in the frame of the line inclined `from`
/// (lifted by the model at `from`) landing on the line inclined `to`: the next section state
/// in `to`'s frame and the indicators of the stride. A stride that does not reach the next
/// heel strike is [`LimitError::StrideFailed`].
pub fn stride_outputs(
    walk: &SlopeWalk,
    sigma: &[f64],
    from: f64,
    to: f64,
    indicators: &[Indicator],
) -> Result<(Vec<f64>, Vec<f64>), LimitError> {
    let before = walk.model(from)?;
    let mut x = vec![0.0; before.dim()];
    before.lift(sigma, &mut x);
    walk.shift(&mut x, from, to);
    let w = walk.model(to)?;
    let map = StrideMap::new(w.as_ref(), walk.options())?;
    let mut integ = walk.integrator(x.len())?;
    let end = run_scalar_with(&mut integ, map.system(), &map.driver(), &x)?;
    if end.outcome != StrideOutcome::Ok {
        return Err(LimitError::StrideFailed {
            from: sigma.to_vec(),
            outcome: end.outcome,
        });
    }
    let mut next = vec![0.0; sigma.len()];
    w.project(&end.post, &mut next);
    let l = w.step_length(&end.pre);
    let g = indicators.iter().map(|i| i.value(end.t, l)).collect();
    Ok((next, g))
}

/// `[σ', g]` stacked, as a function of `v = (σ, e, e')` (slope deviations from the mean).
fn outputs(walk: &SlopeWalk, v: &[f64], ind: &[Indicator]) -> Result<Vec<f64>, LimitError> {
    let d = v.len() - 2;
    let (e, e2) = (walk.mean() + v[d], walk.mean() + v[d + 1]);
    let (mut y, g) = stride_outputs(walk, &v[..d], e, e2, ind)?;
    y.extend(g);
    Ok(y)
}

/// The Richardson-extrapolated Jacobian (row-major `(d_s + m) × (d_s + 2)`) of [`outputs`] at
/// `(σ*, 0, 0)`, steps `h_j` for input `j` and `h_j / 2`.
fn fd_jacobian(
    walk: &SlopeWalk,
    sigma: &[f64],
    ind: &[Indicator],
    steps: &[f64],
) -> Result<Vec<f64>, LimitError> {
    let mut v0 = sigma.to_vec();
    v0.extend([0.0, 0.0]);
    let (n_in, n_out) = (v0.len(), sigma.len() + ind.len());
    let central = |j: usize, h: f64| -> Result<Vec<f64>, LimitError> {
        let (mut vp, mut vm) = (v0.clone(), v0.clone());
        vp[j] += h;
        vm[j] -= h;
        let (yp, ym) = (outputs(walk, &vp, ind)?, outputs(walk, &vm, ind)?);
        Ok(yp
            .iter()
            .zip(&ym)
            .map(|(p, m)| (p - m) / (2.0 * h))
            .collect())
    };
    let mut jac = vec![0.0; n_out * n_in];
    for (j, &h) in steps.iter().enumerate() {
        let (d1, d2) = (central(j, h)?, central(j, 0.5 * h)?);
        for i in 0..n_out {
            jac[i * n_in + j] = (4.0 * d2[i] - d1[i]) / 3.0;
        }
    }
    Ok(jac)
}

/// The steps of the differences: [`REL_STEP`] relative for `σ`, `slope_step` for `e` and `e'`.
pub fn fd_steps(sigma: &[f64], slope_step: f64) -> Vec<f64> {
    let mut h: Vec<f64> = sigma.iter().map(|v| REL_STEP * v.abs().max(1e-3)).collect();
    h.extend([slope_step, slope_step]);
    h
}

/// The linearisation of the terrain stride of `walk` at its mean slope's gait `sigma` (a fixed
/// point of the mean slope's stride map; module docs), for `indicators`, the slopes differenced
/// with step `slope_step` (rad; [`SLOPE_STEP`] is the default).
pub fn linearise(
    walk: &SlopeWalk,
    sigma: &[f64],
    indicators: &[Indicator],
    slope_step: f64,
) -> Result<Linearisation, LimitError> {
    let base = walk.model(walk.mean())?;
    let map = StrideMap::new(base.as_ref(), walk.options())?;
    let (_, dp) = dp_variational(&map, sigma)?;
    let (ds, m) = (sigma.len(), indicators.len());
    let jac = fd_jacobian(walk, sigma, indicators, &fd_steps(sigma, slope_step))?;
    let col = |i: usize, j: usize| jac[i * (ds + 2) + j];
    let fd_error = (0..ds * ds)
        .map(|k| (col(k / ds, k % ds) - dp[k]).abs())
        .fold(0.0, f64::max);
    let n = ds + 1;
    let mut a = vec![0.0; n * n];
    for i in 0..ds {
        a[i * n..i * n + ds].copy_from_slice(&dp[i * ds..(i + 1) * ds]);
        a[i * n + ds] = col(i, ds);
    }
    let mut b: Vec<f64> = (0..ds).map(|i| col(i, ds + 1)).collect();
    b.push(1.0);
    let c = (0..m * n).map(|k| col(ds + k / n, k % n)).collect();
    let (_, g0) = stride_outputs(walk, sigma, walk.mean(), walk.mean(), indicators)?;
    Ok(Linearisation {
        n,
        indicators: indicators.to_vec(),
        a,
        b,
        c,
        d: (0..m).map(|i| col(ds + i, ds + 1)).collect(),
        g0,
        fd_error,
    })
}

/// The gait sensitivity norm and what it is made of.
#[derive(Clone, Debug, PartialEq)]
pub struct Gsn {
    /// `√(Σ_i ‖H_i‖₂²)`.
    pub norm: f64,
    /// `‖H_i‖₂` per indicator, in the order of [`Linearisation::indicators`].
    pub per_indicator: Vec<f64>,
    /// The controllability Gramian `P` (`n × n`).
    pub gramian: Vec<f64>,
    /// The spectral radius of `A`.
    pub radius: f64,
}

/// The spectral radius of the row-major `n × n` matrix `a`.
pub fn spectral_radius(a: &[f64], n: usize) -> Result<f64, LimitError> {
    Ok(multipliers(a, n)?
        .iter()
        .map(|l| l.modulus())
        .fold(0.0, f64::max))
}

/// The solution `P` of `P = A P Aᵀ + B Bᵀ` (`A` row-major `n × n`, `B` row-major `n × p`) by the
/// Kronecker form `(I − A ⊗ A) vec P = vec(B Bᵀ)`, LU with partial pivoting.
pub fn lyapunov(a: &[f64], b: &[f64], n: usize) -> Result<Vec<f64>, GsnError> {
    let p = b.len() / n.max(1);
    let nn = n * n;
    // row (i, j), column (k, l): δ_ik δ_jl − A_ik A_jl
    let m = Mat::<f64>::from_fn(nn, nn, |r, c| {
        let (i, j, k, l) = (r / n, r % n, c / n, c % n);
        f64::from(u8::from(r == c)) - a[i * n + k] * a[j * n + l]
    });
    let q = Mat::<f64>::from_fn(nn, 1, |r, _| {
        (0..p)
            .map(|t| b[(r / n) * p + t] * b[(r % n) * p + t])
            .sum()
    });
    let x = m.partial_piv_lu().solve(&q);
    let out: Vec<f64> = (0..nn).map(|r| x[(r, 0)]).collect();
    if out.iter().all(|v| v.is_finite()) {
        Ok(out)
    } else {
        Err(GsnError::Lyapunov)
    }
}

/// The gait sensitivity norm of `lin` (module docs): [`GsnError::Unstable`] when `A`'s spectral
/// radius is not below 1.
pub fn gait_sensitivity(lin: &Linearisation) -> Result<Gsn, GsnError> {
    let n = lin.n;
    let radius = spectral_radius(&lin.a, n)?;
    if radius.is_nan() || radius >= 1.0 {
        return Err(GsnError::Unstable { radius });
    }
    let p = lyapunov(&lin.a, &lin.b, n)?;
    // ‖H_i‖² = c_i P c_iᵀ + d_i²
    let per_indicator: Vec<f64> = (0..lin.indicators.len())
        .map(|i| {
            let c = &lin.c[i * n..(i + 1) * n];
            let cpc: f64 = (0..n)
                .map(|k| (0..n).map(|l| c[k] * p[k * n + l] * c[l]).sum::<f64>())
                .sum();
            (cpc + lin.d[i] * lin.d[i]).max(0.0).sqrt()
        })
        .collect();
    Ok(Gsn {
        norm: per_indicator.iter().map(|h| h * h).sum::<f64>().sqrt(),
        per_indicator,
        gramian: p,
        radius,
    })
}

/// `Σ_{k=0}^{K} ‖h_k‖²` per indicator by the impulse response itself (`h₀ = D`,
/// `h_k = C A^{k−1} B`), summed until `‖A^{k−1} B‖ ≤ tol ‖B‖` (or `max_terms` terms): the squared
/// per-indicator norms without the Gramian, for checking it.
pub fn impulse_sums(lin: &Linearisation, tol: f64, max_terms: usize) -> Vec<f64> {
    let (n, m) = (lin.n, lin.indicators.len());
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut sums: Vec<f64> = lin.d.iter().map(|d| d * d).collect();
    let mut v = lin.b.clone(); // A^{k−1} B
    let b_norm = norm(&v);
    for _ in 0..max_terms {
        for (i, s) in sums.iter_mut().enumerate().take(m) {
            let h: f64 = (0..n).map(|k| lin.c[i * n + k] * v[k]).sum();
            *s += h * h;
        }
        v = (0..n)
            .map(|i| (0..n).map(|k| lin.a[i * n + k] * v[k]).sum())
            .collect();
        if norm(&v) <= tol * b_norm {
            break;
        }
    }
    sums
}
