//! One stride (section to section) of the simplest walker (Garcia 1998, γ = 0.009, from its
//! stable fixed point) and of the compass gait (Goswami preset, 3°, from its fixed point), with
//! DOPRI5 and DOP853 at `rtol = atol = 1e-6` and `1e-10`:
//! - `scalar`: [`StrideMap::stride`] (builds an [`Integrator`] per call) and
//!   [`StrideMap::stride_with`] (reuses one), reported per stride;
//! - `batch`: 1024 strides from slightly perturbed section states (seeded, relative 1e-4) through
//!   the lockstep engine, serial ([`StrideMap::strides`], 64 and 1024 lanes) and on a rayon pool
//!   of 1 and 2 threads ([`StrideMap::strides_par`], chunks of 256 states, 64 lanes), reported
//!   per lane-stride (`Throughput::Elements(1024)`).
//!
//! Run: `cargo bench -p pdw-benches --bench stride`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use pdw_hybrid::{Integrator, Options, Section};
use pdw_limit::{find_fixed_point, NewtonOptions, StrideMap};
use pdw_walkers::simplest::{Simplest, SimplestParams};
use pdw_walkers::Walker;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const SEED: u64 = 20_240_603;
/// Strides per batched iteration.
const N: usize = 1024;
/// States per parallel task in the pool benches (fixed: independent of the thread count).
const CHUNK: usize = 256;

/// Fixed point of `sys` from its first gait guess (DOP853 at 1e-14, Newton to 1e-12).
fn fixed_point<S: Walker>(sys: &S) -> Vec<f64> {
    let map = StrideMap::new(sys, Options::dop853(1e-14)).expect("valid options");
    let guess = sys.gait_guesses()[0].section.clone();
    find_fixed_point(&map, &guess, &NewtonOptions::default())
        .expect("fixed point found")
        .section
}

/// `n` copies of `s` with each coordinate scaled by `1 + u`, `u` uniform in ±1e-4 (seeded).
fn perturbed(s: &[f64], n: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            s.iter()
                .map(|v| v * (1.0 + rng.random_range(-1e-4..1e-4)))
                .collect()
        })
        .collect()
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
}

fn methods() -> [(&'static str, Options); 4] {
    [
        ("dopri5_1e-6", Options::dopri5(1e-6)),
        ("dopri5_1e-10", Options::dopri5(1e-10)),
        ("dop853_1e-6", Options::dop853(1e-6)),
        ("dop853_1e-10", Options::dop853(1e-10)),
    ]
}

fn bench_model<S: Walker>(c: &mut Criterion, name: &str, sys: &S) {
    let s0 = fixed_point(sys);
    let states = perturbed(&s0, N, SEED);
    let pools = [(1usize, pool(1)), (2usize, pool(2))];

    let mut group = c.benchmark_group(format!("stride_{name}_scalar"));
    group
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_millis(500))
        .throughput(Throughput::Elements(1));
    for (label, opts) in methods() {
        let map = StrideMap::new(sys, opts).expect("valid options");
        let st = map.stride(&s0).expect("stride");
        assert!(st.outcome.is_ok(), "{name} {label}: {}", st.outcome);
        group.bench_function(BenchmarkId::new("stride", label), |b| {
            b.iter(|| black_box(map.stride(black_box(&s0)).expect("stride")))
        });
        let mut integ = Integrator::new(sys.dim(), opts).expect("valid options");
        group.bench_function(BenchmarkId::new("stride_with", label), |b| {
            b.iter(|| black_box(map.stride_with(&mut integ, black_box(&s0)).expect("stride")))
        });
        let stats = {
            integ.reset_stats();
            map.stride_with(&mut integ, &s0).expect("stride");
            integ.stats()
        };
        eprintln!(
            "{name} {label}: {} accepted, {} rejected steps, {} rhs evaluations per stride",
            stats.accepted, stats.rejected, stats.rhs_evals
        );
    }
    group.finish();

    let mut group = c.benchmark_group(format!("stride_{name}_batch{N}"));
    group
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500))
        .sample_size(20)
        .throughput(Throughput::Elements(N as u64));
    for (label, opts) in methods() {
        let map = StrideMap::new(sys, opts).expect("valid options");
        let ok = map
            .strides(&states, 64)
            .expect("strides")
            .iter()
            .filter(|s| s.outcome.is_ok())
            .count();
        assert_eq!(
            ok, N,
            "{name} {label}: every perturbed stride reaches the section"
        );
        for lanes in [64usize, N] {
            group.bench_function(BenchmarkId::new(format!("serial_l{lanes}"), label), |b| {
                b.iter(|| black_box(map.strides(black_box(&states), lanes).expect("strides")))
            });
        }
        for (threads, p) in &pools {
            group.bench_function(
                BenchmarkId::new(format!("pool_t{threads}_l64"), label),
                |b| {
                    b.iter(|| {
                        black_box(
                            map.strides_par(black_box(&states), 64, p, CHUNK, &|_| {})
                                .expect("strides"),
                        )
                    })
                },
            );
        }
    }
    group.finish();
}

fn simplest(c: &mut Criterion) {
    let sys = Simplest::new(SimplestParams {
        slope: 0.009,
        ..SimplestParams::default()
    })
    .expect("valid parameters");
    bench_model(c, "simplest", &sys);
}

fn compass(c: &mut Criterion) {
    let sys = pdw_walkers::presets::compass(&[]).expect("valid parameters");
    assert_eq!(sys.section_dim(), 3);
    bench_model(c, "compass", &sys);
}

criterion_group!(benches, simplest, compass);
criterion_main!(benches);
