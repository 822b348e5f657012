//! The binary used as a hostile user would: nothing lost (outputs that would replace data or
//! inputs, concurrent runs on one file, a full disk), no crash, no false gait (level floor),
//! damaged files never reported complete, early and clear errors (exit 2, the bad value named,
//! no Rust Debug text).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pdw-sweep"))
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("the binary runs")
}

fn err(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn out(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A small basin run (48×40 cells, 40 strides) with `extra` arguments.
fn basin(out: &Path, extra: &[&str]) -> Output {
    basin_grid(out, "48x40", extra)
}

fn basin_grid(out: &Path, grid: &str, extra: &[&str]) -> Output {
    let mut a = vec![
        "basin",
        "--grid",
        grid,
        "--max-strides",
        "40",
        "--quiet",
        "--out",
        s(out),
    ];
    a.extend_from_slice(extra);
    run(&a)
}

/// Exit 2 with a message, and none of Rust's Debug renderings in it.
fn refused(o: &Output) -> String {
    let e = err(o);
    assert_eq!(o.status.code(), Some(2), "stderr: {e}\nstdout: {}", out(o));
    for debug in [
        "Custom {",
        "kind: ",
        "ImageError",
        "Os {",
        "Some(",
        "panicked",
    ] {
        assert!(!e.contains(debug), "Debug text {debug:?} in: {e}");
    }
    e
}

fn same_cells(a: &Path, b: &Path) {
    let (a, b) = (
        pdw::store::read_basin(a).unwrap(),
        pdw::store::read_basin(b).unwrap(),
    );
    assert_eq!(a.outcome, b.outcome);
    assert_eq!(a.strides, b.strides);
    let bits = |d: &pdw::store::BasinData| {
        d.final_state
            .iter()
            .map(|v| v.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&a), bits(&b));
}

#[test]
fn an_output_never_replaces_another_output_or_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // --out x.png: the picture would replace the data
    let o = basin(&d.join("x.png"), &[]);
    assert!(refused(&o).contains("same file"), "{}", err(&o));
    assert!(!d.join("x.png").exists(), "nothing written");
    // --out equal to --png
    let o = basin(&d.join("a.h5"), &["--png", s(&d.join("a.h5"))]);
    assert!(refused(&o).contains("same file"));
    assert!(!d.join("a.h5").exists());
    // fixedpoint --sweep with --out equal to --png
    let o = run(&[
        "fixedpoint",
        "--sweep",
        "slope=0.001:0.002:3",
        "--out",
        s(&d.join("b.png")),
    ]);
    assert!(refused(&o).contains("same file"));

    // merge: an output path that is one of the inputs (the picture beside --out)
    let mut shards: Vec<PathBuf> = Vec::new();
    for (i, name) in ["s0.h5", "s1.png"].iter().enumerate() {
        let p = d.join(name);
        let sh = format!("{i}/2");
        // written as HDF5 (the extension names the format), then renamed
        let o = basin(&p.with_extension("h5"), &["--shard", &sh]);
        assert!(o.status.success(), "{}", err(&o));
        if p.extension().is_some_and(|e| e == "png") {
            std::fs::rename(p.with_extension("h5"), &p).unwrap();
        }
        shards.push(p);
    }
    let before = std::fs::read(&shards[1]).unwrap();
    let o = run(&[
        "merge",
        s(&shards[0]),
        s(&shards[1]),
        "--out",
        s(&d.join("s1.h5x")),
        "--force",
    ]);
    assert!(refused(&o).contains("also an input"), "{}", err(&o));
    assert_eq!(std::fs::read(&shards[1]).unwrap(), before);
    assert!(!d.join("s1.h5x").exists());
    // merge refuses an existing picture without --force, and its message does not offer
    // --resume (merge has none)
    std::fs::write(d.join("m.png"), b"keep").unwrap();
    let o = run(&[
        "merge",
        s(&shards[0]),
        s(&shards[1]),
        "--out",
        s(&d.join("m.h5")),
    ]);
    let e = refused(&o);
    assert!(e.contains("--force") && !e.contains("--resume"), "{e}");
    assert_eq!(std::fs::read(d.join("m.png")).unwrap(), b"keep");

    // basin --resume of an unfinished file does not overwrite an existing picture
    let full = d.join("full.h5");
    assert!(basin(&full, &[]).status.success());
    let h = pdw::store::read_basin_header(&full).unwrap();
    let part = d.join("part.h5");
    pdw::store::BasinWriter::create(&part, &h, false)
        .unwrap()
        .close()
        .unwrap();
    std::fs::write(d.join("old.png"), b"keep").unwrap();
    let o = basin(&part, &["--resume", "--png", s(&d.join("old.png"))]);
    assert!(refused(&o).contains("--force"));
    assert_eq!(std::fs::read(d.join("old.png")).unwrap(), b"keep");
    // ... and resumes to the full result when the picture may be replaced
    let o = basin(
        &part,
        &["--resume", "--png", s(&d.join("old.png")), "--force"],
    );
    assert!(o.status.success(), "{}", err(&o));
    same_cells(&part, &full);
}

/// Flips `n` bytes at a pseudo-random offset (xorshift from `seed`) in the second half of the
/// file, where the data chunks are.
fn damage(p: &Path, seed: u64, n: usize) {
    let mut bytes = std::fs::read(p).unwrap();
    let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    let half = bytes.len() / 2;
    let at = half + (x as usize) % (bytes.len() - half - n);
    for b in &mut bytes[at..at + n] {
        *b ^= 0xA5;
    }
    std::fs::write(p, bytes).unwrap();
}

#[test]
fn resume_never_reports_a_damaged_file_complete() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full.h5");
    assert!(basin(&full, &[]).status.success());
    let mut repaired = 0;
    for seed in 1..=12u64 {
        let p = dir.path().join(format!("d{seed}.h5"));
        std::fs::copy(&full, &p).unwrap();
        damage(&p, seed, 32);
        let o = basin(&p, &["--resume", "--force"]);
        match o.status.code() {
            // success only with a file that reads back whole and equals the undamaged run
            Some(0) => {
                same_cells(&p, &full);
                assert!(pdw::store::read_basin(&p).unwrap().complete);
                if err(&o).contains("recomputing") {
                    repaired += 1;
                }
            }
            // or a refusal that says what is wrong
            Some(2) => {
                let e = refused(&o);
                assert!(e.contains(s(&p)), "seed {seed}: {e}");
            }
            other => panic!("seed {seed}: exit {other:?}: {}", err(&o)),
        }
    }
    assert!(repaired > 0, "no trial hit a data chunk");
}

