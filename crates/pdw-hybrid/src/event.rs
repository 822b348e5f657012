//! Event location on an accepted step `[t₀, t₁]`, `h = t₁ − t₀`, parametrised by `θ ∈ [0, 1]`.
//!
//! **Detection.** Every guard `g_k` of the mode is evaluated at the step's end points (exact
//! states x₀, x₁) together with its rate along the flow `ġ = ∇g·f`
//! ([`HybridSystem::guards_with_rates`], column-wise over lanes in a batch). From these four
//! numbers alone a column kernel decides whether the guard can show a crossing inside the step
//! (`may_cross`: the guard's cubic Hermite over the step, bounded by the convex hull of its
//! Bernstein control points, stays away from zero). Most steps of most guards are cleared
//! there. A flagged step is then cleared after all when its cubic rules out a crossing in the
//! guard's direction (`clears_direction`: it starts on the guard after a reset and moves
//! away, or crosses the other way), so that a stride samples only the step of its heel strike.
//! For a flagged guard the interior is sampled at [`N_SAMPLES`] = 4 points `θ = i/5` of
//! the step's cubic Hermite interpolant built from `(x₀, f(x₀), x₁, f(x₁))` — the guard on the
//! interpolated state, or, for a guard the model declares affine
//! ([`HybridSystem::guard_is_linear`]), the guard's own cubic from its end values and rates,
//! which is the same curve and needs no state. A model without rates (`+∞`, the default)
//! samples every step, as before the end-point test existed; the test never clears a step whose
//! samples would show a crossing (tested on random cubics, and stride by stride against a
//! model without rates), so events and their bits do not depend on it.
//! A *directional crossing* on a sub-interval `[θ_a, θ_b]` means: the left value is strictly on
//! the pre-crossing side and the right value is on the post-crossing side or zero (`Rising`:
//! `g_a < 0 ≤ g_b`; `Falling`: `g_a > 0 ≥ g_b`; `Either`: one of the two). Sampling the
//! interior catches a step that straddles two sign changes (the guard dips across zero and
//! back, ends on the same side) as long as the dip spans one of the five sub-intervals. A
//! window narrower than that — both crossings between two samples — is found where the model
//! gives the guard's rates: when no sample shows a crossing, the guard is also evaluated at each
//! interior extremum of its cubic from end values and rates that comes within the margin of the
//! crossing side (`probe_extrema`), and a crossing from the sample before that extremum to it is
//! refined like the others (the simplest walker's swing foot reaching a lower foothold for a few
//! hundredths of a stride on a step of 0.4). Without rates such a window is not resolved, and a
//! dip shallower than the Hermite interpolation error (O(h⁴), about the local error tolerance)
//! can be missed by the detection — a grazing contact of that depth is below the resolution of
//! the integration anyway.
//!
//! **Confirmation and refinement.** If any sub-interval shows a crossing, the method's own dense
//! output is built (RK4: the Hermite cubic itself; DOPRI5: Shampine's 4th-order continuous
//! extension, free; DOP853: the 7th-order one, three extra flow evaluations), the interior
//! samples of every flagged guard are recomputed on it (a guard the end-point test cleared
//! keeps g(x₀) inside: it has no crossing to show), and for each guard the first crossing
//! sub-interval is refined with the Illinois variant of regula falsi (Dowell & Jarratt 1971),
//! with a bisection step when three iterations fail to halve the bracket, until the bracket is
//! ≤ 4ε·max(|t₀|, |t₁|) in time (≈ 1e-15 for t ≈ 1). The *right-hand* end of the final bracket is reported: the returned state
//! is the dense-output state at that θ and its guard value is on the post-crossing side or zero.
//! A guard the model declares affine ([`HybridSystem::guard_is_linear`]) is, on the nested
//! dense output of DOPRI5 or DOP853, a scalar polynomial in θ with the same nesting: its rows
//! are the guard applied to the rows of the state's interpolant (`g(c₀)`, then
//! `g(c_r) − g(0)`). Its interior samples and its root then come from that polynomial — the
//! root by Newton's method from the bracket's secant point, safeguarded by the bracket and
//! closed to the same width by a probe across the root (about four polynomial evaluations
//! against seven Illinois iterations on states, each a dense-output state and a guard call);
//! the state at the root must show the crossing too, or the root moves right by up to four
//! bracket widths, and where neither holds (a grazing root hidden by rounding) the Illinois
//! iteration on states decides.
//!
//! **Admissibility.** [`HybridSystem::admissible`] is tested at the root; an inadmissible crossing
//! is skipped and the scan continues with the guard's later sub-intervals. The earliest admissible
//! root over all guards wins (ties: lowest guard index).
//!
//! **No re-triggering.** A crossing needs the left value strictly on the pre-crossing side. At a
//! segment start (after a reset) guard values within `guard_tolerance` of zero are stored as 0
//! (see [`HybridSystem::guard_tolerance`]), and a guard stop leaves the guard on the
//! post-crossing side or at zero: the next integration from that point cannot report the same
//! crossing again; the guard must first be seen strictly on its pre-crossing side.
//!
//! **Accuracy.** With DOPRI5/DOP853 the event time inherits the dense-output error (order 4 / 7 in
//! h per step, of the size of the tolerance) divided by |dg/dt|, plus the 1e-15 bracket. With RK4
//! the cubic Hermite interpolant has error ≤ h⁴/384·max‖x⁽⁴⁾‖ on each step (on top of the O(h⁴)
//! global error of the step values), so the event time error is O(h⁴)/|dg/dt|.

use crate::engine::Store;
use crate::options::{Method, Stats};
use crate::system::{Crossing, Scratch};
use crate::tableau;
use crate::HybridSystem;

