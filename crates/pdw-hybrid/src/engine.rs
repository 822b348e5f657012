//! The step machinery shared by the scalar [`Integrator`](crate::Integrator) and the batched
//! lockstep runner: storage, the column kernels of one step attempt, and the per-lane decisions.
//!
//! Storage is structure-of-arrays: a block of shape `(lanes × dim)` is a column-major `Vec<f64>`
//! with column stride `stride ≥ lanes` (component `j` of lane `l` at `j·stride + l`). The scalar
//! integrator is the same storage with one lane and stride 1, so that *every* arithmetic
//! operation a lane sees — stage sums, error norm, step-size control, dense output, event
//! location — is the same code on the same operands in both paths, and the results are equal bit
//! for bit (Rust never contracts `a·b + c` into an FMA, so a vectorised loop over lanes rounds
//! exactly as the scalar loop). A one-lane call (`n = 1`) takes a branch with compile-time stage
//! rows that performs the same operations in the same order (the batch tests compare both
//! branches bit for bit). The only other difference is the model call: `flow_batch` and
//! `guards_with_rates_batch` in the batch, `flow` and `guards_with_rates` in the scalar path,
//! which [`HybridSystem::flow_batch`] and [`HybridSystem::guards_with_rates_batch`] require to
//! agree bit for bit.
//! Flow evaluations that concern a single lane (`f(x₀)` at a segment start, the starting-step
//! trial, DOP853's three dense-output stages) use `flow` in both paths.

// `!(a > b)` is deliberate throughout: it is also true when an operand is NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::event::{self, EventScratch};
use crate::options::{Method, Options, Stats, StopReason};
use crate::tableau::{self, Tableau};
use crate::{Crossing, HybridSystem};

/// The tableau of a method.
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub fn tableau_of(method: Method) -> &'static Tableau {
    match method {
        Method::Rk4 { .. } => &tableau::RK4,
        Method::Dopri5 => &tableau::DOPRI5,
        Method::Dop853 => &tableau::DOP853,
    }
}

/// The tableau of the options' method with its controller ([`Options::controller`]).
pub(crate) fn tableau_for(opts: &Options) -> &'static Tableau {
    match (opts.method, opts.controller) {
        (Method::Dopri5, crate::Controller::Elementary) => &tableau::DOPRI5_ELEMENTARY,
        (m, _) => tableau_of(m),
    }
}

/// Lane-major block storage for one batch (or one scalar integrator: `lanes = stride = 1`).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub struct Store {
    pub dim: usize,
    /// Components `0..err_dim` enter the error norm and the starting step
    /// ([`HybridSystem::error_dim`], clamped to `1..=dim`; set by the runner for its system).
    pub err_dim: usize,
    pub lanes: usize,
    pub stride: usize,
    /// Largest number of guards of any mode.
    pub ng: usize,
    /// `(lanes × dim)` current accepted state x₀; filled at segment start and on acceptance.
    pub x: Vec<f64>,
    /// `(lanes × dim)` input of the current stage.
    pub y: Vec<f64>,
    /// `(lanes × dim)` proposed new state x₁ (input of the last stage).
    pub xn: Vec<f64>,
    /// `n_stages` blocks of `(lanes × dim)`: stage derivatives. Block 0 is `f(x₀)` (persists
    /// across steps), the last block is `f(x₁)`.
    pub k: Vec<f64>,
    /// `(lanes × ng)` guard values at x₀ (zero band applied at segment start), used as the left
    /// end of the next step's crossing scan.
    pub g: Vec<f64>,
    /// `(lanes × ng)` guard rates `ġ = ∇g·f` at x₀ (`+∞` where the model gives none).
    pub gr: Vec<f64>,
    /// `(lanes × ng)` guard values at the attempt's x₁.
    pub g1: Vec<f64>,
    /// `(lanes × ng)` guard rates at the attempt's x₁.
    pub r1: Vec<f64>,
    /// `(lanes)` bit `k` set ([`event::guard_bit`]) when guard `k` of the lane's attempt may
    /// cross zero inside the step ([`mark_near`]); lanes with 0 skip the event locator, and
    /// the locator samples only the flagged guards.
    pub cand: Vec<u8>,
    /// `(lanes)` 1 where the lane's accepted step is committed by [`commit_columns`] (see
    /// [`after_attempt`]), 0 elsewhere; set by the per-lane pass of a batch.
    pub commit: Vec<u8>,
    /// `(lanes)` step of the current attempt.
    pub h: Vec<f64>,
    /// `(lanes)` error norm of the current attempt (0 or NaN for RK4: a finiteness check).
    pub err: Vec<f64>,
    /// `(lanes)` scratch columns for the error kernels (`s2`: `err^α`, the controller's
    /// `fac11`).
    pub s1: Vec<f64>,
    pub s2: Vec<f64>,
    pub s3: Vec<f64>,
}

impl Store {
    pub fn new(dim: usize, lanes: usize, ng: usize, tab: &Tableau) -> Self {
        let stride = lanes;
        let blk = dim * stride;
        Self {
            dim,
            err_dim: dim,
            lanes,
            stride,
            ng,
            x: vec![0.0; blk],
            y: vec![0.0; blk],
            xn: vec![0.0; blk],
            k: vec![0.0; blk * tab.n_stages],
            g: vec![0.0; ng * stride],
            gr: vec![0.0; ng * stride],
            g1: vec![0.0; ng * stride],
            r1: vec![0.0; ng * stride],
            cand: vec![0; lanes],
            commit: vec![0; lanes],
            h: vec![0.0; lanes],
            err: vec![0.0; lanes],
            s1: vec![0.0; lanes],
            s2: vec![0.0; lanes],
            s3: vec![0.0; lanes],
        }
    }

    /// Size of one `(lanes × dim)` block.
    #[inline]
    pub fn blk(&self) -> usize {
        self.dim * self.stride
    }

    /// Copy lane `l` of a block into a contiguous vector.
    #[inline]
    pub fn gather(block: &[f64], stride: usize, l: usize, out: &mut [f64]) {
        for (j, o) in out.iter_mut().enumerate() {
            *o = block[j * stride + l];
        }
    }

    /// Write a contiguous vector into lane `l` of a block.
    #[inline]
    pub fn scatter(block: &mut [f64], stride: usize, l: usize, v: &[f64]) {
        for (j, &vj) in v.iter().enumerate() {
            block[j * stride + l] = vj;
        }
    }

    /// Exchange two lanes in every persistent block (x, f(x), guard values).
    pub fn swap_lanes(&mut self, a: usize, b: usize) {
        let s = self.stride;
        for j in 0..self.dim {
            self.x.swap(j * s + a, j * s + b);
            self.k.swap(j * s + a, j * s + b);
        }
        for k in 0..self.ng {
            self.g.swap(k * s + a, k * s + b);
            self.gr.swap(k * s + a, k * s + b);
        }
    }
}

