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
