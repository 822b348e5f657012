//! `pdw-sweep design` end to end: a seeded search is reproducible, an interrupted search
//! continued on its file gives the uninterrupted run's designs bit for bit, and bad input is
//! refused with exit code 2 naming the value.

use crate::common::{run, stderr};
use std::path::Path;
use std::process::Output;

const COLS: [&str; 3] = ["cost", "rho", "min_knee_torque"];

fn search(out: &Path, budget: &str, seed: &str) -> Output {
    run(&[
        "design",
        "--model",
        "kneed",
        "--free",
        "hip_mass=0.3:1.2",
        "--free",
        "a2=0.12:0.22",
        "--objective",
        "margin",
        "--budget",
        budget,
        "--seed",
        seed,
        "--init",
        "3",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ])
}

fn bits(d: &pdw::store::DesignData) -> Vec<u64> {
    let mut v: Vec<u64> = d.params.iter().flatten().map(|x| x.to_bits()).collect();
    for c in COLS {
        v.extend(d.column(c).unwrap().iter().map(|x| x.to_bits()));
    }
    v.extend(d.status.iter().map(|s| *s as u64));
    v
}

#[test]
fn seeded_search_is_reproducible_and_resumes_to_the_same_designs() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b, c) = (
        dir.path().join("a.h5"),
        dir.path().join("b.h5"),
        dir.path().join("c.h5"),
    );
    // exit 0 with a feasible best, 1 without: either is a completed search
    let o = search(&a, "14", "7");
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    let o = search(&b, "14", "7");
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    let (da, db) = (
        pdw::store::read_design(&a, &COLS).unwrap(),
        pdw::store::read_design(&b, &COLS).unwrap(),
    );
    assert_eq!(da.params.len(), 14);
    assert_eq!(bits(&da), bits(&db), "same seed, same designs");
    // interrupted after 6 designs, continued to 14 on the same file
    let o = search(&c, "6", "7");
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    assert_eq!(pdw::store::read_design(&c, &COLS).unwrap().params.len(), 6);
    let o = search(&c, "14", "7");
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("(8 new)"));
    let dc = pdw::store::read_design(&c, &COLS).unwrap();
    assert_eq!(bits(&da), bits(&dc), "resumed run = uninterrupted run");
    // every design found a gait (the kneed walker walks across these bounds) and the knee
    // torque is measured along the stride
    assert!(da
        .column("rho")
        .unwrap()
        .iter()
        .all(|r| r.is_finite() && *r < 1.0));
    assert!(da
        .column("min_knee_torque")
        .unwrap()
        .iter()
        .all(|k| k.is_finite()));
    // another seed samples other initial designs (the first design is the model's own values)
    let d = dir.path().join("d.h5");
    let o = search(&d, "3", "8");
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    let dd = pdw::store::read_design(&d, &COLS).unwrap();
    assert_eq!(dd.params[0], da.params[0]);
    assert_ne!(dd.params[1], da.params[1]);
    // a rerun with other settings is refused, naming them
    let o = search(&c, "14", "9");
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("other settings"), "{}", stderr(&o));
}

#[test]
fn bad_design_arguments_exit_2_naming_the_value() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.h5");
    let o = out.to_str().unwrap();
    for (args, needle) in [
        (vec!["--free", "nope=0:1"], "nope"),
        (vec!["--free", "hip_mass=1:0.5"], "inverted"),
        (
            vec!["--free", "hip_mass=0.3:1", "--objective", "speed"],
            "speed",
        ),
        (vec!["--free", "hip_mass=0.3:1", "--mu", "-1"], "--mu"),
        (
            vec!["--free", "hip_mass=0.3:1", "--budget", "0"],
            "--budget",
        ),
        (vec!["--free", "hip_mass=-1:1"], "hip_mass"),
        (
            vec!["--free", "hip_mass=0.3:1", "--starts", "0"],
            "--starts",
        ),
        (
            vec!["--free", "hip_mass=0.3:1", "--set", "hip_mass=0.5"],
            "free or set",
        ),
        (vec![], "--free"),
    ] {
        let mut a = vec!["design", "--model", "kneed", "--quiet", "--out", o];
        a.extend(args.iter().copied());
        let r = run(&a);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {}", stderr(&r));
        assert!(stderr(&r).contains(needle), "{args:?}: {}", stderr(&r));
        assert!(!out.exists(), "{args:?}: nothing written on bad input");
    }
}

