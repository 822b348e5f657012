//! Two-parameter continuation of period doublings and folds ([`pdw_limit::codim2`]) against
//! independent references:
//! - the compass gait's period doubling at Goswami et al. 1998's parameters (μ = m_H/m = 2,
//!   β = a/b = 1: γ ≈ 4.39°);
//! - the one-parameter route: at fixed values of the stepped parameter, the period doubling
//!   located by pseudo-arclength continuation in the slope (test function det(DP + I)) and
//!   refined by a secant iteration on "the multiplier nearest −1 equals −1" over fixed points
//!   found by plain Newton — no bordered system involved;
//! - the same for a fold of the kneed walker (located there by the turn of the branch);
//! - the accuracy of the finite-difference gradient of the test function (Richardson);
//! - a curve leaving the free parameter's domain ends with a typed reason.

use pdw_hybrid::Options;
use pdw_limit::codim2::Codim2System;
use pdw_limit::*;
use pdw_walkers::{Walker, WalkerError};
use std::cell::RefCell;

/// Goswami et al. 1998's compass (m = 5 kg, a = b = 0.5 m) with hip mass `h` (μ = h / 5) on
/// slope `s`.
fn compass(h: f64, s: f64) -> Result<Box<dyn Walker>, WalkerError> {
    pdw_walkers::build("compass", &[("hip_mass", h), ("slope", s)])
}

fn kneed(h: f64, s: f64) -> Result<Box<dyn Walker>, WalkerError> {
    pdw_walkers::build("kneed", &[("hip_mass", h), ("slope", s)])
}

/// The stable gait of `family(step, s0)` from the model's preset guesses.
fn gait<F>(family: &F, step: f64, s0: f64) -> Vec<f64>
where
    F: Fn(f64, f64) -> Result<Box<dyn Walker>, WalkerError>,
{
    let m = family(step, s0).unwrap();
    let map = StrideMap::new(&*m, Options::dop853(1e-13)).unwrap();
    for g in m.gait_guesses() {
        if let Ok(fp) = find_fixed_point(&map, &g.section, &NewtonOptions::default()) {
            if fp.stable {
                return fp.section;
            }
        }
    }
    panic!("no stable gait at step {step}, slope {s0}");
}

/// The first bifurcation of `kind` of the stable gait at `(step, s0)` by one-parameter
/// pseudo-arclength continuation in the slope (direction `dir`).
fn one_parameter<F>(
    family: &F,
    step: f64,
    s0: f64,
    dir: f64,
    kind: BifurcationKind,
    ds_max: f64,
) -> Bifurcation
where
    F: Fn(f64, f64) -> Result<Box<dyn Walker>, WalkerError>,
{
    let s = gait(family, step, s0);
    let mut o = ContinuationOptions::new(0.005, 0.2);
    o.stop_at = Some(kind);
    o.direction = dir;
    o.ds_max = ds_max;
    let fam1 = |sl: f64| family(step, sl);
    let br = continue_branch(&fam1, &s, s0, 1, &o).unwrap();
    br.bifurcations
        .iter()
        .find(|b| b.kind == kind)
        .cloned()
        .unwrap_or_else(|| panic!("no {kind:?} at step {step}: {:?}", br.end))
}

/// The real multiplier nearest −1 of the period-one gait at `(step, slope)` minus (−1), by plain
/// Newton from `guess` (returns the gait too).
fn pd_defect(step: f64, slope: f64, guess: &[f64]) -> (f64, Vec<f64>) {
    let m = compass(step, slope).unwrap();
    let map = StrideMap::new(&*m, Options::dop853(1e-13)).unwrap();
    let opts = NewtonOptions {
        tol: 1e-13,
        ..NewtonOptions::default()
    };
    let fp = find_fixed_point(&map, guess, &opts).unwrap();
    let l = fp
        .multipliers
        .iter()
        .filter(|l| l.im == 0.0)
        .map(|l| l.re)
        .min_by(|a, b| (a + 1.0).abs().total_cmp(&(b + 1.0).abs()))
        .unwrap();
    (l + 1.0, fp.section)
}

