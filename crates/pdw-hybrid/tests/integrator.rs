//! Integrator claims: convergence orders, conservation, failure reporting, option validation.

use crate::common;

use common::*;
use pdw_hybrid::{Controller, HybridError, Integrator, Method, Options, StopReason};

/// Max-norm error at t = T of a fixed-step run with step h = T/n (adaptive methods are made
/// fixed-step by h_init = h_max = h and a tolerance so loose that no step is rejected).
fn fixed_step_error(method: Method, n: usize, t_end: f64) -> (f64, u64) {
    let h = t_end / n as f64;
    let opts = match method {
        Method::Rk4 { .. } => Options::rk4(h),
        Method::Dopri5 => Options {
            h_init: Some(h),
            h_max: h,
            ..Options::dopri5(1e6)
        },
        Method::Dop853 => Options {
            h_init: Some(h),
            h_max: h,
            ..Options::dop853(1e6)
        },
    };
    let mut integ = Integrator::new(3, opts).unwrap();
    let mut t = 0.0;
    let mut x = [1.0, 0.0, 1.0];
    let r = integ.integrate(
        &OscGrowth as &dyn pdw_hybrid::HybridSystem,
        0,
        &mut t,
        &mut x,
        t_end,
    );
    assert_eq!(r, StopReason::EndTime);
    assert_eq!(t, t_end);
    let ex = OscGrowth::exact(t_end);
    let err = x
        .iter()
        .zip(&ex)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert_eq!(integ.stats().rejected, 0, "fixed-step run must not reject");
    assert_eq!(integ.stats().accepted, n as u64);
    (err, integ.stats().rhs_evals)
}

fn measured_order(method: Method, ns: &[usize]) -> f64 {
    let t_end = 10.0;
    let mut lh = Vec::new();
    let mut le = Vec::new();
    for &n in ns {
        let (e, _) = fixed_step_error(method, n, t_end);
        eprintln!(
            "{method:?} n = {n:5}  h = {:.4e}  err = {e:.3e}",
            t_end / n as f64
        );
        lh.push((t_end / n as f64).ln());
        le.push(e.ln());
    }
    slope(&lh, &le)
}

#[test]
fn rk4_converges_with_order_4() {
    let p = measured_order(Method::Rk4 { h: 0.0 }, &[40, 56, 80, 113, 160, 226, 320]);
    eprintln!("RK4 measured order {p:.3}");
    assert!((p - 4.0).abs() <= 0.3, "RK4 order {p}");
}

#[test]
fn dopri5_converges_with_order_5() {
    let p = measured_order(Method::Dopri5, &[20, 28, 40, 56, 80, 113, 160]);
    eprintln!("DOPRI5 measured order {p:.3}");
    assert!((p - 5.0).abs() <= 0.3, "DOPRI5 order {p}");
}

#[test]
fn dop853_converges_with_order_8() {
    let p = measured_order(Method::Dop853, &[10, 12, 14, 17, 20, 24, 28]);
    eprintln!("DOP853 measured order {p:.3}");
    assert!((p - 8.0).abs() <= 0.3, "DOP853 order {p}");
}

/// Adaptive runs are tolerance-proportional: the achieved global error scales like the
/// tolerance (slope of log err vs log tol ≈ 1 over five decades) and stays within a small
/// multiple of it — for DOPRI5 with either step-size controller, and DOP853. The two DOPRI5
/// controllers take different step sequences (the option is not ignored).
#[test]
fn adaptive_error_is_proportional_to_tolerance() {
    let mut evals_by_controller = Vec::new();
    for (method, controller) in [
        (Method::Dopri5, Controller::Pi),
        (Method::Dopri5, Controller::Elementary),
        (Method::Dop853, Controller::Pi),
    ] {
        let mut lt = Vec::new();
        let mut le = Vec::new();
        let mut evals = Vec::new();
        for k in 0..6 {
            let tol = 10f64.powi(-5 - k);
            let opts = Options {
                method,
                controller,
                ..Options::dopri5(tol)
            };
            let mut integ = Integrator::new(3, opts).unwrap();
            let (mut t, mut x) = (0.0, [1.0, 0.0, 1.0]);
            assert_eq!(
                integ.integrate(
                    &OscGrowth as &dyn pdw_hybrid::HybridSystem,
                    0,
                    &mut t,
                    &mut x,
                    10.0
                ),
                StopReason::EndTime
            );
            let ex = OscGrowth::exact(10.0);
            let err = x
                .iter()
                .zip(&ex)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            eprintln!(
                "{method:?} {controller:?} tol {tol:.0e}: err {err:.3e}, evals {}",
                integ.stats().rhs_evals
            );
            assert!(
                err < 10.0 * tol,
                "{method:?} {controller:?} tol {tol:e}: err {err:e}"
            );
            lt.push(tol.ln());
            le.push(err.ln());
            evals.push(integ.stats().rhs_evals);
        }
        let s = slope(&lt, &le);
        eprintln!("{method:?} {controller:?}: d log err / d log tol = {s:.3}");
        assert!(
            (s - 1.0).abs() < 0.1,
            "{method:?} {controller:?} tolerance proportionality slope {s}"
        );
        evals_by_controller.push(evals);
    }
    assert_ne!(
        evals_by_controller[0], evals_by_controller[1],
        "DOPRI5's PI and elementary controllers took the same steps"
    );
}