#[test]
fn no_gait_on_a_level_floor() {
    // Every spelling of a level floor on the simplest walker; the compass once: its guesses fail
    // as the simplest walker's do, and the scan that follows costs ~40 s of one core (a start
    // of its 256 whose Newton strides run long: see the note on `pdw::limit::scan`).
    for (model, slopes) in [
        ("simplest", &["0", "-0", "1e-320"][..]),
        ("compass", &["0"][..]),
    ] {
        for &slope in slopes {
            let o = run(&["fixedpoint", "--model", model, "--slope", slope]);
            let e = refused(&o);
            assert!(
                e.contains("degenerate") && !out(&o).contains("stable gait"),
                "{model} at {slope}: {e}"
            );
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let o = basin(&dir.path().join("b.h5"), &["--slope", "0"]);
    assert!(refused(&o).contains("no period-one orbit found"));
}

#[test]
fn huge_grids_are_refused_before_any_allocation_with_the_estimate() {
    let dir = tempfile::tempdir().unwrap();
    let o = basin_grid(&dir.path().join("b.h5"), "1x1000000000", &[]);
    let e = err(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("GiB of memory"), "{e}");
    let o = basin_grid(&dir.path().join("b.h5"), "1000000000x1", &[]);
    let e = err(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("columns") || e.contains("memory"), "{e}");
    assert!(!dir.path().join("b.h5").exists());
}

#[test]
fn small_grid_entropy_is_not_defined_and_loose_tolerances_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let o = basin_grid(&dir.path().join("b.h5"), "4x4", &[]);
    assert!(o.status.success(), "{}", err(&o));
    assert!(out(&o).contains("not defined"), "{}", out(&o));
    let m = pdw::store::read_basin(dir.path().join("b.h5"))
        .unwrap()
        .metrics
        .unwrap();
    assert!(m.basin_entropy.is_nan() && m.boundary_entropy.is_nan());
    for tol in ["1", "0.01", "0"] {
        let o = run(&["fixedpoint", "--tol", tol]);
        assert!(refused(&o).contains("--tol"));
    }
}

#[test]
fn errors_name_the_flag_and_come_before_any_computation() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // negative numbers are values
    let o = run(&["fixedpoint", "--slope", "-0.009"]);
    assert!(!err(&o).contains("unexpected argument"), "{}", err(&o));
    let o = run(&["fixedpoint", "--guess", "-0.2,0.2", "--json"]);
    assert!(!err(&o).contains("unexpected argument"), "{}", err(&o));
    // the flag actually given is the one blamed
    let o = run(&["fixedpoint", "--set", "slope=2"]);
    assert!(refused(&o).contains("--set slope"), "{}", err(&o));
    let o = run(&["fixedpoint", "--sweep", "slope=0.001:2:10"]);
    assert!(refused(&o).contains("--sweep slope"), "{}", err(&o));
    let o = run(&["fixedpoint", "--sweep", "slope=0.001:0.002:100000000"]);
    assert!(refused(&o).contains("point count"), "{}", err(&o));
    let o = basin(&d.join("b.h5"), &["--x", "theta=-1e308:1e308"]);
    assert!(refused(&o).contains("-1e308:1e308"), "{}", err(&o));
    // a missing directory for the picture is found before the grid is computed
    let o = basin(&d.join("b.h5"), &["--png", s(&d.join("no/such/dir.png"))]);
    assert!(refused(&o).contains("does not exist"), "{}", err(&o));
    assert!(!d.join("b.h5").exists());
    // FIFOs and devices are not written or replaced, even with --force (no hang)
    let fifo = d.join("fifo.h5");
    let made = Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|s| s.success()) {
        let o = basin(&fifo, &["--force"]);
        assert!(refused(&o).contains("not a regular file"));
        let o = run(&["merge", s(&d.join("x.h5")), "--out", s(&fifo), "--force"]);
        assert!(refused(&o).contains("not a regular file"));
        use std::os::unix::fs::FileTypeExt;
        assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    } else {
        eprintln!("FIFO cases skipped: mkfifo is not available");
    }
    // an HDF5 error is told once
    std::fs::write(d.join("junk.h5"), b"not an HDF5 file").unwrap();
    let o = basin(&d.join("junk.h5"), &["--resume"]);
    let e = refused(&o);
    let first = e.split(": ").nth(2).unwrap_or_default().to_string();
    assert!(
        first.len() < 12 || e.matches(&first).count() == 1,
        "repeated: {e}"
    );
}

