//! Limit-cycle workloads of the simplest walker (Garcia 1998):
//! - `limit_fixed_point`: the stable gait at γ = 0.009 to `‖P(s) − s‖∞ ≤ 1e-12` from Garcia's
//!   small-slope asymptotic guess (App. A.2), Newton with the variational Jacobian, integrator
//!   DOP853 at 1e-14 (the CLI's choice for this tolerance) and at 1e-13; the result includes
//!   the independent residual check and the multipliers.
//! - `limit_continuation`: 400 accepted points of pseudo-arclength continuation in the slope from
//!   the stable gait at γ = 0.009 upwards (default options — DOP853 at 1e-13, Newton to 1e-11,
//!   bifurcation tests on — with the arclength step pinned to 1e-4 so that every iteration
//!   computes exactly 400 points, ending near γ ≈ 0.0138, below the first period doubling); and
//!   the default adaptive step from γ = 0.009 to the located first period doubling (γ ≈ 0.0151).
//! - `limit_orbit`: brute-force orbit diagrams over γ ∈ [0.0100, 0.0190] (period-one gait,
//!   cascade, chaos), 500 strides per slope (400 transient + 100 recorded; DOP853 at 1e-10),
//!   each slope started next to its period-one gait (`PerParam`, gaits found at setup), on a
//!   2-thread pool: a 100-slope slice and the full 1000 slopes.
//!
//! Run: `cargo bench -p pdw-benches --bench limit`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use pdw_hybrid::Options;
use pdw_limit::{
    continue_branch, find_fixed_point, orbit_diagram, BifurcationKind, BranchEnd,
    ContinuationOptions, NewtonOptions, OrbitColumn, OrbitOptions, OrbitStart, StrideMap,
};
use pdw_walkers::simplest::{GarciaGait, Simplest, SimplestParams};

const GAMMA: f64 = 0.009;

fn family(g: f64) -> Result<Box<Simplest>, pdw_walkers::WalkerError> {
    Simplest::new(SimplestParams {
        slope: g,
        ..SimplestParams::default()
    })
    .map(Box::new)
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
}

fn fixed_point(c: &mut Criterion) {
    let sys = family(GAMMA).expect("valid parameters");
    let guess = GarciaGait::LongPeriod.section_guess(GAMMA);
    let opts = NewtonOptions::default();
    assert_eq!(opts.tol, 1e-12);
    let mut group = c.benchmark_group("limit_fixed_point");
    group.measurement_time(Duration::from_secs(3));
    for itol in [1e-14, 1e-13] {
        let map = StrideMap::new(&*sys, Options::dop853(itol)).expect("valid options");
        let fp = find_fixed_point(&map, &guess, &opts).expect("fixed point");
        eprintln!(
            "fixed point (DOP853 {itol:e}): {:?}, residual {:e}, {} Newton iterations",
            fp.section, fp.residual, fp.iterations
        );
        group.bench_function(
            BenchmarkId::new("simplest_tol1e-12", format!("dop853_{itol:e}")),
            |b| b.iter(|| black_box(find_fixed_point(&map, black_box(&guess), &opts).expect("fp"))),
        );
    }
    group.finish();
}

fn continuation_opts(points: usize) -> ContinuationOptions {
    let mut opts = ContinuationOptions::new(0.0, 0.0151);
    opts.max_points = points;
    opts.ds_init = 1e-4;
    opts.ds_min = 1e-9;
    opts.ds_max = 1e-4;
    opts
}

