//! Event location on an accepted step `[t₀, t₁]`, `h = t₁ − t₀`, parametrised by `θ ∈ [0, 1]`.
//!
//! **Detection.** Every guard `g_k` of the mode is evaluated at the step's end points (exact
//! states x₀, x₁) and at [`N_SAMPLES`] = 4 interior points `θ = i/5` of the cubic Hermite
//! interpolant built from `(x₀, f(x₀), x₁, f(x₁))` (free: all four are stored). A *directional
//! crossing* on a sub-interval `[θ_a, θ_b]` means: the left value is strictly on the pre-crossing
//! side and the right value is on the post-crossing side or zero (`Rising`: `g_a < 0 ≤ g_b`;
//! `Falling`: `g_a > 0 ≥ g_b`; `Either`: one of the two). Sampling the interior catches a step
//! that straddles two sign changes (the guard dips across zero and back, ends on the same side)
//! as long as the dip spans one of the five sub-intervals; two crossings inside one sub-interval
//! of length h/5 are not resolved, and a dip shallower than the Hermite interpolation error
//! (O(h⁴), about the local error tolerance) can be missed by the detection — a grazing contact
//! of that depth is below the resolution of the integration anyway. The samples and guard
//! values are computed before the per-lane pass (column-wise over lanes in a batch, through
//! [`HybridSystem::guard_batch`]); only a lane with a candidate crossing does the work below.
//!
//! **Confirmation and refinement.** If any sub-interval shows a crossing, the method's own dense
//! output is built (RK4: the Hermite cubic itself; DOPRI5: Shampine's 4th-order continuous
//! extension, free; DOP853: the 7th-order one, three extra flow evaluations), the interior
//! samples are recomputed on it, and for each guard the first crossing sub-interval is refined
//! with the Illinois variant of regula falsi (Dowell & Jarratt 1971), with a bisection step when
//! three iterations fail to halve the bracket, until the bracket is ≤ 4ε·max(|t₀|, |t₁|) in time
//! (≈ 1e-15 for t ≈ 1). The *right-hand* end of the final bracket is reported: the returned state
//! is the dense-output state at that θ and its guard value is on the post-crossing side or zero.
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
            model: Scratch::new(),
        }
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
    /// State at θ ∈ (0, 1) (θ = 1 is handled by the callers with the exact x₁).
    fn eval(&self, theta: f64, out: &mut [f64]) {
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
            // The lane's stages k₀…k₁₂, gathered once (contiguous), then k₁₃…k₁₅ appended: the
            // sums below read them in the same order with the same weights as a strided read.
            for q in 0..13 {
                for j in 0..d {
                    sc.kl[q * d + j] = kq(q, j);
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
    }
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
    let tol = (4.0 * f64::EPSILON * t_scale / dense.h.abs()).max(4.0 * f64::EPSILON);
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

/// Locate the earliest admissible directional crossing on the accepted step of lane `l`
/// (x₀ in `st.x`, x₁ in `st.xn`, stages in `st.k`, guard samples in `st.gs`). Returns `(guard, θ*)` with the event state
/// in `sc.xbest`; without an event, stores the guard values at x₁ in `st.g` for the next step.
#[allow(clippy::too_many_arguments)]
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
    let guards = sys.guards(mode);
    let ng = guards.len();
    if ng == 0 {
        return None;
    }
    let (stride, blk) = (st.stride, st.blk());
    if st.cand[l] == 0 {
        // No sub-interval of any guard shows a crossing (the column kernel `mark_candidates`
        // made the same test): keep the guard values at x₁ for the next step.
        for k in 0..ng {
            st.g[k * stride + l] = st.gs[(k * M + M - 1) * stride + l];
        }
        return None;
    }
    // Guard values at θ = 0 (kept from the previous step), at the Hermite samples and at x₁
    // (computed column-wise for all lanes before this per-lane pass).
    for k in 0..ng {
        sc.gv[k * M] = st.g[k * stride + l];
        for i in 1..M {
            sc.gv[k * M + i] = st.gs[(k * M + i) * stride + l];
        }
    }
    let inv = 1.0 / (N_SAMPLES + 1) as f64;
    let any = (0..ng).any(|k| {
        let g = &sc.gv[k * M..(k + 1) * M];
        (0..M - 1).any(|i| crosses(guards[k].crossing, g[i], g[i + 1]))
    });
    let store_end = |st: &mut Store, sc: &EventScratch| {
        for k in 0..ng {
            st.g[k * stride + l] = sc.gv[k * M + M - 1];
        }
    };
    if !any {
        store_end(st, sc);
        return None;
    }
    let last = crate::engine::tableau_of(method).n_stages - 1;
    Store::gather(&st.x, stride, l, &mut sc.x0);
    Store::gather(&st.xn, stride, l, &mut sc.x1);
    Store::gather(&st.k[..blk], stride, l, &mut sc.f0);
    Store::gather(&st.k[last * blk..(last + 1) * blk], stride, l, &mut sc.f1);
    let interp = build_dense(sys, method, mode, st, l, h, sc, stats);
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
    if interp != Interp::Hermite {
        for i in 1..=N_SAMPLES {
            dense.eval(i as f64 * inv, xs);
            for k in 0..ng {
                gv[k * M + i] = sys.guard(model, mode, k, xs);
            }
        }
    }
    let t_scale = t0.abs().max(t1.abs());
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
    if best.is_none() {
        store_end(st, sc);
    }
    best
}
