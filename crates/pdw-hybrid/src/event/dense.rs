//! The interpolants an event is detected and solved on: the cubic Hermite interpolant of a
//! step's end states and rates (HNW I, eq. II.6.7), and the methods' own dense outputs
//! (DOPRI5: Shampine's continuous extension, eq. II.6.12; DOP853: the 7th-order one of §II.10,
//! three extra flow evaluations).

use super::{EventScratch, Interp};
use crate::engine::Store;
use crate::options::{Method, Stats};
use crate::tableau;
use crate::HybridSystem;

/// Cubic Hermite basis `[c₀₀, c₀₁, c₁₀, c₁₁]` at θ (HNW I, eq. II.6.7).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[inline(always)]
pub fn hermite_basis(theta: f64) -> [f64; 4] {
    let t1 = 1.0 - theta;
    [
        (1.0 + 2.0 * theta) * t1 * t1,
        theta * theta * (3.0 - 2.0 * theta),
        theta * t1 * t1,
        -theta * theta * t1,
    ]
}

/// One component of the Hermite interpolant with basis `c` (same expression everywhere).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[inline(always)]
pub fn hermite_point(c: [f64; 4], x0: f64, x1: f64, f0: f64, f1: f64, h: f64) -> f64 {
    c[0] * x0 + c[1] * x1 + h * (c[2] * f0 + c[3] * f1)
}

/// Borrowed view of the interpolation data.
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub struct Dense<'a> {
    pub interp: Interp,
    pub h: f64,
    pub x0: &'a [f64],
    pub x1: &'a [f64],
    pub f0: &'a [f64],
    pub f1: &'a [f64],
    pub cont: &'a [f64],
}

impl Dense<'_> {
    /// State at θ ∈ (0, 1) (θ = 1 is handled by the callers with the exact x₁). The shipped
    /// models' dimensions run the same expressions with a compile-time length (unrolled, no
    /// bounds checks).
    #[inline]
    pub fn eval(&self, theta: f64, out: &mut [f64]) {
        match out.len() {
            2 => self.eval_n::<2>(theta, out),
            4 => self.eval_n::<4>(theta, out),
            6 => self.eval_n::<6>(theta, out),
            8 => self.eval_n::<8>(theta, out),
            10 => self.eval_n::<10>(theta, out),
            12 => self.eval_n::<12>(theta, out),
            _ => self.eval_dyn(theta, out),
        }
    }

    #[inline(always)]
    fn eval_n<const D: usize>(&self, theta: f64, out: &mut [f64]) {
        let out: &mut [f64; D] = (&mut out[..D]).try_into().expect("D values");
        let t1 = 1.0 - theta;
        let v = |v: &[f64]| -> [f64; D] { v[..D].try_into().expect("D values") };
        match self.interp {
            Interp::Hermite => {
                let c = hermite_basis(theta);
                let (x0, x1, f0, f1) = (v(self.x0), v(self.x1), v(self.f0), v(self.f1));
                for j in 0..D {
                    out[j] = hermite_point(c, x0[j], x1[j], f0[j], f1[j], self.h);
                }
            }
            Interp::Dopri5 => {
                let c: [[f64; D]; 5] = std::array::from_fn(|r| v(&self.cont[r * D..]));
                for j in 0..D {
                    out[j] = c[0][j]
                        + theta * (c[1][j] + t1 * (c[2][j] + theta * (c[3][j] + t1 * c[4][j])));
                }
            }
            Interp::Dop853 => {
                let c: [[f64; D]; 8] = std::array::from_fn(|r| v(&self.cont[r * D..]));
                for j in 0..D {
                    let inner = c[4][j] + theta * (c[5][j] + t1 * (c[6][j] + theta * c[7][j]));
                    out[j] = c[0][j]
                        + theta * (c[1][j] + t1 * (c[2][j] + theta * (c[3][j] + t1 * inner)));
                }
            }
        }
    }

    fn eval_dyn(&self, theta: f64, out: &mut [f64]) {
        let d = out.len();
        let t1 = 1.0 - theta;
        match self.interp {
            Interp::Hermite => {
                let c = hermite_basis(theta);
                for (j, o) in out.iter_mut().enumerate() {
                    *o = hermite_point(c, self.x0[j], self.x1[j], self.f0[j], self.f1[j], self.h);
                }
            }
            Interp::Dopri5 => {
                let c = self.cont;
                for (j, o) in out.iter_mut().enumerate() {
                    *o = c[j]
                        + theta
                            * (c[d + j]
                                + t1 * (c[2 * d + j] + theta * (c[3 * d + j] + t1 * c[4 * d + j])));
                }
            }
            Interp::Dop853 => {
                let c = self.cont;
                for (j, o) in out.iter_mut().enumerate() {
                    let inner = c[4 * d + j]
                        + theta * (c[5 * d + j] + t1 * (c[6 * d + j] + theta * c[7 * d + j]));
                    *o = c[j]
                        + theta
                            * (c[d + j]
                                + t1 * (c[2 * d + j] + theta * (c[3 * d + j] + t1 * inner)));
                }
            }
        }
    }
}

