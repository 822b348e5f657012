//! Physics claims about the kneed walker (Hsu Chen 2007; the `kneed` preset of the chain walker,
//! `models/kneed.toml`), each against an independent reference: the point-mass equations of
//! motion written in the test (d'Alembert, `common::PointChain`) for both modes, conservation
//! laws computed from the point masses, and Hsu Chen's published fixed point.
//!
//! State `(q₀, q₁, q₂, q₃, q̇₀ … q̇₃)`: stance leg, stance knee (locked, 0), hip, swing knee
//! (flexion `q₃ < 0`). Modes: 0 swing knee free, 1 every knee locked.

use crate::common;

use common::{ang_mom, check_flow_against_point_masses, kinetic, param, PointChain};
use pdw_hybrid::{HybridSystem, Integrator, Options, Scratch, Section, StopReason};
use pdw_walkers::chain_walker::{FREE, LOCKED};
use pdw_walkers::{presets, ChainWalker, Walker};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Guard (free mode) of the knee strike.
const KNEE_STRIKE: usize = 0;
/// Guard (locked mode) of the heel strike.
const HEEL_STRIKE: usize = 0;

/// Hsu Chen 2007's parameters ("Passive dynamic walking with knees: a point foot model", MIT
/// thesis), held by the test.
struct Kp {
    a1: f64,
    b1: f64,
    a2: f64,
    b2: f64,
    hip_mass: f64,
    thigh_mass: f64,
    shank_mass: f64,
    slope: f64,
    gravity: f64,
}

const HSU_CHEN: Kp = Kp {
    a1: 0.375,
    b1: 0.125,
    a2: 0.175,
    b2: 0.325,
    hip_mass: 0.5,
    thigh_mass: 0.5,
    shank_mass: 0.05,
    slope: 0.0504,
    gravity: 9.8,
};

/// Hsu Chen's published post-heel-strike state (absolute angles from the vertical) in section
/// coordinates (angles from the slope normal): `q₁ = 0.1877 + γ`, `q̇₁ = −1.1014`, hip rate
/// `q̇₂ − q̇₁ = −0.0399 + 1.1014`.
fn hsu_chen_section(gamma: f64) -> [f64; 3] {
    [0.1877 + gamma, -1.1014, -0.0399 + 1.1014]
}

/// The preset, checked to be at Hsu Chen's parameters.
fn kneed() -> ChainWalker {
    let w = presets::kneed(&[]).unwrap();
    let v = w.param_values();
    let p = HSU_CHEN;
    for (name, value) in [
        ("a1", p.a1),
        ("b1", p.b1),
        ("a2", p.a2),
        ("b2", p.b2),
        ("hip_mass", p.hip_mass),
        ("thigh_mass", p.thigh_mass),
        ("shank_mass", p.shank_mass),
        ("slope", p.slope),
        ("gravity", p.gravity),
    ] {
        assert_eq!(param(&v, name), value, "{name}");
    }
    assert_eq!(w.free_knee(), Some(3));
    assert_eq!(w.locked_joints(FREE), &[1]);
    assert_eq!(w.locked_joints(LOCKED), &[1, 3]);
    w
}

/// Point masses, in the order stance shank, stance thigh, hip, swing thigh, swing shank.
fn point_chain(p: &Kp) -> PointChain {
    let (ls, lt) = (p.a1 + p.b1, p.a2 + p.b2);
    PointChain {
        n: 4,
        masses: vec![
            (p.shank_mass, vec![(p.a1, 0)]),
            (p.thigh_mass, vec![(ls, 0), (p.a2, 1)]),
            (p.hip_mass, vec![(ls, 0), (lt, 1)]),
            (p.thigh_mass, vec![(ls, 0), (lt, 1), (-p.b2, 2)]),
            (p.shank_mass, vec![(ls, 0), (lt, 1), (-lt, 2), (-p.b1, 3)]),
        ],
        gravity: p.gravity,
        slope: p.slope,
    }
}

/// Hip, swing knee and swing foot (terms of [`PointChain::point`]).
fn hip_knee_foot(p: &Kp) -> [Vec<(f64, usize)>; 3] {
    let (ls, lt) = (p.a1 + p.b1, p.a2 + p.b2);
    [
        vec![(ls, 0), (lt, 1)],
        vec![(ls, 0), (lt, 1), (-lt, 2)],
        vec![(ls, 0), (lt, 1), (-lt, 2), (-ls, 3)],
    ]
}

