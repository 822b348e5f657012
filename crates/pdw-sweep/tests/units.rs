//! Units on the command line mean what they say: `--slope 3°` is `--slope 3deg` is the compass
//! preset's 0.05235987755982988, a spec parameter in degrees is converted, and a slope far
//! steeper than passive walking (`--slope 1`, meant as 1°) draws one warning naming its degrees.

use crate::common::{json, run, stderr};

#[test]
fn slope_in_degrees_with_a_sign_or_a_word_is_the_presets_slope() {
    let base = [
        "fixedpoint",
        "--model",
        "compass",
        "--gait",
        "stable",
        "--json",
    ];
    let preset = json(&run(&base));
    assert_eq!(preset["slope"].as_f64(), Some(0.05235987755982988));
    for form in ["3°", "3deg", " 3 deg"] {
        let o = run(&[&base[..], &["--slope", form]].concat());
        let j = json(&o);
        assert_eq!(j["slope"].as_f64(), Some(0.05235987755982988), "{form:?}");
        assert_eq!(
            j["fixed_points"], preset["fixed_points"],
            "--slope {form:?} must give the preset's gait bit for bit"
        );
        assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
    }
    let o = run(&["fixedpoint", "--slope", "3 furlong"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("`furlong`, not an angle") && stderr(&o).contains("3deg, 3°"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn a_slope_of_1_warns_once_naming_57_degrees() {
    for args in [
        &["fixedpoint", "--slope", "1"][..],
        &["fixedpoint", "--set", "slope=1"][..],
    ] {
        let o = run(args);
        let e = stderr(&o);
        assert_eq!(
            e.matches("warning: slope 1 rad = 57.3° is far steeper than passive walking (≲ 0.3 rad); did you mean 1deg?")
                .count(),
            1,
            "{args:?}: {e}"
        );
    }
    // not at the presets' slopes
    let o = run(&["fixedpoint", "--slope", "0.3", "--gait", "stable"]);
    assert!(!stderr(&o).contains("far steeper"), "{}", stderr(&o));
}

/// A spec file's slope in degrees is converted; a default of 60° warns as `--slope` would.
#[test]
fn a_spec_files_slope_in_degrees_is_converted_and_checked() {
    let dir = tempfile::tempdir().unwrap();
    let preset = String::from_utf8(run(&["models", "--spec", "compass"]).stdout).unwrap();
    let old = "value = 0.05235987755982988, unit = \"rad\"";
    assert!(preset.contains(old), "{preset}");
    let deg = dir.path().join("deg.toml");
    std::fs::write(&deg, preset.replace(old, "value = 3, unit = \"deg\"")).unwrap();
    let args = ["fixedpoint", "--gait", "stable", "--json", "--model"];
    let a = json(&run(&[&args[..], &["compass"]].concat()));
    let b = json(&run(&[&args[..], &[deg.to_str().unwrap()]].concat()));
    assert_eq!(b["slope"].as_f64(), Some(0.05235987755982988));
    assert_eq!(a["fixed_points"], b["fixed_points"]);
    let steep = dir.path().join("steep.toml");
    std::fs::write(&steep, preset.replace(old, "value = 60, unit = \"deg\"")).unwrap();
    let o = run(&["fixedpoint", "--model", steep.to_str().unwrap()]);
    assert_eq!(
        stderr(&o).matches("= 60.0° is far steeper").count(),
        1,
        "{}",
        stderr(&o)
    );
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, preset.replace("unit = \"kg\"", "unit = \"stone\"")).unwrap();
    let o = run(&["fixedpoint", "--model", bad.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("unit` = \"stone\"") && stderr(&o).contains("units accepted"),
        "{}",
        stderr(&o)
    );
}

/// `--set NAME=VALUE[unit]` converts a unit of the parameter's quantity (the preset's gait bit
/// for bit) and refuses one of another quantity, naming both, with exit 2.
#[test]
fn set_with_a_unit_converts_it_or_refuses_another_quantity() {
    let base = [
        "fixedpoint",
        "--model",
        "compass",
        "--gait",
        "stable",
        "--json",
    ];
    let preset = json(&run(&base));
    for set in [
        "hip_mass=10000g",
        "a=50cm",
        "b=500 mm",
        "max_stride_time=5000ms",
    ] {
        let o = run(&[&base[..], &["--set", set]].concat());
        assert!(o.status.success(), "{set}: {}", stderr(&o));
        assert_eq!(json(&o)["fixed_points"], preset["fixed_points"], "{set}");
    }
    for (set, part) in [
        (
            "hip_mass=572.96deg",
            "unit `deg` is an angle, hip_mass is a mass (kg, g, …)",
        ),
        ("leg_mass=49N", "unit `N` is a force, leg_mass is a mass"),
        (
            "max_stride_time=5m",
            "unit `m` is a length, max_stride_time is a time (s, ms, …)",
        ),
        (
            "a=0.5rad",
            "unit `rad` is an angle, a is a length (m, cm, mm, …)",
        ),
        ("a=0.5furlong", "`furlong` is not a unit"),
        ("slope=0.05m", "`m`, not an angle"),
    ] {
        let o = run(&["fixedpoint", "--model", "compass", "--set", set]);
        assert_eq!(o.status.code(), Some(2), "{set}: {}", stderr(&o));
        assert!(stderr(&o).contains(part), "{set}: {}", stderr(&o));
        assert!(stderr(&o).contains(&format!("--set {set}")) || set.starts_with("slope"));
    }
    // the simplest walker's own units take plain numbers
    let o = run(&["fixedpoint", "--set", "max_stride_time=12s"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("plain number"), "{}", stderr(&o));
    // CLI quantities that are angles: a length refused
    for args in [
        &["fixedpoint", "--slope", "0.05m"][..],
        &["mfpt", "--sd", "1mm", "--walkers", "2"][..],
    ] {
        let o = run(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("is a length") && stderr(&o).contains("is an angle"),
            "{args:?}: {}",
            stderr(&o)
        );
    }
}

/// A spec file whose hip mass is in degrees is refused at the command line (exit 2).
#[test]
fn a_spec_files_mass_in_degrees_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let preset = String::from_utf8(run(&["models", "--spec", "compass"]).stdout).unwrap();
    let old = "hip_mass = { value = 10.0, unit = \"kg\"";
    assert!(preset.contains(old), "{preset}");
    let bad = dir.path().join("deg.toml");
    std::fs::write(
        &bad,
        preset.replace(old, "hip_mass = { value = 572.96, unit = \"deg\""),
    )
    .unwrap();
    let o = run(&["fixedpoint", "--model", bad.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("unit `deg` is an angle, hip_mass is a mass (kg, g, …)"),
        "{}",
        stderr(&o)
    );
}
