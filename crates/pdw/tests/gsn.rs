//! The gait sensitivity norm (Hobbelen & Wisse 2007): the Gramian against the impulse
//! response summed term by term, the norm against the variance of the indicators of walkers on
//! slightly random slopes, the slope derivatives against the gaits of neighbouring slopes, the
//! differences against the exact variational Jacobian, and an unstable gait refused.

use pdw::gsn;
use pdw_limit::gsn::{impulse_sums, stride_outputs, GsnError, Indicator, Linearisation};
use pdw_limit::terrain::{SlopeTerrain, SlopeWalk};
use rayon::prelude::*;

fn model(name: &str, slope: f64) -> pdw::BuiltModel {
    pdw::build(name, &[("slope".to_string(), slope)]).unwrap()
}

/// The stable gait of `m`: full state, section coordinates.
fn stable_gait(m: &pdw::BuiltModel) -> (Vec<f64>, Vec<f64>) {
    pdw::mfpt::start(m).unwrap()
}

fn linearised(name: &str, slope: f64) -> (pdw::BuiltModel, Vec<f64>, Linearisation) {
    let m = model(name, slope);
    let s = stable_gait(&m).1;
    let lin = gsn::linearise(&m, &s, &Indicator::ALL, gsn::default_integrator()).unwrap();
    (m, s, lin)
}

/// (a) `c_i P c_iᵀ + d_i²` from the Lyapunov equation's direct solve equals the impulse
/// response `Σ_k ‖C A^{k−1} B‖² + ‖D‖²` summed until `A^k B` is 1e-16 of `B`.
#[test]
fn the_gramian_gives_the_impulse_response_sum() {
    for (name, slope) in [("simplest", 0.009), ("compass", 0.05)] {
        let (_, _, lin) = linearised(name, slope);
        let g = pdw_limit::gsn::gait_sensitivity(&lin).unwrap();
        let sums = impulse_sums(&lin, 1e-16, 100_000);
        for (h, s) in g.per_indicator.iter().zip(&sums) {
            assert!(
                (h * h - s).abs() <= 1e-10 * s,
                "{name}: Gramian {} vs impulse sum {s}",
                h * h
            );
        }
        let total: f64 = sums.iter().sum();
        assert!((g.norm - total.sqrt()).abs() <= 1e-10 * g.norm);
    }
}

/// The state columns of the differences equal the variational `DP` (to 1e-8), and the slope
/// column changes by less than 1e-7 (relative) when its step is doubled: the `O(h⁴)` accuracy
/// of the Richardson differences, measured.
#[test]
fn the_differences_agree_with_the_variational_jacobian_and_with_a_doubled_step() {
    for (name, slope) in [("simplest", 0.009), ("compass", 0.05)] {
        let (m, s, lin) = linearised(name, slope);
        assert!(lin.fd_error < 1e-8, "{name}: fd error {}", lin.fd_error);
        let at = pdw::mfpt::model_at(&m);
        let walk = SlopeWalk::new(&at, slope, gsn::default_integrator()).unwrap();
        let lin2 = pdw_limit::gsn::linearise(&walk, &s, &Indicator::ALL, 2e-5).unwrap();
        let scale = lin
            .b
            .iter()
            .chain(&lin.d)
            .fold(0.0f64, |a, v| a.max(v.abs()));
        for (x, y) in lin.b.iter().chain(&lin.d).zip(lin2.b.iter().chain(&lin2.d)) {
            assert!((x - y).abs() < 1e-7 * scale, "{name}: {x} vs {y}");
        }
    }
}

