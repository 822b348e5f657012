//! The Monte Carlo MFPT of the compass gait (Goswami preset, 3°) on random slopes (σ = 0.1°,
//! seed 1), 200 walkers × at most 50 steps on a 2-thread pool, from its stable period-one gait
//! (DOP853 at 1e-9, the basin's integrator), against the basin of the same model:
//! - `mfpt/compass_lockstep`: the walkers as lanes of the batched engine
//!   (`pdw_limit::ensemble`, as `pdw-sweep mfpt` runs them);
//! - `mfpt/compass_scalar`: one walker at a time per thread, the model rebuilt at each line's
//!   slope (`terrain::monte_carlo_scalar`, the reference walk);
//! - `mfpt/compass_basin`: the compass basin on a 41 × 41 grid of (θ, θ̇) around the gait
//!   (engine defaults), for the strides-per-second ratio.
//!
//! - `mfpt/compass_chain_mid_stance`: the transitions of the Markov chain on the mid-stance
//!   section (`pdw_limit::mid_stance`), a 12³ mesh around the gait's mid-stance point × 11
//!   Gauss–Hermite nodes (σ = 0.1°): 19 009 strides;
//! - `mfpt/compass_chain_landing`: the chain just after heel strike (`pdw_limit::markov`), a 6³
//!   mesh around the gait's section point, one layer per node: 11 × 216 × 11 + 11 = 26 147
//!   strides;
//! - `mfpt/compass_chain_cloud`: the chain on a cloud of the mid-stance section
//!   (`pdw_limit::cloud`): the mid-stance states of 50 walkers × at most 50 transitions
//!   thinned to the spacing of a 12-node grid and closed under their landings (at most 8
//!   passes), 11 nodes, and the solve; the strides counted on a first run and printed.
//!
//! - `mfpt/rimless_chain`: the rimless wheel's Markov chain just after heel strike (0.08 rad,
//!   σ = 0.5°, 40 Gauss–Hermite nodes, strides in closed form): a mesh of 1 000 rates × 40
//!   layers — its transitions (the strides, the weights, the rows) and its solve (BiCGSTAB and
//!   the power iteration), as `pdw-sweep mfpt --model rimless --mean 0.08 --sd 0.5deg --chain
//!   --nodes 40` builds them; throughput in chain states.
//!
//! - `mfpt/rimless_closed_form` and `mfpt/rimless_lockstep`: Byl & Tedrake's rimless wheel (8
//!   spokes, 8°, σ = 2°, seed 1), 200 walkers × at most 500 steps from its rolling gait, in
//!   closed form (`terrain::monte_carlo_closed_form`, `pdw-sweep mfpt`'s default for the wheel)
//!   and integrated in lockstep (`--stride-map integrated`): the same fates, the ratio of the
//!   two stride maps.
//!
//! Each reports strides per second (`Throughput::Elements`, the strides counted at setup and
//! printed).
//!
//! Run: `cargo bench -p pdw-benches --bench mfpt`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use pdw_hybrid::Options;
use pdw_limit::ensemble::{monte_carlo_lockstep, Lockstep};
use pdw_limit::terrain::{self, Fate, SlopeTerrain, SlopeWalk, TerrainKind};
use pdw_limit::{
    classify_cells, find_fixed_point, grid_cells, linspace, BasinOptions, BasinProblem, LimitError,
    NewtonOptions, Outcome, StrideMap,
};
use pdw_limit::{markov, mid_stance};
use pdw_walkers::Walker;

const SLOPE: f64 = 0.05235987755982988;
const WALKERS: usize = 200;
const STEPS: usize = 50;

fn strides(f: &[Fate]) -> u64 {
    f.iter()
        .map(|f| f.steps as u64 + u64::from(f.end.is_some()))
        .sum()
}

/// The registry model `name` at any slope.
fn model_at(name: &'static str) -> impl Fn(f64) -> Result<Box<dyn Walker>, LimitError> + Sync {
    move |s| {
        pdw_walkers::build(name, &[("slope", s)]).map_err(|e| LimitError::Model {
            param: s,
            message: e.to_string(),
        })
    }
}

/// The model's stable period-one gait from its own guesses.
fn stable_gait(walker: &dyn Walker) -> pdw_limit::FixedPoint {
    let map = StrideMap::new(walker, Options::dop853(1e-14)).expect("valid options");
    walker
        .gait_guesses()
        .iter()
        .filter_map(|g| find_fixed_point(&map, &g.section, &NewtonOptions::default()).ok())
        .find(|fp| fp.stable)
        .expect("the stable gait")
}

