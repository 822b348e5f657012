//! The lockstep Monte Carlo walk on random slopes and step heights (pdw-limit's `lockstep`): a
//! walker's fate does not depend on the thread count, the lane count or the chunk size, and the
//! walk agrees with the independent scalar walk (the model rebuilt at each line's slope or
//! step height, one stride at a time) — the same fates for nearly every walker, the same MFPT
//! within its standard error, the same fall kinds.

use pdw::mfpt;
use pdw_limit::ensemble::{monte_carlo_lockstep, Lockstep};
use pdw_limit::terrain::{self, Fate, SlopeTerrain, SlopeWalk, TerrainKind};

fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
}

fn model(name: &str, slope: f64) -> pdw::BuiltModel {
    pdw::build(name, &[("slope".to_string(), slope)]).unwrap()
}

fn terrain(mean: f64, sd: f64) -> SlopeTerrain {
    SlopeTerrain {
        mean,
        sd,
        seed: 11,
        kind: TerrainKind::Slope,
        dist: Default::default(),
    }
}

/// The walkers' fates in lockstep with `batch` on `threads` threads.
fn lockstep(
    m: &pdw::BuiltModel,
    t: &SlopeTerrain,
    walkers: usize,
    steps: usize,
    threads: usize,
    batch: Lockstep,
) -> Vec<Fate> {
    let at = mfpt::model_at(m);
    let walk = SlopeWalk::new(&at, t.mean, mfpt::default_integrator()).unwrap();
    let (x0, _) = mfpt::start(m).unwrap();
    monte_carlo_lockstep(
        &walk,
        t,
        &x0,
        walkers,
        steps,
        &pool(threads),
        batch,
        &|_| {},
    )
    .unwrap()
}

#[test]
fn a_walkers_fate_is_the_same_for_any_thread_count_lane_count_and_chunk_size() {
    for (name, mean, sd) in [
        ("compass", 0.05235987755982988, 0.5f64.to_radians()),
        ("simplest", 0.009, 0.0005),
    ] {
        let m = model(name, mean);
        let t = terrain(mean, sd);
        let (walkers, steps) = (96, 30);
        let reference = lockstep(&m, &t, walkers, steps, 1, Lockstep { lanes: 1, chunk: 1 });
        // the terrain makes walkers fall and leaves some walking: both kinds are compared
        assert!(reference.iter().any(|f| f.end.is_some()), "{name}");
        assert!(reference.iter().any(|f| f.end.is_none()), "{name}");
        for (threads, lanes, chunk) in [(2, 1, 1), (1, 8, 3), (2, 8, 16), (1, 64, 16), (2, 64, 5)] {
            let f = lockstep(&m, &t, walkers, steps, threads, Lockstep { lanes, chunk });
            assert_eq!(
                f, reference,
                "{name}: {threads} threads, {lanes} lanes, chunk {chunk}"
            );
        }
    }
}

/// Counts of walkers whose fates differ between the two walks, and the largest difference of
/// their step counts.
fn differences(a: &[Fate], b: &[Fate]) -> (usize, usize) {
    let diff: Vec<usize> = a
        .iter()
        .zip(b)
        .filter(|(x, y)| x != y)
        .map(|(x, y)| x.steps.abs_diff(y.steps))
        .collect();
    (diff.len(), diff.iter().copied().max().unwrap_or(0))
}

