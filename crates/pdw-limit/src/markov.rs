//! The mean first-passage time as a Markov chain on a mesh of the section (Byl & Tedrake,
//! "Metastable walking machines", IJRR 28(8), 2009, §4): the slope distribution replaced by a
//! Gauss–Hermite quadrature, every mesh node mapped by the batched stride map for each of its
//! nodes, the landing points spread over the surrounding mesh nodes by multilinear weights, the
//! falls into one absorbing state.
//!
//! # The chain's states
//! With the frame change of [`crate::terrain`] the next stride depends on the section state
//! `σ` in the frame of the line just landed on **and** on that line's slope: the chain's state
//! is `(σ, j)`, `j` the quadrature node of the last slope `s_j = s̄ + sd·z_j`. Since every
//! landing slope is a quadrature node, the slope coordinate needs no interpolation: the mesh
//! is one regular grid of `σ` per quadrature node (a layer). From `(σ, j)` the stride landing on
//! `s_l` (probability `w_l`) starts from `L(σ)` carried from frame `s_j` to frame `s_l`, and
//! lands at `(σ', l)`.
//!
//! # Rules
//! - The mesh is regular in an affine frame of the section ([`Frame`]): the caller's box in
//!   section coordinates ([`Frame::identity`]) or along the principal axes of the states the
//!   walkers visit ([`Frame::principal`], [`crate::section_frame`]), so that a band of visited
//!   states oblique to the axes gets the nodes.
//! - A landing point outside the mesh's box counts as absorbed (as a fall); the mass that left
//!   this way per step, weighted by the quasi-stationary distribution, is reported
//!   ([`ChainResult::out_of_mesh`]) beside the mass that fell ([`ChainResult::fall_per_step`])
//!   so that a box too small shows: where leaving the box is as likely as falling, the chain's
//!   MFPT is the time to leave the box, not to fall. [`landing_hull`] widens a box until it
//!   holds every landing of its own nodes (the rare falls of small σ start from landings far
//!   outside the box the walkers visit in a short run).
//! - `(I − Q) m = 1` gives the expected strides until absorption `m` (the failing stride
//!   included); the MFPT counted in heel strikes from a state is `m − 1`, and from the start
//!   (the gait of the mean slope on a line of the mean slope) it is `q_start · m` with
//!   `q_start` the start's own transition row. The system is solved by BiCGSTAB (van der
//!   Vorst, SIAM J. Sci. Stat. Comput. 13(2), 1992) on the sparse matrix, to a relative
//!   residual of 1e-12.
//! - The dominant eigenvalue `λ` of `Q` (power iteration on `πQ`) gives the quasi-stationary
//!   MFPT `1/(1 − λ) − 1`, which equals the solve's `π m / Σπ − 1` for the quasi-stationary
//!   distribution `π` — a check of both.

use crate::error::LimitError;
pub use crate::section_frame::{Frame, SectionBox};
use crate::terrain::{SlopeWalk, TerrainKind};
use pdw_hybrid::{run_batch_par, BatchOptions, Section};
use pdw_model::{ClosedEnd, Ground};
use rayon::prelude::*;

/// Nodes `z_i` and weights `w_i` of the `n`-point Gauss–Hermite rule for the standard normal
/// density (`Σ w_i f(z_i) ≈ E f(Z)`, exact for polynomials of degree < 2n), by Golub & Welsch
/// (Math. Comp. 23, 1969): the eigenvalues of the Jacobi matrix of the probabilists' Hermite
/// polynomials (zero diagonal, off-diagonal `√k`, k = 1 … n−1) and the squared first
/// components of its unit eigenvectors.
pub fn gauss_hermite(n: usize) -> (Vec<f64>, Vec<f64>) {
    golub_welsch(n, 1.0, |k| k.sqrt())
}

/// Nodes `z_i` and weights `w_i` of the `n`-point Gauss–Legendre rule for the uniform
/// distribution of unit variance, on `[−√3, √3]` (`Σ w_i f(z_i) ≈ E f(U)`, exact for
/// polynomials of degree < 2n), by Golub & Welsch (Math. Comp. 23, 1969) as
/// [`gauss_hermite`]: the Jacobi matrix of the Legendre polynomials (zero diagonal,
/// off-diagonal `k / √(4k² − 1)`, k = 1 … n−1) gives the nodes on `[−1, 1]` (scaled by √3) and
/// the squared first components of its unit eigenvectors the probability weights. The
/// quadrature for a terrain whose draws are uniform with the same standard deviation.
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    golub_welsch(n, 3f64.sqrt(), |k| k / (4.0 * k * k - 1.0).sqrt())
}

