//! Physics claims about the seed thesis' walker (the `seed5` preset of the chain walker,
//! `models/seed5.toml`), each against an independent reference: the point-mass equations of
//! motion written in the test (d'Alembert, `common::PointChain`) for locked knees and for a free
//! swing knee, the thesis' switch matrix T (eq. 3.29) on the five joints, and conservation laws
//! computed from the point masses.
//!
//! State `(q₀, q₁, q₂, q₃, q̇₀ … q̇₃)`: stance leg, stance knee, hip, swing knee. With
//! `free_swing_knee = 0` (the thesis' walker) one mode, 0, every knee locked; with
//! `free_swing_knee = 1` mode 0 has the swing knee free and mode 1 every knee locked.

use crate::common;

use common::{ang_mom, check_flow_against_point_masses, kinetic, param, PointChain};
use pdw_hybrid::{HybridSystem, Integrator, Options, Scratch, Section, StopReason};
use pdw_walkers::chain_walker::{FREE, LOCKED};
use pdw_walkers::{presets, ChainWalker, Walker};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Guard of the heel strike (the locked mode) and of the knee strike (the free mode).
const HEEL_STRIKE: usize = 0;
const KNEE_STRIKE: usize = 0;

/// The thesis' Table 3.1 (shanks 2 kg, thighs 3 kg, segments 2 m, mid-segment point masses,
/// no hip mass, g = 9.81) and the preset's slope 0.05, held by the test.
struct Sp {
    shank_mass: f64,
    thigh_mass: f64,
    shank_length: f64,
    thigh_length: f64,
    gravity: f64,
    slope: f64,
}

const TABLE_3_1: Sp = Sp {
    shank_mass: 2.0,
    thigh_mass: 3.0,
    shank_length: 2.0,
    thigh_length: 2.0,
    gravity: 9.81,
    slope: 0.05,
};

/// The preset (`free_swing_knee` 0 or 1), checked to be at the thesis' parameters.
fn seed5(free_swing_knee: bool) -> ChainWalker {
    let w = presets::seed5(&[("free_swing_knee", f64::from(u8::from(free_swing_knee)))]).unwrap();
    let v = w.param_values();
    let p = TABLE_3_1;
    for (name, value) in [
        ("shank_mass", p.shank_mass),
        ("thigh_mass", p.thigh_mass),
        ("shank_length", p.shank_length),
        ("thigh_length", p.thigh_length),
        ("gravity", p.gravity),
        ("slope", p.slope),
        ("hip_mass", 0.0),
    ] {
        assert_eq!(param(&v, name), value, "{name}");
    }
    if free_swing_knee {
        assert_eq!(
            (w.n_modes(), w.free_knee(), w.locked_mode()),
            (2, Some(3), 1)
        );
    } else {
        assert_eq!((w.n_modes(), w.free_knee(), w.locked_mode()), (1, None, 0));
        assert_eq!(w.locked_joints(0), &[1, 3]);
    }
    w
}

/// Point masses: stance shank, stance thigh, swing thigh, swing shank.
fn point_chain(p: &Sp) -> PointChain {
    let (ls, lt) = (p.shank_length, p.thigh_length);
    PointChain {
        n: 4,
        masses: vec![
            (p.shank_mass, vec![(0.5 * ls, 0)]),
            (p.thigh_mass, vec![(ls, 0), (0.5 * lt, 1)]),
            (p.thigh_mass, vec![(ls, 0), (lt, 1), (-0.5 * lt, 2)]),
            (
                p.shank_mass,
                vec![(ls, 0), (lt, 1), (-lt, 2), (-0.5 * ls, 3)],
            ),
        ],
        gravity: p.gravity,
        slope: p.slope,
    }
}

/// Hip, swing knee and swing foot (terms of [`PointChain::point`]).
fn hip_knee_foot(p: &Sp) -> [Vec<(f64, usize)>; 3] {
    let (ls, lt) = (p.shank_length, p.thigh_length);
    [
        vec![(ls, 0), (lt, 1)],
        vec![(ls, 0), (lt, 1), (-lt, 2)],
        vec![(ls, 0), (lt, 1), (-lt, 2), (-ls, 3)],
    ]
}

#[test]
fn locked_knees_equal_point_mass_rigid_legs() {
    check_flow_against_point_masses(
        &seed5(false),
        &point_chain(&TABLE_3_1),
        0,
        &[0, 2],
        21,
        [2.0, 3.0, 4.0],
    );
    check_flow_against_point_masses(
        &seed5(true),
        &point_chain(&TABLE_3_1),
        LOCKED,
        &[0, 2],
        25,
        [2.0, 3.0, 4.0],
    );
}