/// Fill the first four dense coefficients shared by DOPRI5 and DOP853 (HNW I, eq. II.6.12):
/// `x₀`, `x₁ − x₀`, `h f₀ − (x₁ − x₀)`, `(x₁ − x₀) − h f₁ − (h f₀ − (x₁ − x₀))`.
fn hermite_coefficients(sc: &mut EventScratch, h: f64) {
    let d = sc.x0.len();
    for j in 0..d {
        let y0 = sc.x0[j];
        let ydiff = sc.x1[j] - y0;
        let bspl = h * sc.f0[j] - ydiff;
        sc.cont[j] = y0;
        sc.cont[d + j] = ydiff;
        sc.cont[2 * d + j] = bspl;
        sc.cont[3 * d + j] = ydiff - h * sc.f1[j] - bspl;
    }
}

/// Build the method's dense output for lane `l` of `st` into `sc.cont`.
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[allow(clippy::too_many_arguments)]
pub fn build_dense<S: HybridSystem + ?Sized>(
    sys: &S,
    method: Method,
    mode: usize,
    st: &Store,
    l: usize,
    h: f64,
    sc: &mut EventScratch,
    stats: &mut Stats,
) -> Interp {
    let d = st.dim;
    let (stride, blk) = (st.stride, st.blk());
    let kq = |q: usize, j: usize| st.k[q * blk + j * stride + l];
    match method {
        Method::Rk4 { .. } => Interp::Hermite,
        Method::Dopri5 => {
            hermite_coefficients(sc, h);
            for j in 0..d {
                let mut s = 0.0;
                for (q, &w) in tableau::DOPRI5_D.iter().enumerate() {
                    if w != 0.0 {
                        s += w * kq(q, j);
                    }
                }
                sc.cont[4 * d + j] = h * s;
            }
            Interp::Dopri5
        }
        Method::Dop853 => {
            crate::engine::with_dim!(d,
                D => dop853_dense_fixed::<S, D>(sys, mode, st, l, h, sc, stats),
                _ => dop853_dense_dyn(sys, mode, st, l, h, sc, stats))
        }
    }
}

/// DOP853's dense output for any dimension: the lane's stages k₀…k₁₂ gathered once
/// (contiguous), then k₁₃…k₁₅ appended; the sums read them in the same order with the same
/// weights as [`dop853_dense_fixed`].
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub fn dop853_dense_dyn<S: HybridSystem + ?Sized>(
    sys: &S,
    mode: usize,
    st: &Store,
    l: usize,
    h: f64,
    sc: &mut EventScratch,
    stats: &mut Stats,
) -> Interp {
    let d = st.dim;
    let (stride, blk) = (st.stride, st.blk());
    for q in 0..13 {
        for j in 0..d {
            sc.kl[q * d + j] = st.k[q * blk + j * stride + l];
        }
    }
    for r in 0..3 {
        let a = tableau::DOP853_DENSE_A[r];
        for j in 0..d {
            let mut s = 0.0;
            for (q, &w) in a.iter().enumerate() {
                if w != 0.0 {
                    s += w * sc.kl[q * d + j];
                }
            }
            sc.ytmp[j] = sc.x0[j] + h * s;
        }
        let (_, rest) = sc.kl.split_at_mut((13 + r) * d);
        sys.flow(&mut sc.model, mode, &sc.ytmp, &mut rest[..d]);
        stats.rhs_evals += 1;
    }
    hermite_coefficients(sc, h);
    for (r, drow) in tableau::DOP853_D.iter().enumerate() {
        for j in 0..d {
            let mut s = 0.0;
            for (q, &w) in drow.iter().enumerate() {
                if w != 0.0 {
                    s += w * sc.kl[q * d + j];
                }
            }
            sc.cont[(4 + r) * d + j] = h * s;
        }
    }
    Interp::Dop853
}

