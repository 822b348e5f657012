//! The chain-walker presets (compass, kneed, seed5 as spec files on the batched kernel):
//! their gaits equal those of the hand-written models they replace, and their exact
//! (dual-number) multipliers agree with Richardson-extrapolated finite differences of the stride
//! map.

use pdw_hybrid::{HybridSystem, Options, Section};
use pdw_limit::{
    dp_variational, find_fixed_point, multipliers, FixedPoint, NewtonOptions, StrideMap,
};
use pdw_walkers::Walker;

/// Fixed points `(model, overrides, gait, section, period)` of the hand-written compass, kneed
/// and seed5 models that the chain walker replaced (DOP853 at 1e-14, Newton to 1e-12), printed
/// to 17 digits before the rewrite.
#[allow(clippy::type_complexity)]
const BEFORE: [(&str, &[(&str, f64)], &str, [f64; 3], f64); 6] = [
    (
        "compass",
        &[],
        "stable",
        [0.2710286804988225, -1.0923835898836058, 0.715009640976422],
        0.7343463911587212,
    ),
    (
        "compass",
        &[("slope", 0.0525)],
        "stable",
        [0.27127461798032326, -1.0928668105801012, 0.716732217049337],
        0.7344606213364417,
    ),
    (
        "compass",
        &[("hip_mass", 10.0), ("slope", 0.04)],
        "stable",
        [0.24739851859806916, -1.0406442918670915, 0.5596112441531499],
        0.7240476232535575,
    ),
    (
        "kneed",
        &[],
        "stable",
        [0.23858546025339888, -1.1090216480752053, 1.0519026766396014],
        0.5646160150365004,
    ),
    (
        "seed5",
        &[],
        "stable",
        [0.21512464990665398, -0.5707873106365762, 0.2775831306796213],
        1.3949431429016155,
    ),
    (
        "seed5",
        &[],
        "unstable",
        [
            0.20561869640616331,
            -0.6461814709238121,
            0.12349761193964497,
        ],
        1.1499561821926563,
    ),
];

fn fixed_point(w: &dyn Walker, guess: &[f64]) -> FixedPoint {
    let map = StrideMap::new(w, Options::dop853(1e-14)).unwrap();
    let opts = NewtonOptions {
        tol: 1e-12,
        ..NewtonOptions::default()
    };
    find_fixed_point(&map, guess, &opts).unwrap()
}

#[test]
fn presets_reproduce_the_hand_written_models_gaits_to_1e_11() {
    for (name, ov, gait, section, period) in BEFORE {
        let w = pdw_walkers::build(name, ov).unwrap();
        let g = w
            .gait_guesses()
            .into_iter()
            .find(|g| g.gait == gait)
            .unwrap();
        let fp = fixed_point(w.as_ref(), &g.section);
        for (i, (a, b)) in fp.section.iter().zip(&section).enumerate() {
            let e = (a - b).abs();
            assert!(e <= 1e-11, "{name} {ov:?} {gait} s[{i}] off by {e:.2e}");
        }
        let e = (fp.metrics.period - period).abs();
        assert!(e <= 1e-11, "{name} {ov:?} {gait} period off by {e:.2e}");
    }
}

/// `DP(s)` by central differences of the stride map with steps `h`, `h/2`, `h/4`
/// (`h = 1e-3·max(1, |s_j|)`), extrapolated twice (Richardson: error `O(h⁶)`).
fn dp_richardson3(map: &StrideMap<'_>, s: &[f64]) -> Vec<f64> {
    let n = s.len();
    let mut dp = vec![0.0; n * n];
    for j in 0..n {
        let h = 1e-3 * s[j].abs().max(1.0);
        let central = |h: f64| -> Vec<f64> {
            let (mut sp, mut sm) = (s.to_vec(), s.to_vec());
            sp[j] += h;
            sm[j] -= h;
            let (p, m) = (map.apply(&sp).unwrap(), map.apply(&sm).unwrap());
            p.iter().zip(&m).map(|(a, b)| (a - b) / (2.0 * h)).collect()
        };
        let (d1, d2, d4) = (central(h), central(h / 2.0), central(h / 4.0));
        for i in 0..n {
            let r1 = (4.0 * d2[i] - d1[i]) / 3.0;
            let r2 = (4.0 * d4[i] - d2[i]) / 3.0;
            dp[i * n + j] = (16.0 * r2 - r1) / 15.0;
        }
    }
    dp
}

/// Variational multipliers (exact flow, guard and impact Jacobians) against Richardson
/// extrapolation of central differences of the stride map (integrator at 1e-14): at least 9
/// significant digits.
#[test]
fn exact_multipliers_agree_with_richardson_differences_to_nine_digits() {
    for (name, ov, gait, section, _) in BEFORE {
        let w = pdw_walkers::build(name, ov).unwrap();
        let fp = fixed_point(w.as_ref(), &section);
        let map: StrideMap<'_> = StrideMap::new(w.as_ref(), Options::dop853(1e-14)).unwrap();
        let (_, dp_var) = dp_variational(&map, &fp.section).unwrap();
        let dp_fd = dp_richardson3(&map, &fp.section);
        let mf = multipliers(&dp_fd, 3).unwrap();
        // The fully error-controlled DP, and the one Newton kept from its evaluation of the
        // converged point (the tangent riding on the state's steps).
        for (how, dp) in [("full control", &dp_var), ("Newton's", &fp.dp)] {
            let mv = multipliers(dp, 3).unwrap();
            for (a, b) in mv.iter().zip(&mf) {
                let e = ((a.re - b.re).powi(2) + (a.im - b.im).powi(2)).sqrt()
                    / (a.re.hypot(a.im)).max(1.0);
                assert!(
                    e <= 1e-9,
                    "{name} {ov:?} {gait} ({how}): variational {a:?} vs Richardson {b:?} \
                     ({e:.2e})"
                );
            }
        }
        // and the fixed point's own DP is the variational one
        for (a, b) in fp.dp.iter().zip(&dp_var) {
            assert!(
                (a - b).abs() <= 1e-9 * (1.0 + b.abs()),
                "{name}: {a} vs {b}"
            );
        }
    }
}

