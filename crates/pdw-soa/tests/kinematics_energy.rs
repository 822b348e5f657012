//! Kinematics (Jacobian, J̇q̇, pseudo-inverse IK) and energy against finite differences,
//! conservation laws and the seed's leg-lift task.

use crate::common;

use common::*;
use pdw_soa::*;

#[test]
fn tip_jacobian_equals_finite_differences_of_tip_position_and_angle() {
    let mut r = rng(30);
    for n in [1usize, 3, 6, 10] {
        let chain = random_chain(&mut r, n, true);
        let mut ws = Workspace::new(&chain);
        let (q, _) = random_state(&mut r, &chain);
        let j = tip_jacobian(&chain, &mut ws, &q).unwrap().to_owned();
        let h = 1e-6;
        for k in 0..n {
            let mut qa = q.clone();
            let mut qb = q.clone();
            qa[k] += h;
            qb[k] -= h;
            let pa = tip_position(&chain, &mut ws, &qa).unwrap();
            let pb = tip_position(&chain, &mut ws, &qb).unwrap();
            for a in 0..2 {
                let fd = (pa[a] - pb[a]) / (2.0 * h);
                assert!((j[(1 + a, k)] - fd).abs() < 1e-8, "n={n} J[{},{k}]", 1 + a);
            }
            let expect_w = match chain.kinds()[k] {
                JointKind::Revolute => 1.0,
                JointKind::Prismatic { .. } => 0.0,
            };
            assert_eq!(j[(0, k)], expect_w);
        }
    }
}

#[test]
fn jdot_qdot_equals_time_derivative_of_tip_velocity() {
    let mut r = rng(31);
    for n in [2usize, 4, 7] {
        let chain = random_chain(&mut r, n, true);
        let mut ws = Workspace::new(&chain);
        let (q, qd) = random_state(&mut r, &chain);
        let a = tip_acceleration(&chain, &mut ws, &q, &qd, None).unwrap();
        let h = 1e-5;
        let qa: Vec<f64> = q.iter().zip(&qd).map(|(x, v)| x + h * v).collect();
        let qb: Vec<f64> = q.iter().zip(&qd).map(|(x, v)| x - h * v).collect();
        let va = tip_velocity(&chain, &mut ws, &qa, &qd).unwrap();
        let vb = tip_velocity(&chain, &mut ws, &qb, &qd).unwrap();
        for i in 0..3 {
            let fd = (va[i] - vb[i]) / (2.0 * h);
            assert!(
                (a[i] - fd).abs() < 1e-6 * (1.0 + fd.abs()),
                "n={n} row {i}: {} vs {fd}",
                a[i]
            );
        }
    }
}

/// The seed's 5-DoF kneed biped (Table 3.1: shanks 2 kg, thighs 3 kg, all segments 2 m) with
/// the stance foot as base and the swing foot as tip (joint 5 at the foot, zero tip offset).
fn seed_biped() -> Chain {
    let seg = |m: f64, dir: f64| Link::rod([0.0, 2.0 * dir], m);
    ChainBuilder::new()
        .revolute(seg(2.0, 1.0)) // stance shank, ankle → knee
        .revolute(seg(3.0, 1.0)) // stance thigh, knee → hip
        .revolute(seg(3.0, -1.0)) // swing thigh, hip → knee
        .revolute(seg(2.0, -1.0)) // swing shank, knee → foot
        .revolute(Link {
            to_next: [0.0, 0.0],
            com: [0.0, 0.0],
            mass: 1e-3,
            inertia: 1e-6,
        })
        .build()
        .unwrap()
}

#[test]
fn leg_lift_task_of_seed_section_5_1_tip_follows_commanded_path_to_1e_9() {
    // Lift the swing foot 0.5 m, hold, put it back (seed §5.1, Fig. 5.1–5.2), by resolved-rate
    // steps q̇ = J# v (seed eq. 2.26) with a Newton correction to the commanded point.
    let chain = seed_biped();
    let mut ws = Workspace::new(&chain);
    let mut q = vec![0.12, -0.05, 0.35, 0.05, 0.0];
    let p0 = tip_position(&chain, &mut ws, &q).unwrap();
    let lift = 0.5;
    let profile = |t: f64| -> (f64, f64) {
        // height and its rate: raise on [0,1] s, hold on [1,2] s, lower on [2,3] s
        use std::f64::consts::PI;
        if t < 1.0 {
            (
                0.5 * lift * (1.0 - (PI * t).cos()),
                0.5 * lift * PI * (PI * t).sin(),
            )
        } else if t < 2.0 {
            (lift, 0.0)
        } else if t < 3.0 {
            let s = t - 2.0;
            (
                0.5 * lift * (1.0 + (PI * s).cos()),
                -0.5 * lift * PI * (PI * s).sin(),
            )
        } else {
            (0.0, 0.0)
        }
    };
    let dt = 0.01;
    let mut qd = vec![0.0; 5];
    let mut max_err: f64 = 0.0;
    let mut max_pred: f64 = 0.0;
    for step in 0..300 {
        let t = step as f64 * dt;
        let (_, vz) = profile(t);
        pseudo_inverse_rates(&chain, &mut ws, &q, [0.0, vz], &mut qd).unwrap();
        // J J# v = v
        let v = tip_velocity(&chain, &mut ws, &q, &qd).unwrap();
        assert!(
            v[1].abs() < 1e-12 && (v[2] - vz).abs() < 1e-12,
            "J J# v = v"
        );
        for k in 0..5 {
            q[k] += dt * qd[k];
        }
        let (h1, _) = profile(t + dt);
        let target = [p0[0], p0[1] + h1];
        let p_pred = tip_position(&chain, &mut ws, &q).unwrap();
        max_pred = max_pred
            .max(((p_pred[0] - target[0]).powi(2) + (p_pred[1] - target[1]).powi(2)).sqrt());
        inverse_kinematics(&chain, &mut ws, &mut q, target, 1e-12, 20).unwrap();
        let p = tip_position(&chain, &mut ws, &q).unwrap();
        let err = ((p[0] - target[0]).powi(2) + (p[1] - target[1]).powi(2)).sqrt();
        max_err = max_err.max(err);
    }
    assert!(max_err <= 1e-9, "tracking error {max_err:e}");
    // the rate step alone is a first-order predictor: O(dt²) per step
    assert!(max_pred < 5e-3, "predictor error {max_pred:e}");
    let pend = tip_position(&chain, &mut ws, &q).unwrap();
    assert!((pend[0] - p0[0]).abs() < 1e-9 && (pend[1] - p0[1]).abs() < 1e-9);
}