/// A file system too small for the file: exit 2 with the operating system's message, never a
/// crash, and no unreadable file left that would block a rerun or --resume. Needs root to mount
/// a tiny tmpfs.
#[test]
fn full_disk_is_an_error_not_a_crash() {
    let root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| o.stdout == b"0\n");
    if !root {
        eprintln!("skipped: needs root to mount a tiny tmpfs (a full file system)");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mnt = dir.path().join("mnt");
    std::fs::create_dir(&mnt).unwrap();
    let reference = dir.path().join("ref.h5");
    assert!(basin(&reference, &[]).status.success());
    let png = dir.path().join("pic.png");
    for size in ["4k", "8k", "16k", "32k", "48k"] {
        let ok = Command::new("mount")
            .args([
                "-t",
                "tmpfs",
                "-o",
                &format!("size={size}"),
                "tmpfs",
                s(&mnt),
            ])
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            eprintln!("skipped: mount -t tmpfs failed (no permission in this container)");
            return;
        }
        let f = mnt.join("b.h5");
        let o = basin(&f, &["--png", s(&png), "--force"]);
        let e = refused(&o);
        assert!(e.contains("No space left on device"), "{size}: {e}");
        // the sweep writer too, leaving no temporary file
        let o = run(&[
            "fixedpoint",
            "--sweep",
            "slope=0.001:0.002:3",
            "--out",
            s(&mnt.join("bif.h5")),
            "--png",
            s(&png),
            "--force",
        ]);
        let e = refused(&o);
        assert!(e.contains("No space left on device"), "{size}: {e}");
        // what is left is resumable (or absent): grow the file system and resume
        let ok = Command::new("mount")
            .args(["-o", "remount,size=16m", s(&mnt)])
            .status()
            .is_ok_and(|s| s.success());
        assert!(ok, "remount");
        let o = basin(&f, &["--png", s(&png), "--force", "--resume"]);
        assert!(o.status.success(), "{size}: {}", err(&o));
        same_cells(&f, &reference);
        let leftovers: Vec<_> = std::fs::read_dir(&mnt)
            .unwrap()
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains("partial"))
            .collect();
        assert!(leftovers.is_empty(), "{leftovers:?}");
        let _ = Command::new("umount").args(["-l", s(&mnt)]).status();
    }
}