/// Interior sample points per step used to detect crossings.
pub const N_SAMPLES: usize = 4;
/// Guard values per guard and step: θ = 0, the samples, θ = 1.
pub(crate) const N_COLS: usize = N_SAMPLES + 2;
const M: usize = N_COLS;

/// Cubic Hermite basis `[c₀₀, c₀₁, c₁₀, c₁₁]` at θ (HNW I, eq. II.6.7).
#[inline(always)]
pub(crate) fn hermite_basis(theta: f64) -> [f64; 4] {
    let t1 = 1.0 - theta;
    [
        (1.0 + 2.0 * theta) * t1 * t1,
        theta * theta * (3.0 - 2.0 * theta),
        theta * t1 * t1,
        -theta * theta * t1,
    ]
}

/// One component of the Hermite interpolant with basis `c` (same expression everywhere).
#[inline(always)]
pub(crate) fn hermite_point(c: [f64; 4], x0: f64, x1: f64, f0: f64, f1: f64, h: f64) -> f64 {
    c[0] * x0 + c[1] * x1 + h * (c[2] * f0 + c[3] * f1)
}

/// Per-lane scratch of the event locator (contiguous vectors of length `dim` unless noted).
pub(crate) struct EventScratch {
    pub x0: Vec<f64>,
    pub x1: Vec<f64>,
    pub f0: Vec<f64>,
    pub f1: Vec<f64>,
    /// State at a sample point.
    pub xs: Vec<f64>,
    /// State at the current root iterate.
    pub xr: Vec<f64>,
    /// State at the winning event.
    pub xbest: Vec<f64>,
    /// `(ng × (N_SAMPLES + 2))` guard values at θ = 0, 1/5, …, 1.
    pub gv: Vec<f64>,
    /// `(8 × dim)` dense-output coefficients.
    pub cont: Vec<f64>,
    /// `(16 × dim)` the lane's DOP853 stages k₀…k₁₂ gathered contiguously, then the three
    /// extra dense-output stages k₁₃…k₁₅.
    pub kl: Vec<f64>,
    pub ytmp: Vec<f64>,
    /// `(ng × 8)` coefficients of each affine guard along the dense output ([`guard_poly`]).
    pub poly: Vec<f64>,
    /// `(ng)` guard k has its polynomial in `poly`.
    pub lin: Vec<bool>,
    /// `(dim)` zeros (the affine guards' constant term is `g(0)`).
    pub zero: Vec<f64>,
    /// The model's own scratch, passed to every model call made for this lane.
    pub model: Scratch,
}

impl EventScratch {
    pub fn new(d: usize, ng: usize) -> Self {
        Self {
            x0: vec![0.0; d],
            x1: vec![0.0; d],
            f0: vec![0.0; d],
            f1: vec![0.0; d],
            xs: vec![0.0; d],
            xr: vec![0.0; d],
            xbest: vec![0.0; d],
            gv: vec![0.0; ng * M],
            cont: vec![0.0; 8 * d],
            kl: vec![0.0; 16 * d],
            ytmp: vec![0.0; d],
            poly: vec![0.0; ng * POLY_ROWS],
            lin: vec![false; ng],
            zero: vec![0.0; d],
            model: Scratch::new(),
        }
    }

    /// Room for `ng` guards per mode.
    pub fn reserve_guards(&mut self, ng: usize) {
        self.gv = vec![0.0; ng * M];
        self.poly = vec![0.0; ng * POLY_ROWS];
        self.lin = vec![false; ng];
    }
}

/// Which interpolant is in `cont` / the end-point vectors.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Interp {
    Hermite,
    Dopri5,
    Dop853,
}

