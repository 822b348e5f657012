//! Measurements of the basin engine on the simplest walker's basin at γ = 0.009 (printed, not
//! asserted): throughput at three gait tolerances, and how many labels each integrator and
//! tolerance changes against a DOP853 1e-12 reference. Run with
//! `cargo run --release -p pdw-experiments --bin basin_measure` (`PDW_N` cells per side,
//! default 200; `PDW_THREADS`, default 2).

use pdw_hybrid::{Options, Section};
use pdw_limit::{
    basin_metrics, classify_cells, find_fixed_point, grid_cells, linspace, BasinOptions,
    BasinProblem, NewtonOptions, Outcome, StrideMap,
};
use pdw_walkers::simplest::{Simplest, SimplestParams};
use std::time::Instant;

fn simplest(gamma: f64) -> (Simplest, Vec<f64>) {
    let m = Simplest::new(SimplestParams {
        slope: gamma,
        ..Default::default()
    })
    .unwrap();
    let map = StrideMap::new(&m, Options::dop853(1e-13)).unwrap();
    let fp = find_fixed_point(&map, &[0.2003, -0.1998], &NewtonOptions::default()).unwrap();
    let s = fp.section.clone();
    (m, s)
}

fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
}

fn grid(n: usize) -> Vec<Vec<f64>> {
    grid_cells(
        &[0.0, 0.0],
        0,
        &linspace(0.15, 0.25, n),
        1,
        &linspace(-0.25, -0.15, n),
    )
}

fn summary(res: &[pdw_limit::CellResult], n: usize) -> String {
    let codes: Vec<u8> = res.iter().map(|r| r.outcome).collect();
    let m = basin_metrics(&codes, n, n, 5).unwrap();
    let strides: u64 = res.iter().map(|r| u64::from(r.strides)).sum();
    let mut s = format!("lane-strides {strides}; ");
    for (_, name, f) in m.fractions.iter().filter(|f| f.2 > 0.0) {
        s += &format!("{name} {f:.5} ");
    }
    s += &format!("S_b {:.4} S_bb {:.4}", m.basin_entropy, m.boundary_entropy);
    s
}

fn measure_basin_throughput() {
    let n: usize = std::env::var("PDW_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(200);
    let threads: usize = std::env::var("PDW_THREADS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2);
    let (m, s) = simplest(0.009);
    let prob = BasinProblem::new(&m, s.clone(), &Outcome::of_fall);
    let cells = grid(n);
    let p = pool(threads);
    for (label, integ0, tg) in [
        (
            "dop853 1e-9 tol_gait 1e-6 (default)",
            Options::dop853(1e-9),
            1e-6,
        ),
        ("dop853 1e-9 tol_gait 1e-5", Options::dop853(1e-9), 1e-5),
        ("dop853 1e-9 tol_gait 1e-4", Options::dop853(1e-9), 1e-4),
    ] {
        let opts = BasinOptions {
            integrator: integ0,
            tol_gait: tg,
            ..Default::default()
        };
        let t = Instant::now();
        let res = classify_cells(&prob, &cells, &opts, &p, &|_| {}).unwrap();
        let el = t.elapsed().as_secs_f64();
        let strides: u64 = res.iter().map(|r| u64::from(r.strides) + 1).sum();
        println!(
            "{label}: {n}x{n} on {threads} threads: {el:.3} s, {:.0} cells/s, {:.0} lane-strides/s; {}",
            (n * n) as f64 / el,
            strides as f64 / el,
            summary(&res, n)
        );
    }
    let _ = m.section_dim();
}

fn measure_label_agreement_vs_tight_reference() {
    let n: usize = std::env::var("PDW_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(200);
    let (m, s) = simplest(0.009);
    let prob = BasinProblem::new(&m, s, &Outcome::of_fall);
    let cells = grid(n);
    let p = pool(2);
    let reference = classify_cells(
        &prob,
        &cells,
        &BasinOptions {
            integrator: Options::dop853(1e-12),
            ..Default::default()
        },
        &p,
        &|_| {},
    )
    .unwrap();
    println!("reference dop853 1e-12: {}", summary(&reference, n));
    for integ in [
        Options::dopri5(1e-6),
        Options::dopri5(1e-7),
        Options::dopri5(1e-8),
        Options::dopri5(1e-9),
        Options::dopri5(1e-10),
        Options::dop853(1e-7),
        Options::dop853(1e-9),
        Options::rk4(0.05),
        Options::rk4(0.02),
    ] {
        let opts = BasinOptions {
            integrator: integ,
            ..Default::default()
        };
        let t = Instant::now();
        let res = classify_cells(&prob, &cells, &opts, &p, &|_| {}).unwrap();
        let el = t.elapsed().as_secs_f64();
        let changed = res
            .iter()
            .zip(&reference)
            .filter(|(a, b)| a.outcome != b.outcome)
            .count();
        println!(
            "{:?} rtol {:e}: {el:.3} s, labels changed {changed} of {} ({:.4} %)",
            integ.method,
            integ.rtol,
            n * n,
            100.0 * changed as f64 / (n * n) as f64
        );
    }
}

fn main() {
    measure_basin_throughput();
    measure_label_agreement_vs_tight_reference();
}
