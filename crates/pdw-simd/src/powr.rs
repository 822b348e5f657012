//! `x^a` for `x ≥ 0` in plain IEEE-754 arithmetic, for the step-size controller.
//!
//! The controller raises the error norm to a fixed power every step (HNW I eq. II.4.13:
//! `err^α`, and `facold^β` for the PI form). glibc's `pow` is correctly rounded but costs about
//! as much as a right-hand side of the simplest walker, and its result is glibc's, not ours.
//! [`powr`] computes `exp(a·ln x)` with
//! - `ln x = e·ln 2 + 2·atanh(s)`, `x = m·2^e` with `m ∈ [√½, √2)`, `s = (m − 1)/(m + 1)`
//!   (`|s| ≤ 0.1716`), the odd series `atanh(s) = s + s³/3 + … + s¹⁹/19` (truncation
//!   `< s²¹/21·1/(1 − s²) ≈ 4e−18` relative to `ln x`);
//! - `exp(y) = 2^n·exp(r)`, `y = n·ln 2 + r`, `|r| ≤ ln2/2`, `ln 2` split into a high part with
//!   a short mantissa and a low part (Cody–Waite; the split of fdlibm's `e_log.c`), `exp(r)` by its Taylor polynomial to degree
//!   13 (truncation `< 0.347¹⁴/14! ≈ 4e−18`);
//!
//! so the relative error is at most about `4ε·max(1, |a·ln x|)` (the rounding of `y` carries
//! over into `exp`), tested against `f64::powf` over 1e−300…1e300; for the controller's
//! arguments (`err ∈ [1e−10, 1e10]`, `a ≤ 0.2`, `|y| ≤ 4.7`) that is below 5e−15. It uses `+ − × ÷` and
//! bit manipulation only: the same bits on every instruction-set path and every libm.
//!
//! Domain: `x = 0` gives 0 for `a > 0`, `x = +∞` gives +∞ for `a > 0`, NaN or `x < 0` gives NaN;
//! subnormal `x` is scaled into the normal range first. `a` must be finite.

/// ln 2 with its last 21 mantissa bits zero: `n·LN2_HI` is exact for `|n| < 2¹¹`.
const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
/// ln 2 − LN2_HI, rounded.
const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);
const LN2: f64 = std::f64::consts::LN_2;
const INV_LN2: f64 = std::f64::consts::LOG2_E;
const ROUND: f64 = 6_755_399_441_055_744.0;

/// Natural logarithm of a positive normal `x` (see the module docs).
#[inline(always)]
fn ln_normal(x: f64) -> f64 {
    let bits = x.to_bits();
    let mut e = ((bits >> 52) & 0x7ff) as i64 - 1023;
    // Mantissa in [1, 2), then moved into [√½, √2).
    let mut m = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
    if m > std::f64::consts::SQRT_2 {
        m *= 0.5;
        e += 1;
    }
    let s = (m - 1.0) / (m + 1.0);
    let z = s * s;
    // atanh(s)/s = Σ_{k=0}^{9} z^k/(2k+1), by Estrin's scheme (short dependency chains: the
    // controller waits for this value before its next step).
    let (z2, z4) = (z * z, z * z * (z * z));
    let z8 = z4 * z4;
    let q0 = (1.0 + z * (1.0 / 3.0)) + z2 * (1.0 / 5.0 + z * (1.0 / 7.0));
    let q1 = (1.0 / 9.0 + z * (1.0 / 11.0)) + z2 * (1.0 / 13.0 + z * (1.0 / 15.0));
    let q2 = 1.0 / 17.0 + z * (1.0 / 19.0);
    let p = q0 + z4 * q1 + z8 * q2;
    let ef = e as f64;
    ef * LN2_HI + (2.0 * s * p + ef * LN2_LO)
}