/// Secant iteration on `pd_defect(slope) = 0` from `γ0 ± 1e-6`.
fn refine_pd(step: f64, g0: f64, guess: &[f64]) -> f64 {
    let (mut a, mut b) = (g0 - 1e-6, g0 + 1e-6);
    let (mut fa, s) = pd_defect(step, a, guess);
    let (mut fb, mut s) = pd_defect(step, b, &s);
    for _ in 0..30 {
        if fb == fa {
            break;
        }
        let c = b - fb * (b - a) / (fb - fa);
        let (fc, sc) = pd_defect(step, c, &s);
        (a, fa, b, fb, s) = (b, fb, c, fc, sc);
        if (b - a).abs() < 1e-15 {
            break;
        }
    }
    b
}

fn curve_from<F>(
    family: &F,
    kind: Codim2Kind,
    bif: &Bifurcation,
    steps: &[f64],
    lo: f64,
    hi: f64,
) -> Curve
where
    F: Fn(f64, f64) -> Result<Box<dyn Walker>, WalkerError>,
{
    follow_curve(
        family,
        kind,
        &CurveStart::from_bifurcation(bif),
        steps,
        &Codim2Options::new(lo, hi),
    )
    .unwrap()
}

/// (a) + (b): the compass gait's period-doubling curve in (hip_mass, slope), started at
/// hip_mass = 6 kg (μ = 1.2), passes through Goswami et al. 1998's γ ≈ 4.39° at μ = 2, β = 1
/// (Goswami, Thuilot & Espiau, IJRR 17(12), 1998: "near 4.4°"; the paper's figure gives 4.39°,
/// two decimals), and at
/// hip_mass = 8, 10, 14 kg agrees with the one-parameter route to 1e-8 rad.
#[test]
fn compass_period_doubling_curve_meets_goswami_and_the_one_parameter_route() {
    let t = std::time::Instant::now();
    let pd6 = one_parameter(
        &compass,
        6.0,
        0.0523598776,
        1.0,
        BifurcationKind::PeriodDoubling,
        1e-2,
    );
    let steps = [6.0, 8.0, 10.0, 12.0, 14.0];
    let c = curve_from(
        &compass,
        Codim2Kind::PeriodDoubling,
        &pd6,
        &steps,
        0.01,
        0.3,
    );
    assert_eq!(c.end, CurveEnd::Complete, "{:?}", c.end);
    assert_eq!(c.points.len(), steps.len());
    for p in &c.points {
        assert!((p.critical + 1.0).abs() < 1e-9, "{p:?}");
        assert!(p.residual < 1e-11, "{p:?}");
    }
    let at10 = c.points.iter().find(|p| p.p_step == 10.0).unwrap();
    let deg = at10.p_free.to_degrees();
    eprintln!(
        "PD slope at mu = 2, beta = 1: {} rad = {deg:.6} deg (Goswami 1998: 4.39 deg)",
        at10.p_free
    );
    assert!((deg - 4.39).abs() < 0.005, "{deg} deg");
    assert!((deg - 4.4).abs() < 0.05, "{deg} deg");

    for h in [8.0, 10.0, 14.0] {
        let on_curve = c.points.iter().find(|p| p.p_step == h).unwrap();
        let bif = one_parameter(
            &compass,
            h,
            0.0523598776,
            1.0,
            BifurcationKind::PeriodDoubling,
            1e-2,
        );
        let refined = refine_pd(h, bif.param, &bif.section);
        eprintln!(
            "hip_mass {h}: curve {:.15}, one-parameter located {:.15} (curve - located {:.2e}), \
             refined by secant {:.15} (curve - refined {:.2e})",
            on_curve.p_free,
            bif.param,
            on_curve.p_free - bif.param,
            refined,
            on_curve.p_free - refined
        );
        assert!((on_curve.p_free - refined).abs() < 1e-8);
        assert!((on_curve.p_free - bif.param).abs() < 1e-8);
    }
    eprintln!("{:.2} s", t.elapsed().as_secs_f64());
}

