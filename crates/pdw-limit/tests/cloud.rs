//! The cloud of the Markov chain ([`pdw_limit::cloud`]): its weights against a brute-force
//! search in a metric computed here by hand, their independence of the section's units, and
//! its refusals.

use pdw_limit::cloud::{Cloud, REACH};

/// A lattice of `n = (5, 7, 9)` points per axis with spacings `h = (1, 10, 0.01)`, centred on
/// `c`: its covariance is diagonal, so its principal axes are the coordinate axes and the
/// standard deviation along axis `a` is `h_a √((n_a² − 1)/12)`.
const N: [usize; 3] = [5, 7, 9];
const H: [f64; 3] = [1.0, 10.0, 0.01];
const C: [f64; 3] = [0.3, -2.0, 5.0];

fn lattice() -> Vec<Vec<f64>> {
    let mut pts = Vec::new();
    for i in 0..N[0] {
        for j in 0..N[1] {
            for k in 0..N[2] {
                let idx = [i, j, k];
                pts.push(
                    (0..3)
                        .map(|a| C[a] + H[a] * (idx[a] as f64 - (N[a] - 1) as f64 / 2.0))
                        .collect(),
                );
            }
        }
    }
    pts
}

fn sd(a: usize) -> f64 {
    let n = N[a] as f64;
    H[a] * ((n * n - 1.0) / 12.0).sqrt()
}

/// A deterministic sequence in [0, 1) (a linear congruential generator).
fn uniforms(seed: u64, n: usize) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        })
        .collect()
}

/// The weights by brute force: every node's distance in the metric of [`sd`], the `2^d`
/// nearest within `REACH` cells, inverse squared distances.
fn brute(cloud: &Cloud, p: &[f64]) -> Option<Vec<(usize, f64)>> {
    let reach = REACH * cloud.cell();
    let mut near: Vec<(f64, usize)> = (0..cloud.len())
        .map(|k| {
            let q = cloud.node(k);
            let d2: f64 = (0..3).map(|a| ((p[a] - q[a]) / sd(a)).powi(2)).sum();
            (d2, k)
        })
        .filter(|(d2, _)| d2.sqrt() <= reach)
        .collect();
    near.sort_by(|a, b| a.0.total_cmp(&b.0));
    near.truncate(8);
    if near.is_empty() {
        return None;
    }
    if near[0].0 == 0.0 {
        return Some(vec![(near[0].1, 1.0)]);
    }
    let total: f64 = near.iter().map(|(d2, _)| 1.0 / d2).sum();
    Some(near.iter().map(|(d2, k)| (*k, 1.0 / d2 / total)).collect())
}

/// On the lattice thinned to about half its points (the spacing of a grid of 4 nodes per
/// axis), random points in and around its box get the weights of the brute-force search: the
/// cube search finds every node within reach, and the nearest ones.
#[test]
fn the_weights_are_the_nearest_nodes_by_inverse_squared_distance() {
    let pts = lattice();
    let cloud = Cloud::thinned(&pts, 4).unwrap();
    assert!(
        cloud.len() > 20 && cloud.len() < pts.len(),
        "{}",
        cloud.len()
    );
    // the cell: the geometric mean of the extents (in standard deviations) over 3 spacings
    let extent: f64 = (0..3)
        .map(|a| (H[a] * (N[a] - 1) as f64 / sd(a)).ln())
        .sum::<f64>()
        / 3.0;
    assert!((cloud.cell() - extent.exp() / 3.0).abs() < 1e-12 * cloud.cell());
    let u = uniforms(7, 3 * 400);
    let (mut inside, mut outside) = (0, 0);
    for q in u.chunks(3) {
        // the box widened by half its size on each side: some points beyond reach
        let p: Vec<f64> = (0..3)
            .map(|a| C[a] + H[a] * (N[a] - 1) as f64 * (2.0 * q[a] - 1.0))
            .collect();
        let (got, want) = (cloud.weights(&p), brute(&cloud, &p));
        match (&got, &want) {
            (Some(g), Some(w)) => {
                inside += 1;
                assert_eq!(g.len(), w.len(), "{p:?}");
                let sum: f64 = g.iter().map(|x| x.1).sum();
                assert!((sum - 1.0).abs() < 1e-12, "{sum}");
                for ((gk, gw), (wk, ww)) in g.iter().zip(w) {
                    assert_eq!(gk, wk, "{p:?}");
                    assert!(*gw > 0.0 && (gw - ww).abs() < 1e-9, "{p:?}: {gw} vs {ww}");
                }
            }
            (None, None) => outside += 1,
            _ => panic!("{p:?}: cloud {got:?}, brute force {want:?}"),
        }
    }
    assert!(
        inside > 100 && outside > 20,
        "{inside} inside, {outside} outside"
    );
    // a node is its own weight; a point that is not finite is nowhere
    let k = cloud.len() / 2;
    assert_eq!(cloud.weights(cloud.node(k)), Some(vec![(k, 1.0)]));
    assert_eq!(cloud.weights(&[f64::NAN, 0.0, 5.0]), None);
    assert_eq!(cloud.weights(&[0.0, 5.0]), None);
}

