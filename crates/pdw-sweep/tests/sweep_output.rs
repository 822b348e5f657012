//! `fixedpoint --sweep` output a researcher can use: exactly N points per branch on the
//! requested grid, every point of a period-2 orbit (checked against the orbit diagram and
//! against iterating the stride map), the measurements per point, `--json` and `--csv` holding
//! the HDF5 file's values, and results independent of `--threads`.

use crate::common::{run, stderr};
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The grid of `--sweep NAME=A:B:N` as documented: A + (B − A)·i/(N − 1), the last value B.
fn grid(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| {
            if i + 1 == n {
                b
            } else {
                a + (b - a) * i as f64 / (n - 1) as f64
            }
        })
        .collect()
}

const RANGE: &str = "slope=0.0135:0.0175:9";
const N: usize = 9;

/// Runs the sweep of [`RANGE`] with `threads` threads, writing HDF5, CSV and printing JSON.
fn sweep(dir: &Path, tag: &str, threads: &str) -> (pdw::store::SweepData, serde_json::Value) {
    let out = dir.join(format!("{tag}.h5"));
    let csv = dir.join(format!("{tag}.csv"));
    let o = run(&[
        "fixedpoint",
        "--sweep",
        RANGE,
        "--out",
        s(&out),
        "--csv",
        s(&csv),
        "--threads",
        threads,
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).expect("stdout is JSON");
    (pdw::store::read_sweep(&out).unwrap(), json)
}

fn stride_map_at(slope: f64) -> Box<dyn pdw::walkers::Walker> {
    pdw::walkers::build("simplest", &[("slope", slope)]).unwrap()
}

#[test]
fn sweep_output_points_json_csv_and_threads() {
    let dir = tempfile::tempdir().unwrap();
    let (data, json) = sweep(dir.path(), "one", "1");
    let params = grid(0.0135, 0.0175, N);

    // ---- exactly N points on the period-1 branch, at the grid values, in order
    let p1 = &data.branches[0];
    assert_eq!((p1.name.as_str(), p1.period_strides), ("period-1", 1));
    assert_eq!(
        p1.parameter, params,
        "the period-1 branch is the N-point grid"
    );
    // The period doubling is located on its own (Garcia 1998: γ ≈ 0.0151; 0.0150884379 by
    // two independent routes in pdw-limit's tests) and is not a grid point.
    let pd: Vec<f64> = data
        .bifurcations
        .iter()
        .filter(|b| b.kind == "period_doubling" && b.branch == 0)
        .map(|b| b.parameter)
        .collect();
    assert_eq!(pd.len(), 1, "{:?}", data.bifurcations);
    assert!((pd[0] - 0.015088437941).abs() < 1e-7, "{pd:?}");
    // ---- the period-2 branch exists beyond the period doubling: exactly the grid values there
    let p2 = &data.branches[1];
    assert_eq!((p2.name.as_str(), p2.period_strides), ("period-2", 2));
    let beyond: Vec<f64> = params.iter().copied().filter(|&g| g > pd[0]).collect();
    assert_eq!(p2.parameter, beyond);

    // ---- γ = 0.0165: both points of the period-2 orbit, against the orbit diagram and the map
    let i = params
        .iter()
        .position(|&g| g == 0.0165)
        .expect("0.0165 on the grid");
    let j = p2.parameter.iter().position(|&g| g == 0.0165).unwrap();
    let orbit = &p2.orbit[j];
    assert_eq!(orbit.len(), 2);
    assert_eq!(
        orbit[0], p2.section[j],
        "orbit[0] is the stored section point"
    );
    let diagram = data.orbit.as_ref().unwrap();
    assert_eq!(diagram.parameter[i], 0.0165);
    let samples: Vec<f64> = diagram.points[i].to_vec();
    assert!(
        samples.iter().all(|v| v.is_finite()),
        "the walker keeps walking"
    );
    // The orbit diagram (300 transient strides, then 64 recorded, its own integrator at 1e-10)
    // alternates between exactly the two stored θ values.
    for v in &samples {
        let d = (v - orbit[0][0]).abs().min((v - orbit[1][0]).abs());
        assert!(
            d < 1e-7,
            "diagram sample {v} is neither {} nor {}",
            orbit[0][0],
            orbit[1][0]
        );
    }
    for t in [orbit[0][0], orbit[1][0]] {
        assert!(
            samples.iter().any(|v| (v - t).abs() < 1e-7),
            "{t} not in the diagram"
        );
    }
    assert!(
        (orbit[0][0] - orbit[1][0]).abs() > 1e-3,
        "two distinct points"
    );
    // Iterating the stride map (a fresh DOP853 at 1e-13) maps each point onto the other.
    let w = stride_map_at(0.0165);
    let step = |x: &[f64]| w.step_length(x);
    let map = pdw::limit::StrideMap::new(w.as_ref(), pdw::hybrid::Options::dop853(1e-13))
        .unwrap()
        .with_step_length(&step);
    let s0 = map.stride(&orbit[0]).unwrap();
    let s1 = map.stride(&orbit[1]).unwrap();
    for (a, b) in s0
        .next
        .iter()
        .zip(&orbit[1])
        .chain(s1.next.iter().zip(&orbit[0]))
    {
        assert!(
            (a - b).abs() < 1e-9,
            "P maps the stored points onto each other: {a} vs {b}"
        );
    }
    // Period (the two strides' time), per-stride step lengths and speed, from the same map.
    assert!((p2.period[j] - (s0.period + s1.period)).abs() < 1e-9);
    let (l0, l1) = (s0.step_length.unwrap(), s1.step_length.unwrap());
    assert!((p2.step_length[j][0] - l0).abs() < 1e-9 && (p2.step_length[j][1] - l1).abs() < 1e-9);
    assert!((p2.speed[j] - (l0 + l1) / (s0.period + s1.period)).abs() < 1e-9);
    // Validity: the simplest walker's stance foot is loaded throughout (normal force > 0).
    for v in &p2.validity[j] {
        assert!(v.checked && v.valid && v.min_normal_force > 0.0, "{v:?}");
    }
    // Multipliers, signed: the period-1 gait there is past its period doubling (a real
    // multiplier below −1); the period-2 orbit is stable.
    let m1 = &p1.multipliers[i];
    assert!(m1.iter().any(|&(re, im)| im == 0.0 && re < -1.0), "{m1:?}");
    assert!(!p1.stable[i] && p2.stable[j]);
    // The file says how it was made.
    assert!(data.elapsed_s > 0.0 && data.elapsed_s.is_finite());
    let names: Vec<&str> = data.settings.iter().map(|(k, _)| k.as_str()).collect();
    for k in ["continuation", "grid", "integrator", "tolerances"] {
        assert!(names.contains(&k), "setting {k} missing: {names:?}");
    }

    // ---- --json: the file's values, exactly (NaN as null)
    let same = |j: &serde_json::Value, x: f64| {
        if x.is_nan() {
            assert!(j.is_null(), "{j} for NaN")
        } else {
            assert_eq!(j.as_f64(), Some(x))
        }
    };
    let jb = json["branches"].as_array().unwrap();
    assert_eq!(jb.len(), data.branches.len());
    for (b, jb) in data.branches.iter().zip(jb) {
        assert_eq!(jb["period_k"], b.period_strides);
        let pts = jb["points"].as_array().unwrap();
        assert_eq!(pts.len(), b.parameter.len());
        for (i, q) in pts.iter().enumerate() {
            same(&q["param"], b.parameter[i]);
            same(&q["period"], b.period[i]);
            same(&q["speed"], b.speed[i]);
            assert_eq!(q["stable"], b.stable[i]);
            for (k, pt) in b.orbit[i].iter().enumerate() {
                for (c, &x) in pt.iter().enumerate() {
                    same(&q["orbit"][k][c], x);
                }
                same(&q["step_length"][k], b.step_length[i][k]);
                same(
                    &q["validity"][k]["min_normal_force"],
                    b.validity[i][k].min_normal_force,
                );
                assert_eq!(q["validity"][k]["valid"], b.validity[i][k].valid);
            }
            for (k, &(re, im)) in b.multipliers[i].iter().enumerate() {
                same(&q["multipliers"][k]["re"], re);
                same(&q["multipliers"][k]["im"], im);
            }
        }
    }
    assert_eq!(
        json["bifurcations"].as_array().unwrap().len(),
        data.bifurcations.len()
    );
    assert_eq!(json["section_units"][1], "rad/sqrt(l/g)");

    // ---- --csv: one row per orbit point of every branch point, the file's values exactly
    let text = std::fs::read_to_string(dir.path().join("one.csv")).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        header[..7],
        [
            "param",
            "branch",
            "branch_name",
            "period_k",
            "point",
            "theta",
            "thetadot"
        ]
    );
    assert_eq!(
        header[header.len() - 4..],
        ["lambda1_re", "lambda1_im", "lambda2_re", "lambda2_im"]
    );
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let expected: usize = data
        .branches
        .iter()
        .map(|b| b.parameter.len() * b.period_strides as usize)
        .sum();
    assert_eq!(rows.len(), expected);
    let num = |t: &str| t.parse::<f64>().unwrap();
    let mut r = 0;
    for (bi, b) in data.branches.iter().enumerate() {
        for i in 0..b.parameter.len() {
            for k in 0..b.period_strides as usize {
                let row = &rows[r];
                assert_eq!(row.len(), header.len());
                assert_eq!(row[col("branch")], bi.to_string());
                assert_eq!(row[col("point")], k.to_string());
                assert_eq!(num(row[col("param")]), b.parameter[i]);
                assert_eq!(num(row[col("theta")]), b.orbit[i][k][0]);
                assert_eq!(num(row[col("thetadot")]), b.orbit[i][k][1]);
                assert_eq!(num(row[col("period")]), b.period[i]);
                assert_eq!(num(row[col("step_length")]), b.step_length[i][k]);
                assert_eq!(num(row[col("speed")]), b.speed[i]);
                assert_eq!(
                    row[col("valid")],
                    if b.validity[i][k].valid { "1" } else { "0" }
                );
                assert_eq!(num(row[col("lambda1_re")]), b.multipliers[i][0].0);
                assert_eq!(num(row[col("lambda2_im")]), b.multipliers[i][1].1);
                r += 1;
            }
        }
    }

    // ---- the same sweep on 2 threads: identical results
    let (two, _) = sweep(dir.path(), "two", "2");
    let strip = |d: &pdw::store::SweepData| {
        let mut j = pdw::store::sweep_json(d);
        j["elapsed_s"] = serde_json::Value::Null;
        j["settings"]["threads"] = serde_json::Value::Null;
        j
    };
    assert_eq!(strip(&data), strip(&two));
}

