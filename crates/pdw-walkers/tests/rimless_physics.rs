//! Physics claims about the rimless wheel, against geometry and energy bookkeeping.

use pdw_hybrid::{HybridSystem, Integrator, Options, Scratch, Section, StopReason};
use pdw_walkers::rimless::{Rimless, RimlessParams, SPOKE_IMPACT};
use pdw_walkers::Walker;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn wheel(n: f64, slope: f64) -> Rimless {
    Rimless::new(RimlessParams {
        n_spokes: n,
        slope,
        ..Default::default()
    })
    .unwrap()
}

#[test]
fn spoke_impact_loses_exactly_the_predicted_kinetic_energy() {
    // Hub point mass; the new contact is at angle 2α from the old along the rim. Angular
    // momentum about the new contact conserved ⇒ the velocity component along the new spoke is
    // removed by the impulse; the lost kinetic energy is ½ (v⁻ · e_new)², derived here from
    // vectors, not from cos 2α.
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for n in [4.0, 6.0, 8.0, 12.0] {
        let w = wheel(n, 0.05);
        let a = w.alpha();
        for _ in 0..100 {
            let omega: f64 = rng.random_range(0.1..3.0);
            let xm = [a, omega];
            let mut xp = [0.0; 2];
            w.reset(&mut Scratch::new(), 0, SPOKE_IMPACT, &xm, &mut xp);
            assert!((xp[0] + a).abs() < 1e-15);
            // Old contact at origin: hub = l (sin θ, cos θ); velocity = l θ̇ (cos θ, −sin θ).
            let hub = [a.sin(), a.cos()];
            let v = [omega * a.cos(), -omega * a.sin()];
            let new_contact = [2.0 * a.sin(), 0.0];
            let r = [hub[0] - new_contact[0], hub[1] - new_contact[1]];
            let rn = r[0].hypot(r[1]);
            assert!((rn - 1.0).abs() < 1e-15);
            let along = (v[0] * r[0] + v[1] * r[1]) / rn;
            let ke_before = 0.5 * omega * omega;
            let ke_after = 0.5 * xp[1] * xp[1];
            assert!(((ke_before - ke_after) - 0.5 * along * along).abs() < 1e-14);
            // angular momentum about the new contact
            let l_before = r[0] * v[1] - r[1] * v[0];
            let v_after = [xp[1] * xp[0].cos(), -xp[1] * xp[0].sin()];
            let l_after = r[0] * v_after[1] - r[1] * v_after[0];
            assert!((l_before - l_after).abs() < 1e-14);
        }
    }
}

#[test]
fn energy_gain_over_a_spoke_equals_the_drop_in_hub_height() {
    // E = ½ l² θ̇² + g l cos(θ + γ) is constant along the flow (checked through dE/dt = 0)
    // and the drop of cos(θ + γ) from θ = −α to α is 2 sin α sin γ (Coleman; Tedrake ch. 4).
    let w = wheel(8.0, 0.08);
    let a = w.alpha();
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    for _ in 0..100 {
        let x = [rng.random_range(-a..a), rng.random_range(0.0..2.0)];
        let mut f = [0.0; 2];
        w.flow(&mut Scratch::new(), 0, &x, &mut f);
        let de = 1.0 * x[1] * f[1] - 9.81 * (x[0] + 0.08).sin() * f[0];
        assert!(de.abs() < 1e-13);
    }
    let drop = w.energy(&[-a, 0.0]) - w.energy(&[a, 0.0]);
    assert!((drop - 2.0 * 9.81 * a.sin() * (0.08f64).sin()).abs() < 1e-14);
}

#[test]
fn lift_is_the_post_impact_state() {
    let w = wheel(8.0, 0.08);
    let mut x = [0.0; 2];
    w.lift(&[1.3], &mut x);
    let mut xp = [0.0; 2];
    w.reset(
        &mut Scratch::new(),
        0,
        SPOKE_IMPACT,
        &[w.alpha(), 1.3 / (2.0 * w.alpha()).cos()],
        &mut xp,
    );
    assert!((x[0] - xp[0]).abs() < 1e-15 && (x[1] - xp[1]).abs() < 1e-15);
}