/// 0 for a finite value, NaN for ±∞ or NaN: added to an error sum it flags non-finite states.
#[inline(always)]
#[allow(clippy::eq_op)]
fn poison(v: f64) -> f64 {
    v - v
}

// ---------------------------------------------------------------------------------------------
// Column kernels over lanes 0..n. Loops run lanes innermost over contiguous column slices.
// ---------------------------------------------------------------------------------------------

/// Most terms one pass of [`sum_pass`] adds.
const PASS: usize = 4;

/// Calls `$go!(i, T)` for the consecutive groups of `$m` terms, each of up to [`PASS`] terms:
/// `i` the group's first term, `T` its length as a literal (so that a pass's term loop has a
/// compile-time length).
macro_rules! in_passes {
    ($m:expr, $go:ident) => {{
        let m: usize = $m;
        let mut i = 0;
        while i < m {
            let t = (m - i).min(PASS);
            match t {
                1 => $go!(i, 1),
                2 => $go!(i, 2),
                3 => $go!(i, 3),
                _ => $go!(i, 4),
            }
            i += t;
        }
    }};
}

/// One pass over lanes `0..n` adding `T` terms in order to a running sum:
/// `s = (((s₀ + w₁k₁) + w₂k₂) + …)`, with `s₀ = 0` when `FIRST` (the sum's first addition,
/// `0 + w·k`) and `acc[l]` otherwise; the result goes to `acc`, or when `LAST` to
/// `out = x + h ⊙ s`. Several terms per pass read and write the running sum once instead of
/// once per term; each lane sees the same operations in the same order either way.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn sum_pass<const T: usize, const FIRST: bool, const LAST: bool>(
    n: usize,
    ks: [&[f64]; T],
    ws: [f64; T],
    acc: &mut [f64],
    x: &[f64],
    h: &[f64],
    out: &mut [f64],
) {
    let ks: [&[f64]; T] = ks.map(|k| &k[..n]);
    let acc = &mut acc[..n];
    if LAST {
        let (x, h, out) = (&x[..n], &h[..n], &mut out[..n]);
        for l in 0..n {
            let mut s = if FIRST { 0.0 } else { acc[l] };
            for t in 0..T {
                s += ws[t] * ks[t][l];
            }
            out[l] = x[l] + h[l] * s;
        }
    } else {
        for l in 0..n {
            let mut s = if FIRST { 0.0 } else { acc[l] };
            for t in 0..T {
                s += ws[t] * ks[t][l];
            }
            acc[l] = s;
        }
    }
}

/// `acc = 0 + Σ_q w_q k_q` over the nonzero weights, in increasing q, for column `off` of every
/// stage block, lanes `0..n`; with `tail = Some((x, h, out))` instead `out = x + h ⊙ acc`
/// (`acc` then holds a partial sum). The terms go through [`sum_pass`] up to [`PASS`] at a
/// time: the same additions in the same order as one term per pass, so the same bits.
#[inline(always)]
fn weighted_sum(
    n: usize,
    k: &[f64],
    blk: usize,
    off: usize,
    w: &[f64],
    acc: &mut [f64],
    tail: Option<(&[f64], &[f64], &mut [f64])>,
) {
    let col = |q: usize| &k[q * blk + off..q * blk + off + n];
    // Rows have at most 16 weights (DOP853's dense rows; its stage rows 12).
    debug_assert!(w.len() <= 16, "a row of {} weights", w.len());
    let mut terms = [(0usize, 0.0f64); 16];
    let mut m = 0;
    for (q, &wq) in w.iter().enumerate() {
        if wq != 0.0 {
            terms[m] = (q, wq);
            m += 1;
        }
    }
    let (x, h, out, last) = match tail {
        Some((x, h, out)) => (x, h, out, true),
        None => (&[][..], &[][..], &mut [][..], false),
    };
    if m == 0 {
        acc[..n].fill(0.0);
        if last {
            for l in 0..n {
                out[l] = x[l] + h[l] * acc[l];
            }
        }
        return;
    }
    macro_rules! go {
        ($i:expr, $T:literal) => {{
            let g = &terms[$i..$i + $T];
            let ks: [&[f64]; $T] = std::array::from_fn(|j| col(g[j].0));
            let ws: [f64; $T] = std::array::from_fn(|j| g[j].1);
            match ($i == 0, last && $i + $T == m) {
                (true, true) => sum_pass::<$T, true, true>(n, ks, ws, acc, x, h, out),
                (true, false) => sum_pass::<$T, true, false>(n, ks, ws, acc, x, h, out),
                (false, true) => sum_pass::<$T, false, true>(n, ks, ws, acc, x, h, out),
                (false, false) => sum_pass::<$T, false, false>(n, ks, ws, acc, x, h, out),
            }
        }};
    }
    in_passes!(m, go);
}

/// [`sum_pass`] for two rows over the same `T` stage columns: both running sums in one pass,
/// each column read once.
#[inline(always)]
fn sum_pass2<const T: usize, const FIRST: bool>(
    n: usize,
    ks: [&[f64]; T],
    wa: [f64; T],
    wb: [f64; T],
    acc_a: &mut [f64],
    acc_b: &mut [f64],
) {
    let ks: [&[f64]; T] = ks.map(|k| &k[..n]);
    let (acc_a, acc_b) = (&mut acc_a[..n], &mut acc_b[..n]);
    for l in 0..n {
        let mut a = if FIRST { 0.0 } else { acc_a[l] };
        let mut b = if FIRST { 0.0 } else { acc_b[l] };
        for t in 0..T {
            a += wa[t] * ks[t][l];
            b += wb[t] * ks[t][l];
        }
        acc_a[l] = a;
        acc_b[l] = b;
    }
}

/// Two [`weighted_sum`]s, `acc_a = 0 + Σ_q wa_q k_q` and `acc_b = 0 + Σ_q wb_q k_q`: when the
/// two rows have their nonzero weights at the same stages (DOP853's error rows), both sums run
/// in the same passes ([`sum_pass2`]); otherwise one after the other. Same bits either way.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn weighted_sum2(
    n: usize,
    k: &[f64],
    blk: usize,
    off: usize,
    wa: &[f64],
    wb: &[f64],
    acc_a: &mut [f64],
    acc_b: &mut [f64],
) {
    let same = wa.len() == wb.len() && wa.iter().zip(wb).all(|(a, b)| (*a == 0.0) == (*b == 0.0));
    if !same || wa.len() > 16 {
        weighted_sum(n, k, blk, off, wa, acc_a, None);
        weighted_sum(n, k, blk, off, wb, acc_b, None);
        return;
    }
    let col = |q: usize| &k[q * blk + off..q * blk + off + n];
    let mut terms = [(0usize, 0.0f64, 0.0f64); 16];
    let mut m = 0;
    for (q, (&a, &b)) in wa.iter().zip(wb).enumerate() {
        if a != 0.0 {
            terms[m] = (q, a, b);
            m += 1;
        }
    }
    if m == 0 {
        acc_a[..n].fill(0.0);
        acc_b[..n].fill(0.0);
        return;
    }
    macro_rules! go {
        ($i:expr, $T:literal) => {{
            let g = &terms[$i..$i + $T];
            let ks: [&[f64]; $T] = std::array::from_fn(|j| col(g[j].0));
            let wa: [f64; $T] = std::array::from_fn(|j| g[j].1);
            let wb: [f64; $T] = std::array::from_fn(|j| g[j].2);
            if $i == 0 {
                sum_pass2::<$T, true>(n, ks, wa, wb, acc_a, acc_b)
            } else {
                sum_pass2::<$T, false>(n, ks, wa, wb, acc_a, acc_b)
            }
        }};
    }
    in_passes!(m, go);
}

