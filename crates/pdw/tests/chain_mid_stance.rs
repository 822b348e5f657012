//! The Markov chain on the mid-stance section ([`pdw_limit::mid_stance`]): its map against the
//! stride map's fixed point, its heel-strike count against a first-step analysis done by
//! hand, its MFPT against the Monte Carlo walkers (which count heel strikes one stride at a
//! time, without a section), and its refusals.

use pdw::mfpt::{self, ChainFlags, ChainPlan, ChainSection, MfptPlan};
use pdw_limit::markov::{solve_chain, Transitions};
use pdw_limit::mid_stance;
use pdw_limit::terrain::{SlopeTerrain, SlopeWalk, TerrainKind};

fn pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
}

fn plan(kind: TerrainKind, mean: f64, sd: f64, walkers: usize) -> MfptPlan {
    MfptPlan {
        terrain: SlopeTerrain {
            mean,
            sd,
            seed: 3,
            kind,
            dist: Default::default(),
        },
        walkers,
        max_strides: 20_000,
        integrator: mfpt::default_integrator(),
        stride_map: Default::default(),
    }
}

fn mid(mesh: usize, nodes: usize) -> ChainPlan {
    ChainPlan {
        nodes,
        mesh,
        bounds: None,
        section: ChainSection::MidStance,
        layout: Default::default(),
    }
}

/// On ground of one slope the walk from the gait's first mid-stance returns to it after one
/// heel strike: the mid-stance map's fixed point is the stride map's (found by Newton on the
/// section just after heel strike), to the integrator's accuracy.
#[test]
fn the_gaits_mid_stance_is_a_fixed_point_of_the_mid_stance_map() {
    for (name, slope) in [("compass", 0.05), ("rimless", 0.08), ("simplest", 0.009)] {
        let m = pdw::build(name, &[("slope".to_string(), slope)]).unwrap();
        let (x0, _) = mfpt::start(&m).unwrap();
        let p = plan(TerrainKind::Slope, slope, 0.0, 1);
        let at = mfpt::model_at_param(&m, "slope");
        let walk: SlopeWalk = mfpt::walk_of(&at, &p).unwrap();
        let sense = mid_stance::sweep_sense(m.walker.as_ref(), TerrainKind::Slope, &x0).unwrap();
        let first = mid_stance::first_mid_stance(&walk, sense, &x0).unwrap();
        assert_eq!(first.strikes, 0.0, "{name}");
        let point = first.point.unwrap();
        let next = mid_stance::map_onto(&walk, slope, sense, std::slice::from_ref(&point), &pool())
            .unwrap();
        assert_eq!(next[0].strikes, 1.0, "{name}");
        let back = next[0].point.as_ref().unwrap();
        let err = back
            .iter()
            .zip(&point)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-8, "{name}: {point:?} -> {back:?}");
        // the section drops the absolute angle: one coordinate fewer than the state
        assert_eq!(point.len(), m.walker.dim() - 1, "{name}");
    }
}

/// A two-state chain by hand: from state 0 the walker lands back in 0 with probability `a`
/// (one heel strike), lands and then falls with probability `b` (one heel strike) and falls
/// before landing with `1 − a − b` (none): the heel strikes `m₀` solve `m₀ = a (1 + m₀) + b`,
/// `m₀ = (a + b)/(1 − a)`; from the start (no heel strike, lands in 0) the MFPT is `m₀`.
#[test]
fn the_heel_strikes_of_a_chain_are_its_first_step_analysis() {
    let (a, b) = (0.9, 0.04);
    let t = Transitions {
        rows: vec![vec![(0, a)], vec![(0, 1.0)]],
        fall: vec![1.0 - a, 0.0],
        out: vec![0.0, 0.0],
        strikes: Some(vec![a + b, 0.0]),
    };
    let r = solve_chain(&t);
    let m0 = (a + b) / (1.0 - a);
    assert!((r.mfpt - m0).abs() < 1e-10 * m0, "{r:?} vs {m0}");
    assert!((r.mfpt_quasi_stationary - m0).abs() < 1e-10 * m0, "{r:?}");
    assert!((r.mfpt_lambda - m0).abs() < 1e-10 * m0, "{r:?}");
    assert!((r.lambda - a).abs() < 1e-12, "{r:?}");
}