/// `--min-margin X` requires every validity criterion's relative margin to be at least X: the
/// compass at its defaults is feasible with the default 0 and rejected with 0.9 (its normal
/// force margin alone is 0.69 m g), the stored smallest relative margin below the requirement
/// and the reason naming the binding criterion.
#[test]
fn min_margin_rejects_a_design_below_it() {
    let dir = tempfile::tempdir().unwrap();
    let design = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec![
            "design",
            "--model",
            "compass",
            "--free",
            "hip_mass=9.5:10.5",
            "--objective",
            "margin",
            "--budget",
            "1",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        (run(&args), out)
    };
    let cols = ["min_relative_margin"];
    let (o, out) = design("zero.h5", &[]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let d = pdw::store::read_design(&out, &cols).unwrap();
    let m0 = d.column("min_relative_margin").unwrap()[0];
    assert!(m0 > 0.0 && m0 < 0.9, "smallest relative margin {m0}");
    assert_eq!(d.status[0], 0, "feasible");
    let (o, out) = design("high.h5", &["--min-margin", "0.9"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let d = pdw::store::read_design(&out, &cols).unwrap();
    assert_eq!(d.status[0], 1, "invalid");
    assert_eq!(d.column("min_relative_margin").unwrap()[0], m0);
    assert!(d.reasons[0].contains("min margin 0.9"), "{}", d.reasons[0]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("smallest relative margin"), "{stdout}");
    // a negative requirement is refused
    let (o, _) = design("neg.h5", &["--min-margin", "-0.1"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--min-margin"), "{}", stderr(&o));
}

#[test]
fn the_default_basin_box_follows_each_gait_and_is_not_saturated() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b.h5");
    let o = run(&[
        "design",
        "--model",
        "compass",
        "--free",
        "hip_mass=4:25",
        "--objective",
        "basin",
        "--budget",
        "6",
        "--init",
        "2",
        "--basin-grid",
        "11",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    let cols = [
        "basin_fraction",
        "basin_box_stance",
        "basin_box_stance_rate",
    ];
    let d = pdw::store::read_design(&out, &cols).unwrap();
    let frac = d.column("basin_fraction").unwrap();
    let (b0, b1) = (
        d.column("basin_box_stance").unwrap(),
        d.column("basin_box_stance_rate").unwrap(),
    );
    let mut measured = Vec::new();
    for i in 0..d.params.len() {
        if !frac[i].is_finite() {
            continue;
        }
        // the box stored is 0.15 of the gait's |stance| and |stance_rate|
        assert_eq!(b0[i], 0.15 * d.section[i][0].abs());
        assert_eq!(b1[i], 0.15 * d.section[i][1].abs());
        assert!(
            frac[i] <= 0.95,
            "design {i}: fraction {} fills the box",
            frac[i]
        );
        measured.push(frac[i]);
    }
    assert!(measured.len() >= 3, "{measured:?}");
    assert!(
        measured.iter().any(|f| (f - measured[0]).abs() > 0.0),
        "every design got the same fraction: {measured:?}"
    );
    // the units of the box are the section's
    let f = crate::common::h5_open(&out).unwrap();
    let u: String = f
        .dataset("basin_box_stance_rate")
        .unwrap()
        .attr("units")
        .unwrap()
        .read_scalar::<hdf5::types::VarLenUnicode>()
        .unwrap()
        .to_string();
    assert_eq!(u, "rad/s");
}

fn multi_start(out: &Path, budget: &str, threads: &str) -> Output {
    run(&[
        "design",
        "--model",
        "kneed",
        "--free",
        "hip_mass=0.3:1.2",
        "--free",
        "a2=0.12:0.22",
        "--objective",
        "margin",
        "--budget",
        budget,
        "--seed",
        "3",
        "--starts",
        "2",
        "--threads",
        threads,
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ])
}

/// The multi-start's two runs share the pool: the file is the same on one and two threads,
/// and a search continued from a shorter one's file is the uninterrupted search.
#[test]
fn a_multi_start_is_the_same_on_one_and_two_threads_and_after_a_resume() {
    let dir = tempfile::tempdir().unwrap();
    let path = |n: &str| dir.path().join(n);
    let ok = |o: &Output| assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(o));
    ok(&multi_start(&path("one.h5"), "8", "1"));
    ok(&multi_start(&path("two.h5"), "8", "2"));
    let cols = ["cost", "rho", "min_knee_torque", "run"];
    let read = |n: &str| pdw::store::read_design(path(n), &cols).unwrap();
    let (one, two) = (read("one.h5"), read("two.h5"));
    assert_eq!(one.params.len(), 8);
    let runs = one.column("run").unwrap();
    assert_eq!(runs.iter().filter(|r| **r == 0.0).count(), 4);
    assert_eq!(runs.iter().filter(|r| **r == 1.0).count(), 4);
    // run 1 starts elsewhere than the model's own values (run 0's first design)
    assert_ne!(one.params[0], one.params[4]);
    let bits4 = |d: &pdw::store::DesignData| {
        let mut v = bits(d);
        v.extend(d.column("run").unwrap().iter().map(|x| x.to_bits()));
        v
    };
    assert_eq!(
        bits4(&one),
        bits4(&two),
        "same designs on one and two threads"
    );
    ok(&multi_start(&path("resumed.h5"), "4", "2"));
    assert_eq!(read("resumed.h5").params.len(), 4);
    let o = multi_start(&path("resumed.h5"), "8", "2");
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stdout).contains("(4 new) from 2 starts"));
    assert_eq!(
        bits4(&one),
        bits4(&read("resumed.h5")),
        "resumed = uninterrupted"
    );
}

/// Hsu Chen's walker with push-only stops: its stance knee buckles at the knee strike, so the
/// gait search finds nothing, the design keeps how its guesses ended and is graded by its
/// latched twin. Checked against the
/// latched walker, an independent reading: its gait's knee strike needs the stance knee's latch
/// to pull (a negative margin), which a stop cannot.
#[test]
fn a_design_without_a_gait_keeps_its_fates_and_the_report_names_the_closest_design() {
    let dir = tempfile::tempdir().unwrap();
    let kneed = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/kneed.toml"
    ))
    .unwrap();
    assert!(kneed.contains("hold = \"latch\""));
    let spec = dir.path().join("stops.toml");
    std::fs::write(&spec, kneed.replace("hold = \"latch\"", "hold = \"stop\"")).unwrap();
    let out = dir.path().join("stops.h5");
    let o = run(&[
        "design",
        "--model",
        spec.to_str().unwrap(),
        "--free",
        "hip_mass=0.45:0.55",
        "--objective",
        "margin",
        "--budget",
        "1",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let d = pdw::store::read_design(&out, &["cost", "strides_survived"]).unwrap();
    assert_eq!(d.status[0], 3, "no gait: {}", d.reasons[0]);
    assert!(
        d.fates[0].contains("stance knee buckled"),
        "fates: {}",
        d.fates[0]
    );
    // graded by its latched twin (the same walker with ideal latches, models/kneed.toml): a
    // stable gait invalid by its latches' pull, so the cost lies in the band of a stable,
    // invalid gait, 1 + 3 δ/(1 + δ) + 0.5 ρ in [1, 4.5), not in the no-gait band [9, 10]
    let n = d.column("strides_survived").unwrap()[0];
    let c = d.column("cost").unwrap()[0];
    assert!((1.0..4.5).contains(&c) && n < 10.0, "cost {c}, strides {n}");
    assert!(
        d.reasons[0].contains("with ideal latches for its stops: invalid"),
        "{}",
        d.reasons[0]
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("no feasible design; closest"), "{stdout}");
    assert!(stdout.contains("stance knee buckled"), "{stdout}");
    assert!(
        !stderr(&o).contains("warning:"),
        "no bound warnings: {}",
        stderr(&o)
    );
    // the latched walker: its stance knee's latch pulls at the knee strike
    let fp = crate::common::json(&run(&["fixedpoint", "--model", "kneed", "--json"]));
    let margins = fp["fixed_points"][0]["validity"]["margins"]
        .as_array()
        .expect("margins");
    let pull = margins
        .iter()
        .find(|m| m["name"] == "knee_strike:stance_knee")
        .expect("the knee strike's stance knee entry");
    assert!(pull["raw"].as_f64().unwrap() < 0.0, "{pull}");
}

/// A scan that finds nothing says why, start by start: on the stop-only walker every start's
/// fate is named, the falls' fates add up to the starts that fell and all of them to the starts.
#[test]
fn a_scan_that_finds_nothing_reports_every_start_by_fate() {
    let dir = tempfile::tempdir().unwrap();
    let kneed = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/kneed.toml"
    ))
    .unwrap();
    let spec = dir.path().join("stops.toml");
    std::fs::write(&spec, kneed.replace("hold = \"latch\"", "hold = \"stop\"")).unwrap();
    let m = spec.to_str().unwrap();
    let o = run(&["fixedpoint", "--model", m, "--search", "32", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let scan = &v["scan"];
    let fates = scan["fates"].as_array().expect("fates");
    let count = |f: &serde_json::Value| f["starts"].as_u64().unwrap();
    assert_eq!(fates.iter().map(count).sum::<u64>(), 32, "{fates:?}");
    let fell: u64 = fates
        .iter()
        .filter(|f| {
            f["fate"] != "neither fell nor settled" && f["fate"] != "settled on a gait or orbit"
        })
        .map(count)
        .sum();
    assert_eq!(fell, scan["fell"].as_u64().unwrap());
    // most first
    assert!(fates.windows(2).all(|w| count(&w[0]) >= count(&w[1])));
    if v["fixed_points"].as_array().is_some_and(|f| f.is_empty()) {
        assert_eq!(o.status.code(), Some(2));
        assert!(
            stderr(&o).contains("by a scan (32 starts: "),
            "{}",
            stderr(&o)
        );
    }
}

/// `--json`: the report as one object whose counts and best design are those of the file, and
/// the text's lines carry the same values.
#[test]
fn the_json_report_is_the_file_s_search() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.h5"), dir.path().join("b.h5"));
    let args = |out: &Path, json: bool| {
        let mut v = vec![
            "design",
            "--model",
            "compass",
            "--free",
            "hip_mass=5:15",
            "--objective",
            "margin",
            "--budget",
            "4",
            "--quiet",
            "--out",
        ];
        v.push(out.to_str().unwrap());
        if json {
            v.push("--json");
        }
        v.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let (ja, tb) = (args(&a, true), args(&b, false));
    let o = run(&ja.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let d = pdw::store::read_design(&a, &COLS).unwrap();
    assert_eq!(j["designs"], d.params.len());
    assert_eq!(j["new"], d.params.len());
    let feasible = d.status.iter().filter(|&&s| s == 0).count();
    assert_eq!(j["counts"]["feasible"], feasible);
    let costs = d.column("cost").unwrap();
    let k = (0..costs.len())
        .min_by(|&x, &y| costs[x].total_cmp(&costs[y]))
        .unwrap();
    assert_eq!(j["best"]["index"], k);
    assert_eq!(j["best"]["cost"].as_f64().unwrap(), costs[k]);
    assert_eq!(
        j["best"]["params"]["hip_mass"].as_f64().unwrap(),
        d.params[k][0]
    );
    assert_eq!(o.status.code() == Some(0), j["best"]["feasible"] == true);
    // the text of the same search: its first line counts the same designs
    let o = run(&tb.iter().map(String::as_str).collect::<Vec<_>>());
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        text.starts_with(&format!(
            "4 designs (4 new) from 1 start: {feasible} feasible"
        )),
        "{text}"
    );
    assert!(
        text.contains(&format!("hip_mass = {}", d.params[k][0])),
        "{text}"
    );
}