/// The pendulum's energy ω²/2 − cos θ is a first integral: DOP853 at tolerance 1e-13 keeps it
/// to < 1e-11 relative over ten periods-worth of time (drift of a non-symplectic method grows
/// linearly; its rate is set by the tolerance).
#[test]
fn dop853_conserves_pendulum_energy_at_tight_tolerance() {
    let mut integ = Integrator::new(2, Options::dop853(1e-13)).unwrap();
    let x0 = [2.0, 0.0];
    let e0 = Pendulum::energy(&x0);
    let mut worst = 0.0f64;
    let (mut t, mut x) = (0.0, x0);
    // No guard stop: the bottom guard fires every half swing; continue after each.
    while t < 80.0 {
        let r = integ.integrate_observed(
            &Pendulum as &dyn pdw_hybrid::HybridSystem,
            0,
            &mut t,
            &mut x,
            80.0,
            &mut |_, xs| {
                worst = worst.max(((Pendulum::energy(xs) - e0) / e0).abs());
            },
        );
        assert!(
            matches!(r, StopReason::Guard { guard: 0 } | StopReason::EndTime),
            "{r:?}"
        );
    }
    eprintln!("max relative energy drift over t ∈ [0, 80]: {worst:.3e}");
    assert!(worst < 1e-11, "energy drift {worst:e}");
}

#[test]
fn rk4_blow_up_reports_non_finite() {
    // ẋ = x², x(0) = 1 blows up at t = 1; a fixed step of 0.1 overflows shortly after.
    let mut integ = Integrator::new(1, Options::rk4(0.1)).unwrap();
    let (mut t, mut x) = (0.0, [1.0]);
    let r = integ.integrate(
        &BlowUp as &dyn pdw_hybrid::HybridSystem,
        0,
        &mut t,
        &mut x,
        2.0,
    );
    assert_eq!(r, StopReason::NonFinite);
    assert!(
        x[0].is_finite(),
        "the returned state is the last finite one"
    );
    assert!(t > 0.5 && t < 1.3, "t = {t}");
}

#[test]
fn adaptive_blow_up_reports_step_too_small_near_the_singularity() {
    for opts in [Options::dopri5(1e-8), Options::dop853(1e-8)] {
        let mut integ = Integrator::new(1, opts).unwrap();
        let (mut t, mut x) = (0.0, [1.0]);
        let r = integ.integrate(
            &BlowUp as &dyn pdw_hybrid::HybridSystem,
            0,
            &mut t,
            &mut x,
            2.0,
        );
        assert_eq!(r, StopReason::StepTooSmall, "{:?}", opts.method);
        // The numerical solution's own blow-up time differs from t = 1 by O(tol).
        assert!((t - 1.0).abs() < 1e-6, "{:?}: t = {t}", opts.method);
        assert!(x[0].is_finite() && x[0] > 1e6, "x = {}", x[0]);
    }
}

#[test]
fn adaptive_min_step_reports_step_too_small() {
    let opts = Options {
        h_min: 1e-3,
        ..Options::dopri5(1e-8)
    };
    let mut integ = Integrator::new(1, opts).unwrap();
    let (mut t, mut x) = (0.0, [1.0]);
    assert_eq!(
        integ.integrate(
            &BlowUp as &dyn pdw_hybrid::HybridSystem,
            0,
            &mut t,
            &mut x,
            2.0
        ),
        StopReason::StepTooSmall
    );
    assert!(t < 1.0 && t > 0.9, "t = {t}");
}

