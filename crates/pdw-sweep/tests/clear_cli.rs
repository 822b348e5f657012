//! The CLI's clarity: integrator flags (checked against a second method and Garcia's fixed
//! point), input conflicts refused with exit 2, falls named, the rimless wheel's advice against
//! its own closed form, the compass gait's short-period unstable gait, and `animate` warning on
//! unstable or flagged gaits.

use crate::common::{json, run, stderr};

/// Garcia et al., J. Biomech. Eng. 120 (1998), from Garcia's own code.
const STABLE: [f64; 2] = [0.20031090049483, -0.19983247291764];

fn stable_section(v: &serde_json::Value) -> Vec<f64> {
    let fp = v["fixed_points"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["stable"] == true)
        .expect("a stable gait");
    serde_json::from_value(fp["section"].clone()).unwrap()
}

fn exits_2_naming(args: &[&str], words: &[&str]) {
    let o = run(args);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
    let e = stderr(&o);
    for w in words {
        assert!(e.contains(w), "{args:?}: message {e:?} lacks {w:?}");
    }
    assert!(!e.contains("panicked"), "{e}");
}

#[test]
fn every_integrator_finds_garcias_gait() {
    // The default (DOP853 1e-14), DOPRI5 and fixed-step RK4 are three independent routes to the
    // same fixed point; each is within its own accuracy of Garcia's.
    let base = ["fixedpoint", "--gait", "stable", "--json"];
    let cases: [(&[&str], f64, serde_json::Value); 3] = [
        (
            &[],
            1e-10,
            serde_json::json!({"method": "dop853", "rtol": 1e-14, "atol": 1e-14}),
        ),
        (
            &["--integrator", "dopri5", "--rtol", "1e-13"],
            1e-10,
            serde_json::json!({"method": "dopri5", "rtol": 1e-13, "atol": 1e-13}),
        ),
        // RK4's global error ∝ h⁴: h = 0.005 over a 3.9-long stride leaves ~1e-10.
        (
            &[
                "--integrator",
                "rk4",
                "--rk4-step",
                "0.005",
                "--tol",
                "1e-10",
            ],
            1e-8,
            serde_json::json!({"method": "rk4", "h": 0.005}),
        ),
    ];
    let mut sections = Vec::new();
    for (extra, within, integrator) in cases {
        let mut args = base.to_vec();
        args.extend_from_slice(extra);
        let v = json(&run(&args));
        assert_eq!(v["integrator"], integrator, "{args:?}");
        let s = stable_section(&v);
        for (a, b) in s.iter().zip(STABLE) {
            assert!(
                (a - b).abs() < within,
                "{args:?}: {s:?} vs Garcia {STABLE:?}"
            );
        }
        sections.push(s);
    }
    // DOPRI5 and DOP853 agree far below Garcia's printed digits.
    for (a, b) in sections[0].iter().zip(&sections[1]) {
        assert!((a - b).abs() < 1e-11, "{sections:?}");
    }
}

#[test]
fn integrator_options_that_would_be_ignored_are_refused() {
    for cmd in ["fixedpoint", "basin", "simulate"] {
        exits_2_naming(&[cmd, "--integrator", "rk4"], &["--rk4-step"]);
        exits_2_naming(
            &[
                cmd,
                "--integrator",
                "rk4",
                "--rk4-step",
                "0.01",
                "--rtol",
                "1e-8",
            ],
            &["--rtol", "rk4"],
        );
        exits_2_naming(&[cmd, "--rk4-step", "0.01"], &["--rk4-step", "rk4"]);
        exits_2_naming(&[cmd, "--rtol", "1e-20"], &["--rtol", "1e-20"]);
        exits_2_naming(&[cmd, "--atol", "0"], &["--atol"]);
        exits_2_naming(&[cmd, "--integrator", "euler"], &["euler", "dopri5"]);
    }
}