/// The chain against `walkers` Monte Carlo walkers of `p`: within 3 standard errors plus the
/// chain's own change from its mesh to twice as fine; the solve and the eigenvalue agree.
fn agrees_with_the_walkers(m: &pdw::BuiltModel, p: &MfptPlan, mesh: usize, nodes: usize) {
    let pool = pool();
    let (x0, _) = mfpt::start(m).unwrap();
    let (_, mc) = mfpt::run(m, p, &x0, &pool, &|_| {}).unwrap();
    assert_eq!(mc.censored, 0, "{mc:?}");
    let pair = mfpt::chain_pair(m, p, &mid(mesh, nodes), &x0, &pool, &|_| {}).unwrap();
    let [coarse, fine] = &pair.results;
    eprintln!(
        "{}: Monte Carlo {} ± {}; mid-stance chain {} (mesh/2 {}), box {:?}",
        m.info.name,
        mc.restricted_mean,
        mc.restricted_stderr,
        fine.mfpt,
        coarse.mfpt,
        pair.chain_box
    );
    let tol = 3.0 * mc.restricted_stderr + (fine.mfpt - coarse.mfpt).abs();
    assert!(
        (fine.mfpt - mc.restricted_mean).abs() < tol,
        "chain {} vs Monte Carlo {} ± {} (tol {tol})",
        fine.mfpt,
        mc.restricted_mean,
        mc.restricted_stderr
    );
    for r in [coarse, fine] {
        assert!(r.residual < 1e-10, "{r:?}");
        let rel = (r.mfpt_lambda - r.mfpt_quasi_stationary).abs() / r.mfpt_lambda;
        assert!(rel < 1e-6, "{r:?}");
    }
}

/// The rimless wheel at σ = 2° on its 0.08 rad slope: a few steps, so counting the heel strike
/// of a wheel that lands and then rolls back (every rimless fall) matters at the walkers'
/// resolution; and at σ = 0.5°, ≈ 120 steps.
#[test]
fn the_rimless_mid_stance_chain_agrees_with_the_walkers_on_random_slopes() {
    let m = pdw::build("rimless", &[("slope".to_string(), 0.08)]).unwrap();
    for sd_deg in [2.0f64, 0.5] {
        let p = plan(TerrainKind::Slope, 0.08, sd_deg.to_radians(), 2000);
        agrees_with_the_walkers(&m, &p, 200, 11);
    }
}

/// The rimless wheel on random step heights (σ = 0.01 l): the mid-stance section is the same
/// for every foothold height.
#[test]
fn the_rimless_mid_stance_chain_agrees_with_the_walkers_on_step_heights() {
    let m = pdw::build(
        "rimless",
        &[("slope".to_string(), 0.08), ("step_down".to_string(), 0.0)],
    )
    .unwrap();
    let p = plan(TerrainKind::StepDown, 0.0, 0.01, 2000);
    agrees_with_the_walkers(&m, &p, 200, 11);
}

