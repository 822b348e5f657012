//! Physics claims about the seed thesis' walker, each against an independent reference: a
//! merged-link model for the locked knees, the thesis' switch matrix T (eq. 3.29) on the five
//! joints, and conservation laws computed from the point masses.

use pdw_hybrid::{HybridSystem, Integrator, Options, Scratch, Section, StopReason};
use pdw_soa::{ChainBuilder, Link, Workspace};
use pdw_walkers::seed5::{
    Seed5, Seed5Params, Seed5Variant, HEEL_STRIKE, KNEES_LOCKED, KNEE_STRIKE, SWING_KNEE_FREE,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

type Pm = Vec<(f64, [f64; 2], [f64; 2])>;

/// Point masses (stance shank, stance thigh, swing thigh, swing shank) at state `x`, stance
/// foot at the origin, with an extra base velocity `vb`.
fn masses(p: &Seed5Params, x: &[f64], vb: [f64; 2]) -> Pm {
    let (ls, lt) = (p.shank_length, p.thigh_length);
    let th = [
        x[0],
        x[0] + x[1],
        x[0] + x[1] + x[2],
        x[0] + x[1] + x[2] + x[3],
    ];
    let w = [
        x[4],
        x[4] + x[5],
        x[4] + x[5] + x[6],
        x[4] + x[5] + x[6] + x[7],
    ];
    let pt = |terms: &[(f64, usize)]| {
        let mut r = [0.0; 2];
        let mut v = vb;
        for &(l, k) in terms {
            r[0] -= l * th[k].sin();
            r[1] += l * th[k].cos();
            v[0] -= l * w[k] * th[k].cos();
            v[1] -= l * w[k] * th[k].sin();
        }
        (r, v)
    };
    let list: [(f64, Vec<(f64, usize)>); 4] = [
        (p.shank_mass, vec![(0.5 * ls, 0)]),
        (p.thigh_mass, vec![(ls, 0), (0.5 * lt, 1)]),
        (p.thigh_mass, vec![(ls, 0), (lt, 1), (-0.5 * lt, 2)]),
        (
            p.shank_mass,
            vec![(ls, 0), (lt, 1), (-lt, 2), (-0.5 * ls, 3)],
        ),
    ];
    list.iter()
        .map(|(m, t)| {
            let (r, v) = pt(t);
            (*m, r, v)
        })
        .collect()
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

#[test]
fn locked_knees_equal_merged_two_link_model() {
    let p = Seed5Params::default();
    let w = Seed5::new(p).unwrap();
    let (ls, lt, ms, mt) = (p.shank_length, p.thigh_length, p.shank_mass, p.thigh_mass);
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
        .revolute(link(l, &[(ms, 0.5 * ls), (mt, ls + 0.5 * lt)]))
        .revolute(link(-l, &[(mt, -0.5 * lt), (ms, -(lt + 0.5 * ls))]))
        .build()
        .unwrap();
    let mut ws = Workspace::new(&merged);
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    for _ in 0..200 {
        let x = [
            rng.random_range(-0.6..0.6),
            0.0,
            rng.random_range(-1.2..1.2),
            0.0,
            rng.random_range(-2.0..2.0),
            0.0,
            rng.random_range(-3.0..3.0),
            0.0,
        ];
        let mut dx = [0.0; 8];
        w.flow(&mut Scratch::new(), KNEES_LOCKED, &x, &mut dx);
        let mut qdd = [0.0; 2];
        pdw_soa::aba(
            &merged,
            &mut ws,
            &[x[0], x[2]],
            &[x[4], x[6]],
            &[0.0; 2],
            None,
            &mut qdd,
        )
        .unwrap();
        let scale = 1.0 + qdd[0].abs().max(qdd[1].abs());
        assert!((dx[4] - qdd[0]).abs() < 1e-12 * scale);
        assert!((dx[6] - qdd[1]).abs() < 1e-12 * scale);
        assert_eq!((dx[5], dx[7]), (0.0, 0.0));
    }
}

#[test]
fn switch_rule_is_the_thesis_t_on_five_joints() {
    // seed eq. 3.29: θ' = T θ with T the reversed, negated identity on (q₁…q₅), where q₅ is the
    // closing angle of the swing foot on the ground.
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
        Seed5::switch_rule(&q, &qd, &mut out);
        for i in 0..4 {
            assert!((out[i] - tq[i]).abs() < 1e-15);
            assert!((out[4 + i] - tqd[i]).abs() < 1e-14);
        }
    }
}

#[test]
fn heel_strike_conserves_angular_momenta_and_loses_the_predicted_energy() {
    let p = Seed5Params::default();
    let w = Seed5::new(p).unwrap();
    let l = w.leg_length();
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
        let hs = w.heel_strike(&x, &mut v);
        let pre = masses(&p, &x, [0.0, 0.0]);
        let post = masses(
            &p,
            &[x[0], x[1], x[2], x[3], v[2], v[3], v[4], v[5]],
            [v[0], v[1]],
        );
        let contact = w.swing_foot(&x);
        let scale: f64 = pre.iter().map(|(m, _, u)| m * l * u[0].hypot(u[1])).sum();
        let (h0, h1) = (ang_mom(&pre, contact), ang_mom(&post, contact));
        assert!(
            (h0 - h1).abs() < 1e-12 * scale,
            "about the contact: {h0} vs {h1}"
        );
        let hip = [-l * x[0].sin(), l * x[0].cos()];
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
        let ts = x[0] + x[2];
        let ws = x[4] + x[6];
        let sh = pre[3].2;
        let vc = [
            sh[0] + 0.5 * p.shank_length * ws * ts.cos(),
            sh[1] + 0.5 * p.shank_length * ws * ts.sin(),
        ];
        let (k0, k1) = (kinetic(&pre), kinetic(&post));
        let work = 0.5 * (hs.impulse[0] * vc[0] + hs.impulse[1] * vc[1]);
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
    let p = Seed5Params {
        variant: Seed5Variant::FreeSwingKnee,
        ..Seed5Params::default()
    };
    let w = Seed5::new(p).unwrap();
    let l = w.leg_length();
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
        assert_eq!(
            w.reset(
                &mut Scratch::new(),
                SWING_KNEE_FREE,
                KNEE_STRIKE,
                &x,
                &mut y
            ),
            KNEES_LOCKED
        );
        let (pre, post) = (masses(&p, &x, [0.0; 2]), masses(&p, &y, [0.0; 2]));
        let scale: f64 = pre.iter().map(|(m, _, u)| m * l * u[0].hypot(u[1])).sum();
        let (h0, h1) = (ang_mom(&pre, [0.0, 0.0]), ang_mom(&post, [0.0, 0.0]));
        assert!(
            (h0 - h1).abs() < 1e-12 * scale,
            "about the stance foot: {h0} vs {h1}"
        );
        let hip = [-l * x[0].sin(), l * x[0].cos()];
        let (s0, s1) = (ang_mom(&pre[2..], hip), ang_mom(&post[2..], hip));
        assert!(
            (s0 - s1).abs() < 1e-12 * scale,
            "swing leg about the hip: {s0} vs {s1}"
        );
        let mut v = [0.0; 4];
        w.knee_strike(&x, &mut v);
        assert!(v[1].abs() < 1e-12 && v[3].abs() < 1e-12);
        assert!(kinetic(&post) <= kinetic(&pre));
    }
}

