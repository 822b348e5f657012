//! Random step heights: the rimless wheel's walk on them against the closed-form step map run
//! on the same counter-based numbers (walker by walker), the Markov chain against the Monte
//! Carlo, and the checks of a step-height request.

use pdw::mfpt::{self, MfptFlags, MfptPlan};
use pdw_limit::terrain::{standard_normal, SlopeTerrain, TerrainKind};

const FLAGS: MfptFlags = MfptFlags {
    terrain: "--terrain",
    sd: "--sd",
    mean: "--mean",
    walkers: "--walkers",
    max_steps: "--max-strides",
    dist: "--dist",
};

const GAMMA: f64 = 0.08;
const G: f64 = 9.81;

fn wheel(h: f64) -> pdw::BuiltModel {
    pdw::build(
        "rimless",
        &[("slope".to_string(), GAMMA), ("step_down".to_string(), h)],
    )
    .unwrap()
}

fn plan(mean: f64, sd: f64, walkers: usize, max_steps: usize) -> MfptPlan {
    MfptPlan {
        terrain: SlopeTerrain {
            mean,
            sd,
            seed: 7,
            kind: TerrainKind::StepDown,
            dist: Default::default(),
        },
        walkers,
        max_strides: max_steps,
        integrator: mfpt::default_integrator(),
        stride_map: Default::default(),
    }
}

fn pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
}

/// Steps walker `i` completes by the closed-form map of an 8-spoke wheel (l = 1): from
/// `θ⁺ = −α + asin(h_prev / 2 sin α)` at rate ω the hub passes its apex (`θ = −γ`, if the step
/// contains it) only with `ω² > 2 (g/l)(1 − cos(θ⁺ + γ))`, and lands at
/// `θ⁻ = α + asin(h / 2 sin α)` with `ω' = cos 2α √(ω² + 2 (g/l)(cos(θ⁺ + γ) − cos(θ⁻ + γ)))`.
fn closed_form_steps(t: &SlopeTerrain, i: u64, omega0: f64, max_steps: usize) -> usize {
    let a = std::f64::consts::PI / 8.0;
    let reach = 2.0 * a.sin();
    let (mut omega, mut th_plus) = (omega0, -a + (t.mean / reach).asin());
    for k in 0..max_steps {
        let h = t.slope(i, k as u64 + 1);
        let th_minus = a + (h / reach).asin();
        let lowest = if th_plus < -GAMMA && -GAMMA < th_minus {
            1.0
        } else {
            (th_minus + GAMMA).cos().max((th_plus + GAMMA).cos())
        };
        if omega * omega <= 2.0 * G * (lowest - (th_plus + GAMMA).cos()) {
            return k;
        }
        let w2 = omega * omega + 2.0 * G * ((th_plus + GAMMA).cos() - (th_minus + GAMMA).cos());
        omega = (2.0 * a).cos() * w2.sqrt();
        th_plus = th_minus - 2.0 * a;
    }
    max_steps
}

#[test]
fn the_rimless_walk_on_step_heights_is_the_closed_form_map_walker_by_walker() {
    let m = wheel(0.002);
    let p = plan(0.002, 0.01, 400, 3000);
    let (x0, s0) = mfpt::start(&m).unwrap();
    let (fates, est) = mfpt::run(&m, &p, &x0, &pool(), &|_| {}).unwrap();
    assert!(est.falls > 300, "{est:?}");
    let mut differ = 0;
    for (i, f) in fates.iter().enumerate() {
        let k = closed_form_steps(&p.terrain, i as u64, s0[0], p.max_strides);
        if k != f.steps {
            differ += 1;
        }
    }
    // a walker whose rate grazes the apex could differ by the integration's 1e-9
    assert!(differ <= 2, "{differ} of {} walkers differ", fates.len());
    // the draws are the documented counter-based normals
    assert_eq!(
        p.terrain.slope(3, 5),
        0.002 + 0.01 * standard_normal(7, 3, 5)
    );
}