#[test]
fn the_lockstep_walk_agrees_with_the_scalar_walk_on_every_model() {
    let cases = [
        ("simplest", 0.009, 0.0005, 2000, 200),
        (
            "compass",
            0.05235987755982988,
            0.5f64.to_radians(),
            2000,
            100,
        ),
        ("kneed", 0.0504, 0.5f64.to_radians(), 400, 50),
        ("rimless", 0.08, 0.5f64.to_radians(), 2000, 200),
    ];
    for (name, mean, sd, walkers, steps) in cases {
        let m = model(name, mean);
        let t = terrain(mean, sd);
        let at = mfpt::model_at(&m);
        let walk = SlopeWalk::new(&at, mean, mfpt::default_integrator()).unwrap();
        let (x0, _) = mfpt::start(&m).unwrap();
        let p = pool(2);
        let scalar =
            terrain::monte_carlo_scalar(&walk, &t, &x0, walkers, steps, &p, &|_| {}).unwrap();
        let batch = Lockstep::for_pool(walkers, 2);
        let lock =
            monte_carlo_lockstep(&walk, &t, &x0, walkers, steps, &p, batch, &|_| {}).unwrap();
        let (n_diff, max_steps_diff) = differences(&scalar, &lock);
        let (es, el) = (
            terrain::estimate(&scalar, steps),
            terrain::estimate(&lock, steps),
        );
        println!(
            "{name}: {n_diff} of {walkers} fates differ (largest step difference \
             {max_steps_diff}); MFPT scalar {:.4} ± {:.4}, lockstep {:.4} ± {:.4}; falls {} / {}",
            es.mfpt, es.stderr, el.mfpt, el.stderr, es.falls, el.falls
        );
        assert!(
            es.falls > walkers / 10,
            "{name}: the terrain makes walkers fall"
        );
        // the two walks differ only in the rounding of the flow's angle: a walker's fate
        // changes only where it passes a fall's boundary within that rounding
        assert!(
            n_diff * 100 <= walkers,
            "{name}: {n_diff} of {walkers} fates differ"
        );
        assert!(
            (es.mfpt - el.mfpt).abs() < es.stderr.min(el.stderr),
            "{name}: MFPT {} ± {} against {} ± {}",
            es.mfpt,
            es.stderr,
            el.mfpt,
            el.stderr
        );
        assert_eq!(es.failures.len(), el.failures.len(), "{name}");
    }
}

/// The walkers' fates on random step heights (mean `mean`, standard deviation `sd`, model at
/// slope `slope`): in lockstep with `batch` on `threads` threads (`None`: the scalar walk).
#[allow(clippy::too_many_arguments)]
fn on_heights(
    m: &pdw::BuiltModel,
    mean: f64,
    sd: f64,
    walkers: usize,
    steps: usize,
    threads: usize,
    batch: Option<Lockstep>,
) -> Vec<Fate> {
    let at = mfpt::model_at_param(m, "step_down");
    let walk =
        SlopeWalk::with_kind(&at, TerrainKind::StepDown, mean, mfpt::default_integrator()).unwrap();
    let t = SlopeTerrain {
        mean,
        sd,
        seed: 3,
        kind: TerrainKind::StepDown,
        dist: Default::default(),
    };
    let (x0, _) = mfpt::start(m).unwrap();
    let p = pool(threads);
    match batch {
        Some(b) => monte_carlo_lockstep(&walk, &t, &x0, walkers, steps, &p, b, &|_| {}),
        None => terrain::monte_carlo_scalar(&walk, &t, &x0, walkers, steps, &p, &|_| {}),
    }
    .unwrap()
}

/// Models on random step heights: name, slope, mean and standard deviation of the height,
/// walkers, step limit.
const HEIGHT_CASES: [(&str, f64, f64, f64, usize, usize); 3] = [
    ("compass", 0.05235987755982988, 0.0, 0.004, 2000, 100),
    ("rimless", 0.08, 0.0, 0.03, 2000, 200),
    ("simplest", 0.009, 0.0, 0.0004, 2000, 1000),
];

/// Beyond [`HEIGHT_CASES`] for the agreement: the simplest walker at σ = 0.0002 (MFPT ≈ 100),
/// where its strikes onto a step down just after mid-stance — windows of a few hundredths of
/// a time unit, between two of a step's samples — decide many fates (264 of 2000 differed
/// while the detection missed them).
const HEIGHT_AGREEMENT_EXTRA: [(&str, f64, f64, f64, usize, usize); 1] =
    [("simplest", 0.009, 0.0, 0.0002, 2000, 1000)];

#[test]
fn on_step_heights_a_walkers_fate_is_the_same_for_any_thread_count_and_lane_count() {
    for (name, slope, mean, sd, _, _) in HEIGHT_CASES {
        let m = model(name, slope);
        // MFPTs of about 13, 4 and 15 steps: ten steps leave some walking and make some fall
        let (walkers, steps) = (96, 10);
        let reference = on_heights(
            &m,
            mean,
            sd,
            walkers,
            steps,
            1,
            Some(Lockstep { lanes: 1, chunk: 1 }),
        );
        assert!(reference.iter().any(|f| f.end.is_some()), "{name}");
        assert!(reference.iter().any(|f| f.end.is_none()), "{name}");
        for (threads, lanes, chunk) in [(2, 1, 1), (1, 8, 3), (2, 64, 5)] {
            let f = on_heights(
                &m,
                mean,
                sd,
                walkers,
                steps,
                threads,
                Some(Lockstep { lanes, chunk }),
            );
            assert_eq!(
                f, reference,
                "{name}: {threads} threads, {lanes} lanes, chunk {chunk}"
            );
        }
    }
}

