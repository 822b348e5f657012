//! Random terrain and the mean first-passage time: the counter-based normal numbers against the
//! normal distribution, the frame change between ground lines against the models' energy (which
//! only the correct sign conserves), the terrain stride against the ordinary stride map and
//! against each slope's own fixed point, the walk's independence of the thread count, and the
//! estimator against synthetic geometric data.

use pdw::mfpt::{self, MfptFlags, MfptPlan};
use pdw_limit::terrain::{self, Fate, SlopeTerrain, SlopeWalk};
use pdw_limit::{LimitError, StrideMap, StrideOutcome};

const FLAGS: MfptFlags = MfptFlags {
    terrain: "--terrain",
    sd: "--sd",
    mean: "--mean",
    walkers: "--walkers",
    max_steps: "--max-strides",
    dist: "--dist",
};

fn model(name: &str, slope: f64) -> pdw::BuiltModel {
    pdw::build(name, &[("slope".to_string(), slope)]).unwrap()
}

/// The stable gait of `m` (section coordinates, full state).
fn gait(m: &pdw::BuiltModel) -> (Vec<f64>, Vec<f64>) {
    let (x, s) = mfpt::start(m).unwrap();
    (s, x)
}

/// Φ(x), the standard normal CDF, integrated from −10 by Simpson's rule on 4000 panels (an
/// error far below the 1e-3 the KS bound resolves).
fn normal_cdf(x: f64) -> f64 {
    let f = |t: f64| (-0.5 * t * t).exp() / (2.0 * std::f64::consts::PI).sqrt();
    let (a, n) = (-10.0, 4000);
    if x <= a {
        return 0.0;
    }
    let h = (x - a) / n as f64;
    let mut s = f(a) + f(x);
    for i in 1..n {
        s += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

#[test]
fn the_counter_based_normals_have_the_normal_mean_variance_and_distribution() {
    let n = 100_000usize;
    let mut v: Vec<f64> = (0..n)
        .map(|i| terrain::standard_normal(7, (i / 100) as u64, (i % 100) as u64))
        .collect();
    let mean = v.iter().sum::<f64>() / n as f64;
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64;
    // standard errors: 1/√n = 0.0032 for the mean, √(2/n) = 0.0045 for the variance; 5 of them
    assert!(mean.abs() < 5.0 / (n as f64).sqrt(), "mean {mean}");
    assert!(
        (var - 1.0).abs() < 5.0 * (2.0 / n as f64).sqrt(),
        "variance {var}"
    );
    // Kolmogorov–Smirnov: P(√n D > 1.95) ≈ 0.001 under the null (Kolmogorov's distribution)
    v.sort_by(f64::total_cmp);
    let d = v
        .iter()
        .enumerate()
        .map(|(i, x)| {
            let c = normal_cdf(*x);
            (c - i as f64 / n as f64)
                .abs()
                .max(((i + 1) as f64 / n as f64 - c).abs())
        })
        .fold(0.0, f64::max);
    assert!(d * (n as f64).sqrt() < 1.95, "KS statistic D = {d}");
    // the uniforms stay inside (0, 1) and a pure function of the counter
    for i in 0..1000u64 {
        let u = terrain::uniform(3, i, i * 7, 0);
        assert!(u > 0.0 && u < 1.0);
        assert_eq!(u.to_bits(), terrain::uniform(3, i, i * 7, 0).to_bits());
    }
    // walker and step are not interchangeable, and the seed matters
    assert_ne!(
        terrain::counter_bits(1, 2, 3, 0),
        terrain::counter_bits(1, 3, 2, 0)
    );
    assert_ne!(
        terrain::counter_bits(1, 2, 3, 0),
        terrain::counter_bits(2, 2, 3, 0)
    );
}

#[test]
fn the_frame_change_conserves_each_models_energy_and_the_opposite_sign_would_not() {
    // the same configuration measured from two lines' normals: the energy (potential from the
    // gravity of each line's frame) must be equal; the model's own sign keeps it, the other not
    for (name, s0, s1) in [
        ("simplest", 0.009, 0.03),
        ("compass", 0.05, 0.08),
        ("rimless", 0.1, 0.15),
    ] {
        let m0 = model(name, s0);
        let m1 = model(name, s1);
        let (_, x) = gait(&m0);
        let (a, sign) = m0.walker.terrain_frame().unwrap();
        let e0 = m0.walker.energy(&x).unwrap();
        let mut right = x.clone();
        right[a] += sign * (s1 - s0);
        let mut wrong = x.clone();
        wrong[a] -= sign * (s1 - s0);
        let e_right = m1.walker.energy(&right).unwrap();
        let e_wrong = m1.walker.energy(&wrong).unwrap();
        assert!(
            (e_right - e0).abs() < 1e-12 * e0.abs().max(1.0),
            "{name}: {e0} {e_right}"
        );
        assert!(
            (e_wrong - e0).abs() > 1e-4 * e0.abs().max(1.0),
            "{name}: {e0} {e_wrong}"
        );
    }
}

#[test]
fn a_terrain_stride_on_the_mean_slope_is_the_ordinary_stride_bit_for_bit() {
    for (name, slope) in [("simplest", 0.009), ("compass", 0.05235987755982988)] {
        let m = model(name, slope);
        let (s, x) = gait(&m);
        // off the gait: a stride that changes the state
        let s: Vec<f64> = s
            .iter()
            .enumerate()
            .map(|(i, v)| v * if i == 0 { 0.98 } else { 1.01 })
            .collect();
        let s = s.as_slice();
        let opts = mfpt::default_integrator();
        let map = StrideMap::new(m.walker.as_ref(), opts).unwrap();
        let plain = map.stride(s).unwrap();
        let at = mfpt::model_at(&m);
        let walk = SlopeWalk::new(&at, slope, opts).unwrap();
        let mut integ = walk.integrator(x.len()).unwrap();
        let st = walk.stride(&mut integ, &map.lift(s), slope).unwrap();
        assert_eq!(st.outcome, StrideOutcome::Ok);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&st.post), bits(&plain.post_event), "{name}");
    }
}