#[test]
fn rolling_fixed_point_exists_only_when_the_wheel_can_roll() {
    assert!(wheel(8.0, 0.08).rolling_fixed_point().is_some());
    assert!(wheel(8.0, 0.0).rolling_fixed_point().is_none());
    assert!(wheel(8.0, 0.001).rolling_fixed_point().is_none());
    assert!(wheel(4.0, 0.3).rolling_fixed_point().is_none());
}

#[test]
fn invalid_spoke_counts_are_rejected() {
    for n in [2.0, 7.5, f64::NAN] {
        let e = Rimless::new(RimlessParams {
            n_spokes: n,
            ..Default::default()
        })
        .unwrap_err();
        assert!(e.to_string().contains("n_spokes"));
    }
}

/// The hub in the slope frame, from the model's drawing (its one joint): the reaction is
/// checked against the geometry of `pose`, not against the formula of `constraint_forces`.
fn hub(w: &Rimless, x: &[f64]) -> [f64; 2] {
    w.pose(x).unwrap().joints[0]
}

/// The post-impact state of the rolling gait and the time of its next spoke impact (DOP853 at
/// 1e-13).
fn gait_stride(w: &Rimless) -> ([f64; 2], f64) {
    let mut x0 = [0.0; 2];
    w.lift(&[w.rolling_fixed_point().unwrap()], &mut x0);
    let mut integ = Integrator::new(2, Options::dop853(1e-13)).unwrap();
    let (mut t, mut x) = (0.0, x0);
    let stop = integ.integrate(w as &dyn pdw_hybrid::HybridSystem, 0, &mut t, &mut x, 10.0);
    assert_eq!(
        stop,
        StopReason::Guard {
            guard: SPOKE_IMPACT
        }
    );
    (x0, t)
}

/// Newton's law for the hub, `a = F + g` per unit mass: the hub's acceleration measured by
/// second differences of its position along a simulated stride, minus gravity
/// `g (sin γ, −cos γ)`, is the ground reaction (tangential, normal) the model reports.
///
/// Accuracy: the positions at `t ± h`, `t ± h/2` (h = 10⁻³) come from consecutive DOP853
/// integrations at 10⁻¹³ over intervals of h/2, whose local errors (∝ (h/2)⁹) are far below
/// the positions' rounding, ε|p| ≈ 1.1·10⁻¹⁶ m (|p| ≤ l ≤ 1.3 m). The Richardson combination
/// `(4 D(h/2) − D(h))/3` of the second differences `D` removes the `h²` truncation term (the
/// `h⁴` one is ≈ 10⁻¹² m/s²) and amplifies the rounding by `(4/3)·16/h² + (1/3)·4/h² ≈
/// 2.3·10⁷`: at most ≈ 3·10⁻⁹ m/s² (measured: 1.0·10⁻⁹). The tolerance is 10⁻⁸ m/s²
/// (10⁻⁹ g); a wrong force (a missing `cos θ`, the centripetal term's sign) is off by
/// 10⁻² … 10 m/s².
#[test]
fn ground_reaction_is_the_hub_acceleration_minus_gravity_along_a_stride() {
    let wheels = [
        (8.0, 0.3, 1.0),
        (8.0, 0.08, 1.0),
        (6.0, 0.2, 0.7),
        (12.0, 1.0, 1.3),
    ];
    let mut worst: f64 = 0.0;
    for (n, slope, l) in wheels {
        let w = Rimless::new(RimlessParams {
            n_spokes: n,
            slope,
            l,
            ..Default::default()
        })
        .unwrap();
        let (g, gam) = (9.81, slope);
        let (x0, t_end) = gait_stride(&w);
        for frac in [0.05, 0.25, 0.5, 0.75, 0.95] {
            let tc = frac * t_end;
            let h = 1e-3;
            let mut integ = Integrator::new(2, Options::dop853(1e-13)).unwrap();
            let (mut t, mut x) = (0.0, x0);
            let mut p = Vec::new();
            let mut xc = [0.0; 2];
            for k in [-1.0, -0.5, 0.0, 0.5, 1.0] {
                let stop = integ.integrate(
                    &w as &dyn pdw_hybrid::HybridSystem,
                    0,
                    &mut t,
                    &mut x,
                    tc + k * h,
                );
                assert_eq!(stop, StopReason::EndTime);
                p.push(hub(&w, &x));
                if k == 0.0 {
                    xc = x;
                }
            }
            let cf = w.constraint_forces(0, &xc).unwrap();
            for (j, got) in [(0, cf.tangential), (1, cf.normal)] {
                let d_h = (p[4][j] - 2.0 * p[2][j] + p[0][j]) / (h * h);
                let d_h2 = (p[3][j] - 2.0 * p[2][j] + p[1][j]) / (0.25 * h * h);
                let a = (4.0 * d_h2 - d_h) / 3.0;
                let gravity = if j == 0 {
                    g * gam.sin()
                } else {
                    -g * gam.cos()
                };
                let expect = a - gravity;
                worst = worst.max((got - expect).abs());
                assert!(
                    (got - expect).abs() < 1e-8,
                    "N = {n}, γ = {slope}, l = {l}, t = {tc}: component {j}: model {got}, \
                     Newton {expect}"
                );
            }
            // the friction the ground must supply is |tan θ| of the stance spoke (none can
            // hold a foot the ground would have to pull)
            if cf.normal > 0.0 {
                assert!((cf.friction_required - xc[0].tan().abs()).abs() < 1e-12);
            } else {
                assert_eq!(cf.friction_required, f64::INFINITY);
            }
        }
    }
    eprintln!("largest |model − Newton| = {worst:.2e} m/s²");
}

