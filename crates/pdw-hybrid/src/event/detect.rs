//! The end-point test: from a guard's values and rates at the two ends of a step, whether its
//! interior samples can show a crossing at all ([`may_cross`]) and, for a flagged step, whether
//! they can show one in the guard's direction ([`clears_direction`]); the extrema of the
//! guard's cubic that `probe_extrema` evaluates.

use super::N_SAMPLES;
use crate::system::Crossing;

/// Does `gl → gr` cross zero in direction `dir` (left strictly before, right after or at zero)?
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[inline]
pub fn crosses(dir: Crossing, gl: f64, gr: f64) -> bool {
    match dir {
        Crossing::Rising => gl < 0.0 && gr >= 0.0,
        Crossing::Falling => gl > 0.0 && gr <= 0.0,
        Crossing::Either => (gl < 0.0 && gr >= 0.0) || (gl > 0.0 && gr <= 0.0),
    }
}

/// `max |c₁₀| = max |c₁₁| = 4/27` on θ ∈ [0, 1]: the largest share of the end slopes in the
/// cubic Hermite interpolant (at θ = 1/3 and θ = 2/3).
const SLOPE_BASIS_MAX: f64 = 4.0 / 27.0;

/// Fraction of the slopes' largest share added to the margin of [`may_cross`], for guards that
/// are not linear in the state.
const NONLINEAR_SLACK: f64 = 0.25;

/// Can guard values sampled inside a step show a crossing, given only the end values
/// `g0 = g(x₀)`, `g1 = g(x₁)`, the rates `r0 = ġ(x₀)`, `r1 = ġ(x₁)` and the step `h`?
///
/// The interior samples evaluate the guard on the state's cubic Hermite interpolant. For a
/// guard linear in the state that is exactly the cubic Hermite `p(θ)` of the guard itself
/// (end values g₀, g₁, end slopes h ġ₀, h ġ₁; HNW I, eq. II.6.7). In Bernstein form its
/// control points are `b₀ = g₀`, `b₁ = g₀ + h ġ₀/3`, `b₂ = g₁ − h ġ₁/3`, `b₃ = g₁`, and `p`
/// lies in the convex hull of the control points of its two halves (one de Casteljau split at
/// θ = ½; Farin, *Curves and Surfaces for CAGD*, §4–5). A sample can show a crossing — in
/// either direction — only if that hull comes near zero, so the step is skipped when the hull
/// lies at distance > m from zero on one side, with
/// `m = 10⁻¹²·(1 + |g₀| + |g₁|) + ¼·4/27·|h|·(|ġ₀| + |ġ₁|)`: the first term covers rounding,
/// the second the difference between `p` and a guard that is nonlinear in the state (it
/// vanishes with its first derivative at both ends and is O(h⁴): for the chain walkers' foot
/// height about 10⁻⁷ m at their steps, against a margin of about 10⁻⁴ m). Returns true —
/// "sample this step" — in every other case: a crossing between the ends, a zero end value,
/// an unknown (`+∞`) rate, any NaN. Branch-free (a column kernel over lanes vectorises it).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[inline(always)]
pub fn may_cross(g0: f64, g1: f64, r0: f64, r1: f64, h: f64) -> bool {
    let (lo, hi, m) = hull_and_margin(g0, g1, r0, r1, h);
    let finite = (g0 + g1 + m + lo + hi).is_finite();
    !(finite & ((hi + m < 0.0) | (lo - m > 0.0)))
}

