//! Every shipped walker in one run, so that their ratios to the simplest walker come from the
//! same minutes of the same machine:
//! - `models_stride/<model>`: 1024 strides from the stable gait's section point perturbed by up
//!   to ±1e-3 (seeded), DOPRI5 at 1e-10, 64 lanes on a 2-thread pool (`StrideMap::strides_par`);
//!   `Throughput::Elements(1024)`, so criterion's elements/s are strides/s and the time per
//!   lane-stride is 2 threads / (strides/s);
//! - `models_basin/<model>`: the basin on a 41 × 41 grid of the first two section coordinates
//!   around the stable gait (± 25 % of each coordinate's magnitude, at least ± 0.05; the other
//!   coordinates at the gait), engine defaults (DOP853 at 1e-9, 64 lanes, up to 100 strides),
//!   2 threads; `Throughput::Elements(cells)`, so elements/s are cells/s. The lane-strides of
//!   one grid are printed at setup (the cells' mixes of gaits and falls differ by model).
//!
//! Models: the presets `simplest`, `compass`, `kneed` and `seed5`, each at its preset slope.
//! The spec file `models/seed5_walking.toml` is not among them: under the impact checks its
//! stance knee buckles at the knee strike and it has no gait (docs/models.md).
//!
//! Run: `cargo bench -p pdw-benches --bench models`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use pdw_hybrid::Options;
use pdw_limit::{
    classify_cells, find_fixed_point, grid_cells, linspace, BasinOptions, BasinProblem,
    NewtonOptions, Outcome, StrideMap,
};
use pdw_walkers::Walker;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const STRIDES: usize = 1024;
const GRID: usize = 41;

/// The walkers of the run (registry names).
const MODELS: [&str; 4] = ["simplest", "compass", "kneed", "seed5"];

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
}

/// The stable period-one gait's section point of `w` from its own guesses.
fn stable_gait(w: &dyn Walker) -> Vec<f64> {
    let map = StrideMap::new(w, Options::dop853(1e-14)).expect("valid options");
    w.gait_guesses()
        .iter()
        .filter_map(|g| find_fixed_point(&map, &g.section, &NewtonOptions::default()).ok())
        .find(|fp| fp.stable)
        .expect("a stable gait")
        .section
}

/// The basin grid's cells: the first two section coordinates around `s`.
fn cells(s: &[f64]) -> Vec<Vec<f64>> {
    let axis = |v: f64| {
        let h = (0.25 * v.abs()).max(0.05);
        linspace(v - h, v + h, GRID)
    };
    grid_cells(s, 0, &axis(s[0]), 1, &axis(s[1]))
}

fn bench_stride(c: &mut Criterion, p: &rayon::ThreadPool) {
    let mut group = c.benchmark_group("models_stride");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5))
        .throughput(Throughput::Elements(STRIDES as u64));
    for label in MODELS {
        let w = pdw_walkers::build(label, &[]).expect("model");
        let s = stable_gait(w.as_ref());
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let states: Vec<Vec<f64>> = (0..STRIDES)
            .map(|_| {
                s.iter()
                    .map(|v| v + rng.random_range(-1e-3..1e-3))
                    .collect()
            })
            .collect();
        let map = StrideMap::new(w.as_ref(), Options::dopri5(1e-10)).expect("valid options");
        let run = || {
            map.strides_par(&states, 64, p, 256, &|_| {})
                .expect("strides")
        };
        let ok = run().iter().filter(|x| x.outcome.is_ok()).count();
        eprintln!("stride {label}: {ok} of {STRIDES} perturbed strides reach the section");
        group.bench_function(label, |b| b.iter(|| black_box(run())));
    }
    group.finish();
}

fn bench_basin(c: &mut Criterion, p: &rayon::ThreadPool) {
    let mut group = c.benchmark_group("models_basin");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(8));
    let fall = Outcome::of_fall;
    let opts = BasinOptions::default();
    for label in MODELS {
        let w = pdw_walkers::build(label, &[]).expect("model");
        let s = stable_gait(w.as_ref());
        let problem = BasinProblem::new(w.as_ref(), s.clone(), &fall);
        let cells = cells(&s);
        let run = || classify_cells(&problem, &cells, &opts, p, &|_| {}).expect("basin");
        let res = run();
        let strides: u64 = res.iter().map(|c| u64::from(c.strides)).sum();
        let gait = res.iter().filter(|c| c.outcome() == Outcome::Gait).count();
        eprintln!(
            "basin {label}: {} cells, {strides} lane-strides ({:.1} per cell), {gait} gait cells",
            cells.len(),
            strides as f64 / cells.len() as f64
        );
        group.throughput(Throughput::Elements(cells.len() as u64));
        group.bench_function(label, |b| b.iter(|| black_box(run())));
    }
    group.finish();
}

fn all(c: &mut Criterion) {
    let p = pool(2);
    bench_stride(c, &p);
    bench_basin(c, &p);
}

criterion_group!(benches, all);
criterion_main!(benches);