/// The normal force along the rolling gait against the closed form `(g cos(θ + γ) − l θ̇²)
/// cos θ`, with `θ̇(θ)² = ω*² + (2g/l)(cos(γ − α) − cos(θ + γ))` from energy conservation
/// (module docs of `rimless`; `ω*` the closed-form fixed point): at γ = 0.3 it turns negative
/// before the next spoke lands (the spoke would pull, ≈ −1.33 m/s² along the spoke at θ = α),
/// at the preset γ = 0.08 it stays positive (≥ 6.33 m/s² along the spoke), at γ = 1.5 it
/// reaches ≈ −33 m/s². The model's values along an integrated stride have the closed form's
/// sign and value, and its flag follows the sign.
#[test]
fn normal_force_sign_along_the_rolling_gait_follows_the_closed_form() {
    let closed = |w: &Rimless, gam: f64, th: f64| {
        let (g, l, a) = (9.81, 1.0, w.alpha());
        let om = w.rolling_fixed_point().unwrap();
        let thd2 = om * om + 2.0 * g / l * ((gam - a).cos() - (th + gam).cos());
        (g * (th + gam).cos() - l * thd2, thd2.sqrt())
    };
    for (slope, lo, hi) in [(0.3, -1.34, -1.32), (0.08, 6.32, 6.35), (1.5, -33.2, -32.9)] {
        let w = wheel(8.0, slope);
        let a = w.alpha();
        // the closed form's smallest value over the step, and the model at the same states
        let mut min_axial = f64::INFINITY;
        for i in 0..=400 {
            let th = -a + 2.0 * a * i as f64 / 400.0;
            let (axial, thd) = closed(&w, slope, th);
            min_axial = min_axial.min(axial);
            let cf = w.constraint_forces(0, &[th, thd]).unwrap();
            assert!((cf.normal - axial * th.cos()).abs() < 1e-12 * 9.81);
            assert_eq!(cf.normal < 0.0, axial < 0.0);
            let flags = w.step_flags(0, &[th, thd]).unwrap();
            assert_eq!(flags.normal_force_negative, axial < 0.0);
            assert!(!flags.knee_unlocks && !flags.swing_foot_scuffs);
        }
        assert!(
            (lo..hi).contains(&min_axial),
            "γ = {slope}: smallest g cos(θ+γ) − l θ̇² = {min_axial}"
        );
        // along an integrated stride (θ̇ from the flow, not from the energy), at 100 times
        // and just before the next spoke lands
        let (x0, t_end) = gait_stride(&w);
        let mut integ = Integrator::new(2, Options::dop853(1e-13)).unwrap();
        let (mut t, mut x) = (0.0, x0);
        let mut negative = false;
        for i in 1..=100 {
            let stop = integ.integrate(
                &w as &dyn pdw_hybrid::HybridSystem,
                0,
                &mut t,
                &mut x,
                t_end * (i as f64 / 100.0),
            );
            assert!(i == 100 || stop == StopReason::EndTime, "{stop:?}");
            let (axial, thd) = closed(&w, slope, x[0]);
            assert!((thd - x[1]).abs() < 1e-10, "θ̇ {} vs energy {thd}", x[1]);
            let cf = w.constraint_forces(0, &x).unwrap();
            assert!((cf.normal - axial * x[0].cos()).abs() < 1e-8);
            negative |= cf.normal < 0.0;
        }
        assert_eq!(negative, slope > 0.08, "γ = {slope}");
    }
}