/// One lane of [`weighted_sum`]: the same terms, skipped and ordered identically.
#[inline(always)]
fn lane_sum(k: &[f64], blk: usize, off: usize, w: &[f64]) -> f64 {
    let mut acc = 0.0;
    for (q, &wq) in w.iter().enumerate() {
        if wq != 0.0 {
            acc += wq * k[q * blk + off];
        }
    }
    acc
}

/// The method a tableau belongs to (for the one-lane dispatch).
#[inline]
fn method_of(tab: &Tableau) -> Method {
    match tab.n_stages {
        5 => Method::Rk4 { h: 0.0 },
        7 => Method::Dopri5,
        _ => Method::Dop853,
    }
}

/// One lane of [`stage_input`] with a compile-time row `w` (lets the compiler unroll the sum
/// and drop the zero weights; the surviving operations and their order are unchanged).
#[inline(always)]
fn one_lane_row<const N: usize>(st: &mut Store, last: bool, w: &[f64; N]) {
    if st.stride == 1 {
        one_lane_row_contiguous(st, last, w)
    } else {
        one_lane_row_strided(st, last, w)
    }
}

/// [`one_lane_row`] for any layout (lane 0 of strided blocks).
#[inline(always)]
fn one_lane_row_strided(st: &mut Store, last: bool, w: &[f64]) {
    let (blk, stride, h) = (st.blk(), st.stride, st.h[0]);
    for j in 0..st.dim {
        let off = j * stride;
        let v = st.x[off] + h * lane_sum(&st.k, blk, off, w);
        if last {
            st.xn[off] = v;
        } else {
            st.y[off] = v;
        }
    }
}

/// Evaluates `$body` with the state dimension `$d` as a compile-time constant `$D` for the
/// dimensions of the shipped models (2 … 12, even), else `$dynamic`: fixed-size loops unroll
/// and vectorise where a loop over a run-time `d = 4` does not.
macro_rules! with_dim {
    ($d:expr, $D:ident => $body:expr, _ => $dynamic:expr) => {
        match $d {
            2 => {
                const $D: usize = 2;
                $body
            }
            4 => {
                const $D: usize = 4;
                $body
            }
            6 => {
                const $D: usize = 6;
                $body
            }
            8 => {
                const $D: usize = 8;
                $body
            }
            10 => {
                const $D: usize = 10;
                $body
            }
            12 => {
                const $D: usize = 12;
                $body
            }
            _ => $dynamic,
        }
    };
}
pub(crate) use with_dim;

/// The first `D` elements of `v` as an array reference.
#[inline(always)]
fn arr<const D: usize>(v: &[f64]) -> &[f64; D] {
    v[..D].try_into().expect("block holds D values")
}

/// `0 + Σ_q w_q k_q` over the nonzero weights in increasing q, componentwise, for contiguous
/// stage vectors `k = [k₀ | k₁ | …]` of length `D`.
#[inline(always)]
pub(crate) fn combine_fixed<const D: usize, const N: usize>(k: &[f64], w: &[f64; N]) -> [f64; D] {
    let mut acc = [0.0; D];
    for (&wq, kq) in w.iter().zip(k.chunks_exact(D)) {
        if wq == 0.0 {
            continue;
        }
        for (a, &kv) in acc.iter_mut().zip(kq) {
            *a += wq * kv;
        }
    }
    acc
}

/// [`one_lane_row`] when the lane's blocks are contiguous (`stride = 1`, the scalar
/// integrator) and the dimension is a compile-time `D`: each component sees the same
/// operations in the same order (`0 + Σ_q w_q k_q` in increasing q over the nonzero weights,
/// then `x + h·acc`).
#[inline(always)]
fn one_lane_row_fixed<const D: usize, const N: usize>(st: &mut Store, last: bool, w: &[f64; N]) {
    let v = row_fixed::<D, N>(arr::<D>(&st.x), st.h[0], &st.k, w);
    let out = if last {
        &mut st.xn[..D]
    } else {
        &mut st.y[..D]
    };
    out.copy_from_slice(&v);
}

/// `x₀ + h·(0 + Σ_q w_q k_q)` componentwise, the sum over the nonzero weights in increasing q,
/// for contiguous stage vectors `k = [k₀ | k₁ | …]` of length `D`: the one-lane stage input
/// of [`one_lane_row_fixed`] and of the scalar integrator's register loop.
#[inline(always)]
pub(crate) fn row_fixed<const D: usize, const N: usize>(
    x: &[f64; D],
    h: f64,
    k: &[f64],
    w: &[f64; N],
) -> [f64; D] {
    let acc = combine_fixed::<D, N>(k, w);
    let mut out = [0.0; D];
    for j in 0..D {
        out[j] = x[j] + h * acc[j];
    }
    out
}

/// [`one_lane_row`] for contiguous blocks: fixed dimensions unrolled, others by the lane code.
#[inline(always)]
fn one_lane_row_contiguous<const N: usize>(st: &mut Store, last: bool, w: &[f64; N]) {
    with_dim!(st.dim, D => one_lane_row_fixed::<D, N>(st, last, w), _ => one_lane_row_strided(st, last, w))
}

