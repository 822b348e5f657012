//! The per-lane driver of event location: the end-point flags, the samples on the step's
//! Hermite interpolant, the extremum probe, the method's dense output, and the earliest
//! admissible root over the guards.

use super::dense::{build_dense, gather_ends, hermite_basis, hermite_point, Dense};
use super::detect::{clears_direction, crosses, cubic_extrema, guard_bit, hull_and_margin};
use super::poly::{guard_poly, nested_rows, nested_values, POLY_ROWS};
use super::refine::{bracket_tol, refine, refine_linear};
use super::{EventScratch, Interp, M, N_SAMPLES};
use crate::engine::Store;
use crate::options::{Method, Stats};
use crate::system::{Crossing, Scratch};
use crate::HybridSystem;

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

/// [`locate`] on a step with some guard flagged: the samples on the step's Hermite
/// interpolant detect a crossing (or `probe_extrema` a window between two samples); the
/// method's dense output is then built, the samples recomputed on it, and the earliest
/// admissible root refined there.
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
    let store_end = |st: &mut Store| store_end(st, ng, l);
    stats.sampled += 1;
    let flags = st.cand[l];
    let mut gathered = sample_on_hermite(sys, method, mode, st, l, h, sc);
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
    let (dense, mut work) = split_scratch(sc, interp, h);
    resample_on_dense(sys, mode, flags, &dense, &mut work);
    let t_scale = t0.abs().max(t1.abs());
    let mut best = earliest_root(sys, mode, &dense, &mut work, t_scale);
    if let (None, Some(window)) = (best, probe) {
        best = root_in_window(sys, mode, &dense, &mut work, t_scale, window);
    }
    if best.is_none() {
        store_end(st);
    }
    best
}

/// Values at θ = 0, at the interior points θ = i/5 and at θ = 1 of each flagged guard of lane
/// `l` on the state's cubic Hermite interpolant, into `sc.gv` — for an affine guard with rates,
/// its own cubic Hermite from end values and rates, the same curve without gathering the
/// state. A guard that is not flagged has no crossing to show: its interior values are set to
/// g(x₀). Returns whether the end states were gathered into `sc` (a nonlinear guard, or no
/// rates from the model).
fn sample_on_hermite<S: HybridSystem + ?Sized>(
    sys: &S,
    method: Method,
    mode: usize,
    st: &Store,
    l: usize,
    h: f64,
    sc: &mut EventScratch,
) -> bool {
    let ng = sys.guards(mode).len();
    let stride = st.stride;
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
    gathered
}

/// The vectors of an [`EventScratch`] that the root search writes, borrowed apart from the
/// interpolation data that [`Dense`] reads.
struct Work<'a> {
    /// State at a sample point.
    xs: &'a mut [f64],
    /// State at the current root iterate.
    xr: &'a mut [f64],
    /// State at the winning event.
    xbest: &'a mut [f64],
    /// `(ng × (N_SAMPLES + 2))` guard values at θ = 0, 1/5, …, 1.
    gv: &'a mut [f64],
    /// `(ng × 8)` coefficients of each affine guard along the dense output.
    poly: &'a mut [f64],
    /// `(ng)` guard k has its polynomial in `poly`.
    lin: &'a mut [bool],
    /// `(dim)` zeros.
    zero: &'a [f64],
    /// Number of rows of the dense output in nested form ([`nested_rows`]).
    rows: usize,
    /// The model's scratch.
    model: &'a mut Scratch,
}

/// The dense output of `sc` (interpolant `interp`, step `h`) and the vectors the root search
/// writes.
fn split_scratch(sc: &mut EventScratch, interp: Interp, h: f64) -> (Dense<'_>, Work<'_>) {
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
    let work = Work {
        xs,
        xr,
        xbest,
        gv,
        poly,
        lin,
        zero,
        rows: nested_rows(interp),
        model,
    };
    (dense, work)
}