/// Runs the binary in directory `dir` (for relative and `./` paths).
fn run_in(dir: &Path, args: &[&str]) -> Output {
    bin()
        .current_dir(dir)
        .args(args)
        .output()
        .expect("the binary runs")
}

#[test]
fn no_writer_replaces_its_spec_file_by_any_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let spec = run(&["models", "--spec", "compass"]);
    assert!(spec.status.success());
    std::fs::write(d.join("my.toml"), &spec.stdout).unwrap();
    std::fs::hard_link(d.join("my.toml"), d.join("hard.h5")).unwrap();
    std::os::unix::fs::symlink("my.toml", d.join("sym.h5")).unwrap();
    let sweep = ["--sweep", "slope=0.05:0.06:3"];
    let cases: Vec<Vec<&str>> = vec![
        // the same path, the same file through ./, a hard link and a symbolic link
        vec!["basin", "--model", "my.toml", "--out", "my.toml", "--force"],
        vec![
            "basin",
            "--model",
            "./my.toml",
            "--out",
            "my.toml",
            "--force",
        ],
        vec!["basin", "--model", "my.toml", "--out", "hard.h5", "--force"],
        vec!["basin", "--model", "my.toml", "--out", "sym.h5", "--force"],
        vec![
            "basin", "--model", "my.toml", "--png", "./sym.h5", "--force",
        ],
        // every other writer
        [
            &["fixedpoint", "--model", "my.toml"][..],
            &sweep,
            &["--out", "sym.h5"],
        ]
        .concat(),
        [
            &["fixedpoint", "--model", "my.toml"][..],
            &sweep,
            &["--out", "b.h5", "--csv", "hard.h5", "--force"],
        ]
        .concat(),
        vec![
            "basin",
            "--model",
            "my.toml",
            "--over",
            "slope=0.05:0.06:2",
            "--out",
            "hard.h5",
            "--force",
        ],
        vec![
            "simulate", "--model", "my.toml", "--out", "sym.h5", "--force",
        ],
        vec![
            "animate", "--model", "my.toml", "--out", "hard.h5", "--force",
        ],
        vec![
            "design",
            "--model",
            "my.toml",
            "--free",
            "hip_mass=5:15",
            "--out",
            "sym.h5",
            "--force",
        ],
    ];
    for args in &cases {
        let o = run_in(d, args);
        let e = refused(&o);
        assert!(e.contains("also an input"), "{args:?}: {e}");
        assert_eq!(std::fs::read(d.join("my.toml")).unwrap(), spec.stdout);
    }
    assert!(std::fs::symlink_metadata(d.join("sym.h5"))
        .unwrap()
        .file_type()
        .is_symlink());
}