fn energy_drift(w: &Seed5, mode: usize, x0: [f64; 8]) -> (f64, StopReason, f64) {
    let mut x = x0;
    let e0 = w.energy(&x);
    let mut integ = Integrator::new(8, Options::dop853(1e-13)).unwrap();
    let mut t = 0.0;
    let mut drift: f64 = 0.0;
    let stop = integ.integrate_observed(w, mode, &mut t, &mut x, 3.0, &mut |_, y| {
        drift = drift.max(((w.energy(y) - e0) / e0).abs());
    });
    (drift, stop, t)
}

#[test]
fn energy_conserved_between_impacts_in_both_modes() {
    for variant in [Seed5Variant::LockedKnees, Seed5Variant::FreeSwingKnee] {
        let w = Seed5::new(Seed5Params {
            variant,
            ..Seed5Params::default()
        })
        .unwrap();
        let mut x = [0.0; 8];
        w.lift(&[0.25, -0.7, 0.8], &mut x);
        let mode = w.section_mode();
        let (drift, stop, t) = energy_drift(&w, mode, x);
        assert!(t > 0.2, "{variant:?}: stopped early ({stop:?} at {t})");
        assert!(
            drift < 1e-10,
            "{variant:?}: relative energy drift {drift:e} ({stop:?})"
        );
    }
}

#[test]
fn heel_strike_needs_the_foot_ahead_and_the_symmetric_factor() {
    let w = Seed5::new(Seed5Params::default()).unwrap();
    for q1 in [-0.3, 0.0, 0.2] {
        let x = [q1, 0.0, 1e-14, 0.0, -1.0, 0.0, 1.0, 0.0];
        assert!(!w.admissible(KNEES_LOCKED, HEEL_STRIKE, &x));
    }
    let x = [-0.2, 0.0, 0.4, 0.0, -1.0, 0.0, 1.0, 0.0];
    assert!(w.admissible(KNEES_LOCKED, HEEL_STRIKE, &x));
    assert!(w.swing_foot(&x)[1].abs() < 1e-14);
}

#[test]
fn stance_knee_lock_pushes_when_the_upper_body_leans_forward() {
    // Static, level ground, vertical stance leg. With the swing leg forward (downhill) the
    // upper body's centre of mass is ahead of the stance knee and tends to hyper-extend it: the
    // stop pushes (torque ≥ 0 towards flexion). With the swing leg behind, the knee tends to
    // flex and a stop cannot hold it (negative torque: the knee would unlock).
    let w = Seed5::new(Seed5Params {
        slope: 0.0,
        ..Seed5Params::default()
    })
    .unwrap();
    let fwd = [0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0];
    let back = [0.0, 0.0, -0.5, 0.0, 0.0, 0.0, 0.0, 0.0];
    let tf = w.constraint_forces(KNEES_LOCKED, &fwd).knee_torque[0].unwrap();
    let tb = w.constraint_forces(KNEES_LOCKED, &back).knee_torque[0].unwrap();
    assert!(tf > 0.0 && tb < 0.0, "forward {tf}, backward {tb}");
    assert!(w.check_state(KNEES_LOCKED, &back).knee_unlocks);
    // at rest the ground carries the weight
    let cf = w.constraint_forces(KNEES_LOCKED, &fwd);
    let p = w.params();
    let weight = 2.0 * (p.shank_mass + p.thigh_mass) * p.gravity;
    assert!(cf.normal > 0.0 && cf.normal < weight);
}
