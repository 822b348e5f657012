//! `basin --over NAME=A:B:N`: basin stability over a parameter. The fractions at a value equal a
//! plain `basin` run's on the same box (counted here from that run's own outcome grid), every
//! row sums to 1, `--json` holds the file's values, the default box is the one around the gait
//! at A, and bad input is refused.

use crate::common::{run, stderr};
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const BOX: [&str; 6] = [
    "--x",
    "theta=0.19:0.27",
    "--y",
    "thetadot=-0.27:-0.19",
    "--grid",
    "41x41",
];

/// Fractions of a plain basin file by column: an attractor's name (the gait, codes ≥ 10),
/// `fall` (every fall kind), `timeout`, `other` (the rest), counted from its outcome grid.
fn plain_fractions(path: &Path) -> Vec<(String, f64)> {
    let d = pdw::store::read_basin(path).unwrap();
    let name_of = |code: u8| -> String {
        let n = d
            .header
            .legend
            .iter()
            .find(|(c, _)| *c == code)
            .map(|(_, n)| n.clone())
            .unwrap();
        if code == 0 || code >= 10 {
            n
        } else if n.starts_with("fall") {
            "fall".into()
        } else if n == "timeout" {
            "timeout".into()
        } else {
            "other".into()
        }
    };
    let mut out: Vec<(String, usize)> = Vec::new();
    for &c in d.outcome.iter() {
        let n = name_of(c);
        match out.iter_mut().find(|(m, _)| *m == n) {
            Some(e) => e.1 += 1,
            None => out.push((n, 1)),
        }
    }
    let total = d.outcome.len() as f64;
    out.into_iter()
        .map(|(n, k)| (n, k as f64 / total))
        .collect()
}