#[test]
fn the_step_height_chain_agrees_with_the_monte_carlo() {
    let m = wheel(0.0);
    let p = plan(0.0, 0.01, 2000, 20_000);
    let pool = pool();
    let (x0, _) = mfpt::start(&m).unwrap();
    let (_, mc) = mfpt::run(&m, &p, &x0, &pool, &|_| {}).unwrap();
    assert_eq!(mc.censored, 0);
    let bounds = mfpt::visited_box(&m, &p, &x0, &pool).unwrap();
    let run = |mesh| {
        let c = mfpt::ChainPlan {
            nodes: 11,
            mesh,
            bounds: None,
            section: Default::default(),
            layout: Default::default(),
        };
        mfpt::chain(&m, &p, &c, &bounds, &x0, &pool).unwrap()
    };
    let (coarse, fine) = (run(200), run(400));
    let tol = 3.0 * mc.restricted_stderr + (fine.mfpt - coarse.mfpt).abs();
    assert!(
        (fine.mfpt - mc.restricted_mean).abs() < tol,
        "chain {} vs Monte Carlo {} ± {}",
        fine.mfpt,
        mc.restricted_mean,
        mc.restricted_stderr
    );
    assert!((fine.mfpt_lambda - fine.mfpt_quasi_stationary).abs() < 1e-6 * fine.mfpt_lambda);
}

#[test]
fn step_height_requests_are_checked() {
    assert_eq!(
        mfpt::check_terrain("step-down", &FLAGS).unwrap(),
        TerrainKind::StepDown
    );
    let e = mfpt::parse_sd_values_for("1deg", TerrainKind::StepDown, &FLAGS).unwrap_err();
    assert!(e.to_string().contains("not a height"), "{e}");
    let v = mfpt::parse_sd_values_for("0.01:0.03:3", TerrainKind::StepDown, &FLAGS).unwrap();
    assert_eq!(v.len(), 3);
    for (a, b) in v.iter().zip([0.01, 0.02, 0.03]) {
        assert!((a - b).abs() < 1e-15, "{v:?}");
    }
    // a spoke reaches 2 sin(π/8) ≈ 0.765 m: 0.1 m with 8.66 sd ≈ 0.87 m is beyond it
    let m = wheel(0.0);
    let e = mfpt::check_heights(&m, &plan(0.0, 0.1, 10, 10), &FLAGS).unwrap_err();
    assert!(e.to_string().contains("step_down"), "{e}");
    assert!(mfpt::check_heights(&m, &plan(0.0, 0.05, 10, 10), &FLAGS).is_ok());
    // the compass takes steps shorter than its 1 m leg: 0.5 m with 8.66 sd is beyond it
    let compass = pdw::build("compass", &[]).unwrap();
    assert!(mfpt::check_model_for(&compass, TerrainKind::StepDown).is_ok());
    let e = mfpt::check_heights(&compass, &plan(0.0, 0.5, 10, 10), &FLAGS).unwrap_err();
    assert!(e.to_string().contains("step_down"), "{e}");
}

/// The Gauss–Legendre rule of a unit-variance uniform (support ±√3) integrates its moments
/// `E U^{2j} = 3^j / (2j + 1)` (odd ones 0) exactly for `2j < 2n`, and its weights sum to 1.
#[test]
fn gauss_legendre_integrates_the_uniform_moments_exactly() {
    for n in [1usize, 2, 5, 11, 20] {
        let (z, w) = pdw_limit::markov::gauss_legendre(n);
        assert!(z.iter().all(|z| z.abs() < 3f64.sqrt()));
        assert!(w.iter().all(|w| *w > 0.0));
        for k in 0..2 * n {
            let q: f64 = z.iter().zip(&w).map(|(z, w)| w * z.powi(k as i32)).sum();
            let exact = if k % 2 == 1 {
                0.0
            } else {
                3f64.powi(k as i32 / 2) / (k as f64 + 1.0)
            };
            // the size of the terms summed, E|U|^k = 3^{k/2} / (k + 1), bounds the rounding
            let scale = 3f64.powf(k as f64 / 2.0) / (k as f64 + 1.0);
            assert!(
                (q - exact).abs() < 1e-11 * scale.max(1.0),
                "n {n} k {k}: {q} vs {exact}"
            );
        }
    }
}
