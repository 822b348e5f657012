//! Newton on the simplest walker: the level floor has no gait and says why; order-one gaits
//! keep the absolute tolerance.

use pdw_hybrid::Options;
use pdw_limit::newton::{find_fixed_point, residual_scale, FixedPoint, NewtonOptions};
use pdw_limit::{LimitError, StrideMap};
use pdw_walkers::simplest::{Simplest, SimplestParams};
use pdw_walkers::Walker;

fn solve(slope: f64, guess: &[f64]) -> Result<FixedPoint, LimitError> {
    let m = Simplest::new(SimplestParams {
        slope,
        ..Default::default()
    })
    .unwrap();
    let sl = |x: &[f64]| m.step_length(x);
    let map = StrideMap::new(&m, Options::dop853(1e-14))
        .unwrap()
        .with_step_length(&sl);
    find_fixed_point(&map, guess, &NewtonOptions::default())
}

/// On a level floor the simplest walker loses energy at every heel strike: there is no
/// gait. The absolute test accepted a residual of 1e-12 on states of 6e-5 as a "stable
/// gait"; the relative test and the step-length check reject it, and say why.
#[test]
fn level_floor_has_no_gait_and_the_failure_says_degenerate() {
    for slope in [0.0, -0.0, 1e-320] {
        for guess in [[0.2, -0.2], [9.7e-5, -1.01e-4]] {
            let e = solve(slope, &guess).unwrap_err();
            let LimitError::NoConvergence { reason, last, .. } = &e else {
                panic!("slope {slope}, guess {guess:?}: {e}");
            };
            assert!(
                reason.contains("degenerate") || reason.contains("standing still"),
                "slope {slope}, guess {guess:?}: {reason} (last {last:?})"
            );
        }
    }
}

/// The relative test does not loosen order-one gaits: Garcia's stable gait at 0.009 is
/// found to the same 1e-12 absolute residual.
#[test]
fn order_one_gait_keeps_the_absolute_tolerance() {
    let fp = solve(0.009, &[0.2, -0.2]).unwrap();
    assert!(fp.residual <= 1e-12 * residual_scale(&fp.section));
    assert!((fp.section[0] - 0.200_310_900_494_83).abs() < 1e-9);
    assert!(fp.metrics.step_length.unwrap() > 0.3);
}