#[test]
fn basin_stability_equals_plain_basin_runs_and_sums_to_one() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bs.h5");
    let mut args = vec![
        "basin",
        "--over",
        "slope=0.013:0.017:3",
        "--out",
        s(&out),
        "--json",
        "--threads",
        "1",
    ];
    args.extend(BOX);
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let d = pdw::store::read_stability(&out).unwrap();
    assert_eq!(d.values, vec![0.013, 0.015, 0.017]);
    assert_eq!(d.parameter, "slope");
    assert!(dir.path().join("bs.png").exists());
    // Every row sums to 1 (cells are counted once each).
    for (mu, r) in d.values.iter().zip(&d.fractions) {
        let sum: f64 = r.iter().sum();
        assert!((sum - 1.0).abs() < 1e-12, "{mu}: {r:?} sums to {sum}");
    }
    for r in &d.outcome_fractions {
        assert!((r.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }
    // The attractors met: the gait at 0.013, the period-2 orbit at 0.017 (Garcia 1998: the
    // gait period-doubles near 0.0151).
    let names = |i: usize| {
        d.attractors[i]
            .iter()
            .map(|a| a.name.clone())
            .collect::<Vec<_>>()
    };
    assert!(names(0).contains(&"gait".to_string()), "{:?}", names(0));
    assert!(names(2).contains(&"period-2".to_string()), "{:?}", names(2));
    let p2 = d.attractors[2]
        .iter()
        .find(|a| a.name == "period-2")
        .unwrap();
    assert_eq!((p2.period_strides, p2.points.len()), (2, 2));
    // At two of the values, the fractions equal a plain `basin` run's on the same box.
    for (i, slope) in [(0, "0.013"), (2, "0.017")] {
        let plain = dir.path().join(format!("plain{i}.h5"));
        let mut args = vec!["basin", "--slope", slope, "--out", s(&plain), "--quiet"];
        args.extend(BOX);
        let o = run(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let reference = plain_fractions(&plain);
        for (c, name) in d.columns.iter().enumerate() {
            let want = reference
                .iter()
                .find(|(n, _)| n == name)
                .map_or(0.0, |r| r.1);
            assert_eq!(d.fractions[i][c], want, "slope {slope}, column {name}");
        }
        for (name, f) in &reference {
            assert!(d.columns.contains(name), "{name} ({f}) missing");
        }
    }
    // --json: the file's values.
    assert_eq!(json["columns"], serde_json::json!(d.columns));
    for (i, v) in json["values"].as_array().unwrap().iter().enumerate() {
        assert_eq!(v["param"].as_f64(), Some(d.values[i]));
        for (c, name) in d.columns.iter().enumerate() {
            assert_eq!(v["fractions"][name].as_f64(), Some(d.fractions[i][c]));
        }
    }
    assert_eq!(json["box"]["source"], "--x and --y");
    // The same on two threads.
    let out2 = dir.path().join("bs2.h5");
    let mut args = vec![
        "basin",
        "--over",
        "slope=0.013:0.017:3",
        "--out",
        s(&out2),
        "--threads",
        "2",
    ];
    args.extend(BOX);
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let d2 = pdw::store::read_stability(&out2).unwrap();
    assert_eq!((d2.columns, d2.fractions), (d.columns, d.fractions));
}

#[test]
fn the_default_box_is_the_basin_box_around_the_gait_at_the_first_value() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d.h5");
    let o = run(&[
        "basin",
        "--over",
        "slope=0.009:0.011:2",
        "--grid",
        "11x11",
        "--out",
        s(&out),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    // The stable gait at 0.009 from `fixedpoint`.
    let fp = run(&[
        "fixedpoint",
        "--slope",
        "0.009",
        "--gait",
        "stable",
        "--json",
    ]);
    let fp: serde_json::Value = serde_json::from_slice(&fp.stdout).unwrap();
    let g = &fp["fixed_points"][0]["section"];
    for (axis, k) in [("x", 0), ("y", 1)] {
        let (lo, hi) = (
            j["box"][axis]["lo"].as_f64().unwrap(),
            j["box"][axis]["hi"].as_f64().unwrap(),
        );
        let c = g[k].as_f64().unwrap();
        assert!(
            ((lo + hi) / 2.0 - c).abs() < 1e-12,
            "{axis}: {lo}..{hi} around {c}"
        );
    }
    assert!(
        j["box"]["source"]
            .as_str()
            .unwrap()
            .contains("slope = 0.009"),
        "{}",
        j["box"]
    );
    assert_eq!(j["box"]["x"]["n"], 11);
}

#[test]
fn bad_over_input_is_refused_naming_the_value() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.h5");
    let o_ = s(&out);
    for (args, needles) in [
        (
            vec!["basin", "--over", "nosuch=1:2:3", "--out", o_],
            vec!["nosuch", "parameters"],
        ),
        (
            vec![
                "basin",
                "--over",
                "slope=0.01:0.02:3",
                "--slope",
                "0.01",
                "--out",
                o_,
            ],
            vec!["--over slope", "once"],
        ),
        (
            vec![
                "basin",
                "--over",
                "slope=0.01:0.02:3",
                "--resume",
                "--out",
                o_,
            ],
            vec!["--resume"],
        ),
        (
            vec!["basin", "--over", "slope=0.01:0.02:1", "--out", o_],
            vec!["--over", "point count"],
        ),
        (
            vec!["basin", "--json", "--out", o_],
            vec!["--json", "--over"],
        ),
    ] {
        let o = run(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        for n in needles {
            assert!(stderr(&o).contains(n), "{args:?}: {}", stderr(&o));
        }
    }
    assert!(!out.exists());
}

#[test]
fn basin_over_names_a_physically_invalid_gait_and_outlines_its_band() {
    // the kneed walker's gait at 0.051 rad needs its knee lock to pull (the sampled knee
    // torque of its stride is negative: the same verdict as `basin`'s, tested in cli.rs)
    let dir = tempfile::tempdir().unwrap();
    let (out, png) = (dir.path().join("k.h5"), dir.path().join("k.png"));
    let o = run(&[
        "basin",
        "--model",
        "kneed",
        "--over",
        "slope=0.050:0.051:2",
        "--grid",
        "9x9",
        "--out",
        s(&out),
        "--png",
        s(&png),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let traj = dir.path().join("t.h5");
    let o = run(&[
        "simulate",
        "--model",
        "kneed",
        "--slope",
        "0.051",
        "--steps",
        "1",
        "--dt-out",
        "0.002",
        "--out",
        s(&traj),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let tr = pdw::store::read_trajectory_h5(&traj).unwrap();
    let min_torque = tr
        .column("knee_torque")
        .unwrap()
        .values
        .iter()
        .copied()
        .filter(|v| !v.is_nan())
        .fold(f64::INFINITY, f64::min);
    assert!(min_torque < 0.0, "the stride's knee torque {min_torque}");
    let d = pdw::store::read_stability(&out).unwrap();
    let gait = d.attractors[1]
        .iter()
        .find(|a| a.name == "gait")
        .expect("a gait at 0.051");
    assert_eq!(gait.validity, "invalid");
    assert!(
        gait.invalid_reasons
            .iter()
            .any(|r| r == "a knee lock must pull"),
        "{:?}",
        gait.invalid_reasons
    );
    assert!(d.invalid_column("gait"));
    // the chart outlines the band in red (200, 0, 0), in the top panel only
    let dec = png::Decoder::new(std::fs::File::open(&png).unwrap());
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let (w, h) = (info.width as usize, info.height as usize);
    let red_rows: Vec<usize> = buf[..w * h * 3]
        .chunks(3 * w)
        .enumerate()
        .filter(|(_, row)| row.chunks(3).any(|q| q == [200, 0, 0]))
        .map(|(y, _)| y)
        .collect();
    assert!(
        !red_rows.is_empty() && red_rows.iter().all(|&y| y < h / 2),
        "{red_rows:?}"
    );
}
