//! `fixedpoint --follow pd|fold --sweep NAME=A:B:N --free NAME`: the JSON shape, the curve file
//! (units, provenance, no overwrite without --force), the picture, a curve lost on the way, and
//! bad input refused with exit 2.

use crate::common;

use crate::common::{run, stderr};
use std::process::Command;

fn exits_2_naming(args: &[&str], words: &[&str]) {
    let o = run(args);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
    let e = stderr(&o);
    for w in words {
        assert!(e.contains(w), "{args:?}: message {e:?} lacks {w:?}");
    }
    assert!(!e.contains("panicked"), "{e}");
}

/// The compass period-doubling curve over hip_mass 8, 10, 12 kg (m = 5 kg): `--json` prints
/// `{"curve": {"kind": "pd", "params": ["hip_mass", "slope"], "points": [[p1, p2], …]}}`; at
/// μ = 2 the slope is Goswami et al. 1998's 4.39° (IJRR 17(12), "near 4.4°"); the file
/// holds the same points with units and provenance, and is not overwritten without --force.
#[test]
fn follow_pd_prints_the_curve_and_writes_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("pd.h5");
    let out_s = out.to_str().unwrap();
    let args = [
        "fixedpoint",
        "--model",
        "compass",
        "--follow",
        "pd",
        "--sweep",
        "hip_mass=8:12:3",
        "--free",
        "slope",
        "--json",
        "--out",
        out_s,
    ];
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON on stdout");
    let curve = v["curve"].as_object().unwrap();
    let mut keys: Vec<&str> = curve.keys().map(|k| k.as_str()).collect();
    keys.sort();
    assert_eq!(keys, ["kind", "params", "points"]);
    assert_eq!(curve["kind"], "pd");
    assert_eq!(curve["params"], serde_json::json!(["hip_mass", "slope"]));
    let pts: Vec<[f64; 2]> = serde_json::from_value(curve["points"].clone()).unwrap();
    assert_eq!(pts.len(), 3);
    assert_eq!(
        pts.iter().map(|p| p[0]).collect::<Vec<_>>(),
        [8.0, 10.0, 12.0]
    );
    let deg = pts[1][1].to_degrees();
    assert!((deg - 4.39).abs() < 0.005, "{deg} deg");
    // The period-doubling slope falls as the hip gets heavier (Goswami 1998, fig. of γ vs μ).
    assert!(pts[0][1] > pts[1][1] && pts[1][1] > pts[2][1], "{pts:?}");
    assert_eq!(v["complete"], true);
    for g in v["gaits"].as_array().unwrap() {
        let l = g["critical_multiplier"].as_f64().unwrap();
        assert!((l + 1.0).abs() < 1e-9, "{l}");
    }

    let f = common::h5_open(&out).unwrap();
    let p_free: Vec<f64> = f.dataset("curve/p_free").unwrap().read_raw().unwrap();
    let p_step: Vec<f64> = f.dataset("curve/p_step").unwrap().read_raw().unwrap();
    assert_eq!(p_step, [8.0, 10.0, 12.0]);
    for (a, b) in p_free.iter().zip(&pts) {
        assert_eq!(*a, b[1]);
    }
    let units = |ds: &str| -> String {
        f.dataset(ds)
            .unwrap()
            .attr("units")
            .unwrap()
            .read_scalar::<hdf5::types::VarLenUnicode>()
            .unwrap()
            .to_string()
    };
    assert_eq!(units("curve/p_step"), "kg");
    assert_eq!(units("curve/p_free"), "rad");
    assert_eq!(units("curve/period"), "s");
    for ds in [
        "curve/section",
        "curve/state",
        "curve/multipliers_re",
        "curve/multipliers_im",
        "curve/critical",
        "curve/residual",
    ] {
        assert!(!units(ds).is_empty(), "{ds}");
    }
    let state = f.dataset("curve/state").unwrap().shape();
    assert_eq!(state, [3, 4]);
    let prov = f.group("provenance").unwrap();
    assert!(prov.attr("options").is_ok() && prov.attr("command").is_ok());
    drop(f);

    // No overwrite without --force.
    exits_2_naming(&args, &["--out", "exists", "--force"]);
}