fn continuation(c: &mut Criterion) {
    let start = [0.2003, -0.1998];
    let opts = continuation_opts(400);
    let branch = continue_branch(&family, &start, GAMMA, 1, &opts).expect("branch");
    let last = branch.points.last().expect("points");
    let newton: usize = branch.points.iter().map(|p| p.newton_iters).sum();
    eprintln!(
        "continuation: {} points, γ {GAMMA} → {:.6}, end {:?}, {} bifurcations, {newton} Newton iterations",
        branch.points.len(),
        last.param,
        branch.end,
        branch.bifurcations.len()
    );
    assert_eq!(branch.points.len(), 400);
    assert!(matches!(branch.end, BranchEnd::MaxPoints));
    let mut group = c.benchmark_group("limit_continuation");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5))
        .throughput(Throughput::Elements(400));
    group.bench_function("simplest_400_points", |b| {
        b.iter(|| {
            black_box(continue_branch(&family, black_box(&start), GAMMA, 1, &opts).expect("branch"))
        })
    });
    // The same branch with the default adaptive step (Δs ∈ [1e-9, 1e-2]), up to and including
    // the located first period doubling (γ ≈ 0.0151), as in the continuation tests.
    let mut pd_opts = ContinuationOptions::new(0.005, 0.017);
    pd_opts.stop_at = Some(BifurcationKind::PeriodDoubling);
    let branch = continue_branch(&family, &start, GAMMA, 1, &pd_opts).expect("branch");
    let n_pd = branch.points.len();
    eprintln!(
        "continuation to the first period doubling: {n_pd} points, end {:?}, bifurcation at γ = {:?}",
        branch.end,
        branch.bifurcations.first().map(|b| b.param)
    );
    group.throughput(Throughput::Elements(n_pd as u64));
    group.bench_function("simplest_to_first_pd_default_step", |b| {
        b.iter(|| {
            black_box(
                continue_branch(&family, black_box(&start), GAMMA, 1, &pd_opts).expect("branch"),
            )
        })
    });
    group.finish();
}

/// Strides actually integrated by an orbit diagram (a fall ends a column early).
fn strides_done(cols: &[OrbitColumn], per_column: usize) -> usize {
    cols.iter()
        .map(|c| c.fall.map_or(per_column, |(k, _)| k + 1))
        .sum()
}

/// Start states for an orbit diagram: the period-one gait at every slope (stable or not),
/// found by Newton from the previous slope's gait (natural continuation by hand, starting from
/// Garcia's asymptotic guess), each moved by 1e-6 so that an unstable gait is left for the
/// attractor nearby.
fn period_one_starts(params: &[f64]) -> Vec<Vec<f64>> {
    let mut guess = GarciaGait::LongPeriod.section_guess(params[0]).to_vec();
    params
        .iter()
        .map(|&g| {
            let sys = family(g).expect("valid parameters");
            let map = StrideMap::new(&*sys, Options::dop853(1e-13)).expect("valid options");
            if let Ok(fp) = find_fixed_point(&map, &guess, &NewtonOptions::default()) {
                guess = fp.section;
            }
            vec![guess[0] + 1e-6, guess[1] - 1e-6]
        })
        .collect()
}

fn orbit(c: &mut Criterion) {
    let opts = OrbitOptions {
        transient: 400,
        record: 100,
        ..OrbitOptions::default()
    };
    let per_column = opts.transient + opts.record;
    let p2 = pool(2);
    let mut group = c.benchmark_group("limit_orbit_2threads");
    group.sample_size(10).warm_up_time(Duration::from_secs(1));
    for n in [100usize, 1000] {
        let params: Vec<f64> = (0..n)
            .map(|i| 0.0100 + 0.0090 * i as f64 / (n - 1) as f64)
            .collect();
        let start = OrbitStart::PerParam(period_one_starts(&params));
        let cols = orbit_diagram(&family, &params, &start, &opts, &p2).expect("orbit diagram");
        let falls = cols.iter().filter(|c| c.fall.is_some()).count();
        let done = strides_done(&cols, per_column);
        eprintln!(
            "orbit {n} slopes × {per_column} strides: {done} strides integrated ({falls} columns fell)"
        );
        group
            .measurement_time(Duration::from_secs(if n > 100 { 40 } else { 8 }))
            .throughput(Throughput::Elements(done as u64));
        group.bench_function(BenchmarkId::new("slopes_x500", n), |b| {
            b.iter(|| {
                black_box(
                    orbit_diagram(&family, black_box(&params), &start, &opts, &p2).expect("orbit"),
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, fixed_point, continuation, orbit);
criterion_main!(benches);
