//! Basin of attraction of the simplest walker (Garcia 1998) at γ = 0.009 over
//! θ ∈ [0.15, 0.25], θ̇ ∈ [−0.25, −0.15], up to 100 strides per cell, with the engine's default
//! options (DOP853 at 1e-9, 64 lanes, chunks of 1024 cells, `tol_gait = 1e-6`, `confirm = 2`)
//! — the workload of `pdw-sweep basin --grid NxN --x theta=0.15:0.25 --y thetadot=-0.25:-0.15`
//! without the file output:
//! - `basin_simplest_200x200`: the 200 × 200 grid on a 2-thread pool, reported per cell
//!   (`Throughput::Elements(cells)`); the lane-strides per iteration (sum of
//!   [`CellResult::strides`](pdw_limit::CellResult)) are printed at setup, so that
//!   lane-strides/s = printed strides / time. `lanes64`: the model built as its own type;
//!   `lanes64_dyn_walker`: the same model behind `Box<dyn Walker>` from the registry, as the
//!   CLI runs it (the basin holds either as `dyn Section`, so the two run the same compiled
//!   code; the pair checks that the registry's model costs nothing more);
//! - `basin_simplest_100x100`: the 100 × 100 grid on 1 and 2 threads and with 16, 64 and 256
//!   lanes (2 threads), to show the thread scaling and the lane-width sensitivity.
//!
//! Run: `cargo bench -p pdw-benches --bench basin`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use pdw_hybrid::Options;
use pdw_limit::{
    classify_cells, find_fixed_point, grid_cells, linspace, BasinOptions, BasinProblem, CellResult,
    NewtonOptions, Outcome, StrideMap,
};
use pdw_walkers::simplest::{GarciaGait, Simplest, SimplestParams};

const GAMMA: f64 = 0.009;

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
}

fn summary(res: &[CellResult]) -> (usize, usize) {
    let strides = res.iter().map(|c| usize::from(c.strides)).sum();
    let gait = res.iter().filter(|c| c.outcome() == Outcome::Gait).count();
    (strides, gait)
}

fn basin(c: &mut Criterion) {
    let sys = Simplest::new(SimplestParams {
        slope: GAMMA,
        ..SimplestParams::default()
    })
    .expect("valid parameters");
    let map = StrideMap::new(&sys, Options::dop853(1e-14)).expect("valid options");
    let fp = find_fixed_point(
        &map,
        &GarciaGait::LongPeriod.section_guess(GAMMA),
        &NewtonOptions::default(),
    )
    .expect("fixed point");
    let fall = Outcome::of_fall;
    let problem = BasinProblem::new(&sys, fp.section.clone(), &fall);
    // The same model behind `dyn Walker`, as the CLI builds it from the registry.
    let boxed = pdw_walkers::build("simplest", &[("slope", GAMMA)]).expect("registry model");
    let fall_dyn = Outcome::of_fall;
    let problem_dyn = BasinProblem::new(&*boxed, fp.section.clone(), &fall_dyn);
    let default_opts = BasinOptions::default();
    assert_eq!(default_opts.max_strides, 100);
    let pools = [(1usize, pool(1)), (2usize, pool(2))];

    for (n, configs) in [
        (200usize, vec![(2usize, 64usize, false), (2, 64, true)]),
        (
            100,
            vec![
                (1, 64, false),
                (2, 16, false),
                (2, 64, false),
                (2, 256, false),
            ],
        ),
    ] {
        let cells = grid_cells(
            &fp.section,
            0,
            &linspace(0.15, 0.25, n),
            1,
            &linspace(-0.25, -0.15, n),
        );
        let mut group = c.benchmark_group(format!("basin_simplest_{n}x{n}"));
        group
            .sample_size(10)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(if n >= 200 { 25 } else { 8 }))
            .throughput(Throughput::Elements(cells.len() as u64));
        for (threads, lanes, dynamic) in configs {
            let opts = BasinOptions {
                lanes,
                ..default_opts
            };
            let p = &pools[threads - 1].1;
            let run = || {
                if dynamic {
                    classify_cells(&problem_dyn, &cells, &opts, p, &|_| {})
                } else {
                    classify_cells(&problem, &cells, &opts, p, &|_| {})
                }
                .expect("basin")
            };
            let res = run();
            let (strides, gait) = summary(&res);
            eprintln!(
                "basin {n}x{n}, {threads} threads, {lanes} lanes, dyn {dynamic}: {} cells, \
                 {strides} lane-strides ({:.1} per cell), {gait} gait cells",
                cells.len(),
                strides as f64 / cells.len() as f64
            );
            group.bench_function(
                BenchmarkId::new(
                    format!("t{threads}"),
                    format!("lanes{lanes}{}", if dynamic { "_dyn_walker" } else { "" }),
                ),
                |b| b.iter(|| black_box(run())),
            );
        }
        group.finish();
    }
}

criterion_group!(benches, basin);
criterion_main!(benches);