/// [`stage_input`] for one lane, dispatched to constant rows.
#[inline(always)]
fn stage_input_one(st: &mut Store, method: Method, q: usize) {
    use tableau::*;
    match (method, q) {
        (Method::Rk4 { .. }, 1) => one_lane_row(st, false, &RK4_A1),
        (Method::Rk4 { .. }, 2) => one_lane_row(st, false, &RK4_A2),
        (Method::Rk4 { .. }, 3) => one_lane_row(st, false, &RK4_A3),
        (Method::Rk4 { .. }, _) => one_lane_row(st, true, &RK4_A4),
        (Method::Dopri5, 1) => one_lane_row(st, false, &DP5_A1),
        (Method::Dopri5, 2) => one_lane_row(st, false, &DP5_A2),
        (Method::Dopri5, 3) => one_lane_row(st, false, &DP5_A3),
        (Method::Dopri5, 4) => one_lane_row(st, false, &DP5_A4),
        (Method::Dopri5, 5) => one_lane_row(st, false, &DP5_A5),
        (Method::Dopri5, _) => one_lane_row(st, true, &DP5_A6),
        (Method::Dop853, 1) => one_lane_row(st, false, &DOP_A1),
        (Method::Dop853, 2) => one_lane_row(st, false, &DOP_A2),
        (Method::Dop853, 3) => one_lane_row(st, false, &DOP_A3),
        (Method::Dop853, 4) => one_lane_row(st, false, &DOP_A4),
        (Method::Dop853, 5) => one_lane_row(st, false, &DOP_A5),
        (Method::Dop853, 6) => one_lane_row(st, false, &DOP_A6),
        (Method::Dop853, 7) => one_lane_row(st, false, &DOP_A7),
        (Method::Dop853, 8) => one_lane_row(st, false, &DOP_A8),
        (Method::Dop853, 9) => one_lane_row(st, false, &DOP_A9),
        (Method::Dop853, 10) => one_lane_row(st, false, &DOP_A10),
        (Method::Dop853, 11) => one_lane_row(st, false, &DOP_A11),
        (Method::Dop853, _) => one_lane_row(st, true, &DOP_A12),
    }
}

/// Input of stage `q ≥ 1`: `x₀ + h ⊙ Σ_p a_{qp} k_p`, written to `y`, or to `xn` for the last
/// stage (whose row is b, so that the input is x₁).
#[inline(always)]
pub(crate) fn stage_input(st: &mut Store, tab: &Tableau, n: usize, q: usize) {
    let blk = st.blk();
    let stride = st.stride;
    let a = tab.a[q];
    let last = q + 1 == tab.n_stages;
    if n == 1 {
        stage_input_one(st, method_of(tab), q);
        return;
    }
    for j in 0..st.dim {
        let off = j * stride;
        let out = if last { &mut st.xn } else { &mut st.y };
        let tail = (&st.x[off..off + n], &st.h[..n], &mut out[off..off + n]);
        weighted_sum(n, &st.k, blk, off, a, &mut st.s1, Some(tail));
    }
}

/// Per-lane error norm of the attempt into `st.err` (HNW I, eq. II.4.11, weights
/// `sk = atol + rtol·max(|x₀|, |x₁|)`):
/// - DOPRI5: `err = √(1/d · Σ_i (h·Σ_q e_q k_{q,i} / sk_i)²)`;
/// - DOP853: the stretched combination of the 5th- and 3rd-order estimates of the code DOP853
///   (HNW I §II.10): `err = |h|·E₅ / √(d·(E₅ + 0.01·E₃))` with `E₅ = Σ (err5_i/sk_i)²`,
///   `E₃ = Σ (err3_i/sk_i)²`;
/// - RK4: 0.
///
/// In every method a non-finite x₁ or f(x₁) makes the norm NaN (`v − v` is 0 for finite v).
#[inline(always)]
pub(crate) fn error_norm(st: &mut Store, method: Method, tab: &Tableau, opts: &Options, n: usize) {
    let blk = st.blk();
    let stride = st.stride;
    let dim = st.dim;
    let last = tab.n_stages - 1;
    let (rtol, atol) = (opts.rtol, opts.atol);
    if n == 1 {
        (st.err[0], st.s2[0]) = if st.stride == 1 && st.err_dim == st.dim {
            with_dim!(st.dim, D => match method {
                Method::Rk4 { .. } => error_norm_one(st, method, tab, opts),
                _ => error_norm_fixed::<D>(arr::<D>(&st.x), arr::<D>(&st.xn), &st.k, st.h[0], method, tab, opts),
            }, _ => error_norm_one(st, method, tab, opts))
        } else {
            error_norm_one(st, method, tab, opts)
        };
        return;
    }
    st.err[..n].fill(0.0);
    st.s3[..n].fill(0.0);
    let err_dim = st.err_dim;
    for j in 0..dim {
        let off = j * stride;
        if j >= err_dim {
            // Outside the error control: only the finiteness check (adds +0.0 when finite).
            let x1 = &st.xn[off..off + n];
            let f1 = &st.k[last * blk + off..last * blk + off + n];
            let acc = &mut st.err[..n];
            for l in 0..n {
                acc[l] += poison(x1[l]) + poison(f1[l]);
            }
            continue;
        }
        match method {
            Method::Rk4 { .. } => {}
            Method::Dopri5 => {
                weighted_sum(n, &st.k, blk, off, &tableau::DOPRI5_E, &mut st.s1, None)
            }
            Method::Dop853 => {
                weighted_sum2(
                    n,
                    &st.k,
                    blk,
                    off,
                    &tableau::DOP853_ER,
                    &tableau::DOP853_B,
                    &mut st.s1,
                    &mut st.s2,
                );
            }
        }
        let x0 = &st.x[off..off + n];
        let x1 = &st.xn[off..off + n];
        let f1 = &st.k[last * blk + off..last * blk + off + n];
        let h = &st.h[..n];
        let e = &st.s1[..n];
        let acc = &mut st.err[..n];
        match method {
            Method::Rk4 { .. } => {
                for l in 0..n {
                    acc[l] += poison(x1[l]) + poison(f1[l]);
                }
            }
            Method::Dopri5 => {
                for l in 0..n {
                    let sk = atol + rtol * x0[l].abs().max(x1[l].abs());
                    let r = h[l] * e[l] / sk;
                    acc[l] += r * r + poison(x1[l]) + poison(f1[l]);
                }
            }
            Method::Dop853 => {
                let [b1, b9, b12] = tableau::DOP853_BHH;
                let k0 = &st.k[off..off + n];
                let k8 = &st.k[8 * blk + off..8 * blk + off + n];
                let k11 = &st.k[11 * blk + off..11 * blk + off + n];
                let bs = &st.s2[..n];
                let acc3 = &mut st.s3[..n];
                for l in 0..n {
                    let sk = atol + rtol * x0[l].abs().max(x1[l].abs());
                    let e3 = bs[l] - b1 * k0[l] - b9 * k8[l] - b12 * k11[l];
                    let r5 = e[l] / sk;
                    let r3 = e3 / sk;
                    acc[l] += r5 * r5 + poison(x1[l]) + poison(f1[l]);
                    acc3[l] += r3 * r3;
                }
            }
        }
    }
    match method {
        Method::Rk4 { .. } => {}
        Method::Dopri5 => {
            let inv_d = 1.0 / err_dim as f64;
            let (err, q) = (&mut st.err[..n], &mut st.s2[..n]);
            for l in 0..n {
                (err[l], q[l]) = dopri5_norm(err[l] * inv_d, tab);
            }
        }
        Method::Dop853 => {
            let d = err_dim as f64;
            let (err, q, e3) = (&mut st.err[..n], &mut st.s2[..n], &st.s3[..n]);
            let h = &st.h[..n];
            for l in 0..n {
                let e5 = err[l];
                let mut deno = e5 + 0.01 * e3[l];
                if deno <= 0.0 {
                    deno = 1.0;
                }
                err[l] = h[l].abs() * e5 * (1.0 / (d * deno)).sqrt();
                q[l] = dop853_inverse_power(err[l]);
            }
        }
    }
}

