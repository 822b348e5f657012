//! Locked joints, closed chains and impacts against independent formulations.

use crate::common;

use common::*;
use faer::linalg::solvers::DenseSolveCore;
use faer::prelude::*;
use faer::Mat;
use pdw_soa::*;

fn rot(t: f64, v: [f64; 2]) -> [f64; 2] {
    let (s, c) = t.sin_cos();
    [c * v[0] - s * v[1], s * v[0] + c * v[1]]
}

/// The chain with joint `l` (≥ 1) welded at angle `ql`: links l−1 and l merged into one rigid
/// link by the parallel-axis theorem.
#[allow(clippy::needless_range_loop)]
fn merged_chain(chain: &Chain, l: usize, ql: f64) -> Chain {
    let links = chain.links();
    let (a, b) = (links[l - 1], links[l]);
    let off = a.to_next;
    let cb = {
        let r = rot(ql, b.com);
        [off[0] + r[0], off[1] + r[1]]
    };
    let m = a.mass + b.mass;
    let c = [
        (a.mass * a.com[0] + b.mass * cb[0]) / m,
        (a.mass * a.com[1] + b.mass * cb[1]) / m,
    ];
    let d2 = |p: [f64; 2]| (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2);
    let inertia = a.inertia + a.mass * d2(a.com) + b.inertia + b.mass * d2(cb);
    let tn = rot(ql, b.to_next);
    let merged = Link {
        to_next: [off[0] + tn[0], off[1] + tn[1]],
        com: c,
        mass: m,
        inertia,
    };
    let mut kinds = Vec::new();
    let mut out = Vec::new();
    for k in 0..chain.dof() {
        if k == l {
            continue;
        }
        kinds.push(chain.kinds()[k]);
        out.push(if k == l - 1 { merged } else { links[k] });
    }
    Chain::new(kinds, out, chain.gravity(), chain.slope()).unwrap()
}

#[test]
#[allow(clippy::needless_range_loop)]
fn pseudo_joint_equals_chain_with_locked_joint_merged_into_one_rigid_link() {
    let mut r = rng(20);
    for n in [2usize, 3, 5, 8] {
        for l in 1..n {
            let chain = random_chain(&mut r, n, false);
            let mut ws = Workspace::new(&chain);
            let (q, mut qd) = random_state(&mut r, &chain);
            qd[l] = 0.0; // a locked joint does not move
            let tau = random_vec(&mut r, n, -3.0, 3.0);
            let ft = Some([0.2, 1.0, -0.5]);
            let mut qdd = vec![0.0; n];
            let mut lock = vec![0.0; n];
            pseudo_joint_dynamics(
                &chain,
                &mut ws,
                &q,
                &qd,
                &tau,
                &[l],
                ft,
                &mut qdd,
                &mut lock,
            )
            .unwrap();
            assert_eq!(qdd[l], 0.0);
            let merged = merged_chain(&chain, l, q[l]);
            let mut wm = Workspace::new(&merged);
            let sel =
                |v: &[f64]| -> Vec<f64> { (0..n).filter(|&k| k != l).map(|k| v[k]).collect() };
            let mut qdd_m = vec![0.0; n - 1];
            // the next joint's angle is relative to link l, which the merge removes
            let mut qm = q.clone();
            if l + 1 < n {
                qm[l + 1] += q[l];
            }
            aba(
                &merged,
                &mut wm,
                &sel(&qm),
                &sel(&qd),
                &sel(&tau),
                ft,
                &mut qdd_m,
            )
            .unwrap();
            let e = diff_norm(&sel(&qdd), &qdd_m);
            assert!(e <= 1e-11 * (1.0 + norm(&qdd_m)), "n={n} l={l}: {e:e}");
            // locking torque: RNEA with the constrained accelerations needs τ + τ_lock
            let mut tau_needed = vec![0.0; n];
            rnea(&chain, &mut ws, &q, &qd, &qdd, ft, &mut tau_needed).unwrap();
            let expect = tau_needed[l] - tau[l];
            assert!(
                (lock[l] - expect).abs() <= 1e-11 * (1.0 + expect.abs()),
                "lock torque"
            );
            for k in 0..n {
                if k != l {
                    assert_eq!(lock[k], 0.0);
                }
            }
        }
    }
}