/// The mid-stance section is refused with the reason for a walker whose knee unlocks, and a
/// section name that is not one is refused by name.
#[test]
fn the_mid_stance_section_is_refused_where_it_is_not_one() {
    let flags = ChainFlags {
        chain: "--chain",
        mesh: "--mesh",
        nodes: "--nodes",
        section: "--chain-section",
    };
    let kneed = pdw::build("kneed", &[]).unwrap();
    let e = mfpt::check_chain(&kneed, None, None, ChainSection::MidStance, &flags).unwrap_err();
    assert!(
        e.0.starts_with("--chain-section: ") && e.0.contains("modes"),
        "{}",
        e.0
    );
    // the landing section of the same walker is accepted or refused for its own reasons only
    if let Err(e) = mfpt::check_chain(&kneed, None, None, ChainSection::Landing, &flags) {
        assert!(!e.0.contains("modes"), "{}", e.0);
    }
    let e = ChainSection::parse("midstance", "--chain-section").unwrap_err();
    assert!(
        e.0.contains("'midstance'") && e.0.contains("landing, mid-stance"),
        "{}",
        e.0
    );
    let compass = pdw::build("compass", &[]).unwrap();
    let c = mfpt::check_chain(&compass, None, None, ChainSection::MidStance, &flags).unwrap();
    assert_eq!((c.mesh, c.section), (24, ChainSection::MidStance));
}

/// The chain on a cloud of the mid-stance section at the spacing of a grid of `mesh` nodes per
/// axis, `nodes` terrain nodes, against the plan's walkers: within 3 standard errors — without
/// the mesh's change in the tolerance — with every landing on the cloud and the solve and the
/// eigenvalue in agreement.
fn cloud_agrees_with_the_walkers(m: &pdw::BuiltModel, p: &MfptPlan, mesh: usize, nodes: usize) {
    let pool = pool();
    let (x0, _) = mfpt::start(m).unwrap();
    let (_, mc) = mfpt::run(m, p, &x0, &pool, &|_| {}).unwrap();
    assert_eq!(mc.censored, 0, "{mc:?}");
    let at = mfpt::model_at_param(m, p.terrain.kind.param());
    let walk = mfpt::walk_of(&at, p).unwrap();
    let sense = mid_stance::sweep_sense(m.walker.as_ref(), p.terrain.kind, &x0).unwrap();
    let (visited, _, _) = mfpt::mid_stance_points(
        m,
        p,
        &x0,
        (mfpt::CLOUD_WALKERS, mfpt::CLOUD_STEPS),
        &pool,
        &|_| {},
    )
    .unwrap();
    let mut cloud = pdw_limit::cloud::Cloud::thinned(&visited, mesh).unwrap();
    let nodes = mfpt::terrain_nodes(p, nodes);
    let cc = mid_stance::cloud_transitions(
        &walk,
        &nodes,
        &mut cloud,
        &x0,
        sense,
        mfpt::CLOUD_PASSES,
        &pool,
    )
    .unwrap();
    let r = solve_chain(&cc.transitions);
    eprintln!(
        "{}: Monte Carlo {} ± {}; cloud chain {} ({} seeds, {} nodes, {} passes)",
        m.info.name,
        mc.restricted_mean,
        mc.restricted_stderr,
        r.mfpt,
        cc.seeds,
        cc.nodes,
        cc.passes
    );
    assert!(
        (r.mfpt - mc.restricted_mean).abs() < 3.0 * mc.restricted_stderr,
        "{}: cloud chain {} vs Monte Carlo {} ± {}",
        m.info.name,
        r.mfpt,
        mc.restricted_mean,
        mc.restricted_stderr
    );
    assert!(
        cc.passes < mfpt::CLOUD_PASSES && cc.nodes > cc.seeds,
        "{cc:?}"
    );
    assert_eq!(r.out_of_mesh, 0.0, "{r:?}");
    assert_eq!(r.states, cloud.len());
    assert!(r.residual < 1e-10, "{r:?}");
    let rel = (r.mfpt_lambda - r.mfpt_quasi_stationary).abs() / r.mfpt_lambda;
    assert!(rel < 1e-6, "{r:?}");
}

