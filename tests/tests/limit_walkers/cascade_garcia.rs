//! The simplest walker's period-doubling cascade followed by a sweep ([`pdw_limit::sweep`],
//! `max_period`), and a sweep started inside its range ([`SweepSpec::from`]), each against a
//! route the sweep does not take: every located period doubling (1→2, 2→4, 4→8) against
//! bisection on the most negative multiplier of periodic orbits found directly by Newton on
//! `P^k` with a finite-difference Jacobian; every point of a period-2k branch against the plain
//! stride map iterated 2k and k times; the successive doubling intervals against Feigenbaum's
//! δ = 4.669… (Feigenbaum 1978) and Garcia et al. 1998 (first doubling ≈ 0.0151, chaos near
//! 0.0189); and a sweep started in the middle against the one started at A, point for point.

use pdw_hybrid::Options;
use pdw_limit::sweep::{sweep, Silent, Sweep, SweepSpec};
use pdw_limit::{
    find_fixed_point, find_periodic_orbit, grid_options, BifurcationKind, DpMethod, FdScheme,
    NewtonOptions, StrideMap,
};
use pdw_walkers::simplest::{Simplest, SimplestParams};
use pdw_walkers::{Walker, WalkerError};

fn family(g: f64) -> Result<Box<dyn Walker>, WalkerError> {
    Simplest::new(SimplestParams {
        slope: g,
        ..Default::default()
    })
    .map(|w| Box::new(w) as Box<dyn Walker>)
}

fn pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
}

/// The stable period-one gait at `g` (Newton from Garcia's gait at 0.009).
fn gait_at(g: f64) -> Vec<f64> {
    let w = family(g).unwrap();
    let map = StrideMap::new(w.as_ref(), Options::dop853(1e-13)).unwrap();
    let guess = [0.20031090049483, -0.19983247291764];
    find_fixed_point(&map, &guess, &NewtonOptions::default())
        .unwrap()
        .section
}

fn run(spec: &SweepSpec, start: &[f64]) -> Sweep {
    let opts = grid_options(spec.lo, spec.hi, spec.n);
    sweep(&family, "slope", start, spec, &opts, &pool(), &Silent).unwrap()
}

/// Most negative real multiplier + 1 of the period-k orbit at γ found directly (Newton on P^k
/// from `guess`, multipliers from a finite-difference DP^k), and the orbit's first point.
fn pd_test_direct(gamma: f64, guess: &[f64], k: usize) -> (f64, Vec<f64>) {
    let w = family(gamma).unwrap();
    let map = StrideMap::new(w.as_ref(), Options::dop853(1e-13)).unwrap();
    let opts = NewtonOptions {
        dp_report: DpMethod::FiniteDifference {
            scheme: FdScheme::default(),
            lanes: 8,
        },
        ..Default::default()
    };
    let o = find_periodic_orbit(&map, guess, k, &opts).unwrap();
    let most_negative = o
        .multipliers
        .iter()
        .filter(|l| l.im == 0.0)
        .map(|l| l.re)
        .fold(f64::INFINITY, f64::min);
    (most_negative + 1.0, o.orbit[0].clone())
}