#[test]
#[allow(clippy::needless_range_loop)]
fn pseudo_joints_match_seed_partitioned_inverse_eq_3_23() {
    // 5-DoF kneed biped: knees (joints 1 and 3) locked, seed §3.4.
    let mut r = rng(21);
    let chain = random_chain(&mut r, 5, false);
    let mut ws = Workspace::new(&chain);
    let (q, mut qd) = random_state(&mut r, &chain);
    qd[1] = 0.0;
    qd[3] = 0.0;
    let tau = random_vec(&mut r, 5, -2.0, 2.0);
    let mut qdd = vec![0.0; 5];
    let mut lock = vec![0.0; 5];
    pseudo_joint_dynamics(
        &chain,
        &mut ws,
        &q,
        &qd,
        &tau,
        &[1, 3],
        None,
        &mut qdd,
        &mut lock,
    )
    .unwrap();
    // dense: D = 𝓜⁻¹, E = −𝓜⁻¹ C, partition real r = {0,2,4}, pseudo p = {1,3}
    let m = crba(&chain, &mut ws, &q).unwrap().clone();
    let mut c = vec![0.0; 5];
    bias_forces(&chain, &mut ws, &q, &qd, &mut c).unwrap();
    let d = m.partial_piv_lu().inverse();
    let e: Vec<f64> = (0..5)
        .map(|i| -(0..5).map(|j| d[(i, j)] * c[j]).sum::<f64>())
        .collect();
    let (rr, pp) = ([0usize, 2, 4], [1usize, 3]);
    let d4 = Mat::from_fn(2, 2, |i, j| d[(pp[i], pp[j])]);
    let d4i = d4.partial_piv_lu().inverse();
    // τ_p (total) = −d4⁻¹ (d3 τ_r + e2)
    let rhs: Vec<f64> = (0..2)
        .map(|i| rr.iter().map(|&j| d[(pp[i], j)] * tau[j]).sum::<f64>() + e[pp[i]])
        .collect();
    let tp: Vec<f64> = (0..2)
        .map(|i| -(0..2).map(|j| d4i[(i, j)] * rhs[j]).sum::<f64>())
        .collect();
    for (i, &k) in rr.iter().enumerate() {
        let _ = i;
        let v: f64 = rr.iter().map(|&j| d[(k, j)] * tau[j]).sum::<f64>()
            + pp.iter()
                .enumerate()
                .map(|(a, &j)| d[(k, j)] * tp[a])
                .sum::<f64>()
            + e[k];
        assert!(
            (qdd[k] - v).abs() < 1e-10 * (1.0 + v.abs()),
            "q̈_{k}: {} vs {v}",
            qdd[k]
        );
    }
    for (a, &k) in pp.iter().enumerate() {
        let expect = tp[a] - tau[k];
        assert!(
            (lock[k] - expect).abs() < 1e-10 * (1.0 + expect.abs()),
            "lock_{k}"
        );
    }
}

#[test]
fn closed_chain_zero_tip_acceleration_and_force_equals_kkt_solve() {
    let mut r = rng(22);
    for n in [2usize, 3, 5, 8, 13] {
        let chain = random_chain(&mut r, n, n > 4);
        let mut ws = Workspace::new(&chain);
        let (q, qd) = random_state(&mut r, &chain);
        let tau = random_vec(&mut r, n, -3.0, 3.0);
        let mut qdd = vec![0.0; n];
        let sol = closed_chain_dynamics(&chain, &mut ws, &q, &qd, &tau, &mut qdd).unwrap();
        let at = tip_acceleration(&chain, &mut ws, &q, &qd, Some(&qdd)).unwrap();
        let scale = 1.0 + norm(&qdd);
        assert!(
            at[1].abs() < 1e-11 * scale && at[2].abs() < 1e-11 * scale,
            "n={n}: tip acc {at:?}"
        );
        // KKT: [𝓜 Jᵀ; J 0] [q̈; f] = [τ − C; −J̇q̇]
        let m = crba(&chain, &mut ws, &q).unwrap().clone();
        let mut c = vec![0.0; n];
        bias_forces(&chain, &mut ws, &q, &qd, &mut c).unwrap();
        let jdqd = tip_acceleration(&chain, &mut ws, &q, &qd, None).unwrap();
        let j = tip_jacobian_linear(&chain, &mut ws, &q).unwrap().to_owned();
        let mut k = Mat::<f64>::zeros(n + 2, n + 2);
        let mut b = Mat::<f64>::zeros(n + 2, 1);
        for i in 0..n {
            for jj in 0..n {
                k[(i, jj)] = m[(i, jj)];
            }
            for a in 0..2 {
                k[(i, n + a)] = j[(a, i)];
                k[(n + a, i)] = j[(a, i)];
            }
            b[(i, 0)] = tau[i] - c[i];
        }
        b[(n, 0)] = -jdqd[1];
        b[(n + 1, 0)] = -jdqd[2];
        let x = k.partial_piv_lu().solve(&b);
        for i in 0..n {
            assert!((x[(i, 0)] - qdd[i]).abs() < 1e-9 * scale, "n={n} q̈_{i}");
        }
        let fs = 1.0 + sol.tip_force[0].abs() + sol.tip_force[1].abs();
        assert!(
            (x[(n, 0)] - sol.tip_force[0]).abs() < 1e-9 * fs,
            "n={n} f_y"
        );
        assert!(
            (x[(n + 1, 0)] - sol.tip_force[1]).abs() < 1e-9 * fs,
            "n={n} f_z"
        );
    }
}

