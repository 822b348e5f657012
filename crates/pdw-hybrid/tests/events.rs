//! Event-location claims against closed forms.

use crate::common;

use std::f64::consts::PI;

use common::*;
use pdw_hybrid::{Crossing, HybridSystem, Integrator, Options, Scratch, StopReason};

fn run(
    sys: &dyn HybridSystem,
    opts: Options,
    t0: f64,
    x: &mut [f64],
    t_end: f64,
) -> (StopReason, f64) {
    let mut integ = Integrator::new(sys.dim(), opts).unwrap();
    let mut t = t0;
    let r = integ.integrate(sys as &dyn pdw_hybrid::HybridSystem, 0, &mut t, x, t_end);
    (r, t)
}

#[test]
fn oscillator_zero_crossing_time_matches_pi_over_2() {
    let osc = Oscillator::new(&[(0.0, Crossing::Falling, None)]);
    for (opts, tol) in [
        (Options::dop853(1e-13), 1e-12),
        (Options::dopri5(1e-13), 1e-12),
    ] {
        let mut x = [1.0, 0.0];
        let (r, t) = run(&osc, opts, 0.0, &mut x, 10.0);
        assert_eq!(r, StopReason::Guard { guard: 0 });
        eprintln!(
            "{:?}: |t − π/2| = {:.2e}",
            opts.method,
            (t - PI / 2.0).abs()
        );
        assert!((t - PI / 2.0).abs() < tol, "{:?}: t = {t}", opts.method);
        // Right-hand root: the guard is on its post-crossing side (≤ 0 for Falling) or zero.
        assert!(x[0] <= 0.0 && x[0] > -1e-14, "q = {:e}", x[0]);
    }
}

#[test]
fn rk4_event_time_error_shrinks_like_h4() {
    // Hermite event location with RK4: error O(h⁴).
    let osc = Oscillator::new(&[(0.0, Crossing::Falling, None)]);
    let mut errs = Vec::new();
    let hs = [0.2, 0.1, 0.05, 0.025];
    for &h in &hs {
        let mut x = [1.0, 0.0];
        let (r, t) = run(&osc, Options::rk4(h), 0.0, &mut x, 10.0);
        assert_eq!(r, StopReason::Guard { guard: 0 });
        errs.push((t - PI / 2.0).abs());
    }
    eprintln!("RK4 event time errors {errs:?}");
    let p = slope(
        &hs.map(f64::ln),
        &errs.iter().map(|e| e.ln()).collect::<Vec<_>>(),
    );
    eprintln!("RK4 event-time order {p:.2}");
    assert!(p > 3.5, "event-time order {p}");
}

#[test]
fn pendulum_quarter_period_matches_elliptic_integral() {
    // From rest at θ₀, the pendulum first reaches θ = 0 at T/4 = K(sin(θ₀/2)).
    let theta0: f64 = 2.0;
    let exact = Pendulum::ellip_k((theta0 / 2.0).sin());
    let mut x = [theta0, 0.0];
    let (r, t) = run(&Pendulum, Options::dop853(1e-14), 0.0, &mut x, 20.0);
    assert_eq!(r, StopReason::Guard { guard: 0 });
    eprintln!(
        "pendulum: t = {t:.16}, K = {exact:.16}, diff {:.2e}",
        t - exact
    );
    assert!((t - exact).abs() < 1e-12, "t = {t}, K = {exact}");
}