/// The compass at 3°, σ = 0.2°: its walkers visit a thin set of the 3-D mid-stance section, on
/// which a regular grid's multilinear weights leak into falls (the 60³ grid: 108 steps against
/// the walkers' 137 ± 3, experiments/results/metastable). On a cloud at the spacing of a
/// 60-node grid ([`pdw_limit::cloud`]) the chain agrees with 2000 walkers (132.5 against
/// 134.5 ± 2.9).
#[test]
fn on_a_cloud_the_compass_chain_agrees_with_the_walkers() {
    let m = pdw::build("compass", &[]).unwrap();
    let slope = m.params.iter().find(|p| p.0 == "slope").unwrap().1;
    let p = plan(TerrainKind::Slope, slope, 0.2f64.to_radians(), 2000);
    cloud_agrees_with_the_walkers(&m, &p, 60, 20);
}

/// The simplest walker at Garcia's slope, σ = 0.04°: the grid just after heel strike stays
/// 2.4 % (4 standard errors of 20 000 walkers) short at every mesh (experiments/cli-measurements.md); on a cloud of
/// its mid-stance section at the spacing of a 120-node grid the chain agrees with 20 000
/// walkers.
#[test]
fn on_a_cloud_the_simplest_walkers_chain_agrees_with_the_walkers() {
    let m = pdw::build("simplest", &[("slope".to_string(), 0.009)]).unwrap();
    let p = plan(TerrainKind::Slope, 0.009, 0.04f64.to_radians(), 20_000);
    cloud_agrees_with_the_walkers(&m, &p, 120, 20);
}

/// Where the swing foot passes the stance foot before the stance leg is vertical (the compass
/// gait: legs together about 0.04 s earlier), the next foothold's height decides from there on
/// whether the swing foot strikes: a section at the vertical walked that stretch on the last
/// height and missed the walkers (16.4 steps against 13.38 ± 0.22). On step heights the section
/// is the legs together ([`mid_stance::plane`]), and the chain on a cloud at the spacing of a
/// 120-node grid agrees with 2000 walkers (13.35; at the spacing of 60, 11.4: the legs-together
/// set needs the finer cloud).
#[test]
fn on_step_heights_the_legs_together_chain_agrees_with_the_walkers() {
    let m = pdw::build("compass", &[]).unwrap();
    let x0 = mfpt::start(&m).unwrap().0;
    assert_eq!(
        mid_stance::plane(m.walker.as_ref(), TerrainKind::StepDown).unwrap(),
        (1, 0.0),
        "the hip angle at 0"
    );
    assert_eq!(
        mid_stance::sweep_sense(m.walker.as_ref(), TerrainKind::StepDown, &x0).unwrap(),
        1.0,
        "the hip angle rises from the trailing leg's"
    );
    let p = plan(TerrainKind::StepDown, 0.0, 0.004, 2000);
    cloud_agrees_with_the_walkers(&m, &p, 120, 20);
}

