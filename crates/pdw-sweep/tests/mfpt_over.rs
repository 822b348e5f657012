//! `mfpt --over PARAM=A:B:N` and `fixedpoint --gsn`: each value of the over run is the single
//! run at that value (same walkers and seed), a value without a stable gait is kept and marked,
//! the file reads back and names its provenance, the PNGs are written, and the GSN of the
//! report equals the library's.

use super::common::{h5_open, run, stderr};

/// Over the compass's slope: value 0 (a slope with no gait) is marked, the others equal
/// `mfpt --slope V` with the same walkers and seed; the file round-trips, both PNGs exist.
#[test]
fn mfpt_over_a_parameter_is_the_single_runs_and_marks_missing_gaits() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("over.h5");
    let base = [
        "mfpt",
        "--model",
        "compass",
        "--sd",
        "1deg",
        "--walkers",
        "40",
        "--max-steps",
        "300",
        "--seed",
        "4",
        "--quiet",
    ];
    let mut args = base.to_vec();
    args.extend([
        "--over",
        "slope=-0.02:0.06:3",
        "--out",
        out.to_str().unwrap(),
    ]);
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(text.contains("no stable gait"), "{text}");
    assert!(text.contains("Spearman"), "{text}");
    assert!(out.with_extension("png").exists());
    assert!(dir.path().join("over-gsn.png").exists());
    let d = pdw::store::read_mfpt_over(&out).unwrap();
    assert_eq!(d.values, vec![-0.02, 0.02, 0.06]);
    assert_eq!(d.param, "slope");
    assert_eq!(d.stable[0], 0);
    assert!(d.mfpt[0].is_nan() && d.gsn[0].is_nan());
    for i in 1..3 {
        assert_eq!(d.stable[i], 1);
        assert!(d.gsn[i].is_finite() && d.gsn[i] > 0.0);
        let single = dir.path().join(format!("s{i}.h5"));
        let v = format!("{:?}", d.values[i]);
        let mut args = base.to_vec();
        args.extend(["--slope", &v, "--out", single.to_str().unwrap()]);
        let o = run(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let s = pdw::store::read_mfpt(&single).unwrap();
        assert_eq!((s.total_steps, s.falls), (d.total_steps[i], d.falls[i]));
        // the GSN of the over run is fixedpoint --gsn's
        let o = run(&[
            "fixedpoint",
            "--model",
            "compass",
            "--slope",
            &v,
            "--gait",
            "stable",
            "--gsn",
            "--json",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let g = j["fixed_points"][0]["gsn"]["norm"].as_f64().unwrap();
        assert_eq!(g, d.gsn[i]);
    }
    let f = h5_open(&out).unwrap();
    assert!(
        f.group("provenance").is_ok(),
        "the file names its provenance"
    );
    // the store's own round trip
    let again = dir.path().join("again.h5");
    pdw::store::write_mfpt_over(&again, false, &d).unwrap();
    assert_eq!(pdw::store::read_mfpt_over(&again).unwrap().values, d.values);
    let mut back = pdw::store::read_mfpt_over(&again).unwrap();
    back.command.clear();
    let mut orig = d.clone();
    orig.command.clear();
    // NaN ≠ NaN: compare the finite entries and where the NaNs are
    assert_eq!(format!("{back:?}"), format!("{orig:?}"));
}

/// `fixedpoint --gsn` refuses an unknown indicator by name and reports an unstable gait's norm
/// as infinite, never as a number.
#[test]
fn fixedpoint_gsn_names_bad_indicators_and_unstable_gaits() {
    let o = run(&["fixedpoint", "--gsn", "--indicators", "step-time,hop"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("'hop'"), "{}", stderr(&o));
    let o = run(&[
        "fixedpoint",
        "--slope",
        "0.009",
        "--gait",
        "unstable",
        "--gsn",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let g = &j["fixed_points"][0]["gsn"];
    assert!(g["norm"].is_null() && g["unstable"] == true, "{g}");
}
