//! Every attractor of the simplest walker (Garcia et al. 1998) past its first period doubling:
//! the period-2 gait at γ = 0.016 and the chaotic attractor at γ = 0.0189 found up front, their
//! basins labelled, and the labels independent of thread count and of how the cells are split.

use pdw_hybrid::Options;
use pdw_limit::gaits::{model_guesses, search, search_periodic};
use pdw_limit::{
    classify_cells, discover, dp_variational, grid_cells, linspace, seed_set, AttractorKind,
    AttractorSet, BasinOptions, CellResult, DiscoveryOptions, Outcome, StrideMap,
};
use pdw_walkers::simplest::{Simplest, SimplestParams};
use pdw_walkers::Walker;

fn simplest(gamma: f64) -> Simplest {
    Simplest::new(SimplestParams {
        slope: gamma,
        ..Default::default()
    })
    .unwrap()
}

fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// The CLI's default box around the period-one orbit (half-width max(25 %, 0.05)), its seeds,
/// the attractors found from them (on `threads` threads) and the grid's cells.
struct Setup {
    set: AttractorSet,
    cells: Vec<Vec<f64>>,
}

fn setup(m: &Simplest, threads: usize, n: usize) -> Setup {
    let (ones, _) = search(m, &model_guesses(m), 1e-12).unwrap();
    assert!(
        ones.iter().all(|f| !f.fp.stable),
        "past the period doubling"
    );
    let c = ones[0].fp.section.clone();
    let half = |v: f64| (0.25 * v.abs()).max(0.05);
    let (xr, yr) = (
        (c[0] - half(c[0]), c[0] + half(c[0])),
        (c[1] - half(c[1]), c[1] + half(c[1])),
    );
    let disc = DiscoveryOptions::default();
    let extra: Vec<Vec<f64>> = ones.iter().map(|f| f.fp.section.clone()).collect();
    let seeds = seed_set(&c, 0, xr, 1, yr, disc.lattice, &extra);
    let step = |x: &[f64]| m.step_length(x);
    let newton_map = StrideMap::new(m, Options::dop853(1e-14))
        .unwrap()
        .with_step_length(&step);
    let fall = Outcome::of_fall;
    let set = discover(
        m,
        &newton_map,
        None,
        &seeds,
        &BasinOptions::default(),
        &disc,
        &fall,
        &pool(threads),
    )
    .unwrap();
    let cells = grid_cells(&c, 0, &linspace(xr.0, xr.1, n), 1, &linspace(yr.0, yr.1, n));
    Setup { set, cells }
}

fn labels(m: &Simplest, s: &Setup, cells: &[Vec<f64>], threads: usize) -> Vec<CellResult> {
    let fall = Outcome::of_fall;
    let prob = s.set.problem(m, &fall);
    let mut r = classify_cells(
        &prob,
        cells,
        &BasinOptions::default(),
        &pool(threads),
        &|_| {},
    )
    .unwrap();
    s.set.relabel(&mut r);
    r
}

#[test]
fn the_basin_at_gamma_0_016_holds_the_period_two_gait() {
    let m = simplest(0.016);
    let s = setup(&m, 2, 60);
    // Exactly one attractor: the stable period-2 gait, named and coded as documented.
    assert_eq!(s.set.attractors.len(), 1, "{:?}", s.set.attractors);
    let a = &s.set.attractors[0];
    assert_eq!((a.name.as_str(), a.code, a.period_k), ("period-2", 16, 2));
    assert_eq!(a.kind, AttractorKind::Periodic);
    assert!(s.set.gait().is_none());
    assert!(a.multipliers.iter().all(|l| l.modulus() < 1.0));
    // The same orbit as `fixedpoint --period 2` (both from Newton on P² − id, the one here
    // started from a recurrence of the basin engine's coarser integrator).
    let (p2, _) = search_periodic(&m, &model_guesses(&m), 2, 1e-12).unwrap();
    let o = &p2.iter().find(|f| f.orbit.stable).unwrap().orbit;
    for p in &a.points {
        assert!(
            o.orbit.iter().any(|q| dist(p, q) < 1e-9),
            "{p:?} not on {:?}",
            o.orbit
        );
    }
    // Cells are labelled with the period-2 code; some of them walk on, none is `gait`.
    let r = labels(&m, &s, &s.cells, 2);
    let n2 = r.iter().filter(|c| c.outcome == 16).count();
    assert!(n2 > 0, "no cell labelled period-2");
    assert!(r.iter().all(|c| c.outcome() != Outcome::Gait));
    for c in r.iter().filter(|c| c.outcome == 16) {
        assert_eq!(c.attractor, 0);
        assert!(dist(&c.final_state, &a.points[0]).min(dist(&c.final_state, &a.points[1])) < 1e-6);
    }
    // Labels do not depend on the thread count or on how the grid is split (shards).
    let s1 = setup(&m, 1, 60);
    assert_eq!(s1.set, s.set);
    let half = s.cells.len() / 2 + 7;
    let mut split = labels(&m, &s1, &s.cells[..half], 1);
    split.extend(labels(&m, &s1, &s.cells[half..], 1));
    let key = |c: &CellResult| (c.outcome, c.strides, c.attractor);
    assert_eq!(
        r.iter().map(key).collect::<Vec<_>>(),
        split.iter().map(key).collect::<Vec<_>>()
    );
}