/// The Golub–Welsch rule of a symmetric weight: the Jacobi matrix with zero diagonal and
/// off-diagonal `off(k)`, k = 1 … n−1; nodes its eigenvalues times `scale`, weights the squared
/// first components of its unit eigenvectors. The rule is symmetric, so mirrored nodes and an
/// exact middle zero remove the eigen-solver's last ulps.
fn golub_welsch(n: usize, scale: f64, off: impl Fn(f64) -> f64) -> (Vec<f64>, Vec<f64>) {
    let mut a = vec![0.0; n * n];
    for k in 1..n {
        let b = off(k as f64);
        a[k * n + k - 1] = b;
        a[(k - 1) * n + k] = b;
    }
    let v = jacobi_eigen(&mut a, n);
    let mut pairs: Vec<(f64, f64)> = (0..n)
        .map(|i| (scale * a[i * n + i], v[i] * v[i]))
        .collect();
    pairs.sort_by(|p, q| p.0.total_cmp(&q.0));
    let (mut z, mut w): (Vec<f64>, Vec<f64>) = pairs.into_iter().unzip();
    for i in 0..n / 2 {
        let (zi, wi) = (0.5 * (z[n - 1 - i] - z[i]), 0.5 * (w[i] + w[n - 1 - i]));
        (z[i], z[n - 1 - i], w[i], w[n - 1 - i]) = (-zi, zi, wi, wi);
    }
    if n % 2 == 1 {
        z[n / 2] = 0.0;
    }
    (z, w)
}

/// The cyclic Jacobi eigenvalue method (Jacobi 1846; Golub & Van Loan §8.5) on the symmetric
/// `n × n` row-major `a`: on return its diagonal holds the eigenvalues; returns the first row
/// of the eigenvector matrix (component 0 of each unit eigenvector, in diagonal order).
fn jacobi_eigen(a: &mut [f64], n: usize) -> Vec<f64> {
    let v = jacobi_vectors(a, n);
    (0..n).map(|i| v[i]).collect()
}

/// [`jacobi_eigen`]'s whole eigenvector matrix: row-major `n × n`, column `j` the unit
/// eigenvector of the eigenvalue left in `a[j][j]`.
pub(crate) fn jacobi_vectors(a: &mut [f64], n: usize) -> Vec<f64> {
    let mut v = vec![0.0; n * n];
    for i in 0..n {
        v[i * n + i] = 1.0;
    }
    for _sweep in 0..100 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |j| *j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i * n + j] * a[i * n + j])
            .sum();
        if off < 1e-30 {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                rotate(a, &mut v, n, p, q);
            }
        }
    }
    v
}

/// One Jacobi rotation annihilating `a[p][q]` (and `a[q][p]`), accumulated into `v`.
fn rotate(a: &mut [f64], v: &mut [f64], n: usize, p: usize, q: usize) {
    let apq = a[p * n + q];
    if apq == 0.0 {
        return;
    }
    let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
    let sign = if theta >= 0.0 { 1.0 } else { -1.0 };
    let t = sign / (theta.abs() + (theta * theta + 1.0).sqrt());
    let c = 1.0 / (t * t + 1.0).sqrt();
    let s = t * c;
    for k in 0..n {
        let (akp, akq) = (a[k * n + p], a[k * n + q]);
        a[k * n + p] = c * akp - s * akq;
        a[k * n + q] = s * akp + c * akq;
    }
    for k in 0..n {
        let (apk, aqk) = (a[p * n + k], a[q * n + k]);
        a[p * n + k] = c * apk - s * aqk;
        a[q * n + k] = s * apk + c * aqk;
    }
    for k in 0..n {
        let (vkp, vkq) = (v[k * n + p], v[k * n + q]);
        v[k * n + p] = c * vkp - s * vkq;
        v[k * n + q] = s * vkp + c * vkq;
    }
}

/// A regular grid of `n` nodes per axis over the box `[lo, hi]` (`n ≥ 2`) of the frame
/// coordinates of `frame` ([`Frame::identity`]: the section's own), nodes numbered with the
/// first axis fastest.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
    pub n: usize,
    pub frame: Frame,
}