/// The metric has no unit: the same points in other units and from another origin (each
/// coordinate scaled and shifted) give the same nodes and the same weights at the moved points.
/// (Its distances are those of any whitening of the points, the same under every affine map of
/// the section; the cubes follow the principal axes, which a rotation of the section moves.)
#[test]
fn the_weights_do_not_depend_on_the_sections_units() {
    // a tilted sheet with some thickness
    let u = uniforms(11, 3 * 3000);
    let pts: Vec<Vec<f64>> = u
        .chunks(3)
        .map(|q| vec![q[0], q[1], 0.5 * q[0] - 0.2 * q[1] + 0.02 * q[2]])
        .collect();
    let map = |p: &[f64]| -> Vec<f64> {
        vec![
            1000.0 * p[0] + 4.0,
            0.001 * p[1] - 1.0,
            180.0 / std::f64::consts::PI * p[2],
        ]
    };
    let moved: Vec<Vec<f64>> = pts.iter().map(|p| map(p)).collect();
    let (a, b) = (
        Cloud::thinned(&pts, 12).unwrap(),
        Cloud::thinned(&moved, 12).unwrap(),
    );
    assert!(a.len() > 100, "{}", a.len());
    assert_eq!(a.len(), b.len());
    assert!((a.cell() - b.cell()).abs() < 1e-9 * a.cell());
    for q in uniforms(13, 3 * 200).chunks(3) {
        let p = vec![
            q[0],
            q[1],
            0.5 * q[0] - 0.2 * q[1] + 0.02 * (2.0 * q[2] - 0.5),
        ];
        let (wa, wb) = (a.weights(&p), b.weights(&map(&p)));
        match (wa, wb) {
            (Some(wa), Some(wb)) => {
                assert_eq!(wa.len(), wb.len());
                for ((ka, xa), (kb, xb)) in wa.iter().zip(&wb) {
                    assert_eq!(ka, kb);
                    assert!((xa - xb).abs() < 1e-7, "{xa} vs {xb}");
                }
            }
            (None, None) => {}
            (wa, wb) => panic!("{p:?}: {wa:?} vs {wb:?}"),
        }
    }
}

/// Clouds that cannot be built say why.
#[test]
fn a_cloud_refuses_what_it_cannot_measure() {
    let pts = lattice();
    let msg = |r: Result<Cloud, pdw_limit::LimitError>| r.unwrap_err().to_string();
    assert!(msg(Cloud::thinned(&pts, 1)).contains("at least 2"));
    assert!(msg(Cloud::thinned(&pts[..3], 4)).contains("3 states of 3"));
    let mut bad = pts.clone();
    bad[5][1] = f64::INFINITY;
    assert!(msg(Cloud::thinned(&bad, 4)).contains("not finite"));
    let flat: Vec<Vec<f64>> = pts.iter().map(|p| vec![p[0], p[1], 1.0]).collect();
    assert!(msg(Cloud::thinned(&flat, 4)).contains("do not spread"));
}