#[test]
fn locked_mode_equals_point_mass_rigid_legs() {
    // every knee locked: two rigid legs of point masses (the merged-link model)
    check_flow_against_point_masses(
        &kneed(),
        &point_chain(&HSU_CHEN),
        LOCKED,
        &[0, 2],
        11,
        [3.0, 5.0, 5.0],
    );
}

#[test]
fn free_mode_equals_point_mass_three_link_swing() {
    check_flow_against_point_masses(
        &kneed(),
        &point_chain(&HSU_CHEN),
        FREE,
        &[0, 2, 3],
        14,
        [3.0, 5.0, 5.0],
    );
}

#[test]
fn knee_strike_conserves_angular_momenta_and_loses_the_predicted_energy() {
    let p = HSU_CHEN;
    let w = kneed();
    let pc = point_chain(&p);
    let [hip_t, knee_t, _] = hip_knee_foot(&p);
    let l = w.leg_length();
    let mut ws = Scratch::new();
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for _ in 0..100 {
        let x = [
            rng.random_range(-0.3..0.3),
            0.0,
            rng.random_range(-0.2..0.6),
            0.0,
            rng.random_range(-2.0..-0.2),
            0.0,
            rng.random_range(-1.0..3.0),
            rng.random_range(0.1..8.0),
        ];
        let mut y = [0.0; 8];
        assert_eq!(w.reset(&mut ws, FREE, KNEE_STRIKE, &x, &mut y), LOCKED);
        assert_eq!((y[3], y[7]), (0.0, 0.0));
        assert_eq!((y[1], y[5]), (0.0, 0.0));
        assert_eq!((y[0], y[2]), (x[0], x[2]));
        let (pre, post) = (pc.masses(&x, [0.0; 2]), pc.masses(&y, [0.0; 2]));
        let scale: f64 = pre.iter().map(|(m, _, v)| m * l * v[0].hypot(v[1])).sum();
        let (h0, h1) = (ang_mom(&pre, [0.0, 0.0]), ang_mom(&post, [0.0, 0.0]));
        assert!(
            (h0 - h1).abs() < 1e-12 * scale,
            "about the stance foot: {h0} vs {h1}"
        );
        let hip = pc.point(&hip_t, &x, [0.0; 2]).0;
        let (s0, s1) = (ang_mom(&pre[3..], hip), ang_mom(&post[3..], hip));
        assert!(
            (s0 - s1).abs() < 1e-12 * scale,
            "swing leg about the hip: {s0} vs {s1}"
        );
        // the locking impulse (a torque impulse on the shank) is the shank's change of angular
        // momentum about the knee; its work is ½ Λ (q̇₃⁻ + q̇₃⁺) = ½ Λ q̇₃⁻
        let knee = pc.point(&knee_t, &x, [0.0; 2]).0;
        let lam = ang_mom(&post[4..], knee) - ang_mom(&pre[4..], knee);
        let (k0, k1) = (kinetic(&pre), kinetic(&post));
        assert!(
            ((k1 - k0) - 0.5 * x[7] * lam).abs() < 1e-12 * k0,
            "ΔT {} vs {}",
            k1 - k0,
            0.5 * x[7] * lam
        );
        assert!(k1 <= k0);
    }
}

