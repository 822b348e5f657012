//! The rimless wheel against its closed form (Coleman; Tedrake, Underactuated Robotics ch. 4).

use pdw_hybrid::{FallKind, Options};
use pdw_limit::*;
use pdw_walkers::rimless::{Rimless, RimlessParams};
use pdw_walkers::Walker;

fn wheel(slope: f64) -> Rimless {
    Rimless::new(RimlessParams {
        slope,
        ..Default::default()
    })
    .unwrap()
}

#[test]
fn rimless_fixed_point_and_multiplier_equal_the_closed_form() {
    for slope in [0.08, 0.15, 0.3] {
        let w = wheel(slope);
        let exact = w.rolling_fixed_point().unwrap();
        let sl = |x: &[f64]| w.step_length(x);
        let map = StrideMap::new(&w, Options::dop853(1e-14))
            .unwrap()
            .with_step_length(&sl);
        let fp = find_fixed_point(
            &map,
            &[1.5 * exact],
            &NewtonOptions {
                tol: 1e-13,
                ..Default::default()
            },
        )
        .unwrap();
        let c = (2.0 * w.alpha()).cos();
        assert!(
            (fp.section[0] - exact).abs() < 1e-12,
            "{slope}: {} vs {exact}",
            fp.section[0]
        );
        assert!(
            (fp.multipliers[0].re - c * c).abs() < 1e-12,
            "{:?}",
            fp.multipliers
        );
        assert!(fp.stable);
        // FD agrees with the variational DP to ≥ 7 digits
        let fd = dp_finite_difference(&map, &fp.section, FdScheme::default(), 2).unwrap();
        assert!((fd[0] - fp.dp[0]).abs() < 1e-7 * fp.dp[0].abs());
        // step length 2 l sin α
        assert!((fp.metrics.step_length.unwrap() - 2.0 * w.alpha().sin()).abs() < 1e-15);
    }
}

#[test]
fn rimless_return_map_matches_closed_form_off_the_fixed_point() {
    let w = wheel(0.08);
    let map = StrideMap::new(&w, Options::dop853(1e-14)).unwrap();
    let (a, g) = (w.alpha(), 0.08f64);
    for omega in [1.0, 1.5, 2.5] {
        let next = map.apply(&[omega]).unwrap()[0];
        let exact = (2.0 * a).cos() * (omega * omega + 4.0 * 9.81 * a.sin() * g.sin()).sqrt();
        assert!((next - exact).abs() < 1e-12, "{next} vs {exact}");
    }
}

#[test]
fn rimless_on_a_shallow_slope_rolls_back() {
    // ω* ≤ ω₁: no rolling gait; a slow start fails to reach the next spoke.
    let w = wheel(0.001);
    assert!(w.rolling_fixed_point().is_none());
    let map = StrideMap::new(&w, Options::dop853(1e-10)).unwrap();
    let st = map.stride(&[0.5]).unwrap();
    assert!(
        matches!(
            st.outcome,
            StrideOutcome::Fall {
                kind: FallKind::RollsBack,
                ..
            }
        ),
        "{:?}",
        st.outcome
    );
    let st = map.stride(&[0.0]).unwrap();
    assert!(
        matches!(
            st.outcome,
            StrideOutcome::Fall {
                kind: FallKind::RollsBack,
                ..
            }
        ),
        "{:?}",
        st.outcome
    );
}
