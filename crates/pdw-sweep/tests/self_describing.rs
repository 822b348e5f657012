//! Every file the CLI writes describes itself: a `units` attribute on every dataset,
//! provenance (build, host, command, every numerical option), the basin's slice, dimension
//! scales on the grid, the fill value in the legend; a merged basin keeps each shard's command.
//! Attributes are read back with the hdf5 crate.

use crate::common;
use crate::common::run;
use common::*;
use hdf5::types::{FixedAscii, VarLenUnicode};
use std::path::Path;
use std::process::{Command, Output};

fn ok(args: &[&str]) -> Output {
    let o = run(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn attr_str(loc: &hdf5::Location, name: &str) -> String {
    loc.attr(name)
        .unwrap_or_else(|_| panic!("attribute {name}"))
        .read_scalar::<VarLenUnicode>()
        .unwrap()
        .as_str()
        .to_string()
}

/// Every dataset of the file and its `units` (panics naming a dataset without one).
fn units_of_every_dataset(f: &hdf5::File) -> Vec<(String, String)> {
    fn walk(g: &hdf5::Group, prefix: &str, out: &mut Vec<(String, String)>) {
        for n in g.member_names().unwrap() {
            let full = if prefix.is_empty() {
                n.clone()
            } else {
                format!("{prefix}/{n}")
            };
            if let Ok(sub) = g.group(&n) {
                walk(&sub, &full, out);
            } else if let Ok(d) = g.dataset(&n) {
                assert!(
                    d.attr_names().unwrap().iter().any(|a| a == "units"),
                    "dataset /{full} has no units"
                );
                out.push((full, attr_str(&d, "units")));
            }
        }
    }
    let mut out = Vec::new();
    walk(f, "", &mut out);
    assert!(!out.is_empty());
    out
}

fn unit<'a>(all: &'a [(String, String)], ds: &str) -> &'a str {
    &all.iter()
        .find(|(n, _)| n == ds)
        .unwrap_or_else(|| panic!("no dataset {ds}"))
        .1
}

/// The provenance group holds this build's facts and the run's command and options.
fn check_provenance(f: &hdf5::File, command_has: &str) -> serde_json::Value {
    let p = f.group("provenance").expect("/provenance");
    assert_eq!(attr_str(&p, "crate_version"), env!("CARGO_PKG_VERSION"));
    let commit = attr_str(&p, "git_commit");
    // The commit of this checkout when git is available (the build read the same repository).
    if let Ok(o) = Command::new("git").args(["rev-parse", "HEAD"]).output() {
        if o.status.success() {
            let head = String::from_utf8_lossy(&o.stdout).trim().to_string();
            assert!(commit.starts_with(&head[..12]), "{commit} vs HEAD {head}");
        }
    }
    let profile = attr_str(&p, "build_profile");
    assert_eq!(
        profile,
        if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        }
    );
    // The path the run chose (this process would choose the same on this CPU) and the contract.
    assert_eq!(attr_str(&p, "simd_path"), pdw::simd::path().name());
    assert_eq!(attr_str(&p, "numerics"), pdw::simd::NUMERICS);
    assert!(!attr_str(&p, "host").is_empty());
    assert!(attr_str(&p, "command").contains(command_has));
    assert!(!attr_str(&p, "created").is_empty());
    serde_json::from_str(&attr_str(&p, "options")).expect("options are JSON")
}

fn read_fixed_class(d: &hdf5::Dataset) -> String {
    d.attr("CLASS")
        .unwrap()
        .read_scalar::<FixedAscii<16>>()
        .unwrap()
        .as_str()
        .to_string()
}

