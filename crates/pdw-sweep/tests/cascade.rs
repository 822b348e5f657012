//! `fixedpoint --sweep … --max-period P` and `--from MU` on the command line: every branch of
//! the cascade in the HDF5 file, the JSON and the CSV; a range whose first value has no gait
//! started inside it, against the rimless wheel's closed-form rolling gait (Coleman; REFERENCES
//! §2); bad values refused with messages naming them.

use crate::common::{json, run, stderr};
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn max_period_four_writes_every_branch_of_the_cascade() {
    let dir = tempfile::tempdir().unwrap();
    let (out, csv) = (dir.path().join("c.h5"), dir.path().join("c.csv"));
    let o = run(&[
        "fixedpoint",
        "--sweep",
        "slope=0.014:0.0185:6",
        "--max-period",
        "4",
        "--out",
        s(&out),
        "--csv",
        s(&csv),
        "--json",
        "--quiet",
    ]);
    let j = json(&o);
    let names: Vec<&str> = j["branches"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["period-1", "period-2", "period-4"]);
    // The file holds the same branches, each with its period, and the located doublings of
    // every branch (1→2 near Garcia's 0.0151; then 2→4 and 4→8 above it).
    let d = pdw::store::read_sweep(&out).unwrap();
    let periods: Vec<u32> = d.branches.iter().map(|b| b.period_strides).collect();
    assert_eq!(periods, [1, 2, 4]);
    let pd: Vec<(usize, f64)> = d
        .bifurcations
        .iter()
        .filter(|b| b.kind == "period_doubling")
        .map(|b| (b.branch, b.parameter))
        .collect();
    assert_eq!(pd.iter().map(|p| p.0).collect::<Vec<_>>(), [0, 1, 2]);
    assert!((pd[0].1 - 0.0151).abs() < 1e-3 && pd[0].1 < pd[1].1 && pd[1].1 < pd[2].1);
    // The period-4 branch: its points past the 2→4 doubling, four orbit points each, in the
    // JSON as in the file; and four CSV rows per point.
    let four = &d.branches[2];
    assert!(!four.parameter.is_empty());
    assert!(four.parameter.iter().all(|&g| g > pd[1].1));
    assert!(four.orbit.iter().all(|o| o.len() == 4));
    let jp = j["branches"][2]["points"].as_array().unwrap();
    assert_eq!(jp.len(), four.parameter.len());
    let text = std::fs::read_to_string(&csv).unwrap();
    let header = text.lines().find(|l| !l.starts_with('#')).unwrap();
    let col = header.split(',').position(|c| c == "branch_name").unwrap();
    let rows = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .filter(|l| l.split(',').nth(col) == Some("period-4"))
        .count();
    assert_eq!(rows, 4 * four.parameter.len());
    assert!(dir.path().join("c.png").exists());
}

#[test]
fn a_range_whose_first_value_has_no_gait_starts_inside_it() {
    // The rimless wheel (8 spokes, g/l = 9.81) rolls on only where its closed-form fixed point
    // ω* = cot 2α √(4 (g/l) sin α sin γ) exceeds the vaulting speed ω₁ = √(2 (g/l)(1 −
    // cos(γ − α))): for γ above ≈ 0.0683. At A = 0.04 nothing rolls; the middle value 0.08 does.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r.h5");
    let o = run(&[
        "fixedpoint",
        "--model",
        "rimless",
        "--sweep",
        "slope=0.04:0.12:9",
        "--out",
        s(&out),
        "--json",
        "--quiet",
    ]);
    let err = stderr(&o);
    assert!(err.contains("starting from the gait at slope = "), "{err}");
    let j = json(&o);
    let start = j["settings"]["grid"]["start"].as_f64().unwrap();
    assert!((start - 0.08).abs() < 1e-12, "{start}");
    let a = std::f64::consts::PI / 8.0;
    let rolls = |g: f64| {
        let w = (4.0 * 9.81 * a.sin() * g.sin()).sqrt() / (2.0 * a).tan();
        let w1 = (2.0 * 9.81 * (1.0 - (g - a).cos())).sqrt();
        (w > w1).then_some(w)
    };
    let pts = j["branches"][0]["points"].as_array().unwrap();
    let got: Vec<f64> = pts.iter().map(|p| p["param"].as_f64().unwrap()).collect();
    let want: Vec<f64> = (0..9)
        .map(|i| 0.04 + 0.01 * i as f64)
        .filter(|&g| rolls(g).is_some())
        .collect();
    assert_eq!(got.len(), want.len(), "{got:?} vs {want:?}");
    for (p, g) in pts.iter().zip(&want) {
        let mu = p["param"].as_f64().unwrap();
        assert!((mu - g).abs() < 1e-12);
        let w = p["section"][0].as_f64().unwrap();
        let exact = rolls(mu).unwrap();
        assert!((w - exact).abs() < 1e-9 * exact, "{w} vs {exact} at {mu}");
    }
}

#[test]
fn bad_cascade_depths_and_start_values_are_refused() {
    for (args, want) in [
        (
            vec!["--max-period", "3"],
            "--max-period: 3 is not a power of two",
        ),
        (
            vec!["--max-period", "128"],
            "--max-period: 128 is not a power of two",
        ),
        (
            vec!["--from", "0.5"],
            "--from: 0.5 is outside the swept range",
        ),
    ] {
        let mut a = vec!["fixedpoint", "--sweep", "slope=0.005:0.01:3"];
        a.extend(args);
        let o = run(&a);
        assert!(!o.status.success());
        let err = stderr(&o);
        assert!(err.contains(want), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

#[test]
fn no_gait_anywhere_names_the_values_tried() {
    // Uphill (a negative slope) the simplest walker has no gait at any value of the range.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("n.h5");
    let o = run(&[
        "fixedpoint",
        "--sweep",
        "slope=-0.02:-0.01:5",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains("slope = -0.02, -0.015, -0.0175, -0.0125 "),
        "{err}"
    );
    assert!(err.contains("--from") && err.contains("--search"), "{err}");
}
