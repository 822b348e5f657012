//! Cross-checks of the four dynamics routes (RNEA, ABA, CRBA + Cholesky, naive dense operators)
//! on seeded random chains, and the double pendulum against its closed form.

use crate::common;

use common::*;
use faer::Side;
use pdw_soa::*;

const EPS: f64 = f64::EPSILON;

/// Condition number of the mass matrix (2-norm, symmetric positive definite).
fn cond(m: &faer::Mat<f64>) -> f64 {
    let ev = m.self_adjoint_eigenvalues(Side::Lower).unwrap();
    ev[ev.len() - 1] / ev[0]
}

#[test]
fn aba_inverts_rnea_on_random_chains() {
    let mut r = rng(1);
    for n in 1..=64 {
        for prismatic in [false, true] {
            let chain = random_chain(&mut r, n, prismatic);
            let mut ws = Workspace::new(&chain);
            let (q, qd) = random_state(&mut r, &chain);
            let tau = random_vec(&mut r, n, -5.0, 5.0);
            let ft = [r_f(&mut r), r_f(&mut r), r_f(&mut r)];
            let mut qdd = vec![0.0; n];
            aba(&chain, &mut ws, &q, &qd, &tau, Some(ft), &mut qdd).unwrap();
            let mut tau_back = vec![0.0; n];
            rnea(&chain, &mut ws, &q, &qd, &qdd, Some(ft), &mut tau_back).unwrap();
            // Backward error: RNEA of ABA's answer reproduces τ. Scale: the size of the
            // generalised forces involved (τ, 𝓜q̈ and C are all of this order).
            let scale = norm(&tau) + chain.total_mass() * 9.81 * n as f64 + 1.0;
            let err = diff_norm(&tau, &tau_back);
            assert!(
                err <= 64.0 * n as f64 * EPS * scale,
                "n={n} prismatic={prismatic}: |rnea(aba(τ)) − τ| = {err:e}, scale {scale:e}"
            );
        }
    }
}

fn r_f(r: &mut rand_chacha::ChaCha8Rng) -> f64 {
    use rand::Rng;
    r.random_range(-3.0..3.0)
}

#[test]
fn aba_agrees_with_crba_cholesky_and_naive_lu() {
    let mut r = rng(2);
    for n in 1..=64 {
        let chain = random_chain(&mut r, n, n % 3 == 0);
        let mut ws = Workspace::new(&chain);
        let mut nws = NaiveWorkspace::new(&chain);
        let (q, qd) = random_state(&mut r, &chain);
        let tau = random_vec(&mut r, n, -5.0, 5.0);
        let ft = Some([0.3, -1.0, 2.0]);
        let mut qa = vec![0.0; n];
        let mut qc = vec![0.0; n];
        let mut qn = vec![0.0; n];
        aba(&chain, &mut ws, &q, &qd, &tau, ft, &mut qa).unwrap();
        forward_dynamics_crba(&chain, &mut ws, &q, &qd, &tau, ft, &mut qc).unwrap();
        naive_forward_dynamics(&chain, &mut ws, &mut nws, &q, &qd, &tau, ft, &mut qn).unwrap();
        let kappa = cond(crba(&chain, &mut ws, &q).unwrap());
        // forward error of a backward-stable solve: ≲ κ · (backward error)
        let tol = 64.0 * n as f64 * EPS * kappa * (norm(&qa) + 1.0);
        let e_c = diff_norm(&qa, &qc);
        let e_n = diff_norm(&qa, &qn);
        assert!(
            e_c <= tol,
            "n={n}: |aba − crba| = {e_c:e} > {tol:e} (κ = {kappa:e})"
        );
        assert!(
            e_n <= tol,
            "n={n}: |aba − naive| = {e_n:e} > {tol:e} (κ = {kappa:e})"
        );
    }
}