#[test]
fn on_ground_of_one_constant_slope_the_walk_is_that_slopes_own_gait_in_the_mean_frame() {
    for (name, mean, s) in [("simplest", 0.009, 0.011), ("compass", 0.0524, 0.06)] {
        let m = model(name, mean);
        let (fs, x_s) = gait(&model(name, s));
        // the gait of slope s just after a heel strike, expressed in the mean slope's frame
        let at = mfpt::model_at(&m);
        let walk = SlopeWalk::new(&at, mean, mfpt::default_integrator()).unwrap();
        let mut x = x_s.clone();
        walk.shift(&mut x, s, mean);
        assert!((x[0] - x_s[0]).abs() > 1e-3, "{name}: the frames differ");
        let mut integ = walk.integrator(x.len()).unwrap();
        let mut y = x.clone();
        for _ in 0..3 {
            let st = walk.stride(&mut integ, &y, s).unwrap();
            assert_eq!(st.outcome, StrideOutcome::Ok);
            y = st.post;
        }
        let err = x
            .iter()
            .zip(&y)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            err < 1e-8,
            "{name}: gait {fs:?} at slope {s}: {x:?} → {y:?}"
        );
    }
}

#[test]
fn the_walk_is_the_same_on_one_and_on_two_threads() {
    let m = model("simplest", 0.009);
    let (x0, _) = mfpt::start(&m).unwrap();
    let plan = MfptPlan {
        terrain: SlopeTerrain {
            mean: 0.009,
            sd: 0.0005,
            seed: 5,
            kind: pdw_limit::terrain::TerrainKind::Slope,
            dist: Default::default(),
        },
        walkers: 24,
        max_strides: 40,
        integrator: mfpt::default_integrator(),
        stride_map: Default::default(),
    };
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    };
    let (f1, e1) = mfpt::run(&m, &plan, &x0, &pool(1), &|_| {}).unwrap();
    let (f2, e2) = mfpt::run(&m, &plan, &x0, &pool(2), &|_| {}).unwrap();
    assert_eq!(f1, f2);
    assert_eq!(e1, e2);
    // this terrain makes walkers fall and keeps some walking: both kinds of fate are compared
    assert!(e1.falls > 0 && e1.censored > 0, "{e1:?}");
    assert_eq!(e1.survival[0], 1.0);
}