/// [`error_norm`] for a single lane (lane 0): the same operations in the same order. Returns
/// the norm and the controller's `q = err^(−α)` (see [`decide`]; 0 for RK4).
#[inline(always)]
fn error_norm_one(st: &Store, method: Method, tab: &Tableau, opts: &Options) -> (f64, f64) {
    let blk = st.blk();
    let stride = st.stride;
    let dim = st.dim;
    let err_dim = st.err_dim;
    let last = engine_last(method);
    let (rtol, atol) = (opts.rtol, opts.atol);
    let h = st.h[0];
    let mut acc = 0.0;
    let mut acc3 = 0.0;
    for j in 0..dim {
        let off = j * stride;
        let (x0, x1, f1) = (st.x[off], st.xn[off], st.k[last * blk + off]);
        if j >= err_dim {
            // Outside the error control: only the finiteness check (adds +0.0 when finite).
            acc += poison(x1) + poison(f1);
            continue;
        }
        match method {
            Method::Rk4 { .. } => {
                acc += poison(x1) + poison(f1);
            }
            Method::Dopri5 => {
                let e = lane_sum(&st.k, blk, off, &tableau::DOPRI5_E);
                let sk = atol + rtol * x0.abs().max(x1.abs());
                let r = h * e / sk;
                acc += r * r + poison(x1) + poison(f1);
            }
            Method::Dop853 => {
                let [b1, b9, b12] = tableau::DOP853_BHH;
                let e = lane_sum(&st.k, blk, off, &tableau::DOP853_ER);
                let bs = lane_sum(&st.k, blk, off, &tableau::DOP853_B);
                let sk = atol + rtol * x0.abs().max(x1.abs());
                let e3 =
                    bs - b1 * st.k[off] - b9 * st.k[8 * blk + off] - b12 * st.k[11 * blk + off];
                let r5 = e / sk;
                let r3 = e3 / sk;
                acc += r5 * r5 + poison(x1) + poison(f1);
                acc3 += r3 * r3;
            }
        }
    }
    match method {
        Method::Rk4 { .. } => (acc, 0.0),
        Method::Dopri5 => {
            let inv_d = 1.0 / err_dim as f64;
            dopri5_norm(acc * inv_d, tab)
        }
        Method::Dop853 => {
            let d = err_dim as f64;
            let mut deno = acc + 0.01 * acc3;
            if deno <= 0.0 {
                deno = 1.0;
            }
            let err = h.abs() * acc * (1.0 / (d * deno)).sqrt();
            (err, dop853_inverse_power(err))
        }
    }
}

/// [`error_norm_one`] of DOPRI5 or DOP853 (not RK4) for one lane whose error is controlled on
/// every component, with a compile-time dimension `D`: x₀, x₁ and the contiguous stage vectors
/// `k = [k₀ | k₁ | …]`. The weighted stage sums run over whole vectors, then the norm sums over
/// components in increasing order as before — the same operations on the same operands.
#[inline(always)]
pub(crate) fn error_norm_fixed<const D: usize>(
    x0: &[f64; D],
    x1: &[f64; D],
    k: &[f64],
    h: f64,
    method: Method,
    tab: &Tableau,
    opts: &Options,
) -> (f64, f64) {
    let (rtol, atol) = (opts.rtol, opts.atol);
    match method {
        Method::Rk4 { .. } => unreachable!("RK4 has no error estimate"),
        Method::Dopri5 => {
            let e = combine_fixed::<D, 7>(k, &tableau::DOPRI5_E);
            let f1 = arr::<D>(&k[6 * D..]);
            let mut acc = 0.0;
            for j in 0..D {
                let sk = atol + rtol * x0[j].abs().max(x1[j].abs());
                let r = h * e[j] / sk;
                acc += r * r + poison(x1[j]) + poison(f1[j]);
            }
            dopri5_norm(acc * (1.0 / D as f64), tab)
        }
        Method::Dop853 => {
            let [b1, b9, b12] = tableau::DOP853_BHH;
            let e = combine_fixed::<D, 12>(k, &tableau::DOP853_ER);
            let bs = combine_fixed::<D, 12>(k, &tableau::DOP853_B);
            let f1 = arr::<D>(&k[12 * D..]);
            let (k0, k8, k11) = (arr::<D>(k), arr::<D>(&k[8 * D..]), arr::<D>(&k[11 * D..]));
            let (mut acc, mut acc3) = (0.0, 0.0);
            for j in 0..D {
                let sk = atol + rtol * x0[j].abs().max(x1[j].abs());
                let e3 = bs[j] - b1 * k0[j] - b9 * k8[j] - b12 * k11[j];
                let r5 = e[j] / sk;
                let r3 = e3 / sk;
                acc += r5 * r5 + poison(x1[j]) + poison(f1[j]);
                acc3 += r3 * r3;
            }
            let mut deno = acc + 0.01 * acc3;
            if deno <= 0.0 {
                deno = 1.0;
            }
            let err = h.abs() * acc * (1.0 / (D as f64 * deno)).sqrt();
            (err, dop853_inverse_power(err))
        }
    }
}

/// Index of the `f(x₁)` block.
#[inline]
fn engine_last(method: Method) -> usize {
    tableau_of(method).n_stages - 1
}

/// DOPRI5's norm and the controller's `q = err^(−α)` from the mean square `ms = err²` of the
/// scaled error (HNW I eq. II.4.11): `err = √ms`, `q = ms^(−α/2)` by [`pdw_simd::powr`] (our own
/// `exp(a·ln x)`, a few ulp from libm's `pow`, same bits everywhere). `q` is taken from `ms`,
/// not from `err`, so that the next step waits for one power, not for a square root and then a
/// power; `err` (the acceptance test and the PI memory) is computed beside it.
#[inline(always)]
fn dopri5_norm(ms: f64, tab: &Tableau) -> (f64, f64) {
    (ms.sqrt(), pdw_simd::powr(ms, -0.5 * tab.alpha))
}

/// DOP853's `q = err^(−1/8)` (HNW's dop853: α = 1/8, the `alpha` of [`tableau::DOP853`]) as
/// the reciprocal of three square roots.
#[inline(always)]
fn dop853_inverse_power(err: f64) -> f64 {
    1.0 / err.sqrt().sqrt().sqrt()
}

