//! `sin` and `cos` that vectorise on every instruction-set path and give the same bits on all.
//!
//! A library `sin`/`cos` is an opaque call: it cannot be inlined into the vector loops, and
//! `wide`'s vector routine, compiled for the portable baseline, is an out-of-line SSE2 function
//! that the AVX copies of the hot loops cannot widen. This routine is plain IEEE arithmetic
//! marked `#[inline(always)]`: inside a loop over lanes the compiler vectorises it at the width
//! of the path it is compiled for, and, being a fixed sequence of correctly rounded operations
//! (no fused multiply-add), it rounds identically on every path, for one value or many.
//!
//! Method (the classical one of fdlibm, Sun Microsystems 1993; formulas, not code):
//! 1. Quadrant `n = round(x·2/π)` by the round-to-nearest trick `(y + 1.5·2⁵²) − 1.5·2⁵²`, and
//!    `n mod 4` from the low mantissa bits of `y + 1.5·2⁵²`.
//! 2. Cody–Waite reduction `r = ((x − n·P₁) − n·P₂) − n·P₃` with π/2 = P₁ + P₂ + P₃ split into
//!    33-, 33- and 53-bit parts (`n·P₁`, `n·P₂` exact for |n| < 2²⁰), so |r| ≤ π/4.
//! 3. Minimax polynomials on [−π/4, π/4] (fdlibm `__kernel_sin`/`__kernel_cos`):
//!    `sin r = r + r³(S₁ + r²(S₂ + … + r²S₆))`,
//!    `cos r = w + (((1 − w) − r²/2) + r⁴(C₁ + … + r¹⁰C₆))` with `w = 1 − r²/2`.
//! 4. `(sin x, cos x)` = `(s, c)`, `(c, −s)`, `(−s, −c)`, `(−c, s)` for `n mod 4` = 0, 1, 2, 3.
//!
//! Accuracy: within 2 ulp of the platform libm (glibc, itself < 1 ulp from the exact value) on
//! |x| ≤ 10³ and equal to it for most arguments (tested over 4·10⁶ values: counts printed by
//! the test), and at multiples of π/2. For |x| > 10³ the value is
//! libm's (per element, so still the same on every path); NaN and ±∞ give NaN.
//!
//! Constants carry fdlibm's published digits; the compiler rounds them to the nearest f64.
#![allow(clippy::excessive_precision)]

const TWO_OVER_PI: f64 = std::f64::consts::FRAC_2_PI;
/// 1.5·2⁵²: adding it rounds any |y| < 2⁵¹ to an integer (round half to even).
const ROUND: f64 = 6_755_399_441_055_744.0;
const P1: f64 = 1.570_796_326_734_125_614_17e0;
const P2: f64 = 6.077_100_506_303_965_976_60e-11;
const P3: f64 = 2.022_266_248_711_166_455_80e-21;
const S1: f64 = -1.666_666_666_666_663_243_48e-1;
const S2: f64 = 8.333_333_333_322_489_461_24e-3;
const S3: f64 = -1.984_126_982_985_794_931_34e-4;
const S4: f64 = 2.755_731_370_707_006_767_89e-6;
const S5: f64 = -2.505_076_025_340_686_341_95e-8;
const S6: f64 = 1.589_690_995_211_550_102_21e-10;
const C1: f64 = 4.166_666_666_666_660_190_37e-2;
const C2: f64 = -1.388_888_888_887_410_957_49e-3;
const C3: f64 = 2.480_158_728_947_672_941_78e-5;
const C4: f64 = -2.755_731_435_139_066_330_35e-7;
const C5: f64 = 2.087_572_321_298_174_827_90e-9;
const C6: f64 = -1.135_964_755_778_819_482_65e-11;
/// Above this |x| the value comes from libm (the reduction's rounding grows with |x|; walker
/// angles stay far below).
pub const REDUCED_RANGE: f64 = 1.0e3;

/// Below this |x| the reduction is the identity (`n = 0`, `r = x`, quadrant 0): |x·2/π| < 0.4966
/// rounds to 0, so `r = ((x − 0·P₁) − 0·P₂) − 0·P₃ = x` exactly (also for −0). [`sincos_lanes`]
/// (up to four values) then skips the reduction: the same bits, without its chain of dependent
/// operations. Walker
/// angles (θ − γ, φ, segment angles near the vertical) mostly live here.
pub const SMALL: f64 = 0.78;

/// The reduced kernel for one value (valid for |x| ≤ [`REDUCED_RANGE`]; NaN for NaN/±∞).
// Public, hidden from the docs, for the integration tests (crates/pdw-hybrid/tests/simd.rs).
#[doc(hidden)]
#[inline(always)]
pub fn kernel(x: f64) -> (f64, f64) {
    let t = x * TWO_OVER_PI + ROUND;
    let n = t - ROUND;
    let q = (t.to_bits() & 3) as u32;
    let r = ((x - n * P1) - n * P2) - n * P3;
    let (s, c) = kernel_reduced(r);
    let (a, b) = if q & 1 == 0 { (s, c) } else { (c, s) };
    let sa = if q & 2 == 0 { a } else { -a };
    let cb = if (q + 1) & 2 == 0 { b } else { -b };
    (sa, cb)
}

