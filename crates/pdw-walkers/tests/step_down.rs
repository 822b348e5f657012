//! Step heights (`step_down`): the simplest walker and the rimless wheel landing on a foothold
//! `h` below the stance foot, checked against geometry (the drawn swing foot), energy
//! bookkeeping across the flow and the impact, the level-ground map, and the rimless wheel's
//! closed-form step map.

use pdw_hybrid::{HybridSystem, Integrator, Options, Scratch, Section, StopReason};
use pdw_walkers::rimless::{Rimless, RimlessParams, SPOKE_IMPACT};
use pdw_walkers::simplest::{GarciaGait, Simplest, SimplestParams, HEEL_STRIKE};
use pdw_walkers::Walker;

const GAMMA: f64 = 0.009;

fn simplest(h: f64) -> Simplest {
    Simplest::new(SimplestParams {
        slope: GAMMA,
        step_down: h,
        ..Default::default()
    })
    .unwrap()
}

fn wheel(h: f64) -> Rimless {
    Rimless::new(RimlessParams {
        slope: 0.08,
        step_down: h,
        ..Default::default()
    })
    .unwrap()
}

/// Integrates `sys` from `x` (DOP853 at 1e-13) to its section guard, calling `obs` at every
/// accepted step; returns the pre-impact state.
fn to_strike(sys: &dyn HybridSystem, x: &[f64], obs: &mut dyn FnMut(&[f64])) -> Vec<f64> {
    let mut integ = Integrator::new(x.len(), Options::dop853(1e-13)).unwrap();
    let (mut t, mut y) = (0.0, x.to_vec());
    let stop = integ.integrate_observed(sys, 0, &mut t, &mut y, 20.0, &mut |_, s| obs(s));
    assert_eq!(
        stop,
        StopReason::Guard { guard: 0 },
        "stride did not end in a strike"
    );
    y
}

/// The walker just after a level-ground heel strike near Garcia's stable gait.
fn garcia_start() -> Vec<f64> {
    let mut x = vec![0.0; 4];
    simplest(0.0).lift(&GarciaGait::LongPeriod.section_guess(GAMMA), &mut x);
    x
}

#[test]
fn step_down_zero_is_the_level_ground_stride_and_a_vanishing_step_its_limit() {
    // h = 0 set explicitly runs the level code (the default model, bit for bit); a step of
    // 1e-300 runs the general guard, jump map and lift, which must give the same stride to the
    // event location's accuracy.
    let x0 = garcia_start();
    let level = simplest(0.0);
    let dflt = Simplest::new(SimplestParams {
        slope: GAMMA,
        ..Default::default()
    })
    .unwrap();
    let (a, b) = (
        to_strike(&level, &x0, &mut |_| {}),
        to_strike(&dflt, &x0, &mut |_| {}),
    );
    assert_eq!(a, b);
    let tiny = simplest(1e-300);
    let c = to_strike(&tiny, &x0, &mut |_| {});
    let (mut pa, mut pc) = ([0.0; 4], [0.0; 4]);
    level.reset(&mut Scratch::new(), 0, HEEL_STRIKE, &a, &mut pa);
    tiny.reset(&mut Scratch::new(), 0, HEEL_STRIKE, &c, &mut pc);
    for k in 0..4 {
        assert!((pa[k] - pc[k]).abs() < 1e-12, "{k}: {pa:?} vs {pc:?}");
    }
    let (mut la, mut lc) = ([0.0; 4], [0.0; 4]);
    level.lift(&pa[..2], &mut la);
    tiny.lift(&pa[..2], &mut lc);
    for k in 0..4 {
        assert!((la[k] - lc[k]).abs() < 1e-15, "{k}: {la:?} vs {lc:?}");
    }
}

#[test]
fn simplest_strikes_the_step_and_keeps_the_energy_books() {
    for h in [0.01, -0.002, 0.03] {
        let w = simplest(h);
        let x0 = garcia_start();
        let e0 = w.energy(&x0);
        let mut drift: f64 = 0.0;
        let pre = to_strike(&w, &x0, &mut |x| {
            drift = drift.max((w.energy(x) - e0).abs())
        });
        assert!(drift < 1e-9, "h {h}: energy drift {drift:e} along the flow");
        // the drawn swing foot is on the foothold's level, ahead of the stance foot
        let bp = w.body_points(&pre).unwrap();
        let foot = bp.points[2];
        assert!((foot[1] + h).abs() < 1e-9, "h {h}: foot at {foot:?}");
        assert!(foot[0] > 0.0);
        let mut post = [0.0; 4];
        w.reset(&mut Scratch::new(), 0, HEEL_STRIKE, &pre, &mut post);
        // the new stance foot is the drawn swing foot: the hip seen from it is the old hip
        let hip_new = w.body_points(&post).unwrap().points[1];
        let hip_old = bp.points[1];
        for k in 0..2 {
            assert!((hip_new[k] - (hip_old[k] - foot[k])).abs() < 1e-12);
        }
        // potential energy referred to the new foot rises by g·p (gravity (sin γ, −cos γ)),
        // kinetic energy drops by ½ (v·e)² with e the new stance leg (from the drawing)
        let (ex, ey) = (hip_new[0], hip_new[1]);
        let v = [-pre[1] * pre[0].cos(), -pre[1] * pre[0].sin()];
        let along = v[0] * ex + v[1] * ey;
        let gp = foot[0] * GAMMA.sin() - foot[1] * GAMMA.cos();
        let expected = w.energy(&pre) - 0.5 * along * along + gp;
        assert!((w.energy(&post) - expected).abs() < 1e-12, "h {h}");
        // the loss is the impact report's
        let rep = w.impact_report(0, HEEL_STRIKE, &pre).unwrap();
        assert!((rep.energy_lost - 0.5 * along * along).abs() < 1e-14);
        // the lift of the model at this h is the post-impact state
        let mut lifted = [0.0; 4];
        w.lift(&post[..2], &mut lifted);
        for k in 0..4 {
            assert!((lifted[k] - post[k]).abs() < 1e-12, "h {h} {k}");
        }
    }
}