#[test]
fn bouncing_ball_impact_times_match_closed_form() {
    // Drop from height H at rest: impacts at t₁ = √(2H/g), then every 2·e^k·v₁/g.
    let (g, e, h0) = (9.81, 0.8, 1.0);
    let ball = Ball { g, e };
    let mut integ = Integrator::new(2, Options::dop853(1e-12)).unwrap();
    let (mut t, mut x) = (0.0, [h0, 0.0]);
    let v1 = (2.0 * g * h0).sqrt();
    let mut expected = (2.0 * h0 / g).sqrt();
    let mut v = v1;
    for bounce in 0..8 {
        let r = integ.integrate(
            &ball as &dyn pdw_hybrid::HybridSystem,
            0,
            &mut t,
            &mut x,
            100.0,
        );
        assert_eq!(r, StopReason::Guard { guard: 0 }, "bounce {bounce}");
        assert!(
            (t - expected).abs() < 1e-12,
            "bounce {bounce}: t = {t}, expected {expected}"
        );
        assert!(x[0] <= 0.0 && x[0] > -1e-13);
        let mut xp = [0.0; 2];
        ball.reset(&mut Scratch::new(), 0, 0, &x, &mut xp);
        x = xp;
        v *= e;
        expected += 2.0 * v / g;
    }
}

#[test]
fn step_straddling_two_sign_changes_is_not_missed() {
    // q = sin t rises through 0.99 at asin(0.99) and falls back at π − asin(0.99): both inside
    // the single RK4 step [1.2, 2.0], whose end values of g = q − 0.99 are both negative.
    let osc = Oscillator::new(&[(0.99, Crossing::Rising, None)]);
    let t0 = 1.2f64;
    assert!(t0.sin() < 0.99 && (t0 + 0.8).sin() < 0.99);
    let mut x = [t0.sin(), t0.cos()];
    let (r, t) = run(&osc, Options::rk4(0.8), t0, &mut x, 2.0);
    assert_eq!(r, StopReason::Guard { guard: 0 });
    let exact = 0.99f64.asin();
    eprintln!(
        "straddle: t = {t}, exact {exact}, err {:.2e}",
        (t - exact).abs()
    );
    // Hermite with h = 0.8: interpolation error ~h⁴/384·max|x⁗| ≈ 1e-3 in q.
    assert!((t - exact).abs() < 2e-2, "t = {t}");
    // The same with DOP853 forced to one big step.
    let opts = Options {
        h_init: Some(0.8),
        h_max: 0.8,
        ..Options::dop853(1e3)
    };
    let mut x = [t0.sin(), t0.cos()];
    let (r, t) = run(&osc, opts, t0, &mut x, 2.0);
    assert_eq!(r, StopReason::Guard { guard: 0 });
    eprintln!("straddle DOP853 one step: err {:.2e}", (t - exact).abs());
    assert!((t - exact).abs() < 1e-4, "t = {t}");
}

#[test]
fn crossing_direction_is_respected() {
    // q = cos t: falls through 0 at π/2, rises at 3π/2.
    for (dir, expected) in [
        (Crossing::Falling, PI / 2.0),
        (Crossing::Rising, 1.5 * PI),
        (Crossing::Either, PI / 2.0),
    ] {
        let osc = Oscillator::new(&[(0.0, dir, None)]);
        let mut x = [1.0, 0.0];
        let (r, t) = run(&osc, Options::dop853(1e-12), 0.0, &mut x, 10.0);
        assert_eq!(r, StopReason::Guard { guard: 0 });
        assert!((t - expected).abs() < 1e-11, "{dir:?}: t = {t}");
    }
}

#[test]
fn inadmissible_crossing_is_skipped() {
    // Either-direction guard q = 0, admissible only with p > 0: the falling crossing at π/2
    // (p = −1) is skipped, the rising one at 3π/2 (p = +1) counts.
    let osc = Oscillator::new(&[(0.0, Crossing::Either, Some(1.0))]);
    for opts in [
        Options::dop853(1e-12),
        Options::dopri5(1e-12),
        Options::rk4(0.01),
    ] {
        let mut x = [1.0, 0.0];
        let (r, t) = run(&osc, opts, 0.0, &mut x, 10.0);
        assert_eq!(r, StopReason::Guard { guard: 0 });
        let tol = if let pdw_hybrid::Method::Rk4 { .. } = opts.method {
            1e-8
        } else {
            1e-11
        };
        assert!((t - 1.5 * PI).abs() < tol, "{:?}: t = {t}", opts.method);
        assert!(x[1] > 0.0);
    }
}

