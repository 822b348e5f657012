//! Impacts with unilateral contacts and stops (`pdw_soa::unilateral_impact`): the bilateral case
//! against the kernel's plastic impact, complementarity of the solution and its uniqueness by
//! brute force over every active set, energy never gained, momentum about the contact point
//! conserved, and the exact Jacobian against central differences.

use crate::common::{random_vec, rng};
use pdw_soa::{
    angular_momentum_about, kinetic_energy, tip_impact, tip_impact_derivatives, unilateral_impact,
    Chain, ChainBuilder, ImpactItem, ImpactRow, Link, Workspace,
};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// A floating chain (prismatic `y`, `z` with negligible mass, then `n` revolute links) shaped
/// like a walker: a stance leg of `m` links going up, a swing leg of `m` links hanging down.
fn floating_walker(rng: &mut ChaCha8Rng, m: usize) -> Chain {
    let base = Link {
        to_next: [0.0, 0.0],
        com: [0.0, 0.0],
        mass: 1e-30,
        inertia: 0.0,
    };
    let mut b = ChainBuilder::new()
        .gravity(9.81)
        .slope(0.05)
        .prismatic([1.0, 0.0], base)
        .prismatic([0.0, 1.0], base);
    for k in 0..2 * m {
        let len = rng.random_range(0.4..1.0);
        let s = if k < m { 1.0 } else { -1.0 };
        b = b.revolute(Link {
            to_next: [0.0, s * len],
            com: [
                rng.random_range(-0.05..0.05),
                s * rng.random_range(0.2..0.8) * len,
            ],
            mass: rng.random_range(0.5..3.0),
            inertia: rng.random_range(0.0..0.1),
        });
    }
    b.build().expect("floating walker")
}

/// A walker-like configuration: knees near straight, legs apart.
fn walker_state(rng: &mut ChaCha8Rng, m: usize) -> (Vec<f64>, Vec<f64>) {
    let n = 2 * m + 2;
    let mut q = vec![0.0; n];
    let mut qd = random_vec(rng, n, -1.5, 1.5);
    q[2] = rng.random_range(0.1..0.3);
    for k in 1..m {
        q[2 + k] = rng.random_range(0.0..0.2);
        q[2 + m + k] = -rng.random_range(0.0..0.2);
    }
    q[2 + m] = -2.0 * q[2] + rng.random_range(-0.05..0.05);
    qd[0] = 0.0;
    qd[1] = 0.0;
    (q, qd)
}

fn stop(j: usize, sign: f64, unilateral: bool) -> ImpactItem {
    ImpactItem {
        row: ImpactRow::Stop { joint: j, sign },
        unilateral,
    }
}

/// A heel strike's two feet on feet of radius `rad`: the striking foot held (bilateral), the
/// trailing foot free to leave the ground (unilateral).
fn heel_strike_feet(rad: f64) -> [ImpactItem; 2] {
    [
        ImpactItem {
            row: ImpactRow::TipContact {
                offset: [0.0, -rad],
            },
            unilateral: false,
        },
        ImpactItem {
            row: ImpactRow::BaseContact { radius: rad },
            unilateral: true,
        },
    ]
}

#[test]
fn bilateral_heel_strike_equals_the_kernel_tip_impact() {
    let mut r = rng(11);
    for _ in 0..20 {
        let ch = floating_walker(&mut r, 2);
        let (q, qd) = walker_state(&mut r, 2);
        let n = ch.dof();
        let locked = [3usize, 5];
        let items = [
            ImpactItem {
                row: ImpactRow::TipContact { offset: [0.0, 0.0] },
                unilateral: false,
            },
            stop(3, 1.0, false),
            stop(5, -1.0, false),
        ];
        let mut v = vec![0.0; n];
        let mut jac = vec![0.0; 2 * n * n];
        let sol =
            unilateral_impact(&ch, &q, &qd, &items, None, &mut v, Some(&mut jac)).expect("impact");
        let mut v0 = vec![0.0; n];
        let mut imp = vec![0.0; 4];
        tip_impact(
            &ch,
            &mut Workspace::new(&ch),
            &q,
            &qd,
            &locked,
            &mut v0,
            &mut imp,
        )
        .expect("tip impact");
        let mut jac0 = vec![0.0; 2 * n * n];
        let mut v1 = vec![0.0; n];
        tip_impact_derivatives(&ch, &q, &qd, &locked, &mut v1, &mut jac0).expect("derivatives");
        for k in 0..n {
            assert!(
                (v[k] - v0[k]).abs() < 1e-12,
                "q̇⁺[{k}]: {} vs {}",
                v[k],
                v0[k]
            );
        }
        for (a, b) in jac.iter().zip(&jac0) {
            assert!(
                (a - b).abs() < 1e-10 * (1.0 + b.abs()),
                "jacobian {a} vs {b}"
            );
        }
        // the kernel's impulse is on the environment: the ground's on the foot is its negative
        assert!((sol.items[0].impulse[0] + imp[0]).abs() < 1e-10 * (1.0 + imp[0].abs()));
        assert!((sol.items[0].impulse[1] + imp[1]).abs() < 1e-10 * (1.0 + imp[1].abs()));
    }
}