#[test]
fn slope_given_twice_and_sweep_options_without_sweep_are_refused() {
    for cmd in ["fixedpoint", "basin", "simulate", "animate"] {
        exits_2_naming(
            &[cmd, "--slope", "0.01", "--set", "slope=0.02"],
            &["--slope 0.01", "--set slope=0.02"],
        );
    }
    exits_2_naming(
        &["fixedpoint", "--set", "gravity=1", "--set", "gravity=2"],
        &["gravity", "twice"],
    );
    // --csv and --threads shape a sweep's output only: without --sweep they are refused, not
    // ignored (`--sweep … --json` prints the sweep: tests/sweep_output.rs).
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.csv");
    exits_2_naming(
        &["fixedpoint", "--csv", out.to_str().unwrap()],
        &["--csv", "--sweep"],
    );
    exits_2_naming(&["fixedpoint", "--threads", "2"], &["--threads", "--sweep"]);
    assert!(!out.exists(), "nothing is computed or written");
}

#[test]
fn falls_are_named_without_guard_numbers() {
    let o = run(&["fixedpoint", "--guess", "0.5,0.5"]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("fell backward"), "{e}");
    assert!(!e.contains("guard"), "{e}");
    assert!(!e.contains("no  period"), "{e}");
}

/// The advice's threshold against the rimless model's own closed-form fixed point: just below
/// it the model has no rolling gait and the CLI asks for a steeper slope (naming the threshold);
/// just above it the gait exists.
#[test]
fn rimless_advice_asks_for_a_steeper_slope_at_the_right_threshold() {
    let o = run(&["fixedpoint", "--model", "rimless", "--slope", "0.03"]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("steeper --slope"), "{e}");
    assert!(!e.contains("smaller --slope"), "{e}");
    let threshold: f64 = e
        .split("needs slope > ")
        .nth(1)
        .and_then(|t| t.split_whitespace().next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("a threshold in {e:?}"));
    assert!((0.05..0.09).contains(&threshold), "{threshold}");
    let below = format!("{}", threshold - 2e-4);
    let above = format!("{}", threshold + 2e-4);
    let o = run(&["fixedpoint", "--model", "rimless", "--slope", &below]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let v = json(&run(&[
        "fixedpoint",
        "--model",
        "rimless",
        "--slope",
        &above,
        "--json",
    ]));
    assert_eq!(v["fixed_points"].as_array().unwrap().len(), 1, "{v}");
    // The legged walkers' advice names both directions; an uphill slope is named as such.
    let o = run(&["fixedpoint", "--guess", "0.5,0.5"]);
    assert!(
        stderr(&o).contains("another --slope (too steep"),
        "{}",
        stderr(&o)
    );
    assert!(stderr(&o).contains("too shallow"), "{}", stderr(&o));
    let o = run(&["fixedpoint", "--slope", "-0.01"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("a downhill --slope"), "{}", stderr(&o));
    assert!(stderr(&o).contains("uphill"), "{}", stderr(&o));
    assert!(!stderr(&o).contains("shallower"), "{}", stderr(&o));
    // A degenerate step is not blamed on the floor alone (a rimless wheel with 1e9 spokes
    // rolls fast with steps of 6e-9).
    let o = run(&["fixedpoint", "--model", "rimless", "--set", "n_spokes=1e9"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("very many spokes"), "{}", stderr(&o));
    assert!(!stderr(&o).contains("barely moves"), "{}", stderr(&o));
}

/// Goswami et al. 1998: besides the stable long-period gait, the compass at 3° has an unstable
/// short-period one.
#[test]
fn compass_unstable_gait_is_the_short_period_one() {
    let v = json(&run(&["fixedpoint", "--model", "compass", "--json"]));
    let fps = v["fixed_points"].as_array().unwrap();
    assert_eq!(fps.len(), 2, "{v}");
    let period = |stable: bool| {
        fps.iter().find(|f| f["stable"] == stable).unwrap()["period"]
            .as_f64()
            .unwrap()
    };
    // Goswami, Thuilot & Espiau 1998: the stable gait's step period at 3° is ≈ 0.73 s.
    assert!((period(true) - 0.73).abs() < 0.01, "{v}");
    assert!(period(false) < 0.85 * period(true), "{v}");
    let v = json(&run(&[
        "fixedpoint",
        "--model",
        "compass",
        "--gait",
        "unstable",
        "--json",
    ]));
    let fp = &v["fixed_points"][0];
    assert_eq!(fp["gait"], "unstable");
    let lmax = fp["multipliers"][0]["re"].as_f64().unwrap();
    assert!(lmax > 1.0, "{fp}");
    assert_eq!(v["time_unit"], "s");
    assert_eq!(
        v["section_units"],
        serde_json::json!(["rad", "rad/s", "rad/s"])
    );
}

#[test]
fn animate_warns_on_unstable_and_flagged_gaits() {
    let dir = tempfile::tempdir().unwrap();
    let gif = dir.path().join("a.gif");
    let g = gif.to_str().unwrap();
    // γ = 0.0185: the simplest walker's period-one gait exists but is unstable (chaos).
    let o = run(&["animate", "--slope", "0.0185", "--out", g]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("UNSTABLE"), "{}", stderr(&o));
    // seed5's locked-knee gait needs a pulling knee torque: flagged.
    let o = run(&["animate", "--model", "seed5", "--out", g, "--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("FLAGGED"), "{}", stderr(&o));
    assert!(stderr(&o).contains("knee"), "{}", stderr(&o));
    // The Garcia gait is stable and valid: no warning.
    let o = run(&["animate", "--out", g, "--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
}

/// A basin integrator coarse enough to move the gait by more than a tenth of the gait
/// tolerance is run, with a warning naming the residual; the default gives none.
#[test]
fn basin_warns_when_its_integrator_moves_the_gait() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b.h5");
    let o = out.to_str().unwrap();
    let r = run(&[
        "basin",
        "--integrator",
        "rk4",
        "--rk4-step",
        "0.2",
        "--grid",
        "6x6",
        "--quiet",
        "--out",
        o,
    ]);
    assert!(r.status.success(), "{}", stderr(&r));
    assert!(stderr(&r).contains("fixed point only to"), "{}", stderr(&r));
    let r = run(&["basin", "--grid", "6x6", "--quiet", "--force", "--out", o]);
    assert!(r.status.success(), "{}", stderr(&r));
    assert!(!stderr(&r).contains("warning"), "{}", stderr(&r));
}

/// Flags that one run would silently drop are refused, naming them; errors name the flag
/// given; a file that cannot be resumed says what to do.
#[test]
fn conflicting_or_ignored_flags_are_refused_naming_them() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let o = run(&[
        "fixedpoint",
        "--sweep",
        "slope=0.01:0.02:3",
        "--slope",
        "0.01",
        "--out",
        &p("s.h5"),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--sweep slope: the parameter is also set"),
        "{}",
        stderr(&o)
    );
    let o = run(&["fixedpoint", "--png", &p("q.png")]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--png: only a --sweep"),
        "{}",
        stderr(&o)
    );
    assert!(!dir.path().join("q.png").exists());
    let o = run(&[
        "fixedpoint",
        "--sweep",
        "slope=0.01:0.02:3",
        "--follow",
        "pd",
        "--free",
        "hip_mass",
        "--map-grid",
        "0x0",
        "--png",
        &p("f.png"),
        "--out",
        &p("f.h5"),
        "--model",
        "compass",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--map-grid: '0'"), "{}", stderr(&o));
    std::fs::write(dir.path().join("junk.h5"), vec![7u8; 5000]).unwrap();
    let o = run(&[
        "basin",
        "--grid",
        "8x8",
        "--max-strides",
        "10",
        "--quiet",
        "--out",
        &p("junk.h5"),
        "--resume",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("start it over with --force instead of --resume"),
        "{}",
        stderr(&o)
    );
}