#[test]
fn free_swing_knee_equals_point_mass_three_link_swing() {
    check_flow_against_point_masses(
        &seed5(true),
        &point_chain(&TABLE_3_1),
        FREE,
        &[0, 2, 3],
        26,
        [2.0, 3.0, 4.0],
    );
}

#[test]
fn switch_rule_is_the_thesis_t_on_five_joints() {
    // seed eq. 3.29: θ' = T θ with T the reversed, negated identity on (q₁…q₅), where q₅ is the
    // closing angle of the swing foot on the ground.
    let w = seed5(false);
    let mut rng = ChaCha8Rng::seed_from_u64(22);
    for _ in 0..20 {
        let q: [f64; 4] = std::array::from_fn(|_| rng.random_range(-0.5..0.5));
        let qd: [f64; 4] = std::array::from_fn(|_| rng.random_range(-2.0..2.0));
        let q5 = -(q[0] + q[1] + q[2] + q[3]);
        let qd5 = -(qd[0] + qd[1] + qd[2] + qd[3]);
        let full = [q[0], q[1], q[2], q[3], q5];
        let fulld = [qd[0], qd[1], qd[2], qd[3], qd5];
        let t = |v: [f64; 5]| -> [f64; 5] { std::array::from_fn(|i| -v[4 - i]) };
        let (tq, tqd) = (t(full), t(fulld));
        let mut out = [0.0; 8];
        w.swap(&q, &qd, &mut out);
        for i in 0..4 {
            assert!((out[i] - tq[i]).abs() < 1e-15);
            assert!((out[4 + i] - tqd[i]).abs() < 1e-14);
        }
    }
}

#[test]
fn heel_strike_conserves_angular_momenta_and_loses_the_predicted_energy() {
    let p = TABLE_3_1;
    let w = seed5(false);
    let pc = point_chain(&p);
    let [hip_t, _, foot_t] = hip_knee_foot(&p);
    let l = w.leg_length();
    assert_eq!(w.section_guard(), (0, HEEL_STRIKE));
    let mut ws = Scratch::new();
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    for _ in 0..100 {
        let a: f64 = rng.random_range(0.05..0.5);
        let x = [
            -a,
            0.0,
            2.0 * a,
            0.0,
            rng.random_range(-1.5..-0.1),
            0.0,
            rng.random_range(-2.0..2.0),
            0.0,
        ];
        let mut v = [0.0; 6];
        let impulse = w.heel_strike(&mut ws, &x, &mut v);
        let vb = [v[0], v[1]];
        let xpost = [x[0], x[1], x[2], x[3], v[2], v[3], v[4], v[5]];
        let pre = pc.masses(&x, [0.0, 0.0]);
        let post = pc.masses(&xpost, vb);
        let contact = pc.point(&foot_t, &x, [0.0; 2]).0;
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
        assert!(
            v[3].abs() < 1e-12 && v[5].abs() < 1e-12,
            "knees must stay locked: {v:?}"
        );
        // contact velocity before the impact, and the impulse's work
        let vc = pc.point(&foot_t, &x, [0.0; 2]).1;
        let (k0, k1) = (kinetic(&pre), kinetic(&post));
        let work = 0.5 * (impulse[0] * vc[0] + impulse[1] * vc[1]);
        assert!(
            ((k1 - k0) - work).abs() < 1e-12 * k0,
            "ΔT {} vs {}",
            k1 - k0,
            work
        );
    }
}

