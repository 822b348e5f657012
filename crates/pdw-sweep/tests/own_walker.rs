//! A user's own walker rebuilt anywhere: every file records the resolved spec of its chain
//! walker (`/provenance/model_spec`), so the explorer, `animate --from` and `merge` rebuild it
//! after the spec file is gone and from another folder (before, the explorer answered "unknown
//! model `mk2`").

use pdw_explore::source::{self, Window};
use std::path::Path;
use std::process::{Command, Output};

/// Runs pdw-sweep in `dir`.
fn run_in(dir: &Path, args: &[&str]) -> Output {
    let o = Command::new(env!("CARGO_BIN_EXE_pdw-sweep"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("the binary runs");
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

#[test]
fn files_of_a_users_own_walker_rebuild_it_without_its_spec_file() {
    let home = tempfile::tempdir().unwrap();
    let elsewhere = tempfile::tempdir().unwrap();
    let d = home.path();
    // the compass preset, renamed and with another hip mass: a model no registry knows
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/compass.toml"
    ))
    .unwrap()
    .replacen("name = \"compass\"", "name = \"mk2\"", 1);
    assert!(text.contains("name = \"mk2\""));
    std::fs::write(d.join("mk2.toml"), &text).unwrap();
    run_in(
        d,
        &[
            "basin", "--quiet", "--model", "mk2.toml", "--grid", "12x12", "--out", "b.h5",
        ],
    );
    run_in(
        d,
        &[
            "basin", "--quiet", "--model", "mk2.toml", "--grid", "12x12", "--shard", "0/2",
            "--out", "s0.h5",
        ],
    );
    run_in(
        d,
        &[
            "basin", "--quiet", "--model", "mk2.toml", "--grid", "12x12", "--shard", "1/2",
            "--out", "s1.h5",
        ],
    );
    run_in(
        d,
        &[
            "simulate", "--model", "mk2.toml", "--steps", "3", "--out", "t.h5",
        ],
    );
    run_in(
        d,
        &[
            "fixedpoint",
            "--model",
            "mk2.toml",
            "--sweep",
            "slope=0.05:0.06:3",
            "--out",
            "sw.h5",
        ],
    );
    std::fs::remove_file(d.join("mk2.toml")).unwrap();
    // every file names the spec's model and records its resolved spec
    for f in ["b.h5", "t.h5", "sw.h5"] {
        let spec = pdw::store::provenance::read_model_spec(&d.join(f)).unwrap();
        assert!(
            spec.is_some_and(|s| s.contains("mk2")),
            "{f} records no spec"
        );
    }
    // merge, run elsewhere: the merged file keeps the shards' spec
    let (s0, s1, m) = (d.join("s0.h5"), d.join("s1.h5"), d.join("m.h5"));
    run_in(
        elsewhere.path(),
        &[
            "merge",
            s0.to_str().unwrap(),
            s1.to_str().unwrap(),
            "--out",
            m.to_str().unwrap(),
        ],
    );
    // the explorer rebuilds the basin's run (and reproduces its grid and legend) from another
    // folder, with no spec file anywhere; likewise the merged file
    // (the explorer does not rebuild a merged file's run: merge records no integrator)
    assert_eq!(
        pdw::store::provenance::read_model_spec(&m).unwrap(),
        pdw::store::provenance::read_model_spec(&s0).unwrap()
    );
    {
        let f = d.join("b.h5");
        let src = source::load(&f).unwrap();
        assert_eq!(src.data.header.model, "mk2");
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let w = Window {
            bounds: None,
            grid: None,
            z_fixed: None,
            overrides: Vec::new(),
        };
        let r = source::rebuild(&src, &w, &pool)
            .unwrap_or_else(|e| panic!("{}: {}", f.display(), e.message));
        source::check_same_run(&src, &r).unwrap_or_else(|e| panic!("{}", e.message));
        assert_eq!(r.m.info.name, "mk2");
    }
    // a sweep point's gait walks
    let sw = pdw::store::read_sweep(d.join("sw.h5")).unwrap();
    let spec = pdw::store::provenance::read_model_spec(&d.join("sw.h5")).unwrap();
    pdw_explore::sweep::gait(&sw, spec.as_deref(), 0, 1)
        .unwrap_or_else(|e| panic!("{}", e.message));
    // the trajectory animates
    let t = d.join("t.h5");
    run_in(
        elsewhere.path(),
        &["animate", "--from", t.to_str().unwrap(), "--out", "t.gif"],
    );
}