/// The spoke impact's report against the reset map and the drawing: the impulse per unit mass
/// on the new spoke's foot is the jump of the hub's velocity (finite differences of `pose`'s
/// hub along θ, times θ̇ before and after), the trailing spoke's foot leaves the slope at the
/// rate of its drawn tip after the impact (zero height there), the energy lost is the drop of
/// `energy`, and the friction needed is `tan α`. The trailing spoke lifts off for N ≥ 5, stays
/// on the ground for N = 4 (`cos 2α = 0`) and would be driven into it for N = 3 (a negative
/// margin).
#[test]
fn spoke_impact_report_is_the_hub_velocity_jump_and_the_trailing_spoke_lifts_off() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let d = 1e-6;
    for n in [3.0, 4.0, 5.0, 8.0, 12.0] {
        let w = wheel(n, 0.1);
        let a = w.alpha();
        assert_eq!(w.scales().unwrap().force(), 9.81);
        for _ in 0..50 {
            let om: f64 = rng.random_range(0.1..3.0);
            let xm = [a, om];
            let mut xp = [0.0; 2];
            w.reset(&mut Scratch::new(), 0, SPOKE_IMPACT, &xm, &mut xp);
            let vel = |x: &[f64; 2]| {
                let (p, q) = (hub(&w, &[x[0] + d, 0.0]), hub(&w, &[x[0] - d, 0.0]));
                [
                    (p[0] - q[0]) / (2.0 * d) * x[1],
                    (p[1] - q[1]) / (2.0 * d) * x[1],
                ]
            };
            let (vm, vp) = (vel(&xm), vel(&xp));
            let r = w.impact_report(0, SPOKE_IMPACT, &xm).unwrap();
            assert_eq!(r.event, "spoke_impact");
            let new = |k| {
                r.entries
                    .iter()
                    .find(|e| e.name == "new_stance_foot" && e.kind == k)
                    .unwrap()
            };
            let (ln, lt) = (
                new(pdw_walkers::ImpulseKind::ContactNormal),
                new(pdw_walkers::ImpulseKind::ContactTangential),
            );
            assert!((lt.impulse - (vp[0] - vm[0])).abs() < 1e-8, "{r:?}");
            assert!((ln.impulse - (vp[1] - vm[1])).abs() < 1e-8, "{r:?}");
            assert!(ln.active && ln.impulse > 0.0);
            // the trailing spoke is spoke 1 of the drawing after the impact (at θ⁺ + 2α = θ⁻)
            let tip = |th: f64| w.pose(&[th, 0.0]).unwrap().links[1][1];
            assert!(tip(xp[0])[1].abs() < 1e-14);
            let rate = (tip(xp[0] + d)[1] - tip(xp[0] - d)[1]) / (2.0 * d) * xp[1];
            let tr = r.entry("trailing_foot").unwrap();
            assert!(!tr.active && tr.unilateral);
            assert!(
                (tr.rate_after - rate).abs() < 1e-8,
                "{} vs {rate}",
                tr.rate_after
            );
            // the hub does not move in the impact: the kinetic energy (per unit mass) is lost
            let e_lost = 0.5 * (xm[1] * xm[1] - xp[1] * xp[1]);
            assert!((r.energy_lost - e_lost).abs() < 1e-12 * (1.0 + e_lost));
            assert!((r.friction_required - a.tan()).abs() < 1e-12);
            let (m, _) = r.min_margin().unwrap();
            match n as u32 {
                3 => assert!(m < 0.0, "N = 3: {m}"),
                4 => assert!(tr.rate_after.abs() < 1e-12),
                _ => assert!(m > 0.0),
            }
        }
        assert!(w.impact_report(0, 1, &[a, 1.0]).is_none());
    }
}
