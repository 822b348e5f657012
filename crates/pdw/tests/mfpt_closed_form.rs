//! The Monte Carlo walk in closed form (`--stride-map closed-form`, the rimless wheel's
//! default) against a wheel this file walks by itself, and against the integrated walk.
//!
//! The reference wheel (Coleman; Tedrake, *Underactuated Robotics* ch. 4; Byl & Tedrake, IJRR
//! 28(8), 2009, §3) lives in the stance spoke's angle from the vertical, `ψ` (downhill
//! positive), not in the model's angle from the slope normal: a wheel that landed on a line
//! inclined `s'` starts at `ψ₀ = s' − α` and lands on the next line, inclined `s`, at
//! `ψ₁ = s + α`. On steps of a slope `γ` with the foothold `h` below the stance foot the spoke
//! tip reaches it where `2 l sin α sin(ψ − γ − α) = h`, and the spokes stay `2α` apart.
//! Energy: `ω(ψ)² = ω₀² + 2 (g/l)(cos ψ₀ − cos ψ)`; the wheel rolls back when `ω²` reaches 0 on
//! `[ψ₀, ψ₁]`; the impact keeps `cos 2α` of the rate.

use pdw::mfpt::{self, MfptPlan, StrideMap};
use pdw_hybrid::FallKind;
use pdw_limit::ensemble::{monte_carlo_lockstep, Lockstep};
use pdw_limit::stride::StrideOutcome;
use pdw_limit::terrain::{self, Fate, SlopeTerrain, SlopeWalk, TerrainKind};

/// Byl & Tedrake's wheel: 8 spokes, l = 1 m, g = 9.81, mean slope 8°.
const MEAN_DEG: f64 = 8.0;

fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
}

fn wheel(param: &str, value: f64) -> pdw::BuiltModel {
    let mut p = vec![("slope".to_string(), MEAN_DEG.to_radians())];
    if param != "slope" {
        p.push((param.to_string(), value));
    } else {
        p[0].1 = value;
    }
    pdw::build("rimless", &p).unwrap()
}

fn terrain(kind: TerrainKind, mean: f64, sd: f64) -> SlopeTerrain {
    SlopeTerrain {
        mean,
        sd,
        seed: 5,
        kind,
        dist: Default::default(),
    }
}

/// The walkers' fates by the engine's closed form and by its integrated lockstep walk.
fn both(m: &pdw::BuiltModel, t: &SlopeTerrain, walkers: usize, steps: usize) -> [Vec<Fate>; 2] {
    let at = mfpt::model_at_param(m, t.kind.param());
    let walk = SlopeWalk::with_kind(&at, t.kind, t.mean, mfpt::default_integrator()).unwrap();
    let (x0, _) = mfpt::start(m).unwrap();
    let p = pool(2);
    let closed =
        terrain::monte_carlo_closed_form(&walk, t, &x0, walkers, steps, &p, &|_| {}).unwrap();
    let batch = Lockstep::for_pool(walkers, 2);
    let integrated =
        monte_carlo_lockstep(&walk, t, &x0, walkers, steps, &p, batch, &|_| {}).unwrap();
    [closed, integrated]
}

/// The reference wheel's steps before it rolls back, from `(ψ₀, ω₀)`, landing on the lines of
/// `slope(k)` (random slopes), or on the footholds `h(k)` below on slope `gamma` (steps).
fn reference_walk(
    (alpha, g_over_l): (f64, f64),
    (psi0, w0): (f64, f64),
    max_steps: usize,
    landing: impl Fn(usize) -> (f64, f64),
) -> Option<usize> {
    let (mut psi0, mut w0) = (psi0, w0);
    for k in 0..max_steps {
        // the spoke angle from the vertical at the strike, and just after it
        let (psi1, after) = landing(k + 1);
        let w2 = |psi: f64| w0 * w0 + 2.0 * g_over_l * (psi0.cos() - psi.cos());
        if w2(0.0f64.clamp(psi0, psi1)) <= 0.0 {
            return Some(k);
        }
        w0 = (2.0 * alpha).cos() * w2(psi1).sqrt();
        psi0 = after;
    }
    None
}

