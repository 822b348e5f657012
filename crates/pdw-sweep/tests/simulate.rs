//! `pdw-sweep simulate`: the files hold exactly what the library computes.

use pdw::limit::gaits;
use pdw::limit::trajectory::{self, TrajectoryOptions};
use std::process::Command;

fn simulate(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_pdw-sweep"))
        .arg("simulate")
        .args(args)
        .output()
        .unwrap()
}

/// The library's trajectory of the compass walker's stable gait, 3 steps.
fn library_compass() -> pdw::limit::Trajectory {
    let w = pdw::walkers::build("compass", &[]).unwrap();
    let (found, _) = gaits::search(w.as_ref(), &gaits::model_guesses(w.as_ref()), 1e-12).unwrap();
    let fp = &found.iter().find(|f| f.fp.stable).unwrap().fp;
    trajectory::simulate(w.as_ref(), &fp.state, &TrajectoryOptions::new(3)).unwrap()
}

#[test]
fn hdf5_and_csv_hold_the_library_trajectory() {
    let dir = tempfile::tempdir().unwrap();
    let tr = library_compass();
    let h5 = dir.path().join("c.h5");
    let csv = dir.path().join("c.csv");
    for p in [&h5, &csv] {
        let o = simulate(&[
            "--model",
            "compass",
            "--strides",
            "3",
            "--dt-out",
            "steps",
            "--out",
            p.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let d = pdw::store::read_trajectory_h5(&h5).unwrap();
    assert_eq!(d.column("t").unwrap().values, tr.t);
    assert_eq!(d.column("t").unwrap().units, "s");
    for (j, name) in tr.state_names.iter().enumerate() {
        let want: Vec<f64> = (0..tr.len()).map(|i| tr.state(i)[j]).collect();
        assert_eq!(d.column(name).unwrap().values, want, "{name}");
    }
    assert_eq!(
        d.column("energy").unwrap().values,
        *tr.energy.as_ref().unwrap()
    );
    assert_eq!(
        d.column("normal_force").unwrap().values,
        tr.forces.as_ref().unwrap().normal
    );
    assert_eq!(
        d.events.t,
        tr.events.iter().map(|e| e.t).collect::<Vec<_>>()
    );
    assert!(d.events.kind.iter().all(|k| k == "heel_strike"));
    // CSV: shortest round-trip floats, the same numbers.
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), tr.len());
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(r[col("t")], tr.t[i]);
        assert_eq!(r[col("stance_rate")], tr.state(i)[2]);
        assert_eq!(r[col("energy")], tr.energy.as_ref().unwrap()[i]);
    }
    assert_eq!(text.matches("# event: ").count(), 3);
    // An existing file is refused and left as it was.
    let before = std::fs::read(&csv).unwrap();
    let o = simulate(&["--model", "compass", "--out", csv.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(std::fs::read(&csv).unwrap(), before);
}

#[test]
fn bad_input_names_the_value() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.csv");
    let out = out.to_str().unwrap();
    for (args, needle) in [
        (vec!["--state", "1,2,3", "--out", out], "3 values given"),
        (vec!["--strides", "0", "--out", out], "--strides"),
        (vec!["--dt-out=-1", "--out", out], "--dt-out"),
        (vec!["--dt-out", "0", "--out", out], "--dt-out"),
        (vec!["--dt-out", "fast", "--out", out], "nor the word steps"),
        (vec!["--gait", "sideways", "--out", out], "sideways"),
        (
            vec!["--state", "0.2,-0.2", "--gait", "stable", "--out", out],
            "cannot be used with",
        ),
        (vec!["--out", "t.txt"], "t.txt"),
    ] {
        let o = simulate(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains(needle), "{args:?}: {e}");
        assert!(!e.contains("panicked"));
    }
}

/// A walk whose samples would not fit in memory is refused up front from the gait's period (a
/// tiny --dt-out or --rk4-step), not grown until the process is killed; the library's own bound
/// stops a walk from any state at `max_samples`.
#[test]
fn walks_that_would_not_fit_in_memory_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.h5");
    for args in [
        &["--strides", "10", "--dt-out", "1e-12"][..],
        &[
            "--integrator",
            "rk4",
            "--rk4-step",
            "1e-12",
            "--dt-out",
            "steps",
        ][..],
    ] {
        let o = simulate(&[args, &["--out", out.to_str().unwrap()]].concat());
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        assert!(
            e.contains("samples") && e.contains("memory"),
            "{args:?}: {e}"
        );
        assert!(!out.exists(), "{args:?}: nothing written");
    }
    // the library's bound: a 3-step walk of every accepted step, at most 40 samples
    let w = pdw::walkers::build("compass", &[]).unwrap();
    let (found, _) = gaits::search(w.as_ref(), &gaits::model_guesses(w.as_ref()), 1e-12).unwrap();
    let fp = &found.iter().find(|f| f.fp.stable).unwrap().fp;
    let full = trajectory::simulate(w.as_ref(), &fp.state, &TrajectoryOptions::new(3)).unwrap();
    assert!(full.len() > 40, "{} samples", full.len());
    for dt_out in [None, Some(0.01)] {
        let opts = TrajectoryOptions {
            max_samples: 40,
            dt_out,
            ..TrajectoryOptions::new(3)
        };
        match trajectory::simulate(w.as_ref(), &fp.state, &opts) {
            Err(trajectory::TrajectoryError::TooManySamples { max_samples, .. }) => {
                assert_eq!(max_samples, 40)
            }
            other => panic!(
                "{dt_out:?}: expected the sample bound, got {:?}",
                other.map(|t| t.len())
            ),
        }
    }
    // RK4 at 1e-10 from the gait: one stride would be ~10^10 steps (hours). A full recorder
    // ends the integration call, so the bound is reached after 40 steps and the walk stops
    // there; before, the stride was integrated to its end with the samples dropped.
    let opts = TrajectoryOptions {
        max_samples: 40,
        integrator: pdw::hybrid::Options::rk4(1e-10),
        ..TrajectoryOptions::new(3)
    };
    match trajectory::simulate(w.as_ref(), &fp.state, &opts) {
        Err(trajectory::TrajectoryError::TooManySamples { steps_done, .. }) => {
            assert_eq!(steps_done, 0, "stopped inside the first stride")
        }
        other => panic!(
            "expected the sample bound, got {:?}",
            other.map(|t| t.len())
        ),
    }
    let opts = TrajectoryOptions {
        max_samples: full.len(),
        ..TrajectoryOptions::new(3)
    };
    assert_eq!(
        trajectory::simulate(w.as_ref(), &fp.state, &opts)
            .unwrap()
            .len(),
        full.len(),
        "a walk exactly at the bound is whole"
    );
}