/// Φ(z), the standard normal distribution function, by Marsaglia's series
/// `½ + φ(z) (z + z³/3 + z⁵/15 + …)` ("Evaluating the normal distribution", J. Stat. Softw.
/// 11(4), 2004) on `|z|` (no cancellation) and `Φ(−z) = 1 − Φ(z)`: an absolute error near
/// 1e-16, which is all a quantisation of draws needs.
fn phi(z: f64) -> f64 {
    let x = z.abs();
    let pdf = (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt();
    let (mut term, mut sum, mut k) = (x, x, 1.0);
    while term > 1e-17 * sum {
        k += 2.0;
        term *= x * x / k;
        sum += term;
    }
    let upper = 0.5 + pdf * sum;
    if z >= 0.0 {
        upper
    } else {
        1.0 - upper
    }
}

/// The simplest walker on random step heights: the chain's map walked with the walkers' own
/// draws (no mesh, no quadrature: [`mid_stance::walk_map`]) is the Monte Carlo walk — the
/// same heel strikes for all but a few walkers and the same MFPT within 3 standard errors — so
/// the chain's 4 % excess over the walkers (11.2 against 10.73 ± 0.11, docs) lies in its
/// discretisation. Each walker's own draws quantised (its standard normal `ξ` replaced by the
/// node whose cell of cumulative weight holds `Φ(ξ)`; the same walkers, so the difference to
/// the walkers is paired): onto the 20 Gauss–Hermite nodes the map walks longer than the
/// walkers by more than 3 standard errors of the paired difference — the quadrature; onto
/// 100 000 equal-probability nodes it walks as they do, within 3.
#[test]
fn the_simplest_walkers_legs_together_map_is_its_walk_and_the_quadrature_its_excess() {
    let m = pdw::build("simplest", &[("slope".to_string(), 0.009)]).unwrap();
    let x0 = mfpt::start(&m).unwrap().0;
    let p = plan(TerrainKind::StepDown, 0.0, 0.0005, 4000);
    let at = mfpt::model_at_param(&m, "step_down");
    let walk = mfpt::walk_of(&at, &p).unwrap();
    let kind = TerrainKind::StepDown;
    let sense = mid_stance::sweep_sense(walk.model(0.0).unwrap().as_ref(), kind, &x0).unwrap();
    let first = mid_stance::first_mid_stance(&walk, sense, &x0).unwrap();
    let start = first.point.clone().unwrap();
    let pool = pool();
    let n = p.walkers;
    let mean_se = |v: &[f64]| {
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (v.len() - 1) as f64;
        (mean, (var / v.len() as f64).sqrt())
    };
    let through = |draw: &(dyn Fn(u64, u64) -> f64 + Sync)| -> Vec<f64> {
        use rayon::prelude::*;
        pool.install(|| {
            (0..n)
                .into_par_iter()
                .map(|i| {
                    first.strikes
                        + mid_stance::walk_map(&walk, draw, &start, sense, i as u64, p.max_strides)
                            .unwrap()
                })
                .collect()
        })
    };
    let t = &p.terrain;
    let exact = through(&|i, k| t.slope(i, k));
    let fates =
        pdw_limit::terrain::monte_carlo(&walk, t, &x0, n, p.max_strides, &pool, &|_| {}).unwrap();
    let walkers: Vec<f64> = fates.iter().map(|f| f.steps as f64).collect();
    let differ = exact.iter().zip(&walkers).filter(|(a, b)| a != b).count();
    let ((me, se), (mw, sw)) = (mean_se(&exact), mean_se(&walkers));
    // each walker's draw quantised onto the nodes `z` of weights `w`, paired with the walkers
    let paired = |z: &[f64], w: &[f64]| -> (f64, f64) {
        let cum: Vec<f64> = w
            .iter()
            .scan(0.0, |a, v| {
                *a += v;
                Some(*a)
            })
            .collect();
        let on = through(&|i, k| {
            let u = phi(pdw_limit::terrain::standard_normal(t.seed, i, k)) * cum[cum.len() - 1];
            t.mean + t.sd * z[cum.iter().position(|c| *c >= u).unwrap_or(z.len() - 1)]
        });
        let d: Vec<f64> = on.iter().zip(&walkers).map(|(a, b)| a - b).collect();
        mean_se(&d)
    };
    let (z, w) = pdw_limit::markov::gauss_hermite(20);
    let (dq, sq) = paired(&z, &w);
    // 100 000 nodes of equal probability, each at its cell's middle quantile (by bisection on Φ)
    let q = 100_000;
    let fine: Vec<f64> = (0..q)
        .map(|b| {
            let u = (b as f64 + 0.5) / q as f64;
            let (mut lo, mut hi) = (-9.0, 9.0);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if phi(mid) < u {
                    lo = mid
                } else {
                    hi = mid
                }
            }
            0.5 * (lo + hi)
        })
        .collect();
    let (df, sf) = paired(&fine, &vec![1.0 / q as f64; q]);
    println!(
        "simplest on heights: walkers {mw:.4} ± {sw:.4}, the map with their draws {me:.4} ± \
         {se:.4} ({differ} of {n} differ); their draws on the 20 Gauss-Hermite nodes \
         {dq:+.4} ± {sq:.4} (paired), on {q} quantiles {df:+.4} ± {sf:.4}"
    );
    assert!(differ <= n / 100, "{differ} of {n} walkers differ");
    assert!((me - mw).abs() < 3.0 * sw, "{me} against {mw} ± {sw}");
    assert!(dq > 3.0 * sq, "Gauss-Hermite: {dq} ± {sq}");
    assert!(df.abs() < 3.0 * sf, "{q} quantiles: {df} ± {sf}");
}