#[test]
fn simplest_step_jump_map_jacobian_is_its_derivative() {
    let w = simplest(0.02);
    let x = [-0.2, -0.19, -0.38, 0.03];
    let mut jac = [0.0; 16];
    w.reset_jacobian(&mut Scratch::new(), 0, HEEL_STRIKE, &x, &mut jac);
    for j in 0..4 {
        let d = 1e-6;
        let (mut xp, mut xm) = (x, x);
        xp[j] += d;
        xm[j] -= d;
        let (mut yp, mut ym) = ([0.0; 4], [0.0; 4]);
        w.reset(&mut Scratch::new(), 0, HEEL_STRIKE, &xp, &mut yp);
        w.reset(&mut Scratch::new(), 0, HEEL_STRIKE, &xm, &mut ym);
        for i in 0..4 {
            let fd = (yp[i] - ym[i]) / (2.0 * d);
            assert!((fd - jac[i * 4 + j]).abs() < 1e-8, "({i},{j})");
        }
    }
}

/// The stance angle at which the next spoke's drawn tip is `h` below the contact, by
/// bisection on the drawing.
fn tip_angle(w: &Rimless, h: f64) -> f64 {
    let a = w.alpha();
    let height = |th: f64| w.pose(&[th, 0.0]).unwrap().swing_foot.unwrap()[1] + h;
    let (mut lo, mut hi) = (-a, 3.0 * a);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        // the tip falls as θ grows
        if height(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[test]
fn rimless_step_map_is_the_closed_form() {
    let (g, l) = (9.81, 1.0);
    for (h_prev, h) in [(0.0, 0.05), (0.05, -0.03), (-0.1, 0.2), (0.02, 0.02)] {
        let (from, to) = (wheel(h_prev), wheel(h));
        let omega = 2.0;
        let mut x0 = [0.0; 2];
        from.lift(&[omega], &mut x0);
        let th_plus = tip_angle(&from, h_prev) - 2.0 * from.alpha();
        assert!((x0[0] - th_plus).abs() < 1e-12);
        let mut drift: f64 = 0.0;
        let e0 = to.energy(&x0);
        let pre = to_strike(&to, &x0, &mut |x| {
            drift = drift.max((to.energy(x) - e0).abs())
        });
        assert!(drift < 1e-9 * g * l);
        let th_minus = tip_angle(&to, h);
        assert!((pre[0] - th_minus).abs() < 1e-9, "{h_prev} {h}");
        let tip = to.pose(&pre).unwrap().swing_foot.unwrap();
        assert!((tip[1] + h).abs() < 1e-9);
        let mut post = [0.0; 2];
        to.reset(&mut Scratch::new(), 0, SPOKE_IMPACT, &pre, &mut post);
        let gamma = 0.08f64;
        let drop = (th_plus + gamma).cos() - (th_minus + gamma).cos();
        let closed = (2.0 * to.alpha()).cos() * (omega * omega + 2.0 * g / l * drop).sqrt();
        assert!(
            (post[1] - closed).abs() < 1e-9,
            "{h_prev} {h}: {post:?} vs {closed}"
        );
    }
}

#[test]
fn rimless_stairs_fixed_point_returns_to_itself() {
    for h in [0.03, -0.005] {
        let w = wheel(h);
        let omega = w.rolling_fixed_point().unwrap();
        let mut x0 = [0.0; 2];
        w.lift(&[omega], &mut x0);
        let pre = to_strike(&w, &x0, &mut |_| {});
        let mut post = [0.0; 2];
        w.reset(&mut Scratch::new(), 0, SPOKE_IMPACT, &pre, &mut post);
        assert!((post[1] - omega).abs() < 1e-10, "{h}: {post:?} vs {omega}");
    }
}

#[test]
fn steps_beyond_reach_are_refused() {
    let reach = 2.0 * (std::f64::consts::PI / 8.0).sin();
    for h in [reach, -reach * 1.01, f64::NAN] {
        let e = Rimless::new(RimlessParams {
            step_down: h,
            ..Default::default()
        })
        .unwrap_err();
        assert!(e.to_string().contains("step_down"), "{e}");
    }
    for h in [1.0, -1.5, f64::INFINITY] {
        let e = Simplest::new(SimplestParams {
            step_down: h,
            ..Default::default()
        })
        .unwrap_err();
        assert!(e.to_string().contains("step_down"), "{e}");
    }
}