#[test]
fn basin_file_carries_units_slice_scales_provenance_and_the_fill_value() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c.h5");
    let o = out.to_str().unwrap();
    ok(&[
        "basin", "--model", "compass", "--grid", "16x16", "--quiet", "--rtol", "1e-10", "--out", o,
    ]);
    let f = h5_open(&out).unwrap();
    let units = units_of_every_dataset(&f);
    assert_eq!(unit(&units, "grid/x"), "rad");
    assert_eq!(unit(&units, "grid/y"), "rad/s");
    assert_eq!(unit(&units, "basin/outcome"), "1");
    assert_eq!(unit(&units, "basin/final"), r#"["rad","rad/s","rad/s"]"#);
    assert_eq!(
        unit(&units, "attractors/gait/section"),
        r#"["rad","rad/s","rad/s"]"#
    );
    let opts = check_provenance(&f, "basin");
    assert_eq!(opts["integrator"]["method"], "dop853");
    assert_eq!(opts["integrator"]["rtol"], 1e-10);
    assert_eq!(opts["integrator"]["atol"], 1e-10);
    assert_eq!(opts["integrator"]["warm_restart"], true);
    assert_eq!(opts["max_strides"], 100);
    // The header's integrator agrees with the provenance.
    assert_eq!(
        attr_str(&f, "integrator"),
        "dop853 rtol=1e-10 atol=1e-10 warm-restart"
    );

    // --cold-restarts: the same basin with every segment started cold, recorded as such.
    let cold = dir.path().join("cold.h5");
    ok(&[
        "basin",
        "--model",
        "compass",
        "--grid",
        "16x16",
        "--quiet",
        "--rtol",
        "1e-10",
        "--cold-restarts",
        "--out",
        cold.to_str().unwrap(),
    ]);
    let fc = h5_open(&cold).unwrap();
    let opts_cold = check_provenance(&fc, "basin");
    assert!(opts_cold["integrator"].get("warm_restart").is_none());
    assert_eq!(attr_str(&fc, "integrator"), "dop853 rtol=1e-10 atol=1e-10");

    // The slice: hip_rate held at the gait's value (defaulted), the gait on the slice.
    let fp: serde_json::Value = serde_json::from_slice(
        &ok(&[
            "fixedpoint",
            "--model",
            "compass",
            "--gait",
            "stable",
            "--json",
        ])
        .stdout,
    )
    .unwrap();
    let hip_rate = fp["fixed_points"][0]["section"][2].as_f64().unwrap();
    let s = f.group("slice").unwrap();
    assert_eq!(attr_str(&s, "x"), "stance");
    assert_eq!(attr_str(&s, "y"), "stance_rate");
    let v: f64 = s.attr("hip_rate").unwrap().read_scalar().unwrap();
    assert!((v - hip_rate).abs() < 1e-12, "{v} vs {hip_rate}");
    let fixed: serde_json::Value = serde_json::from_str(&attr_str(&s, "fixed")).unwrap();
    assert_eq!(fixed["hip_rate"]["source"], "fixed point");
    assert_eq!(fixed["hip_rate"]["unit"], "rad/s");
    assert!(s
        .attr("on_fixed_point")
        .unwrap()
        .read_scalar::<bool>()
        .unwrap());

    // The legend names the fill value.
    let legend: serde_json::Value =
        serde_json::from_str(&attr_str(&f.dataset("basin/outcome").unwrap(), "legend")).unwrap();
    assert_eq!(legend["255"], "not_computed");
    assert_eq!(legend["0"], "gait");
    assert!(attr_str(&f.dataset("basin/final").unwrap(), "description").contains("fall"));

    // Dimension scales: /grid/x, /grid/y are scales named after their coordinates, attached
    // to dimensions 1 and 0 of the three grid datasets.
    for (scale, coord) in [("grid/x", "stance"), ("grid/y", "stance_rate")] {
        let d = f.dataset(scale).unwrap();
        assert_eq!(read_fixed_class(&d), "DIMENSION_SCALE");
        let name = d
            .attr("NAME")
            .unwrap()
            .read_scalar::<FixedAscii<32>>()
            .unwrap();
        assert_eq!(name.as_str(), coord);
        assert_eq!(d.attr("REFERENCE_LIST").unwrap().shape(), vec![3]);
    }
    for (ds, rank) in [
        ("basin/outcome", 2),
        ("basin/strides", 2),
        ("basin/final", 3),
    ] {
        let d = f.dataset(ds).unwrap();
        assert_eq!(
            d.attr("DIMENSION_LIST").unwrap().shape(),
            vec![rank],
            "{ds}"
        );
    }
    drop(f);

    // A coordinate set off the gait: the slice says so, and the file is still complete.
    let off = dir.path().join("off.h5");
    ok(&[
        "basin",
        "--model",
        "compass",
        "--grid",
        "8x8",
        "--quiet",
        "--set",
        "hip_rate=0.6",
        "--out",
        off.to_str().unwrap(),
    ]);
    let f = h5_open(&off).unwrap();
    let s = f.group("slice").unwrap();
    let v: f64 = s.attr("hip_rate").unwrap().read_scalar().unwrap();
    assert_eq!(v, 0.6);
    let fixed: serde_json::Value = serde_json::from_str(&attr_str(&s, "fixed")).unwrap();
    assert_eq!(fixed["hip_rate"]["source"], "--set");
    assert!(!s
        .attr("on_fixed_point")
        .unwrap()
        .read_scalar::<bool>()
        .unwrap());
}