#[test]
fn outputs_are_checked_before_computing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // design's picture is not replaced without --force, and nothing is left behind
    std::fs::write(d.join("p.png"), b"keep").unwrap();
    let o = run(&[
        "design",
        "--model",
        "kneed",
        "--free",
        "hip_mass=0.3:1.2",
        "--quiet",
        "--out",
        s(&d.join("new.h5")),
        "--png",
        s(&d.join("p.png")),
    ]);
    let e = refused(&o);
    assert!(e.contains("--png") && e.contains("--force"), "{e}");
    assert_eq!(std::fs::read(d.join("p.png")).unwrap(), b"keep");
    assert!(!d.join("new.h5").exists());
    // the extension names the format written
    let o = run(&[
        "fixedpoint",
        "--sweep",
        "slope=0.001:0.002:3",
        "--out",
        s(&d.join("a.csv")),
    ]);
    assert!(refused(&o).contains(".h5"), "{}", err(&o));
    assert!(!d.join("a.csv").exists());
    let o = run(&["animate", "--out", s(&d.join("x.h5"))]);
    assert!(refused(&o).contains(".gif"), "{}", err(&o));
    assert!(!d.join("x.h5").exists());
    let o = basin(&d.join("b.h5"), &["--png", s(&d.join("q.txt"))]);
    assert!(refused(&o).contains(".png"), "{}", err(&o));

    // a directory that takes no new files is found before a long sweep, named with its cause
    let ro = d.join("ro");
    std::fs::create_dir(&ro).unwrap();
    let root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| o.stdout == b"0\n");
    let read_only = if root {
        // permission bits do not stop root: a read-only file system does
        Command::new("mount")
            .args(["-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", s(&ro)])
            .status()
            .is_ok_and(|s| s.success())
    } else {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).is_ok()
    };
    if !read_only {
        eprintln!("read-only case skipped: cannot make a read-only directory here");
        return;
    }
    let target = ro.join("b.h5");
    let long = [
        "fixedpoint",
        "--sweep",
        "slope=0.001:0.019:4000",
        "--out",
        s(&target),
    ];
    let o = run(&long);
    let png = ro.join("p.png");
    let o2 = run(&[
        "fixedpoint",
        "--sweep",
        "slope=0.001:0.019:4000",
        "--out",
        s(&d.join("ok.h5")),
        "--png",
        s(&png),
    ]);
    if root {
        let _ = Command::new("umount").args(["-l", s(&ro)]).status();
    }
    for (o, p) in [(o, &target), (o2, &png)] {
        let e = refused(&o);
        assert!(e.contains(s(p)) && !e.contains("partial"), "{e}");
        assert!(
            e.contains("read-only") || e.contains("permission denied"),
            "{e}"
        );
    }
    assert!(!d.join("ok.h5").exists());
}

#[test]
fn a_second_writer_of_any_command_is_refused_naming_the_path_and_the_holder() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let target = d.join("c.h5");
    // a long basin run holds its --out from the start
    let mut first = bin()
        .args([
            "basin",
            "--grid",
            "600x600",
            "--max-strides",
            "200",
            "--threads",
            "1",
            "--quiet",
            "--out",
            s(&target),
        ])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("the binary runs");
    // past its gait search: the basin file has its header
    while !std::fs::metadata(&target).is_ok_and(|m| m.len() > 0) {
        assert!(first.try_wait().unwrap().is_none(), "the first run ended");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let c = s(&target);
    let shard = d.join("s0.h5");
    let seconds: Vec<Vec<&str>> = vec![
        vec!["basin", "--grid", "4x4", "--out", c, "--force"],
        vec!["basin", "--grid", "4x4", "--out", c, "--resume"],
        vec!["merge", s(&shard), "--out", c, "--force"],
        vec![
            "fixedpoint",
            "--sweep",
            "slope=0.001:0.002:3",
            "--out",
            c,
            "--force",
        ],
        vec!["simulate", "--out", c, "--force"],
        vec![
            "design",
            "--model",
            "kneed",
            "--free",
            "hip_mass=0.3:1.2",
            "--out",
            c,
            "--force",
        ],
    ];
    let holder = format!("process {}", first.id());
    for args in &seconds {
        let o = run(args);
        let e = refused(&o);
        assert!(
            e.contains("another process") && e.contains(c) && e.contains(&holder),
            "{args:?}: {e}"
        );
        assert!(
            first.try_wait().unwrap().is_none(),
            "{args:?} ended the first run"
        );
    }
    first.kill().unwrap();
    first.wait().unwrap();
    // no second writer removed or replaced the first one's file
    assert!(target.exists());
}