/// Energy in a fixed frame, checked against Garcia's closed-form heel strike (1998, the jump map:
/// `θ̇⁺ = cos 2θ · θ̇⁻`, the massless swing foot carries no energy): on the simplest walker's
/// gait the fixed-frame energy is constant within each step (the flow conserves it) and drops
/// at each heel strike by the kinetic energy the strike removes, `½ θ̇⁻² sin² 2θ⁻` — which is
/// also the `m g L sin γ` one step down the slope releases, `L = 2 |sin θ⁻|`. The model's own
/// energy (potential zero at the stance foot) instead comes back to the same value each step.
#[test]
fn fixed_frame_energy_drops_by_the_heel_strike_loss() {
    let dir = tempfile::tempdir().unwrap();
    let h5 = dir.path().join("s.h5");
    let o = simulate(&["--strides", "3", "--out", h5.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let d = pdw::store::read_trajectory_h5(&h5).unwrap();
    let col = |n: &str| d.column(n).unwrap().values.clone();
    let (e, fixed, step) = (col("energy"), col("energy_fixed_frame"), col("step"));
    assert_eq!(d.column("energy_fixed_frame").unwrap().units, "M g l");
    for k in 0..3 {
        let within: Vec<f64> = (0..e.len())
            .filter(|&i| step[i] == k as f64)
            .map(|i| fixed[i])
            .collect();
        let spread = within.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - within.iter().copied().fold(f64::INFINITY, f64::min);
        assert!(
            spread < 1e-9,
            "step {k}: fixed-frame energy varies by {spread:e}"
        );
    }
    let slope = 0.009_f64;
    for (k, pre) in d.events.pre.chunks(4).enumerate() {
        let (th, thd) = (pre[0], pre[1]);
        let loss = 0.5 * thd * thd * (2.0 * th).sin().powi(2);
        let released = 2.0 * th.sin().abs() * slope.sin();
        let at = |s: f64| (0..e.len()).find(|&i| step[i] == s).unwrap();
        let drop = fixed[at(k as f64)] - fixed[at(k as f64 + 1.0)];
        assert!(
            (drop - loss).abs() < 1e-9,
            "step {k}: drop {drop:e}, strike loss {loss:e}"
        );
        assert!(
            (loss - released).abs() < 1e-9,
            "step {k}: {loss:e} vs {released:e}"
        );
        assert!((e[at(k as f64)] - e[at(k as f64 + 1.0)]).abs() < 1e-9);
    }
}

fn root_attr(f: &hdf5::File, name: &str) -> String {
    f.attr(name)
        .unwrap_or_else(|_| panic!("attribute {name}"))
        .read_scalar::<hdf5::types::VarLenUnicode>()
        .unwrap()
        .as_str()
        .to_string()
}

/// Without --dt-out the file is dense: samples every period / 100 of the gait (the period
/// measured independently as the time between two heel strikes), about 100 per step plus both
/// sides of every heel strike, and the attributes say so; `--dt-out steps` gives the library's
/// per-step trajectory, sample for sample.
#[test]
fn the_default_output_is_a_hundred_samples_per_step() {
    let dir = tempfile::tempdir().unwrap();
    for model in ["simplest", "compass"] {
        let h5 = dir.path().join(format!("{model}.h5"));
        let o = simulate(&[
            "--model",
            model,
            "--strides",
            "3",
            "--out",
            h5.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let d = pdw::store::read_trajectory_h5(&h5).unwrap();
        let (t, step) = (
            &d.column("t").unwrap().values,
            &d.column("step").unwrap().values,
        );
        let period = d.events.t[2] - d.events.t[1];
        let f = crate::common::h5_open(&h5).unwrap();
        let h: f64 = root_attr(&f, "dt_out").parse().unwrap();
        assert!(
            (h - period / 100.0).abs() < 1e-9 * period,
            "{model}: {h} vs {period}"
        );
        assert!(root_attr(&f, "dt_out_source").contains("period"));
        for k in 0..3 {
            let grid = (0..t.len())
                .filter(|&i| step[i] == k as f64 && !d.events.t.contains(&t[i]))
                .count();
            assert!(
                (98..=102).contains(&grid),
                "{model} step {k}: {grid} samples"
            );
        }
        for te in &d.events.t {
            assert_eq!(
                t.iter().filter(|&&s| s == *te).count(),
                2,
                "{model}: event {te}"
            );
        }
    }
    let tr = library_compass();
    let h5 = dir.path().join("steps.h5");
    let o = simulate(&[
        "--model",
        "compass",
        "--strides",
        "3",
        "--dt-out",
        "steps",
        "--out",
        h5.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let d = pdw::store::read_trajectory_h5(&h5).unwrap();
    assert_eq!(d.len(), tr.len());
    let f = crate::common::h5_open(&h5).unwrap();
    assert_eq!(root_attr(&f, "dt_out"), "every accepted step and event");
}

/// The positions in the file are the library's ([`pdw::simulate::positions`]): a 2-wide dataset
/// per point (`pos_hip`, …; CSV columns `pos_hip_x`, `pos_hip_y`), `com`, and the attributes
/// naming the points and the frame; the hip is the compass's stance-leg geometry by hand.
#[test]
fn the_files_hold_the_walkers_positions() {
    let dir = tempfile::tempdir().unwrap();
    let (h5, csv) = (dir.path().join("p.h5"), dir.path().join("p.csv"));
    for p in [&h5, &csv] {
        let o = simulate(&[
            "--model",
            "compass",
            "--strides",
            "2",
            "--out",
            p.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let d = pdw::store::read_trajectory_h5(&h5).unwrap();
    let f = crate::common::h5_open(&h5).unwrap();
    assert_eq!(
        root_attr(&f, "point_names"),
        r#"["stance_foot","hip","swing_foot"]"#
    );
    assert!(root_attr(&f, "positions_frame").contains("downhill"));
    let hip = d.column("pos_hip").unwrap();
    assert_eq!((hip.width, hip.units.as_str()), (2, "m"));
    assert_eq!(hip.components, ["pos_hip_x", "pos_hip_y"]);
    let (stance, foot) = (
        &d.column("stance").unwrap().values,
        &d.column("pos_stance_foot").unwrap().values,
    );
    for i in 0..d.len() {
        // leg length a + b = 1 m (models/compass.toml)
        assert!((hip.values[2 * i] - (foot[2 * i] - stance[i].sin())).abs() < 1e-12);
        assert!((hip.values[2 * i + 1] - stance[i].cos()).abs() < 1e-12);
    }
    assert_eq!(d.column("com").unwrap().components, ["com_x", "com_y"]);
    let text = std::fs::read_to_string(&csv).unwrap();
    let header = text.lines().find(|l| !l.starts_with('#')).unwrap();
    for c in ["pos_hip_x", "pos_swing_foot_y", "com_x", "com_y"] {
        assert!(
            header.split(',').any(|h| h == c),
            "{c} missing from {header}"
        );
    }
}

/// `--json`: the report as one object whose counts are those of the file written, and the old
/// spelling `--steps` walks the same strides.
#[test]
fn the_json_report_counts_what_the_file_holds() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.h5"), dir.path().join("b.h5"));
    let o = simulate(&["--strides", "4", "--json", "--out", a.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let d = pdw::store::read_trajectory_h5(&a).unwrap();
    assert_eq!(j["strides"], 4);
    assert_eq!(j["strides_done"], 4);
    assert_eq!(j["outcome"], "ok");
    assert_eq!(j["fell"], false);
    assert_eq!(j["samples"], d.column("t").unwrap().values.len());
    assert_eq!(j["event_count"], d.events.t.len());
    assert_eq!(j["out"], a.to_str().unwrap());
    assert!(j["start"].as_str().unwrap().starts_with("stable gait"));
    let o = simulate(&["--steps", "4", "--out", b.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(text.contains("4 of 4 strides"), "{text}");
    let e = pdw::store::read_trajectory_h5(&b).unwrap();
    assert_eq!(d.column("t").unwrap().values, e.column("t").unwrap().values);
    assert_eq!(d.events.pre, e.events.pre);
}