#[test]
fn closed_chain_base_reaction_satisfies_newtons_law_for_the_whole_chain() {
    // Σ external forces = d/dt (linear momentum): F_0 (ground on base) − f_c (tip is pushed
    // back by the environment) + Σ m g = dP/dt, with dP/dt by central differences.
    let mut r = rng(23);
    for n in [2usize, 4, 6] {
        let chain = random_chain(&mut r, n, false);
        let mut ws = Workspace::new(&chain);
        let (q, qd) = random_state(&mut r, &chain);
        let tau = vec![0.0; n];
        let mut qdd = vec![0.0; n];
        let sol = closed_chain_dynamics(&chain, &mut ws, &q, &qd, &tau, &mut qdd).unwrap();
        let h = 1e-5;
        let state = |s: f64| -> (Vec<f64>, Vec<f64>) {
            (
                (0..n)
                    .map(|k| q[k] + s * qd[k] + 0.5 * s * s * qdd[k])
                    .collect(),
                (0..n).map(|k| qd[k] + s * qdd[k]).collect(),
            )
        };
        let (qa, va) = state(h);
        let (qb, vb) = state(-h);
        let pa = linear_momentum(&chain, &mut ws, &qa, &va).unwrap();
        let pb = linear_momentum(&chain, &mut ws, &qb, &vb).unwrap();
        let g = chain.base_acceleration();
        let mt = chain.total_mass();
        for a in 0..2 {
            let pdot = (pa[a] - pb[a]) / (2.0 * h);
            let sum = sol.base_reaction[1 + a] - sol.tip_force[a] - mt * g[1 + a];
            assert!(
                (sum - pdot).abs() < 1e-5 * (1.0 + mt * 9.81),
                "n={n} axis {a}: {sum} vs {pdot}"
            );
        }
    }
}

/// Free-floating planar chain: two virtual sliders (y, z) at the base, then revolute links.
/// The sliders carry a negligible mass (1e-13 kg): a massive slider would be pushed by the
/// ground across its guide, an external impulse that breaks the conservation law tested.
fn floating_chain(r: &mut rand_chacha::ChaCha8Rng, nrev: usize) -> Chain {
    let body = random_chain(r, nrev, false);
    let mut b = ChainBuilder::new()
        .gravity(9.81)
        .prismatic(
            [1.0, 0.0],
            Link {
                to_next: [0.0, 0.0],
                com: [0.0, 0.0],
                mass: 1e-13,
                inertia: 0.0,
            },
        )
        .prismatic(
            [0.0, 1.0],
            Link {
                to_next: [0.0, 0.0],
                com: [0.0, 0.0],
                mass: 1e-13,
                inertia: 0.0,
            },
        );
    for l in body.links() {
        b = b.revolute(*l);
    }
    b.build().unwrap()
}

#[test]
fn tip_impact_stops_tip_conserves_angular_momentum_about_contact_and_loses_energy() {
    let mut r = rng(24);
    for nrev in [2usize, 3, 5] {
        let chain = floating_chain(&mut r, nrev);
        let n = chain.dof();
        let mut ws = Workspace::new(&chain);
        let (q, qd) = random_state(&mut r, &chain);
        let mut qp = vec![0.0; n];
        let mut imp = vec![0.0; 2];
        tip_impact(&chain, &mut ws, &q, &qd, &[], &mut qp, &mut imp).unwrap();
        let vt = tip_velocity(&chain, &mut ws, &q, &qp).unwrap();
        let v0 = tip_velocity(&chain, &mut ws, &q, &qd).unwrap();
        let vs = 1.0 + v0[1].abs() + v0[2].abs();
        assert!(
            vt[1].abs() < 1e-12 * vs && vt[2].abs() < 1e-12 * vs,
            "tip velocity {vt:?}"
        );
        let tip = tip_position(&chain, &mut ws, &q).unwrap();
        let l0 = angular_momentum_about(&chain, &mut ws, &q, &qd, tip).unwrap();
        let l1 = angular_momentum_about(&chain, &mut ws, &q, &qp, tip).unwrap();
        assert!(
            (l0 - l1).abs() < 1e-11 * (1.0 + l0.abs()),
            "L about contact {l0} → {l1}"
        );
        // linear momentum changes by the environment's impulse on the tip, −Λ
        let p0 = linear_momentum(&chain, &mut ws, &q, &qd).unwrap();
        let p1 = linear_momentum(&chain, &mut ws, &q, &qp).unwrap();
        for a in 0..2 {
            assert!(
                (p1[a] - p0[a] + imp[a]).abs() < 1e-11 * (1.0 + imp[a].abs()),
                "momentum"
            );
        }
        let t0 = kinetic_energy(&chain, &mut ws, &q, &qd).unwrap();
        let t1 = kinetic_energy(&chain, &mut ws, &q, &qp).unwrap();
        assert!(t1 <= t0, "kinetic energy must not increase");
        // exact identity ΔT = −½ (J q̇⁻)ᵀ Λ
        let dt = -0.5 * (v0[1] * imp[0] + v0[2] * imp[1]);
        assert!(
            ((t1 - t0) - dt).abs() < 1e-12 * (1.0 + t0),
            "ΔT {} vs {}",
            t1 - t0,
            dt
        );
    }
}

