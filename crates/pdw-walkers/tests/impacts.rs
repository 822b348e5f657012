//! Impacts of the chain walkers from one set of impulse equations consistent with the contact
//! model: momentum conservation through the knee strike and the heel strike (about the contact
//! point for the whole walker, about the hip for the leg that no external impulse reaches), for
//! point and round feet; energy never gained; `r → 0` tends to the point-foot impact; the
//! unilateral stops: the seed5_walking design's stance knee buckles at its knee strike (the
//! independent model's number: a hold would need −0.063 N m s).

use crate::chain_common::{all_presets, random_state};
use pdw_hybrid::{FallKind, HybridSystem, Integrator, Options, Scratch, Section, StopReason};
use pdw_soa::{angular_momentum_about, crba, Workspace};
use pdw_walkers::chain_walker::{FREE, LOCKED};
use pdw_walkers::{ChainWalker, ImpulseKind, Walker, WalkerSpec};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn seed5_walking() -> ChainWalker {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/seed5_walking.toml"
    ))
    .expect("models/seed5_walking.toml");
    ChainWalker::from_spec(WalkerSpec::from_toml(&text, "seed5_walking.toml").unwrap()).unwrap()
}

fn with_radius(w: &ChainWalker, r: f64) -> ChainWalker {
    let mut spec = w.spec().clone();
    spec.foot_radius = pdw_walkers::spec::Num::Value(r);
    let values: Vec<f64> = w.param_values().into_iter().map(|p| p.1).collect();
    ChainWalker::new(spec, &values).unwrap()
}

/// Walkers with a free swing knee: the kneed preset, seed5 with its free knee, seed5_walking,
/// each with point feet and two radii.
fn kneed_walkers() -> Vec<(String, ChainWalker)> {
    let mut v = Vec::new();
    for (name, w) in all_presets()
        .into_iter()
        .filter(|(_, w)| w.free_knee().is_some())
        .map(|(n, w)| (n.to_string(), w))
        .chain([("seed5_walking".to_string(), seed5_walking())])
    {
        for r in [0.0, 0.05, 0.2] {
            v.push((format!("{name} r={r}"), with_radius(&w, r)));
        }
    }
    v
}

/// Floating-chain coordinates `(y, z, q)` and rates `(−r q̇₀, 0, q̇)` of a state.
fn floating(w: &ChainWalker, x: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = w.dim() / 2;
    let mut q = vec![0.0; n + 2];
    let mut qd = vec![0.0; n + 2];
    q[2..].copy_from_slice(&x[..n]);
    qd[2..].copy_from_slice(&x[n..]);
    qd[0] = -w.foot_radius() * x[n];
    (q, qd)
}

/// `𝓜_F (q̇⁺ − q̇⁻)`: the generalized impulse on each floating-chain coordinate.
fn generalized_impulse(w: &ChainWalker, q: &[f64], qd0: &[f64], qd1: &[f64]) -> Vec<f64> {
    let ch = w.floating_chain();
    let nf = ch.dof();
    let mut ws = Workspace::new(ch);
    let mm = crba(ch, &mut ws, q).unwrap();
    (0..nf)
        .map(|i| (0..nf).map(|k| mm[(i, k)] * (qd1[k] - qd0[k])).sum())
        .collect()
}