/// `(sin r, cos r)` for a reduced |r| ≤ π/4 (step 3 of the module docs). The polynomials are
/// evaluated by Estrin's scheme (pairs of coefficients, then powers of r²): the same operations
/// on every path, with half the dependent steps of Horner's rule — a right-hand side waits for
/// this value before the integrator's next stage can start.
#[inline(always)]
fn kernel_reduced(r: f64) -> (f64, f64) {
    (sin_reduced(r), cos_reduced(r))
}

/// The sine half of [`kernel_reduced`] (`sin r`, |r| ≤ π/4).
#[inline(always)]
fn sin_reduced(r: f64) -> f64 {
    let z = r * r;
    let v = z * r;
    let z2 = z * z;
    let ps = (S2 + z * S3) + z2 * ((S4 + z * S5) + z2 * S6);
    // The value has the sign of r for every r ≠ 0 (|r³/6| < |r| on |r| ≤ π/4 + ε), so taking
    // r's sign changes nothing there, and r = ±0 gets ±0 (sin(−0) = −0, as libm; the
    // polynomial alone would give +0). A sign copy, not a branch: it vectorises.
    (r + v * (S1 + z * ps)).copysign(r)
}

/// The cosine half of [`kernel_reduced`] (`cos r`, |r| ≤ π/4).
#[inline(always)]
fn cos_reduced(r: f64) -> f64 {
    let z = r * r;
    let z2 = z * z;
    let z4 = z2 * z2;
    let pc = z * (((C1 + z * C2) + z2 * (C3 + z * C4)) + z4 * (C5 + z * C6));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    w + (((1.0 - w) - hz) + z * pc)
}

/// `(sin x, cos x)` for one value: the same bits as the element of [`sincos_lanes`].
#[inline(always)]
pub fn sincos(x: f64) -> (f64, f64) {
    let (s, c) = sincos_lanes([x]);
    (s[0], c[0])
}

/// `(sin, cos)` of every element (element-wise: each element's bits depend on it alone).
#[inline(always)]
pub fn sincos_lanes<const N: usize>(x: [f64; N]) -> ([f64; N], [f64; N]) {
    let mut s = [0.0; N];
    let mut c = [0.0; N];
    // The identity-reduction shortcut pays off for the few values of a scalar right-hand side
    // (latency-bound); a vector of lanes is throughput-bound and keeps one branch-free path.
    if N <= 4 && x.iter().all(|v| v.abs() < SMALL) {
        for i in 0..N {
            (s[i], c[i]) = kernel_reduced(x[i]);
        }
        return (s, c);
    }
    let mut big = false;
    for i in 0..N {
        (s[i], c[i]) = kernel(x[i]);
        big |= x[i].abs() > REDUCED_RANGE;
    }
    if big {
        for i in 0..N {
            if x[i].abs() > REDUCED_RANGE {
                (s[i], c[i]) = x[i].sin_cos();
            }
        }
    }
    (s, c)
}

/// `(sin x, cos x)` for |x| < [`SMALL`], where the reduction is the identity: the bits of
/// [`sincos`], about two thirds of its operations. Branch-free, for column loops over lanes
/// (they vectorise at the width of their path). For other x the values are not sin and cos
/// (no reduction is made): such a loop flags those lanes and takes [`sincos`] for them.
#[inline(always)]
pub fn sincos_small(x: f64) -> (f64, f64) {
    kernel_reduced(x)
}

/// `sin x` for |x| < [`SMALL`]: the sine half of [`sincos_small`] (the bits of [`sincos`]; for
/// other x, as there, not the sine).
#[inline(always)]
pub fn sin_small(x: f64) -> f64 {
    sin_reduced(x)
}

/// `(sin x, cos x)` for |x| ≤ [`REDUCED_RANGE`] (NaN for NaN and ±∞): the bits of [`sincos`],
/// branch-free, for column loops over lanes. Above the range the values are wrong: such a loop
/// notes whether any |x| > [`REDUCED_RANGE`] and then takes [`sincos`] for those values, as
/// [`sincos_lanes`] does.
#[inline(always)]
pub fn sincos_reduced_range(x: f64) -> (f64, f64) {
    kernel(x)
}

/// `sin`/`cos` of every element of `x` into `s` and `c` (the shortest of the three lengths).
#[inline(always)]
pub fn sincos_slice(x: &[f64], s: &mut [f64], c: &mut [f64]) {
    let n = x.len().min(s.len()).min(c.len());
    let (x, s, c) = (&x[..n], &mut s[..n], &mut c[..n]);
    let mut i = 0;
    while i + 8 <= n {
        let mut v = [0.0; 8];
        v.copy_from_slice(&x[i..i + 8]);
        let (vs, vc) = sincos_lanes(v);
        s[i..i + 8].copy_from_slice(&vs);
        c[i..i + 8].copy_from_slice(&vc);
        i += 8;
    }
    while i < n {
        (s[i], c[i]) = sincos(x[i]);
        i += 1;
    }
}