/// Does `gl → gr` cross zero in direction `dir` (left strictly before, right after or at zero)?
#[inline]
pub(crate) fn crosses(dir: Crossing, gl: f64, gr: f64) -> bool {
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
#[inline(always)]
pub(crate) fn may_cross(g0: f64, g1: f64, r0: f64, r1: f64, h: f64) -> bool {
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
#[inline(always)]
pub(crate) fn clears_direction(dir: Crossing, g0: f64, g1: f64, r0: f64, r1: f64, h: f64) -> bool {
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
#[inline(always)]
fn hull_and_margin(g0: f64, g1: f64, r0: f64, r1: f64, h: f64) -> (f64, f64, f64) {
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

/// Borrowed view of the interpolation data.
struct Dense<'a> {
    interp: Interp,
    h: f64,
    x0: &'a [f64],
    x1: &'a [f64],
    f0: &'a [f64],
    f1: &'a [f64],
    cont: &'a [f64],
}

impl Dense<'_> {
    /// State at θ ∈ (0, 1) (θ = 1 is handled by the callers with the exact x₁). The shipped
    /// models' dimensions run the same expressions with a compile-time length (unrolled, no
    /// bounds checks).
    #[inline]
    fn eval(&self, theta: f64, out: &mut [f64]) {
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
#[allow(clippy::too_many_arguments)]
fn build_dense<S: HybridSystem + ?Sized>(
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
fn dop853_dense_dyn<S: HybridSystem + ?Sized>(
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
#[inline(always)]
fn dop853_dense_fixed<S: HybridSystem + ?Sized, const D: usize>(
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

/// Largest number of dense-output coefficient rows (DOP853's 8).
const POLY_ROWS: usize = 8;

/// Number of coefficient rows of a dense output in nested form (0: not in nested form).
#[inline]
fn nested_rows(interp: Interp) -> usize {
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
#[inline(always)]
fn nested_with_derivative(c: &[f64], n: usize, theta: f64) -> (f64, f64) {
    match n {
        5 => nested_fixed::<5>(c, theta),
        _ => nested_fixed::<POLY_ROWS>(c, theta),
    }
}

/// The value of [`nested_with_derivative`] at several points at once (the same operations per
/// point, so the same bits; the points side by side in vector registers).
#[inline(always)]
fn nested_values<const P: usize>(c: &[f64], n: usize, theta: [f64; P]) -> [f64; P] {
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
#[allow(clippy::too_many_arguments)]
fn guard_poly<S: HybridSystem + ?Sized>(
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
#[allow(clippy::too_many_arguments)]
fn refine_linear<S: HybridSystem + ?Sized>(
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
#[allow(clippy::too_many_arguments)]
fn refine<S: HybridSystem + ?Sized>(
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
#[inline]
fn bracket_tol(t_scale: f64, h: f64) -> f64 {
    (4.0 * f64::EPSILON * t_scale / h.abs()).max(4.0 * f64::EPSILON)
}

/// x₀, x₁, f(x₀), f(x₁) of lane `l` into the scratch's contiguous vectors.
fn gather_ends(st: &Store, l: usize, method: Method, sc: &mut EventScratch) {
    let (stride, blk) = (st.stride, st.blk());
    let last = crate::engine::tableau_of(method).n_stages - 1;
    Store::gather(&st.x, stride, l, &mut sc.x0);
    Store::gather(&st.xn, stride, l, &mut sc.x1);
    Store::gather(&st.k[..blk], stride, l, &mut sc.f0);
    Store::gather(&st.k[last * blk..(last + 1) * blk], stride, l, &mut sc.f1);
}

/// Locate the earliest admissible directional crossing on the accepted step of lane `l`
/// (x₀ in `st.x`, x₁ in `st.xn`, stages in `st.k`, guard values and rates at both ends in
/// `st.g`/`st.gr` and `st.g1`/`st.r1`). Returns `(guard, θ*)` with the event state in
/// `sc.xbest`; without an event, keeps the guard values and rates at x₁ (in `st.g`, `st.gr`)
/// for the next step.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn locate<S: HybridSystem + ?Sized>(
    sys: &S,
    method: Method,
    mode: usize,
    st: &mut Store,
    l: usize,
    h: f64,
    t0: f64,
    t1: f64,
    sc: &mut EventScratch,
    stats: &mut Stats,
) -> Option<(usize, f64)> {
    if st.cand[l] != 0 {
        // A few steps per stride: drop the flags whose direction rules out a crossing.
        clear_by_direction(sys.guards(mode), st, l, h);
    }
    if st.cand[l] == 0 {
        // No guard can cross inside the step (the column kernel `mark_near`; no guards, no
        // flags): the step's end values are the next step's start values. Inlined into the
        // step loops, the common case.
        store_end(st, sys.guards(mode).len(), l);
        return None;
    }
    let t = crate::phases::now();
    let found = locate_flagged(sys, method, mode, st, l, h, t0, t1, sc, stats);
    crate::phases::charge_locate(crate::phases::now().wrapping_sub(t));
    found
}

/// Clear the flag of every guard of lane `l` whose step [`clears_direction`] rules out.
#[inline(always)]
fn clear_by_direction(specs: &[crate::GuardSpec], st: &mut Store, l: usize, h: f64) {
    let stride = st.stride;
    for (k, spec) in specs.iter().enumerate().take(8) {
        let bit = guard_bit(k);
        // Guards from the eighth on share the last bit: only a lone guard's bit is cleared.
        if st.cand[l] & bit == 0 || (k == 7 && specs.len() > 8) {
            continue;
        }
        let i = k * stride + l;
        if clears_direction(spec.crossing, st.g[i], st.g1[i], st.gr[i], st.r1[i], h) {
            st.cand[l] &= !bit;
        }
    }
}

/// Keep the guard values and rates at x₁ of lane `l` (in `st.g`, `st.gr`) for the next step.
#[inline(always)]
fn store_end(st: &mut Store, ng: usize, l: usize) {
    let stride = st.stride;
    for k in 0..ng {
        let i = k * stride + l;
        st.g[i] = st.g1[i];
        st.gr[i] = st.r1[i];
    }
}

/// [`locate`] on a step with some guard flagged.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn locate_flagged<S: HybridSystem + ?Sized>(
    sys: &S,
    method: Method,
    mode: usize,
    st: &mut Store,
    l: usize,
    h: f64,
    t0: f64,
    t1: f64,
    sc: &mut EventScratch,
    stats: &mut Stats,
) -> Option<(usize, f64)> {
    let guards = sys.guards(mode);
    let ng = guards.len();
    if ng == 0 {
        return None;
    }
    let stride = st.stride;
    let store_end = |st: &mut Store| store_end(st, ng, l);
    stats.sampled += 1;
    // Values at θ = 0, at the interior points θ = i/5 and at θ = 1 of each flagged guard on the
    // state's cubic Hermite interpolant — for an affine guard with rates, its own cubic Hermite
    // from end values and rates, the same curve without gathering the state. A guard that is
    // not flagged has no crossing to show: its interior values are set to g(x₀).
    let inv = 1.0 / (N_SAMPLES + 1) as f64;
    let flags = st.cand[l];
    let mut gathered = false;
    for k in 0..ng {
        let i0 = k * stride + l;
        let (g0, g1) = (st.g[i0], st.g1[i0]);
        let row = &mut sc.gv[k * M..(k + 1) * M];
        row[0] = g0;
        row[M - 1] = g1;
        let (r0, r1) = (st.gr[i0], st.r1[i0]);
        if flags & guard_bit(k) == 0 {
            row[1..M - 1].fill(g0);
        } else if r0.is_finite() && r1.is_finite() && sys.guard_is_linear(mode, k) {
            for (i, v) in row[1..M - 1].iter_mut().enumerate() {
                let c = hermite_basis((i + 1) as f64 * inv);
                *v = hermite_point(c, g0, g1, r0, r1, h);
            }
        } else {
            // A nonlinear guard, or no rates from the model: the guard on the state's Hermite
            // interpolant.
            if !gathered {
                gather_ends(st, l, method, sc);
                gathered = true;
            }
            for i in 1..=N_SAMPLES {
                let c = hermite_basis(i as f64 * inv);
                for j in 0..sc.xs.len() {
                    sc.xs[j] = hermite_point(c, sc.x0[j], sc.x1[j], sc.f0[j], sc.f1[j], h);
                }
                sc.gv[k * M + i] = sys.guard(&mut sc.model, mode, k, &sc.xs);
            }
        }
    }
    let any = (0..ng).any(|k| {
        let g = &sc.gv[k * M..(k + 1) * M];
        (0..M - 1).any(|i| crosses(guards[k].crossing, g[i], g[i + 1]))
    });
    let probe = if any {
        None
    } else {
        probe_extrema(sys, method, mode, st, l, h, sc, &mut gathered)
    };
    if !any && probe.is_none() {
        store_end(st);
        return None;
    }
    if !gathered {
        gather_ends(st, l, method, sc);
    }
    let t_dense = crate::phases::now();
    let interp = build_dense(sys, method, mode, st, l, h, sc, stats);
    crate::phases::charge_dense(crate::phases::now().wrapping_sub(t_dense));
    let EventScratch {
        x0,
        x1,
        f0,
        f1,
        xs,
        xr,
        xbest,
        gv,
        cont,
        poly,
        lin,
        zero,
        model,
        ..
    } = sc;
    let dense = Dense {
        interp,
        h,
        x0,
        x1,
        f0,
        f1,
        cont,
    };
    // An affine guard on the dense output is a scalar polynomial in θ: its samples and its root
    // come from that polynomial, not from states (see `refine_linear`).
    let rows = nested_rows(interp);
    // Only the flagged guards: a guard whose step `mark_near` cleared has no crossing to show
    // (its interior values stay g(x₀), as in the Hermite samples above).
    let mut states_needed = false;
    for k in 0..ng {
        let flagged = flags & guard_bit(k) != 0;
        lin[k] = flagged && rows > 0 && sys.guard_is_linear(mode, k);
        if lin[k] {
            let p = &mut poly[k * POLY_ROWS..(k + 1) * POLY_ROWS];
            guard_poly(sys, model, mode, k, dense.cont, zero, rows, p);
        } else if flagged {
            states_needed = true;
        }
    }
    // The guards on the method's own interpolant at the same points: the brackets the root
    // finder starts from hold the guard's values on the curve it solves on.
    let thetas: [f64; N_SAMPLES] = std::array::from_fn(|i| (i + 1) as f64 * inv);
    for k in 0..ng {
        if lin[k] {
            let v = nested_values(&poly[k * POLY_ROWS..], rows, thetas);
            gv[k * M + 1..=k * M + N_SAMPLES].copy_from_slice(&v);
        }
    }
    if states_needed {
        for (i, &theta) in thetas.iter().enumerate() {
            dense.eval(theta, xs);
            for k in 0..ng {
                if !lin[k] && flags & guard_bit(k) != 0 {
                    gv[k * M + i + 1] = sys.guard(model, mode, k, xs);
                }
            }
        }
    }
    let t_scale = t0.abs().max(t1.abs());
    let tol = bracket_tol(t_scale, h);
    let mut best: Option<(usize, f64)> = None;
    for (k, spec) in guards.iter().enumerate() {
        for i in 0..M - 1 {
            let theta_a = i as f64 * inv;
            if let Some((_, tb)) = best {
                if theta_a >= tb {
                    break;
                }
            }
            let (ga, gb) = (gv[k * M + i], gv[k * M + i + 1]);
            if !crosses(spec.crossing, ga, gb) {
                continue;
            }
            let theta_b = if i + 1 == M - 1 {
                1.0
            } else {
                (i + 1) as f64 * inv
            };
            let (lo, hi) = ((theta_a, ga), (theta_b, gb));
            let poly_k = &poly[k * POLY_ROWS..(k + 1) * POLY_ROWS];
            let root = lin[k]
                .then(|| refine_linear(sys, model, mode, k, &dense, poly_k, rows, tol, lo, hi, xr))
                .flatten()
                .unwrap_or_else(|| refine(sys, model, mode, k, &dense, t_scale, lo, hi, xr));
            if best.is_some_and(|(_, tb)| root >= tb) {
                break;
            }
            if sys.admissible(mode, k, xr) {
                best = Some((k, root));
                xbest.copy_from_slice(xr);
                break;
            }
        }
    }
    if let (None, Some((k, i, theta_b))) = (best, probe) {
        // the window between two samples that only the cubic's extremum showed, on the dense
        // output
        let (theta_a, ga) = (i as f64 * inv, gv[k * M + i]);
        dense.eval(theta_b, xs);
        let gb = sys.guard(model, mode, k, xs);
        if crosses(guards[k].crossing, ga, gb) {
            let root = refine(
                sys,
                model,
                mode,
                k,
                &dense,
                t_scale,
                (theta_a, ga),
                (theta_b, gb),
                xr,
            );
            if sys.admissible(mode, k, xr) {
                best = Some((k, root));
                xbest.copy_from_slice(xr);
            }
        }
    }
    if best.is_none() {
        store_end(st);
    }
    best
}

/// The stationary points in `(0, 1)` of the cubic with Bernstein coefficients `b`: the roots
/// of `p'(θ)/3 = (a − 2b + c) θ² + 2 (b − a) θ + a`, `a, b, c` the differences of `b`.
fn cubic_extrema(b: [f64; 4]) -> [Option<f64>; 2] {
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

/// On a flagged step whose samples show no crossing: does a guard cross and cross back between
/// two samples? The guard's cubic from its end values and rates (the curve the samples of an
/// affine guard lie on, within [`may_cross`]'s margin of a nonlinear one) has its extrema at
/// `θ*`; where one lies on the post-crossing side within that margin, the guard is evaluated
/// there (its cubic, or the guard on the state's Hermite interpolant), and a crossing from the
/// sample left of `θ*` to `θ*` is a window the five sub-intervals missed: the simplest walker's
/// swing foot reaching a lower foothold for a few hundredths of a stride. Returns the earliest
/// such window `(guard, index of its left sample, θ*)`. A guard without rates is not probed.
#[allow(clippy::too_many_arguments)]
fn probe_extrema<S: HybridSystem + ?Sized>(
    sys: &S,
    method: Method,
    mode: usize,
    st: &Store,
    l: usize,
    h: f64,
    sc: &mut EventScratch,
    gathered: &mut bool,
) -> Option<(usize, usize, f64)> {
    let guards = sys.guards(mode);
    let inv = 1.0 / (N_SAMPLES + 1) as f64;
    let third = 1.0 / 3.0;
    let mut found: Option<(usize, usize, f64)> = None;
    for (k, spec) in guards.iter().enumerate() {
        let i0 = k * st.stride + l;
        let (g0, g1, r0, r1) = (st.g[i0], st.g1[i0], st.gr[i0], st.r1[i0]);
        if st.cand[l] & guard_bit(k) == 0 || !(r0.is_finite() && r1.is_finite()) {
            continue;
        }
        let (_, _, margin) = hull_and_margin(g0, g1, r0, r1, h);
        let b = [g0, g0 + h * r0 * third, g1 - h * r1 * third, g1];
        for theta in cubic_extrema(b).into_iter().flatten() {
            if found.is_some_and(|f| f.2 <= theta) {
                continue;
            }
            let p = hermite_point(hermite_basis(theta), g0, g1, r0, r1, h);
            let near = match spec.crossing {
                Crossing::Rising => p + margin >= 0.0,
                Crossing::Falling => p - margin <= 0.0,
                Crossing::Either => true,
            };
            if !near {
                continue;
            }
            let g = if sys.guard_is_linear(mode, k) {
                p
            } else {
                if !*gathered {
                    gather_ends(st, l, method, sc);
                    *gathered = true;
                }
                let c = hermite_basis(theta);
                for j in 0..sc.xs.len() {
                    sc.xs[j] = hermite_point(c, sc.x0[j], sc.x1[j], sc.f0[j], sc.f1[j], h);
                }
                sys.guard(&mut sc.model, mode, k, &sc.xs)
            };
            let i = ((theta / inv) as usize).min(N_SAMPLES);
            if crosses(spec.crossing, sc.gv[k * M + i], g) {
                found = Some((k, i, theta));
            }
        }
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Crossing;

    /// The claim the event detection rests on: when `may_cross` clears a step, the cubic
    /// Hermite of the guard — which the interior samples evaluate for an affine guard — shows no
    /// crossing in either direction at the sample points, nor anywhere on a fine grid. Checked
    /// on 200 000 seeded random cubics (a plain LCG, no dependency), many of them near zero.
    #[test]
    fn a_cleared_step_has_no_crossing_on_the_guards_cubic() {
        let mut seed: u64 = 0x2545_f491_4f6c_dd1d;
        let mut uniform = move || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut cleared, mut flagged) = (0, 0);
        for _ in 0..200_000 {
            let scale = 10f64.powf(-6.0 * uniform());
            let g0 = scale * (2.0 * uniform() - 1.0);
            let g1 = scale * (2.0 * uniform() - 1.0);
            let r0 = 3.0 * (2.0 * uniform() - 1.0);
            let r1 = 3.0 * (2.0 * uniform() - 1.0);
            let h = 10f64.powf(-4.0 * uniform());
            if may_cross(g0, g1, r0, r1, h) {
                flagged += 1;
                continue;
            }
            cleared += 1;
            let p = |t: f64| hermite_point(hermite_basis(t), g0, g1, r0, r1, h);
            let values: Vec<f64> = (0..=1000).map(|i| p(i as f64 / 1000.0)).collect();
            assert!(
                values.iter().all(|&v| v < 0.0) || values.iter().all(|&v| v > 0.0),
                "cleared but the cubic reaches zero: g0 {g0}, g1 {g1}, r0 {r0}, r1 {r1}, h {h}"
            );
            let mut samples = [g0, 0.0, 0.0, 0.0, 0.0, g1];
            for (i, v) in samples.iter_mut().enumerate().take(M - 1).skip(1) {
                *v = p(i as f64 / (N_SAMPLES + 1) as f64);
            }
            for w in samples.windows(2) {
                assert!(!crosses(Crossing::Either, w[0], w[1]));
            }
        }
        // Both branches are exercised, and most far-from-zero steps are cleared.
        assert!(
            cleared > 20_000 && flagged > 20_000,
            "{cleared} cleared, {flagged} flagged"
        );
    }

    /// The claim of the directional test: when `clears_direction` clears a step that
    /// `may_cross` flags, its samples — the guard's cubic at θ = i/5, each moved by up to the
    /// margin m (rounding and a nonlinear guard's deviation), and the exact end values — show
    /// no crossing in that direction. Checked on 300 000 seeded random cubics, a third of them
    /// starting on the guard (g₀ = 0), for both directions; each of the three ways to clear
    /// must occur.
    #[test]
    fn a_step_cleared_by_direction_shows_no_crossing_in_that_direction() {
        let mut uniform = xorshift(0x9e37_79b9_7f4a_7c15);
        let (mut cleared, mut flagged) = (0, 0);
        let mut ways = [0usize; 3];
        for n in 0..300_000 {
            let scale = 10f64.powf(-6.0 * uniform());
            let g0 = if n % 3 == 0 {
                0.0
            } else {
                scale * (2.0 * uniform() - 1.0)
            };
            let g1 = scale * (2.0 * uniform() - 1.0);
            let r0 = 3.0 * (2.0 * uniform() - 1.0);
            let r1 = 3.0 * (2.0 * uniform() - 1.0);
            let h = 10f64.powf(-4.0 * uniform());
            if !may_cross(g0, g1, r0, r1, h) {
                continue;
            }
            for dir in [Crossing::Rising, Crossing::Falling] {
                if !clears_direction(dir, g0, g1, r0, r1, h) {
                    flagged += 1;
                    continue;
                }
                cleared += 1;
                let (_, _, m) = hull_and_margin(g0, g1, r0, r1, h);
                let p = |t: f64| hermite_point(hermite_basis(t), g0, g1, r0, r1, h);
                let mut samples = [g0, 0.0, 0.0, 0.0, 0.0, g1];
                for (i, v) in samples.iter_mut().enumerate().take(M - 1).skip(1) {
                    *v = p(i as f64 / (N_SAMPLES + 1) as f64) + 0.99 * m * (2.0 * uniform() - 1.0);
                }
                for w in samples.windows(2) {
                    assert!(
                        !crosses(dir, w[0], w[1]),
                        "{dir:?} cleared but the samples cross: g0 {g0}, g1 {g1}, r0 {r0}, \
                         r1 {r1}, h {h}: {samples:?}"
                    );
                }
                // Which way cleared it (for the coverage check below), in the sign of `dir`.
                let s = if let Crossing::Rising = dir {
                    1.0
                } else {
                    -1.0
                };
                let v: Vec<f64> = samples.iter().map(|v| s * v).collect();
                if v[1..].iter().all(|&x| x < 0.0) {
                    ways[0] += 1;
                } else if v.iter().all(|&x| x >= 0.0) {
                    ways[1] += 1;
                } else {
                    ways[2] += 1;
                }
            }
        }
        assert!(
            cleared > 20_000 && flagged > 20_000 && ways.iter().all(|&w| w > 1000),
            "{cleared} cleared, {flagged} flagged, ways {ways:?}"
        );
    }

    /// The steps the directional test is for: starting on the guard and moving away from its
    /// crossing side, crossing the other way; and the ones it must keep: a crossing in the
    /// guard's direction, a start on the guard moving into the crossing, non-finite values,
    /// `Either`.
    #[test]
    fn directional_clearing_cases() {
        use Crossing::{Either, Falling, Rising};
        // (g₀, g₁, ġ₀, ġ₁, h)
        let clears = |dir, [g0, g1, r0, r1, h]: [f64; 5]| clears_direction(dir, g0, g1, r0, r1, h);
        let up_from_zero = [0.0, 0.3, 1.0, 1.0, 0.3];
        let falling = [0.1, -0.1, -0.7, -0.7, 0.3];
        // A rising guard at 0 after a reset, moving up (away from a rising crossing), which the
        // hull test cannot clear; and moving down: no sample is ≥ 0 after the start.
        assert!(may_cross(0.0, 0.3, 1.0, 1.0, 0.3));
        assert!(clears(Rising, up_from_zero));
        assert!(clears(Rising, [0.0, -0.3, -1.0, -1.0, 0.3]));
        // A falling crossing clears a rising guard, not a falling one.
        assert!(clears(Rising, falling));
        assert!(!clears(Falling, falling));
        // Kept: a rising crossing; a dip below zero and back for a falling guard; `Either`;
        // a NaN or unknown rate.
        assert!(!clears(Rising, [-0.1, 0.1, 0.7, 0.7, 0.3]));
        assert!(!clears(Falling, [0.01, 0.01, -1.0, 1.0, 0.1]));
        assert!(!clears(Either, up_from_zero));
        assert!(!clears(Rising, [0.0, 0.3, f64::NAN, 1.0, 0.3]));
        assert!(!clears(Rising, [0.0, 0.3, f64::INFINITY, 1.0, 0.3]));
    }

    /// Steps the test cannot clear: an end on zero (a reset placed the state on the guard),
    /// a sign change between the ends, an unknown rate, NaN anywhere; and a guard far from zero
    /// is cleared.
    #[test]
    fn steps_that_must_be_sampled_are() {
        assert!(may_cross(0.0, -0.5, 1.0, 1.0, 0.1));
        assert!(may_cross(-0.1, 0.2, 1.0, 1.0, 0.1));
        assert!(may_cross(-0.5, -0.5, f64::INFINITY, 0.0, 0.1));
        assert!(may_cross(f64::NAN, -0.5, 0.0, 0.0, 0.1));
        assert!(may_cross(-0.5, -0.5, f64::NAN, 0.0, 0.1));
        assert!(may_cross(-0.5, -0.5, 0.0, 0.0, f64::NAN));
        // a dip between two negative ends: g0 = g1 = −0.01 with slopes that lift the middle
        // above zero (p(½) = −0.01 + h(r0 − r1)/8 = +0.015)
        assert!(may_cross(-0.01, -0.01, 1.0, -1.0, 0.1));
        assert!(!may_cross(-0.5, -0.4, 1.0, 1.0, 0.1));
        assert!(!may_cross(0.5, 0.4, -1.0, -1.0, 0.1));
    }

    /// A seeded xorshift generator of uniform values in [0, 1) (no dependency).
    fn xorshift(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// A nonlinear flow of any dimension for the dense-output build (no guards).
    struct Coupled(usize);

    crate::integrate_through_dyn!(Coupled);
    impl HybridSystem for Coupled {
        fn dim(&self) -> usize {
            self.0
        }
        fn guards(&self, _mode: usize) -> &[crate::GuardSpec] {
            &[]
        }
        fn flow(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], dx: &mut [f64]) {
            let d = x.len();
            for j in 0..d {
                dx[j] = x[(j + 1) % d].sin() - 0.3 * x[j] * x[j];
            }
        }
        fn guard(&self, _ws: &mut Scratch, _mode: usize, _k: usize, _x: &[f64]) -> f64 {
            0.0
        }
        fn reset(
            &self,
            _: &mut Scratch,
            mode: usize,
            _: usize,
            x: &[f64],
            out: &mut [f64],
        ) -> usize {
            out.copy_from_slice(x);
            mode
        }
    }

    /// The DOP853 dense output of the shipped dimensions (compile-time rows) is the general
    /// loop's, bit for bit, on a strided lane of a batch store: coefficients, the three extra
    /// evaluations, and the interpolated states.
    #[test]
    fn dop853_dense_output_of_fixed_dimensions_is_the_general_loops() {
        let mut uniform = xorshift(0x2545_f491_4f6c_dd1du64);
        let tab = crate::engine::tableau_of(Method::Dop853);
        for d in [2, 4, 6, 8, 10, 12] {
            let sys = Coupled(d);
            let (lanes, l) = (5, 3);
            let mut st = Store::new(d, lanes, 0, tab);
            for v in
                st.k.iter_mut()
                    .chain(st.x.iter_mut())
                    .chain(st.xn.iter_mut())
            {
                *v = 2.0 * uniform() - 1.0;
            }
            let h = 0.01 + 0.1 * uniform();
            let run = |fixed: bool| {
                let mut sc = EventScratch::new(d, 0);
                gather_ends(&st, l, Method::Dop853, &mut sc);
                let mut stats = Stats::default();
                let interp = if fixed {
                    crate::engine::with_dim!(d,
                        D => dop853_dense_fixed::<Coupled, D>(&sys, 0, &st, l, h, &mut sc, &mut stats),
                        _ => unreachable!("{d} is a shipped dimension"))
                } else {
                    dop853_dense_dyn(&sys, 0, &st, l, h, &mut sc, &mut stats)
                };
                let dense = Dense {
                    interp,
                    h,
                    x0: &sc.x0,
                    x1: &sc.x1,
                    f0: &sc.f0,
                    f1: &sc.f1,
                    cont: &sc.cont,
                };
                let mut states = vec![0.0; 3 * d];
                for (i, out) in states.chunks_exact_mut(d).enumerate() {
                    dense.eval(0.2 + 0.3 * i as f64, out);
                }
                (sc.cont[..8 * d].to_vec(), states, stats.rhs_evals)
            };
            let (fixed, dynamic) = (run(true), run(false));
            assert_eq!(fixed.2, 3);
            assert_eq!(fixed.2, dynamic.2);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fixed.0), bits(&dynamic.0), "coefficients, d = {d}");
            assert_eq!(bits(&fixed.1), bits(&dynamic.1), "states, d = {d}");
            assert!(
                fixed.0.iter().all(|v| v.is_finite()) && fixed.0[4 * d..].iter().any(|&v| v != 0.0)
            );
        }
    }

    /// The flow of [`Coupled`] with one affine guard `x₀ − c` (Either direction).
    struct Plane {
        d: usize,
        c: f64,
    }

    crate::integrate_through_dyn!(Plane);
    impl HybridSystem for Plane {
        fn dim(&self) -> usize {
            self.d
        }
        fn guards(&self, _mode: usize) -> &[crate::GuardSpec] {
            &[]
        }
        fn flow(&self, ws: &mut Scratch, mode: usize, x: &[f64], dx: &mut [f64]) {
            Coupled(self.d).flow(ws, mode, x, dx)
        }
        fn guard(&self, _ws: &mut Scratch, _mode: usize, _k: usize, x: &[f64]) -> f64 {
            x[0] - self.c
        }
        fn guard_is_linear(&self, _mode: usize, _k: usize) -> bool {
            true
        }
        fn reset(
            &self,
            ws: &mut Scratch,
            mode: usize,
            k: usize,
            x: &[f64],
            o: &mut [f64],
        ) -> usize {
            Coupled(self.d).reset(ws, mode, k, x, o)
        }
    }

    /// The nested polynomial's value has the bits of [`Dense::eval`] on a one-component state
    /// (the same operations in the same order), and its derivative is the derivative: checked
    /// against a central difference of the value on random coefficients, for DOPRI5's five rows
    /// and DOP853's eight.
    #[test]
    fn nested_polynomial_is_the_dense_output_and_its_derivative() {
        let mut uniform = xorshift(0x9e37_79b9_7f4a_7c15u64);
        for (interp, rows) in [(Interp::Dopri5, 5), (Interp::Dop853, 8)] {
            for _ in 0..200 {
                let c: Vec<f64> = (0..8).map(|_| 2.0 * uniform() - 1.0).collect();
                let z = [0.0];
                let dense = Dense {
                    interp,
                    h: 0.1,
                    x0: &z,
                    x1: &z,
                    f0: &z,
                    f1: &z,
                    cont: &c,
                };
                let theta = uniform();
                let mut out = [0.0];
                dense.eval(theta, &mut out);
                let (v, dv) = nested_with_derivative(&c, rows, theta);
                assert_eq!(v.to_bits(), out[0].to_bits(), "{rows} rows at θ = {theta}");
                let four = nested_values(&c, rows, [theta, 0.2, 0.4, 0.8]);
                assert_eq!(four[0].to_bits(), v.to_bits());
                for (i, t) in [0.2, 0.4, 0.8].into_iter().enumerate() {
                    let one = nested_with_derivative(&c, rows, t).0;
                    assert_eq!(four[i + 1].to_bits(), one.to_bits());
                }
                let e = 1e-6;
                let fd = (nested_with_derivative(&c, rows, theta + e).0
                    - nested_with_derivative(&c, rows, theta - e).0)
                    / (2.0 * e);
                assert!(
                    (dv - fd).abs() <= 1e-8 * (1.0 + dv.abs()),
                    "{dv} against {fd}"
                );
            }
        }
    }

    /// The Newton iteration on an affine guard's polynomial finds the root the Illinois
    /// iteration finds on the states, to within the width of their brackets (a few 1e-15 of
    /// the step), and its state lies on the post-crossing side, for DOPRI5 and DOP853 dense
    /// outputs of a nonlinear flow, in dimensions 2 and 4, on random steps and random roots
    /// in both directions.
    #[test]
    fn newton_on_the_guard_polynomial_finds_the_illinois_root() {
        let mut uniform = xorshift(0x2545_f491_4f6c_dd1du64);
        let mut roots = 0;
        for method in [Method::Dopri5, Method::Dop853] {
            let tab = crate::engine::tableau_of(method);
            for d in [2, 4] {
                for _ in 0..300 {
                    let mut st = Store::new(d, 1, 1, tab);
                    for v in st.k.iter_mut().chain(st.x.iter_mut()) {
                        *v = 2.0 * uniform() - 1.0;
                    }
                    // A consistent step: x₁ from the stages with the method's weights b.
                    let h = 0.05 + 0.5 * uniform();
                    let last = tab.n_stages - 1;
                    for j in 0..d {
                        let mut s = 0.0;
                        for (q, &w) in tab.a[last].iter().enumerate() {
                            s += w * st.k[q * d + j];
                        }
                        st.xn[j] = st.x[j] + h * s;
                    }
                    let mut sc = EventScratch::new(d, 1);
                    gather_ends(&st, 0, method, &mut sc);
                    let mut stats = Stats::default();
                    let sys0 = Plane { d, c: 0.0 };
                    let interp = build_dense(&sys0, method, 0, &st, 0, h, &mut sc, &mut stats);
                    let dense = Dense {
                        interp,
                        h,
                        x0: &sc.x0,
                        x1: &sc.x1,
                        f0: &sc.f0,
                        f1: &sc.f1,
                        cont: &sc.cont,
                    };
                    // The guard's level: the first component at a random interior point.
                    let mut xs = vec![0.0; d];
                    dense.eval(0.05 + 0.9 * uniform(), &mut xs);
                    let sys = Plane { d, c: xs[0] };
                    let mut ws = Scratch::new();
                    let rows = nested_rows(interp);
                    let mut poly = [0.0; POLY_ROWS];
                    let zero = vec![0.0; d];
                    guard_poly(&sys, &mut ws, 0, 0, dense.cont, &zero, rows, &mut poly);
                    let g_at = |theta: f64, xr: &mut [f64], ws: &mut Scratch| {
                        if theta == 1.0 {
                            xr.copy_from_slice(dense.x1);
                        } else {
                            dense.eval(theta, xr);
                        }
                        sys.guard(ws, 0, 0, xr)
                    };
                    let mut xr = vec![0.0; d];
                    let gs: Vec<f64> = (0..M)
                        .map(|i| g_at(i as f64 / (M - 1) as f64, &mut xr, &mut ws))
                        .collect();
                    let Some(i) = (0..M - 1).find(|&i| crosses(Crossing::Either, gs[i], gs[i + 1]))
                    else {
                        continue;
                    };
                    let (ta, tb) = (i as f64 / (M - 1) as f64, (i + 1) as f64 / (M - 1) as f64);
                    let t_scale = 1.0 + h;
                    let tol = bracket_tol(t_scale, h);
                    let lo = (ta, gs[i]);
                    let hi = (tb, gs[i + 1]);
                    let mut xl = vec![0.0; d];
                    let newton = refine_linear(
                        &sys, &mut ws, 0, 0, &dense, &poly, rows, tol, lo, hi, &mut xl,
                    )
                    .expect("the polynomial's root");
                    let illinois = refine(&sys, &mut ws, 0, 0, &dense, t_scale, lo, hi, &mut xr);
                    assert!(
                        (newton - illinois).abs() <= 6.0 * tol,
                        "{method:?} d = {d}: Newton {newton}, Illinois {illinois}, tol {tol:e}"
                    );
                    assert!(newton > ta && newton <= tb);
                    let sig = if gs[i] < 0.0 { 1.0 } else { -1.0 };
                    assert!(sig * sys.guard(&mut ws, 0, 0, &xl) >= 0.0);
                    roots += 1;
                }
            }
        }
        assert!(roots > 600, "{roots} roots tested");
    }
}