/// Round feet (radius 0.2 of the leg, rolling without slip): the compass gait's exact
/// multipliers agree with Richardson differences of the stride map to 9 digits, as the point
/// foot's do.
#[test]
fn round_foot_multipliers_agree_with_richardson_differences() {
    let w = pdw_walkers::presets::compass(&[]).unwrap();
    let mut spec = w.spec().clone();
    spec.foot_radius = pdw_walkers::spec::Num::Value(0.2);
    let values: Vec<f64> = w.param_values().into_iter().map(|p| p.1).collect();
    let w = pdw_walkers::ChainWalker::new(spec, &values).unwrap();
    let fp = fixed_point(&w, &[0.3383, -1.2859, 0.8596]);
    // a different gait from the point foot's (s₀ = 0.2710): longer steps on round feet
    assert!((fp.section[0] - 0.3383).abs() < 1e-3, "{:?}", fp.section);
    let map: StrideMap<'_> = StrideMap::new(&w as &dyn Walker, Options::dop853(1e-14)).unwrap();
    let (_, dp_var) = dp_variational(&map, &fp.section).unwrap();
    let dp_fd = dp_richardson3(&map, &fp.section);
    let (mv, mf) = (
        multipliers(&dp_var, 3).unwrap(),
        multipliers(&dp_fd, 3).unwrap(),
    );
    for (a, b) in mv.iter().zip(&mf) {
        let e =
            ((a.re - b.re).powi(2) + (a.im - b.im).powi(2)).sqrt() / (a.re.hypot(a.im)).max(1.0);
        assert!(e <= 1e-9, "variational {a:?} vs Richardson {b:?} ({e:.2e})");
    }
}

/// The design `models/seed5_walking.toml` (the thesis walker's lengths and masses, from an
/// earlier `pdw-sweep design` search whose validity was sampled at accepted steps only): with
/// hyper-extension stops that only push, its stance knee buckles at the knee strike (a hold
/// would need −0.063 N m s, the independent reference model's number) — the stride is a fall.
/// With the stance knee latched (both ways) the same design has a stable gait with a knee strike
/// before the heel strike, whose round-foot knee strike (rolling contact, floating-chain impact)
/// has an exact Jacobian: its multipliers agree with Richardson differences to 1e-9.
#[test]
fn seed5_walking_buckles_with_stops_and_its_latched_gait_has_exact_multipliers() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/seed5_walking.toml");
    let mut spec = pdw_walkers::WalkerSpec::from_file(std::path::Path::new(path)).unwrap();
    let w = pdw_walkers::ChainWalker::from_spec(spec.clone()).unwrap();
    assert!(w.free_knee().is_some() && w.foot_radius() > 0.0);
    let g = w.gait_guesses().into_iter().next().unwrap();
    let mut x0 = vec![0.0; w.dim()];
    w.lift(&g.section, &mut x0);
    let tr = pdw_limit::simulate(&w, &x0, &pdw_limit::TrajectoryOptions::new(1)).unwrap();
    assert_eq!(
        tr.outcome,
        pdw_limit::StrideOutcome::Fall {
            kind: pdw_hybrid::FallKind::KneeBuckled,
            guard: 5
        },
        "{:?}",
        tr.outcome
    );
    // the same design with its stance knee latched
    spec.knees[0].hold = Some("latch".into());
    let w = pdw_walkers::ChainWalker::from_spec(spec).unwrap();
    // latched: no swing_knee_rate in the section
    assert_eq!(w.section_dim(), 3);
    let fp = fixed_point(&w, &g.section[..3]);
    let rho = fp
        .multipliers
        .iter()
        .map(|l| l.re.hypot(l.im))
        .fold(0.0, f64::max);
    assert!(fp.stable && rho < 0.6, "max |λ| = {rho}");
    let tr = pdw_limit::simulate(&w, &fp.state, &pdw_limit::TrajectoryOptions::new(1)).unwrap();
    let kinds: Vec<&str> = tr.events.iter().map(|e| e.kind.as_str()).collect();
    assert_eq!(
        kinds,
        ["knee_strike", "heel_strike"],
        "one knee strike, then the heel strike"
    );
    // the stance knee is locked all step, the swing knee free until the knee strike
    assert_eq!(w.locked_joints(pdw_walkers::chain_walker::FREE), &[1]);
    let map: StrideMap<'_> = StrideMap::new(&w as &dyn Walker, Options::dop853(1e-14)).unwrap();
    let (_, dp_var) = dp_variational(&map, &fp.section).unwrap();
    let dp_fd = dp_richardson3(&map, &fp.section);
    let (mv, mf) = (
        multipliers(&dp_var, 3).unwrap(),
        multipliers(&dp_fd, 3).unwrap(),
    );
    for (a, b) in mv.iter().zip(&mf) {
        let e =
            ((a.re - b.re).powi(2) + (a.im - b.im).powi(2)).sqrt() / (a.re.hypot(a.im)).max(1.0);
        assert!(e <= 1e-9, "variational {a:?} vs Richardson {b:?} ({e:.2e})");
    }
}
