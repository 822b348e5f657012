//! Linear stability data of a gait, as outputs: the stride-map Jacobian `DP` (exact, by the
//! variational equations with the saltation matrix at every event,
//! [`pdw_limit::dp_variational`]), its eigenpairs (Floquet multipliers and their directions),
//! the saltation matrix `Ξ = DR + (f⁺ − DR f⁻) ∇gᵀ / (∇g · f⁻)` of each impact along a stride
//! (Aizerman & Gantmacher 1958; Müller 1995; [`pdw_limit::Variational::event_matrix`]), and
//! finite-time Lyapunov exponents of the stride map (Benettin, Galgani, Giorgilli & Strelcyn
//! 1980, Meccanica 15: `Q_{k+1} R_{k+1} = DP(x_k) Q_k`, `λ_i = (1/N) Σ ln |R_ii|`, per stride).

use crate::model::BuiltModel;
use faer::Mat;
use pdw_hybrid::Scratch;
use pdw_limit::trajectory::TrajectoryError;
use pdw_limit::{LimitError, StrideMap, Variational};

/// Why the impacts of a stride could not be found: the state does not fit the model, or the
/// walk failed.
#[derive(Debug)]
pub enum ImpactError {
    Limit(LimitError),
    Trajectory(TrajectoryError),
}

impl std::fmt::Display for ImpactError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ImpactError::Limit(e) => e.fmt(f),
            ImpactError::Trajectory(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for ImpactError {}

/// The integrator of the Jacobians: the fixed-point search's ([`pdw_limit::gaits`]).
fn stride_map(m: &BuiltModel) -> Result<StrideMap<'_>, LimitError> {
    let tol = pdw_limit::gaits::FIXEDPOINT_INTEGRATOR_TOL;
    StrideMap::new(m.walker.as_ref(), pdw_limit::gaits::default_integrator(tol))
}

/// `DP(s)` (row-major `d_s × d_s`) and `P(s)`.
pub fn jacobian(m: &BuiltModel, s: &[f64]) -> Result<(Vec<f64>, Vec<f64>), LimitError> {
    let map = stride_map(m)?;
    let (stride, dp) = pdw_limit::dp_variational(&map, s)?;
    Ok((dp, stride.next))
}

/// One eigenpair of a real matrix: `λ` and `v` (complex, unit 2-norm) with `A v = λ v`.
#[derive(Clone, Debug, PartialEq)]
pub struct Eigenpair {
    pub value: (f64, f64),
    pub vector: Vec<(f64, f64)>,
}

/// The eigenpairs of the `n × n` row-major matrix `a`, by decreasing |λ|.
pub fn eigenpairs(a: &[f64], n: usize) -> Result<Vec<Eigenpair>, LimitError> {
    let mat = Mat::<f64>::from_fn(n, n, |i, j| a[i * n + j]);
    let e = mat.eigen().map_err(|_| LimitError::Eigen)?;
    let (s, u) = (e.S().column_vector(), e.U());
    let mut out: Vec<Eigenpair> = (0..n)
        .map(|k| {
            let norm = (0..n)
                .map(|i| u[(i, k)].re * u[(i, k)].re + u[(i, k)].im * u[(i, k)].im)
                .sum::<f64>()
                .sqrt();
            Eigenpair {
                value: (s[k].re, s[k].im),
                vector: (0..n)
                    .map(|i| (u[(i, k)].re / norm, u[(i, k)].im / norm))
                    .collect(),
            }
        })
        .collect();
    out.sort_by(|p, q| {
        let m = |e: &Eigenpair| e.value.0.hypot(e.value.1);
        m(q).total_cmp(&m(p)).then(q.value.1.total_cmp(&p.value.1))
    });
    Ok(out)
}

/// An impact along a stride: its guard's name, the time, the modes and the saltation matrix
/// (row-major `d × d`, full state) at the pre-impact state.
#[derive(Clone, Debug, PartialEq)]
pub struct Impact {
    pub event: String,
    pub t: f64,
    pub mode_before: usize,
    pub mode_after: usize,
    pub pre: Vec<f64>,
    pub saltation: Vec<f64>,
}

