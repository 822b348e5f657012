//! An affine guard along a nested dense output (DOPRI5, DOP853) is a scalar polynomial in θ
//! with the nesting of the state's interpolant: its rows ([`guard_poly`]), its value and
//! derivative by one Horner pass ([`nested_with_derivative`]), its values at the samples
//! ([`nested_values`]).

use super::Interp;
use crate::system::Scratch;
use crate::HybridSystem;

/// Largest number of dense-output coefficient rows (DOP853's 8).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub const POLY_ROWS: usize = 8;

/// Number of coefficient rows of a dense output in nested form (0: not in nested form).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[inline]
pub fn nested_rows(interp: Interp) -> usize {
    match interp {
        Interp::Hermite => 0,
        Interp::Dopri5 => 5,
        Interp::Dop853 => POLY_ROWS,
    }
}

/// The dense outputs of DOPRI5 and DOP853 in their nested form (HNW I, eq. II.6.12 and the
/// code DOP853's `contd8`), `c₀ + θ(c₁ + (1−θ)(c₂ + θ(c₃ + (1−θ)(c₄ + …))))`, with `n` rows
/// `c = [c₀, …, c_{n−1}]` of scalars, and its derivative in θ carried along the same Horner
/// chain (`v_r = c_r + s_r v_{r+1}`, `s_r = θ` for even r and `1 − θ` for odd r, so
/// `v'_r = s_r v'_{r+1} ± v_{r+1}`). The multipliers are those of [`Dense::eval`].
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[inline(always)]
pub fn nested_with_derivative(c: &[f64], n: usize, theta: f64) -> (f64, f64) {
    match n {
        5 => nested_fixed::<5>(c, theta),
        _ => nested_fixed::<POLY_ROWS>(c, theta),
    }
}

/// The value of [`nested_with_derivative`] at several points at once (the same operations per
/// point, so the same bits; the points side by side in vector registers).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[inline(always)]
pub fn nested_values<const P: usize>(c: &[f64], n: usize, theta: [f64; P]) -> [f64; P] {
    fn fixed<const N: usize, const P: usize>(c: &[f64], theta: [f64; P]) -> [f64; P] {
        let c: &[f64; N] = c[..N].try_into().expect("N rows");
        let mut v = [c[N - 1]; P];
        for r in (0..N - 1).rev() {
            for p in 0..P {
                let s = if r % 2 == 0 { theta[p] } else { 1.0 - theta[p] };
                v[p] = c[r] + s * v[p];
            }
        }
        v
    }
    match n {
        5 => fixed::<5, P>(c, theta),
        _ => fixed::<POLY_ROWS, P>(c, theta),
    }
}

/// [`nested_with_derivative`] with a compile-time number of rows `N` (unrolled).
#[inline(always)]
fn nested_fixed<const N: usize>(c: &[f64], theta: f64) -> (f64, f64) {
    let c: &[f64; N] = c[..N].try_into().expect("N rows");
    let t1 = 1.0 - theta;
    let mut v = c[N - 1];
    let mut dv = 0.0;
    for r in (0..N - 1).rev() {
        if r % 2 == 0 {
            dv = theta * dv + v;
            v = c[r] + theta * v;
        } else {
            dv = t1 * dv - v;
            v = c[r] + t1 * v;
        }
    }
    (v, dv)
}

/// Coefficients of an affine guard `g(x) = a·x + b` along the dense output in nested form:
/// since every row of the state's interpolant enters linearly, `g(x(θ))` is the same nested
/// polynomial with the scalar rows `G₀ = g(c₀)` (c₀ = x₀) and `G_r = g(c_r) − g(0) = a·c_r`
/// for r ≥ 1. Written to `out[..rows]`.
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[allow(clippy::too_many_arguments)]
pub fn guard_poly<S: HybridSystem + ?Sized>(
    sys: &S,
    ws: &mut Scratch,
    mode: usize,
    k: usize,
    cont: &[f64],
    zero: &[f64],
    rows: usize,
    out: &mut [f64],
) {
    let d = zero.len();
    let b = sys.guard(ws, mode, k, zero);
    out[0] = sys.guard(ws, mode, k, &cont[..d]);
    for r in 1..rows {
        out[r] = sys.guard(ws, mode, k, &cont[r * d..(r + 1) * d]) - b;
    }
}