/// The finite-difference gradient of the test function g (default relative step 1e-5) against
/// the Richardson extrapolation of steps 1e-4 and 5e-5, at the compass period doubling.
#[test]
fn gradient_of_the_test_function_is_accurate() {
    let bif = one_parameter(
        &compass,
        10.0,
        0.0523598776,
        1.0,
        BifurcationKind::PeriodDoubling,
        1e-2,
    );
    let n = bif.section.len();
    let b = real_eigenvector(
        &(0..n * n)
            .map(|k| bif.dp[(k % n) * n + k / n])
            .collect::<Vec<_>>(),
        n,
        -1.0,
    )
    .unwrap();
    let c = real_eigenvector(&bif.dp, n, -1.0).unwrap();
    let failure = RefCell::new(None);
    let sys = Codim2System::new(
        &compass,
        Codim2Kind::PeriodDoubling,
        10.0,
        b,
        c,
        Codim2Options::new(0.01, 0.3),
        &failure,
    );
    let mut y = bif.section.clone();
    y.push(bif.param);
    let m = n + 1;
    let j = |rel: f64| sys.jacobian_with_step(&y, rel).unwrap();
    let (j1, j2, j0) = (j(1e-4), j(5e-5), j(1e-5));
    let mut worst = 0.0f64;
    // The last row (∇g) and the last column (∂P/∂p) are the differenced entries.
    for k in (0..m).map(|i| n * m + i).chain((0..n).map(|i| i * m + n)) {
        let rich = (4.0 * j2[k] - j1[k]) / 3.0;
        let rel = (j0[k] - rich).abs() / rich.abs().max(1e-3);
        worst = worst.max(rel);
    }
    eprintln!("max relative error of the differenced Jacobian entries: {worst:.2e}");
    assert!(worst < 1e-5, "{worst}");
    // The bordered test function vanishes at the located period doubling (to the location
    // accuracy of the one-parameter continuation).
    let ev = sys.evaluate(&y).unwrap();
    assert!(ev.f[n].abs() < 1e-8, "g = {}", ev.f[n]);
}

/// (c) A fold: the kneed walker's stable gait turns back at slope ≈ 0.0318 (hip mass 0.5).
/// The fold curve in (hip_mass, slope) agrees with the one-parameter continuation's fold
/// (located by the turn of the branch, a different test function) at two other hip masses.
#[test]
fn kneed_fold_curve_agrees_with_the_one_parameter_turning_point() {
    let t = std::time::Instant::now();
    let f0 = one_parameter(&kneed, 0.5, 0.0504, -1.0, BifurcationKind::Fold, 2e-3);
    let steps = [0.5, 0.55, 0.6];
    let c = curve_from(&kneed, Codim2Kind::Fold, &f0, &steps, 0.005, 0.2);
    assert_eq!(c.end, CurveEnd::Complete, "{:?}", c.end);
    for p in &c.points {
        assert!((p.critical - 1.0).abs() < 1e-9, "{p:?}");
    }
    for h in [0.55, 0.6] {
        let on_curve = c.points.iter().find(|p| p.p_step == h).unwrap();
        let f = one_parameter(&kneed, h, 0.0504, -1.0, BifurcationKind::Fold, 2e-3);
        eprintln!(
            "kneed hip_mass {h}: fold curve {:.15}, one-parameter turning point {:.15} \
             (difference {:.2e})",
            on_curve.p_free,
            f.param,
            on_curve.p_free - f.param
        );
        assert!((on_curve.p_free - f.param).abs() < 1e-8);
    }
    eprintln!("{:.2} s", t.elapsed().as_secs_f64());
}

/// A curve whose free parameter would leave its domain ends with that reason, keeping the points
/// reached (the compass period-doubling slope rises as the hip gets lighter: 0.0832 rad at
/// 6 kg, 0.0856 at 5 kg; the domain ends at 0.085).
#[test]
fn a_curve_leaving_the_domain_ends_with_a_typed_reason() {
    let pd = one_parameter(
        &compass,
        10.0,
        0.0523598776,
        1.0,
        BifurcationKind::PeriodDoubling,
        1e-2,
    );
    let steps = [10.0, 8.0, 6.0, 5.0, 4.0];
    let c = curve_from(
        &compass,
        Codim2Kind::PeriodDoubling,
        &pd,
        &steps,
        0.01,
        0.085,
    );
    assert_eq!(c.points.len(), 3, "{:?}", c.end);
    let CurveEnd::Lost {
        last,
        tried,
        reason,
    } = &c.end
    else {
        panic!("{:?}", c.end)
    };
    assert!(last.unwrap() < 6.0 && last.unwrap() > 5.0, "{last:?}");
    assert!(*tried < last.unwrap() && *tried >= 5.0);
    assert!(
        matches!(reason, LostReason::FreeOutOfDomain { max, .. } if *max == 0.085),
        "{reason}"
    );
    assert!(c.points.iter().all(|p| p.p_free.is_finite()));
}