#[test]
fn on_step_heights_the_lockstep_walk_agrees_with_the_scalar_walk() {
    for (name, slope, mean, sd, walkers, steps) in
        HEIGHT_CASES.into_iter().chain(HEIGHT_AGREEMENT_EXTRA)
    {
        heights_agree(name, &model(name, slope), mean, sd, walkers, steps);
    }
}

/// The scalar and the lockstep walk of `m` on random step heights: at most 1 % of the fates
/// differ, the MFPTs within the smaller standard error, the same kinds of fall, and the
/// terrain makes more than a tenth of the walkers fall.
fn heights_agree(
    name: &str,
    m: &pdw::BuiltModel,
    mean: f64,
    sd: f64,
    walkers: usize,
    steps: usize,
) {
    let scalar = on_heights(m, mean, sd, walkers, steps, 2, None);
    let lock = on_heights(
        m,
        mean,
        sd,
        walkers,
        steps,
        2,
        Some(Lockstep::for_pool(walkers, 2)),
    );
    let (n_diff, max_steps_diff) = differences(&scalar, &lock);
    let (es, el) = (
        terrain::estimate(&scalar, steps),
        terrain::estimate(&lock, steps),
    );
    println!(
        "{name} on heights: {n_diff} of {walkers} fates differ (largest step difference \
         {max_steps_diff}); MFPT scalar {:.4} ± {:.4}, lockstep {:.4} ± {:.4}; falls {} / {}; \
         kinds {:?} / {:?}",
        es.mfpt, es.stderr, el.mfpt, el.stderr, es.falls, el.falls, es.failures, el.failures
    );
    assert!(
        es.falls > walkers / 10,
        "{name}: the terrain makes walkers fall"
    );
    assert!(
        n_diff * 100 <= walkers,
        "{name}: {n_diff} of {walkers} fates differ"
    );
    assert!(
        (es.mfpt - el.mfpt).abs() < es.stderr.min(el.stderr),
        "{name}: MFPT {} ± {} against {} ± {}",
        es.mfpt,
        es.stderr,
        el.mfpt,
        el.stderr
    );
    // the same kinds of fall
    let kinds = |e: &terrain::MfptEstimate| -> Vec<String> {
        e.failures.iter().map(|f| f.0.clone()).collect()
    };
    assert_eq!(kinds(&es), kinds(&el), "{name}: fall kinds");
}

#[test]
fn step_heights_run_in_lockstep_and_the_walk_refuses_a_terrain_of_the_other_kind() {
    let m = pdw::build("rimless", &[("slope".to_string(), 0.08)]).unwrap();
    let at = mfpt::model_at_param(&m, "step_down");
    let walk =
        SlopeWalk::with_kind(&at, TerrainKind::StepDown, 0.0, mfpt::default_integrator()).unwrap();
    let t = SlopeTerrain {
        mean: 0.0,
        sd: 0.01,
        seed: 3,
        kind: TerrainKind::StepDown,
        dist: Default::default(),
    };
    let (x0, _) = mfpt::start(&m).unwrap();
    let p = pool(2);
    // `monte_carlo` runs step heights in lockstep
    let a = terrain::monte_carlo(&walk, &t, &x0, 16, 20, &p, &|_| {}).unwrap();
    let b = monte_carlo_lockstep(
        &walk,
        &t,
        &x0,
        16,
        20,
        &p,
        Lockstep::for_pool(16, 2),
        &|_| {},
    )
    .unwrap();
    assert_eq!(a, b);
    // a slope terrain on a walk of step heights is refused, naming both
    let slopes = SlopeTerrain {
        kind: TerrainKind::Slope,
        ..t
    };
    let e = monte_carlo_lockstep(
        &walk,
        &slopes,
        &x0,
        4,
        5,
        &p,
        Lockstep::for_pool(4, 2),
        &|_| {},
    );
    let e = e.unwrap_err().to_string();
    assert!(e.contains("slope") && e.contains("step_down"), "{e}");
}

/// Round feet on random step heights: the compass of Goswami et al. with arc feet of a tenth
/// of its leg. The lockstep walk (the mean model's guards, admissibility and impact at each
/// lane's height) against the scalar walk (the model rebuilt with `step_down` at each drawn
/// height), as for the point-foot models above.
#[test]
fn on_step_heights_round_feet_walk_in_lockstep_as_in_the_scalar_walk() {
    let m = crate::mfpt::round_compass();
    heights_agree("compass with round feet", &m, 0.0, 0.004, 1000, 200);
}