/// On a constant slope `s̄ + δ` every step the linear system's fixed point is
/// `σ = (I − F_σ)⁻¹ (F_e + F_e') δ` with indicators `g = (G_σ σ/δ + G_e + G_e') δ`; the same are
/// the derivatives in the slope of the gaits found by Newton at `s̄ ± δ` (each in its own
/// line's frame) and of their step time, length and speed: the slope columns against an
/// independent route.
#[test]
fn the_slope_columns_predict_the_gaits_of_neighbouring_slopes() {
    for (name, slope) in [("simplest", 0.009), ("compass", 0.05)] {
        let (_, _, lin) = linearised(name, slope);
        let (n, ds) = (lin.n, lin.n - 1);
        let delta = 1e-5;
        let gait_at = |sl: f64| {
            let mi = model(name, sl);
            let sec = stable_gait(&mi).1;
            let st = pdw_limit::StrideMap::new(mi.walker.as_ref(), gsn::default_integrator())
                .unwrap()
                .stride(&sec)
                .unwrap();
            let l = mi.walker.step_length(&st.pre_event);
            (sec, [st.period, l, l / st.period])
        };
        let (sp, gp) = gait_at(slope + delta);
        let (sm, gm) = gait_at(slope - delta);
        // (I − F_σ) y = F_e + F_e'
        let ia: Vec<f64> = (0..ds * ds)
            .map(|k| f64::from(u8::from(k / ds == k % ds)) - lin.a[(k / ds) * n + k % ds])
            .collect();
        let rhs: Vec<f64> = (0..ds).map(|i| lin.a[i * n + ds] + lin.b[i]).collect();
        let y = solve(&ia, &rhs, ds);
        for i in 0..ds {
            let fd = (sp[i] - sm[i]) / (2.0 * delta);
            assert!(
                (fd - y[i]).abs() < 1e-5 * y[i].abs().max(1.0),
                "{name} σ{i}: {fd} vs {}",
                y[i]
            );
        }
        for j in 0..3 {
            let c = &lin.c[j * n..(j + 1) * n];
            let lin_g: f64 = (0..ds).map(|k| c[k] * y[k]).sum::<f64>() + c[ds] + lin.d[j];
            let fd = (gp[j] - gm[j]) / (2.0 * delta);
            assert!(
                (fd - lin_g).abs() < 1e-5 * lin_g.abs().max(1.0),
                "{name} g{j}: {fd} vs {lin_g}"
            );
        }
    }
}

/// Gaussian elimination with partial pivoting of the row-major `n × n` system `a y = b`.
fn solve(a: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let mut m: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            a[i * n..(i + 1) * n]
                .iter()
                .copied()
                .chain([b[i]])
                .collect()
        })
        .collect();
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| m[i][c].abs().total_cmp(&m[j][c].abs()))
            .unwrap();
        m.swap(c, p);
        let pivot = m[c].clone();
        for row in m.iter_mut().skip(c + 1) {
            let f = row[c] / pivot[c];
            for (x, p) in row[c..].iter_mut().zip(&pivot[c..]) {
                *x -= f * p;
            }
        }
    }
    let mut y = vec![0.0; n];
    for r in (0..n).rev() {
        y[r] = (m[r][n] - (r + 1..n).map(|k| m[r][k] * y[k]).sum::<f64>()) / m[r][r];
    }
    y
}

/// The walk of the linearisation (section state in the frame of the line last landed on, and
/// that line's slope) is the terrain walk of [`SlopeWalk::stride`] (full state in the mean
/// slope's frame): 20 walkers, 30 strides each, on slopes with σ = 2°.
#[test]
fn the_section_walk_is_the_terrain_walk() {
    let slope = 0.05;
    let m = model("compass", slope);
    let (x0, s0) = stable_gait(&m);
    let at = pdw::mfpt::model_at(&m);
    let walk = SlopeWalk::new(&at, slope, gsn::default_integrator()).unwrap();
    let terrain = SlopeTerrain {
        mean: slope,
        sd: 2f64.to_radians() * 0.1,
        seed: 5,
        kind: pdw_limit::terrain::TerrainKind::Slope,
        dist: Default::default(),
    };
    let mut integ = walk.integrator(x0.len()).unwrap();
    for i in 0..20u64 {
        let (mut x, mut sigma, mut prev) = (x0.clone(), s0.clone(), slope);
        for k in 1..=30u64 {
            let e = terrain.slope(i, k);
            let st = walk.stride(&mut integ, &x, e).unwrap();
            if !st.outcome.is_ok() {
                break;
            }
            x = st.post;
            sigma = stride_outputs(&walk, &sigma, prev, e, &[]).unwrap().0;
            prev = e;
            let mut y = x.clone();
            walk.shift(&mut y, slope, e);
            let mut proj = vec![0.0; sigma.len()];
            m.walker.project(&y, &mut proj);
            for (p, q) in proj.iter().zip(&sigma) {
                assert!(
                    (p - q).abs() < 1e-9,
                    "walker {i} step {k}: {proj:?} vs {sigma:?}"
                );
            }
        }
    }
}