/// DOP853's dense output (HNW I, §II.10: the three extra stages k₁₃…k₁₅ and the coefficient
/// rows `d`) for a compile-time dimension `D`: the lane's stages contiguous in a stack array,
/// every row a constant of the tableau, so each sum is unrolled over its nonzero weights with
/// no test of a weight at run time — the same terms in the same order as
/// [`dop853_dense_dyn`] (`0 + Σ_q w_q k_q` in increasing q), so the same bits.
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[inline(always)]
pub fn dop853_dense_fixed<S: HybridSystem + ?Sized, const D: usize>(
    sys: &S,
    mode: usize,
    st: &Store,
    l: usize,
    h: f64,
    sc: &mut EventScratch,
    stats: &mut Stats,
) -> Interp {
    use crate::engine::{combine_fixed, row_fixed};
    let (stride, blk) = (st.stride, st.blk());
    // k₀…k₁₅; `as_flattened` reads them as one slice, stage q at [q·D, (q + 1)·D).
    // Only the stages some row weighs (k₁…k₄ have zero weight in all of them): the others
    // would be strided loads never read.
    let mut kl = [[0.0f64; D]; 16];
    for (q, kq) in kl.iter_mut().enumerate().take(13) {
        let used = tableau::DOP853_DENSE_A.iter().any(|a| a[q] != 0.0)
            || tableau::DOP853_D.iter().any(|d| d[q] != 0.0);
        if !used {
            continue;
        }
        for (j, v) in kq.iter_mut().enumerate() {
            *v = st.k[q * blk + j * stride + l];
        }
    }
    let x0: [f64; D] = sc.x0[..D].try_into().expect("D values");
    let model = &mut sc.model;
    let mut extra = |kl: &mut [[f64; D]; 16], q: usize, y: [f64; D]| {
        sys.flow(model, mode, &y, &mut kl[q]);
        stats.rhs_evals += 1;
    };
    let y = row_fixed::<D, 13>(&x0, h, kl.as_flattened(), &tableau::DOP853_DENSE_A13);
    extra(&mut kl, 13, y);
    let y = row_fixed::<D, 14>(&x0, h, kl.as_flattened(), &tableau::DOP853_DENSE_A14);
    extra(&mut kl, 14, y);
    let y = row_fixed::<D, 15>(&x0, h, kl.as_flattened(), &tableau::DOP853_DENSE_A15);
    extra(&mut kl, 15, y);
    let kl = kl.as_flattened();
    hermite_coefficients(sc, h);
    let rows = [
        combine_fixed::<D, 16>(kl, &tableau::DOP853_D[0]),
        combine_fixed::<D, 16>(kl, &tableau::DOP853_D[1]),
        combine_fixed::<D, 16>(kl, &tableau::DOP853_D[2]),
        combine_fixed::<D, 16>(kl, &tableau::DOP853_D[3]),
    ];
    for (r, s) in rows.iter().enumerate() {
        for (c, &v) in sc.cont[(4 + r) * D..(5 + r) * D].iter_mut().zip(s) {
            *c = h * v;
        }
    }
    Interp::Dop853
}

/// x₀, x₁, f(x₀), f(x₁) of lane `l` into the scratch's contiguous vectors.
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub fn gather_ends(st: &Store, l: usize, method: Method, sc: &mut EventScratch) {
    let (stride, blk) = (st.stride, st.blk());
    let last = crate::engine::tableau_of(method).n_stages - 1;
    Store::gather(&st.x, stride, l, &mut sc.x0);
    Store::gather(&st.xn, stride, l, &mut sc.x1);
    Store::gather(&st.k[..blk], stride, l, &mut sc.f0);
    Store::gather(&st.k[last * blk..(last + 1) * blk], stride, l, &mut sc.f1);
}