#[test]
fn kinetic_energy_is_half_qdot_mass_matrix_qdot() {
    let mut r = rng(32);
    for n in [1usize, 4, 9] {
        let chain = random_chain(&mut r, n, true);
        let mut ws = Workspace::new(&chain);
        let (q, qd) = random_state(&mut r, &chain);
        let t = kinetic_energy(&chain, &mut ws, &q, &qd).unwrap();
        let m = crba(&chain, &mut ws, &q).unwrap();
        let mut t2 = 0.0;
        for i in 0..n {
            for j in 0..n {
                t2 += 0.5 * qd[i] * m[(i, j)] * qd[j];
            }
        }
        assert!((t - t2).abs() < 1e-12 * (1.0 + t2));
    }
}

#[test]
fn gravity_torques_are_gradient_of_potential_energy() {
    let mut r = rng(33);
    let chain = random_chain(&mut r, 6, true);
    let mut ws = Workspace::new(&chain);
    let (q, _) = random_state(&mut r, &chain);
    let mut g = vec![0.0; 6];
    bias_forces(&chain, &mut ws, &q, &[0.0; 6], &mut g).unwrap();
    let h = 1e-6;
    for k in 0..6 {
        let mut qa = q.clone();
        let mut qb = q.clone();
        qa[k] += h;
        qb[k] -= h;
        let fd = (potential_energy(&chain, &mut ws, &qa).unwrap()
            - potential_energy(&chain, &mut ws, &qb).unwrap())
            / (2.0 * h);
        assert!(
            (g[k] - fd).abs() < 1e-6 * (1.0 + fd.abs()),
            "G_{k}: {} vs {fd}",
            g[k]
        );
    }
}

fn rk4_energy_drift(chain: &Chain, q0: &[f64], qd0: &[f64], dt: f64, t_end: f64) -> f64 {
    let n = chain.dof();
    let mut ws = Workspace::new(chain);
    let tau = vec![0.0; n];
    let mut f = |q: &[f64], v: &[f64], out: &mut [f64]| {
        aba(chain, &mut ws, q, v, &tau, None, out).unwrap();
    };
    let (mut q, mut v) = (q0.to_vec(), qd0.to_vec());
    let mut wse = Workspace::new(chain);
    let e0 = total_energy(chain, &mut wse, &q, &v).unwrap();
    let mut drift: f64 = 0.0;
    let steps = (t_end / dt).round() as usize;
    let (mut a1, mut a2, mut a3, mut a4) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let (mut qt, mut vt) = (vec![0.0; n], vec![0.0; n]);
    for _ in 0..steps {
        f(&q, &v, &mut a1);
        for k in 0..n {
            qt[k] = q[k] + 0.5 * dt * v[k];
            vt[k] = v[k] + 0.5 * dt * a1[k];
        }
        let v2 = vt.clone();
        f(&qt, &vt, &mut a2);
        for k in 0..n {
            qt[k] = q[k] + 0.5 * dt * v2[k];
            vt[k] = v[k] + 0.5 * dt * a2[k];
        }
        let v3 = vt.clone();
        f(&qt, &vt, &mut a3);
        for k in 0..n {
            qt[k] = q[k] + dt * v3[k];
            vt[k] = v[k] + dt * a3[k];
        }
        let v4 = vt.clone();
        f(&qt, &vt, &mut a4);
        for k in 0..n {
            q[k] += dt / 6.0 * (v[k] + 2.0 * v2[k] + 2.0 * v3[k] + v4[k]);
            v[k] += dt / 6.0 * (a1[k] + 2.0 * a2[k] + 2.0 * a3[k] + a4[k]);
        }
        let e = total_energy(chain, &mut wse, &q, &v).unwrap();
        drift = drift.max((e - e0).abs());
    }
    drift
}

#[test]
fn free_n_link_pendulum_conserves_energy_with_fourth_order_drift() {
    let mut r = rng(34);
    let chain = random_chain(&mut r, 4, true);
    let (q, qd) = random_state(&mut r, &chain);
    let scale = chain.total_mass() * 9.81 * 4.0;
    let d1 = rk4_energy_drift(&chain, &q, &qd, 2e-3, 5.0);
    let d2 = rk4_energy_drift(&chain, &q, &qd, 1e-3, 5.0);
    assert!(
        d2 < 1e-7 * scale,
        "energy drift {d2:e} J over 5 s (scale {scale} J)"
    );
    // halving the step divides the error by ~16 (RK4): the drift is integration error,
    // not a modelling error in the dynamics.
    assert!(
        d1 / d2 > 10.0,
        "drift ratio {} (d1 {d1:e}, d2 {d2:e})",
        d1 / d2
    );
}
