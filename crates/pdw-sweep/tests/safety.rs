//! Data safety and resources: a kill at any moment leaves outputs a resume finishes, picture
//! included; a file-size limit is an error, not a death by signal; every file a command writes
//! is claimed before work starts; memory is estimated up front; special files are refused as
//! inputs; bisection and no-fall runs end honestly; extreme values print briefly.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

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

/// A refusal: exit 2, no panic; its stderr.
fn refused(o: &Output) -> String {
    assert_eq!(o.status.code(), Some(2), "{}{}", out(o), err(o));
    assert!(!err(o).contains("panicked"), "{}", err(o));
    err(o)
}

const GRID: &str = "48x40";

fn basin_cmd(out: &Path, extra: &[&str]) -> Command {
    let mut c = bin();
    c.args([
        "basin",
        "--grid",
        GRID,
        "--max-strides",
        "40",
        "--quiet",
        "--out",
        s(out),
    ])
    .args(extra);
    c
}

fn basin(out: &Path, extra: &[&str]) -> Output {
    basin_cmd(out, extra).output().expect("the binary runs")
}

fn same_cells(a: &Path, b: &Path) {
    let (a, b) = (
        pdw::store::read_basin(a).unwrap(),
        pdw::store::read_basin(b).unwrap(),
    );
    assert!(a.complete && b.complete);
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

/// The temporary files (`.NAME.partial-PID…`) in `dir`.
fn partials(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.contains(".partial-"))
        })
        .collect()
}

/// The rows of `path` on disk, read as another process sees them (0 while unreadable).
fn rows_on_disk(path: &Path) -> usize {
    let Ok(f) = hdf5::File::with_options()
        .with_fapl(|p| p.file_locking(false))
        .open(path)
    else {
        return 0;
    };
    f.dataset("basin/rows_done")
        .and_then(|d| d.read_raw::<u8>())
        .map_or(0, |v| v.iter().filter(|b| **b == 1).count())
}

/// The reference basin (uninterrupted) in `dir`: its file and picture.
fn reference(dir: &Path) -> (PathBuf, PathBuf) {
    let r = dir.join("ref.h5");
    let o = basin(&r, &[]);
    assert!(o.status.success(), "{}", err(&o));
    (r.clone(), r.with_extension("png"))
}