/// `exp(y)` for finite `y` (overflow to +∞, underflow to 0).
#[inline(always)]
fn exp_finite(y: f64) -> f64 {
    if y > 709.8 {
        return f64::INFINITY;
    }
    if y < -745.2 {
        return 0.0;
    }
    // Round to nearest by adding and subtracting 1.5·2⁵² (|y/ln 2| < 1100 here): no libm call
    // on the baseline target, the same result on every path.
    let n = (y * INV_LN2 + ROUND) - ROUND;
    let r = (y - n * LN2_HI) - n * LN2_LO;
    // Taylor polynomial of exp(r) to degree 13, Estrin's scheme.
    let r2 = r * r;
    let r4 = r2 * r2;
    let r8 = r4 * r4;
    let f0 = (1.0 + r) + r2 * (0.5 + r * (1.0 / 6.0));
    let f1 = (1.0 / 24.0 + r * (1.0 / 120.0)) + r2 * (1.0 / 720.0 + r * (1.0 / 5_040.0));
    let f2 = (1.0 / 40_320.0 + r * (1.0 / 362_880.0))
        + r2 * (1.0 / 3_628_800.0 + r * (1.0 / 39_916_800.0));
    let f3 = 1.0 / 479_001_600.0 + r * (1.0 / 6_227_020_800.0);
    let p = (f0 + r4 * f1) + r8 * (f2 + r4 * f3);
    // 2^n in two factors so that n down to −1075 and up to 1024 stays representable.
    let n = n as i64;
    let (n1, n2) = (n / 2, n - n / 2);
    let pow2 = |k: i64| f64::from_bits(((k + 1023) as u64) << 52);
    p * pow2(n1) * pow2(n2)
}

/// `x^a` for `x ≥ 0` and finite `a` (see the module docs for the method, accuracy and domain).
#[inline(always)]
pub fn powr(x: f64, a: f64) -> f64 {
    if x > 0.0 && x < f64::INFINITY {
        let l = if x < f64::MIN_POSITIVE {
            // Subnormal: scale by 2^64 into the normal range.
            ln_normal(x * 18_446_744_073_709_551_616.0) - 64.0 * LN2
        } else {
            ln_normal(x)
        };
        exp_finite(a * l)
    } else if x == 0.0 {
        if a > 0.0 {
            0.0
        } else if a == 0.0 {
            1.0
        } else {
            f64::INFINITY
        }
    } else if x == f64::INFINITY {
        if a > 0.0 {
            f64::INFINITY
        } else if a == 0.0 {
            1.0
        } else {
            0.0
        }
    } else {
        f64::NAN
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ln2_split_is_exact_in_its_high_part() {
        assert_eq!(LN2_HI.to_bits() & 0x1f_ffff, 0);
        assert!((LN2_HI + LN2_LO - LN2).abs() <= f64::EPSILON * LN2);
        assert!((LN2_LO - 1.908_214_929_270_587_7e-10).abs() < 1e-25);
    }

    #[test]
    fn agrees_with_libm_pow_over_the_range() {
        let mut worst: f64 = 0.0;
        for a in [0.2, 0.17, 0.04, 0.125, 1.0 / 3.0, 0.25, -0.2, 1.5] {
            let mut x = 1e-300_f64;
            while x < 1e300 {
                for f in [1.0, 1.234_567_89, 3.3, 7.77] {
                    let xv = x * f;
                    let (p, q) = (powr(xv, a), xv.powf(a));
                    if q.is_finite() && q > 1e-300 {
                        let scale = 4.0 * f64::EPSILON * (a * xv.ln()).abs().max(1.0);
                        worst = worst.max(((p - q) / q).abs() / scale);
                    }
                }
                x *= 10.0;
            }
        }
        assert!(
            worst <= 1.0,
            "worst relative error {worst} × 4ε·max(1, |a ln x|)"
        );
        // Near 1, where ln x is small: relative accuracy of the result holds too.
        for i in 1..2000 {
            let x = 1.0 + (i as f64 - 1000.0) * 1e-6;
            let (p, q) = (powr(x, 0.2), x.powf(0.2));
            assert!(((p - q) / q).abs() < 1e-15, "x = {x}: {p} vs {q}");
        }
    }

    #[test]
    fn subnormals_edges_and_invalid_inputs() {
        let x = 5e-320_f64;
        let scale = 4.0 * f64::EPSILON * (0.2 * x.ln()).abs();
        assert!(((powr(x, 0.2) - x.powf(0.2)) / x.powf(0.2)).abs() < scale);
        assert_eq!(powr(0.0, 0.2), 0.0);
        assert_eq!(powr(0.0, 0.0), 1.0);
        assert_eq!(powr(0.0, -0.2), f64::INFINITY);
        assert_eq!(powr(f64::INFINITY, 0.2), f64::INFINITY);
        assert_eq!(powr(f64::INFINITY, -0.2), 0.0);
        assert!(powr(f64::NAN, 0.2).is_nan());
        assert!(powr(-1.0, 0.2).is_nan());
        assert_eq!(powr(1.0, 0.2), 1.0);
        assert_eq!(powr(2.0, 1.0), 2.0);
        assert_eq!(powr(1e300, 2.0), f64::INFINITY);
        assert_eq!(powr(1e-300, 2.0), 0.0);
    }
}
