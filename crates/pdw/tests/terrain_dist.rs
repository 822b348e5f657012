//! The terrain's distributions by name (`normal`, `uniform`, `file:PATH`): their draws against
//! their moments, the chain's quadrature of a list of values, the walk's independence of the
//! thread and lane count, and the messages for bad requests.

use pdw::mfpt::{self, MfptFlags, MfptPlan};
use pdw_limit::terrain::{self, empirical_nodes, SlopeTerrain, TerrainDist, TerrainKind};

const FLAGS: MfptFlags = MfptFlags {
    terrain: "--terrain",
    sd: "--sd",
    mean: "--mean",
    walkers: "--walkers",
    max_steps: "--max-strides",
    dist: "--dist",
};

/// `n` draws of `dist` over a grid of walkers and steps.
fn draws(dist: &TerrainDist, n: u64) -> Vec<f64> {
    (0..n).map(|i| dist.draw(7, i / 100, i % 100 + 1)).collect()
}

/// A uniform of unit variance: mean 0 (standard error `1/√N`), variance 1 (standard error
/// `√((E ξ⁴ − 1)/N)`, `E ξ⁴ = 9/5`), every draw inside `(−√3, √3)`; tolerances 4 standard
/// errors.
#[test]
fn uniform_draws_have_mean_zero_variance_one_and_stay_within_root_three() {
    let n = 200_000u64;
    let v = draws(&TerrainDist::Uniform, n);
    let nf = n as f64;
    let mean = v.iter().sum::<f64>() / nf;
    let var = v.iter().map(|x| x * x).sum::<f64>() / nf - mean * mean;
    assert!(mean.abs() < 4.0 / nf.sqrt(), "mean {mean}");
    assert!(
        (var - 1.0).abs() < 4.0 * (0.8 / nf).sqrt(),
        "variance {var}"
    );
    assert!(v.iter().all(|x| x.abs() < 3f64.sqrt()));
    // the half-width is reached: the extreme draws lie within 1e-3 of ±√3
    let top = v.iter().cloned().fold(0.0, f64::max);
    assert!(3f64.sqrt() - top < 1e-3, "largest draw {top}");
}

/// A list's draws take each value with probability `1/m` (binomial standard error
/// `√(p (1 − p)/N)`, tolerance 4 of them) and no other value.
#[test]
fn list_draws_take_each_value_equally_often() {
    let values = vec![-2.0, 0.5, 3.0, 7.25];
    let dist = TerrainDist::values("list", values.clone()).unwrap();
    let n = 100_000u64;
    let v = draws(&dist, n);
    let p = 1.0 / values.len() as f64;
    let se = (p * (1.0 - p) / n as f64).sqrt();
    for x in &values {
        let f = v.iter().filter(|y| *y == x).count() as f64 / n as f64;
        assert!((f - p).abs() < 4.0 * se, "value {x}: frequency {f}");
    }
    assert!(v.iter().all(|y| values.contains(y)));
}

/// The chain's quadrature of a list: its distinct values and frequencies when there are at
/// most `n`; else `n` equal-count bins of the sorted values at their means (by hand: the values
/// 1 … 100 in 10 bins are 5.5, 15.5, … each of weight 1/10).
#[test]
fn a_lists_quadrature_is_its_frequencies_or_equal_count_bins() {
    let (z, w) = empirical_nodes(&[2.0, 1.0, 2.0, 3.0, 2.0], 3);
    assert_eq!(z, vec![1.0, 2.0, 3.0]);
    assert_eq!(w, vec![0.2, 0.6, 0.2]);
    let shuffled: Vec<f64> = (0..100).map(|i| ((i * 37) % 100 + 1) as f64).collect();
    let (z, w) = empirical_nodes(&shuffled, 10);
    for j in 0..10 {
        assert!((z[j] - (5.5 + 10.0 * j as f64)).abs() < 1e-12, "{z:?}");
        assert!((w[j] - 0.1).abs() < 1e-15);
    }
    let dist = TerrainDist::values("list", shuffled).unwrap();
    assert_eq!(dist.quadrature(10), (z, w));
}

fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
}

/// Uniform and list draws walk the same on one and two threads in lockstep and one walker at
/// a time (any lane count): each draw is its walker's and step's own.
#[test]
fn uniform_and_list_walks_are_the_same_on_any_thread_count() {
    let m = pdw::build("simplest", &[("slope".to_string(), 0.009)]).unwrap();
    let (x0, _) = mfpt::start(&m).unwrap();
    for dist in [
        TerrainDist::Uniform,
        TerrainDist::values("list", vec![-1.5, 0.2, 1.3]).unwrap(),
    ] {
        let plan = MfptPlan {
            terrain: SlopeTerrain {
                mean: 0.009,
                sd: 0.0005,
                seed: 5,
                kind: TerrainKind::Slope,
                dist,
            },
            walkers: 24,
            max_strides: 40,
            integrator: mfpt::default_integrator(),
            stride_map: Default::default(),
        };
        let (f1, e1) = mfpt::run(&m, &plan, &x0, &pool(1), &|_| {}).unwrap();
        let (f2, e2) = mfpt::run(&m, &plan, &x0, &pool(2), &|_| {}).unwrap();
        let at = mfpt::model_at(&m);
        let walk = mfpt::walk_of(&at, &plan).unwrap();
        let scalar =
            terrain::monte_carlo_scalar(&walk, &plan.terrain, &x0, 24, 40, &pool(2), &|_| {})
                .unwrap();
        assert_eq!(f1, f2);
        assert_eq!(e1, e2);
        assert_eq!(
            f1.iter().map(|f| f.steps).collect::<Vec<_>>(),
            scalar.iter().map(|f| f.steps).collect::<Vec<_>>()
        );
        assert!(e1.falls > 0, "{e1:?}");
    }
}

/// Bad distributions are refused with messages naming the option and the reason.
#[test]
fn bad_distributions_are_refused_with_clear_messages() {
    let dir = std::env::temp_dir();
    let file = |name: &str, text: &str| {
        let p = dir.join(format!("pdw-dist-{}-{name}", std::process::id()));
        std::fs::write(&p, text).unwrap();
        p
    };
    let msg = |s: &str| mfpt::parse_dist(s, &FLAGS).unwrap_err().0;
    assert!(msg("cauchy").contains("'cauchy' is not one of normal, uniform, file:PATH"));
    assert!(msg("file:").contains("is not one of"));
    let missing = dir.join("pdw-no-such-dist-file.txt");
    assert!(msg(&format!("file:{}", missing.display())).contains("cannot read"));
    let empty = file("empty", "# nothing\n\n");
    assert!(msg(&format!("file:{}", empty.display())).contains("holds no value"));
    let nan = file("nan", "1\nnan\n");
    assert!(msg(&format!("file:{}", nan.display())).contains("line 2: 'nan' is not a finite"));
    let words = file("words", "1 2\n");
    assert!(msg(&format!("file:{}", words.display())).contains("line 1: '1 2'"));
    let ok = file("ok", "  0.5 # a comment\n-0.5\n");
    let d = mfpt::parse_dist(&format!("file:{}", ok.display()), &FLAGS).unwrap();
    assert_eq!(d.max_abs(), 0.5);
    for p in [empty, nan, words, ok] {
        std::fs::remove_file(p).unwrap();
    }
    assert!(TerrainDist::values("v", vec![1.0, f64::INFINITY])
        .unwrap_err()
        .contains("value 2 is inf"));
}