fn mfpt(c: &mut Criterion) {
    let at = model_at("compass");
    let walker = at(SLOPE).expect("registry model");
    let fp = stable_gait(walker.as_ref());
    let walk =
        SlopeWalk::new(&at, SLOPE, BasinOptions::default_integrator()).expect("terrain walk");
    let t = SlopeTerrain {
        mean: SLOPE,
        sd: 0.1f64.to_radians(),
        seed: 1,
        kind: TerrainKind::Slope,
        dist: Default::default(),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("thread pool");
    let x0 = fp.state.clone();
    let lockstep = || {
        let batch = Lockstep::for_pool(WALKERS, 2);
        monte_carlo_lockstep(&walk, &t, &x0, WALKERS, STEPS, &pool, batch, &|_| {})
            .expect("lockstep walk")
    };
    let scalar = || {
        terrain::monte_carlo_scalar(&walk, &t, &x0, WALKERS, STEPS, &pool, &|_| {})
            .expect("scalar walk")
    };
    let fall = Outcome::of_fall;
    let problem = BasinProblem::new(walker.as_ref(), fp.section.clone(), &fall);
    let (th, thd) = (fp.section[0], fp.section[1]);
    let cells = grid_cells(
        &fp.section,
        0,
        &linspace(th - 0.1, th + 0.1, 41),
        1,
        &linspace(thd - 0.3, thd + 0.3, 41),
    );
    let opts = BasinOptions::default();
    let basin = || classify_cells(&problem, &cells, &opts, &pool, &|_| {}).expect("basin");
    let n_lock = strides(&lockstep());
    let n_scalar = strides(&scalar());
    let n_basin: u64 = basin().iter().map(|c| u64::from(c.strides)).sum();
    eprintln!("strides: lockstep {n_lock}, scalar {n_scalar}, basin {n_basin}");
    let mut group = c.benchmark_group("mfpt");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(8));
    group.throughput(Throughput::Elements(n_lock));
    group.bench_function("compass_lockstep", |b| b.iter(|| black_box(lockstep())));
    group.throughput(Throughput::Elements(n_scalar));
    group.bench_function("compass_scalar", |b| b.iter(|| black_box(scalar())));
    group.throughput(Throughput::Elements(n_basin));
    group.bench_function("compass_basin", |b| b.iter(|| black_box(basin())));
    chains(
        &mut group,
        walker.as_ref(),
        &walk,
        &t,
        &x0,
        &fp.section,
        &pool,
    );
    rimless(&mut group, &pool);
    rimless_chain(&mut group, &pool);
    group.finish();
}

/// The rimless wheel's walk in closed form and integrated in lockstep (module docs).
fn rimless(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    pool: &rayon::ThreadPool,
) {
    let slope = 8f64.to_radians();
    let (walkers, steps) = (200, 500);
    let at = model_at("rimless");
    let fp = stable_gait(at(slope).expect("registry model").as_ref());
    let walk =
        SlopeWalk::new(&at, slope, BasinOptions::default_integrator()).expect("terrain walk");
    let t = SlopeTerrain {
        mean: slope,
        sd: 2f64.to_radians(),
        seed: 1,
        kind: TerrainKind::Slope,
        dist: Default::default(),
    };
    let x0 = fp.state.clone();
    let closed = || {
        terrain::monte_carlo_closed_form(&walk, &t, &x0, walkers, steps, pool, &|_| {})
            .expect("closed-form walk")
    };
    let lockstep = || {
        let batch = Lockstep::for_pool(walkers, 2);
        monte_carlo_lockstep(&walk, &t, &x0, walkers, steps, pool, batch, &|_| {})
            .expect("lockstep walk")
    };
    let (a, b) = (closed(), lockstep());
    let same = a.iter().zip(&b).filter(|(x, y)| x == y).count();
    eprintln!(
        "rimless strides: closed form {}, lockstep {}; {same} of {walkers} fates the same",
        strides(&a),
        strides(&b)
    );
    group.throughput(Throughput::Elements(strides(&a)));
    group.bench_function("rimless_closed_form", |b| b.iter(|| black_box(closed())));
    group.throughput(Throughput::Elements(strides(&b)));
    group.bench_function("rimless_lockstep", |b| b.iter(|| black_box(lockstep())));
}