#[test]
fn knee_strike_conserves_momentum_about_the_contact_point_and_the_swing_legs_about_the_hip() {
    let mut rng = ChaCha8Rng::seed_from_u64(31);
    for (name, w) in kneed_walkers() {
        let n = w.dim() / 2;
        let m = w.segments();
        let r = w.foot_radius();
        let ch = w.floating_chain();
        let mut ws = Workspace::new(ch);
        for _ in 0..20 {
            let mut x = random_state(&w, &mut rng, FREE);
            let k = w.free_knee().unwrap();
            x[k] = 0.0;
            // the knee straightening into its stop (a swing knee flexes with q < 0)
            x[n + k] = x[n + k].abs() + 0.5;
            let mut y = vec![0.0; 2 * n];
            let mode = w.reset(&mut Scratch::new(), FREE, 0, &x, &mut y);
            assert_eq!(mode, LOCKED);
            let (q, qd0) = floating(&w, &x);
            let (_, qd1) = floating(&w, &y);
            // the whole walker about the contact point, r below the stance arc centre
            let h0 = angular_momentum_about(ch, &mut ws, &q, &qd0, [0.0, -r]).unwrap();
            let h1 = angular_momentum_about(ch, &mut ws, &q, &qd1, [0.0, -r]).unwrap();
            assert!(
                (h1 - h0).abs() < 1e-12 * (1.0 + h0.abs()),
                "{name}: H about the contact point {h0} -> {h1}"
            );
            // the swing leg (the subtree beyond the hip) about the hip: only the stop's
            // internal impulse and the hip force act on it
            let p = generalized_impulse(&w, &q, &qd0, &qd1);
            let scale = p.iter().fold(1.0f64, |s, v| s.max(v.abs()));
            assert!(
                p[2 + m].abs() < 1e-12 * scale,
                "{name}: swing leg's H about the hip changes by {}",
                p[2 + m]
            );
            // no energy gained
            let (e0, e1) = (w.energy(&x).unwrap(), w.energy(&y).unwrap());
            assert!(e1 <= e0 + 1e-12 * e0.abs(), "{name}: energy {e0} -> {e1}");
        }
    }
}

#[test]
fn heel_strike_conserves_momentum_about_the_new_contact_and_the_trailing_legs_about_the_hip() {
    let mut rng = ChaCha8Rng::seed_from_u64(32);
    let walkers: Vec<(String, ChainWalker)> = all_presets()
        .into_iter()
        .map(|(n, w)| (n.to_string(), w))
        .chain(kneed_walkers())
        .collect();
    for (name, w) in walkers {
        let n = w.dim() / 2;
        let m = w.segments();
        let r = w.foot_radius();
        let ch = w.floating_chain();
        let mut ws = Workspace::new(ch);
        let lm = w.locked_mode();
        for _ in 0..20 {
            let x = random_state(&w, &mut rng, lm);
            let pose = w.pose(&x).unwrap();
            // pose: drawn from the stance contact point; the floating chain's base is the
            // stance arc centre, r above it
            let foot = pose.swing_foot.unwrap();
            let contact = [foot[0], foot[1] - r];
            let hip = [pose.joints[m - 1][0], pose.joints[m - 1][1] - r];
            let mut v = vec![0.0; n + 2];
            let imp = w.heel_strike(&mut Scratch::new(), &x, &mut v);
            assert!(imp.iter().all(|v| v.is_finite()), "{name}");
            let (q, qd0) = floating(&w, &x);
            let h0 = angular_momentum_about(ch, &mut ws, &q, &qd0, contact).unwrap();
            let h1 = angular_momentum_about(ch, &mut ws, &q, &v, contact).unwrap();
            assert!(
                (h1 - h0).abs() < 1e-12 * (1.0 + h0.abs()),
                "{name}: H about the new contact {h0} -> {h1}"
            );
            // trailing leg about the hip: total H about the hip minus the swing subtree's
            // (the generalized impulse on the hip joint)
            let g0 = angular_momentum_about(ch, &mut ws, &q, &qd0, hip).unwrap();
            let g1 = angular_momentum_about(ch, &mut ws, &q, &v, hip).unwrap();
            let p = generalized_impulse(&w, &q, &qd0, &v);
            let scale = 1.0 + g0.abs() + p[2 + m].abs();
            assert!(
                ((g1 - g0) - p[2 + m]).abs() < 1e-12 * scale,
                "{name}: trailing leg's H about the hip changes by {}",
                (g1 - g0) - p[2 + m]
            );
        }
    }
}