/// Every active set of the unilateral items by brute force: the solver's is the complementary
/// one, and no other is (the stops' LCP has a positive definite Delassus matrix: one solution).
#[test]
fn the_complementarity_solution_is_the_only_one() {
    let mut r = rng(12);
    let mut released = [0usize; 4];
    let mut unsolved = 0;
    for case in 0..200 {
        let ch = floating_walker(&mut r, 2);
        let (q, qd) = walker_state(&mut r, 2);
        let n = ch.dof();
        let rad = if case % 2 == 0 { 0.0 } else { 0.1 };
        let [strike, trail] = heel_strike_feet(rad);
        let items = [strike, trail, stop(3, 1.0, true), stop(5, -1.0, true)];
        let mut v = vec![0.0; n];
        let Ok(sol) = unilateral_impact(&ch, &q, &qd, &items, None, &mut v, None) else {
            continue;
        };
        // every active set of the unilateral items, by brute force
        let mut found = 0;
        for code in 0..8u32 {
            let hold = [true, code & 1 == 1, code & 2 == 2, code & 4 == 4];
            let mut w = vec![0.0; n];
            if let Ok(s) = unilateral_impact(&ch, &q, &qd, &items, Some(&hold), &mut w, None) {
                if s.complementary {
                    found += 1;
                    let d: f64 = w
                        .iter()
                        .zip(&v)
                        .map(|(a, b): (&f64, &f64)| (a - b).abs())
                        .sum();
                    assert!(
                        d < 1e-9,
                        "case {case}: two complementary solutions differ by {d}"
                    );
                }
            }
        }
        // with sticking contacts the problem is a P-matrix LCP only in the stops; a contact
        // whose tangential row comes and goes with its normal one can leave it without a
        // solution (found by brute force too): the solver says so, never claims one
        assert_eq!(sol.complementary, found >= 1, "case {case}");
        if !sol.complementary {
            unsolved += 1;
            continue;
        }
        #[allow(clippy::needless_range_loop)] // item i, its sign row and its counter
        for i in 1..4 {
            let it = &sol.items[i];
            let sign_row = if i == 1 { 1 } else { 0 };
            if it.active {
                assert!(
                    it.impulse[sign_row] >= -1e-9,
                    "case {case} item {i}: {it:?}"
                );
                assert!(
                    it.rate[sign_row].abs() < 1e-9,
                    "case {case} item {i}: {it:?}"
                );
            } else {
                released[i] += 1;
                assert!(it.rate[sign_row] >= -1e-9, "case {case} item {i}: {it:?}");
                assert_eq!(it.impulse, [0.0, 0.0]);
            }
        }
        // energy never gained, and ΔT equals the kernel's kinetic energies
        let mut ws = Workspace::new(&ch);
        let t0 = kinetic_energy(&ch, &mut ws, &q, &qd).expect("T");
        let t1 = kinetic_energy(&ch, &mut ws, &q, &v).expect("T");
        assert!(sol.energy_lost >= -1e-12 * t0, "case {case}: energy gained");
        assert!(
            (t0 - t1 - sol.energy_lost).abs() < 1e-10 * t0.max(1.0),
            "case {case}: ΔT {} vs {}",
            t0 - t1,
            sol.energy_lost
        );
    }
    // the random cases exercise releases of each kind; unsolvable ones are rare
    assert!(
        released[1] > 0 && released[2] > 0 && released[3] > 0,
        "{released:?}"
    );
    assert!(
        unsolved <= 10,
        "{unsolved} of 200 random impacts without a solution"
    );
}

/// A round foot rolling at the base, with a knee stop struck: the contact point is at rest after
/// the impact and the angular momentum about it is conserved (no other impulse has a moment
/// about it: the stop is internal).
#[test]
fn rolling_contact_impact_conserves_momentum_about_the_contact_point() {
    let mut r = rng(13);
    for _ in 0..30 {
        let ch = floating_walker(&mut r, 2);
        let (q, mut qd) = walker_state(&mut r, 2);
        let n = ch.dof();
        let rad = r.random_range(0.01..0.3);
        qd[0] = -rad * qd[2];
        let items = [
            ImpactItem {
                row: ImpactRow::BaseContact { radius: rad },
                unilateral: false,
            },
            stop(5, -1.0, false),
            stop(3, 1.0, false),
        ];
        let mut v = vec![0.0; n];
        unilateral_impact(&ch, &q, &qd, &items, Some(&[true; 3]), &mut v, None).expect("impact");
        assert!((v[0] + rad * v[2]).abs() < 1e-12, "contact point slides");
        assert!(v[1].abs() < 1e-12, "contact point lifts");
        assert!(v[3].abs() < 1e-12 && v[5].abs() < 1e-12, "stops hold");
        let mut ws = Workspace::new(&ch);
        let contact = [q[0], q[1] - rad];
        let h0 = angular_momentum_about(&ch, &mut ws, &q, &qd, contact).expect("H");
        let h1 = angular_momentum_about(&ch, &mut ws, &q, &v, contact).expect("H");
        assert!((h0 - h1).abs() < 1e-12 * (1.0 + h0.abs()), "H {h0} -> {h1}");
    }
}