/// The rimless wheel's layered chain in closed form, transitions and solve (module docs).
fn rimless_chain(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    pool: &rayon::ThreadPool,
) {
    let slope = 0.08;
    let at = model_at("rimless");
    let fp = stable_gait(at(slope).expect("registry model").as_ref());
    let walk = SlopeWalk::new(&at, slope, BasinOptions::default_integrator())
        .expect("terrain walk")
        .with_closed_form(true);
    let sd = 0.5f64.to_radians();
    let (z, w) = markov::gauss_hermite(40);
    let nodes: Vec<(f64, f64)> = z
        .iter()
        .zip(&w)
        .map(|(z, w)| (slope + sd * z, *w))
        .collect();
    // the walkers' padded box of `pdw-sweep mfpt --model rimless --mean 0.08 --sd 0.5deg`
    let mesh = markov::Mesh {
        lo: vec![0.9709],
        hi: vec![1.2308],
        n: 1000,
        frame: markov::Frame::identity(1),
    };
    let x0 = fp.state.clone();
    let chain = || {
        let t = markov::transitions(&walk, &nodes, &mesh, &x0, pool).expect("rimless chain");
        pool.install(|| markov::solve_chain(&t))
    };
    let r = chain();
    eprintln!("rimless chain: {} states, MFPT {:.4}", r.states, r.mfpt);
    group.throughput(Throughput::Elements(r.states as u64));
    group.bench_function("rimless_chain", |b| b.iter(|| black_box(chain())));
}

/// A mesh of `n` nodes per axis over `centre ± half`.
fn mesh_around(centre: &[f64], half: &[f64], n: usize) -> markov::Mesh {
    markov::Mesh {
        lo: centre.iter().zip(half).map(|(c, h)| c - h).collect(),
        hi: centre.iter().zip(half).map(|(c, h)| c + h).collect(),
        n,
        frame: markov::Frame::identity(centre.len()),
    }
}

/// The two chains' transitions (module docs).
fn chains(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    walker: &dyn Walker,
    walk: &SlopeWalk,
    t: &SlopeTerrain,
    x0: &[f64],
    section: &[f64],
    pool: &rayon::ThreadPool,
) {
    let (z, w) = markov::gauss_hermite(11);
    let nodes: Vec<(f64, f64)> = z
        .iter()
        .zip(&w)
        .map(|(z, w)| (t.mean + t.sd * z, *w))
        .collect();
    let sense = mid_stance::sweep_sense(walker, walk.kind(), x0).expect("the gait leans back");
    let first = mid_stance::first_mid_stance(walk, sense, x0)
        .expect("first mid-stance")
        .point
        .expect("the gait reaches mid-stance");
    let mid_mesh = mesh_around(&first, &[0.05, 0.05, 0.05], 12);
    let mid = || {
        mid_stance::transitions(walk, &nodes, &mid_mesh, x0, sense, pool).expect("mid-stance chain")
    };
    let land_mesh = mesh_around(section, &[0.01, 0.05, 0.05], 6);
    let land = || markov::transitions(walk, &nodes, &land_mesh, x0, pool).expect("layered chain");
    let n_mid = (mid_mesh.len() * nodes.len() + 1) as u64;
    let n_land = (nodes.len() * land_mesh.len() * nodes.len() + nodes.len()) as u64;
    eprintln!("chain strides: mid-stance {n_mid}, landing {n_land}");
    group.throughput(Throughput::Elements(n_mid));
    group.bench_function("compass_chain_mid_stance", |b| b.iter(|| black_box(mid())));
    group.throughput(Throughput::Elements(n_land));
    group.bench_function("compass_chain_landing", |b| b.iter(|| black_box(land())));
    let visited = mid_stance::visited(walk, t, x0, sense, 50, 50, pool).expect("visited states");
    let seeds = pdw_limit::cloud::Cloud::thinned(&visited, 12).expect("a cloud");
    let cloud = || {
        let mut c = seeds.clone();
        let cc = mid_stance::cloud_transitions(walk, &nodes, &mut c, x0, sense, 8, pool)
            .expect("cloud chain");
        (
            pool.install(|| markov::solve_chain(&cc.transitions)),
            cc.nodes,
        )
    };
    let n_cloud = (cloud().1 * nodes.len() + 1) as u64;
    eprintln!(
        "cloud chain strides: {n_cloud} ({} seeds of {} visited states)",
        seeds.len(),
        visited.len()
    );
    group.throughput(Throughput::Elements(n_cloud));
    group.bench_function("compass_chain_cloud", |b| b.iter(|| black_box(cloud())));
}

criterion_group!(benches, mfpt);
criterion_main!(benches);