/// The interior samples of every flagged guard recomputed on the method's own interpolant at
/// the same points (the brackets the root finder starts from hold the guard's values on the
/// curve it solves on): an affine guard's from its polynomial ([`guard_poly`]), the others'
/// from the dense-output state. Only the flagged guards: a guard whose step `mark_near`
/// cleared has no crossing to show (its interior values stay g(x₀), as in the Hermite samples).
fn resample_on_dense<S: HybridSystem + ?Sized>(
    sys: &S,
    mode: usize,
    flags: u8,
    dense: &Dense<'_>,
    w: &mut Work<'_>,
) {
    let ng = sys.guards(mode).len();
    let (rows, inv) = (w.rows, 1.0 / (N_SAMPLES + 1) as f64);
    let mut states_needed = false;
    for k in 0..ng {
        let flagged = flags & guard_bit(k) != 0;
        w.lin[k] = flagged && rows > 0 && sys.guard_is_linear(mode, k);
        if w.lin[k] {
            let p = &mut w.poly[k * POLY_ROWS..(k + 1) * POLY_ROWS];
            guard_poly(sys, w.model, mode, k, dense.cont, w.zero, rows, p);
        } else if flagged {
            states_needed = true;
        }
    }
    let thetas: [f64; N_SAMPLES] = std::array::from_fn(|i| (i + 1) as f64 * inv);
    for k in 0..ng {
        if w.lin[k] {
            let v = nested_values(&w.poly[k * POLY_ROWS..], rows, thetas);
            w.gv[k * M + 1..=k * M + N_SAMPLES].copy_from_slice(&v);
        }
    }
    if states_needed {
        for (i, &theta) in thetas.iter().enumerate() {
            dense.eval(theta, w.xs);
            for k in 0..ng {
                if !w.lin[k] && flags & guard_bit(k) != 0 {
                    w.gv[k * M + i + 1] = sys.guard(w.model, mode, k, w.xs);
                }
            }
        }
    }
}

/// The earliest admissible root over all guards on their sampled sub-intervals (ties: lowest
/// guard index), with its state in `w.xbest`: per guard the first crossing sub-interval is
/// refined, and an inadmissible root moves the scan on to the guard's later sub-intervals.
fn earliest_root<S: HybridSystem + ?Sized>(
    sys: &S,
    mode: usize,
    dense: &Dense<'_>,
    w: &mut Work<'_>,
    t_scale: f64,
) -> Option<(usize, f64)> {
    let inv = 1.0 / (N_SAMPLES + 1) as f64;
    let (rows, tol) = (w.rows, bracket_tol(t_scale, dense.h));
    let mut best: Option<(usize, f64)> = None;
    for (k, spec) in sys.guards(mode).iter().enumerate() {
        for i in 0..M - 1 {
            let theta_a = i as f64 * inv;
            if let Some((_, tb)) = best {
                if theta_a >= tb {
                    break;
                }
            }
            let (ga, gb) = (w.gv[k * M + i], w.gv[k * M + i + 1]);
            if !crosses(spec.crossing, ga, gb) {
                continue;
            }
            let theta_b = if i + 1 == M - 1 {
                1.0
            } else {
                (i + 1) as f64 * inv
            };
            let (lo, hi) = ((theta_a, ga), (theta_b, gb));
            let poly_k = &w.poly[k * POLY_ROWS..(k + 1) * POLY_ROWS];
            let (model, xr) = (&mut *w.model, &mut *w.xr);
            let root = w.lin[k]
                .then(|| refine_linear(sys, model, mode, k, dense, poly_k, rows, tol, lo, hi, xr))
                .flatten()
                .unwrap_or_else(|| refine(sys, model, mode, k, dense, t_scale, lo, hi, xr));
            if best.is_some_and(|(_, tb)| root >= tb) {
                break;
            }
            if sys.admissible(mode, k, w.xr) {
                best = Some((k, root));
                w.xbest.copy_from_slice(w.xr);
                break;
            }
        }
    }
    best
}

/// The window between two samples that only the cubic's extremum showed (`probe_extrema`:
/// guard `k`, left sample `i`, extremum θ_b), confirmed and refined on the dense output; the
/// root, if admissible, with its state in `w.xbest`.
fn root_in_window<S: HybridSystem + ?Sized>(
    sys: &S,
    mode: usize,
    dense: &Dense<'_>,
    w: &mut Work<'_>,
    t_scale: f64,
    (k, i, theta_b): (usize, usize, f64),
) -> Option<(usize, f64)> {
    let inv = 1.0 / (N_SAMPLES + 1) as f64;
    let (theta_a, ga) = (i as f64 * inv, w.gv[k * M + i]);
    dense.eval(theta_b, w.xs);
    let gb = sys.guard(w.model, mode, k, w.xs);
    if !crosses(sys.guards(mode)[k].crossing, ga, gb) {
        return None;
    }
    let root = refine(
        sys,
        w.model,
        mode,
        k,
        dense,
        t_scale,
        (theta_a, ga),
        (theta_b, gb),
        w.xr,
    );
    if sys.admissible(mode, k, w.xr) {
        w.xbest.copy_from_slice(w.xr);
        return Some((k, root));
    }
    None
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