#[test]
fn on_random_slopes_the_closed_form_walk_is_the_reference_wheels() {
    let m = wheel("slope", MEAN_DEG.to_radians());
    let alpha = std::f64::consts::PI / 8.0;
    let t = terrain(TerrainKind::Slope, MEAN_DEG.to_radians(), 2f64.to_radians());
    let (walkers, steps) = (4000, 5000);
    let at = mfpt::model_at(&m);
    let walk = SlopeWalk::new(&at, t.mean, mfpt::default_integrator()).unwrap();
    let (x0, _) = mfpt::start(&m).unwrap();
    let fates = terrain::monte_carlo_closed_form(&walk, &t, &x0, walkers, steps, &pool(2), &|_| {})
        .unwrap();
    let (mut differ, mut falls) = (0, 0);
    for (i, f) in fates.iter().enumerate() {
        let slope = |k: usize| t.slope(i as u64, k as u64);
        let landing = |k: usize| (slope(k) + alpha, slope(k) - alpha);
        let r = reference_walk((alpha, 9.81), (x0[0] + t.mean, x0[1]), steps, landing);
        falls += r.is_some() as usize;
        match (r, &f.end) {
            (Some(k), Some(end)) if k == f.steps => assert_eq!(
                *end,
                StrideOutcome::Fall {
                    kind: FallKind::RollsBack,
                    guard: 1
                },
                "{i}"
            ),
            (None, None) => assert_eq!(f.steps, steps),
            _ => differ += 1,
        }
    }
    eprintln!("{falls} of {walkers} walkers fell; {differ} fates differ");
    // a fate can differ only by rounding at the roll-back threshold
    assert!(differ <= 1, "{differ} fates differ");
    assert!(falls > walkers / 2, "{falls} falls: the test needs falls");
}

#[test]
fn on_random_step_heights_the_closed_form_walk_is_the_reference_wheels() {
    let m = wheel("step_down", 0.0);
    let (alpha, gamma) = (std::f64::consts::PI / 8.0, MEAN_DEG.to_radians());
    let t = terrain(TerrainKind::StepDown, 0.0, 0.04);
    let (walkers, steps) = (3000, 3000);
    let at = mfpt::model_at_param(&m, "step_down");
    let walk =
        SlopeWalk::with_kind(&at, TerrainKind::StepDown, 0.0, mfpt::default_integrator()).unwrap();
    let (x0, _) = mfpt::start(&m).unwrap();
    let fates = terrain::monte_carlo_closed_form(&walk, &t, &x0, walkers, steps, &pool(2), &|_| {})
        .unwrap();
    let (mut differ, mut falls) = (0, 0);
    for (i, f) in fates.iter().enumerate() {
        let landing = |k: usize| {
            let h = t.slope(i as u64, k as u64);
            let psi1 = gamma + alpha + (h / (2.0 * alpha.sin())).asin();
            (psi1, psi1 - 2.0 * alpha)
        };
        let r = reference_walk((alpha, 9.81), (x0[0] + gamma, x0[1]), steps, landing);
        falls += r.is_some() as usize;
        match (r, &f.end) {
            (Some(k), Some(_)) if k == f.steps => {}
            (None, None) => {}
            _ => differ += 1,
        }
    }
    eprintln!("{falls} of {walkers} walkers fell; {differ} fates differ");
    assert!(differ <= 1, "{differ} fates differ");
    assert!(falls > walkers / 4, "{falls} falls: the test needs falls");
}

/// The closed form and the integrator (DOP853 at 1e-9) walk the same walkers: the same fate for
/// nearly every one (a fate can differ where a stride lands within the tolerance of the
/// roll-back threshold, and every later step of that walker with it), and the same MFPT within
/// the standard error.
#[test]
fn the_closed_form_and_the_integrated_walk_agree() {
    for (kind, mean, sd) in [
        (
            TerrainKind::Slope,
            MEAN_DEG.to_radians(),
            2.25f64.to_radians(),
        ),
        (TerrainKind::StepDown, 0.0, 0.05),
    ] {
        let m = wheel(kind.param(), mean);
        let t = terrain(kind, mean, sd);
        let steps = 1500;
        let [closed, integrated] = both(&m, &t, 1000, steps);
        let same = closed
            .iter()
            .zip(&integrated)
            .filter(|(a, b)| a == b)
            .count();
        let (a, b) = (
            terrain::estimate(&closed, steps),
            terrain::estimate(&integrated, steps),
        );
        eprintln!(
            "{}: {same} of {} fates the same; MFPT {} ± {} vs {} ± {}",
            kind.name(),
            closed.len(),
            a.mfpt,
            a.stderr,
            b.mfpt,
            b.stderr
        );
        assert!(a.falls > 500, "{}: {} falls", kind.name(), a.falls);
        assert!(same * 1000 >= 995 * closed.len(), "{same} the same");
        assert!(
            (a.mfpt - b.mfpt).abs() < 3.0 * a.stderr.max(b.stderr),
            "{} vs {}",
            a.mfpt,
            b.mfpt
        );
        let kinds = |e: &terrain::MfptEstimate| e.failures.iter().map(|f| f.0.clone()).collect();
        let k: Vec<String> = kinds(&a);
        assert_eq!(k, kinds(&b));
    }
}