#[test]
fn hostile_specs_are_refused_without_a_crash_or_unbounded_reads() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let spec = String::from_utf8(run(&["models", "--spec", "compass"]).stdout).unwrap();
    assert!(spec.contains("com = \"a\""));
    // 30 000 nested parentheses, then 100 000 unary minuses: SIGABRT (stack overflow) before
    for (i, deep) in [
        format!("{}a{}", "(".repeat(30_000), ")".repeat(30_000)),
        format!("{}a", "-".repeat(100_000)),
        format!("{}a{}", "(".repeat(3_000), ")".repeat(3_000)),
    ]
    .iter()
    .enumerate()
    {
        let p = d.join(format!("deep{i}.toml"));
        std::fs::write(
            &p,
            spec.replace("com = \"a\"", &format!("com = \"{deep}\"")),
        )
        .unwrap();
        let o = run(&["fixedpoint", "--model", s(&p)]);
        let e = refused(&o);
        assert!(e.contains("characters") || e.contains("levels deep"), "{e}");
        // the expression is echoed by its start and length only
        assert!(e.len() < 1000, "{} bytes", e.len());
    }
    // a spec that is a device (through a link named .toml) is refused before it is read
    let z = d.join("zero.toml");
    std::os::unix::fs::symlink("/dev/zero", &z).unwrap();
    let o = run(&["fixedpoint", "--model", s(&z)]);
    assert!(refused(&o).contains("not a regular file"), "{}", err(&o));
}

#[test]
fn fixedpoint_warns_when_the_integrator_cannot_support_the_newton_tolerance() {
    // --rtol 1e-3 gave a "stable gait" with |λ| 0.768 (0.589 on an accurate map), silently
    let o = run(&["fixedpoint", "--rtol", "1e-3"]);
    let e = err(&o);
    assert!(
        e.contains("warning") && e.contains("accurate stride map") && e.contains("--rtol"),
        "{e}"
    );
    // the default integrator's tolerance given explicitly: no warning
    let o = run(&["fixedpoint", "--rtol", "1e-14"]);
    assert!(o.status.success(), "{}", err(&o));
    assert!(!err(&o).contains("warning"), "{}", err(&o));
}

/// The `validity` of the first gait of `fixedpoint --model rimless --json` with `extra`.
fn rimless_validity(extra: &[&str]) -> serde_json::Value {
    let mut a = vec!["fixedpoint", "--model", "rimless", "--json"];
    a.extend_from_slice(extra);
    let o = run(&a);
    assert!(o.status.success(), "{}", err(&o));
    let j: serde_json::Value = serde_json::from_str(&out(&o)).unwrap();
    j["fixed_points"][0]["validity"].clone()
}

/// The smallest normal ground reaction per unit mass along the rimless wheel's rolling gait
/// (8 spokes, g = 9.81, l = 1), in closed form: the axial spoke force `g cos(θ + γ) − l θ̇²`
/// times `cos θ` is smallest at one end of the step, just before (θ = α, θ̇ = ω*/cos 2α) or
/// just after (θ = −α, θ̇ = ω*) a spoke impact, with `ω* = cot 2α √(4 (g/l) sin α sin γ)`.
fn rimless_min_normal(gamma: f64) -> f64 {
    let (g, a) = (9.81, std::f64::consts::PI / 8.0);
    let w = (4.0 * g * a.sin() * gamma.sin()).sqrt() / (2.0 * a).tan();
    let before = (g * (a + gamma).cos() - (w / (2.0 * a).cos()).powi(2)) * a.cos();
    let after = (g * (gamma - a).cos() - w * w) * a.cos();
    before.min(after)
}

#[test]
fn a_rimless_wheel_whose_spoke_would_pull_the_ground_is_no_valid_gait() {
    // γ = 0.3: the spoke would have to pull the ground before the next one lands
    let v = rimless_validity(&["--slope", "0.3"]);
    assert_eq!(v["valid"], false, "{v}");
    assert_eq!(v["normal_force_negative"], true, "{v}");
    let min = v["min_normal_force"].as_f64().unwrap();
    let expect = rimless_min_normal(0.3);
    assert!(
        expect < -1.2 && (min - expect).abs() < 1e-8,
        "{min} vs {expect}"
    );
    let viol = v["violations"].as_array().unwrap();
    assert!(viol.iter().any(|x| x["criterion"] == "normal_force"), "{v}");
    assert_eq!(v["binding"], "normal_force", "{v}");
    // the preset γ = 0.08: valid, with positive margins on the scales g and √(g l)
    let v = rimless_validity(&[]);
    assert_eq!(v["valid"], true, "{v}");
    assert_eq!(v["normal_force_negative"], false);
    assert_eq!(v["impact_violation"], false);
    let min = v["min_normal_force"].as_f64().unwrap();
    let expect = rimless_min_normal(0.08);
    assert!(
        expect > 5.0 && (min - expect).abs() < 1e-8,
        "{min} vs {expect}"
    );
    let margins = v["margins"].as_array().unwrap();
    for name in [
        "normal_force",
        "spoke_impact:new_stance_foot",
        "spoke_impact:trailing_foot",
    ] {
        let m = margins.iter().find(|m| m["name"] == name).unwrap();
        assert!(m["relative"].as_f64().unwrap() > 0.0, "{m}");
    }
    assert_eq!(v["scales"]["gravity"], 9.81);
    // the human-readable line says the same, in N/kg
    let o = run(&["fixedpoint", "--model", "rimless", "--slope", "0.3"]);
    let text = out(&o);
    assert!(
        text.contains("validity     FLAGGED") && text.contains("N/kg"),
        "{text}"
    );
}

