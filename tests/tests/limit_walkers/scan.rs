//! Gaits found without a guess ([`pdw_limit::scan`]), each against a reference the scan does not
//! use: the simplest walker's two period-one gaits at γ = 0.009 (Garcia et al. 1998, values of
//! REFERENCES §1 held here), the rimless wheel's rolling fixed point from Coleman's closed-form
//! return map (written here), and the simplest walker's period-2 attractor at γ = 0.016 checked
//! on a walk of the trajectory recorder (another integration path) from a start the scan did not
//! see. Also: the accounting of the starts, and the same result on one and two threads.

use pdw_limit::scan::{halton, scan, starts_in, Scan, ScanBox, ScanOptions};
use pdw_limit::trajectory::{self, TrajectoryOptions};
use pdw_walkers::rimless::{Rimless, RimlessParams};
use pdw_walkers::simplest::{Simplest, SimplestParams};
use pdw_walkers::Walker;

fn simplest(gamma: f64) -> Simplest {
    Simplest::new(SimplestParams {
        slope: gamma,
        ..Default::default()
    })
    .unwrap()
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

fn model_box(w: &dyn Walker) -> ScanBox {
    let (lo, hi) = w.section_box().expect("the model has a box");
    ScanBox { lo, hi }
}

/// Every start is accounted for once by where its iterates went.
fn assert_accounted(sc: &Scan) {
    let settled: usize = sc.gaits.iter().map(|g| g.attracted_starts).sum::<usize>()
        + sc.orbits.iter().map(|o| o.attracted_starts).sum::<usize>();
    assert_eq!(settled + sc.fell + sc.unsettled, sc.starts);
}

#[test]
fn halton_points_are_the_radical_inverses() {
    // base 2: 1 → 0.5, 2 → 0.25, 3 → 0.75; base 3: 1 → 1/3, 2 → 2/3, 3 → 1/9
    assert_eq!(halton(1, 2), vec![0.5, 1.0 / 3.0]);
    assert_eq!(halton(2, 2), vec![0.25, 2.0 / 3.0]);
    assert_eq!(halton(3, 2), vec![0.75, 1.0 / 9.0]);
    let b = ScanBox {
        lo: vec![-1.0, 10.0],
        hi: vec![1.0, 13.0],
    };
    let s = starts_in(&b, 3);
    assert_eq!(s[0], vec![0.0, 11.0]);
    assert_eq!(s[2], vec![0.5, 10.0 + 3.0 / 9.0]);
}

#[test]
fn both_of_garcias_gaits_are_found_without_a_guess() {
    let w = simplest(0.009);
    let sc = scan(&w, &model_box(&w), &ScanOptions::new(256, 1e-12), &pool(2)).unwrap();
    assert_accounted(&sc);
    assert_eq!(
        sc.gaits.len(),
        2,
        "{:?}",
        sc.gaits.iter().map(|g| &g.fp.section).collect::<Vec<_>>()
    );
    let stable = sc
        .gaits
        .iter()
        .find(|g| g.fp.stable)
        .expect("a stable gait");
    let unstable = sc
        .gaits
        .iter()
        .find(|g| !g.fp.stable)
        .expect("an unstable gait");
    for (g, want) in [
        (stable, [0.20031090049483, -0.19983247291764]),
        (unstable, [0.19393736960624, -0.20386692731962]),
    ] {
        assert!(
            (g.fp.section[0] - want[0]).abs() < 1e-9 && (g.fp.section[1] - want[1]).abs() < 1e-9,
            "{:?} vs {want:?}",
            g.fp.section
        );
        assert!(g.newton_starts > 0);
    }
    // the stable gait attracts starts, the unstable one (|λ| ≈ 4) none
    assert!(stable.attracted_starts > 0);
    assert_eq!(unstable.attracted_starts, 0);
    assert!(sc.orbits.is_empty());
}

#[test]
fn the_rimless_wheel_rolls_to_colemans_closed_form_fixed_point() {
    let p = RimlessParams {
        slope: 0.08,
        n_spokes: 8.0,
        ..Default::default()
    };
    let w = Rimless::new(p).unwrap();
    let sc = scan(&w, &model_box(&w), &ScanOptions::new(24, 1e-12), &pool(2)).unwrap();
    assert_accounted(&sc);
    // ω' = cos 2α √(ω² + 4 (g/l) sin α sin γ): ω*² = cos² 2α · 4 (g/l) sin α sin γ / sin² 2α
    let a = std::f64::consts::PI / p.n_spokes;
    let c = (2.0 * a).cos();
    let want = (c * c * 4.0 * p.g / p.l * a.sin() * p.slope.sin() / (2.0 * a).sin().powi(2)).sqrt();
    assert_eq!(sc.gaits.len(), 1);
    let g = &sc.gaits[0];
    assert!(g.fp.stable);
    assert!(
        (g.fp.section[0] - want).abs() < 1e-10 * want,
        "{} vs {want}",
        g.fp.section[0]
    );
    // every start that rolls on settles on it (the map contracts); slow starts roll back
    assert_eq!(g.attracted_starts + sc.fell, sc.starts);
    assert_eq!(sc.unsettled, 0);
}

#[test]
fn past_the_first_period_doubling_the_scan_finds_the_period_two_attractor() {
    let w = simplest(0.016);
    let sc = scan(&w, &model_box(&w), &ScanOptions::new(256, 1e-12), &pool(2)).unwrap();
    assert_accounted(&sc);
    let two: Vec<_> = sc.orbits.iter().filter(|o| o.orbit.period_k == 2).collect();
    assert_eq!(two.len(), 1);
    let orbit = &two[0].orbit;
    // reached from the box and from next to the unstable gait it was born from
    assert!(orbit.stable && two[0].attracted_starts + two[0].near_gaits > 0);
    assert!(sc.near_gait_starts >= 2);
    // no stable period-one gait is left; the period-one gaits found are unstable
    assert!(sc.gaits.iter().all(|g| !g.fp.stable));
    // A walk of 300 steps from near the orbit, on the trajectory recorder, alternates between
    // its two points at the end.
    let mut start = orbit.states[0].clone();
    start[0] += 1e-4;
    let tr = trajectory::simulate(&w, &start, &TrajectoryOptions::new(300)).unwrap();
    assert!(tr.outcome.is_ok());
    let pts: Vec<&[f64]> = tr.section.chunks(2).collect();
    let (a, b) = (pts[pts.len() - 2], pts[pts.len() - 1]);
    let near = |p: &[f64], q: &[f64]| (p[0] - q[0]).abs() < 1e-7 && (p[1] - q[1]).abs() < 1e-7;
    let (o0, o1) = (&orbit.orbit[0], &orbit.orbit[1]);
    assert!(
        (near(a, o0) && near(b, o1)) || (near(a, o1) && near(b, o0)),
        "walk ends {a:?} {b:?}, orbit {o0:?} {o1:?}"
    );
}

#[test]
fn the_scan_is_the_same_on_one_and_two_threads() {
    let w = simplest(0.012);
    let b = model_box(&w);
    let opts = ScanOptions::new(64, 1e-12);
    let (one, two) = (
        scan(&w, &b, &opts, &pool(1)).unwrap(),
        scan(&w, &b, &opts, &pool(2)).unwrap(),
    );
    assert_eq!(one.gaits.len(), two.gaits.len());
    for (x, y) in one.gaits.iter().zip(&two.gaits) {
        assert_eq!(x.fp.section, y.fp.section);
        assert_eq!(
            (x.newton_starts, x.attracted_starts),
            (y.newton_starts, y.attracted_starts)
        );
    }
    assert_eq!((one.fell, one.unsettled), (two.fell, two.unsettled));
}

#[test]
fn a_bad_box_or_option_is_refused() {
    let w = simplest(0.009);
    let bad = [
        ScanBox {
            lo: vec![0.1],
            hi: vec![0.2],
        },
        ScanBox {
            lo: vec![0.3, -0.1],
            hi: vec![0.2, -0.05],
        },
        ScanBox {
            lo: vec![0.1, f64::NAN],
            hi: vec![0.2, -0.05],
        },
    ];
    for b in bad {
        assert!(
            scan(&w, &b, &ScanOptions::new(4, 1e-12), &pool(1)).is_err(),
            "{b:?}"
        );
    }
    let opts = ScanOptions {
        iterates: 3,
        ..ScanOptions::new(4, 1e-12)
    };
    assert!(scan(&w, &model_box(&w), &opts, &pool(1)).is_err());
}

/// On a level floor there is no passive gait (nothing makes up the impacts' losses): the scan
/// reports none — its starts fall or shrink towards standing still, and the numerically neutral
/// micro-steps Newton can reach there are below the scan's shortest step.
#[test]
fn a_scan_finds_no_gait_on_a_level_floor() {
    let w = simplest(0.0);
    let sc = scan(&w, &model_box(&w), &ScanOptions::new(256, 1e-12), &pool(2)).unwrap();
    assert_accounted(&sc);
    assert!(sc.gaits.is_empty() && sc.orbits.is_empty());
}

/// The gaits and orbits of two scans, by their points (the scan's order).
fn found(sc: &Scan) -> (Vec<Vec<f64>>, Vec<Vec<Vec<f64>>>) {
    (
        sc.gaits.iter().map(|g| g.fp.section.clone()).collect(),
        sc.orbits.iter().map(|o| o.orbit.orbit.clone()).collect(),
    )
}

/// The Newton budget a sweep's start scan uses (12 iterations a start, 64 starts) finds what
/// the default budget (40) finds, on every model and slope scanned above: the simplest
/// walker's two gaits at 0.009, its period-2 attractor at 0.016, nothing on a level floor, the
/// rimless wheel's rolling gait.
#[test]
fn a_capped_newton_budget_finds_the_same_gaits() {
    let rimless = Rimless::new(RimlessParams {
        slope: 0.08,
        n_spokes: 8.0,
        ..Default::default()
    })
    .unwrap();
    let walkers: Vec<Box<dyn Walker>> = vec![
        Box::new(simplest(0.009)),
        Box::new(simplest(0.016)),
        Box::new(simplest(0.0)),
        Box::new(rimless),
    ];
    for w in &walkers {
        let b = model_box(w.as_ref());
        let full = ScanOptions::new(64, 1e-12);
        let capped = ScanOptions {
            newton_max_iters: 12,
            ..full.clone()
        };
        let (x, y) = (
            scan(w.as_ref(), &b, &full, &pool(2)).unwrap(),
            scan(w.as_ref(), &b, &capped, &pool(2)).unwrap(),
        );
        let ((gx, ox), (gy, oy)) = (found(&x), found(&y));
        assert_eq!((gx.len(), ox.len()), (gy.len(), oy.len()));
        let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(u, v)| (u - v).abs() < 1e-9);
        assert!(
            gx.iter().zip(&gy).all(|(a, b)| close(a, b)),
            "{gx:?} {gy:?}"
        );
        for (a, b) in ox.iter().zip(&oy) {
            assert!(a.iter().zip(b).all(|(p, q)| close(p, q)), "{a:?} {b:?}");
        }
    }
}
