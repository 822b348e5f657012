//! Every instruction-set path of the hot loops (pdw-simd: baseline x86-64, AVX2+FMA, AVX-512)
//! gives the same bits: basins cell for cell (label, stride count, final state bit for bit),
//! fixed points and multipliers. Each available path is forced in turn; paths this CPU lacks are
//! listed and skipped (the baseline path always runs).
//!
//! One test function, so that no other test in this binary changes the process-wide path while
//! a path is being measured.

use pdw_hybrid::{Options, Section};
use pdw_limit::{
    classify_cells, find_fixed_point, grid_cells, linspace, BasinOptions, BasinProblem, CellResult,
    NewtonOptions, Outcome, StrideMap,
};
use pdw_simd::{available_paths, set_path, SimdPath};
use pdw_walkers::simplest::{Simplest, SimplestParams};
use pdw_walkers::Walker;

fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
}

/// Basin of `m` around its first gait guess's fixed point on an `n × n` window of the first two
/// section coordinates (half-widths `dx`, `dy`).
fn basin<W: Walker + Section>(m: &W, n: usize, dx: f64, dy: f64, strides: u16) -> Vec<CellResult> {
    let guess = m.gait_guesses()[0].section.clone();
    let map = StrideMap::new(m, Options::dop853(1e-12)).unwrap();
    let s = find_fixed_point(&map, &guess, &NewtonOptions::default())
        .unwrap()
        .section;
    let fall = Outcome::of_fall;
    let prob = BasinProblem::new(m, s.clone(), &fall);
    let cells = grid_cells(
        &s,
        0,
        &linspace(s[0] - dx, s[0] + dx, n),
        1,
        &linspace(s[1] - dy, s[1] + dy, n),
    );
    let opts = BasinOptions {
        max_strides: strides,
        ..Default::default()
    };
    classify_cells(&prob, &cells, &opts, &pool(2), &|_| {}).unwrap()
}

/// Fixed point and multipliers (exact Jacobians), as raw bits.
fn fixed_point_bits<W: Walker + Section>(m: &W) -> Vec<u64> {
    let guess = m.gait_guesses()[0].section.clone();
    let map = StrideMap::new(m, Options::dop853(1e-12)).unwrap();
    let fp = find_fixed_point(&map, &guess, &NewtonOptions::default()).unwrap();
    let mut bits: Vec<u64> = fp.section.iter().map(|v| v.to_bits()).collect();
    bits.push(fp.metrics.period.to_bits());
    bits.extend(fp.dp.iter().map(|v| v.to_bits()));
    for z in &fp.multipliers {
        bits.push(z.re.to_bits());
        bits.push(z.im.to_bits());
    }
    bits
}

fn same_cells(a: &[CellResult], b: &[CellResult], what: &str, path: SimdPath) {
    assert_eq!(a.len(), b.len());
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        assert_eq!(x.outcome, y.outcome, "{what}, path {path}, cell {k}: label");
        assert_eq!(
            x.strides, y.strides,
            "{what}, path {path}, cell {k}: strides"
        );
        let bx: Vec<u64> = x.final_state.iter().map(|v| v.to_bits()).collect();
        let by: Vec<u64> = y.final_state.iter().map(|v| v.to_bits()).collect();
        assert_eq!(bx, by, "{what}, path {path}, cell {k}: final state bits");
    }
}

#[test]
fn every_available_simd_path_gives_identical_basins_and_fixed_points() {
    let paths = available_paths();
    eprintln!(
        "paths available: {:?}; skipped (CPU lacks them): {:?}",
        paths,
        SimdPath::ALL
            .iter()
            .filter(|p| !paths.contains(p))
            .collect::<Vec<_>>()
    );
    let simplest = Simplest::new(SimplestParams {
        slope: 0.009,
        ..Default::default()
    })
    .unwrap();
    let compass = pdw_walkers::presets::compass(&[]).unwrap();
    let kneed = pdw_walkers::presets::kneed(&[]).unwrap();

    set_path(SimdPath::Baseline).unwrap();
    let ref_simplest = basin(&simplest, 201, 0.05, 0.05, 100);
    let ref_compass = basin(&compass, 41, 0.1, 0.5, 30);
    let ref_kneed = basin(&kneed, 15, 0.02, 0.1, 10);
    let ref_fp: Vec<Vec<u64>> = vec![
        fixed_point_bits(&simplest),
        fixed_point_bits(&compass),
        fixed_point_bits(&kneed),
    ];
    // The grids are not trivial: the gait and falls both occur.
    for (what, r) in [
        ("simplest", &ref_simplest),
        ("compass", &ref_compass),
        ("kneed", &ref_kneed),
    ] {
        assert!(r.iter().any(|c| c.outcome() == Outcome::Gait), "{what}");
        assert!(r.iter().any(|c| c.outcome().is_fall()), "{what}");
    }
    for &p in paths.iter().filter(|&&p| p != SimdPath::Baseline) {
        set_path(p).unwrap();
        same_cells(
            &basin(&simplest, 201, 0.05, 0.05, 100),
            &ref_simplest,
            "simplest 201x201",
            p,
        );
        same_cells(
            &basin(&compass, 41, 0.1, 0.5, 30),
            &ref_compass,
            "compass 41x41",
            p,
        );
        same_cells(
            &basin(&kneed, 15, 0.02, 0.1, 10),
            &ref_kneed,
            "kneed 15x15",
            p,
        );
        let fp = vec![
            fixed_point_bits(&simplest),
            fixed_point_bits(&compass),
            fixed_point_bits(&kneed),
        ];
        assert_eq!(fp, ref_fp, "fixed points and multipliers, path {p}");
    }
    set_path(pdw_simd::best_path()).unwrap();
}