#[test]
fn earliest_guard_wins_regardless_of_index() {
    // guard 0: q = 0 falling (π/2); guard 1: q = 0.5 falling (π/3, earlier).
    let osc = Oscillator::new(&[
        (0.0, Crossing::Falling, None),
        (0.5, Crossing::Falling, None),
    ]);
    let mut x = [1.0, 0.0];
    let (r, t) = run(&osc, Options::dop853(1e-12), 0.0, &mut x, 10.0);
    assert_eq!(r, StopReason::Guard { guard: 1 });
    assert!((t - PI / 3.0).abs() < 1e-11, "t = {t}");
}

#[test]
fn restarting_at_an_event_does_not_retrigger_it() {
    // Integrate again from the stop point without any reset: the next falling crossing of
    // q = 0 is one period later, at 5π/2.
    let osc = Oscillator::new(&[(0.0, Crossing::Falling, None)]);
    for opts in [
        Options::dop853(1e-12),
        Options::dopri5(1e-12),
        Options::rk4(0.01),
    ] {
        let mut integ = Integrator::new(2, opts).unwrap();
        let (mut t, mut x) = (0.0, [1.0, 0.0]);
        assert_eq!(
            integ.integrate(
                &osc as &dyn pdw_hybrid::HybridSystem,
                0,
                &mut t,
                &mut x,
                20.0
            ),
            StopReason::Guard { guard: 0 }
        );
        let t_first = t;
        assert_eq!(
            integ.integrate(
                &osc as &dyn pdw_hybrid::HybridSystem,
                0,
                &mut t,
                &mut x,
                20.0
            ),
            StopReason::Guard { guard: 0 }
        );
        let tol = if let pdw_hybrid::Method::Rk4 { .. } = opts.method {
            1e-7
        } else {
            1e-10
        };
        assert!(
            (t - t_first - 2.0 * PI).abs() < tol,
            "{:?}: Δt = {}",
            opts.method,
            t - t_first
        );
    }
}

#[test]
fn start_on_the_wrong_side_within_roundoff_does_not_loop() {
    // A reset that leaves the guard a few ulps on the pre-crossing side, moving towards the
    // crossing, must not fire at t₀ + ε: q₀ = −1e-15 rising counts as "on the surface".
    let osc = Oscillator::new(&[(0.0, Crossing::Rising, None)]);
    let mut x = [-1e-15, 1.0];
    let (r, t) = run(&osc, Options::dop853(1e-12), 0.0, &mut x, 10.0);
    assert_eq!(r, StopReason::Guard { guard: 0 });
    assert!((t - 2.0 * PI).abs() < 1e-10, "t = {t}");
    // Outside the band (q₀ = −1e-6) the crossing at t ≈ 1e-6 is a genuine event.
    let mut x = [-1e-6, 1.0];
    let (r, t) = run(&osc, Options::dop853(1e-12), 0.0, &mut x, 10.0);
    assert_eq!(r, StopReason::Guard { guard: 0 });
    assert!((t - 1e-6).abs() < 1e-12, "t = {t}");
}

#[test]
fn grazing_start_does_not_loop() {
    // Ball at rest on the ground (y = 0, v = 0): the guard starts at zero with zero slope and
    // then goes negative. There is no crossing from the positive side, so no event: the run
    // ends at t_end instead of stopping again and again at t₀.
    let ball = Ball { g: 9.81, e: 0.5 };
    for opts in [
        Options::dop853(1e-10),
        Options::dopri5(1e-10),
        Options::rk4(0.01),
    ] {
        let mut x = [0.0, 0.0];
        let (r, t) = run(&ball, opts, 3.0, &mut x, 4.0);
        assert_eq!(r, StopReason::EndTime, "{:?}", opts.method);
        assert_eq!(t, 4.0);
    }
}

