//! Period-K orbits of the simplest walker past its first period doubling (γ ≈ 0.01509: Garcia,
//! Chatterjee, Ruina & Coleman, "The simplest walking model: stability, complexity, and
//! scaling", J. Biomech. Eng. 120 (1998) 281–288): found by Newton on P^K − id and checked
//! against two other routes — iterating the map (the orbit attracts, at the rate its multipliers
//! predict) and a finite-difference K-step Jacobian (the multipliers).

use pdw_hybrid::Options;
use pdw_limit::gaits::{model_guesses, search_periodic, FoundOrbit};
use pdw_limit::*;
use pdw_walkers::simplest::{Simplest, SimplestParams};
use pdw_walkers::Walker;

fn walker(gamma: f64) -> Simplest {
    Simplest::new(SimplestParams {
        slope: gamma,
        ..Default::default()
    })
    .unwrap()
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn orbits(m: &Simplest, k: usize) -> Vec<FoundOrbit> {
    let (found, _) = search_periodic(m, &model_guesses(m), k, 1e-12).unwrap();
    found
}

/// Distance of `s` from the nearest point of `orbit`.
fn to_orbit(orbit: &[Vec<f64>], s: &[f64]) -> f64 {
    orbit
        .iter()
        .map(|p| dist(p, s))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn period_two_at_gamma_0_016_is_found_stable_and_agrees_with_iterating_the_map() {
    let m = walker(0.016);
    let found = orbits(&m, 2);
    let stable: Vec<&FoundOrbit> = found.iter().filter(|f| f.orbit.stable).collect();
    assert_eq!(
        stable.len(),
        1,
        "{:?}",
        found.iter().map(|f| &f.orbit.orbit).collect::<Vec<_>>()
    );
    let o = &stable[0].orbit;
    assert_eq!(o.period_k, 2);
    assert_eq!(o.orbit.len(), 2);
    // Two distinct points (a true period-2 orbit, not the period-one gait twice).
    let split = dist(&o.orbit[0], &o.orbit[1]);
    assert!(split > 1e-3, "points {:?}", o.orbit);
    assert!(o.residual <= 1e-12, "{}", o.residual);
    assert!(
        o.multipliers.iter().all(|l| l.modulus() < 1.0),
        "{:?}",
        o.multipliers
    );

    // Route 2: a different integrator (DOPRI5, 1e-12) maps each point onto the other.
    let sl = |x: &[f64]| m.step_length(x);
    let other = StrideMap::new(&m, Options::dopri5(1e-12))
        .unwrap()
        .with_step_length(&sl);
    let p0 = other.apply(&o.orbit[0]).unwrap();
    let p1 = other.apply(&o.orbit[1]).unwrap();
    assert!(dist(&p0, &o.orbit[1]) < 1e-9, "{p0:?} vs {:?}", o.orbit[1]);
    assert!(dist(&p1, &o.orbit[0]) < 1e-9, "{p1:?} vs {:?}", o.orbit[0]);

    // Route 3: iterating P from a perturbed point converges onto the orbit, and the error
    // shrinks per two strides at the rate of the largest 2-step multiplier.
    let map = StrideMap::new(&m, Options::dop853(1e-14)).unwrap();
    let mut s = o.orbit[0].clone();
    s[0] += 1e-5;
    let mut errs = Vec::new();
    for _ in 0..30 {
        errs.push(dist(&s, &o.orbit[0]));
        s = map.apply(&map.apply(&s).unwrap()).unwrap();
    }
    assert!(errs[29] < 1e-12, "{errs:?}");
    let rho = o.multipliers[0].modulus();
    // Geometric mean rate over 8 double strides while the error is far above round-off
    // (1e-5·ρ⁹ ≈ 2e-10); the rotation of a complex pair modulates the ∞-norm by a bounded
    // factor, whose 8th root stays within 15 %.
    let rate = (errs[9] / errs[1]).powf(1.0 / 8.0);
    eprintln!("errors {errs:?}, rate {rate}, |λ₁| {rho}");
    assert!(
        (rate - rho).abs() < 0.15 * rho,
        "rate {rate} vs |λ₁| {rho} ({:?})",
        o.multipliers
    );

    // Route 4: the multipliers from a finite-difference K-step Jacobian (Richardson, product
    // of per-stride FD Jacobians) agree with the exact (variational) ones.
    let fd = PeriodKProblem::new(
        &map,
        2,
        DpMethod::FiniteDifference {
            scheme: FdScheme::default(),
            lanes: 8,
        },
    );
    let mfd = multipliers(&fd.dp_k(&o.orbit[0]).unwrap(), 2).unwrap();
    for (a, b) in o.multipliers.iter().zip(&mfd) {
        assert!(
            (a.re - b.re).abs() + (a.im - b.im).abs() < 1e-6,
            "{a:?} vs {b:?}"
        );
    }
    // The period-one gait at this slope is unstable (past the period doubling) and lies between
    // the two points of the period-2 orbit.
    let (ones, _) = pdw_limit::gaits::search(&m, &model_guesses(&m), 1e-12).unwrap();
    let p1 = ones
        .iter()
        .map(|f| &f.fp)
        .min_by(|a, b| to_orbit(&o.orbit, &a.section).total_cmp(&to_orbit(&o.orbit, &b.section)))
        .unwrap();
    assert!(!p1.stable);
    assert!(
        p1.multipliers.iter().any(|l| l.im == 0.0 && l.re < -1.0),
        "{:?}",
        p1.multipliers
    );
    let (lo, hi) = (
        o.orbit[0][0].min(o.orbit[1][0]),
        o.orbit[0][0].max(o.orbit[1][0]),
    );
    assert!(
        lo < p1.section[0] && p1.section[0] < hi,
        "{lo} {} {hi}",
        p1.section[0]
    );
    // The whole-orbit time is the sum of the two strides'.
    assert!((o.period - o.strides[0].period - o.strides[1].period).abs() < 1e-12);
}

#[test]
fn period_four_at_gamma_0_0177() {
    let m = walker(0.0177);
    let found = orbits(&m, 4);
    let stable: Vec<&FoundOrbit> = found.iter().filter(|f| f.orbit.stable).collect();
    assert_eq!(
        stable.len(),
        1,
        "{:?}",
        found.iter().map(|f| &f.orbit.orbit).collect::<Vec<_>>()
    );
    let o = &stable[0].orbit;
    assert_eq!(o.orbit.len(), 4);
    // Minimal period 4: no two points coincide.
    for i in 0..4 {
        for j in 0..i {
            assert!(dist(&o.orbit[i], &o.orbit[j]) > 1e-4, "{:?}", o.orbit);
        }
    }
    assert!(o.multipliers.iter().all(|l| l.modulus() < 1.0));
    // Iterating the map from a perturbed point lands on the orbit.
    let map = StrideMap::new(&m, Options::dop853(1e-14)).unwrap();
    let mut s = o.orbit[0].clone();
    s[1] += 1e-5;
    for _ in 0..400 {
        s = map.apply(&s).unwrap();
    }
    assert!(to_orbit(&o.orbit, &s) < 1e-9, "{}", to_orbit(&o.orbit, &s));
    // The period-2 orbit still exists at this slope but has doubled: it is unstable, with a
    // 2-step multiplier below −1.
    let two = orbits(&m, 2);
    assert!(!two.is_empty());
    assert!(two.iter().all(|f| !f.orbit.stable));
    assert!(two.iter().any(|f| f
        .orbit
        .multipliers
        .iter()
        .any(|l| l.im == 0.0 && l.re < -1.0)));
}

#[test]
fn before_the_period_doubling_there_is_no_period_two_orbit_and_the_failure_says_why() {
    // At γ = 0.009 the stable period-one gait attracts every walking guess; Newton on P² lands
    // on period-one points, which are rejected by name.
    let m = walker(0.009);
    let (found, failed) = search_periodic(&m, &model_guesses(&m), 2, 1e-12).unwrap();
    assert!(
        found.is_empty(),
        "{:?}",
        found.iter().map(|f| &f.orbit.orbit).collect::<Vec<_>>()
    );
    assert!(
        failed
            .iter()
            .any(|(_, _, e)| e.to_string().contains("orbit of period 1")),
        "{failed:?}"
    );
    // find_periodic_orbit rejects K = 0.
    let map = StrideMap::new(&m, Options::dop853(1e-14)).unwrap();
    let e = find_periodic_orbit(&map, &[0.2, -0.2], 0, &NewtonOptions::default()).unwrap_err();
    assert!(e.to_string().contains("period"), "{e}");
}

#[test]
fn period_one_through_the_period_k_solver_matches_find_fixed_point() {
    let m = walker(0.009);
    let sl = |x: &[f64]| m.step_length(x);
    let map = StrideMap::new(&m, Options::dop853(1e-14))
        .unwrap()
        .with_step_length(&sl);
    let a = find_fixed_point(&map, &[0.2, -0.2], &NewtonOptions::default()).unwrap();
    let b = find_periodic_orbit(&map, &[0.2, -0.2], 1, &NewtonOptions::default()).unwrap();
    assert!(dist(&a.section, &b.orbit[0]) < 1e-13);
    for (x, y) in a.multipliers.iter().zip(&b.multipliers) {
        assert!((x.re - y.re).abs() + (x.im - y.im).abs() < 1e-12);
    }
    assert_eq!(a.metrics.step_length, b.strides[0].step_length);
}
