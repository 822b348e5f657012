//! Physics claims about the kneed walker (Hsu Chen 2007), each against an independent reference:
//! a merged-link model for the locked knee, conservation laws computed from the point masses,
//! and Hsu Chen's published fixed point.

use pdw_hybrid::{HybridSystem, Integrator, Options, Scratch, Section, StopReason};
use pdw_soa::{ChainBuilder, Link, Workspace};
use pdw_walkers::kneed::{
    hsu_chen_section, Kneed, KneedParams, HEEL_STRIKE, KNEE_STRIKE, LOCKED, UNLOCKED,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A point `Σ len_j · (−sin θ_j, cos θ_j)` and its velocity, for terms `(len_j, θ_j, θ̇_j)`.
fn point(terms: &[(f64, f64, f64)]) -> ([f64; 2], [f64; 2]) {
    let mut r = [0.0; 2];
    let mut v = [0.0; 2];
    for &(l, th, w) in terms {
        r[0] -= l * th.sin();
        r[1] += l * th.cos();
        v[0] -= l * w * th.cos();
        v[1] -= l * w * th.sin();
    }
    (r, v)
}

/// Point masses `(m, r, v)` of the kneed walker at state `x` (stance foot at the origin, at
/// rest), in the order stance shank, stance thigh, hip, swing thigh, swing shank.
fn masses(p: &KneedParams, x: &[f64]) -> Vec<(f64, [f64; 2], [f64; 2])> {
    let (ls, lt) = (p.a1 + p.b1, p.a2 + p.b2);
    let l = ls + lt;
    let (t1, tt, ts) = (x[0], x[0] + x[1], x[0] + x[1] + x[2]);
    let (w1, wt, ws) = (x[3], x[3] + x[4], x[3] + x[4] + x[5]);
    let mk = |m: f64, terms: &[(f64, f64, f64)]| {
        let (r, v) = point(terms);
        (m, r, v)
    };
    vec![
        mk(p.shank_mass, &[(p.a1, t1, w1)]),
        mk(p.thigh_mass, &[(ls + p.a2, t1, w1)]),
        mk(p.hip_mass, &[(l, t1, w1)]),
        mk(p.thigh_mass, &[(l, t1, w1), (-p.b2, tt, wt)]),
        mk(p.shank_mass, &[(l, t1, w1), (-lt, tt, wt), (-p.b1, ts, ws)]),
    ]
}

fn ang_mom(pm: &[(f64, [f64; 2], [f64; 2])], c: [f64; 2]) -> f64 {
    pm.iter()
        .map(|(m, r, v)| m * ((r[0] - c[0]) * v[1] - (r[1] - c[1]) * v[0]))
        .sum()
}

fn kinetic(pm: &[(f64, [f64; 2], [f64; 2])]) -> f64 {
    pm.iter()
        .map(|(m, _, v)| 0.5 * m * (v[0] * v[0] + v[1] * v[1]))
        .sum()
}

fn shifted(pm: &[(f64, [f64; 2], [f64; 2])], vb: [f64; 2]) -> Vec<(f64, [f64; 2], [f64; 2])> {
    pm.iter()
        .map(|(m, r, v)| (*m, *r, [v[0] + vb[0], v[1] + vb[1]]))
        .collect()
}

#[test]
fn locked_mode_equals_merged_link_model() {
    let p = KneedParams::default();
    let w = Kneed::new(p).unwrap();
    // second model: thigh and shank merged into one rigid swing leg (two point masses)
    let (ls, lt) = (p.a1 + p.b1, p.a2 + p.b2);
    let l = ls + lt;
    let link = |len: f64, pm: &[(f64, f64)]| {
        let m: f64 = pm.iter().map(|q| q.0).sum();
        let c = pm.iter().map(|q| q.0 * q.1).sum::<f64>() / m;
        Link {
            to_next: [0.0, len],
            com: [0.0, c],
            mass: m,
            inertia: pm.iter().map(|q| q.0 * (q.1 - c).powi(2)).sum(),
        }
    };
    let merged = ChainBuilder::new()
        .gravity(p.gravity)
        .slope(p.slope)
        .revolute(link(
            l,
            &[
                (p.shank_mass, p.a1),
                (p.thigh_mass, ls + p.a2),
                (p.hip_mass, l),
            ],
        ))
        .revolute(link(
            -l,
            &[(p.thigh_mass, -p.b2), (p.shank_mass, -(lt + p.b1))],
        ))
        .build()
        .unwrap();
    let mut ws = Workspace::new(&merged);
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for _ in 0..200 {
        let x = [
            rng.random_range(-0.6..0.6),
            rng.random_range(-1.2..1.2),
            0.0,
            rng.random_range(-3.0..3.0),
            rng.random_range(-5.0..5.0),
            0.0,
        ];
        let mut dx = [0.0; 6];
        w.flow(&mut Scratch::new(), LOCKED, &x, &mut dx);
        let mut qdd = [0.0; 2];
        pdw_soa::aba(
            &merged,
            &mut ws,
            &x[0..2],
            &[x[3], x[4]],
            &[0.0; 2],
            None,
            &mut qdd,
        )
        .unwrap();
        let scale = 1.0 + qdd[0].abs().max(qdd[1].abs());
        assert!(
            (dx[3] - qdd[0]).abs() < 1e-12 * scale,
            "{} vs {}",
            dx[3],
            qdd[0]
        );
        assert!(
            (dx[4] - qdd[1]).abs() < 1e-12 * scale,
            "{} vs {}",
            dx[4],
            qdd[1]
        );
        assert_eq!(dx[5], 0.0);
        assert_eq!(dx[2], 0.0);
    }
}

#[test]
fn knee_strike_conserves_angular_momenta_and_loses_the_predicted_energy() {
    let p = KneedParams::default();
    let w = Kneed::new(p).unwrap();
    let l = w.leg_length();
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for _ in 0..100 {
        let x = [
            rng.random_range(-0.3..0.3),
            rng.random_range(-0.2..0.6),
            0.0,
            rng.random_range(-2.0..-0.2),
            rng.random_range(-1.0..3.0),
            rng.random_range(0.1..8.0),
        ];
        let mut y = [0.0; 6];
        assert_eq!(
            w.reset(&mut Scratch::new(), UNLOCKED, KNEE_STRIKE, &x, &mut y),
            LOCKED
        );
        assert_eq!(y[5], 0.0);
        let (pre, post) = (masses(&p, &x), masses(&p, &y));
        let scale: f64 = pre.iter().map(|(m, _, v)| m * l * v[0].hypot(v[1])).sum();
        let (h0, h1) = (ang_mom(&pre, [0.0, 0.0]), ang_mom(&post, [0.0, 0.0]));
        assert!(
            (h0 - h1).abs() < 1e-12 * scale,
            "about the stance foot: {h0} vs {h1}"
        );
        let hip = pre[2].1;
        let (s0, s1) = (ang_mom(&pre[3..], hip), ang_mom(&post[3..], hip));
        assert!(
            (s0 - s1).abs() < 1e-12 * scale,
            "swing leg about the hip: {s0} vs {s1}"
        );
        // ΔT = −½ q̇₃⁻ Λ (work of the locking impulse, kernel sign)
        let mut v = [0.0; 3];
        let lam = w.knee_strike(&x, &mut v);
        let (k0, k1) = (kinetic(&pre), kinetic(&post));
        assert!(
            ((k1 - k0) + 0.5 * x[5] * lam).abs() < 1e-12 * k0,
            "ΔT {} vs {}",
            k1 - k0,
            -0.5 * x[5] * lam
        );
        assert!(k1 <= k0);
    }
}

#[test]
fn heel_strike_conserves_angular_momenta_and_loses_the_predicted_energy() {
    let p = KneedParams::default();
    let w = Kneed::new(p).unwrap();
    let l = w.leg_length();
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    for _ in 0..100 {
        let a: f64 = rng.random_range(0.05..0.5);
        let x = [
            -a,
            2.0 * a,
            0.0,
            rng.random_range(-2.5..-0.2),
            rng.random_range(-3.0..3.0),
            0.0,
        ];
        let mut v = [0.0; 5];
        let hs = w.heel_strike(&x, &mut v);
        let pre = masses(&p, &x);
        let post = shifted(
            &masses(&p, &[x[0], x[1], x[2], v[2], v[3], v[4]]),
            [v[0], v[1]],
        );
        let contact = w.swing_foot(&x);
        let scale: f64 = pre.iter().map(|(m, _, u)| m * l * u[0].hypot(u[1])).sum();
        let (h0, h1) = (ang_mom(&pre, contact), ang_mom(&post, contact));
        assert!(
            (h0 - h1).abs() < 1e-12 * scale,
            "about the contact: {h0} vs {h1}"
        );
        let hip = pre[2].1;
        let (t0, t1) = (ang_mom(&pre[0..2], hip), ang_mom(&post[0..2], hip));
        assert!(
            (t0 - t1).abs() < 1e-12 * scale,
            "trailing leg about the hip: {t0} vs {t1}"
        );
        // the knee stays locked and the new contact point is at rest
        assert!(v[4].abs() < 1e-12 * scale);
        let foot_v = post[4].2;
        // swing-foot velocity = shank-mass velocity + b1·ω_shank·(cos, sin) of the shank axis
        let ts = x[0] + x[1] + x[2];
        let ws = v[2] + v[3] + v[4];
        let fv = [
            foot_v[0] + p.a1 * ws * ts.cos(),
            foot_v[1] + p.a1 * ws * ts.sin(),
        ];
        assert!(
            fv[0].hypot(fv[1]) < 1e-12 * scale,
            "contact velocity after impact {fv:?}"
        );
        // ΔT equals the impulse's work ½ Λ·v_c⁻
        let ts_pre_w = x[3] + x[4] + x[5];
        let fpre = pre[4].2;
        let vc = [
            fpre[0] + p.a1 * ts_pre_w * ts.cos(),
            fpre[1] + p.a1 * ts_pre_w * ts.sin(),
        ];
        let (k0, k1) = (kinetic(&pre), kinetic(&post));
        let work = 0.5 * (hs.impulse[0] * vc[0] + hs.impulse[1] * vc[1]);
        assert!(
            ((k1 - k0) - work).abs() < 1e-12 * k0,
            "ΔT {} vs work {}",
            k1 - k0,
            work
        );
    }
}

/// Runs one stride from the section with DOP853 at `tol`, returning the worst relative energy
/// drift within a mode, the stop reasons and the next section state.
fn stride(w: &Kneed, s: &[f64], tol: f64) -> (f64, Vec<StopReason>, [f64; 3]) {
    let mut x = [0.0; 6];
    w.lift(s, &mut x);
    let mut mode = w.section_mode();
    let mut integ = Integrator::new(6, Options::dop853(tol)).unwrap();
    let mut t = 0.0;
    let mut drift: f64 = 0.0;
    let mut stops = vec![];
    for _ in 0..2 {
        let e0 = w.energy(&x);
        let stop = integ.integrate_observed(w, mode, &mut t, &mut x, 5.0, &mut |_, y| {
            drift = drift.max(((w.energy(y) - e0) / e0).abs());
        });
        stops.push(stop);
        let StopReason::Guard { guard } = stop else {
            break;
        };
        let mut y = [0.0; 6];
        mode = w.reset(&mut Scratch::new(), mode, guard, &x, &mut y);
        x = y;
    }
    let mut s2 = [0.0; 3];
    w.project(&x, &mut s2);
    (drift, stops, s2)
}

#[test]
fn energy_conserved_between_impacts_in_both_modes() {
    let w = Kneed::new(KneedParams::default()).unwrap();
    let (drift, stops, _) = stride(&w, &hsu_chen_section(w.params().slope), 1e-13);
    assert_eq!(
        stops,
        vec![
            StopReason::Guard { guard: KNEE_STRIKE },
            StopReason::Guard { guard: HEEL_STRIKE }
        ]
    );
    assert!(drift < 1e-10, "relative energy drift {drift:e}");
}

#[test]
fn stable_gait_near_hsu_chen_published_fixed_point() {
    // The gait is stable: iterating the stride map from the published state converges.
    let w = Kneed::new(KneedParams::default()).unwrap();
    let published = hsu_chen_section(w.params().slope);
    let mut s = published;
    let mut step = f64::INFINITY;
    for _ in 0..60 {
        let (_, stops, s2) = stride(&w, &s, 1e-12);
        assert_eq!(stops.len(), 2);
        step = (0..3).map(|i| (s2[i] - s[i]).abs()).fold(0.0, f64::max);
        s = s2;
    }
    assert!(
        step < 1e-8,
        "stride map iteration did not settle: last change {step:e}"
    );
    // Hsu Chen integrated with forward Euler (dt = 1e-3): agreement in the second or third
    // digit only (measured: 5e-4 in the stance angle, ~1e-2 in the rates).
    assert!((s[0] - published[0]).abs() < 2e-3, "{s:?} vs {published:?}");
    assert!((s[1] - published[1]).abs() < 2e-2, "{s:?} vs {published:?}");
    assert!((s[2] - published[2]).abs() < 2e-2, "{s:?} vs {published:?}");
}

#[test]
fn knee_flexes_at_the_start_of_the_swing() {
    // just after heel strike the free knee must bend (q̈₃ < 0, flexion), not hyper-extend
    let w = Kneed::new(KneedParams::default()).unwrap();
    let mut x = [0.0; 6];
    w.lift(&hsu_chen_section(w.params().slope), &mut x);
    let mut dx = [0.0; 6];
    w.flow(&mut Scratch::new(), UNLOCKED, &x, &mut dx);
    assert!(dx[5] < 0.0, "q̈₃ = {}", dx[5]);
}