/// The outcome codes and strides of a basin file, row-major, and the file.
fn basin_codes(p: &Path) -> (Vec<u8>, Vec<u16>, pdw::store::BasinData) {
    let d = pdw::store::read_basin(p).unwrap();
    let codes = d.outcome.iter().copied().collect();
    let strides = d.strides.iter().copied().collect();
    (codes, strides, d)
}

#[test]
fn a_walk_dying_out_on_a_level_floor_is_no_attractor() {
    let dir = tempfile::tempdir().unwrap();
    // `fall`: a fall of another kind, or a walk that came to a stand. `basin`'s default box
    // (docs/cli.md) at slope 0 with 1000 strides: 10 of 441 cells were `chaotic`
    // (θ ≈ 0.0046 and shrinking as k^{-1/2}), the attractor a sample of that decay
    let fall = 6u8;
    let p = dir.path().join("level.h5");
    let o = run(&[
        "basin",
        "--slope",
        "0",
        "--grid",
        "21x21",
        "--x",
        "theta=0.15:0.25",
        "--y",
        "thetadot=-0.25:-0.15",
        "--max-strides",
        "1000",
        "--quiet",
        "--out",
        s(&p),
    ]);
    assert!(o.status.success(), "{}", err(&o));
    let (codes, strides, d) = basin_codes(&p);
    let legend = &d.header.legend;
    // no attractor code (16 and up): only the fixed outcomes
    assert!(legend.iter().all(|(c, _)| *c < 16), "{legend:?}");
    assert!(d.attractors.is_empty(), "{:?}", d.attractors);
    assert!(
        codes.iter().all(|&c| c != 1 && c != 7 && c < 16),
        "{codes:?}"
    );
    let stood: Vec<usize> = (0..codes.len()).filter(|&i| codes[i] == fall).collect();
    assert_eq!(stood.len(), 10, "{codes:?}");
    for &i in &stood {
        // decided at the budget, at a scale of about 0.0046 rad
        assert_eq!(strides[i], 1000);
        let th = d.final_state[[i / 21, i % 21, 0]];
        assert!(th > 0.004 && th < 0.005, "{th}");
    }
    // with 100 strides, one cell of this box walked down to (9.4e-7, −9.8e-7), where a stride
    // moved it by less than an absolute 1e-10: it was `other`
    let p = dir.path().join("tiny.h5");
    let o = run(&[
        "basin",
        "--slope",
        "0",
        "--grid",
        "21x21",
        "--x",
        "theta=0.001:0.021",
        "--y",
        "thetadot=-0.021:-0.001",
        "--max-strides",
        "100",
        "--quiet",
        "--out",
        s(&p),
    ]);
    assert!(o.status.success(), "{}", err(&o));
    let (codes, strides, d) = basin_codes(&p);
    let legend = &d.header.legend;
    assert!(legend.iter().all(|(c, _)| *c < 16), "{legend:?}");
    assert!(
        codes.iter().all(|&c| c != 1 && c != 7 && c < 16),
        "{codes:?}"
    );
    // the cell (θ, θ̇) = (0.001, −0.001): row 20, column 0
    let i = 20 * 21;
    assert_eq!(codes[i], fall);
    assert_eq!(strides[i], 100);
    let th = d.final_state[[20, 0, 0]];
    assert!(th > 0.0 && th < 1e-6, "{th}");
}