#[test]
fn heel_strike_conserves_angular_momenta_and_loses_the_predicted_energy() {
    let p = HSU_CHEN;
    let w = kneed();
    let pc = point_chain(&p);
    let [hip_t, _, foot_t] = hip_knee_foot(&p);
    let l = w.leg_length();
    assert_eq!(w.section_guard(), (LOCKED, HEEL_STRIKE));
    let mut ws = Scratch::new();
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    for _ in 0..100 {
        let a: f64 = rng.random_range(0.05..0.5);
        let x = [
            -a,
            0.0,
            2.0 * a,
            0.0,
            rng.random_range(-2.5..-0.2),
            0.0,
            rng.random_range(-3.0..3.0),
            0.0,
        ];
        // floating-chain rates (ẏ, ż, q̇₀ … q̇₃) of the old chain after the impact
        let mut v = [0.0; 6];
        let impulse = w.heel_strike(&mut ws, &x, &mut v);
        let vb = [v[0], v[1]];
        let xpost = [x[0], x[1], x[2], x[3], v[2], v[3], v[4], v[5]];
        let pre = pc.masses(&x, [0.0; 2]);
        let post = pc.masses(&xpost, vb);
        let contact = pc.point(&foot_t, &x, [0.0; 2]).0;
        let sf = w.swing_foot(&x);
        assert!((sf[0] - contact[0]).abs() < 1e-15 && (sf[1] - contact[1]).abs() < 1e-15);
        let scale: f64 = pre.iter().map(|(m, _, u)| m * l * u[0].hypot(u[1])).sum();
        let (h0, h1) = (ang_mom(&pre, contact), ang_mom(&post, contact));
        assert!(
            (h0 - h1).abs() < 1e-12 * scale,
            "about the contact: {h0} vs {h1}"
        );
        let hip = pc.point(&hip_t, &x, [0.0; 2]).0;
        let (t0, t1) = (ang_mom(&pre[0..2], hip), ang_mom(&post[0..2], hip));
        assert!(
            (t0 - t1).abs() < 1e-12 * scale,
            "trailing leg about the hip: {t0} vs {t1}"
        );
        // the knees stay locked and the new contact point is at rest
        assert!(
            v[3].abs() < 1e-12 * scale && v[5].abs() < 1e-12 * scale,
            "{v:?}"
        );
        let fv = pc.point(&foot_t, &xpost, vb).1;
        assert!(
            fv[0].hypot(fv[1]) < 1e-12 * scale,
            "contact velocity after impact {fv:?}"
        );
        // ΔT equals the impulse's work ½ Λ·v_c⁻
        let vc = pc.point(&foot_t, &x, [0.0; 2]).1;
        let (k0, k1) = (kinetic(&pre), kinetic(&post));
        let work = 0.5 * (impulse[0] * vc[0] + impulse[1] * vc[1]);
        assert!(
            ((k1 - k0) - work).abs() < 1e-12 * k0,
            "ΔT {} vs work {}",
            k1 - k0,
            work
        );
        // after the leg swap: the same kinetic energy (new chain, new stance foot at rest)
        let mut y = [0.0; 8];
        assert_eq!(w.reset(&mut ws, LOCKED, HEEL_STRIKE, &x, &mut y), FREE);
        assert!((kinetic(&pc.masses(&y, [0.0; 2])) - k1).abs() < 1e-12 * k0);
    }
}

/// Runs one stride from the section with DOP853 at `tol`, returning the worst relative energy
/// drift within a mode, the stop reasons and the next section state.
fn stride(w: &ChainWalker, s: &[f64], tol: f64) -> (f64, Vec<StopReason>, [f64; 3]) {
    let mut x = [0.0; 8];
    w.lift(s, &mut x);
    let mut mode = w.section_mode();
    let mut integ = Integrator::new(8, Options::dop853(tol)).unwrap();
    let mut ws = Scratch::new();
    let mut t = 0.0;
    let mut drift: f64 = 0.0;
    let mut stops = vec![];
    for _ in 0..2 {
        let e0 = w.energy(&x).unwrap();
        let stop = integ.integrate_observed(
            w as &dyn pdw_hybrid::HybridSystem,
            mode,
            &mut t,
            &mut x,
            5.0,
            &mut |_, y| {
                drift = drift.max(((w.energy(y).unwrap() - e0) / e0).abs());
            },
        );
        stops.push(stop);
        let StopReason::Guard { guard } = stop else {
            break;
        };
        let mut y = [0.0; 8];
        mode = w.reset(&mut ws, mode, guard, &x, &mut y);
        x = y;
    }
    let mut s2 = [0.0; 3];
    w.project(&x, &mut s2);
    (drift, stops, s2)
}

#[test]
fn energy_is_point_mass_energy_and_conserved_between_impacts_in_both_modes() {
    let w = kneed();
    let pc = point_chain(&HSU_CHEN);
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    for _ in 0..50 {
        let x: [f64; 8] = std::array::from_fn(|i| {
            if i < 4 {
                rng.random_range(-0.6..0.6)
            } else {
                rng.random_range(-3.0..3.0)
            }
        });
        let e = kinetic(&pc.masses(&x, [0.0; 2])) + pc.potential(&x);
        let we = w.energy(&x).unwrap();
        assert!((we - e).abs() < 1e-12 * (1.0 + e.abs()), "{we} vs {e}");
    }
    let (drift, stops, _) = stride(&w, &hsu_chen_section(HSU_CHEN.slope), 1e-13);
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
    let w = kneed();
    let published = hsu_chen_section(HSU_CHEN.slope);
    // the preset's gait guess is the published state
    let guess = &w.gait_guesses()[0].section;
    for i in 0..3 {
        assert!((guess[i] - published[i]).abs() < 1e-15, "{guess:?}");
    }
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
    let w = kneed();
    let mut x = [0.0; 8];
    w.lift(&hsu_chen_section(HSU_CHEN.slope), &mut x);
    let mut dx = [0.0; 8];
    w.flow(&mut Scratch::new(), FREE, &x, &mut dx);
    assert!(dx[7] < 0.0, "q̈₃ = {}", dx[7]);
}
