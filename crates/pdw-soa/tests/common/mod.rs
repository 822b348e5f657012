//! Shared test helpers: seeded random chains and states.
#![allow(dead_code)]

use pdw_soa::{Chain, ChainBuilder, JointKind, Link};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// A random planar chain of `n` joints; roughly one joint in five is prismatic when
/// `prismatic` is true. Gravity 9.81 on a random slope.
pub fn random_chain(rng: &mut ChaCha8Rng, n: usize, prismatic: bool) -> Chain {
    let mut b = ChainBuilder::new()
        .gravity(9.81)
        .slope(rng.random_range(-0.2..0.2));
    for _ in 0..n {
        let len = rng.random_range(0.3..1.2);
        let ang: f64 = rng.random_range(-0.5..0.5);
        let to_next = [len * ang.sin(), -len * ang.cos()];
        let com = [
            rng.random_range(0.2..0.8) * to_next[0] + rng.random_range(-0.1..0.1),
            rng.random_range(0.2..0.8) * to_next[1] + rng.random_range(-0.1..0.1),
        ];
        let link = Link {
            to_next,
            com,
            mass: rng.random_range(0.5..3.0),
            inertia: rng.random_range(0.01..0.3),
        };
        let kind = if prismatic && rng.random_range(0.0..1.0) < 0.2 {
            let a: f64 = rng.random_range(-3.0..3.0);
            JointKind::Prismatic {
                axis: [a.cos(), a.sin()],
            }
        } else {
            JointKind::Revolute
        };
        b = b.joint(kind, link);
    }
    b.build().expect("random chain is valid")
}

pub fn random_vec(rng: &mut ChaCha8Rng, n: usize, lo: f64, hi: f64) -> Vec<f64> {
    (0..n).map(|_| rng.random_range(lo..hi)).collect()
}

/// Random state: angles in ±0.8 rad per joint (prismatic: ±0.3 m), rates ±1.5.
pub fn random_state(rng: &mut ChaCha8Rng, chain: &Chain) -> (Vec<f64>, Vec<f64>) {
    let n = chain.dof();
    let q = random_vec(rng, n, -0.8, 0.8);
    let qd = random_vec(rng, n, -1.5, 1.5);
    (q, qd)
}

pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

pub fn diff_norm(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

#[allow(clippy::too_many_arguments)]
/// Planar double pendulum of two uniform-density links hanging along −z at q = 0.
pub fn double_pendulum(
    m1: f64,
    m2: f64,
    l1: f64,
    l2: f64,
    lc1: f64,
    lc2: f64,
    i1: f64,
    i2: f64,
    g: f64,
    slope: f64,
) -> Chain {
    ChainBuilder::new()
        .gravity(g)
        .slope(slope)
        .revolute(Link {
            to_next: [0.0, -l1],
            com: [0.0, -lc1],
            mass: m1,
            inertia: i1,
        })
        .revolute(Link {
            to_next: [0.0, -l2],
            com: [0.0, -lc2],
            mass: m2,
            inertia: i2,
        })
        .build()
        .unwrap()
}
