//! Brute-force orbit diagram of the simplest walker across the period-doubling cascade.

use pdw_hybrid::Options;
use pdw_limit::{
    find_fixed_point, orbit_diagram, NewtonOptions, OrbitOptions, OrbitStart, StrideMap,
};
use pdw_walkers::simplest::{Simplest, SimplestParams};

fn family(g: f64) -> Result<Box<Simplest>, pdw_walkers::WalkerError> {
    Simplest::new(SimplestParams {
        slope: g,
        ..Default::default()
    })
    .map(Box::new)
}

fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
}

#[test]
fn orbit_diagram_shows_periods_1_2_4_then_chaos_near_0189() {
    // Period doublings located by continuation at γ ≈ 0.015088, 0.017669, 0.018160 (see the
    // continuation tests); chaos near 0.0189 (Garcia 1998).
    let params = [0.0140, 0.0165, 0.0179, 0.0189];
    let opts = OrbitOptions {
        transient: 600,
        record: 128,
        ..Default::default()
    };
    // Start each slope at its (possibly unstable) period-one gait, slightly perturbed.
    let starts: Vec<Vec<f64>> = params
        .iter()
        .map(|&g| {
            let m = family(g).unwrap();
            let map = StrideMap::new(&*m, Options::dop853(1e-13)).unwrap();
            let guess = [0.2003 + 6.0 * (g - 0.009), -0.1998 - 5.6 * (g - 0.009)];
            let fp = find_fixed_point(&map, &guess, &NewtonOptions::default()).unwrap();
            vec![fp.section[0] + 1e-6, fp.section[1]]
        })
        .collect();
    let start = OrbitStart::PerParam(starts);
    let cols = orbit_diagram(&family, &params, &start, &opts, &pool(2)).unwrap();
    let periods: Vec<Option<usize>> = cols.iter().map(|c| c.period).collect();
    println!(
        "{periods:?} {:?}",
        cols.iter().map(|c| c.fall).collect::<Vec<_>>()
    );
    assert_eq!(&periods[..3], &[Some(1), Some(2), Some(4)]);
    let chaos = &cols[3];
    assert!(chaos.fall.is_none(), "{:?}", chaos.fall);
    assert_eq!(chaos.period, None);
    // No period-one convergence: successive strides stay apart.
    let min_step = chaos
        .points
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).abs().max((w[1][1] - w[0][1]).abs()))
        .fold(f64::INFINITY, f64::min);
    assert!(min_step > 1e-6, "{min_step}");
}

#[test]
fn orbit_diagram_is_identical_for_any_thread_count() {
    let params: Vec<f64> = (0..12).map(|i| 0.0175 + 1.5e-4 * i as f64).collect();
    let opts = OrbitOptions {
        transient: 100,
        record: 16,
        chunk: 3,
        ..Default::default()
    };
    let start = OrbitStart::FollowPrevious(vec![0.2003, -0.1998]);
    let a = orbit_diagram(&family, &params, &start, &opts, &pool(1)).unwrap();
    let b = orbit_diagram(&family, &params, &start, &opts, &pool(2)).unwrap();
    assert_eq!(a, b);
    assert_eq!(a.len(), params.len());
}