/// A basin killed with SIGKILL after its first two row blocks are on disk (a requeued cluster
/// job) leaves its file and the empty placeholder of its picture; `--resume`, without
/// `--force`, finishes both to an uninterrupted run's bits, and no temporary file is left.
/// The run stalls after its 32nd row (`PDW_SWEEP_STALL_AFTER_ROWS`); the test waits until the
/// file shows those rows, then kills it.
#[test]
fn a_basin_killed_by_sigkill_resumes_to_the_same_file_and_picture() {
    let dir = tempfile::tempdir().unwrap();
    let (r, r_png) = reference(dir.path());
    let k = dir.path().join("k.h5");
    let mut child = basin_cmd(&k, &["--threads", "1"])
        .env("PDW_SWEEP_STALL_AFTER_ROWS", "32")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    while rows_on_disk(&k) < 32 {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before its rows were on disk"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    let png = k.with_extension("png");
    assert_eq!(
        std::fs::metadata(&png).unwrap().len(),
        0,
        "the picture's placeholder is left by the kill"
    );
    let o = basin(&k, &["--resume"]);
    assert!(o.status.success(), "{}", err(&o));
    same_cells(&r, &k);
    assert_eq!(std::fs::read(&png).unwrap(), std::fs::read(&r_png).unwrap());
    assert!(
        partials(dir.path()).is_empty(),
        "{:?}",
        partials(dir.path())
    );
}

/// A kill right after the claim (before the file was created) leaves two empty placeholders;
/// a kill after the file was finished but before its picture was renamed into place leaves no
/// picture. `--resume` finishes both cases to the reference's file and picture; without
/// `--resume` the empty files are still refused without `--force`.
#[test]
fn resume_finishes_outputs_left_empty_or_missing_by_a_kill() {
    let dir = tempfile::tempdir().unwrap();
    let (r, r_png) = reference(dir.path());
    let e = dir.path().join("e.h5");
    std::fs::write(&e, b"").unwrap();
    std::fs::write(e.with_extension("png"), b"").unwrap();
    assert!(refused(&basin(&e, &[])).contains("--force"));
    let o = basin(&e, &["--resume"]);
    assert!(o.status.success(), "{}", err(&o));
    same_cells(&r, &e);
    assert_eq!(
        std::fs::read(e.with_extension("png")).unwrap(),
        std::fs::read(&r_png).unwrap()
    );
    let c = dir.path().join("c.h5");
    std::fs::copy(&r, &c).unwrap();
    let o = basin(&c, &["--resume"]);
    assert!(o.status.success(), "{}", err(&o));
    assert!(out(&o).contains("already complete"), "{}", out(&o));
    assert_eq!(
        std::fs::read(c.with_extension("png")).unwrap(),
        std::fs::read(&r_png).unwrap()
    );
}

/// Runs `cmd` under a file-size limit of `bytes` (`ulimit -f`).
fn with_file_limit(cmd: &mut Command, bytes: u64) -> Output {
    use std::os::unix::process::CommandExt;
    // SAFETY: setrlimit is async-signal-safe; the closure touches nothing else.
    unsafe {
        cmd.pre_exec(move || {
            let lim = libc::rlimit {
                rlim_cur: bytes,
                rlim_max: bytes,
            };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    cmd.output().expect("the binary runs")
}

/// A file-size limit hit while writing is an error (exit 2, the operating system's "File too
/// large"), not a death by SIGXFSZ; the basin file is left resumable and `mfpt` leaves no
/// temporary file.
#[test]
fn a_file_size_limit_is_an_error_not_a_signal() {
    let dir = tempfile::tempdir().unwrap();
    let (r, _) = reference(dir.path());
    let b = dir.path().join("b.h5");
    let o = with_file_limit(&mut basin_cmd(&b, &[]), 24 << 10);
    let msg = refused(&o);
    assert!(msg.contains("too large"), "{msg}");
    let o = basin(&b, &["--resume"]);
    assert!(o.status.success(), "{}", err(&o));
    same_cells(&r, &b);
    // a writer without the HDF5 writers' check: the write past the limit fails (EFBIG)
    let csv = dir.path().join("t.csv");
    let mut c = bin();
    c.args(["simulate", "--model", "simplest", "--steps", "20", "--out"])
        .arg(&csv);
    let o = with_file_limit(&mut c, 4 << 10);
    let msg = refused(&o);
    assert!(msg.to_lowercase().contains("too large"), "{msg}");
    assert!(!csv.exists());
    let m = dir.path().join("m.h5");
    let mut c = bin();
    c.args([
        "mfpt",
        "--model",
        "rimless",
        "--sd",
        "1deg",
        "--walkers",
        "20",
        "--max-steps",
        "50",
        "--quiet",
        "--out",
    ])
    .arg(&m);
    let msg = refused(&with_file_limit(&mut c, 4 << 10));
    assert!(msg.contains("too large"), "{msg}");
    assert!(
        partials(dir.path()).is_empty(),
        "{:?}",
        partials(dir.path())
    );
}

/// The temporary file a killed writer left beside its output is removed by the next run that
/// claims the output (its process is gone; a live process's is kept).
#[test]
fn a_killed_writers_temporary_file_is_removed_by_the_next_claim() {
    let dir = tempfile::tempdir().unwrap();
    let mut gone = Command::new("true").spawn().unwrap();
    let dead = gone.id();
    gone.wait().unwrap();
    let m = dir.path().join("m.h5");
    let stale = dir.path().join(format!(".m.h5.partial-{dead}"));
    let live = dir
        .path()
        .join(format!(".m.h5.partial-{}", std::process::id()));
    std::fs::write(&stale, b"half").unwrap();
    std::fs::write(&live, b"half").unwrap();
    let o = run(&[
        "mfpt",
        "--model",
        "rimless",
        "--sd",
        "1deg",
        "--walkers",
        "20",
        "--max-steps",
        "50",
        "--quiet",
        "--out",
        s(&m),
    ]);
    assert!(o.status.success(), "{}", err(&o));
    assert!(!stale.exists());
    assert!(live.exists());
}

/// `mfpt --over … --out ov.h5` claims `ov-gsn.png` as it claims `ov.png`: an existing one is
/// refused without `--force` before any walker walks, and left as it was; `--dist file:X`
/// is an input, never replaced by `--out X`, with or without `--force`.
#[test]
fn mfpt_claims_its_gsn_picture_and_never_replaces_its_dist_file() {
    let dir = tempfile::tempdir().unwrap();
    let ov = dir.path().join("ov.h5");
    let gsn = dir.path().join("ov-gsn.png");
    std::fs::write(&gsn, b"keep").unwrap();
    let o = run(&[
        "mfpt",
        "--model",
        "simplest",
        "--sd",
        "0.1deg",
        "--walkers",
        "10",
        "--max-steps",
        "20",
        "--over",
        "slope=0.009:0.01:2",
        "--quiet",
        "--out",
        s(&ov),
    ]);
    let msg = refused(&o);
    assert!(
        msg.contains("ov-gsn.png") && msg.contains("--force"),
        "{msg}"
    );
    assert_eq!(std::fs::read(&gsn).unwrap(), b"keep");
    assert!(!ov.exists());
    let xi = dir.path().join("xi.h5");
    std::fs::write(&xi, "0.5\n-0.5\n1\n").unwrap();
    let dist = format!("file:{}", s(&xi));
    for force in [&[][..], &["--force"][..]] {
        let mut a = vec![
            "mfpt",
            "--model",
            "rimless",
            "--sd",
            "0.5deg",
            "--walkers",
            "10",
            "--max-steps",
            "20",
            "--dist",
            &dist,
            "--quiet",
            "--out",
            s(&xi),
        ];
        a.extend_from_slice(force);
        let msg = refused(&run(&a));
        assert!(
            msg.contains("also an input") && msg.contains("--dist"),
            "{msg}"
        );
        assert_eq!(std::fs::read_to_string(&xi).unwrap(), "0.5\n-0.5\n1\n");
    }
}

/// Requests whose memory cannot fit are refused up front with the estimate and the limit; a
/// step limit far beyond any walk costs nothing (the survival curve ends at the longest walk).
#[test]
fn mfpt_memory_is_estimated_before_the_walkers_walk() {
    let msg = refused(&run(&[
        "mfpt",
        "--model",
        "rimless",
        "--sd",
        "1deg",
        "--walkers",
        "1000000000000",
    ]));
    assert!(
        msg.contains("--walkers 1000000000000") && msg.contains("GiB") && msg.contains("80 %"),
        "{msg}"
    );
    // refused before the walkers walk: no walker output, no file
    let dir = tempfile::tempdir().unwrap();
    let c = dir.path().join("c.h5");
    let o = run(&[
        "mfpt",
        "--model",
        "simplest",
        "--sd",
        "0.1deg",
        "--walkers",
        "10",
        "--chain",
        "--mesh",
        "100000",
        "--quiet",
        "--out",
        s(&c),
    ]);
    let msg = refused(&o);
    assert!(
        msg.contains("--mesh 100000") && msg.contains("GiB"),
        "{msg}"
    );
    assert!(out(&o).is_empty(), "{}", out(&o));
    assert!(!c.exists());
    for steps in ["18446744073709551615", "300000000"] {
        let f = dir.path().join(format!("s{}.h5", steps.len()));
        let o = run(&[
            "mfpt",
            "--model",
            "rimless",
            "--sd",
            "3deg",
            "--walkers",
            "10",
            "--max-steps",
            steps,
            "--quiet",
            "--out",
            s(&f),
        ]);
        assert!(o.status.success(), "{}", err(&o));
        let file = hdf5::File::with_options()
            .with_fapl(|p| p.file_locking(false))
            .open(&f)
            .unwrap();
        let n = file.dataset("mfpt/survival").unwrap().size();
        assert!(n < 10_000, "{n} survival values");
        let survival: Vec<f64> = file.dataset("mfpt/survival").unwrap().read_raw().unwrap();
        assert!(survival[n - 1] > 0.0, "the curve ends at the longest walk");
    }
}

/// Makes a FIFO at `p`.
fn fifo(p: &Path) {
    let c = std::ffi::CString::new(s(p)).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
}

/// Devices and FIFOs given as inputs are refused before anything opens them (a FIFO would
/// block, /dev/zero never end), naming the path and what an input must be.
#[test]
fn special_files_are_refused_as_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("pipe");
    fifo(&p);
    let out_h5 = dir.path().join("o.h5");
    let gif = dir.path().join("a.gif");
    for input in ["/dev/zero", s(&p)] {
        let dist = format!("file:{input}");
        for args in [
            vec!["merge", input, "--out", s(&out_h5)],
            vec!["animate", "--from", input, "--out", s(&gif)],
            vec![
                "mfpt",
                "--model",
                "rimless",
                "--sd",
                "1deg",
                "--walkers",
                "5",
                "--dist",
                &dist,
            ],
        ] {
            let msg = refused(&run(&args));
            assert!(
                msg.contains(input) && msg.contains("regular file"),
                "{args:?}: {msg}"
            );
        }
    }
    assert!(!out_h5.exists() && !gif.exists());
}

/// `--nodes 1` is refused (one node is deterministic ground: no MFPT); `--over` where nobody
/// falls draws its pictures with empty axes and says so instead of failing after the file.
#[test]
fn no_fall_runs_are_reported_honestly() {
    let msg = refused(&run(&[
        "mfpt",
        "--model",
        "simplest",
        "--sd",
        "0.1deg",
        "--walkers",
        "5",
        "--chain",
        "--nodes",
        "1",
    ]));
    assert!(
        msg.contains("--nodes: 1") && msg.contains("between 2 and 80"),
        "{msg}"
    );
    let dir = tempfile::tempdir().unwrap();
    let ov = dir.path().join("ov.h5");
    let o = run(&[
        "mfpt",
        "--model",
        "simplest",
        "--sd",
        "1e-9",
        "--walkers",
        "5",
        "--max-steps",
        "5",
        "--over",
        "slope=0.009:0.01:2",
        "--quiet",
        "--out",
        s(&ov),
    ]);
    assert!(o.status.success(), "{}", err(&o));
    assert!(err(&o).contains("no walker fell"), "{}", err(&o));
    for p in [
        ov.clone(),
        ov.with_extension("png"),
        dir.path().join("ov-gsn.png"),
    ] {
        assert!(std::fs::metadata(&p).unwrap().len() > 0, "{}", p.display());
    }
}

/// `--largest --tol 1e-20` ends: the bisection stops where the interval no longer shrinks
/// (adjacent doubles) and says so.
#[test]
fn bisection_below_the_spacing_of_doubles_ends_and_says_so() {
    let o = run(&[
        "disturb",
        "--model",
        "rimless",
        "--largest",
        "--tol",
        "1e-20",
        "--steps",
        "5",
    ]);
    assert!(o.status.success(), "{}", err(&o));
    assert!(out(&o).contains("spacing of doubles"), "{}", out(&o));
}

/// The longest run of digits in `t`.
fn longest_digits(t: &str) -> usize {
    t.split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0)
}

/// Extreme values print with an exponent, not as 300-digit decimals; an interior grid value
/// that differs is named by its index with both values.
#[test]
fn messages_show_extreme_values_briefly_and_name_the_point_that_differs() {
    let dir = tempfile::tempdir().unwrap();
    let xi = dir.path().join("xi.txt");
    std::fs::write(&xi, "1e308\n-1\n").unwrap();
    let dist = format!("file:{}", s(&xi));
    let o = run(&[
        "mfpt",
        "--model",
        "rimless",
        "--sd",
        "1deg",
        "--walkers",
        "5",
        "--dist",
        &dist,
    ]);
    let msg = refused(&o);
    assert!(longest_digits(&msg) < 30, "{msg}");
    // a disturbance the model refuses, through the stride map's error
    let o = run(&["disturb", "--once", "1e308"]);
    let msg = refused(&o);
    assert!(
        longest_digits(&msg) < 30 && msg.contains("1.000000e308"),
        "{msg}"
    );
    // a file whose y axis differs from the run's at one interior point
    let (r, _) = reference(dir.path());
    let h = pdw::store::read_basin_header(&r).unwrap();
    let f = dir.path().join("part.h5");
    pdw::store::BasinWriter::create(&f, &h, false)
        .unwrap()
        .close()
        .unwrap();
    let mut other = h.clone();
    other.y[17] = f64::from_bits(other.y[17].to_bits() + 1);
    let e = pdw::store::BasinWriter::resume(&f, &other)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("point 17")
            && e.contains(&format!("{:?}", h.y[17]))
            && e.contains(&format!("{:?}", other.y[17])),
        "{e}"
    );
}