impl Mesh {
    /// Number of nodes, `n^d`.
    pub fn len(&self) -> usize {
        self.n.pow(self.lo.len() as u32)
    }

    /// Always false (a mesh has at least 2^d nodes).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The section coordinates of node `idx`.
    pub fn node(&self, mut idx: usize) -> Vec<f64> {
        let u: Vec<f64> = (0..self.lo.len())
            .map(|a| {
                let i = idx % self.n;
                idx /= self.n;
                self.lo[a] + (self.hi[a] - self.lo[a]) * i as f64 / (self.n - 1) as f64
            })
            .collect();
        self.frame.from_frame(&u)
    }

    /// The multilinear weights (in frame coordinates) of the section point `p` on the `2^d`
    /// nodes of its cell (weights ≥ 0, summing to 1); `None` outside the box or for a
    /// non-finite point.
    pub fn weights(&self, p: &[f64]) -> Option<Vec<(usize, f64)>> {
        let d = self.lo.len();
        let mut base = Vec::with_capacity(d);
        let top = (self.n - 1) as f64;
        let u = self.frame.to_frame(p);
        for ((pa, lo), hi) in u.iter().zip(&self.lo).zip(&self.hi) {
            let u = (pa - lo) / (hi - lo) * top;
            // false for NaN too
            if !(0.0..=top).contains(&u) {
                return None;
            }
            let i = (u.floor() as usize).min(self.n - 2);
            base.push((i, u - i as f64));
        }
        let out = (0..1usize << d)
            .map(|corner| {
                let (mut idx, mut stride, mut w) = (0, 1, 1.0);
                for (a, (i, f)) in base.iter().enumerate() {
                    let up = corner >> a & 1 == 1;
                    idx += (i + up as usize) * stride;
                    w *= if up { *f } else { 1.0 - f };
                    stride *= self.n;
                }
                (idx, w)
            })
            .filter(|c| c.1 > 0.0)
            .collect();
        Some(out)
    }
}

/// The transition rows of the chain: `rows[i]` the `(target, probability)` entries of state
/// `i = layer · mesh.len() + node`; `fall[i]`, `out[i]` the probability of a fall and of a
/// landing outside the mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Transitions {
    pub rows: Vec<Vec<(usize, f64)>>,
    pub fall: Vec<f64>,
    pub out: Vec<f64>,
    /// The expected heel strikes of each transition, where a transition is not one stride
    /// from heel strike to heel strike (the mid-stance chain, [`crate::mid_stance`]: a walker
    /// may land and then fall). `None`: every transition that stays in the mesh is one heel
    /// strike and every absorption none (module docs, "Rules").
    pub strikes: Option<Vec<f64>>,
}

/// The chain on `mesh` for the walk `walk` with slope nodes `slopes` (`(s_l, w_l)`, the
/// quadrature of the slope distribution), strides batched per landing slope on `pool`; with
/// the row of the start `x0` (full state in the mean slope's frame, on a line of the mean
/// slope) as the last row.
pub fn transitions(
    walk: &SlopeWalk,
    slopes: &[(f64, f64)],
    mesh: &Mesh,
    x0: &[f64],
    pool: &rayon::ThreadPool,
) -> Result<Transitions, LimitError> {
    let base = walk.model(walk.mean())?;
    let mut starts: Vec<(f64, Vec<f64>)> = Vec::with_capacity(slopes.len() * mesh.len() + 1);
    for (s, _) in slopes {
        let w = walk.model(*s)?;
        for k in 0..mesh.len() {
            let mut x = vec![0.0; w.dim()];
            w.lift(&mesh.node(k), &mut x);
            starts.push((*s, x));
        }
    }
    starts.push((walk.mean(), x0.to_vec()));
    let mut t = Transitions {
        rows: vec![Vec::new(); starts.len()],
        fall: vec![0.0; starts.len()],
        out: vec![0.0; starts.len()],
        strikes: None,
    };
    for (l, (s_l, w_l)) in slopes.iter().enumerate() {
        let landed = strides_onto(walk, *s_l, &starts, pool)?;
        // each landing's weights in parallel, then added in the states' order (the rows as a
        // serial loop builds them)
        let spread: Vec<Spread> = pool.install(|| {
            landed
                .into_par_iter()
                .with_min_len(256)
                .map(|end| spread_on(end, mesh, base.as_ref()))
                .collect()
        });
        for (i, sp) in spread.into_iter().enumerate() {
            add_spread(&mut t, i, l, *w_l, sp, mesh.len());
        }
    }
    Ok(t)
}