#[test]
fn flow_leaving_its_domain_reports_non_finite() {
    for opts in [Options::dopri5(1e-8), Options::dop853(1e-8)] {
        let mut integ = Integrator::new(1, opts).unwrap();
        let (mut t, mut x) = (0.0, [0.0]);
        let r = integ.integrate(
            &Cliff as &dyn pdw_hybrid::HybridSystem,
            0,
            &mut t,
            &mut x,
            3.0,
        );
        assert_eq!(r, StopReason::NonFinite, "{:?}", opts.method);
        assert!(x[0] <= 1.5 && x[0] > 1.5 - 1e-9, "x = {}", x[0]);
        assert!((t - x[0]).abs() < 1e-12);
    }
}

#[test]
fn non_finite_initial_state_is_reported_without_stepping() {
    let mut integ = Integrator::new(2, Options::dopri5(1e-8)).unwrap();
    let (mut t, mut x) = (0.0, [f64::NAN, 0.0]);
    assert_eq!(
        integ.integrate(
            &Pendulum as &dyn pdw_hybrid::HybridSystem,
            0,
            &mut t,
            &mut x,
            1.0
        ),
        StopReason::NonFinite
    );
    assert_eq!(t, 0.0);
    assert_eq!(integ.stats().accepted, 0);
}

#[test]
fn max_steps_is_reported() {
    let opts = Options {
        max_steps: 5,
        ..Options::dopri5(1e-10)
    };
    let mut integ = Integrator::new(3, opts).unwrap();
    let (mut t, mut x) = (0.0, [1.0, 0.0, 1.0]);
    assert_eq!(
        integ.integrate(
            &OscGrowth as &dyn pdw_hybrid::HybridSystem,
            0,
            &mut t,
            &mut x,
            10.0
        ),
        StopReason::MaxSteps
    );
    let s = integ.stats();
    assert_eq!(s.accepted + s.rejected, 5);
    assert!(t > 0.0 && t < 10.0);
}

#[test]
fn end_time_at_or_before_start_returns_immediately() {
    let mut integ = Integrator::new(2, Options::dop853(1e-8)).unwrap();
    let (mut t, mut x) = (1.0, [0.3, 0.1]);
    assert_eq!(
        integ.integrate(
            &Pendulum as &dyn pdw_hybrid::HybridSystem,
            0,
            &mut t,
            &mut x,
            1.0
        ),
        StopReason::EndTime
    );
    assert_eq!((t, x), (1.0, [0.3, 0.1]));
}

#[test]
fn h_max_bounds_every_step() {
    let opts = Options {
        h_max: 0.01,
        ..Options::dop853(1e-6)
    };
    let mut integ = Integrator::new(3, opts).unwrap();
    let (mut t, mut x) = (0.0, [1.0, 0.0, 1.0]);
    let mut last = 0.0;
    let mut worst = 0.0f64;
    integ.integrate_observed(
        &OscGrowth as &dyn pdw_hybrid::HybridSystem,
        0,
        &mut t,
        &mut x,
        1.0,
        &mut |tt, _| {
            worst = worst.max(tt - last);
            last = tt;
        },
    );
    assert!(worst <= 0.01 * (1.0 + 1e-12), "largest step {worst}");
    assert!(integ.stats().accepted >= 100);
}

#[test]
fn invalid_options_are_rejected_with_the_offending_name() {
    let cases: Vec<(Options, &str)> = vec![
        (Options::rk4(0.0), "h"),
        (Options::rk4(f64::NAN), "h"),
        (Options::dopri5(-1e-6), "rtol"),
        (Options::dopri5(1e-17), "rtol"),
        (
            Options {
                atol: 0.0,
                ..Options::dopri5(1e-6)
            },
            "atol",
        ),
        (
            Options {
                h_init: Some(-1.0),
                ..Options::dop853(1e-6)
            },
            "h_init",
        ),
        (
            Options {
                h_max: 0.0,
                ..Options::dop853(1e-6)
            },
            "h_max",
        ),
        (
            Options {
                h_min: 2.0,
                h_max: 1.0,
                ..Options::dop853(1e-6)
            },
            "h_min",
        ),
        (
            Options {
                max_steps: 0,
                ..Options::dop853(1e-6)
            },
            "max_steps",
        ),
    ];
    for (o, name) in cases {
        match Integrator::new(2, o) {
            Err(HybridError::InvalidOption { name: n, .. }) => assert_eq!(n, name),
            Err(e) => panic!("{name}: unexpected error {e}"),
            Ok(_) => panic!("{name}: accepted {o:?}"),
        }
    }
    assert!(matches!(
        Integrator::new(0, Options::dopri5(1e-6)),
        Err(HybridError::ZeroDimension { dim: 0 })
    ));
}
