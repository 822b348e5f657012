//! `models/kneed_latched.toml`: Hsu Chen's kneed walker with latches of declared strength walks
//! a physically valid gait, and the smallest latch that holds it is the pull the ideal latch of
//! `models/kneed.toml` reports. The reference is that ideal latch's pull (its margins checked
//! against the independent Lagrange model in `tests/tests/round_foot_kneed_reference.rs`); the
//! latched walker is judged by its own limits, built and released by the hybrid model.

use crate::common::{
    first_gait as gait, raw, run, stderr, LATCH_IMPULSES as IMPULSES, LATCH_TORQUES as TORQUES,
};

const LATCHED: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../models/kneed_latched.toml"
);

#[test]
fn a_latched_kneed_walker_is_valid_and_its_smallest_latch_is_the_pull() {
    // the ideal latch (no limits): the pulls its gait needs, flagged invalid
    let ideal = gait(&["--model", "kneed"]);
    assert_eq!(ideal["validity"]["valid"], false);
    let pull_torque = TORQUES.iter().map(|n| -raw(&ideal, n)).fold(0.0, f64::max);
    let pull_impulse = IMPULSES.iter().map(|n| -raw(&ideal, n)).fold(0.0, f64::max);
    assert!((pull_torque - 0.0993).abs() < 1e-4, "{pull_torque}");
    assert!((pull_impulse - 0.00233).abs() < 1e-5, "{pull_impulse}");

    // the shipped latches (0.2, 0.005): valid, the same gait bit for bit
    let shipped = gait(&["--model", LATCHED]);
    assert_eq!(
        shipped["validity"]["valid"], true,
        "{}",
        shipped["validity"]
    );
    assert_eq!(
        shipped["validity"]["violations"].as_array().unwrap().len(),
        0
    );
    assert!(shipped["validity"]["min_relative_margin"].as_f64().unwrap() > 0.0);
    assert_eq!(shipped["state"], ideal["state"]);
    assert_eq!(shipped["stable"], true);

    // latches 1 % stronger than the pulls: valid, each latch margin limit − pull
    let (t, i) = (1.01 * pull_torque, 1.01 * pull_impulse);
    let (ts, is) = (format!("latch_torque={t}"), format!("latch_impulse={i}"));
    let just = gait(&["--model", LATCHED, "--set", &ts, "--set", &is]);
    assert_eq!(just["validity"]["valid"], true, "{}", just["validity"]);
    assert_eq!(just["state"], ideal["state"]);
    for n in TORQUES {
        let want = t + raw(&ideal, n);
        assert!(
            (raw(&just, n) - want).abs() < 1e-9,
            "{n}: {} vs {want}",
            raw(&just, n)
        );
    }
    for n in IMPULSES {
        let want = i + raw(&ideal, n);
        assert!(
            (raw(&just, n) - want).abs() < 1e-9,
            "{n}: {} vs {want}",
            raw(&just, n)
        );
    }

    // 1 % weaker than either pull: the latch lets go and the published gait is gone — in
    // stance the stance knee buckles under the walker; at heel strike the trailing knee is
    // released, so the stride map no longer returns to a state with the swing knee at rest
    for (set, why) in [
        (
            format!("latch_torque={}", 0.99 * pull_torque),
            "stance knee buckled",
        ),
        (
            format!("latch_impulse={}", 0.99 * pull_impulse),
            "no fixed point found",
        ),
    ] {
        let o = run(&["fixedpoint", "--model", LATCHED, "--set", &set]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{set}: {e}");
        let guess = e
            .lines()
            .find(|l| l.contains("guess 'stable'"))
            .unwrap_or("");
        assert!(
            guess.contains(why) && e.contains("no gait found"),
            "{set}: {e}"
        );
    }
}
