//! Physics claims about the rimless wheel, against geometry and energy bookkeeping.

use pdw_hybrid::{HybridSystem, Scratch, Section};
use pdw_walkers::rimless::{Rimless, RimlessParams, SPOKE_IMPACT};
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
    // and the drop of cos(θ + γ) from θ = −α to α is 2 sin α sin γ (REFERENCES §2).
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