/// Slope nodes lighter than this are left out of [`landing_hull`] (their landings may lie
/// anywhere; the probability they carry per step is below any fall rate the chain resolves).
pub const HULL_MIN_WEIGHT: f64 = 1e-16;

/// The box `[lo, hi]` (coordinates of `frame`) widened to hold every landing (not a fall) of
/// the nodes of a coarse mesh of `per_axis` nodes per axis over it, from every layer onto every
/// slope node of weight at least [`HULL_MIN_WEIGHT`], repeated on the widened box until a pass
/// widens no side by more than 1 % of its range (at most `passes` passes). Returns the box and
/// the passes run.
pub fn landing_hull(
    walk: &SlopeWalk,
    slopes: &[(f64, f64)],
    frame: &Frame,
    bounds: SectionBox,
    per_axis: usize,
    passes: usize,
    pool: &rayon::ThreadPool,
) -> Result<(SectionBox, usize), LimitError> {
    widen_box(frame, bounds, per_axis, passes, &|mesh| {
        layered_landings(walk, slopes, mesh, pool)
    })
}

/// Every landing (section coordinates) of the nodes of a mesh, for [`widen_box`].
pub type Landings<'a> = dyn Fn(&Mesh) -> Result<Vec<Vec<f64>>, LimitError> + 'a;

/// The loop of [`landing_hull`] for any chain: `landings(mesh)` gives every landing (section
/// coordinates) of the nodes of a mesh.
pub fn widen_box(
    frame: &Frame,
    bounds: SectionBox,
    per_axis: usize,
    passes: usize,
    landings: &Landings,
) -> Result<(SectionBox, usize), LimitError> {
    let (mut lo, mut hi) = bounds;
    for pass in 1..=passes {
        let mesh = Mesh {
            lo: lo.clone(),
            hi: hi.clone(),
            n: per_axis.max(2),
            frame: frame.clone(),
        };
        let (mut new_lo, mut new_hi) = (lo.clone(), hi.clone());
        for sec in landings(&mesh)? {
            if sec.iter().all(|v| v.is_finite()) {
                for (a, v) in frame.to_frame(&sec).iter().enumerate() {
                    new_lo[a] = new_lo[a].min(*v);
                    new_hi[a] = new_hi[a].max(*v);
                }
            }
        }
        let grew = (0..lo.len()).any(|a| {
            let r = hi[a] - lo[a];
            lo[a] - new_lo[a] > 0.01 * r || new_hi[a] - hi[a] > 0.01 * r
        });
        (lo, hi) = (new_lo, new_hi);
        if !grew {
            return Ok(((lo, hi), pass));
        }
    }
    Ok(((lo, hi), passes))
}

/// Every landing (section coordinates) of the mesh's nodes, from every layer onto every slope
/// node of weight at least [`HULL_MIN_WEIGHT`].
fn layered_landings(
    walk: &SlopeWalk,
    slopes: &[(f64, f64)],
    mesh: &Mesh,
    pool: &rayon::ThreadPool,
) -> Result<Vec<Vec<f64>>, LimitError> {
    let base = walk.model(walk.mean())?;
    let mut starts = Vec::with_capacity(slopes.len() * mesh.len());
    for (s, _) in slopes {
        let w = walk.model(*s)?;
        for k in 0..mesh.len() {
            let mut x = vec![0.0; w.dim()];
            w.lift(&mesh.node(k), &mut x);
            starts.push((*s, x));
        }
    }
    let mut out = Vec::new();
    for (s_l, w_l) in slopes {
        if *w_l < HULL_MIN_WEIGHT {
            continue;
        }
        for post in strides_onto(walk, *s_l, &starts, pool)?
            .into_iter()
            .flatten()
        {
            let mut sec = vec![0.0; base.section_dim()];
            base.project(&post, &mut sec);
            out.push(sec);
        }
    }
    Ok(out)
}