/// What the closed form does not cover is integrated: a three-spoke wheel's impact reverses its
/// rate (`cos 2α < 0`), so every stride after the first starts rolling back — the integrated
/// stride decides it, and the walk is the integrated walk's.
#[test]
fn a_start_the_closed_form_does_not_cover_is_integrated() {
    let m = pdw::build(
        "rimless",
        &[("slope".to_string(), 0.3), ("n_spokes".to_string(), 3.0)],
    )
    .unwrap();
    let t = terrain(TerrainKind::Slope, 0.3, 0.01);
    let at = mfpt::model_at(&m);
    let walk = SlopeWalk::new(&at, t.mean, mfpt::default_integrator()).unwrap();
    let x0 = [-std::f64::consts::PI / 3.0, 3.0];
    let p = pool(2);
    let closed = terrain::monte_carlo_closed_form(&walk, &t, &x0, 40, 20, &p, &|_| {}).unwrap();
    let batch = Lockstep::for_pool(40, 2);
    let integrated = monte_carlo_lockstep(&walk, &t, &x0, 40, 20, &p, batch, &|_| {}).unwrap();
    assert_eq!(closed, integrated);
    assert!(closed.iter().all(|f| f.end.is_some()), "{closed:?}");
}

#[test]
fn the_closed_form_walk_is_the_same_on_any_thread_count() {
    let m = wheel("slope", MEAN_DEG.to_radians());
    let t = terrain(TerrainKind::Slope, MEAN_DEG.to_radians(), 2f64.to_radians());
    let at = mfpt::model_at(&m);
    let walk = SlopeWalk::new(&at, t.mean, mfpt::default_integrator()).unwrap();
    let (x0, _) = mfpt::start(&m).unwrap();
    let run =
        |n| terrain::monte_carlo_closed_form(&walk, &t, &x0, 300, 400, &pool(n), &|_| {}).unwrap();
    assert_eq!(run(1), run(2));
}

/// `stride_map` through [`mfpt::run`]: auto is the closed form for the wheel and the
/// integrated walk for the compass; closed-form is refused for a model without one.
#[test]
fn the_plans_stride_map_chooses_the_walk() {
    let plan = |stride_map, mean| MfptPlan {
        terrain: terrain(TerrainKind::Slope, mean, 1f64.to_radians()),
        walkers: 200,
        max_strides: 300,
        integrator: mfpt::default_integrator(),
        stride_map,
    };
    let m = wheel("slope", MEAN_DEG.to_radians());
    let (x0, _) = mfpt::start(&m).unwrap();
    let p = pool(2);
    let mean = MEAN_DEG.to_radians();
    let run = |s| mfpt::run(&m, &plan(s, mean), &x0, &p, &|_| {}).unwrap().0;
    let [closed, integrated] = both(&m, &plan(StrideMap::Auto, mean).terrain, 200, 300);
    assert_eq!(run(StrideMap::Auto), closed);
    assert_eq!(run(StrideMap::ClosedForm), closed);
    assert_eq!(run(StrideMap::Integrated), integrated);
    assert_eq!(StrideMap::Auto.describe(&m), "closed form");

    let c = pdw::build("compass", &[("slope".to_string(), 0.05)]).unwrap();
    assert_eq!(StrideMap::Auto.describe(&c), "integrated");
    let e = StrideMap::ClosedForm
        .closed_form(&c, "--stride-map")
        .unwrap_err();
    assert!(
        e.0.contains("--stride-map") && e.0.contains("closed form"),
        "{e}"
    );
    let e = StrideMap::parse("exact", "--stride-map").unwrap_err();
    assert!(e.0.contains("auto, closed-form, integrated"), "{e}");
}
