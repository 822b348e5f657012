//! The root of a guard on a bracket `(θa, θb]` of the dense output, to a bracket of
//! 4ε·max(|t₀|, |t₁|) in time: the Illinois iteration on states ([`refine`]; Dowell & Jarratt
//! 1971) and, for an affine guard, safeguarded Newton on its polynomial ([`refine_linear`]).

use super::poly::nested_with_derivative;
use super::Dense;
use crate::system::Scratch;
use crate::HybridSystem;

/// Safeguarded Newton iteration for a root of an affine guard's polynomial `poly` (see
/// [`guard_poly`]) on `(θa, θb]`, with `g(θa)` strictly before and `g(θb)` after or at the
/// crossing — the bracket [`refine`] starts from, and the same result contract, to the same
/// bracket width `tol`: the right-hand end θ* of a final bracket `[θ*−w, θ*]` with `w ≤ tol`
/// whose left end is before the crossing and whose right end after it or at zero.
///
/// Newton's iterates (value and derivative from one Horner pass) converge quadratically from
/// the secant point of the bracket; an iterate that leaves the bracket is replaced by the
/// bracket's secant point, or its midpoint. When a step is shorter than half the width, the
/// next point probes the other side of the root at 0.99·tol from the current one, which closes
/// the bracket. The guard is then evaluated on the state at θ* (`xr`), and the crossing must
/// hold there too. Returns `None` — the caller falls back on [`refine`] on the state — when
/// the polynomial's rounding hides the root (a grazing crossing, `|ġ|` tiny), after 40 points,
/// on a non-finite value, or when the guard on the state disagrees with its polynomial.
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[allow(clippy::too_many_arguments)]
pub fn refine_linear<S: HybridSystem + ?Sized>(
    sys: &S,
    ws: &mut Scratch,
    mode: usize,
    k: usize,
    dense: &Dense<'_>,
    poly: &[f64],
    rows: usize,
    tol: f64,
    (theta_a, ga): (f64, f64),
    (theta_b, gb): (f64, f64),
    xr: &mut [f64],
) -> Option<f64> {
    let sig = if ga < 0.0 { 1.0 } else { -1.0 };
    let (mut a, mut fa, mut b, mut fb) = (theta_a, sig * ga, theta_b, sig * gb);
    let secant = |a: f64, fa: f64, b: f64, fb: f64| {
        let c = b - fb * (b - a) / (fb - fa);
        if c > a && c < b {
            c
        } else {
            0.5 * (a + b)
        }
    };
    let mut c = secant(a, fa, b, fb);
    let mut closed = fb == 0.0 || b - a <= tol;
    for _ in 0..40 {
        if closed {
            break;
        }
        if !(c > a && c < b) {
            return None;
        }
        let (v, dv) = nested_with_derivative(poly, rows, c);
        let (fc, dc) = (sig * v, sig * dv);
        if !(fc.is_finite() && dc.is_finite()) {
            return None;
        }
        if fc < 0.0 {
            (a, fa) = (c, fc);
        } else {
            (b, fb) = (c, fc);
        }
        if fc == 0.0 || b - a <= tol {
            closed = true;
            continue;
        }
        let step = fc / dc;
        let newton = c - step;
        c = if step.abs() <= 0.5 * tol {
            // Converged to within half the width: probe across the root.
            let probe = if fc < 0.0 {
                c + 0.99 * tol
            } else {
                c - 0.99 * tol
            };
            if probe > a && probe < b {
                probe
            } else {
                secant(a, fa, b, fb)
            }
        } else if newton > a && newton < b {
            newton
        } else {
            secant(a, fa, b, fb)
        };
    }
    if !closed {
        return None;
    }
    // The state at θ* must show the crossing too; the guard on the state and its polynomial
    // differ by rounding, so a root within that rounding of the state's side is moved right by
    // up to four bracket widths (never past θ_b).
    for j in 0..5 {
        let theta = if j == 0 { b } else { b + j as f64 * tol };
        if theta > theta_b {
            break;
        }
        if theta == 1.0 {
            xr.copy_from_slice(dense.x1);
        } else {
            dense.eval(theta, xr);
        }
        if sig * sys.guard(ws, mode, k, xr) >= 0.0 {
            return Some(theta);
        }
    }
    None
}

/// Illinois iteration for a root of guard `k` on `(θa, θb]` with `g(θa)` strictly before and
/// `g(θb)` after or at the crossing. Returns the right-hand end θ* of the final bracket and leaves
/// the state at θ* in `xr`.
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[allow(clippy::too_many_arguments)]
pub fn refine<S: HybridSystem + ?Sized>(
    sys: &S,
    ws: &mut Scratch,
    mode: usize,
    k: usize,
    dense: &Dense<'_>,
    t_scale: f64,
    (theta_a, ga): (f64, f64),
    (theta_b, gb): (f64, f64),
    xr: &mut [f64],
) -> f64 {
    let sig = if ga < 0.0 { 1.0 } else { -1.0 };
    let (mut a, mut fa, mut b, mut fb) = (theta_a, sig * ga, theta_b, sig * gb);
    let tol = bracket_tol(t_scale, dense.h);
    let mut side = 0i8;
    let mut w_ref = b - a;
    let mut since = 0u8;
    let mut bisect = false;
    for _ in 0..200 {
        if fb == 0.0 || b - a <= tol {
            break;
        }
        let mut c = if bisect {
            0.5 * (a + b)
        } else {
            b - fb * (b - a) / (fb - fa)
        };
        bisect = false;
        if !(c > a && c < b) {
            c = 0.5 * (a + b);
            if !(c > a && c < b) {
                break;
            }
        }
        dense.eval(c, xr);
        let fc = sig * sys.guard(ws, mode, k, xr);
        if fc.is_nan() {
            break;
        }
        if fc < 0.0 {
            a = c;
            fa = fc;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        } else {
            b = c;
            fb = fc;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        }
        since += 1;
        if b - a <= 0.5 * w_ref {
            w_ref = b - a;
            since = 0;
        } else if since >= 3 {
            bisect = true;
            since = 0;
            w_ref = b - a;
        }
    }
    if b == 1.0 {
        xr.copy_from_slice(dense.x1);
    } else {
        dense.eval(b, xr);
    }
    b
}

/// Width in θ of the final bracket of a root: 4ε·max(|t₀|, |t₁|) in time.
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[inline]
pub fn bracket_tol(t_scale: f64, h: f64) -> f64 {
    (4.0 * f64::EPSILON * t_scale / h.abs()).max(4.0 * f64::EPSILON)
}