/// The saltation matrix of every reset along one stride from section state `s` (found on a
/// one-step walk, [`pdw_limit::trajectory`]), the heel strike that ends it included.
pub fn impacts(m: &BuiltModel, s: &[f64]) -> Result<Vec<Impact>, ImpactError> {
    let w = m.walker.as_ref();
    let x0 = pdw_limit::trajectory::initial_state(w, s).map_err(ImpactError::Trajectory)?;
    let opts = crate::simulate::options(m, 1, None, crate::simulate::default_integrator());
    let tr = pdw_limit::trajectory::simulate(w, &x0, &opts).map_err(ImpactError::Trajectory)?;
    let d = w.dim();
    let var = Variational::new(w, d);
    let mut ws = Scratch::new();
    let mut out = Vec::new();
    for e in &tr.events {
        let guards = w.guards(e.mode_before);
        let Some(k) = guards.iter().position(|g| g.name == e.kind) else {
            continue;
        };
        if !matches!(guards[k].kind, pdw_hybrid::GuardKind::Reset) {
            continue;
        }
        let (mut x_plus, mut xi) = (vec![0.0; d], vec![0.0; d * d]);
        let mode_after = var.event_matrix(
            &mut ws,
            e.mode_before,
            k,
            &e.pre,
            false,
            &mut x_plus,
            &mut xi,
        );
        out.push(Impact {
            event: e.kind.clone(),
            t: e.t,
            mode_before: e.mode_before,
            mode_after,
            pre: e.pre.clone(),
            saltation: xi,
        });
    }
    Ok(out)
}

/// Finite-time Lyapunov exponents of the stride map over `strides` strides from section state
/// `s` (per stride, descending): `DP` along the orbit, re-orthonormalised each stride by a
/// modified Gram–Schmidt QR.
pub fn lyapunov(m: &BuiltModel, s: &[f64], strides: usize) -> Result<Vec<f64>, LimitError> {
    let map = stride_map(m)?;
    let n = s.len();
    let mut q: Vec<f64> = (0..n * n)
        .map(|k| if k / n == k % n { 1.0 } else { 0.0 })
        .collect();
    let mut sums = vec![0.0; n];
    let mut x = s.to_vec();
    for _ in 0..strides {
        let (stride, dp) = pdw_limit::dp_variational(&map, &x)?;
        // columns of DP·Q
        let mut cols: Vec<Vec<f64>> = (0..n)
            .map(|j| {
                (0..n)
                    .map(|i| (0..n).map(|k| dp[i * n + k] * q[k * n + j]).sum())
                    .collect()
            })
            .collect();
        for (sum, r) in sums.iter_mut().zip(gram_schmidt(&mut cols)) {
            *sum += r.ln();
        }
        for (j, c) in cols.iter().enumerate() {
            for i in 0..n {
                q[i * n + j] = c[i];
            }
        }
        x = stride.next;
    }
    let mut out: Vec<f64> = sums.iter().map(|v| v / strides as f64).collect();
    out.sort_by(|a, b| b.total_cmp(a));
    Ok(out)
}

/// Orthonormalises `cols` in place by modified Gram–Schmidt (the QR factorisation `A = QR`,
/// `cols` becoming `Q`) and returns the diagonal of `R`.
fn gram_schmidt(cols: &mut [Vec<f64>]) -> Vec<f64> {
    let mut diag = Vec::with_capacity(cols.len());
    for j in 0..cols.len() {
        let (done, rest) = cols.split_at_mut(j);
        let c = &mut rest[0];
        for q in done.iter() {
            let r: f64 = q.iter().zip(c.iter()).map(|(a, b)| a * b).sum();
            for (ci, qi) in c.iter_mut().zip(q) {
                *ci -= r * qi;
            }
        }
        let r = c.iter().map(|v| v * v).sum::<f64>().sqrt();
        for v in c.iter_mut() {
            *v /= r;
        }
        diag.push(r);
    }
    diag
}
