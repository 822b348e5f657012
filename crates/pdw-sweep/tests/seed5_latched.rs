//! `models/seed5_latched.toml`: the seed's walker (Table 3.1) with a free swing knee walks a
//! stable gait at slope 0.1, held by the smallest latch with 1 % margins; its gait stays invalid
//! for what no latch changes (the swing foot below the slope before the knee strike); below the
//! pull the latch lets go and the gait falls. The gait was reached by a homotopy from Hsu
//! Chen's walker (`experiments/results/seed5_latched/homotopy.toml`), which must arrive at the
//! seed's own walker: the same gait in other units. The latch margins against an independent
//! Lagrange model: `tests/tests/round_foot_kneed_reference.rs`.

use crate::common::{
    first_gait as gait, json, margin, raw, run, stderr, LATCH_IMPULSES as IMPULSES,
    LATCH_TORQUES as TORQUES,
};

const MODEL: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../models/seed5_latched.toml"
);
const HOMOTOPY: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../experiments/results/seed5_latched/homotopy.toml"
);

/// The ideal latch's gait of the seed's walker with a free swing knee at slope 0.1.
fn ideal() -> serde_json::Value {
    gait(&[
        "--model",
        "seed5",
        "--set",
        "free_swing_knee=1",
        "--slope",
        "0.1",
        "--guess",
        "0.2712,-0.6428,0.4213",
    ])
}

#[test]
fn the_seeds_walker_walks_held_by_its_smallest_latch() {
    let ideal = ideal();
    assert_eq!(ideal["stable"], true);
    let pull_t = TORQUES.iter().map(|n| -raw(&ideal, n)).fold(0.0, f64::max);
    let pull_i = IMPULSES.iter().map(|n| -raw(&ideal, n)).fold(0.0, f64::max);
    // the pulls the model file documents (9.45 N m, 1.63 N m s)
    assert!((pull_t - 9.454).abs() < 1e-3, "{pull_t}");
    assert!((pull_i - 1.627).abs() < 1e-3, "{pull_i}");

    let latched = gait(&["--model", MODEL]);
    let v = &latched["validity"];
    // the same gait: a latch that holds changes no state
    assert_eq!(latched["state"], ideal["state"]);
    let rho = latched["multipliers"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["re"].as_f64().unwrap().hypot(m["im"].as_f64().unwrap()))
        .fold(0.0, f64::max);
    assert!(rho < 0.9, "max |λ| {rho}");
    // every latch margin is limit − pull, at least 1 % of its scale, and the declared limits
    // exceed the smallest such latch by less than 0.05 % of the scale (their rounding)
    let (lt, li) = (13.5, 4.2);
    let scale_t = margin(&latched, "stance_knee_torque")["scale"]
        .as_f64()
        .unwrap();
    let scale_i = margin(&latched, "knee_strike:stance_knee")["scale"]
        .as_f64()
        .unwrap();
    for (names, limit, scale, pull) in [
        (&TORQUES[..], lt, scale_t, pull_t),
        (&IMPULSES[..], li, scale_i, pull_i),
    ] {
        for n in names {
            let want = limit + raw(&ideal, n);
            assert!((raw(&latched, n) - want).abs() < 1e-9, "{n}");
            assert!(
                margin(&latched, n)["relative"].as_f64().unwrap() >= 0.01,
                "{n}"
            );
        }
        let smallest = pull + 0.01 * scale;
        assert!(
            limit >= smallest && limit - smallest < 5e-4 * scale,
            "{limit} vs {smallest}"
        );
    }
    // invalid, but only for the swing foot's dip before the knee strike, which no latch changes
    assert_eq!(v["valid"], false);
    let violated: Vec<&str> = v["violations"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x["criterion"].as_str().unwrap())
        .collect();
    assert_eq!(violated, ["swing_clearance"], "{v}");
    assert!(v["scuff_depth"].as_f64().unwrap() > 1e-3);

    // 10 % below either pull the latch lets go: the stance knee buckles and the gait is gone
    for set in [
        format!("latch_torque={}", 0.9 * pull_t),
        format!("latch_impulse={}", 0.9 * pull_i),
    ] {
        let o = run(&["fixedpoint", "--model", MODEL, "--set", &set]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{set}: {e}");
        assert!(
            e.contains("stance knee buckled") && e.contains("no gait found"),
            "{set}: {e}"
        );
    }
}

/// The homotopy from Hsu Chen's walker (h = 0) covers its range to the seed's walker (h = 1):
/// the last point is at h = 1 exactly, where the hip mass reaches 0 and the model cannot be
/// built beyond (the continuation's μ-derivative turns one-sided there), and its gait is the
/// seed's own in Hsu Chen's units — the same angles, rates scaled by √((g/l)_seed / (g/l)_H).
#[test]
fn the_homotopy_arrives_at_the_seeds_walker() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("h.h5");
    let slope = "0.10101818181818181";
    let d = json(&run(&[
        "fixedpoint",
        "--model",
        HOMOTOPY,
        "--set",
        &format!("slope={slope}"),
        "--guess",
        "0.3039289637217219,-1.1614448278086533,2.008567827721782",
        "--sweep",
        "h=0:1:5",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]));
    let pts = d["branches"][0]["points"].as_array().unwrap();
    assert_eq!(pts.len(), 5, "every grid value, h = 1 included");
    let last = &pts[4];
    assert_eq!(last["param"], 1.0);
    let s: Vec<f64> = last["section"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let seed = gait(&[
        "--model",
        "seed5",
        "--set",
        "free_swing_knee=1",
        "--slope",
        slope,
        "--guess",
        "0.2717,-0.6422,0.4196",
    ]);
    let rate = ((9.81 / 4.0) / (9.8 / 1.0f64)).sqrt();
    let want = seed["section"].as_array().unwrap();
    for (i, w) in want.iter().enumerate() {
        let w = w.as_f64().unwrap() / if i == 0 { 1.0 } else { rate };
        assert!((s[i] - w).abs() < 1e-8, "coordinate {i}: {} vs {w}", s[i]);
    }
}