#[test]
fn observer_sees_start_steps_and_stop_point() {
    let osc = Oscillator::new(&[(0.0, Crossing::Falling, None)]);
    let mut integ = Integrator::new(2, Options::dopri5(1e-8)).unwrap();
    let (mut t, mut x) = (0.0, [1.0, 0.0]);
    let mut seen = Vec::new();
    let r = integ.integrate_observed(
        &osc as &dyn pdw_hybrid::HybridSystem,
        0,
        &mut t,
        &mut x,
        10.0,
        &mut |tt, xs| {
            seen.push((tt, xs[0]));
        },
    );
    assert_eq!(r, StopReason::Guard { guard: 0 });
    assert_eq!(seen.first().unwrap().0, 0.0);
    assert_eq!(*seen.last().unwrap(), (t, x[0]));
    assert!(seen.windows(2).all(|w| w[1].0 > w[0].0), "times increase");
    assert!(seen.iter().all(|&(tt, q)| (q - tt.cos()).abs() < 1e-6));
}

#[test]
fn end_time_on_a_guard_surface_is_not_a_missed_event() {
    // q = −cos t rises through 0 at t = π/2. Stopping at t_end = π/2 leaves the guard a few ulps
    // below the surface (or exactly on it), moving into it. Taking frames at exact event times
    // (animations at multiples of a gait period) must not lose the event: either this call or
    // the next one reports it at π/2, never a period later.
    let osc = Oscillator::new(&[(0.0, Crossing::Rising, None)]);
    for opts in [Options::dop853(1e-12), Options::dopri5(1e-12)] {
        let mut integ = Integrator::new(2, opts).unwrap();
        let (mut t, mut x) = (0.0, [-1.0, 0.0]);
        let r = integ.integrate(
            &osc as &dyn pdw_hybrid::HybridSystem,
            0,
            &mut t,
            &mut x,
            PI / 2.0,
        );
        let r = if r == StopReason::EndTime {
            integ.integrate(
                &osc as &dyn pdw_hybrid::HybridSystem,
                0,
                &mut t,
                &mut x,
                10.0,
            )
        } else {
            r
        };
        assert_eq!(r, StopReason::Guard { guard: 0 }, "{:?}", opts.method);
        assert!((t - PI / 2.0).abs() < 1e-10, "{:?}: t = {t}", opts.method);
    }
}

/// `q = sin t` passes above 0.9999 only for `|t − π/2| < 0.0141`: inside the one step
/// [1.3, 1.7] that window lies between the samples at t = 1.54 and 1.62 (h/5 = 0.08 apart),
/// which both stay below the level, as do the step's ends. With the guard's rates the cubic
/// through its end values and rates peaks at 0.99995 near π/2, the probe at that extremum shows
/// the crossing and the root is asin 0.9999 to the dense output's accuracy — for a guard
/// declared affine (its cubic) and one that is not (the guard on the interpolated state).
/// Without rates nothing tells the step's interior apart, and the window is missed: the
/// limit the module docs state.
#[test]
fn a_window_between_two_samples_is_found_at_the_guards_extremum() {
    let t0 = 1.3f64;
    let opts = Options {
        h_init: Some(0.4),
        h_max: 0.4,
        ..Options::dop853(1e3)
    };
    for i in 0..=5 {
        assert!((t0 + 0.08 * i as f64).sin() < 0.9999);
    }
    let exact = 0.9999f64.asin();
    for linear in [true, false] {
        let sys = Oscillator::new(&[(0.9999, Crossing::Rising, None)]).with_rates(linear);
        let mut x = [t0.sin(), t0.cos()];
        let (r, t) = run(&sys, opts, t0, &mut x, 1.7);
        assert_eq!(r, StopReason::Guard { guard: 0 }, "linear {linear}");
        assert!(
            (t - exact).abs() < 1e-6,
            "linear {linear}: t = {t}, exact {exact}"
        );
    }
    let osc = Oscillator::new(&[(0.9999, Crossing::Rising, None)]);
    let mut x = [t0.sin(), t0.cos()];
    let (r, _) = run(&osc, opts, t0, &mut x, 1.7);
    assert_eq!(
        r,
        StopReason::EndTime,
        "without rates the window is not seen"
    );
}