#[test]
fn the_estimator_recovers_a_known_geometric_mfpt() {
    // fates drawn from a constant fall probability p per stride, censored at K: the MFPT is
    // (1 − p)/p = 49 steps; the estimate must lie within 3 of its standard errors
    let (p, k, n) = (0.02, 60usize, 20_000u64);
    let fates: Vec<Fate> = (0..n)
        .map(|i| {
            let fall = (0..=k).find(|j| terrain::uniform(11, i, *j as u64, 0) < p);
            match fall {
                Some(j) if j < k => Fate {
                    steps: j,
                    end: Some(StrideOutcome::NoHeelStrike),
                },
                _ => Fate {
                    steps: k,
                    end: None,
                },
            }
        })
        .collect();
    let e = terrain::estimate(&fates, k);
    let truth = (1.0 - p) / p;
    assert!(e.censored > 0 && e.falls > 0);
    assert!(
        (e.mfpt - truth).abs() < 3.0 * e.stderr,
        "{} ± {}",
        e.mfpt,
        e.stderr
    );
    // survival after k steps is (1 − p)^k, within 4 binomial standard errors
    for j in [1, 10, 30, 60] {
        let q = (1.0 - p).powi(j as i32);
        let se = (q * (1.0 - q) / n as f64).sqrt();
        assert!(
            (e.survival[j] - q).abs() < 4.0 * se,
            "S({j}) = {} vs {q}",
            e.survival[j]
        );
    }
    // the restricted mean is the mean of min(T, K): Σ_{j=1}^{K} S(j)
    let sum: f64 = e.survival[1..].iter().sum();
    assert!((sum - e.restricted_mean).abs() < 1e-9);
    assert_eq!(
        e.failures,
        vec![(StrideOutcome::NoHeelStrike.to_string(), e.falls)]
    );
}

/// The compass preset with round feet of radius 0.1 (a tenth of its leg), built from a spec
/// file written for it.
pub fn round_compass() -> pdw::BuiltModel {
    crate::mfpt_round_slopes::compass_with_radius(0.1)
}

#[test]
fn round_feet_and_bad_requests_are_refused_with_clear_messages() {
    let m = round_compass();
    let e = mfpt::check_model(&m).unwrap_err().to_string();
    assert!(e.contains("point feet") && e.contains("foot_radius"), "{e}");
    // round feet walk random slopes on tilted landing lines, with no stride of one slope
    let at = mfpt::model_at(&m);
    let walk = SlopeWalk::new(&at, 0.05, mfpt::default_integrator()).unwrap();
    assert!(walk.tilted());
    let (x0, _) = mfpt::start(&m).unwrap();
    let mut integ = walk.integrator(x0.len()).unwrap();
    let e = walk.stride(&mut integ, &x0, 0.05).unwrap_err();
    assert!(matches!(e, LimitError::Model { .. }), "{e}");
    assert!(mfpt::parse_sd("-1deg", &FLAGS)
        .unwrap_err()
        .0
        .contains("--sd"));
    assert!((mfpt::parse_sd("1deg", &FLAGS).unwrap() - 1f64.to_radians()).abs() < 1e-16);
    assert!(mfpt::check_terrain("height", &FLAGS)
        .unwrap_err()
        .0
        .contains("slope"));
    let plan = |sd: f64, walkers: usize| MfptPlan {
        terrain: SlopeTerrain {
            mean: 0.05,
            sd,
            seed: 0,
            kind: pdw_limit::terrain::TerrainKind::Slope,
            dist: Default::default(),
        },
        walkers,
        max_strides: 10,
        integrator: mfpt::default_integrator(),
        stride_map: Default::default(),
    };
    assert!(mfpt::check_plan(&plan(0.2, 10), &FLAGS)
        .unwrap_err()
        .0
        .contains("--sd"));
    assert!(mfpt::check_plan(&plan(0.01, 0), &FLAGS)
        .unwrap_err()
        .0
        .contains("--walkers"));
    assert!(mfpt::check_plan(&plan(0.01, 10), &FLAGS).is_ok());
}