/// Every start `(s_from, x)` (full state in the frame of line `s_from`) carried to the frame of
/// line `s_to` and run one stride of the model at `s_to`: the post-heel-strike state in
/// `s_to`'s frame, or `None` for a stride that did not reach it. In closed form where the walk
/// asks for it and the model has one ([`SlopeWalk::with_closed_form`]), every other stride
/// integrated, batched.
fn strides_onto(
    walk: &SlopeWalk,
    s_to: f64,
    starts: &[(f64, Vec<f64>)],
    pool: &rayon::ThreadPool,
) -> Result<Vec<Option<Vec<f64>>>, LimitError> {
    let items: Vec<Vec<f64>> = starts
        .iter()
        .map(|(s_from, x)| {
            let mut y = x.clone();
            walk.shift(&mut y, *s_from, s_to);
            y
        })
        .collect();
    let base = walk.model(walk.mean())?;
    let closed = walk.closed_form().then(|| base.closed_stride()).flatten();
    let Some(closed) = closed else {
        return integrated_strides(walk, s_to, &items, pool);
    };
    let ground = match walk.kind() {
        TerrainKind::Slope => Ground::Slope(s_to),
        TerrainKind::StepDown => Ground::StepDown(s_to),
    };
    // `Err(())`: the closed form does not cover the start (integrated below)
    let mut ends: Vec<Result<Option<Vec<f64>>, ()>> = pool.install(|| {
        items
            .par_iter()
            .with_min_len(256)
            .map(|y| {
                let mut out = vec![0.0; y.len()];
                match closed.stride_on(ground, y, &mut out) {
                    ClosedEnd::Landed => Ok(Some(out)),
                    ClosedEnd::Terminal { .. } => Ok(None),
                    ClosedEnd::Outside => Err(()),
                }
            })
            .collect()
    });
    let outside: Vec<usize> = (0..ends.len()).filter(|&i| ends[i].is_err()).collect();
    walk.report(items.len() - outside.len());
    if !outside.is_empty() {
        let rest: Vec<Vec<f64>> = outside.iter().map(|&i| items[i].clone()).collect();
        for (i, end) in outside
            .into_iter()
            .zip(integrated_strides(walk, s_to, &rest, pool)?)
        {
            ends[i] = Ok(end);
        }
    }
    Ok(ends.into_iter().map(|e| e.unwrap_or(None)).collect())
}

/// One integrated stride of the model at `s_to` from each of `items` (full states in `s_to`'s
/// frame), batched: the post-heel-strike state, or `None` for a stride that did not reach it.
fn integrated_strides(
    walk: &SlopeWalk,
    s_to: f64,
    items: &[Vec<f64>],
    pool: &rayon::ThreadPool,
) -> Result<Vec<Option<Vec<f64>>>, LimitError> {
    let w = walk.model(s_to)?;
    let map = crate::StrideMap::new(w.as_ref(), walk.options())?;
    let opts = BatchOptions {
        lanes: 256,
        integrator: walk.options(),
    };
    let progress = walk.batch_progress();
    let ends = run_batch_par(
        map.system(),
        &map.driver(),
        items,
        &opts,
        pool,
        1024,
        &progress,
    )?;
    Ok(ends
        .into_iter()
        .map(|e| e.outcome.is_ok().then_some(e.post))
        .collect())
}

/// Where a stride's landing went: `None` a fall, `Some(None)` outside the mesh, else its
/// weights on the mesh's nodes.
type Spread = Option<Option<Vec<(usize, f64)>>>;

/// A landing (`None`: a fall) spread over the mesh.
fn spread_on(end: Option<Vec<f64>>, mesh: &Mesh, base: &dyn Section) -> Spread {
    let post = end?;
    let mut s = vec![0.0; base.section_dim()];
    base.project(&post, &mut s);
    Some(mesh.weights(&s))
}

/// Row `i`'s landing on slope node `l` (probability `w_l`, layers of `per_layer` nodes): its
/// weights on layer `l`'s mesh, or counted as a fall / out of the mesh.
fn add_spread(t: &mut Transitions, i: usize, l: usize, w_l: f64, sp: Spread, per_layer: usize) {
    match sp {
        None => t.fall[i] += w_l,
        Some(None) => t.out[i] += w_l,
        Some(Some(ws)) => {
            t.rows[i].extend(ws.into_iter().map(|(k, w)| (l * per_layer + k, w_l * w)))
        }
    }
}