/// (b) Walkers on slopes `s̄ + σ ξ_k` with σ = 1e-4 rad (small: the walk stays linear to
/// O(σ)) from the gait: at stride K = 30 each indicator's variance is `σ² Σ_{k<K} ‖h_k‖²`, which
/// equals `σ² ‖H_i‖²` to 1e-12 (|λ|^K ≈ 1e-7, squared). The sample variance of N independent
/// walkers has the relative standard error `√(2/(N − 1))` (normal samples): 2.2 % for N = 4000;
/// the test allows 4 of them.
#[test]
fn the_norm_is_the_indicators_standard_deviation_per_unit_slope_noise() {
    let (n_walkers, k_strides, sd) = (4000usize, 30usize, 1e-4);
    let slope = 0.009;
    let (m, s, lin) = linearised("simplest", slope);
    let g = pdw_limit::gsn::gait_sensitivity(&lin).unwrap();
    let at = pdw::mfpt::model_at(&m);
    let walk = SlopeWalk::new(&at, slope, gsn::default_integrator()).unwrap();
    let terrain = SlopeTerrain {
        mean: slope,
        sd,
        seed: 11,
        kind: pdw_limit::terrain::TerrainKind::Slope,
        dist: Default::default(),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let last: Vec<Vec<f64>> = pool.install(|| {
        (0..n_walkers)
            .into_par_iter()
            .map(|i| {
                let (mut sigma, mut prev, mut g) = (s.clone(), slope, Vec::new());
                for k in 1..=k_strides {
                    let e = terrain.slope(i as u64, k as u64);
                    (sigma, g) = stride_outputs(&walk, &sigma, prev, e, &Indicator::ALL).unwrap();
                    prev = e;
                }
                g
            })
            .collect()
    });
    let tol = 4.0 * (2.0 / (n_walkers - 1) as f64).sqrt();
    for (j, h) in g.per_indicator.iter().enumerate() {
        let v: Vec<f64> = last.iter().map(|g| g[j]).collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() - 1) as f64;
        let expect = sd * sd * h * h;
        assert!(
            (var / expect - 1.0).abs() < tol,
            "indicator {j}: sample variance {var} vs σ²‖H‖² {expect}"
        );
    }
}

/// (c) The unstable period-one gait of the simplest walker (the short-period one) has no
/// finite norm: the error names its multiplier, never a number.
#[test]
fn an_unstable_gait_is_refused_with_its_multiplier() {
    let m = model("simplest", 0.009);
    let guesses = pdw::gaits::guesses(&m, None, "--guess").unwrap();
    let (found, _) = pdw::gaits::search(&m, &guesses, 1e-12).unwrap();
    let unstable = found
        .iter()
        .find(|f| !f.fp.stable)
        .expect("an unstable gait");
    let r = gsn::gait_sensitivity(
        &m,
        &unstable.fp.section,
        &Indicator::DEFAULT,
        gsn::default_integrator(),
    );
    match r {
        Err(GsnError::Unstable { radius }) => {
            assert!(radius > 1.0);
            let msg = GsnError::Unstable { radius }.to_string();
            assert!(
                msg.contains("unstable") && msg.contains("infinite"),
                "{msg}"
            );
        }
        other => panic!("expected the unstable-gait error, got {other:?}"),
    }
}

#[test]
fn indicator_names_parse_and_bad_ones_are_named() {
    let v = gsn::parse_indicators("step-time, step_length,speed", "--indicators").unwrap();
    assert_eq!(v, Indicator::ALL.to_vec());
    let e = gsn::parse_indicators("step-time,hop", "--indicators").unwrap_err();
    assert!(
        e.0.contains("'hop'") && e.0.contains("step-length"),
        "{}",
        e.0
    );
    let e = gsn::parse_indicators("speed,speed", "--indicators").unwrap_err();
    assert!(e.0.contains("twice"), "{}", e.0);
}

/// Spearman's ρ against its closed form `1 − 6 Σ d² / (n (n² − 1))` for distinct ranks, ±1 for
/// monotone pairs, ties by average ranks, non-finite pairs left out.
#[test]
fn spearman_matches_its_closed_form() {
    use pdw::mfpt_over::spearman;
    let x = [1.0, 2.0, 3.0, 4.0, 5.0];
    let y = [2.0, 1.0, 4.0, 3.0, 5.0];
    // d = (1, −1, 1, −1, 0): Σ d² = 4 → 1 − 24/120 = 0.8
    assert!((spearman(&x, &y) - 0.8).abs() < 1e-15);
    assert!((spearman(&x, &[10.0, 5.0, 1.0, 0.5, 0.1]) + 1.0).abs() < 1e-15);
    assert!((spearman(&x, &x.map(f64::exp)) - 1.0).abs() < 1e-15);
    let with_nan = [1.0, f64::NAN, 3.0, 4.0, 5.0];
    assert!(
        (spearman(&with_nan, &y) - spearman(&[1.0, 3.0, 4.0, 5.0], &[2.0, 4.0, 3.0, 5.0])).abs()
            < 1e-15
    );
    // ties: ranks (1.5, 1.5, 3) against (1, 2, 3): Pearson of the ranks = √3/2
    assert!((spearman(&[1.0, 1.0, 2.0], &[1.0, 2.0, 3.0]) - 0.75f64.sqrt()).abs() < 1e-15);
    assert!(spearman(&[1.0, 2.0], &[2.0, 1.0]).is_nan());
}