#[test]
fn gauss_hermite_integrates_the_normal_moments_exactly() {
    for n in [1usize, 2, 5, 11, 20] {
        let (z, w) = pdw_limit::markov::gauss_hermite(n);
        // E Z^{2k} = (2k − 1)!!, E Z^{2k+1} = 0, exact for degree < 2n
        let mut dfact = 1.0;
        for k in 0..n {
            if k > 0 {
                dfact *= (2 * k - 1) as f64;
            }
            let even: f64 = z
                .iter()
                .zip(&w)
                .map(|(z, w)| w * z.powi(2 * k as i32))
                .sum();
            let odd: f64 = z
                .iter()
                .zip(&w)
                .map(|(z, w)| w * z.powi(2 * k as i32 + 1))
                .sum();
            // a node error of ε changes z^{2k} by about 2k ε relative: 1e-9 leaves room for
            // k ≤ 19 and the eigen-solver's ~1e-13
            assert!(
                (even - dfact).abs() < 1e-9 * dfact,
                "n {n} k {k}: {even} vs {dfact}"
            );
            assert!(odd.abs() < 1e-11 * dfact.max(1.0), "n {n} k {k}: {odd}");
        }
        assert!(w.iter().all(|w| *w > 0.0));
    }
}

/// The rimless wheel (Byl & Tedrake 2009's first example; one section coordinate, so a fine
/// mesh is cheap) at its preset 0.08 rad with σ = 0.5°: MFPT ≈ 120 steps, every walker falls
/// within the step limit, so the walkers' mean is the MFPT from the start without censoring.
#[test]
fn the_markov_chain_agrees_with_the_monte_carlo_walkers() {
    let m = model("rimless", 0.08);
    let (x0, _) = mfpt::start(&m).unwrap();
    let plan = MfptPlan {
        terrain: SlopeTerrain {
            mean: 0.08,
            sd: 0.5f64.to_radians(),
            seed: 1,
            kind: pdw_limit::terrain::TerrainKind::Slope,
            dist: Default::default(),
        },
        walkers: 2000,
        max_strides: 20_000,
        integrator: mfpt::default_integrator(),
        stride_map: Default::default(),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let (_, mc) = mfpt::run(&m, &plan, &x0, &pool, &|_| {}).unwrap();
    assert_eq!(mc.censored, 0, "{mc:?}");
    assert!(
        mc.restricted_mean > 20.0 && mc.restricted_mean < 500.0,
        "{mc:?}"
    );
    let bounds = mfpt::visited_box(&m, &plan, &x0, &pool).unwrap();
    let run = |mesh| {
        let c = mfpt::ChainPlan {
            nodes: 11,
            mesh,
            bounds: None,
            section: Default::default(),
            layout: Default::default(),
        };
        mfpt::chain(&m, &plan, &c, &bounds, &x0, &pool).unwrap()
    };
    let (coarse, fine) = (run(200), run(400));
    eprintln!(
        "MC {} ± {}; chain {coarse:?} {fine:?} box {bounds:?}",
        mc.restricted_mean, mc.restricted_stderr
    );
    let tol = 3.0 * mc.restricted_stderr + (fine.mfpt - coarse.mfpt).abs();
    assert!(
        (fine.mfpt - mc.restricted_mean).abs() < tol,
        "{} vs {}",
        fine.mfpt,
        mc.restricted_mean
    );
    for c in [&coarse, &fine] {
        assert!(c.residual < 1e-10, "{c:?}");
        let rel = (c.mfpt_lambda - c.mfpt_quasi_stationary).abs() / c.mfpt_lambda;
        assert!(rel < 1e-6, "{c:?}");
    }
}