/// The chain's answers.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainResult {
    /// MFPT (heel strikes) from the start: `q_start · m`.
    pub mfpt: f64,
    /// Dominant eigenvalue of `Q` (power iteration).
    pub lambda: f64,
    /// `1/(1 − λ) − 1`: the MFPT from the quasi-stationary distribution by the eigenvalue,
    /// with `1 − λ = π·(fall + out)` (the probability the quasi-stationary distribution leaves
    /// per step; equal to `1 − λ` for the eigenvector, and exact where `λ` rounds to 1).
    pub mfpt_lambda: f64,
    /// `π m / Σπ − 1`: the same by the solve.
    pub mfpt_quasi_stationary: f64,
    /// Probability per step of landing outside the mesh, under the quasi-stationary
    /// distribution.
    pub out_of_mesh: f64,
    /// Probability per step of a fall, under the quasi-stationary distribution
    /// (`fall_per_step + out_of_mesh = 1 − λ`).
    pub fall_per_step: f64,
    /// Relative residual of the solve.
    pub residual: f64,
    /// Number of chain states (without the absorbing one).
    pub states: usize,
}

/// `y = Q x` (the start's row, last, excluded), the rows in parallel (each row's sum in its
/// entries' order, as serially).
fn matvec(t: &Transitions, n: usize, x: &[f64], y: &mut [f64]) {
    y[..n]
        .par_iter_mut()
        .with_min_len(4096)
        .zip(&t.rows[..n])
        .for_each(|(yi, row)| *yi = row.iter().map(|(j, q)| q * x[*j]).sum());
}

/// `Qᵀ` of the first `n` rows and columns, by rows (compressed sparse rows: row `j` holds the
/// entries `(i, q_ij)` of column `j` of `Q`, in increasing `i`), so that `x Q` is a gather per
/// column that runs in parallel.
struct Transposed {
    start: Vec<usize>,
    entries: Vec<(usize, f64)>,
}

fn transpose(t: &Transitions, n: usize) -> Transposed {
    let mut start = vec![0usize; n + 1];
    for row in &t.rows[..n] {
        for (j, _) in row {
            start[j + 1] += 1;
        }
    }
    for j in 0..n {
        start[j + 1] += start[j];
    }
    let mut fill = start.clone();
    let mut entries = vec![(0, 0.0); start[n]];
    for (i, row) in t.rows[..n].iter().enumerate() {
        for (j, q) in row {
            entries[fill[*j]] = (i, *q);
            fill[*j] += 1;
        }
    }
    Transposed { start, entries }
}