/// Candidate flags of rows `a..b` for the guards `specs` of their mode, from the step's end
/// points alone: bit k of `cand[l]` set when [`event::may_cross`] holds for guard k — the
/// guard's cubic over the step, from its end values and rates, comes near zero (the locator
/// first clears the flags [`event::clears_direction`] rules out). A column
/// kernel over lanes; the per-lane locator samples the flagged guards and locates events only
/// where some bit is set.
#[inline(always)]
pub(crate) fn mark_near(st: &mut Store, specs: &[crate::GuardSpec], a: usize, b: usize) {
    let stride = st.stride;
    let cand = &mut st.cand[a..b];
    cand.fill(0);
    let h = &st.h[a..b];
    for k in 0..specs.len() {
        let c = k * stride;
        let (g0, r0) = (&st.g[c + a..c + b], &st.gr[c + a..c + b]);
        let (g1, r1) = (&st.g1[c + a..c + b], &st.r1[c + a..c + b]);
        let bit = event::guard_bit(k);
        for l in 0..cand.len() {
            cand[l] |= bit * event::may_cross(g0[l], g1[l], r0[l], r1[l], h[l]) as u8;
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Per-lane control.
// ---------------------------------------------------------------------------------------------

/// Control state of one lane's current integration segment.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Ctl {
    pub t: f64,
    pub t_end: f64,
    pub mode: usize,
    /// Step to attempt next (before clipping to `t_end`).
    pub h: f64,
    /// Step of the attempt in flight.
    pub h_used: f64,
    /// The attempt in flight ends exactly at `t_end`.
    pub last: bool,
    /// The last step committed in full — accepted, no event inside, not shortened to land on
    /// `t_end` (0 before the first): the cap of a warm restart (see [`start_segment`]).
    pub h_full: f64,
    /// Previous accepted error norm (PI controller memory, HNW's `facold`).
    pub facold: f64,
    /// `safety·facold^β`, computed when `facold` is set (off the next step's critical path).
    pub pi_scale: f64,
    /// The previous attempt was rejected (then h may not grow: HNW II.4).
    pub rejected: bool,
    /// The previous rejection was caused by non-finite values.
    pub nonfinite: bool,
    /// Step attempts in this segment.
    pub attempts: usize,
    pub stats: Stats,
}

/// Outcome of one attempt for one lane.
pub(crate) enum After {
    Rejected,
    Accepted,
    Stop(StopReason),
}

/// Per-lane contiguous scratch (one set per batch: lanes are processed one after another here).
pub(crate) struct LaneScratch {
    pub xg: Vec<f64>,
    pub fg: Vec<f64>,
    pub ytmp: Vec<f64>,
    pub ev: EventScratch,
}

impl LaneScratch {
    pub fn new(dim: usize, ng: usize) -> Self {
        Self {
            xg: vec![0.0; dim],
            fg: vec![0.0; dim],
            ytmp: vec![0.0; dim],
            ev: EventScratch::new(dim, ng),
        }
    }
}

/// Start a segment for lane `l` whose state is already in `st.x`: evaluate `f(x₀)` into block 0,
/// choose the first step, and record the guard values at x₀. A guard value with
/// `|g| ≤ guard_tolerance` is stored as exactly 0: a crossing then needs the guard to be seen
/// strictly on its pre-crossing side at a later point first, so that a state placed on a guard
/// surface by a reset (with roundoff on either side) cannot re-trigger the same event.
///
/// The first step: the method's fixed step (RK4), else `opts.h_init`, else — when `resume` is
/// set and [`Options::warm_restart`] holds — the step the controller proposed when the lane's
/// previous segment of the same trajectory stopped (`ctl.h` on entry), capped by that
/// segment's last step committed in full (`ctl.h_full`, not the step that held the event: no
/// growth across a reset — on a flow the method integrates exactly, the error estimate
/// vanishes, the proposal is the largest growth factor times the last step and the event's
/// step may be far longer than the motion it ended, long enough to step over a whole flight
/// phase of a bouncing ball), else the starting-step heuristic. A segment without such a step
/// (a single step to its event or to `t_end`, or a failure) restarts cold. `resume`
/// is set only for a segment that continues the same work item, never for a lane's first
/// segment of an item: a lane's result never depends on what ran in it before.
///
/// Returns a stop reason when the segment cannot start: `NonFinite` if t is not finite,
/// `EndTime` if `t_end ≤ t` (or NaN), `NonFinite` if x₀ or f(x₀) is not finite.
#[allow(clippy::too_many_arguments)]
pub(crate) fn start_segment<S: HybridSystem + ?Sized>(
    sys: &S,
    opts: &Options,
    tab: &Tableau,
    st: &mut Store,
    l: usize,
    ctl: &mut Ctl,
    mode: usize,
    t: f64,
    t_end: f64,
    resume: bool,
    sc: &mut LaneScratch,
) -> Option<StopReason> {
    let h_prev = ctl.h.min(ctl.h_full);
    let warm = resume && opts.warm_restart && h_prev.is_finite() && h_prev > 0.0;
    *ctl = Ctl {
        t,
        t_end,
        mode,
        facold: 1e-4,
        pi_scale: if tab.beta == 0.0 {
            tab.safety
        } else {
            tab.safety * pdw_simd::powr(1e-4, tab.beta)
        },
        stats: ctl.stats,
        ..Ctl::default()
    };
    if !t.is_finite() {
        return Some(StopReason::NonFinite);
    }
    if !(t_end > t) {
        return Some(StopReason::EndTime);
    }
    let stride = st.stride;
    Store::gather(&st.x, stride, l, &mut sc.xg);
    if !sc.xg.iter().all(|v| v.is_finite()) {
        return Some(StopReason::NonFinite);
    }
    sys.flow(&mut sc.ev.model, mode, &sc.xg, &mut sc.fg);
    ctl.stats.rhs_evals += 1;
    Store::scatter(&mut st.k, stride, l, &sc.fg);
    if !sc.fg.iter().all(|v| v.is_finite()) {
        return Some(StopReason::NonFinite);
    }
    let h = match opts.method {
        Method::Rk4 { h } => h,
        _ => match opts.h_init {
            Some(h) => h,
            None if warm => h_prev,
            None => initial_step(sys, st.err_dim, mode, tab, opts, ctl, sc),
        },
    };
    ctl.h = h.min(opts.h_max);
    let ng = sys.guards(mode).len();
    let (gv, rv) = sc.ev.gv.split_at_mut(ng);
    sys.guards_with_rates(&mut sc.ev.model, mode, &sc.xg, &sc.fg, gv, &mut rv[..ng]);
    for k in 0..ng {
        let g = gv[k];
        st.g[k * stride + l] = if g.abs() <= sys.guard_tolerance(mode, k) {
            0.0
        } else {
            g
        };
        st.gr[k * stride + l] = rv[k];
    }
    None
}

/// Starting step (HNW I, §II.4, "starting step size", in the form of the codes DOPRI5/DOP853):
/// `h₀ = 0.01·‖x₀‖/‖f₀‖` (or 10⁻⁶), one explicit Euler step to estimate ‖f'‖ ≈ ‖f(x₀+h₀f₀) − f₀‖/h₀,
/// `h₁ = (0.01/max(‖f₀‖, ‖f'‖))^{1/p}`, `h = min(100·h₀, h₁, h_max)`; norms weighted by
/// `atol + rtol·|x₀ᵢ|`, over the error-controlled components `0..err_dim`. Reads x₀ from
/// `sc.xg` and f₀ from `sc.fg`; one flow evaluation.
fn initial_step<S: HybridSystem + ?Sized>(
    sys: &S,
    err_dim: usize,
    mode: usize,
    tab: &Tableau,
    opts: &Options,
    ctl: &mut Ctl,
    sc: &mut LaneScratch,
) -> f64 {
    let (rtol, atol) = (opts.rtol, opts.atol);
    let (mut dnf, mut dny) = (0.0, 0.0);
    for (&x, &f) in sc.xg[..err_dim].iter().zip(&sc.fg[..err_dim]) {
        let sk = atol + rtol * x.abs();
        dnf += (f / sk) * (f / sk);
        dny += (x / sk) * (x / sk);
    }
    let mut h = if dnf <= 1e-10 || dny <= 1e-10 {
        1e-6
    } else {
        (dny / dnf).sqrt() * 0.01
    };
    h = h.min(opts.h_max).min(ctl.t_end - ctl.t);
    for ((y, &x), &f) in sc.ytmp.iter_mut().zip(&sc.xg).zip(&sc.fg) {
        *y = x + h * f;
    }
    let mut f1 = std::mem::take(&mut sc.ev.f1);
    sys.flow(&mut sc.ev.model, mode, &sc.ytmp, &mut f1);
    ctl.stats.rhs_evals += 1;
    let mut der2 = 0.0;
    for ((&a, &b), &x) in f1[..err_dim]
        .iter()
        .zip(&sc.fg[..err_dim])
        .zip(&sc.xg[..err_dim])
    {
        let sk = atol + rtol * x.abs();
        der2 += ((a - b) / sk) * ((a - b) / sk);
    }
    sc.ev.f1 = f1;
    let der2 = der2.sqrt() / h;
    // f64::max ignores a NaN operand: a non-finite trial derivative falls back on ‖f₀‖.
    let der12 = der2.max(dnf.sqrt());
    let h1 = if der12 <= 1e-15 {
        (h * 1e-3).max(1e-6)
    } else {
        pdw_simd::powr(0.01 / der12, 1.0 / tab.hinit_order)
    };
    let h = (100.0 * h).min(h1).min(opts.h_max);
    if h.is_finite() && h > 0.0 {
        h
    } else {
        1e-6
    }
}

/// Step for the next attempt of a lane, or the reason it cannot continue (`MaxSteps`;
/// `StepTooSmall`/`NonFinite` when `h < h_min` or `0.1·h ≤ ε·|t|`, HNW's criterion). The last
/// step is stretched to land exactly on `t_end` when `t + 1.01·h ≥ t_end` (as in DOPRI5).
#[inline]
pub(crate) fn prepare(opts: &Options, ctl: &mut Ctl) -> Result<f64, StopReason> {
    // An interrupt ends the call as a spent budget, polled every 1024 attempts
    // (see [`crate::interrupt`]; the callers turn it into `HybridError::Interrupted`).
    if ctl.attempts >= opts.max_steps
        || (ctl.attempts & 1023 == 1023 && crate::interrupt::requested())
    {
        return Err(StopReason::MaxSteps);
    }
    let h = ctl.h;
    if !(h > 0.0) || h < opts.h_min || 0.1 * h <= f64::EPSILON * ctl.t.abs() {
        return Err(if ctl.nonfinite {
            StopReason::NonFinite
        } else {
            StopReason::StepTooSmall
        });
    }
    if ctl.t + 1.01 * h >= ctl.t_end {
        ctl.h_used = ctl.t_end - ctl.t;
        ctl.last = true;
    } else {
        ctl.h_used = h;
        ctl.last = false;
    }
    Ok(ctl.h_used)
}

/// Accept or reject an attempt with error norm `err` and choose the next step (HNW I,
/// eq. II.4.13 with the PI stabilisation of the codes DOPRI5/DOP853: `h_new = h/fac`,
/// `fac = clamp(err^α / facold^β / safety, 1/fac_max, 1/fac_min)`, and no growth right after a
/// rejection; a rejection takes `h_new = h / min(1/fac_min, err^α/safety)`). A non-finite norm
/// is a rejection with `h ← h/10`. RK4 accepts every finite step and stops on a non-finite one.
///
/// The same rule in reciprocal form, so that the next step waits for one power and one
/// multiplication instead of three divisions: `q = err^(−α)` comes with the norm
/// ([`error_norm`]), `ctl.pi_scale = safety·facold^β` is set at the previous acceptance, and
/// `h_new = h·clamp(pi_scale·q, fac_min, fac_max)` on acceptance, `h·max(fac_min, safety·q)` on
/// rejection.
#[inline(always)]
pub(crate) fn decide(
    method: Method,
    tab: &Tableau,
    opts: &Options,
    ctl: &mut Ctl,
    err: f64,
    q: f64,
) -> After {
    ctl.attempts += 1;
    let h = ctl.h_used;
    if let Method::Rk4 { .. } = method {
        return if err.is_finite() {
            ctl.stats.accepted += 1;
            After::Accepted
        } else {
            ctl.stats.rejected += 1;
            After::Stop(StopReason::NonFinite)
        };
    }
    if !err.is_finite() {
        ctl.stats.rejected += 1;
        ctl.rejected = true;
        ctl.nonfinite = true;
        ctl.h = 0.1 * h;
        return After::Rejected;
    }
    ctl.nonfinite = false;
    if err <= 1.0 {
        // q = +∞ (err = 0) gives the largest growth; plain comparisons (q is never NaN here).
        let r = ctl.pi_scale * q;
        let r = if r > tab.fac_max {
            tab.fac_max
        } else if r < tab.fac_min {
            tab.fac_min
        } else {
            r
        };
        let mut h_new = h * r;
        if ctl.rejected && h_new > h {
            h_new = h;
        }
        ctl.facold = if err > 1e-4 { err } else { 1e-4 };
        if tab.beta != 0.0 {
            ctl.pi_scale = tab.safety * pdw_simd::powr(ctl.facold, tab.beta);
        }
        ctl.rejected = false;
        ctl.h = if h_new > opts.h_max {
            opts.h_max
        } else {
            h_new
        };
        ctl.stats.accepted += 1;
        After::Accepted
    } else {
        let r = tab.safety * q;
        ctl.h = h * if r < tab.fac_min { tab.fac_min } else { r };
        ctl.rejected = true;
        ctl.stats.rejected += 1;
        After::Rejected
    }
}

/// Everything that happens to lane `l` after the stage and error kernels: accept/reject, event
/// location on the accepted step, and commit of the new point. On `Stop(Guard)` the lane's `x`
/// holds the event state and `ctl.t` the event time; on `Stop(EndTime)` `x = x₁`, `t = t_end`.
///
/// With `DEFER` (a lane of a batch), an accepted step that is not the segment's last and on
/// which no guard is flagged (`cand[l] = 0`, the common case) is decided here — time, `h_full`
/// — and marked in `st.commit`; its commit (x₀ ← x₁, f(x₀) ← f(x₁), the guard values and rates
/// at x₁ kept for the next step) is left to [`commit_columns`] over all lanes after the
/// per-lane pass. The same values land in the same places: the commit is a copy.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn after_attempt<S: HybridSystem + ?Sized, const DEFER: bool>(
    sys: &S,
    method: Method,
    tab: &Tableau,
    opts: &Options,
    st: &mut Store,
    l: usize,
    ctl: &mut Ctl,
    sc: &mut LaneScratch,
) -> After {
    let err = st.err[l];
    ctl.stats.rhs_evals += (tab.n_stages - 1) as u64;
    match decide(method, tab, opts, ctl, err, st.s2[l]) {
        After::Accepted if DEFER && st.cand[l] == 0 && !ctl.last => {
            // `after_accept` with no flagged guard and not the last step: `locate` keeps the end
            // values, the state is committed, t₁ = t₀ + h, and the step was committed in full.
            let h = ctl.h_used;
            ctl.t += h;
            ctl.h_full = h;
            st.commit[l] = 1;
            After::Accepted
        }
        After::Accepted => after_accept(sys, method, tab, st, l, ctl, sc),
        other => other,
    }
}

/// The commits [`after_attempt`] left (with `DEFER`) for rows `a..b` (all in a mode with `ng`
/// guards), as column selects: where `commit` is set, x₀ ← x₁, f(x₀) ← f(x₁) and the guard
/// values and rates at x₁ become the next step's start values; the flags are cleared.
#[inline(always)]
pub(crate) fn commit_columns(st: &mut Store, tab: &Tableau, a: usize, b: usize, ng: usize) {
    let stride = st.stride;
    let blk = st.blk();
    let last = tab.n_stages - 1;
    let c = &st.commit[a..b];
    // A bitwise select (all ones where the flag is set): branch-free, so it runs at vector
    // width whatever the flags, and copies the bits.
    let sel = |dst: &mut [f64], src: &[f64]| {
        let n = c.len();
        let (dst, src) = (&mut dst[..n], &src[..n]);
        for l in 0..n {
            let m = 0u64.wrapping_sub(u64::from(c[l]));
            dst[l] = f64::from_bits((src[l].to_bits() & m) | (dst[l].to_bits() & !m));
        }
    };
    for j in 0..st.dim {
        let (o, e) = (j * stride + a, j * stride + b);
        sel(&mut st.x[o..e], &st.xn[o..e]);
        let (k0, kl) = st.k.split_at_mut(last * blk);
        sel(&mut k0[o..e], &kl[o..e]);
    }
    for k in 0..ng {
        let (o, e) = (k * stride + a, k * stride + b);
        sel(&mut st.g[o..e], &st.g1[o..e]);
        sel(&mut st.gr[o..e], &st.r1[o..e]);
    }
    st.commit[a..b].fill(0);
}

/// The part of [`after_attempt`] after an acceptance: event location on the step, then the
/// commit of x₁ (or the stop at the event or at `t_end`). Returns `Accepted` or `Stop`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn after_accept<S: HybridSystem + ?Sized>(
    sys: &S,
    method: Method,
    tab: &Tableau,
    st: &mut Store,
    l: usize,
    ctl: &mut Ctl,
    sc: &mut LaneScratch,
) -> After {
    let h = ctl.h_used;
    let t0 = ctl.t;
    let t1 = if ctl.last { ctl.t_end } else { t0 + h };
    let stride = st.stride;
    let blk = st.blk();
    let last = tab.n_stages - 1;
    if let Some((guard, theta)) = event::locate(
        sys,
        method,
        ctl.mode,
        st,
        l,
        h,
        t0,
        t1,
        &mut sc.ev,
        &mut ctl.stats,
    ) {
        ctl.t = if theta == 1.0 { t1 } else { t0 + theta * h };
        Store::scatter(&mut st.x, stride, l, &sc.ev.xbest);
        return After::Stop(StopReason::Guard { guard });
    }
    // Commit x₀ ← x₁, f(x₀) ← f(x₁).
    for j in 0..st.dim {
        let i = j * stride + l;
        st.x[i] = st.xn[i];
        st.k[i] = st.k[last * blk + i];
    }
    ctl.t = t1;
    if ctl.last {
        // An end point within `guard_tolerance` of a guard surface, on its pre-crossing side and
        // moving into it (ġ = ∇g·f), is that guard's event: the next segment would count its
        // start value as 0 (see `start_segment`) and miss the crossing. Reported as a `Guard`
        // stop at t_end, whose state is as close to the surface as a located event.
        if let Some(guard) = guard_at_end(sys, st, l, ctl.mode, sc) {
            return After::Stop(StopReason::Guard { guard });
        }
        After::Stop(StopReason::EndTime)
    } else {
        ctl.h_full = h;
        After::Accepted
    }
}