/// `--png` draws the diagram over a region map (a small grid here).
#[test]
fn follow_png_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("pd.h5");
    let png = dir.path().join("pd.png");
    let o = run(&[
        "fixedpoint",
        "--model",
        "compass",
        "--follow",
        "pd",
        "--sweep",
        "hip_mass=9:11:2",
        "--free",
        "slope",
        "--map-grid",
        "4x6",
        "--out",
        out.to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let f = common::h5_open(&out).unwrap();
    let region = f.dataset("map/region").unwrap();
    assert_eq!(region.shape(), [6, 4]);
    let codes: Vec<u8> = region.read_raw().unwrap();
    // Below the curve the gait is stable (code 0), far above it the walker falls or leaves the
    // period-one gait: both kinds are present in every column.
    for i in 0..4 {
        let col: Vec<u8> = (0..6).map(|j| codes[j * 4 + i]).collect();
        assert_eq!(col[0], 0, "column {i}: {col:?}");
        assert_ne!(col[5], 0, "column {i}: {col:?}");
    }
    // The same map on one worker thread (`--threads 1`, `--quiet`): the same codes.
    let out1 = dir.path().join("pd1.h5");
    let png1 = dir.path().join("pd1.png");
    let o = run(&[
        "fixedpoint",
        "--model",
        "compass",
        "--follow",
        "pd",
        "--sweep",
        "hip_mass=9:11:2",
        "--free",
        "slope",
        "--map-grid",
        "4x6",
        "--threads",
        "1",
        "--quiet",
        "--out",
        out1.to_str().unwrap(),
        "--png",
        png1.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let f1 = common::h5_open(&out1).unwrap();
    let codes1: Vec<u8> = f1.dataset("map/region").unwrap().read_raw().unwrap();
    assert_eq!(codes1, codes);
}

/// A curve that leaves the free parameter's domain: the points reached are printed and written,
/// the reason is named, exit 2.
#[test]
fn a_lost_curve_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("pd.h5");
    let o = run(&[
        "fixedpoint",
        "--model",
        "compass",
        "--follow",
        "pd",
        "--sweep",
        "hip_mass=10:4:4",
        "--free",
        "slope=0.01:0.085",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("lost") && e.contains("domain"), "{e}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON on stdout");
    assert_eq!(v["complete"], false);
    // hip_mass 10 and 8 (slope 0.0766, 0.0794) are inside, 6 (0.0832) too, 4 (0.0884) is not.
    assert_eq!(v["curve"]["points"].as_array().unwrap().len(), 3);
    assert!(out.exists());
}

#[test]
fn bad_input_exits_2_with_a_clear_message() {
    let base = ["fixedpoint", "--model", "compass"];
    let with = |extra: &[&'static str]| -> Vec<&'static str> {
        base.iter().chain(extra).copied().collect::<Vec<_>>()
    };
    exits_2_naming(
        &with(&[
            "--follow",
            "ns",
            "--sweep",
            "hip_mass=2:20:3",
            "--free",
            "slope",
        ]),
        &["not supported", "Neimark"],
    );
    exits_2_naming(
        &with(&[
            "--follow",
            "hopf",
            "--sweep",
            "hip_mass=2:20:3",
            "--free",
            "slope",
        ]),
        &["hopf", "pd", "fold"],
    );
    exits_2_naming(
        &with(&["--follow", "pd", "--free", "slope"]),
        &["--follow needs --sweep"],
    );
    exits_2_naming(
        &with(&[
            "--follow",
            "pd",
            "--sweep",
            "hip_mass=2:20:3",
            "--free",
            "slope",
            "--csv",
            "c.csv",
        ]),
        &["--csv", "--out"],
    );
    exits_2_naming(
        &with(&[
            "--follow",
            "pd",
            "--sweep",
            "hip_mass=2:20:3",
            "--free",
            "slope",
            "--threads",
            "0",
        ]),
        &["--threads", "between 1 and 1024"],
    );
    exits_2_naming(
        &with(&["--follow", "pd", "--sweep", "hip_mass=2:20:3"]),
        &["--follow needs --free"],
    );
    exits_2_naming(
        &with(&["--free", "slope", "--sweep", "hip_mass=2:20:3"]),
        &["--follow"],
    );
    exits_2_naming(
        &with(&[
            "--follow",
            "pd",
            "--sweep",
            "hip_mass=2:20:3",
            "--free",
            "legmass",
        ]),
        &["legmass", "leg_mass", "hip_mass"],
    );
    exits_2_naming(
        &with(&[
            "--follow",
            "pd",
            "--sweep",
            "hipmass=2:20:3",
            "--free",
            "slope",
        ]),
        &["hipmass", "hip_mass"],
    );
    exits_2_naming(
        &with(&[
            "--follow",
            "pd",
            "--sweep",
            "slope=2deg:5deg:3",
            "--free",
            "slope",
        ]),
        &["same parameter"],
    );
    exits_2_naming(
        &with(&[
            "--follow",
            "pd",
            "--sweep",
            "hip_mass=2:20:1",
            "--free",
            "slope",
        ]),
        &["point count", "2"],
    );
    exits_2_naming(
        &with(&[
            "--follow",
            "pd",
            "--sweep",
            "hip_mass=2:20:3",
            "--free",
            "slope=0.1:0.05",
        ]),
        &["inverted"],
    );
    exits_2_naming(
        &with(&[
            "--follow",
            "pd",
            "--sweep",
            "hip_mass=2:20:3",
            "--free",
            "slope=4deg:8deg",
        ]),
        &["outside", "--slope"],
    );
    exits_2_naming(
        &with(&[
            "--follow",
            "pd",
            "--sweep",
            "hip_mass=2:20:3",
            "--free",
            "slope",
            "--map-grid",
            "10x10",
        ]),
        &["--map-grid", "--png"],
    );
    exits_2_naming(
        &with(&[
            "--follow",
            "pd",
            "--sweep",
            "hip_mass=-2:20:3",
            "--free",
            "slope",
        ]),
        &["hip_mass = -2"],
    );
}

/// Without --out the curve goes to `pd.h5` (the kind's name), not to a sweep's `bif.h5`: a
/// sweep's file in the same directory is left alone.
#[test]
fn follow_defaults_its_output_to_the_kind() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bif.h5"), b"a sweep's file").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_pdw-sweep"))
        .current_dir(dir.path())
        .args([
            "fixedpoint",
            "--model",
            "compass",
            "--follow",
            "pd",
            "--sweep",
            "hip_mass=8:10:2",
            "--free",
            "slope",
            "--quiet",
        ])
        .output()
        .expect("the binary runs");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(dir.path().join("pd.h5").exists());
    assert_eq!(
        std::fs::read(dir.path().join("bif.h5")).unwrap(),
        b"a sweep's file"
    );
}