/// `y = x Q` (row vector times Q) by the transpose.
fn vecmat(qt: &Transposed, x: &[f64], y: &mut [f64]) {
    y.par_iter_mut()
        .with_min_len(4096)
        .enumerate()
        .for_each(|(j, yj)| {
            *yj = qt.entries[qt.start[j]..qt.start[j + 1]]
                .iter()
                .map(|(i, q)| x[*i] * q)
                .sum();
        });
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solves `(I − Q) m = b` by BiCGSTAB; returns `m` and the relative residual reached.
fn solve(t: &Transitions, n: usize, b: Vec<f64>) -> (Vec<f64>, f64) {
    let apply = |x: &[f64], y: &mut [f64]| {
        matvec(t, n, x, y);
        for (yi, xi) in y.iter_mut().zip(x) {
            *yi = xi - *yi;
        }
    };
    let bn = dot(&b, &b).sqrt();
    let mut x = vec![0.0; n];
    let mut r = b.clone();
    let r0 = r.clone();
    let (mut rho, mut alpha, mut omega) = (1.0, 1.0, 1.0);
    let (mut v, mut p) = (vec![0.0; n], vec![0.0; n]);
    let (mut s, mut tt) = (vec![0.0; n], vec![0.0; n]);
    let mut res = 1.0;
    for _ in 0..20 * n.max(100) {
        let rho1 = dot(&r0, &r);
        let beta = (rho1 / rho) * (alpha / omega);
        rho = rho1;
        for ((pk, rk), vk) in p.iter_mut().zip(&r).zip(&v) {
            *pk = rk + beta * (*pk - omega * vk);
        }
        apply(&p, &mut v);
        alpha = rho / dot(&r0, &v);
        for ((sk, rk), vk) in s.iter_mut().zip(&r).zip(&v) {
            *sk = rk - alpha * vk;
        }
        // converged at the half step (exactly, in a small system): `t = A s` would be zero
        // and `ω = t·s / t·t` undefined
        if dot(&s, &s).sqrt() / bn < 1e-12 {
            for (xk, pk) in x.iter_mut().zip(&p) {
                *xk += alpha * pk;
            }
            res = dot(&s, &s).sqrt() / bn;
            break;
        }
        apply(&s, &mut tt);
        omega = dot(&tt, &s) / dot(&tt, &tt);
        for ((xk, pk), sk) in x.iter_mut().zip(&p).zip(&s) {
            *xk += alpha * pk + omega * sk;
        }
        for ((rk, sk), tk) in r.iter_mut().zip(&s).zip(&tt) {
            *rk = sk - omega * tk;
        }
        res = dot(&r, &r).sqrt() / bn;
        if !res.is_finite() || res < 1e-12 {
            break;
        }
    }
    (x, res)
}

/// The dominant left eigenvector `π` (Σπ = 1) and eigenvalue of `Q` by power iteration from
/// the uniform vector, until the probability `π·(fall + out)` that `π` leaves per step (which
/// is `1 − λ`) changes by less than 1e-12 relative (at most 10⁵ steps). Stopping on `λ`
/// itself would stop too early when `1 − λ` is below `λ`'s rounding.
fn dominant(t: &Transitions, n: usize) -> (Vec<f64>, f64) {
    let leave: Vec<f64> = t.fall[..n]
        .iter()
        .zip(&t.out[..n])
        .map(|(f, o)| f + o)
        .collect();
    let qt = transpose(t, n);
    let mut pi = vec![1.0 / n as f64; n];
    let mut next = vec![0.0; n];
    let (mut lambda, mut rate) = (0.0, f64::INFINITY);
    for _ in 0..100_000 {
        vecmat(&qt, &pi, &mut next);
        let l: f64 = next.iter().sum();
        if l <= 0.0 {
            return (pi, 0.0);
        }
        next.iter_mut().for_each(|v| *v /= l);
        std::mem::swap(&mut pi, &mut next);
        lambda = l;
        let r = dot(&pi, &leave);
        let done = (r - rate).abs() <= 1e-12 * r;
        rate = r;
        if done {
            break;
        }
    }
    (pi, lambda)
}

/// The MFPT from the chain (module docs, "Rules"; with [`Transitions::strikes`],
/// [`solve_strikes`]).
pub fn solve_chain(t: &Transitions) -> ChainResult {
    if let Some(r) = &t.strikes {
        return solve_strikes(t, r);
    }
    let n = t.rows.len() - 1;
    let (m, residual) = solve(t, n, vec![1.0; n]);
    let start = &t.rows[n];
    let mfpt = start.iter().map(|(j, q)| q * m[*j]).sum();
    let (pi, lambda) = dominant(t, n);
    // 1 − λ = π·(fall + out) for the normalised eigenvector (the rows of Q, fall and out sum
    // to 1): computed this way it keeps its digits when 1 − λ nears the rounding of λ.
    let absorbed = dot(&pi, &t.fall[..n]) + dot(&pi, &t.out[..n]);
    ChainResult {
        mfpt,
        lambda,
        mfpt_lambda: 1.0 / absorbed - 1.0,
        mfpt_quasi_stationary: dot(&pi, &m) - 1.0,
        out_of_mesh: dot(&pi, &t.out[..n]),
        fall_per_step: dot(&pi, &t.fall[..n]),
        residual,
        states: n,
    }
}

/// The MFPT of a chain whose transitions carry `r`, their expected heel strikes: the heel
/// strikes until absorption `m` solve `(I − Q) m = r` (a first-step analysis: `m = r + Q m`),
/// from the start `r_start + q_start · m`; from the quasi-stationary distribution `π m`, which
/// for the eigenvector (`π Q = λ π`) is `π·r / (1 − λ)` — the check by the eigenvalue.
pub fn solve_strikes(t: &Transitions, r: &[f64]) -> ChainResult {
    let n = t.rows.len() - 1;
    let (m, residual) = solve(t, n, r[..n].to_vec());
    let mfpt = r[n] + t.rows[n].iter().map(|(j, q)| q * m[*j]).sum::<f64>();
    let (pi, lambda) = dominant(t, n);
    let (fall, out) = (dot(&pi, &t.fall[..n]), dot(&pi, &t.out[..n]));
    ChainResult {
        mfpt,
        lambda,
        mfpt_lambda: dot(&pi, &r[..n]) / (fall + out),
        mfpt_quasi_stationary: dot(&pi, &m),
        out_of_mesh: out,
        fall_per_step: fall,
        residual,
        states: n,
    }
}