/// The earliest-index guard that the committed end point of lane `l` sits on (within
/// `guard_tolerance`), strictly on its pre-crossing side, moving into the crossing and
/// admissible there; `None` otherwise (the common case costs one comparison per guard).
fn guard_at_end<S: HybridSystem + ?Sized>(
    sys: &S,
    st: &Store,
    l: usize,
    mode: usize,
    sc: &mut LaneScratch,
) -> Option<usize> {
    let stride = st.stride;
    let specs = sys.guards(mode);
    for (k, spec) in specs.iter().enumerate() {
        let g = st.g[k * stride + l];
        let pre = match spec.crossing {
            Crossing::Rising => g < 0.0,
            Crossing::Falling => g > 0.0,
            Crossing::Either => g != 0.0,
        };
        if !(pre && g.abs() <= sys.guard_tolerance(mode, k)) {
            continue;
        }
        Store::gather(&st.x, stride, l, &mut sc.xg);
        Store::gather(&st.k, stride, l, &mut sc.fg);
        let mut grad = vec![0.0; st.dim];
        sys.guard_gradient(&mut sc.ev.model, mode, k, &sc.xg, &mut grad);
        let gdot: f64 = grad.iter().zip(&sc.fg).map(|(a, b)| a * b).sum();
        let into = match spec.crossing {
            Crossing::Rising => gdot > 0.0,
            Crossing::Falling => gdot < 0.0,
            Crossing::Either => gdot * g < 0.0,
        };
        if into && sys.admissible(mode, k, &sc.xg) {
            return Some(k);
        }
    }
    None
}