#[test]
fn a_decreasing_sweep_gives_its_n_values_in_its_own_order_and_bad_threads_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("down.h5");
    let o = run(&[
        "fixedpoint",
        "--sweep",
        "slope=0.012:0.004:5",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let d = pdw::store::read_sweep(&out).unwrap();
    assert_eq!(d.branches.len(), 1, "no period doubling below 0.012");
    assert_eq!(d.branches[0].parameter, grid(0.012, 0.004, 5));
    // Each point is a fixed point of the stride map at its own slope.
    for (g, x) in d.branches[0].parameter.iter().zip(&d.branches[0].section) {
        let w = stride_map_at(*g);
        let map =
            pdw::limit::StrideMap::new(w.as_ref(), pdw::hybrid::Options::dop853(1e-13)).unwrap();
        let p = map.apply(x).unwrap();
        assert!(
            p.iter().zip(x).all(|(a, b)| (a - b).abs() < 1e-9),
            "{g}: {x:?} → {p:?}"
        );
    }
    for bad in ["0", "100000"] {
        let o = run(&[
            "fixedpoint",
            "--sweep",
            "slope=0.012:0.004:5",
            "--threads",
            bad,
            "--out",
            s(&dir.path().join("x.h5")),
        ]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains("--threads"), "{}", stderr(&o));
    }
}

/// The console summary of a sweep is plain words: no Rust `Debug` text (`ParamBound { param:
/// … }`) reaches it; the branch's end is said as a sentence.
#[test]
fn sweep_console_output_has_no_debug_text() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bif.h5");
    let o = run(&[
        "fixedpoint",
        "--sweep",
        "slope=0.009:0.011:3",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout).into_owned() + &stderr(&o);
    assert!(
        text.contains("end: the parameter left the range at "),
        "{text}"
    );
    for debug in ["ParamBound", "param:", " { ", "Some(", "None", "::"] {
        assert!(!text.contains(debug), "{debug:?} in:\n{text}");
    }
}

/// The kneed preset's gait holds its knees with a latch that has to pull (its `valid` flags are
/// 0 in the file): the console counts the invalid points of the branch and names what fails,
/// from the same flags the file stores; the simplest walker (no constraint forces, unchecked)
/// says nothing of validity.
#[test]
fn sweep_console_counts_and_names_physically_invalid_points() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("kneed.h5");
    let o = run(&[
        "fixedpoint",
        "--model",
        "kneed",
        "--sweep",
        "slope=0.0504:0.052:3",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    let data = pdw::store::read_sweep(&out).unwrap();
    let b = &data.branches[0];
    let invalid = b
        .validity
        .iter()
        .filter(|strides| strides.iter().any(|v| v.checked && !v.valid))
        .count();
    let knee = b.validity.iter().flatten().any(|v| v.knee_unlocks);
    assert_eq!(invalid, 3, "the preset's latch pulls at every point");
    assert!(knee);
    assert!(
        text.contains("3 points on the output grid of 3 values; 3 physically invalid (")
            && text.contains("a knee lock must pull"),
        "{text}"
    );

    let simple = dir.path().join("simplest.h5");
    let o = run(&[
        "fixedpoint",
        "--sweep",
        "slope=0.009:0.011:3",
        "--out",
        s(&simple),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!String::from_utf8_lossy(&o.stdout).contains("invalid"));
}
