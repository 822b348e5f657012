//! Every lane of the batched kernels equals the scalar kernel bit for bit.

mod common;

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
        for lanes in [1usize, 7, 64, 1000] {
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
}
