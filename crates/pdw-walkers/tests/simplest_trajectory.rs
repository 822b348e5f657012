//! Trajectory-level claims of the simplest walker, integrated with DOP853.

use pdw_hybrid::Section;
use pdw_hybrid::{HybridSystem, Integrator, Options, Scratch, StopReason};
use pdw_walkers::simplest::{Simplest, SimplestParams, HEEL_STRIKE};

// Garcia's stable gait at γ = 0.009 (Garcia et al., J. Biomech. Eng. 120, 1998; his own code).
const S_STABLE: [f64; 2] = [0.20031090049483, -0.19983247291764];

fn model() -> Simplest {
    Simplest::new(SimplestParams::default()).unwrap()
}

#[test]
fn energy_conserved_between_impacts() {
    let m = model();
    let mut x = [0.0; 4];
    m.lift(&S_STABLE, &mut x);
    let e0 = m.energy(&x);
    let mut worst = 0.0f64;
    let mut integ = Integrator::new(4, Options::dop853(1e-13)).unwrap();
    let mut t = 0.0;
    let stop = integ.integrate_observed(
        &m as &dyn pdw_hybrid::HybridSystem,
        0,
        &mut t,
        &mut x,
        12.0,
        &mut |_, xs| {
            worst = worst.max(((m.energy(xs) - e0) / e0).abs());
        },
    );
    assert_eq!(stop, StopReason::Guard { guard: HEEL_STRIKE });
    assert!(worst < 1e-10, "relative energy drift {worst:e}");
    // the impact then removes kinetic energy ½θ̇⁻²(1 − cos²2θ⁻) (the potential is measured
    // from the stance foot, which changes at the impact, so only kinetic energy is compared)
    let mut xp = [0.0; 4];
    m.reset(&mut Scratch::new(), 0, HEEL_STRIKE, &x, &mut xp);
    let lost = 0.5 * (x[1] * x[1] - xp[1] * xp[1]);
    let c2 = (2.0 * x[0]).cos();
    assert!((lost - 0.5 * x[1] * x[1] * (1.0 - c2 * c2)).abs() < 1e-15);
}

#[test]
fn scuffing_crossing_is_never_taken_as_heel_strike() {
    // Along a stride the heel-strike function g = φ − 2θ changes sign near mid-stance (the swing
    // foot passes through the floor, ignored as in Garcia 1998); the integrator must run past it
    // and stop only at the real heel strike, with the swing foot ahead (θ⁻ ≈ −θ*).
    let m = model();
    let mut x = [0.0; 4];
    m.lift(&S_STABLE, &mut x);
    let mut integ = Integrator::new(4, Options::dop853(1e-12)).unwrap();
    let mut t = 0.0;
    let mut samples: Vec<(f64, f64, f64)> = Vec::new();
    let stop = integ.integrate_observed(
        &m as &dyn pdw_hybrid::HybridSystem,
        0,
        &mut t,
        &mut x,
        12.0,
        &mut |t, xs| {
            samples.push((t, m.guard(&mut Scratch::new(), 0, HEEL_STRIKE, xs), xs[0]));
        },
    );
    assert_eq!(stop, StopReason::Guard { guard: HEEL_STRIKE });
    let mid_crossings: Vec<_> = samples
        .windows(2)
        .filter(|w| w[0].1 > 0.0 && w[1].1 <= 0.0)
        .map(|w| (w[1].0, w[1].2))
        .collect();
    assert!(!mid_crossings.is_empty(), "no scuffing crossing seen");
    for (tc, th) in &mid_crossings {
        assert!(*tc < t, "scuffing at {tc} after the stop {t}");
        assert!(
            th.abs() < 0.1,
            "scuffing crossing away from mid-stance, θ = {th}"
        );
    }
    assert!(
        (x[0] + S_STABLE[0]).abs() < 1e-8,
        "heel strike at θ = {}",
        x[0]
    );
    assert!((t - 3.88).abs() < 5e-3, "period {t}");
}

#[test]
fn a_start_on_the_heel_strike_surface_does_not_retrigger() {
    // The post-impact state has g = 0 exactly (φ = 2θ) and θ > 0: not admissible, no event.
    let m = model();
    let mut x = [0.0; 4];
    m.lift(&S_STABLE, &mut x);
    assert_eq!(m.guard(&mut Scratch::new(), 0, HEEL_STRIKE, &x), 0.0);
    let mut integ = Integrator::new(4, Options::dop853(1e-10)).unwrap();
    let mut t = 0.0;
    integ.integrate(&m as &dyn pdw_hybrid::HybridSystem, 0, &mut t, &mut x, 12.0);
    assert!(t > 3.0, "stopped at t = {t}");
}