/// The strides a chain reports as it runs ([`mfpt::Progress`], the CLI's counter) are the
/// strides it maps, counted once whichever thread ran them: on a mesh of `n^d` nodes with `N`
/// terrain nodes, `N n^d` at mid-stance and `N (N n^d + 1)` just after heel strike (every layer
/// and the start's row onto every node); the calls are increments, and the count is the same
/// with one thread and with two.
#[test]
fn a_chain_reports_every_stride_it_maps_once() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let slope = 3f64.to_radians();
    let m = pdw::build("compass", &[("slope".to_string(), slope)]).unwrap();
    let (x0, _) = mfpt::start(&m).unwrap();
    let p = plan(TerrainKind::Slope, slope, 0.2f64.to_radians(), 50);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        for (section, want) in [
            (ChainSection::MidStance, 5 * 6usize.pow(3)),
            (ChainSection::Landing, 5 * (5 * 6usize.pow(3) + 1)),
        ] {
            let c = ChainPlan {
                section,
                ..mid(6, 5)
            };
            let cb = mfpt::chain_box(&m, &p, &c, &x0, &pool, &|_| {}).unwrap();
            let (count, calls) = (AtomicUsize::new(0), AtomicUsize::new(0));
            let tell = |n: usize| {
                assert!(n > 0, "a report of no stride");
                count.fetch_add(n, Ordering::Relaxed);
                calls.fetch_add(1, Ordering::Relaxed);
            };
            mfpt::chain_in(&m, &p, &c, &cb.frame, &cb.bounds, &x0, &pool, &tell).unwrap();
            assert_eq!(count.into_inner(), want, "{section:?}, {threads} threads");
            assert!(
                calls.into_inner() >= 5,
                "{section:?}: one report per node at least"
            );
        }
    }
}

/// The warning of a terrain node at a step height of exactly 0 (level ground, the step model's
/// limit from below only): set on step heights of mean 0 with an odd symmetric rule (Gauss–
/// Hermite, Gauss–Legendre), not with an even one, a mean off 0, no spread, or on slopes.
#[test]
fn a_node_at_zero_step_height_is_warned_of() {
    let warn = |kind, mean, sd, dist: pdw_limit::terrain::TerrainDist, nodes| {
        let mut p = plan(kind, mean, sd, 1);
        p.terrain.dist = dist;
        mfpt::zero_height_node_warning(&p, nodes, "--nodes")
    };
    use pdw_limit::terrain::TerrainDist::{Normal, Uniform};
    let w = warn(TerrainKind::StepDown, 0.0, 0.0005, Normal, 11).unwrap();
    assert!(w.contains("--nodes 11") && w.contains("even"), "{w}");
    assert!(warn(TerrainKind::StepDown, 0.0, 0.0005, Uniform, 3).is_some());
    for (kind, mean, sd, nodes) in [
        (TerrainKind::StepDown, 0.0, 0.0005, 12),
        (TerrainKind::StepDown, 0.001, 0.0005, 11),
        (TerrainKind::StepDown, 0.0, 0.0, 11),
        (TerrainKind::Slope, 0.0, 0.0005, 11),
    ] {
        assert!(
            warn(kind, mean, sd, Normal, nodes).is_none(),
            "{kind:?} {mean} {sd} {nodes}"
        );
    }
}