/// For a step that [`may_cross`] flags: can its samples still not show a crossing in direction
/// `dir`? `Rising` needs a sample `< 0` followed by one `≥ 0` (see [`crosses`]); with the
/// samples within `m` of the guard's cubic `p` (as in [`may_cross`]) there is none when one of
/// these holds:
/// - `p` stays below `−m` on `[1/5, 1]`: no sample after the first is `≥ 0`;
/// - `g₀ ≥ 0` and `p` stays above `m` on `[1/5, 1]`: no sample is `< 0` — the step that starts
///   on the guard after a reset (`g₀ = 0`) and moves away from it;
/// - `p` falls by more than `2m` over every fifth of the step (`p' < −10m` on `[0, 1]`): each
///   sample is below the one before — a crossing in the other direction.
///
/// `Falling` is the mirror image; `Either`: never. The bounds are the Bernstein hulls of the
/// sub-curve on `[1/5, 1]` (one de Casteljau split at θ = 1/5) and of `p'` (control points
/// `3(b₁ − b₀) = hġ₀`, `3(b₂ − b₁)`, `3(b₃ − b₂) = hġ₁`). Any non-finite value: `false`. Called
/// only on flagged steps (a few per stride), so it costs nothing on the others.
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[inline(always)]
pub fn clears_direction(dir: Crossing, g0: f64, g1: f64, r0: f64, r1: f64, h: f64) -> bool {
    if let Crossing::Either = dir {
        return false;
    }
    let third = 1.0 / 3.0;
    let (b0, b1, b2, b3) = (g0, g0 + h * r0 * third, g1 - h * r1 * third, g1);
    let (_, _, m) = hull_and_margin(g0, g1, r0, r1, h);
    let tau = 1.0 / (N_SAMPLES + 1) as f64;
    let lerp = |a: f64, b: f64| a + tau * (b - a);
    let (c0, c1, c2) = (lerp(b0, b1), lerp(b1, b2), lerp(b2, b3));
    let (d0, d1) = (lerp(c0, c1), lerp(c1, c2));
    let e0 = lerp(d0, d1);
    let (sub_lo, sub_hi) = (e0.min(d1).min(c2).min(b3), e0.max(d1).max(c2).max(b3));
    let dm = 3.0 * (b2 - b1);
    let (hr0, hr1) = (h * r0, h * r1);
    let (dlo, dhi) = (hr0.min(dm).min(hr1), hr0.max(dm).max(hr1));
    if !(g0 + m + e0 + d1 + c2 + b3 + hr0 + dm + hr1).is_finite() {
        return false;
    }
    match dir {
        Crossing::Rising => {
            sub_hi + m < 0.0 || (g0 >= 0.0 && sub_lo - m > 0.0) || tau * dhi + 2.0 * m < 0.0
        }
        _ => sub_lo - m > 0.0 || (g0 <= 0.0 && sub_hi + m < 0.0) || tau * dlo - 2.0 * m > 0.0,
    }
}

/// The Bernstein hull `(lo, hi)` of the guard's cubic over the step (one de Casteljau split at
/// θ = ½) and the margin `m` of [`may_cross`].
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[inline(always)]
pub fn hull_and_margin(g0: f64, g1: f64, r0: f64, r1: f64, h: f64) -> (f64, f64, f64) {
    let third = 1.0 / 3.0;
    let (b0, b1, b2, b3) = (g0, g0 + h * r0 * third, g1 - h * r1 * third, g1);
    let (b01, b12, b23) = (0.5 * (b0 + b1), 0.5 * (b1 + b2), 0.5 * (b2 + b3));
    let (b012, b123) = (0.5 * (b01 + b12), 0.5 * (b12 + b23));
    let mid = 0.5 * (b012 + b123);
    // Plain comparisons (one instruction each; f64::min/max add NaN handling): a non-finite
    // input or control point (an overflow: ∞ in b₀₁ or b₂₃, NaN only after it) leaves `lo`,
    // `hi` or `m` non-finite, so `finite` is false and the NaN rules never decide the result.
    let (min, max) = (
        |a: f64, b: f64| if a < b { a } else { b },
        |a: f64, b: f64| if a > b { a } else { b },
    );
    let lo = min(min(min(b0, b3), min(b01, b23)), min(min(b012, b123), mid));
    let hi = max(max(max(b0, b3), max(b01, b23)), max(max(b012, b123), mid));
    let m = 1e-12 * (1.0 + g0.abs() + g1.abs())
        + NONLINEAR_SLACK * SLOPE_BASIS_MAX * h.abs() * (r0.abs() + r1.abs());
    (lo, hi, m)
}

/// The bit of guard `k` in a lane's candidate flags (guards from the eighth on share the last
/// bit: a lane with it set samples all of them).
#[inline(always)]
pub(crate) fn guard_bit(k: usize) -> u8 {
    1 << k.min(7)
}

/// The stationary points in `(0, 1)` of the cubic with Bernstein coefficients `b`: the roots
/// of `p'(θ)/3 = (a − 2b + c) θ² + 2 (b − a) θ + a`, `a, b, c` the differences of `b`.
pub(super) fn cubic_extrema(b: [f64; 4]) -> [Option<f64>; 2] {
    let (a, m, c) = (b[1] - b[0], b[2] - b[1], b[3] - b[2]);
    let (qa, qb, qc) = (a - 2.0 * m + c, 2.0 * (m - a), a);
    let inside = |t: f64| (t > 0.0 && t < 1.0).then_some(t);
    if qa.abs() <= 1e-14 * (qb.abs() + qc.abs()) {
        return [(qb != 0.0).then(|| -qc / qb).and_then(inside), None];
    }
    let disc = qb * qb - 4.0 * qa * qc;
    if disc.is_nan() || disc < 0.0 {
        return [None, None];
    }
    let r = disc.sqrt();
    [
        inside((-qb - r) / (2.0 * qa)),
        inside((-qb + r) / (2.0 * qa)),
    ]
}