#[test]
fn knee_strike_zeroes_joint_rate_conserves_angular_momentum_about_base_pin() {
    let mut r = rng(25);
    for n in [3usize, 5] {
        let chain = random_chain(&mut r, n, false);
        let mut ws = Workspace::new(&chain);
        let (q, qd) = random_state(&mut r, &chain);
        let mut qp = vec![0.0; n];
        let mut imp = vec![0.0; 1];
        joint_lock_impact(&chain, &mut ws, &q, &qd, &[1], &mut qp, &mut imp).unwrap();
        assert!(qp[1].abs() < 1e-13 * (1.0 + qd[1].abs()));
        let l0 = angular_momentum_about(&chain, &mut ws, &q, &qd, [0.0, 0.0]).unwrap();
        let l1 = angular_momentum_about(&chain, &mut ws, &q, &qp, [0.0, 0.0]).unwrap();
        assert!((l0 - l1).abs() < 1e-12 * (1.0 + l0.abs()));
        let t0 = kinetic_energy(&chain, &mut ws, &q, &qd).unwrap();
        let t1 = kinetic_energy(&chain, &mut ws, &q, &qp).unwrap();
        assert!(((t1 - t0) + 0.5 * qd[1] * imp[0]).abs() < 1e-12 * (1.0 + t0));
        // heel strike and knee lock in the same instant
        let mut imp3 = vec![0.0; 3];
        tip_impact(&chain, &mut ws, &q, &qd, &[n - 2], &mut qp, &mut imp3).unwrap();
        let vt = tip_velocity(&chain, &mut ws, &q, &qp).unwrap();
        assert!(vt[1].abs() < 1e-12 && vt[2].abs() < 1e-12 && qp[n - 2].abs() < 1e-12);
    }
}

#[test]
fn general_impulsive_constraint_matches_dense_formula() {
    let mut r = rng(26);
    let chain = random_chain(&mut r, 6, true);
    let mut ws = Workspace::new(&chain);
    let (q, qd) = random_state(&mut r, &chain);
    let a = Mat::from_fn(3, 6, |i, j| ((i * 7 + j * 3) % 5) as f64 - 2.0);
    let mut qp = vec![0.0; 6];
    let mut imp = vec![0.0; 3];
    impulsive_constraint(&chain, &mut ws, &q, &qd, a.as_ref(), &mut qp, &mut imp).unwrap();
    let m = crba(&chain, &mut ws, &q).unwrap().clone();
    let mi = m.partial_piv_lu().inverse();
    let qdm = Mat::from_fn(6, 1, |i, _| qd[i]);
    let s = &a * &mi * a.transpose();
    let lam = s.partial_piv_lu().solve(&a * &qdm);
    let qpe = &qdm - &mi * a.transpose() * &lam;
    for i in 0..6 {
        assert!((qpe[(i, 0)] - qp[i]).abs() < 1e-10 * (1.0 + qp[i].abs()));
    }
    for i in 0..3 {
        assert!((lam[(i, 0)] - imp[i]).abs() < 1e-10 * (1.0 + imp[i].abs()));
    }
    // dependent rows are a typed error
    let dep = Mat::from_fn(2, 6, |_, j| j as f64);
    let mut imp2 = vec![0.0; 2];
    let e = impulsive_constraint(&chain, &mut ws, &q, &qd, dep.as_ref(), &mut qp, &mut imp2)
        .unwrap_err();
    assert!(matches!(e, SoaError::SingularConstraint { .. }), "{e}");
}
