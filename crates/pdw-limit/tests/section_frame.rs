//! The principal frame of a cloud of section states (`pdw_limit::section_frame`): the affine
//! map there and back, the thin box it gives an oblique band, multilinear interpolation on a
//! mesh in that frame, and the identity where the cloud is degenerate.

use pdw_limit::markov::Mesh;
use pdw_limit::section_frame::Frame;
/// Points along the line `y = −x` with a small spread across it.
fn band() -> Vec<Vec<f64>> {
    (0..200)
        .map(|i| {
            let t = i as f64 / 199.0;
            let w = 1e-3 * ((i * 37 % 11) as f64 - 5.0);
            vec![0.1 + 0.1 * t + w, -0.1 - 0.1 * t + w]
        })
        .collect()
}

#[test]
fn a_frame_maps_there_and_back_and_its_matrices_are_inverse() {
    let f = Frame::principal(&band(), 2);
    for p in band().iter().step_by(17) {
        let back = f.from_frame(&f.to_frame(p));
        assert!((back[0] - p[0]).abs() < 1e-15 && (back[1] - p[1]).abs() < 1e-15);
    }
    for i in 0..2 {
        for j in 0..2 {
            let ab: f64 = (0..2).map(|k| f.to[i * 2 + k] * f.from[k * 2 + j]).sum();
            assert!(
                (ab - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12,
                "A·B[{i}][{j}]"
            );
        }
    }
}

#[test]
fn the_principal_box_of_an_oblique_band_is_thin_across_it() {
    let pts = band();
    let f = Frame::principal(&pts, 2);
    let (lo, hi) = f.bounds(&pts, &f.to_frame(&pts[0]));
    let (corner, edges) = f.edges(&(lo, hi));
    let area = |e: &[Vec<f64>]| (e[0][0] * e[1][1] - e[0][1] * e[1][0]).abs();
    // axis-aligned: 0.11 × 0.11; the band's own box: its length 0.1·√2 by ≈ 0.01·√2
    assert!(area(&edges) < 0.25 * 0.11 * 0.11, "area {}", area(&edges));
    // the long edge runs along (1, −1)
    let e = &edges[0];
    assert!((e[0] + e[1]).abs() < 0.05 * e[0].abs(), "long edge {e:?}");
    assert!(corner.iter().all(|v| v.is_finite()));
}

#[test]
fn a_mesh_in_a_frame_interpolates_affine_functions_exactly() {
    let pts = band();
    let frame = Frame::principal(&pts, 2);
    let (lo, hi) = frame.bounds(&pts, &frame.to_frame(&pts[0]));
    let mesh = Mesh {
        lo,
        hi,
        n: 7,
        frame,
    };
    // multilinear weights reproduce every affine function of the frame coordinates, so of
    // the section coordinates too (the frame is affine)
    let f = |p: &[f64]| 0.3 + 2.0 * p[0] - 5.0 * p[1];
    for p in pts.iter().step_by(13) {
        let w = mesh
            .weights(p)
            .expect("a visited point lies in its own box");
        let sum: f64 = w.iter().map(|(_, w)| w).sum();
        let interp: f64 = w.iter().map(|(k, w)| w * f(&mesh.node(*k))).sum();
        assert!((sum - 1.0).abs() < 1e-14, "weights sum {sum}");
        assert!((interp - f(p)).abs() < 1e-13, "{interp} vs {}", f(p));
    }
    // a point far across the band lies outside the thin box
    assert!(mesh.weights(&[0.15, 0.15]).is_none());
}

#[test]
fn degenerate_clouds_get_the_identity() {
    assert!(Frame::principal(&band()[..2], 2).is_identity());
    assert!(Frame::principal(&[vec![1.0], vec![2.0], vec![3.0]], 1).is_identity());
    let flat: Vec<Vec<f64>> = (0..10).map(|i| vec![i as f64, 0.5]).collect();
    assert!(Frame::principal(&flat, 2).is_identity());
    let mut bad = band();
    bad[3][1] = f64::NAN;
    assert!(Frame::principal(&bad, 2).is_identity());
}