#[test]
fn a_vanishing_foot_radius_tends_to_the_point_foot_knee_strike() {
    let mut rng = ChaCha8Rng::seed_from_u64(33);
    for (name, w0) in all_presets()
        .into_iter()
        .filter(|(_, w)| w.free_knee().is_some())
    {
        let n = w0.dim() / 2;
        for _ in 0..10 {
            let mut x = random_state(&w0, &mut rng, FREE);
            let k = w0.free_knee().unwrap();
            x[k] = 0.0;
            x[n + k] = x[n + k].abs() + 0.5;
            let mut y0 = vec![0.0; 2 * n];
            w0.reset(&mut Scratch::new(), FREE, 0, &x, &mut y0);
            let mut last = f64::INFINITY;
            for r in [1e-3, 1e-5, 1e-7] {
                let w = with_radius(&w0, r);
                let mut y = vec![0.0; 2 * n];
                w.reset(&mut Scratch::new(), FREE, 0, &x, &mut y);
                let d = y
                    .iter()
                    .zip(&y0)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                assert!(d < 50.0 * r, "{name}: r = {r}: differs by {d}");
                assert!(d < last, "{name}: no convergence as r → 0");
                last = d;
            }
        }
    }
}

/// Integrates from `x` in `mode` until the next stop, returning it.
fn run_to_event(w: &ChainWalker, mode: usize, x: &mut [f64]) -> StopReason {
    let mut integ = Integrator::new(w.dim(), Options::dop853(1e-12)).unwrap();
    let mut t = 0.0;
    integ.integrate(w as &dyn pdw_hybrid::HybridSystem, mode, &mut t, x, 10.0)
}

/// The design that was reported "stable and valid along the whole stride" needs its stance
/// knee's stop to pull at the knee strike (an independent Lagrangian model: −0.063 N m s):
/// with stops that only push, the stance knee buckles there.
#[test]
fn seed5_walkings_old_design_buckles_its_stance_knee_at_the_knee_strike() {
    let w = seed5_walking();
    let mut x = vec![0.0; w.dim()];
    // its section carries the swing knee's rate (stop knees): 0, the old gait's
    w.lift(&[0.25436, -0.51543, 0.32274, 0.0], &mut x);
    let stop = run_to_event(&w, FREE, &mut x);
    let StopReason::Guard { guard } = stop else {
        panic!("no event: {stop:?}")
    };
    let spec = w.guards(FREE)[guard];
    assert_eq!(spec.name, "knee_strike_buckles");
    assert_eq!(
        spec.kind,
        pdw_hybrid::GuardKind::Terminal(FallKind::KneeBuckled)
    );
    assert!(w.stance_knee_buckles(FREE, &x));
    let rep = w.impact_report(FREE, 0, &x).expect("report");
    assert_eq!(rep.event, "knee_strike");
    let knee = rep.entry("stance_knee").expect("stance knee entry");
    assert_eq!(knee.kind, ImpulseKind::KneeStop);
    assert!(
        (knee.impulse - (-0.063)).abs() < 0.0015,
        "held stance knee impulse {} N m s (independent model: −0.063)",
        knee.impulse
    );
    assert!(knee.margin().unwrap() < 0.0);
    let striking = rep.entry("striking_knee").unwrap();
    assert!(striking.impulse > 0.0, "the striking knee's stop pushes");
    assert!(rep.energy_lost > 0.0);
}

/// The compass gait's heel strike: the new contact pushes, the trailing foot leaves.
#[test]
fn compass_heel_strike_report_is_consistent() {
    let (_, w) = all_presets().into_iter().next().unwrap();
    let mut x = vec![0.0; w.dim()];
    w.lift(&w.gait_guesses()[0].section, &mut x);
    let stop = run_to_event(&w, w.section_mode(), &mut x);
    let StopReason::Guard { guard } = stop else {
        panic!("{stop:?}")
    };
    assert_eq!(w.guards(w.section_mode())[guard].name, "heel_strike");
    let rep = w.impact_report(w.section_mode(), guard, &x).unwrap();
    let n = rep
        .entries
        .iter()
        .find(|e| e.name == "new_stance_foot" && e.kind == ImpulseKind::ContactNormal)
        .unwrap();
    assert!(n.impulse > 0.0 && n.active);
    let t = rep
        .entries
        .iter()
        .find(|e| e.name == "trailing_foot" && e.kind == ImpulseKind::ContactNormal)
        .unwrap();
    assert!(!t.active && t.rate_after > 0.0, "{t:?}");
    assert!(rep.min_margin().unwrap().0 > 0.0);
    assert!(rep.friction_required.is_finite() && rep.friction_required < 1.0);
}