#[test]
fn knee_strike_conserves_angular_momenta_and_keeps_the_stance_knee_locked() {
    let p = TABLE_3_1;
    let w = seed5(true);
    let pc = point_chain(&p);
    let [hip_t, knee_t, _] = hip_knee_foot(&p);
    let l = w.leg_length();
    let mut ws = Scratch::new();
    let mut rng = ChaCha8Rng::seed_from_u64(24);
    for _ in 0..100 {
        let x = [
            rng.random_range(-0.3..0.3),
            0.0,
            rng.random_range(-0.2..0.6),
            0.0,
            rng.random_range(-1.5..-0.1),
            0.0,
            rng.random_range(-1.0..2.0),
            rng.random_range(0.1..4.0),
        ];
        let mut y = [0.0; 8];
        assert_eq!(w.reset(&mut ws, FREE, KNEE_STRIKE, &x, &mut y), LOCKED);
        assert_eq!([y[1], y[3], y[5], y[7]], [0.0; 4]);
        let (pre, post) = (pc.masses(&x, [0.0; 2]), pc.masses(&y, [0.0; 2]));
        let scale: f64 = pre.iter().map(|(m, _, u)| m * l * u[0].hypot(u[1])).sum();
        let (h0, h1) = (ang_mom(&pre, [0.0, 0.0]), ang_mom(&post, [0.0, 0.0]));
        assert!(
            (h0 - h1).abs() < 1e-12 * scale,
            "about the stance foot: {h0} vs {h1}"
        );
        let hip = pc.point(&hip_t, &x, [0.0; 2]).0;
        let (s0, s1) = (ang_mom(&pre[2..], hip), ang_mom(&post[2..], hip));
        assert!(
            (s0 - s1).abs() < 1e-12 * scale,
            "swing leg about the hip: {s0} vs {s1}"
        );
        // the locking impulse (a torque impulse on the shank) is the shank's change of angular
        // momentum about the knee; its work is ½ Λ (q̇₃⁻ + q̇₃⁺) = ½ Λ q̇₃⁻
        let knee = pc.point(&knee_t, &x, [0.0; 2]).0;
        let lam = ang_mom(&post[3..], knee) - ang_mom(&pre[3..], knee);
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

fn energy_drift(w: &ChainWalker, mode: usize, x0: [f64; 8]) -> (f64, StopReason, f64) {
    let mut x = x0;
    let e0 = w.energy(&x).unwrap();
    let mut integ = Integrator::new(8, Options::dop853(1e-13)).unwrap();
    let mut t = 0.0;
    let mut drift: f64 = 0.0;
    let stop = integ.integrate_observed(
        w as &dyn pdw_hybrid::HybridSystem,
        mode,
        &mut t,
        &mut x,
        3.0,
        &mut |_, y| {
            drift = drift.max(((w.energy(y).unwrap() - e0) / e0).abs());
        },
    );
    (drift, stop, t)
}

#[test]
fn energy_is_point_mass_energy_and_conserved_between_impacts_in_both_modes() {
    let pc = point_chain(&TABLE_3_1);
    let mut rng = ChaCha8Rng::seed_from_u64(27);
    for free in [false, true] {
        let w = seed5(free);
        for _ in 0..20 {
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
        let mut x = [0.0; 8];
        w.lift(&[0.25, -0.7, 0.8], &mut x);
        let mode = w.section_mode();
        let (drift, stop, t) = energy_drift(&w, mode, x);
        assert!(
            t > 0.2,
            "free swing knee {free}: stopped early ({stop:?} at {t})"
        );
        assert!(
            drift < 1e-10,
            "free swing knee {free}: relative energy drift {drift:e} ({stop:?})"
        );
    }
}

#[test]
fn heel_strike_needs_the_foot_ahead_and_the_symmetric_factor() {
    let w = seed5(false);
    for q1 in [-0.3, 0.0, 0.2] {
        let x = [q1, 0.0, 1e-14, 0.0, -1.0, 0.0, 1.0, 0.0];
        assert!(!w.admissible(0, HEEL_STRIKE, &x));
    }
    let x = [-0.2, 0.0, 0.4, 0.0, -1.0, 0.0, 1.0, 0.0];
    assert!(w.admissible(0, HEEL_STRIKE, &x));
    assert!(w.swing_foot(&x)[1].abs() < 1e-14);
}

#[test]
fn stance_knee_lock_pushes_when_the_upper_body_leans_forward() {
    // Static, level ground, vertical stance leg. With the swing leg forward (downhill) the
    // upper body's centre of mass is ahead of the stance knee and tends to hyper-extend it: the
    // stop pushes (torque ≥ 0 towards flexion). With the swing leg behind, the knee tends to
    // flex and a stop cannot hold it (negative torque: the knee would unlock).
    let w = presets::seed5(&[("slope", 0.0)]).unwrap();
    let mut ws = Scratch::new();
    let fwd = [0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0];
    let back = [0.0, 0.0, -0.5, 0.0, 0.0, 0.0, 0.0, 0.0];
    let tf = w.constraint_forces_ws(&mut ws, 0, &fwd).knee_torque[0].unwrap();
    let tb = w.constraint_forces_ws(&mut ws, 0, &back).knee_torque[0].unwrap();
    assert!(tf > 0.0 && tb < 0.0, "forward {tf}, backward {tb}");
    assert!(w.check_state_ws(&mut ws, 0, &back).knee_unlocks);
    // at rest the ground carries the weight
    let cf = w.constraint_forces_ws(&mut ws, 0, &fwd);
    let p = TABLE_3_1;
    let weight = 2.0 * (p.shank_mass + p.thigh_mass) * p.gravity;
    assert!(cf.normal > 0.0 && cf.normal < weight);
}
