//! The scalar types the per-link step functions of [`crate::spatial`] run on: `f64` for the
//! kernels, and the forward-mode dual number [`Dual`] for exact derivatives
//! ([`crate::derivatives`]).
//!
//! # Forward-mode dual numbers
//! A dual number `x = v + Σᵢ dᵢ εᵢ` with `εᵢ εⱼ = 0` carries a value `v` and the directional
//! derivatives `dᵢ = ∂x/∂sᵢ` along `N` seed directions. Arithmetic on it is the chain rule:
//!
//! ```text
//! (a ± b)' = a' ± b',   (a b)' = a' b + a b',   (a / b)' = (a' − (a/b) b') / b,
//! sin(a)' = cos(a) a',  cos(a)' = −sin(a) a'
//! ```
//! so running a function on duals seeded with `dᵢ = δᵢⱼ` at input `j` returns the function's
//! value and its exact Jacobian columns (to rounding), with no step size to choose.
//!
//! The value part of every operation is the very IEEE operation the `f64` code performs (sin/cos
//! by [`crate::spatial::sincos`], the kernel's own routine), so the value of a dual computation is
//! bit-identical to the `f64` computation through the same generic code.
//!
//! A `Dual<N>` lives on the stack (`N + 1` doubles); nothing here allocates.

use std::ops::{Add, Div, Mul, Neg, Sub};

use crate::spatial;

/// The arithmetic the per-link step functions need: a `Copy` field-like type with `+ − × ÷`,
/// negation, constants from `f64` and `sin_cos`.
///
/// For `f64` every method is the plain IEEE operation (`cst` is the identity), so generic code
/// instantiated at `f64` compiles to the same operations in the same order as hand-written `f64`
/// code.
pub trait Scalar:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// The constant `x` (zero derivative part for duals).
    fn cst(x: f64) -> Self;
    /// `(sin x, cos x)`; the value by [`spatial::sincos`].
    fn sin_cos(self) -> (Self, Self);
    /// The value (the real part of a dual number).
    fn re(self) -> f64;
    /// `(sin, cos)` of every element of `x` into `s` and `c` (same length), each element as
    /// [`Scalar::sin_cos`] gives it.
    #[inline(always)]
    fn sin_cos_lanes(x: &[Self], s: &mut [Self], c: &mut [Self]) {
        for ((x, s), c) in x.iter().zip(s.iter_mut()).zip(c.iter_mut()) {
            (*s, *c) = x.sin_cos();
        }
    }
}

impl Scalar for f64 {
    #[inline(always)]
    fn cst(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        spatial::sincos(self)
    }
    #[inline(always)]
    fn sin_cos_lanes(x: &[f64], s: &mut [f64], c: &mut [f64]) {
        spatial::sincos_slice(x, s, c);
    }
    #[inline(always)]
    fn re(self) -> f64 {
        self
    }
}

/// Forward-mode dual number with `N` derivative directions: value `v`, derivatives `d`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dual<const N: usize> {
    /// Value.
    pub v: f64,
    /// Derivatives along the `N` seed directions.
    pub d: [f64; N],
}

impl<const N: usize> Dual<N> {
    /// A constant: value `v`, zero derivatives.
    #[inline(always)]
    pub fn constant(v: f64) -> Self {
        Dual { v, d: [0.0; N] }
    }
    /// An independent variable: value `v`, derivative 1 along direction `i` (`i < N`).
    #[inline(always)]
    pub fn variable(v: f64, i: usize) -> Self {
        let mut d = [0.0; N];
        d[i] = 1.0;
        Dual { v, d }
    }
}

impl<const N: usize> Scalar for Dual<N> {
    #[inline(always)]
    fn cst(x: f64) -> Self {
        Dual::constant(x)
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = spatial::sincos(self.v);
        let mut ds = [0.0; N];
        let mut dc = [0.0; N];
        for i in 0..N {
            ds[i] = c * self.d[i];
            dc[i] = -(s * self.d[i]);
        }
        (Dual { v: s, d: ds }, Dual { v: c, d: dc })
    }
    #[inline(always)]
    fn re(self) -> f64 {
        self.v
    }
}

impl<const N: usize> Add for Dual<N> {
    type Output = Self;
    #[inline(always)]
    fn add(self, b: Self) -> Self {
        let mut d = self.d;
        for (x, y) in d.iter_mut().zip(&b.d) {
            *x += y;
        }
        Dual { v: self.v + b.v, d }
    }
}

impl<const N: usize> Sub for Dual<N> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, b: Self) -> Self {
        let mut d = self.d;
        for (x, y) in d.iter_mut().zip(&b.d) {
            *x -= y;
        }
        Dual { v: self.v - b.v, d }
    }
}

impl<const N: usize> Mul for Dual<N> {
    type Output = Self;
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // three arrays in lockstep
    fn mul(self, b: Self) -> Self {
        let mut d = [0.0; N];
        for i in 0..N {
            d[i] = self.d[i] * b.v + self.v * b.d[i];
        }
        Dual { v: self.v * b.v, d }
    }
}

impl<const N: usize> Div for Dual<N> {
    type Output = Self;
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // three arrays in lockstep
    fn div(self, b: Self) -> Self {
        let v = self.v / b.v;
        let mut d = [0.0; N];
        for i in 0..N {
            d[i] = (self.d[i] - v * b.d[i]) / b.v;
        }
        Dual { v, d }
    }
}

impl<const N: usize> Neg for Dual<N> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x = -*x;
        }
        Dual { v: -self.v, d }
    }
}
