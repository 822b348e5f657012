//! End-to-end tests of the `pdw-sweep` binary: published values through `fixedpoint --json`,
//! bad input (exit code 2, a message naming the value, nothing lost), and the basin file's
//! reproducibility across thread counts, shards and interrupted runs.

use crate::common;
use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pdw-sweep"))
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("the binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn p(dir: &Path, name: &str) -> PathBuf {
    dir.join(name)
}

fn s(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// Garcia et al., J. Biomech. Eng. 120 (1998), from Garcia's own code.
const STABLE: [f64; 2] = [0.20031090049483, -0.19983247291764];
const UNSTABLE: [f64; 2] = [0.19393736960624, -0.20386692731962];

#[test]
fn fixedpoint_json_reproduces_garcia_both_gaits() {
    let o = run(&["fixedpoint", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["model"], "simplest");
    assert_eq!(v["slope"], 0.009);
    assert_eq!(v["section_names"], serde_json::json!(["theta", "thetadot"]));
    let fps = v["fixed_points"].as_array().unwrap();
    assert_eq!(fps.len(), 2, "both gaits expected: {v}");
    for fp in fps {
        for key in [
            "gait",
            "section",
            "state_names",
            "state",
            "period",
            "step_length",
            "speed",
            "multipliers",
            "stable",
            "residual",
            "iterations",
        ] {
            assert!(fp.get(key).is_some(), "missing key {key} in {fp}");
        }
        let sec: Vec<f64> = serde_json::from_value(fp["section"].clone()).unwrap();
        let want = if fp["stable"].as_bool().unwrap() {
            STABLE
        } else {
            UNSTABLE
        };
        for (a, b) in sec.iter().zip(want) {
            assert!((a - b).abs() < 1e-9, "{sec:?} vs Garcia {want:?}");
        }
        assert!(fp["residual"].as_f64().unwrap() <= 1e-12);
        // multipliers by decreasing modulus
        let m: Vec<f64> = fp["multipliers"]
            .as_array()
            .unwrap()
            .iter()
            .map(|z| z["re"].as_f64().unwrap().hypot(z["im"].as_f64().unwrap()))
            .collect();
        assert!(m.windows(2).all(|w| w[0] >= w[1] - 1e-15), "{m:?}");
        let stable = fp["stable"].as_bool().unwrap();
        assert_eq!(stable, m[0] < 1.0);
        // period ≈ 3.88 (long) or ≈ 3.10 (short), Garcia 1998
        let t = fp["period"].as_f64().unwrap();
        let want_t = if stable { 3.88 } else { 3.10 };
        assert!((t - want_t).abs() < 0.01, "period {t}");
    }
}

/// `--controller elementary` (DOPRI5 only): the same Garcia gait as the default PI controller
/// to the tolerance's level, recorded in `--json`'s integrator; refused for dop853.
#[test]
fn dopri5_controllers_find_garcias_gait_and_are_recorded() {
    let mut sections = Vec::new();
    for controller in [None, Some("elementary"), Some("pi")] {
        let mut args = vec![
            "fixedpoint",
            "--json",
            "--gait",
            "stable",
            "--integrator",
            "dopri5",
            "--rtol",
            "1e-12",
        ];
        if let Some(c) = controller {
            args.extend(["--controller", c]);
        }
        let o = run(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let elementary = controller == Some("elementary");
        assert_eq!(
            v["integrator"].get("controller").and_then(|c| c.as_str()),
            elementary.then_some("elementary"),
            "{v}"
        );
        let sec: Vec<f64> =
            serde_json::from_value(v["fixed_points"][0]["section"].clone()).unwrap();
        for (a, b) in sec.iter().zip(STABLE) {
            assert!(
                (a - b).abs() < 1e-9,
                "{controller:?}: {sec:?} vs Garcia {STABLE:?}"
            );
        }
        sections.push(sec);
    }
    // Different step sequences, the same gait to the tolerance's level; "pi" is the default.
    assert_ne!(sections[0], sections[1]);
    assert_eq!(sections[0], sections[2]);
    assert!(sections[0]
        .iter()
        .zip(&sections[1])
        .all(|(a, b)| (a - b).abs() < 1e-10));
    let o = run(&["fixedpoint", "--controller", "elementary"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--controller"), "{}", stderr(&o));
}

#[test]
fn fixedpoint_gait_filter_and_rimless_closed_form() {
    let o = run(&["fixedpoint", "--json", "--gait", "unstable"]);
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let fps = v["fixed_points"].as_array().unwrap();
    assert_eq!(fps.len(), 1);
    assert_eq!(fps[0]["stable"], false);
    // Rimless wheel (Coleman; Tedrake ch. 4): ω* = cot 2α √(4 (g/l) sin α sin γ), multiplier
    // cos² 2α.
    let o = run(&[
        "fixedpoint",
        "--model",
        "rimless",
        "--slope",
        "0.1",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let fp = &v["fixed_points"][0];
    let a = std::f64::consts::PI / 8.0;
    let w = (4.0 * 9.81 * a.sin() * 0.1f64.sin()).sqrt() / (2.0 * a).tan();
    assert!((fp["section"][0].as_f64().unwrap() - w).abs() < 1e-12);
    let lam = fp["multipliers"][0]["re"].as_f64().unwrap();
    assert!((lam - (2.0 * a).cos().powi(2)).abs() < 1e-10);
}

#[test]
fn bad_input_exits_2_with_a_message_naming_the_value() {
    let dir = tempfile::tempdir().unwrap();
    let out = p(dir.path(), "b.h5");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["fixedpoint", "--model", "bogus"], "bogus"),
        (vec!["fixedpoint", "--set", "massx=2"], "massx"),
        (vec!["fixedpoint", "--slope", "2"], "'2'"),
        (vec!["fixedpoint", "--slope", "3degx"], "3degx"),
        (vec!["fixedpoint", "--guess", "0.2"], "--guess"),
        (vec!["fixedpoint", "--gait", "wobbly"], "wobbly"),
        (
            vec!["basin", "--grid", "10by10", "--out", s(&out)],
            "10by10",
        ),
        (
            vec!["basin", "--x", "theta=0.3:0.1", "--out", s(&out)],
            "inverted",
        ),
        (vec!["basin", "--x", "psi=0.1:0.3", "--out", s(&out)], "psi"),
        (
            vec!["basin", "--max-strides", "0", "--out", s(&out)],
            "--max-strides",
        ),
        (vec!["basin", "--shard", "3/3", "--out", s(&out)], "3/3"),
        (vec!["basin", "--model", "rimless", "--out", s(&out)], "two"),
        (
            vec!["basin", "--grid", "8x8", "--out", "/nonexistent-dir/b.h5"],
            "nonexistent-dir",
        ),
    ];
    for (args, needle) in cases {
        let o = run(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.contains(needle),
            "{args:?}: message {e:?} should name {needle:?}"
        );
        assert!(!e.contains("panicked"), "{args:?}: {e}");
    }
    assert!(
        !out.exists(),
        "no file may be left behind by rejected input"
    );
}

fn basin(dir: &Path, name: &str, extra: &[&str]) -> (Output, PathBuf) {
    basin_grid(dir, name, "48x40", extra)
}

/// `basin` on a `grid`, at most 40 strides, quiet, into `out`, then `extra`.
fn basin_cmd(out: &Path, grid: &str, extra: &[&str]) -> Command {
    let mut c = bin();
    c.args([
        "basin",
        "--grid",
        grid,
        "--max-strides",
        "40",
        "--quiet",
        "--out",
        s(out),
    ])
    .args(extra);
    c
}

fn basin_grid(dir: &Path, name: &str, grid: &str, extra: &[&str]) -> (Output, PathBuf) {
    let out = p(dir, name);
    let o = basin_cmd(&out, grid, extra).output().unwrap();
    (o, out)
}

fn read(path: &Path) -> pdw::store::BasinData {
    pdw::store::read_basin(path).expect("readable basin file")
}

fn same_cells(a: &pdw::store::BasinData, b: &pdw::store::BasinData) {
    assert_eq!(a.outcome, b.outcome);
    assert_eq!(a.strides, b.strides);
    let (fa, fb) = (&a.final_state, &b.final_state);
    assert_eq!(fa.shape(), fb.shape());
    assert!(fa
        .iter()
        .zip(fb.iter())
        .all(|(x, y)| x.to_bits() == y.to_bits()));
}

#[test]
fn basin_is_identical_for_any_thread_count_and_refuses_overwrite() {
    let dir = tempfile::tempdir().unwrap();
    let (o1, f1) = basin(dir.path(), "t1.h5", &["--threads", "1"]);
    assert!(o1.status.success(), "{}", stderr(&o1));
    let (o2, f2) = basin(dir.path(), "t2.h5", &["--threads", "2"]);
    assert!(o2.status.success(), "{}", stderr(&o2));
    let (a, b) = (read(&f1), read(&f2));
    assert!(a.complete && b.complete);
    same_cells(&a, &b);
    // the fixed point's neighbourhood is gait, and both falls occur (Schwab & Wisse 2001 band)
    let gait = a.outcome.iter().filter(|&&c| c == 0).count();
    assert!(gait > 0 && gait < a.outcome.len() / 4, "gait cells {gait}");
    assert!(p(dir.path(), "t1.png").exists());
    // no overwrite without --force: the bytes stay
    let before = std::fs::read(&f1).unwrap();
    let (o3, _) = basin(dir.path(), "t1.h5", &["--threads", "1"]);
    assert_eq!(o3.status.code(), Some(2));
    assert!(stderr(&o3).contains("--force"));
    assert_eq!(std::fs::read(&f1).unwrap(), before);
    // resuming a complete file of the same run is an idempotent success (a requeued cluster
    // task that had finished): exit 0, says so, file and picture left alone
    let png_before = std::fs::read(p(dir.path(), "t1.png")).unwrap();
    let (o4, _) = basin(dir.path(), "t1.h5", &["--resume"]);
    assert_eq!(o4.status.code(), Some(0), "{}", stderr(&o4));
    assert!(
        String::from_utf8_lossy(&o4.stdout).contains("already complete"),
        "{}",
        String::from_utf8_lossy(&o4.stdout)
    );
    assert_eq!(std::fs::read(&f1).unwrap(), before);
    assert_eq!(std::fs::read(p(dir.path(), "t1.png")).unwrap(), png_before);
    // ... but not a complete file of another run: that is refused, file untouched
    let (o5, _) = basin_grid(dir.path(), "t1.h5", "48x41", &["--resume"]);
    assert_eq!(o5.status.code(), Some(2), "{}", stderr(&o5));
    assert!(stderr(&o5).contains("y grid"), "{}", stderr(&o5));
    assert_eq!(std::fs::read(&f1).unwrap(), before);
}

#[test]
fn shards_merged_equal_a_single_run() {
    let dir = tempfile::tempdir().unwrap();
    let (o, single) = basin(dir.path(), "single.h5", &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut shards = Vec::new();
    for i in 0..3 {
        let spec = format!("{i}/3");
        let (o, f) = basin(dir.path(), &format!("s{i}.h5"), &["--shard", &spec]);
        assert!(o.status.success(), "{}", stderr(&o));
        shards.push(f);
    }
    let merged = p(dir.path(), "merged.h5");
    let mut args = vec!["merge".to_string()];
    args.extend(shards.iter().map(|f| s(f).to_string()));
    args.extend(["--out".to_string(), s(&merged).to_string()]);
    let o = bin().args(&args).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let (a, b) = (read(&single), read(&merged));
    same_cells(&a, &b);
    let (ma, mb) = (a.metrics.unwrap(), b.metrics.unwrap());
    assert_eq!(ma.fractions, mb.fractions);
    assert_eq!(ma.basin_entropy.to_bits(), mb.basin_entropy.to_bits());
    // merging an incomplete set is refused
    let o = bin()
        .args([
            "merge",
            s(&shards[0]),
            s(&shards[1]),
            "--out",
            s(&p(dir.path(), "m2.h5")),
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    // a shard computed with --cold-restarts does not join warm ones: its integrator differs
    let (o, cold) = basin(
        dir.path(),
        "cold2.h5",
        &["--shard", "2/3", "--cold-restarts"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let o = bin()
        .args([
            "merge",
            s(&shards[0]),
            s(&shards[1]),
            s(&cold),
            "--out",
            s(&p(dir.path(), "m3.h5")),
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("integrator"), "{}", stderr(&o));
}

/// SIGTERM during a basin exits 130 leaving a resumable file; `--resume` finishes it with the
/// cells of an uninterrupted run, and its provenance keeps both command lines. The run signals
/// itself right after handing its 37th row to the writer (`PDW_SWEEP_SIGNAL_AFTER_ROWS`, a hook
/// in the basin command that raises a real SIGTERM and waits for the handler), so the cut is
/// mid-grid, at the same row, on every run. The cut is inside a block of
/// [`pdw::store::BLOCK_ROWS`] rows: the writer writes the rows of that incomplete block when the
/// run stops, so exactly the rows before the signal are done, and the resume completes the
/// block.
#[test]
fn interrupted_basin_resumes_to_the_same_file() {
    const GRID: &str = "50x50";
    // Not a multiple of the writer's row block: the rows of the incomplete block are kept too.
    const CUT: usize = 37;
    assert_ne!(CUT % pdw::store::BLOCK_ROWS, 0);
    let dir = tempfile::tempdir().unwrap();
    let (o, reference) = basin_grid(dir.path(), "ref.h5", GRID, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = p(dir.path(), "cut.h5");
    let child = basin_cmd(&out, GRID, &["--threads", "1"])
        .env("PDW_SWEEP_SIGNAL_AFTER_ROWS", CUT.to_string())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let status = child.wait_with_output().unwrap();
    assert_eq!(status.status.code(), Some(130), "SIGTERM exits with 130");
    assert!(stderr(&status).contains("continue with --resume"));
    let part = read(&out);
    assert!(!part.complete);
    let done: Vec<usize> = (0..part.rows_done.len())
        .filter(|&r| part.rows_done[r])
        .collect();
    assert_eq!(
        done,
        (0..CUT).collect::<Vec<_>>(),
        "exactly the rows before the signal"
    );
    let o = basin_cmd(&out, GRID, &["--resume"]).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    // The provenance lists both command lines: the interrupted run and its resume.
    let f = h5_open(&out).unwrap();
    let cmds: Vec<String> = serde_json::from_str(
        f.group("provenance")
            .unwrap()
            .attr("commands")
            .unwrap()
            .read_scalar::<hdf5::types::VarLenUnicode>()
            .unwrap()
            .as_str(),
    )
    .unwrap();
    assert_eq!(cmds.len(), 2, "{cmds:?}");
    assert!(!cmds[0].contains("--resume") && cmds[1].contains("--resume"));
    let (a, b) = (read(&reference), read(&out));
    assert!(b.complete);
    same_cells(&a, &b);
}

#[test]
fn corrupt_file_given_to_resume_is_an_error_and_left_alone() {
    let dir = tempfile::tempdir().unwrap();
    let f = p(dir.path(), "junk.h5");
    std::fs::write(&f, b"not an hdf5 file at all").unwrap();
    let (o, _) = basin(dir.path(), "junk.h5", &["--resume"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("junk.h5"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&f).unwrap(), b"not an hdf5 file at all");
}

#[test]
fn models_and_animate() {
    let o = run(&["models", "--json"]);
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let names: Vec<&str> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    for want in ["rimless", "simplest", "compass", "kneed", "seed5"] {
        assert!(names.contains(&want), "{names:?}");
    }
    let dir = tempfile::tempdir().unwrap();
    let gif = p(dir.path(), "g.gif");
    let o = run(&["animate", "--out", s(&gif)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&gif).unwrap();
    assert_eq!(&bytes[..6], b"GIF89a");
}

#[test]
fn sweep_locates_garcia_period_doubling_and_writes_hdf5_and_png() {
    let dir = tempfile::tempdir().unwrap();
    let out = p(dir.path(), "bif.h5");
    let o = run(&[
        "fixedpoint",
        "--sweep",
        "slope=0.013:0.016:40",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let data = pdw::store::read_sweep(&out).unwrap();
    assert_eq!(data.parameter, "slope");
    let pd: Vec<f64> = data
        .bifurcations
        .iter()
        .filter(|b| b.kind == "period_doubling" && b.branch == 0)
        .map(|b| b.parameter)
        .collect();
    assert_eq!(pd.len(), 1, "{:?}", data.bifurcations);
    // Garcia 1998: the stable gait period-doubles near γ ≈ 0.0151; our two independent routes
    // (continuation, bisection on directly computed multipliers) agree on 0.0150884379 (pdw-limit
    // tests); here the CLI must reproduce it to 1e-7.
    assert!((pd[0] - 0.015088437941).abs() < 1e-7, "{pd:?}");
    assert!(p(dir.path(), "bif.png").exists());
    let orbit = data.orbit.unwrap();
    assert_eq!(orbit.parameter.len(), 40);
}

#[test]
fn basins_past_the_period_doubling_label_every_attractor_for_any_shard_split() {
    // γ = 0.016: no stable period-one gait, a stable period-2 gait (Garcia 1998's cascade).
    let dir = tempfile::tempdir().unwrap();
    let (o, whole) = basin(dir.path(), "w.h5", &["--slope", "0.016", "--threads", "2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut shards = Vec::new();
    for (i, threads) in [(0, "1"), (1, "2")] {
        let spec = format!("{i}/2");
        let (o, f) = basin(
            dir.path(),
            &format!("s{i}.h5"),
            &["--slope", "0.016", "--shard", &spec, "--threads", threads],
        );
        assert!(o.status.success(), "{}", stderr(&o));
        shards.push(f);
    }
    let merged = p(dir.path(), "m.h5");
    let o = bin()
        .args(["merge", s(&shards[0]), s(&shards[1]), "--out", s(&merged)])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let (a, b) = (read(&whole), read(&merged));
    same_cells(&a, &b);
    assert_eq!(a.attractors, b.attractors);
    assert!(a.header.legend.contains(&(16, "period-2".to_string())));
    assert!(a.outcome.iter().any(|&c| c == 16), "no period-2 cell");
    assert!(a.outcome.iter().all(|&c| c != 0), "no cell may be `gait`");
    let at = a.attractors.iter().find(|x| x.name == "period-2").unwrap();
    assert_eq!((at.period_strides, at.section.len()), (2, 2));
    assert!(at.multipliers.iter().all(|(re, im)| re.hypot(*im) < 1.0));
    assert!(p(dir.path(), "w.png").exists() && p(dir.path(), "m.png").exists());
    // γ = 0.0189: a chaotic attractor, sampled, with its own code.
    let (o, ch) = basin(dir.path(), "c.h5", &["--slope", "0.0189"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let c = read(&ch);
    assert!(c.header.legend.contains(&(16, "chaotic".to_string())));
    assert!(c.outcome.iter().any(|&x| x == 16), "no chaotic cell");
    let at = c.attractors.iter().find(|x| x.name == "chaotic").unwrap();
    assert_eq!(at.period_strides, 0);
    assert!(at.multipliers.is_empty() && at.section.len() > 100);
    assert!(at.period_time.is_nan());
    // Its shards merge (the NaN period of a chaotic attractor equals itself bit for bit).
    let mut shards = Vec::new();
    for i in 0..2 {
        let spec = format!("{i}/2");
        let (o, f) = basin(
            dir.path(),
            &format!("c{i}.h5"),
            &["--slope", "0.0189", "--shard", &spec],
        );
        assert!(o.status.success(), "{}", stderr(&o));
        shards.push(f);
    }
    let merged = p(dir.path(), "cm.h5");
    let o = bin()
        .args(["merge", s(&shards[0]), s(&shards[1]), "--out", s(&merged)])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    same_cells(&c, &read(&merged));
    // Before the period doubling nothing changes: the stable gait keeps code 0 and is the only
    // attractor.
    let (o, g) = basin(dir.path(), "g.h5", &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let g = read(&g);
    assert_eq!(g.header.legend.len(), 13, "the fixed outcomes 0-12 only");
    assert_eq!(g.attractors.len(), 1);
    assert_eq!(g.attractors[0].name, "gait");
    assert!(g.outcome.iter().any(|&x| x == 0));
}

#[test]
fn fixedpoint_period_two_lists_both_points() {
    let o = run(&[
        "fixedpoint",
        "--slope",
        "0.016",
        "--period",
        "2",
        "--gait",
        "stable",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let fps = v["fixed_points"].as_array().unwrap();
    assert_eq!(fps.len(), 1);
    let f = &fps[0];
    assert_eq!(f["period_k"], 2);
    let orbit = f["orbit"].as_array().unwrap();
    assert_eq!(orbit.len(), 2);
    assert_eq!(f["section"], orbit[0]);
    let th: Vec<f64> = orbit.iter().map(|p| p[0].as_f64().unwrap()).collect();
    assert!((th[0] - th[1]).abs() > 1e-3, "{th:?}");
    for m in f["multipliers"].as_array().unwrap() {
        assert!(m["re"].as_f64().unwrap().hypot(m["im"].as_f64().unwrap()) < 1.0);
    }
    // the period is the two strides together
    let sp: f64 = f["stride_periods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .sum();
    assert!((f["period"].as_f64().unwrap() - sp).abs() < 1e-12);
    // text output lists both points
    let o = run(&[
        "fixedpoint",
        "--slope",
        "0.016",
        "--period",
        "2",
        "--gait",
        "stable",
    ]);
    let t = String::from_utf8_lossy(&o.stdout);
    assert!(
        t.contains("period-2 orbit") && t.contains("\n  1 ") && t.contains("\n  2 "),
        "{t}"
    );
    // period one keeps its output and gains period_k and orbit
    let o = run(&["fixedpoint", "--json", "--gait", "stable"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let f = &v["fixed_points"][0];
    assert_eq!(f["period_k"], 1);
    assert_eq!(f["orbit"][0], f["section"]);
    // bad periods are refused
    for bad in ["0", "65"] {
        let o = run(&["fixedpoint", "--period", bad]);
        assert_eq!(o.status.code(), Some(2));
        assert!(stderr(&o).contains("--period"), "{}", stderr(&o));
    }
}

/// The default basin (simplest walker, γ = 0.009, 200 × 200 cells, 100 strides) against the
/// same grid at DOP853 1e-14. At `--rtol 1e-10` every label agrees. At the default 1e-9 a
/// cell may differ only on a boundary of the reference's basins — a reference 8-neighbour
/// carries the label the default gave it — and only a few do: cells whose strides wander near
/// the boundary of the gait's basin for tens of strides (transient chaos) before they settle,
/// where a change at the 1e-9 level decides the side. When this was written one cell of 40 000
/// differed (θ = 0.1769, θ̇ = −0.1835: a forward fall after 21 strides at 1e-9, the gait after
/// 42 at 1e-10 … 1e-14).
#[test]
fn default_basin_labels_against_a_dop853_1e14_reference() {
    let dir = tempfile::tempdir().unwrap();
    let labels = |name: &str, extra: &[&str]| {
        let out = p(dir.path(), name);
        let o = bin()
            .args(["basin", "--grid", "200x200", "--quiet", "--out", s(&out)])
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        read(&out).outcome
    };
    let reference = labels("ref.h5", &["--rtol", "1e-14"]);
    let tight = labels("tight.h5", &["--rtol", "1e-10"]);
    assert_eq!(tight, reference, "DOP853 1e-10 against 1e-14");
    let dflt = labels("default.h5", &[]);
    let (ny, nx) = reference.dim();
    let mut differ = 0;
    for ((r, c), &v) in dflt.indexed_iter() {
        if v == reference[[r, c]] {
            continue;
        }
        differ += 1;
        let on_boundary = (r.saturating_sub(1)..=(r + 1).min(ny - 1)).any(|rr| {
            (c.saturating_sub(1)..=(c + 1).min(nx - 1)).any(|cc| reference[[rr, cc]] == v)
        });
        assert!(
            on_boundary,
            "cell (row {r}, column {c}): label {v} at 1e-9, {} at 1e-14, and no neighbour \
             labelled {v} at 1e-14",
            reference[[r, c]]
        );
    }
    // At most 0.01 % of the cells.
    assert!(differ <= nx * ny / 10_000, "{differ} cells differ");
}

/// `fixedpoint --json`'s validity: the old keys kept, the dense-solution keys added and
/// consistent — every relative margin is raw / scale, the binding one is the smallest, the
/// simplest walker keeps the mid-stance convention with its scuff reported.
#[test]
fn fixedpoint_json_validity_margins_are_consistent() {
    let o = run(&["fixedpoint", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let v = &j["fixed_points"][0]["validity"];
    for k in [
        "valid",
        "min_normal_force",
        "max_friction_required",
        "min_knee_torque",
        "normal_force_negative",
        "knee_unlocks",
        "swing_foot_scuffs",
        "impact_violation",
        "margins",
        "binding",
        "min_relative_margin",
        "clearance_rule",
        "scuff_depth",
        "impacts",
        "violations",
    ] {
        assert!(v.get(k).is_some(), "validity has no {k}: {v}");
    }
    assert_eq!(v["valid"], true);
    assert_eq!(v["clearance_rule"], "after_mid_stance");
    let scuff = v["scuff_depth"].as_f64().unwrap();
    assert!(scuff > 1e-5 && scuff < 1e-3, "mid-stance scuff {scuff} l");
    let margins = v["margins"].as_array().unwrap();
    let mut smallest = (f64::INFINITY, String::new());
    for m in margins {
        let (raw, scale, rel) = (
            m["raw"].as_f64().unwrap(),
            m["scale"].as_f64().unwrap(),
            m["relative"].as_f64().unwrap(),
        );
        assert_eq!(rel, raw / scale, "{m}");
        // the simplest walker's own units: relative = raw
        assert_eq!(scale, 1.0, "{m}");
        if rel < smallest.0 {
            smallest = (rel, m["name"].as_str().unwrap().to_string());
        }
    }
    assert_eq!(v["binding"], smallest.1.as_str());
    assert_eq!(v["min_relative_margin"].as_f64().unwrap(), smallest.0);
    let nf = margins
        .iter()
        .find(|m| m["name"] == "normal_force")
        .unwrap();
    assert_eq!(nf["raw"], v["min_normal_force"]);
    // the heel strike's impulses: pushing, the trailing foot separating
    let imp = &v["impacts"][0];
    assert_eq!(imp["event"], "heel_strike");
    assert_eq!(imp["checked"], true);
    assert!(imp["min_margin"].as_f64().unwrap() > 0.0, "{imp}");
}

/// Ctrl-C during the gait search stops it at once (every integration polls the stop request):
/// the seed's walker with a free swing knee searches for about 40 s from its two guesses and
/// finds no gait; a SIGINT sent as the search starts ends the run with 130, "nothing written",
/// and no file, long before the search would have ended (measured: 5–21 ms after the signal).
#[test]
fn ctrl_c_during_the_gait_search_stops_it_at_once() {
    use std::io::{BufRead, BufReader};
    let dir = tempfile::tempdir().unwrap();
    let out = p(dir.path(), "s5.h5");
    let mut child = bin()
        .args([
            "basin",
            "--model",
            "seed5",
            "--set",
            "free_swing_knee=1",
            "--grid",
            "21x21",
            "--out",
            s(&out),
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    let mut seen = String::new();
    while err.read_line(&mut line).unwrap() > 0 {
        seen.push_str(&line);
        if line.starts_with("finding the period-one gaits") {
            break;
        }
        line.clear();
    }
    assert!(seen.contains("finding the period-one gaits"), "{seen}");
    let t0 = std::time::Instant::now();
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success(), "the run was still there to signal");
    let status = child.wait().unwrap();
    let latency = t0.elapsed().as_secs_f64();
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut err, &mut rest).unwrap();
    assert_eq!(status.code(), Some(130), "{seen}{rest}");
    assert!(rest.contains("nothing written"), "{rest}");
    assert!(
        !out.exists(),
        "no file is left by a run stopped before its grid"
    );
    // The uninterrupted search takes ~40 s; ten seconds leaves room for any load on the machine.
    assert!(latency < 10.0, "exited {latency:.1} s after the signal");
}

/// A basin's attractors carry their physical validity (console, file), and the verdict agrees
/// with an independent computation: the knee-lock torque and normal force `simulate` samples
/// along one stride of the same gait (forces at output samples, not the dense location the
/// basin's check uses). The kneed preset at slope 0.051 needs its stance-knee lock to pull;
/// the compass gait at its default slope needs nothing the ground cannot give.
#[test]
fn basin_names_a_physically_invalid_gait_as_its_trajectory_shows() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (model, slope, invalid) in [("kneed", "0.051", true), ("compass", "3deg", false)] {
        let out = p(d, &format!("{model}.h5"));
        let o = run(&[
            "basin",
            "--model",
            model,
            "--slope",
            slope,
            "--grid",
            "9x9",
            "--out",
            s(&out),
            "--png",
            s(&p(d, &format!("{model}.png"))),
            "--quiet",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        let gait = pdw::store::read_basin(&out).unwrap().attractors[0].clone();
        assert_eq!(gait.name, "gait");
        let traj = p(d, &format!("{model}_t.h5"));
        let o = run(&[
            "simulate",
            "--model",
            model,
            "--slope",
            slope,
            "--steps",
            "1",
            "--dt-out",
            "0.002",
            "--out",
            s(&traj),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let tr = pdw::store::read_trajectory_h5(&traj).unwrap();
        let min = |name: &str| {
            tr.column(name)
                .unwrap()
                .values
                .iter()
                .copied()
                .filter(|v| !v.is_nan())
                .fold(f64::INFINITY, f64::min)
        };
        let pulls = min("knee_torque") < 0.0 || min("normal_force") < 0.0;
        assert_eq!(
            pulls, invalid,
            "{model}: sampled forces disagree with the verdict"
        );
        if invalid {
            let reasons = gait.validity.reasons().expect("an invalid gait");
            assert!(
                reasons.iter().any(|r| r == "a knee lock must pull"),
                "{reasons:?}"
            );
            assert!(
                text.contains("(physically invalid: a knee lock must pull"),
                "{text}"
            );
        } else {
            assert_eq!(gait.validity, pdw::store::OrbitCheck::Valid);
            assert!(!text.contains("physically invalid"), "{text}");
        }
    }
}