/// Largest Lyapunov exponent of the stride map along `n` strides from `s` (per stride), from
/// the exact Jacobians: ln of the growth of a renormalised tangent vector, averaged.
fn lyapunov(map: &StrideMap<'_>, s: &[f64], n: usize) -> f64 {
    let mut x = s.to_vec();
    let mut v = [1.0, 0.0];
    let mut sum = 0.0;
    for _ in 0..n {
        let (st, dp) = dp_variational(map, &x).unwrap();
        assert!(st.outcome.is_ok());
        let w = [dp[0] * v[0] + dp[1] * v[1], dp[2] * v[0] + dp[3] * v[1]];
        let g = w[0].hypot(w[1]);
        sum += g.ln();
        v = [w[0] / g, w[1] / g];
        x = st.next;
    }
    sum / n as f64
}

#[test]
fn gamma_0_0189_is_chaotic_and_its_walking_cells_are_labelled_chaotic() {
    let m = simplest(0.0189);
    let s = setup(&m, 2, 40);
    assert_eq!(s.set.attractors.len(), 1, "{:?}", s.set.attractors);
    let a = &s.set.attractors[0];
    assert_eq!((a.name.as_str(), a.code, a.period_k), ("chaotic", 16, 0));
    assert_eq!(a.kind, AttractorKind::Chaotic);
    assert!(a.multipliers.is_empty() && a.period_time.is_nan());
    // Independent evidence of chaos on the sample, with the tight integrator: (1) no
    // recurrence — no point of 600 strides returns within 1e-6 of itself after p ≤ 16 strides;
    // (2) a positive largest Lyapunov exponent from the exact (variational) Jacobians.
    let map = StrideMap::new(&m, Options::dop853(1e-13)).unwrap();
    let mut x = a.points[a.points.len() - 1].clone();
    let mut orbit = vec![x.clone()];
    for _ in 0..600 {
        x = map.apply(&x).expect("the chaotic attractor keeps walking");
        orbit.push(x.clone());
    }
    let closest = (1..=16)
        .flat_map(|p| (p..orbit.len()).map(move |i| (i, p)))
        .map(|(i, p)| dist(&orbit[i], &orbit[i - p]))
        .fold(f64::INFINITY, f64::min);
    assert!(closest > 1e-6, "a near-recurrence {closest:e}");
    let le = lyapunov(&map, &orbit[100], 400);
    eprintln!("closest return {closest:e}, largest Lyapunov exponent {le} per stride");
    assert!(le > 0.02, "largest Lyapunov exponent {le} per stride");
    // Cells labelled chaotic walked the whole budget and ended near the sample.
    let r = labels(&m, &s, &s.cells, 2);
    let chaotic: Vec<&CellResult> = r.iter().filter(|c| c.outcome == 16).collect();
    assert!(!chaotic.is_empty());
    for c in &chaotic {
        assert_eq!(c.strides, BasinOptions::default().max_strides);
        assert!(a.distance(&c.final_state) <= a.radius);
    }
    assert!(r.iter().all(|c| c.outcome() != Outcome::Gait));
}

#[test]
fn at_gamma_0_0177_the_attractor_is_the_period_four_gait_of_the_period_k_search() {
    let m = simplest(0.0177);
    let s = setup(&m, 2, 20);
    assert_eq!(s.set.attractors.len(), 1, "{:?}", s.set.attractors);
    let a = &s.set.attractors[0];
    assert_eq!((a.name.as_str(), a.period_k), ("period-4", 4));
    let (p4, _) = search_periodic(&m, &model_guesses(&m), 4, 1e-12).unwrap();
    let o = &p4.iter().find(|f| f.orbit.stable).unwrap().orbit;
    // Same cycle, stored from the same (smallest) point.
    for (p, q) in a.points.iter().zip(&o.orbit) {
        assert!(dist(p, q) < 1e-9, "{p:?} vs {q:?}");
    }
    for (x, y) in a.multipliers.iter().zip(&o.multipliers) {
        assert!(
            (x.re - y.re).abs() + (x.im - y.im).abs() < 1e-8,
            "{x:?} vs {y:?}"
        );
    }
}