#[test]
fn simplest_walker_files_are_in_leg_units_and_merged_shards_keep_their_commands() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n);
    for i in 0..2 {
        ok(&[
            "basin",
            "--grid",
            "20x20",
            "--quiet",
            "--shard",
            &format!("{i}/2"),
            "--out",
            p(&format!("s{i}.h5")).to_str().unwrap(),
        ]);
    }
    let merged = p("m.h5");
    ok(&[
        "merge",
        p("s0.h5").to_str().unwrap(),
        p("s1.h5").to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    let f = h5_open(&merged).unwrap();
    let units = units_of_every_dataset(&f);
    assert_eq!(unit(&units, "grid/x"), "rad");
    assert_eq!(unit(&units, "grid/y"), "rad/sqrt(l/g)");
    check_provenance(&f, "merge");
    let shards = f.group("provenance/shards").unwrap();
    for i in 0..2 {
        let g = shards.group(&format!("{i:03}")).unwrap();
        assert!(attr_str(&g, "command").contains(&format!("--shard {i}/2")));
        assert!(attr_str(&g, "file").ends_with(&format!("s{i}.h5")));
        assert!(attr_str(&g, "options").contains("\"integrator\""));
    }
    // The simplest walker's section has just the two axes: an empty slice, the gait on it.
    let s = f.group("slice").unwrap();
    assert_eq!(attr_str(&s, "fixed"), "{}");
    assert!(s
        .attr("on_fixed_point")
        .unwrap()
        .read_scalar::<bool>()
        .unwrap());
    assert_eq!(
        f.dataset("basin/outcome")
            .unwrap()
            .attr("DIMENSION_LIST")
            .unwrap()
            .shape(),
        vec![2]
    );
}

#[test]
fn sweep_and_trajectory_files_carry_units_and_every_numerical_option() {
    let dir = tempfile::tempdir().unwrap();
    let bif = dir.path().join("bif.h5");
    ok(&[
        "fixedpoint",
        "--sweep",
        "slope=0.005:0.012:4",
        "--out",
        bif.to_str().unwrap(),
    ]);
    let f = h5_open(&bif).unwrap();
    let units = units_of_every_dataset(&f);
    assert_eq!(unit(&units, "branches/000/parameter"), "rad");
    assert_eq!(
        unit(&units, "branches/000/section"),
        r#"["rad","rad/sqrt(l/g)"]"#
    );
    assert_eq!(unit(&units, "orbit/points"), "rad");
    let opts = check_provenance(&f, "--sweep");
    assert_eq!(opts["orbit_diagram"]["transient"], 300);
    assert_eq!(opts["orbit_diagram"]["record"], 64);
    assert_eq!(opts["continuation"]["integrator"]["method"], "dop853");
    assert!(opts["continuation"]["ds_max"].as_f64().unwrap() > 0.0);
    drop(f);

    let traj = dir.path().join("t.h5");
    ok(&[
        "simulate",
        "--model",
        "compass",
        "--steps",
        "2",
        "--integrator",
        "dopri5",
        "--rtol",
        "1e-9",
        "--out",
        traj.to_str().unwrap(),
    ]);
    let f = h5_open(&traj).unwrap();
    let units = units_of_every_dataset(&f);
    assert_eq!(unit(&units, "t"), "s");
    assert_eq!(unit(&units, "stance_rate"), "rad/s");
    assert!(unit(&units, "events/pre").starts_with(r#"["rad""#));
    let opts = check_provenance(&f, "simulate");
    assert_eq!(opts["integrator"]["method"], "dopri5");
    assert_eq!(opts["integrator"]["rtol"], 1e-9);

    let csv = dir.path().join("t.csv");
    ok(&["simulate", "--steps", "1", "--out", csv.to_str().unwrap()]);
    let text = std::fs::read_to_string(&csv).unwrap();
    for key in [
        "# git_commit: ",
        "# build_profile: ",
        "# simd_path: ",
        "# host: ",
        "# options: ",
    ] {
        assert!(text.contains(key), "{key} missing from the CSV header");
    }
    assert!(Path::new(&csv).exists());
}

#[test]
fn merge_accepts_shards_from_any_simd_path_and_refuses_other_builds_unless_forced() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    // Shard 0 on the baseline path, shard 1 on the best one: one build, the same bits.
    for (i, path) in [(0, "baseline"), (1, pdw::simd::best_path().name())] {
        let o = Command::new(env!("CARGO_BIN_EXE_pdw-sweep"))
            .env("PDW_SIMD", path)
            .args(["basin", "--grid", "16x16", "--quiet", "--shard"])
            .arg(format!("{i}/2"))
            .args(["--out", &p(&format!("s{i}.h5"))])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let f = h5_open(p(&format!("s{i}.h5"))).unwrap();
        assert_eq!(attr_str(&f.group("provenance").unwrap(), "simd_path"), path);
    }
    ok(&["merge", &p("s0.h5"), &p("s1.h5"), "--out", &p("m.h5")]);
    // The same grid in one run equals the merged shards.
    ok(&["basin", "--grid", "16x16", "--quiet", "--out", &p("one.h5")]);
    let read = |f: &str| {
        h5_open(p(f))
            .unwrap()
            .dataset("basin/outcome")
            .unwrap()
            .read_raw::<u8>()
            .unwrap()
    };
    assert_eq!(read("m.h5"), read("one.h5"));
    // Shard 1 claims another commit: refused, naming both; --force joins them with a warning.
    {
        let f = h5_open_rw(p("s1.h5")).unwrap();
        let g = f.group("provenance").unwrap();
        g.delete_attr("git_commit").unwrap();
        let v: VarLenUnicode = "0123456789abcdef".parse().unwrap();
        g.new_attr::<VarLenUnicode>()
            .create("git_commit")
            .unwrap()
            .write_scalar(&v)
            .unwrap();
    }
    let o = run(&["merge", &p("s0.h5"), &p("s1.h5"), "--out", &p("m2.h5")]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("different builds") && err.contains("0123456789abcdef"),
        "{err}"
    );
    assert!(!Path::new(&p("m2.h5")).exists());
    let o = ok(&[
        "merge",
        &p("s0.h5"),
        &p("s1.h5"),
        "--out",
        &p("m2.h5"),
        "--force",
    ]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("different builds"));
}

/// A design search's file: units on every dataset (the compass in SI, Goswami et al. 1998's
/// kg, m, s), the provenance with the search's settings, and the commands of every run that
/// wrote it (a continued search lists the first run, then its own).
#[test]
fn design_file_carries_units_and_the_commands_of_every_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("design.h5");
    let search = |budget: &str| {
        let o = run(&[
            "design",
            "--model",
            "compass",
            "--free",
            "hip_mass=8:12",
            "--objective",
            "margin",
            "--budget",
            budget,
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ]);
        // exit 0 with a feasible best, 1 without: either is a completed search
        assert!(
            matches!(o.status.code(), Some(0 | 1)),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
    };
    search("2");
    search("3");
    let f = h5_open(&out).unwrap();
    let units = units_of_every_dataset(&f);
    assert_eq!(unit(&units, "params"), r#"["kg"]"#);
    assert_eq!(unit(&units, "section"), r#"["rad","rad/s","rad/s"]"#);
    assert_eq!(unit(&units, "min_normal_force"), "N");
    assert_eq!(unit(&units, "min_knee_torque"), "N m");
    assert_eq!(unit(&units, "period"), "s");
    assert_eq!(unit(&units, "step_length"), "m");
    for ds in ["cost", "rho", "basin_fraction", "max_friction", "status"] {
        assert_eq!(unit(&units, ds), "1", "{ds}");
    }
    let opts = check_provenance(&f, "--budget 3");
    assert_eq!(opts["objective"], "margin");
    assert_eq!(opts["mu"], 0.6);
    assert_eq!(opts["threads"], 2);
    let p = f.group("provenance").unwrap();
    let commands: Vec<String> = serde_json::from_str(&attr_str(&p, "commands")).unwrap();
    assert_eq!(commands.len(), 2, "{commands:?}");
    assert!(commands[0].contains("--budget 2") && commands[1].contains("--budget 3"));
    assert_eq!(
        pdw::store::read_design(&out, &["cost"])
            .unwrap()
            .params
            .len(),
        3
    );
}

/// Basin and sweep files say what the model's coordinates mean (the `coordinates` root
/// attribute, state name → meaning, as trajectory files): the compass's `stance` is its stance
/// leg's angle from the slope normal.
#[test]
fn basin_and_sweep_files_name_the_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    ok(&[
        "basin",
        "--model",
        "compass",
        "--grid",
        "4x4",
        "--quiet",
        "--out",
        &p("b.h5"),
    ]);
    ok(&[
        "fixedpoint",
        "--model",
        "compass",
        "--sweep",
        "slope=0.05:0.052:2",
        "--out",
        &p("s.h5"),
    ]);
    for file in ["b.h5", "s.h5"] {
        let f = h5_open(Path::new(&p(file))).unwrap();
        let c: serde_json::Value = serde_json::from_str(&attr_str(&f, "coordinates")).unwrap();
        let stance = c["stance"].as_str().unwrap_or_default();
        assert!(
            stance.contains("stance leg") && stance.contains("slope normal"),
            "{file}: {c}"
        );
        assert!(c["hip_rate"].as_str().is_some(), "{file}: {c}");
    }
}
