//! Kernel benchmarks: scalar ABA, CRBA + Cholesky and the naive dense operator form on random
//! planar revolute chains, and the batched ABA per lane-DoF.
//!
//! Run: `cargo bench -p pdw-benches --bench soa`; `experiments/soa_bench_plot.py` turns the
//! criterion estimates into a log-log plot and a table.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use faer::Mat;
use pdw_soa::{
    aba, batch_aba, forward_dynamics_crba, naive_forward_dynamics, BatchWorkspace, Chain,
    ChainBuilder, Link, NaiveWorkspace, Workspace,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const SEED: u64 = 20_240_601;

/// Random planar revolute chain: link lengths 0.3–1.2 m, masses 0.5–3 kg, random COM offsets
/// and inertias; gravity on a small slope.
fn random_chain(rng: &mut ChaCha8Rng, n: usize) -> Chain {
    let mut b = ChainBuilder::new().gravity(9.81).slope(0.05);
    for _ in 0..n {
        let len = rng.random_range(0.3..1.2);
        let ang: f64 = rng.random_range(-0.5..0.5);
        let to_next = [len * ang.sin(), -len * ang.cos()];
        let f = rng.random_range(0.2..0.8);
        b = b.revolute(Link {
            to_next,
            com: [f * to_next[0], f * to_next[1]],
            mass: rng.random_range(0.5..3.0),
            inertia: rng.random_range(0.01..0.3),
        });
    }
    b.build().expect("valid chain")
}

fn random_vec(rng: &mut ChaCha8Rng, n: usize, a: f64) -> Vec<f64> {
    (0..n).map(|_| rng.random_range(-a..a)).collect()
}

fn scalar(c: &mut Criterion) {
    let sizes = [2usize, 3, 5, 8, 16, 32, 64, 128];
    for (name, method) in [
        ("soa_aba", 0),
        ("soa_crba_cholesky", 1),
        ("soa_naive_lu", 2),
    ] {
        let mut group = c.benchmark_group(name);
        for &n in &sizes {
            let mut rng = ChaCha8Rng::seed_from_u64(SEED + n as u64);
            let chain = random_chain(&mut rng, n);
            let q = random_vec(&mut rng, n, 1.0);
            let qd = random_vec(&mut rng, n, 1.0);
            let tau = random_vec(&mut rng, n, 2.0);
            let mut qdd = vec![0.0; n];
            let mut ws = Workspace::new(&chain);
            group.throughput(Throughput::Elements(n as u64));
            match method {
                0 => group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
                    b.iter(|| {
                        aba(
                            &chain,
                            &mut ws,
                            black_box(&q),
                            black_box(&qd),
                            &tau,
                            None,
                            &mut qdd,
                        )
                        .unwrap();
                        black_box(&qdd);
                    })
                }),
                1 => group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
                    b.iter(|| {
                        forward_dynamics_crba(
                            &chain,
                            &mut ws,
                            black_box(&q),
                            black_box(&qd),
                            &tau,
                            None,
                            &mut qdd,
                        )
                        .unwrap();
                        black_box(&qdd);
                    })
                }),
                _ => {
                    let mut nws = NaiveWorkspace::new(&chain);
                    group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
                        b.iter(|| {
                            naive_forward_dynamics(
                                &chain,
                                &mut ws,
                                &mut nws,
                                black_box(&q),
                                black_box(&qd),
                                &tau,
                                None,
                                &mut qdd,
                            )
                            .unwrap();
                            black_box(&qdd);
                        })
                    })
                }
            };
        }
        group.finish();
    }
}

fn batched(c: &mut Criterion) {
    for n in [2usize, 3, 5, 8, 12] {
        let mut group = c.benchmark_group(format!("soa_batch_aba_n{n}"));
        let mut rng = ChaCha8Rng::seed_from_u64(SEED + 1000 + n as u64);
        let chain = random_chain(&mut rng, n);
        for lanes in [1usize, 64, 1024, 16384] {
            let q = Mat::from_fn(lanes, n, |_, _| rng.random_range(-1.0..1.0));
            let qd = Mat::from_fn(lanes, n, |_, _| rng.random_range(-1.0..1.0));
            let tau = Mat::from_fn(lanes, n, |_, _| rng.random_range(-2.0..2.0));
            let mut qdd = Mat::zeros(lanes, n);
            let mut bw = BatchWorkspace::new(&chain, lanes);
            group.throughput(Throughput::Elements((lanes * n) as u64));
            group.bench_with_input(BenchmarkId::from_parameter(lanes), &lanes, |b, _| {
                b.iter(|| {
                    batch_aba(
                        &chain,
                        &mut bw,
                        black_box(&q),
                        black_box(&qd),
                        &tau,
                        None,
                        &mut qdd,
                    )
                    .unwrap();
                    black_box(&qdd);
                })
            });
        }
        group.finish();
    }
}

criterion_group!(benches, scalar, batched);
criterion_main!(benches);