/// The mode change at heel strike (chain walker docs, "Impacts"): a trailing free knee held by
/// a stop that would have to pull is released. At random pre-impact states of seed5_walking
/// (stop knees) with point and round feet: the model releases exactly where the held impulse is
/// negative; the released knee leaves flexing and every other knee straight and still (the
/// momenta of the released impact are checked against the independent model in
/// tests/tests/round_foot_kneed_reference.rs); the section carries the knee's rate
/// (`swing_knee_rate`, lift and project inverse); the reset's exact Jacobian matches Richardson
/// differences on both sides of the switch.
#[test]
fn a_trailing_knee_whose_stop_would_pull_is_released_at_heel_strike() {
    let mut rng = ChaCha8Rng::seed_from_u64(34);
    for r in [0.0, 0.05] {
        let w = with_radius(&seed5_walking(), r);
        assert_eq!(
            w.section_names(),
            &["stance", "stance_rate", "hip_rate", "swing_knee_rate"]
        );
        let (n, m, d) = (w.dim() / 2, w.segments(), w.dim());
        let fk = w.free_knee().unwrap();
        let mut sc = Scratch::new();
        let (mut released, mut held) = (0, 0);
        for _ in 0..30 {
            // stance and hip rates over a wide range: both signs of the held impulse
            let mut x = random_state(&w, &mut rng, LOCKED);
            x[n] = rng.random_range(-2.0..2.0);
            x[n + m] = rng.random_range(-2.0..2.0);
            let rep = w.impact_report_at(LOCKED, &x).unwrap();
            let trailing = rep
                .entries
                .iter()
                .find(|e| e.name == "trailing_knee")
                .unwrap();
            let mut out = vec![0.0; d];
            w.reset(&mut sc, LOCKED, 0, &x, &mut out);
            let rel = w.trailing_knee_releases_at(&x);
            assert_eq!(rel, !trailing.active, "r={r}: report and map agree");
            if !rel {
                held += 1;
                assert!(trailing.impulse >= 0.0, "r={r}: a held stop pushes");
                assert_eq!(out[n + fk], 0.0, "r={r}: a held knee leaves still");
                continue;
            }
            released += 1;
            assert!(
                trailing.rate_after > 0.0 && out[n + fk] < 0.0,
                "r={r}: the released knee flexes (stop rate {}, swing knee rate {})",
                trailing.rate_after,
                out[n + fk]
            );
            for k in (1..m).chain(m + 1..n).filter(|k| *k != fk) {
                assert_eq!(out[k], 0.0);
                assert_eq!(out[n + k], 0.0, "r={r}: held knee {k} still");
            }
            // the section carries the knee's rate
            let mut s = vec![0.0; 4];
            w.project(&out, &mut s);
            assert_eq!(s[3], out[n + fk]);
            let mut x2 = vec![0.0; d];
            w.lift(&s, &mut x2);
            assert_eq!(
                x2[n + fk],
                out[n + fk],
                "r={r}: lift puts the knee's rate back"
            );
        }
        for x in [
            random_state(&w, &mut rng, LOCKED),
            random_state(&w, &mut rng, LOCKED),
        ] {
            let mut jr = vec![0.0; d * d];
            let mut ws2 = Scratch::new();
            w.reset_jacobian(&mut sc, LOCKED, 0, &x, &mut jr);
            let fd = crate::chain_walker::richardson(
                &mut |x, out| {
                    w.reset(&mut ws2, LOCKED, 0, x, out);
                },
                &x,
                d,
            );
            crate::chain_walker::assert_close(&jr, &fd, 1e-8, &format!("r={r} reset jacobian"));
        }
        eprintln!("seed5_walking r={r}: {released} of 30 heel strikes release the trailing knee");
        assert!(
            released > 0 && held > 0,
            "r={r}: both maps exercised ({released} released, {held} held)"
        );
    }
}