#[test]
fn the_jacobian_matches_central_differences() {
    let mut r = rng(14);
    for _ in 0..10 {
        let ch = floating_walker(&mut r, 2);
        let (q, qd) = walker_state(&mut r, 2);
        let n = ch.dof();
        let items = [
            ImpactItem {
                row: ImpactRow::TipContact {
                    offset: [0.0, -0.07],
                },
                unilateral: false,
            },
            ImpactItem {
                row: ImpactRow::BaseContact { radius: 0.07 },
                unilateral: true,
            },
            stop(3, 1.0, true),
            stop(5, -1.0, true),
        ];
        let hold = [true, false, true, true];
        let mut v = vec![0.0; n];
        let mut jac = vec![0.0; 2 * n * n];
        unilateral_impact(&ch, &q, &qd, &items, Some(&hold), &mut v, Some(&mut jac))
            .expect("impact");
        let h = 1e-6;
        for j in 0..2 * n {
            let (mut qp, mut qm, mut dp, mut dm) = (q.clone(), q.clone(), qd.clone(), qd.clone());
            if j < n {
                qp[j] += h;
                qm[j] -= h;
            } else {
                dp[j - n] += h;
                dm[j - n] -= h;
            }
            let (mut vp, mut vm) = (vec![0.0; n], vec![0.0; n]);
            unilateral_impact(&ch, &qp, &dp, &items, Some(&hold), &mut vp, None).expect("+");
            unilateral_impact(&ch, &qm, &dm, &items, Some(&hold), &mut vm, None).expect("-");
            for i in 0..n {
                let fd = (vp[i] - vm[i]) / (2.0 * h);
                let an = jac[i * 2 * n + j];
                assert!(
                    (fd - an).abs() < 1e-7 * (1.0 + an.abs()),
                    "∂q̇⁺[{i}]/∂x[{j}]: analytic {an}, differences {fd}"
                );
            }
        }
    }
}

#[test]
fn bad_items_are_clear_errors() {
    let mut r = rng(15);
    let ch = floating_walker(&mut r, 2);
    let (q, qd) = walker_state(&mut r, 2);
    let n = ch.dof();
    let mut v = vec![0.0; n];
    assert!(unilateral_impact(&ch, &q, &qd, &[], None, &mut v, None).is_err());
    assert!(unilateral_impact(&ch, &q, &qd, &[stop(n, 1.0, true)], None, &mut v, None).is_err());
    assert!(unilateral_impact(&ch, &q, &qd, &[stop(3, 0.5, true)], None, &mut v, None).is_err());
    // a bilateral item cannot be released by the hold mask
    let e = unilateral_impact(
        &ch,
        &q,
        &qd,
        &[stop(3, 1.0, false)],
        Some(&[false]),
        &mut v,
        None,
    );
    assert!(e.is_err());
}

/// Asked without its Jacobian, an impact gives the same bits as with it (post-impact rates,
/// impulses, rates per item, energy lost and the active set): the value-only solve runs the
/// same value arithmetic in duals of width 0. Bilateral items are active in every solution.
#[test]
fn the_map_without_its_jacobian_has_the_same_bits() {
    let mut r = rng(14);
    let mut solved = 0;
    for case in 0..200 {
        let m = 1 + case % 3;
        let ch = floating_walker(&mut r, m);
        let (q, qd) = walker_state(&mut r, m);
        let n = ch.dof();
        let rad = if case % 2 == 0 { 0.0 } else { 0.1 };
        let [strike, trail] = heel_strike_feet(rad);
        let items = [strike, trail, stop(2 + m - 1, 1.0, case % 4 < 2)];
        let (mut v, mut w) = (vec![0.0; n], vec![f64::NAN; n]);
        let mut jac = vec![0.0; 2 * n * n];
        let with = unilateral_impact(&ch, &q, &qd, &items, None, &mut v, Some(&mut jac));
        let without = unilateral_impact(&ch, &q, &qd, &items, None, &mut w, None);
        match (with, without) {
            (Ok(a), Ok(b)) => {
                solved += 1;
                let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&v), bits(&w), "case {case}");
                assert_eq!(a.energy_lost.to_bits(), b.energy_lost.to_bits());
                for (i, item) in items.iter().enumerate() {
                    let (x, y) = (&a.items[i], &b.items[i]);
                    assert_eq!(x.active, y.active, "case {case} item {i}");
                    // a bilateral item (a latched knee, the striking foot) holds in every
                    // solution: what lets a walker skip the buckling solve for latched knees
                    assert!(item.unilateral || x.active, "case {case} item {i}");
                    assert_eq!(bits(&x.impulse), bits(&y.impulse), "case {case} item {i}");
                    assert_eq!(bits(&x.rate), bits(&y.rate), "case {case} item {i}");
                }
                assert!(jac.iter().all(|x| x.is_finite()));
            }
            (a, b) => assert_eq!(a.is_ok(), b.is_ok(), "case {case}"),
        }
    }
    assert!(solved > 150, "{solved} of 200 solved");
}