/// The period doubling of the period-k orbits through `guess`, by bisection on
/// [`pd_test_direct`] in `[lo, hi]` (the sign change there checked) to 1e-11.
fn pd_by_bisection(mut lo: f64, mut hi: f64, guess: &[f64], k: usize) -> f64 {
    let (flo, mut guess) = pd_test_direct(lo, guess, k);
    let (fhi, _) = pd_test_direct(hi, &guess, k);
    assert!(
        flo > 0.0 && fhi < 0.0,
        "period {k}: {flo} at {lo}, {fhi} at {hi}"
    );
    while hi - lo > 1e-11 {
        let mid = 0.5 * (lo + hi);
        let (f, s) = pd_test_direct(mid, &guess, k);
        guess = s;
        if f > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

#[test]
fn a_sweep_follows_garcias_cascade_to_period_eight() {
    let spec = SweepSpec {
        max_period: 8,
        ..SweepSpec::new(0.009, 0.0186, 13)
    };
    let sw = run(&spec, &gait_at(0.009));
    assert!(sw.warnings.is_empty(), "{:?}", sw.warnings);
    let names: Vec<&str> = sw.continued.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["period-1", "period-2", "period-4", "period-8"]);
    // The first period doubling of each branch: 1→2, 2→4, 4→8, 8→16.
    let pds: Vec<_> = sw
        .continued
        .iter()
        .map(|(_, b)| {
            b.bifurcations
                .iter()
                .find(|x| x.kind == BifurcationKind::PeriodDoubling)
                .expect("each branch doubles in the range")
        })
        .collect();
    let g: Vec<f64> = pds.iter().map(|p| p.param).collect();
    println!("period doublings at γ = {g:.12?}");
    for (i, pd) in pds.iter().enumerate().take(3) {
        let k = 1 << i;
        assert_eq!(pd.period_strides, k);
        let direct = pd_by_bisection(pd.param - 2e-5, pd.param + 2e-5, &pd.section, k);
        println!(
            "period {k}: continuation {:.12}, direct {direct:.12}",
            pd.param
        );
        assert!((pd.param - direct).abs() < 1e-7, "{} vs {direct}", pd.param);
    }
    // Garcia 1998: the first doubling near 0.0151, the cascade below the chaos near 0.0189.
    assert!((g[0] - 0.0151).abs() < 1e-3 && g[3] < 0.0189);
    // Feigenbaum: δ_i = (γ_{i+1} − γ_i)/(γ_{i+2} − γ_{i+1}) → 4.669… along the cascade.
    let d1 = (g[1] - g[0]) / (g[2] - g[1]);
    let d2 = (g[2] - g[1]) / (g[3] - g[2]);
    println!("δ₁ = {d1:.4}, δ₂ = {d2:.4}");
    assert!(d1 > 3.0 && d1 < 7.0 && d2 > 3.0 && d2 < 7.0, "{d1} {d2}");
    assert!((d2 - 4.669).abs() < (d1 - 4.669).abs(), "{d1} {d2}");
    // Every point of a period-2k branch is a fixed point of P^{2k}, not of P^k.
    let mut min_gap = f64::INFINITY;
    for b in &sw.branches[1..] {
        let k2 = b.period_k;
        assert!(!b.points.is_empty(), "{} has points on the grid", b.name);
        for p in &b.points {
            let w = family(p.point.param).unwrap();
            let map = StrideMap::new(w.as_ref(), Options::dop853(1e-13)).unwrap();
            let mut s = p.point.section.clone();
            let mut half = Vec::new();
            for j in 0..k2 {
                s = map.apply(&s).unwrap();
                if j + 1 == k2 / 2 {
                    half = s.clone();
                }
            }
            assert!(
                dist(&s, &p.point.section) < 1e-9,
                "{} at {}",
                b.name,
                p.point.param
            );
            let gap = dist(&half, &p.point.section);
            min_gap = min_gap.min(gap);
            assert!(
                gap > 1e-5,
                "{} at {}: P^k moves it by {gap}",
                b.name,
                p.point.param
            );
        }
    }
    println!("smallest |P^k(s) − s| on the period-2k branches: {min_gap:.3e}");
}

#[test]
fn a_sweep_from_the_middle_equals_the_sweep_from_a() {
    let at_a = SweepSpec {
        max_period: 4,
        ..SweepSpec::new(0.005, 0.0185, 10)
    };
    let params = pdw_limit::linspace(at_a.lo, at_a.hi, at_a.n);
    let mid = SweepSpec {
        from: params[5],
        ..at_a
    };
    let (a, m) = (run(&at_a, &gait_at(at_a.lo)), run(&mid, &gait_at(mid.from)));
    assert!(a.warnings.is_empty() && m.warnings.is_empty());
    // The middle start's branch covers both sides of it, in order from A.
    let main = &m.continued[0].1;
    assert!(main.points.first().unwrap().param < at_a.lo);
    assert!(main.points.last().unwrap().param > at_a.hi);
    assert_eq!(a.branches.len(), 3);
    assert_eq!(m.branches.len(), a.branches.len());
    for (x, y) in a.branches.iter().zip(&m.branches) {
        assert_eq!((&x.name, x.points.len()), (&y.name, y.points.len()));
        for (p, q) in x.points.iter().zip(&y.points) {
            assert_eq!(p.point.param, q.point.param);
            assert!(
                dist(&p.point.section, &q.point.section) < 1e-9,
                "{} {}",
                x.name,
                p.point.param
            );
            assert!((p.point.period - q.point.period).abs() < 1e-8);
            assert_eq!(p.point.stable, q.point.stable);
        }
    }
    for ((_, x), (_, y)) in a.continued.iter().zip(&m.continued) {
        let pd = |b: &pdw_limit::Branch| {
            b.bifurcations
                .iter()
                .filter(|f| f.kind == BifurcationKind::PeriodDoubling)
                .map(|f| f.param)
                .collect::<Vec<_>>()
        };
        let (px, py) = (pd(x), pd(y));
        assert_eq!(px.len(), py.len());
        for (u, v) in px.iter().zip(&py) {
            assert!((u - v).abs() < 1e-8, "{u} vs {v}");
        }
    }
}
