//! Every lane of the batched kernels equals the scalar kernel bit for bit.

use crate::common;

use common::*;
use faer::Mat;
use pdw_soa::*;
use rand::Rng;

fn fill(r: &mut rand_chacha::ChaCha8Rng, lanes: usize, cols: usize, lo: f64, hi: f64) -> Mat<f64> {
    Mat::from_fn(lanes, cols, |_, _| r.random_range(lo..hi))
}

#[test]
fn batched_aba_and_rnea_equal_scalar_bit_for_bit_per_lane() {
    let mut r = rng(10);
    for (ci, n) in [1usize, 2, 5, 9].into_iter().enumerate() {
        let chain = random_chain(&mut r, n, ci % 2 == 1);
        let mut ws = Workspace::new(&chain);
        for lanes in [1usize, 2, 7, 23, 64, 1000] {
            let mut bw = BatchWorkspace::new(&chain, lanes);
            let q = fill(&mut r, lanes, n, -2.5, 2.5);
            let qd = fill(&mut r, lanes, n, -3.0, 3.0);
            let tau = fill(&mut r, lanes, n, -5.0, 5.0);
            let ft = fill(&mut r, lanes, 3, -2.0, 2.0);
            for with_tip in [false, true] {
                let tip = if with_tip { Some(&ft) } else { None };
                let mut qdd = Mat::zeros(lanes, n);
                batch_aba(&chain, &mut bw, &q, &qd, &tau, tip, &mut qdd).unwrap();
                let mut tau_b = Mat::zeros(lanes, n);
                batch_rnea(&chain, &mut bw, &q, &qd, &qdd, tip, &mut tau_b).unwrap();
                let mut qdd_s = vec![0.0; n];
                let mut tau_s = vec![0.0; n];
                for l in 0..lanes {
                    let ql: Vec<f64> = (0..n).map(|k| q[(l, k)]).collect();
                    let qdl: Vec<f64> = (0..n).map(|k| qd[(l, k)]).collect();
                    let tl: Vec<f64> = (0..n).map(|k| tau[(l, k)]).collect();
                    let fl = if with_tip {
                        Some([ft[(l, 0)], ft[(l, 1)], ft[(l, 2)]])
                    } else {
                        None
                    };
                    aba(&chain, &mut ws, &ql, &qdl, &tl, fl, &mut qdd_s).unwrap();
                    let qddl: Vec<f64> = (0..n).map(|k| qdd[(l, k)]).collect();
                    rnea(&chain, &mut ws, &ql, &qdl, &qddl, fl, &mut tau_s).unwrap();
                    for k in 0..n {
                        assert_eq!(
                            qdd[(l, k)].to_bits(),
                            qdd_s[k].to_bits(),
                            "aba n={n} lanes={lanes} lane {l} joint {k}"
                        );
                        assert_eq!(
                            tau_b[(l, k)].to_bits(),
                            tau_s[k].to_bits(),
                            "rnea n={n} lanes={lanes} lane {l} joint {k}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn batched_kernels_reject_wrong_shapes() {
    let mut r = rng(11);
    let chain = random_chain(&mut r, 3, false);
    let mut bw = BatchWorkspace::new(&chain, 8);
    let good = Mat::<f64>::zeros(8, 3);
    let bad = Mat::<f64>::zeros(7, 3);
    let mut out = Mat::<f64>::zeros(8, 3);
    let e = batch_aba(&chain, &mut bw, &bad, &good, &good, None, &mut out).unwrap_err();
    assert!(
        matches!(e, SoaError::DimensionMismatch { what: "q", .. }),
        "{e}"
    );
    let bad_tip = Mat::<f64>::zeros(8, 2);
    let e = batch_rnea(
        &chain,
        &mut bw,
        &good,
        &good,
        &good,
        Some(&bad_tip),
        &mut out,
    )
    .unwrap_err();
    assert!(
        matches!(e, SoaError::DimensionMismatch { what: "f_tip", .. }),
        "{e}"
    );
    // the one-lane masked entry checks its lengths too
    let mut ws = Workspace::new(&chain);
    let (q, mut qdd) = ([0.1; 3], [0.0; 3]);
    let e = aba_masked(&chain, &mut ws, &q, &q, &[false; 2], &mut qdd).unwrap_err();
    assert!(
        matches!(e, SoaError::DimensionMismatch { what: "locked", .. }),
        "{e}"
    );
    let e = aba_masked(&chain, &mut ws, &q, &q[..2], &[false; 3], &mut qdd).unwrap_err();
    assert!(
        matches!(e, SoaError::DimensionMismatch { what: "qd", .. }),
        "{e}"
    );
}

/// The batched pseudo-joint path (locked joints welded in the articulated-body recursion) on
/// column views of a state matrix equals the scalar `pseudo_joint_dynamics` bit for bit per lane,
/// for any lane count, with zero torques (`tau = None`) as the passive walkers use it.
#[test]
fn batched_locked_joints_on_views_equal_scalar_pseudo_joints_bit_for_bit() {
    let mut r = rng(11);
    for (ci, n) in [2usize, 3, 4, 6].into_iter().enumerate() {
        let chain = random_chain(&mut r, n, ci % 2 == 1);
        let mut ws = Workspace::new(&chain);
        let lock_sets: Vec<Vec<usize>> = vec![vec![], vec![1], vec![0, n - 1], vec![n - 1]];
        for lanes in [1usize, 5, 300] {
            let mut bw = BatchWorkspace::new(&chain, lanes.min(64));
            // state matrix (lanes × 2n): q then q̇, as a hybrid system's flow receives it
            let x = fill(&mut r, lanes, 2 * n, -2.0, 2.0);
            for locked in &lock_sets {
                let mask: Vec<bool> = (0..n).map(|k| locked.contains(&k)).collect();
                let mut dx = Mat::<f64>::zeros(lanes, 2 * n);
                batch_aba_view(
                    &chain,
                    &mut bw,
                    x.as_ref().subcols(0, n),
                    x.as_ref().subcols(n, n),
                    None,
                    None,
                    Some(&mask),
                    dx.as_mut().subcols_mut(n, n),
                )
                .unwrap();
                let zero = vec![0.0; n];
                let (mut qdd, mut lock) = (vec![0.0; n], vec![0.0; n]);
                for l in 0..lanes {
                    let xl: Vec<f64> = (0..2 * n).map(|k| x[(l, k)]).collect();
                    pseudo_joint_dynamics(
                        &chain,
                        &mut ws,
                        &xl[..n],
                        &xl[n..],
                        &zero,
                        locked,
                        None,
                        &mut qdd,
                        &mut lock,
                    )
                    .unwrap();
                    // and the one-lane entry the walkers' single-state flow calls
                    let mut one = vec![f64::NAN; n];
                    aba_masked(&chain, &mut ws, &xl[..n], &xl[n..], &mask, &mut one).unwrap();
                    for k in 0..n {
                        assert_eq!(
                            dx[(l, n + k)].to_bits(),
                            qdd[k].to_bits(),
                            "n={n} lanes={lanes} locked={locked:?} lane {l} joint {k}"
                        );
                        assert_eq!(
                            one[k].to_bits(),
                            qdd[k].to_bits(),
                            "aba_masked: n={n} locked={locked:?} lane {l} joint {k}"
                        );
                    }
                }
            }
        }
    }
}
