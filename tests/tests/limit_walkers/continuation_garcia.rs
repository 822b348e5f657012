//! Continuation of the simplest walker's gait in the slope (Garcia et al., J. Biomech. Eng. 1998).

use pdw_hybrid::Options;
use pdw_limit::{
    continue_branch, find_fixed_point, period_doubling_cascade, BifurcationKind,
    ContinuationOptions, DpMethod, FdScheme, NewtonOptions, StrideMap,
};
use pdw_walkers::simplest::{Simplest, SimplestParams};

fn family(g: f64) -> Result<Box<Simplest>, pdw_walkers::WalkerError> {
    Simplest::new(SimplestParams {
        slope: g,
        ..Default::default()
    })
    .map(Box::new)
}

/// Most negative real multiplier + 1 of the directly computed fixed point at γ, with the
/// multipliers from a finite-difference DP (Richardson) — a route independent of the
/// continuation's corrector, tangent, test functions and location.
fn pd_test_direct(gamma: f64, guess: &[f64]) -> (f64, Vec<f64>) {
    let m = family(gamma).unwrap();
    let map = StrideMap::new(&*m, Options::dop853(1e-13)).unwrap();
    let opts = NewtonOptions {
        dp_report: DpMethod::FiniteDifference {
            scheme: FdScheme::default(),
            lanes: 8,
        },
        ..Default::default()
    };
    let fp = find_fixed_point(&map, guess, &opts).unwrap();
    let most_negative = fp
        .multipliers
        .iter()
        .filter(|l| l.im == 0.0)
        .map(|l| l.re)
        .fold(f64::INFINITY, f64::min);
    (most_negative + 1.0, fp.section)
}

#[test]
fn first_period_doubling_located_by_continuation_agrees_with_direct_bisection_to_1e7() {
    let mut opts = ContinuationOptions::new(0.005, 0.017);
    opts.stop_at = Some(BifurcationKind::PeriodDoubling);
    let branch = continue_branch(&family, &[0.2003, -0.1998], 0.009, 1, &opts).unwrap();
    // The start point is Garcia's stable gait (his own code's values, J. Biomech. Eng. 1998).
    let p0 = &branch.points[0];
    assert!((p0.section[0] - 0.20031090049483).abs() < 1e-9);
    assert!((p0.section[1] + 0.19983247291764).abs() < 1e-9);
    assert!(p0.stable);
    let pd = &branch.bifurcations[0];
    assert_eq!(pd.kind, BifurcationKind::PeriodDoubling);
    assert!(pd
        .multipliers
        .iter()
        .any(|l| l.im == 0.0 && (l.re + 1.0).abs() < 1e-8));
    // Second route: bisection on the multiplier of fixed points computed directly.
    let (mut lo, mut hi) = (0.0150, 0.0152);
    let (flo, mut guess) = pd_test_direct(lo, &pd.section);
    let (fhi, _) = pd_test_direct(hi, &pd.section);
    assert!(flo > 0.0 && fhi < 0.0, "{flo} {fhi}");
    while hi - lo > 1e-11 {
        let mid = 0.5 * (lo + hi);
        let (f, s) = pd_test_direct(mid, &guess);
        guess = s;
        if f > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let direct = 0.5 * (lo + hi);
    println!(
        "PD: continuation {:.12}, direct bisection {direct:.12}",
        pd.param
    );
    assert!((pd.param - direct).abs() < 1e-7, "{} vs {direct}", pd.param);
    // Garcia 1998: the period-one gait loses stability at γ ≈ 0.0151.
    assert!((pd.param - 0.0151).abs() < 1e-3);
}

#[test]
fn cascade_ratio_lies_between_feigenbaum_and_garcia() {
    // Three period doublings (1→2, 2→4, 4→8). The first ratio δ₁ = (γ₂−γ₁)/(γ₃−γ₂) of a
    // period-doubling cascade of a smooth map approaches Feigenbaum's 4.669 from above; Garcia
    // 1998 quotes 5.9, 5.2, 4.6 for the walker's successive ratios.
    let mut opts = ContinuationOptions::new(0.009, 0.0195);
    opts.ds_max = 2e-3;
    let (pds, _) = period_doubling_cascade(&family, &[0.2003, -0.1998], 0.009, 3, &opts).unwrap();
    assert_eq!(pds.len(), 3);
    assert_eq!(
        pds.iter().map(|b| b.period_strides).collect::<Vec<_>>(),
        vec![1, 2, 4]
    );
    let d1 = (pds[1].param - pds[0].param) / (pds[2].param - pds[1].param);
    println!(
        "γ = {:.12} {:.12} {:.12}; δ₁ = {d1:.4}",
        pds[0].param, pds[1].param, pds[2].param
    );
    assert!(d1 > 4.669 && d1 < 6.0, "δ₁ = {d1}");
    // Chaos near γ ≈ 0.0189 (Garcia): the cascade accumulates below it.
    assert!(pds[2].param < 0.0189);
}