#[test]
fn crba_mass_matrix_equals_dense_operator_product() {
    let mut r = rng(3);
    for n in [1, 2, 5, 17, 40] {
        let chain = random_chain(&mut r, n, true);
        let mut ws = Workspace::new(&chain);
        let mut nws = NaiveWorkspace::new(&chain);
        let (q, qd) = random_state(&mut r, &chain);
        let m1 = crba(&chain, &mut ws, &q).unwrap().clone();
        let m2 = naive_mass_matrix(&chain, &mut ws, &mut nws, &q, &qd).unwrap();
        let scale = m1.norm_max();
        for i in 0..n {
            for j in 0..n {
                let d = (m1[(i, j)] - m2[(i, j)]).abs();
                assert!(d <= 16.0 * n as f64 * EPS * scale, "n={n} ({i},{j}): {d:e}");
                assert_eq!(m1[(i, j)], m1[(j, i)], "crba mass matrix symmetric");
            }
        }
    }
}

/// Closed-form double pendulum (angles from the downward vertical, q2 relative; Spong–Vidyasagar
/// form) with gravity rotated by the slope: G(q) uses q1 − γ.
#[allow(clippy::type_complexity)]
fn double_pendulum_closed_form(
    p: (f64, f64, f64, f64, f64, f64, f64, f64, f64, f64),
    q: [f64; 2],
    qd: [f64; 2],
) -> ([[f64; 2]; 2], [f64; 2], [f64; 2]) {
    let (m1, m2, l1, _l2, lc1, lc2, i1, i2, g, gam) = p;
    let c2 = q[1].cos();
    let s2 = q[1].sin();
    let m11 = i1 + i2 + m1 * lc1 * lc1 + m2 * (l1 * l1 + lc2 * lc2 + 2.0 * l1 * lc2 * c2);
    let m12 = i2 + m2 * (lc2 * lc2 + l1 * lc2 * c2);
    let m22 = i2 + m2 * lc2 * lc2;
    let h = m2 * l1 * lc2 * s2;
    let cor = [
        -h * (2.0 * qd[0] * qd[1] + qd[1] * qd[1]),
        h * qd[0] * qd[0],
    ];
    let a1 = q[0] - gam;
    let grav = [
        (m1 * lc1 + m2 * l1) * g * a1.sin() + m2 * lc2 * g * (a1 + q[1]).sin(),
        m2 * lc2 * g * (a1 + q[1]).sin(),
    ];
    ([[m11, m12], [m12, m22]], cor, grav)
}

#[test]
fn double_pendulum_matches_closed_form_mass_coriolis_gravity() {
    let p = (1.3, 0.7, 1.1, 0.9, 0.45, 0.5, 0.08, 0.05, 9.81, 0.07);
    let chain = double_pendulum(p.0, p.1, p.2, p.3, p.4, p.5, p.6, p.7, p.8, p.9);
    let no_grav = chain.with_gravity(0.0, p.9).unwrap();
    let mut ws = Workspace::new(&chain);
    let mut r = rng(4);
    for _ in 0..50 {
        let q = random_vec(&mut r, 2, -3.0, 3.0);
        let qd = random_vec(&mut r, 2, -4.0, 4.0);
        let (mm, cor, grav) = double_pendulum_closed_form(p, [q[0], q[1]], [qd[0], qd[1]]);
        let m = crba(&chain, &mut ws, &q).unwrap();
        for i in 0..2 {
            for j in 0..2 {
                assert!((m[(i, j)] - mm[i][j]).abs() < 1e-14 * 4.0, "M[{i}{j}]");
            }
        }
        // Coriolis: bias forces without gravity; gravity: bias forces at q̇ = 0.
        let mut c = vec![0.0; 2];
        bias_forces(&no_grav, &mut ws, &q, &qd, &mut c).unwrap();
        for i in 0..2 {
            assert!(
                (c[i] - cor[i]).abs() < 1e-13,
                "C[{i}] {} vs {}",
                c[i],
                cor[i]
            );
        }
        bias_forces(&chain, &mut ws, &q, &[0.0, 0.0], &mut c).unwrap();
        for i in 0..2 {
            assert!(
                (c[i] - grav[i]).abs() < 1e-13,
                "G[{i}] {} vs {}",
                c[i],
                grav[i]
            );
        }
    }
}
