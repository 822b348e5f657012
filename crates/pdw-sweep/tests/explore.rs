//! `pdw-sweep explore`: the cells the explorer walks get the labels their basin file records, a
//! refined window is `pdw-sweep basin` on that box cell for cell, and the server keeps to its
//! rules (loopback unless told, files by index only, JSON errors, body cap, disconnects and
//! rapid refines).

use crate::common::run;
use pdw_explore::jobs::compute;
use pdw_explore::source::{self, Window};
use pdw_limit::trajectory::Trajectory;
use std::io::{Read, Write};
use std::net::{IpAddr, Ipv4Addr, TcpStream};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize};
use std::time::{Duration, Instant};

/// A basin file of `model` on `grid` (extra `args`) in `dir`.
fn basin(dir: &Path, name: &str, args: &[&str]) -> PathBuf {
    let out = dir.join(format!("{name}.h5"));
    let png = dir.join(format!("{name}.png"));
    let mut a = vec!["basin", "--quiet", "--out", out.to_str().unwrap()];
    a.extend(["--png", png.to_str().unwrap()]);
    a.extend_from_slice(args);
    let o = run(&a);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

fn pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
}

/// Whether a walk fell (its trajectory ended on a terminal guard).
fn fell(tr: &Trajectory) -> bool {
    matches!(tr.outcome, pdw_limit::StrideOutcome::Fall { .. })
}

/// Every `step`-th cell of the file walks to the outcome the file records: the engine's label
/// of the single cell equals the file's, and, as a second method, the dense walk of the
/// scalar trajectory integrator falls for every fall cell and keeps walking for every gait cell
/// away from a basin boundary (all four neighbours share its label).
fn walks_match_file(path: &Path, step: usize) {
    let src = source::load(path).unwrap();
    let pool = pool();
    let r = source::rebuild(&src, &Window::default(), &pool).unwrap();
    source::check_same_run(&src, &r).unwrap();
    let h = &src.data.header;
    let (nx, ny) = (h.nx(), h.ny());
    let label = |i: usize, j: usize| h.outcome_name(src.data.outcome[[i, j]]).unwrap();
    let (mut n, mut gaits, mut falls) = (0, 0, 0);
    for k in (0..nx * ny).step_by(step) {
        let (i, j) = (k / nx, k % nx);
        let cell = r.plan.row_cells(&[i]).swap_remove(j);
        let res = pdw_explore::walk::classify(&r, &cell, &pool).unwrap();
        let got = pdw_explore::walk::outcome_name(&r, res.outcome);
        assert_eq!(got, label(i, j), "cell [{i}, {j}] of {}", path.display());
        assert_eq!(
            res.strides,
            src.data.strides[[i, j]],
            "strides of [{i}, {j}]"
        );
        n += 1;
        let interior = i > 0 && j > 0 && i + 1 < ny && j + 1 < nx && {
            let l = label(i, j);
            [(i - 1, j), (i + 1, j), (i, j - 1), (i, j + 1)]
                .iter()
                .all(|&(a, b)| label(a, b) == l)
        };
        let steps = usize::from(res.strides) + 1;
        if got.starts_with("fall") {
            falls += 1;
            let tr = pdw_explore::walk::walk(&r, &cell, steps).unwrap();
            assert!(
                fell(&tr),
                "fall cell [{i}, {j}] walked {} steps",
                tr.steps_done
            );
        } else if got == "gait" {
            gaits += 1;
            if interior {
                let tr = pdw_explore::walk::walk(&r, &cell, steps.max(8)).unwrap();
                assert!(!fell(&tr), "gait cell [{i}, {j}] fell");
            }
        }
    }
    assert!(
        n >= 50 && gaits >= 3 && falls >= 10,
        "{n} cells, {gaits} gait, {falls} fall"
    );
}

#[test]
fn walked_cells_get_the_labels_the_file_records() {
    let dir = tempfile::tempdir().unwrap();
    let s = basin(dir.path(), "simplest", &["--grid", "41x41"]);
    walks_match_file(&s, 13);
    let c = basin(
        dir.path(),
        "compass",
        &["--model", "compass", "--grid", "21x21"],
    );
    walks_match_file(&c, 5);
}

/// Refines the box of `args` of the file at `file` and compares cell for cell with `basin` run
/// on that box.
fn refine_equals_basin(
    dir: &Path,
    file: &Path,
    bx: (f64, f64, f64, f64),
    n: (usize, usize),
    cli: &[&str],
) {
    let src = source::load(file).unwrap();
    let w = Window {
        bounds: Some(bx),
        grid: Some(n),
        z_fixed: None,
        overrides: Vec::new(),
    };
    let (stop, done) = (AtomicBool::new(false), AtomicUsize::new(0));
    let (_, outcome, strides, _) = compute(&src, &w, &pool(), &stop, &done)
        .unwrap()
        .expect("not cancelled");
    let h = &src.data.header;
    let x = format!("{}={}:{}", h.x_name, bx.0, bx.1);
    let y = format!("{}={}:{}", h.y_name, bx.2, bx.3);
    let grid = format!("{}x{}", n.0, n.1);
    let mut args = vec!["--x", &x, "--y", &y, "--grid", &grid];
    args.extend_from_slice(cli);
    let b = basin(dir, "box", &args);
    let d = pdw_store::read_basin(&b).unwrap();
    assert_eq!(outcome, d.outcome.iter().copied().collect::<Vec<_>>());
    assert_eq!(strides, d.strides.iter().copied().collect::<Vec<_>>());
    assert_eq!(done.load(std::sync::atomic::Ordering::SeqCst), n.0 * n.1);
}

#[test]
fn a_refined_window_is_basin_on_that_box() {
    let dir = tempfile::tempdir().unwrap();
    let s = basin(dir.path(), "simplest", &["--grid", "21x21"]);
    refine_equals_basin(dir.path(), &s, (0.17, 0.23, -0.23, -0.17), (37, 29), &[]);
    let c = basin(
        dir.path(),
        "compass",
        &[
            "--model",
            "compass",
            "--grid",
            "11x11",
            "--max-strides",
            "60",
        ],
    );
    std::fs::remove_file(dir.path().join("box.h5")).unwrap();
    std::fs::remove_file(dir.path().join("box.png")).unwrap();
    let h = pdw_store::read_basin_header(&c).unwrap();
    let (x0, x1) = (h.x[0], h.x[h.nx() - 1]);
    let (y0, y1) = (h.y[0], h.y[h.ny() - 1]);
    let bx = (x0, 0.5 * (x0 + x1), 0.5 * (y0 + y1), y1);
    refine_equals_basin(
        dir.path(),
        &c,
        bx,
        (13, 9),
        &["--model", "compass", "--max-strides", "60"],
    );
}

/// A response: status and JSON body.
fn http(addr: &str, method: &str, path: &str, body: &str) -> (u16, serde_json::Value) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    write!(
        s,
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nContent-Type: application/json\r\n\
         Content-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    )
    .unwrap();
    let mut text = String::new();
    s.read_to_string(&mut text).unwrap();
    let status: u16 = text[9..12].parse().unwrap();
    let json = text
        .split_once("\r\n\r\n")
        .and_then(|(_, b)| serde_json::from_str(b).ok())
        .unwrap_or(serde_json::Value::Null);
    (status, json)
}

/// Polls job `id` until it leaves `queued`/`running`; its final JSON.
fn wait_job(addr: &str, id: u64) -> serde_json::Value {
    let t0 = Instant::now();
    loop {
        let (st, j) = http(addr, "GET", &format!("/api/job/{id}"), "");
        assert_eq!(st, 200);
        let s = j["status"].as_str().unwrap().to_string();
        if s != "queued" && s != "running" {
            return j;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(120),
            "job {id} never ends"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A client that disconnects mid-refine cancels it and leaves the server serving; of 20 rapid refines only
/// the last computes; save writes the window into the save directory `dir`.
fn refines_cancel_and_save(a: &str, dir: &Path) {
    let a = a.to_string();
    // a client that disconnects while a refine runs: the server goes on serving
    let mut c = TcpStream::connect(&a).unwrap();
    let body = r#"{"file": 0, "box": {"x": [0.16, 0.24], "y": [-0.24, -0.16]}, "nx": 300, "ny": 300, "wait": true}"#;
    write!(
        c,
        "POST /api/refine HTTP/1.1\r\nHost: x\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    )
    .unwrap();
    std::thread::sleep(Duration::from_millis(200));
    drop(c);
    let (st, _) = http(&a, "GET", "/api/files", "");
    assert_eq!(st, 200);
    let first = wait_job(&a, 1);
    // the request's drop guard cancelled it (90 000 cells take over a second on 2 threads)
    assert_eq!(first["status"], "cancelled", "{first}");
    // 20 rapid refines: only the last computes
    let (_, before) = http(&a, "GET", "/api/stats", "");
    let mut ids = Vec::new();
    for k in 0..20 {
        let lo = 0.16 + 0.001 * k as f64;
        let body = format!(
            r#"{{"file": 0, "box": {{"x": [{lo}, 0.24], "y": [-0.24, -0.16]}}, "nx": 40, "ny": 40}}"#
        );
        let (st, j) = http(&a, "POST", "/api/refine", &body);
        assert_eq!(st, 200, "{j}");
        ids.push(j["job"].as_u64().unwrap());
    }
    let last = wait_job(&a, *ids.last().unwrap());
    assert_eq!(last["status"], "done");
    for id in &ids[..19] {
        assert_eq!(wait_job(&a, *id)["status"], "cancelled", "job {id}");
    }
    let (_, after) = http(&a, "GET", "/api/stats", "");
    let n = |v: &serde_json::Value, k: &str| v[k].as_u64().unwrap();
    assert_eq!(
        n(&after, "refines_completed") - n(&before, "refines_completed"),
        1
    );
    // save: the server names the file, in its save directory
    let (st, j) = http(
        &a,
        "POST",
        "/api/save",
        &format!(r#"{{"job": {}}}"#, ids[19]),
    );
    assert_eq!(st, 200, "{j}");
    let saved = dir.join(j["saved"].as_str().unwrap());
    let d = pdw_store::read_basin(&saved).unwrap();
    assert_eq!(d.header.nx(), 40);
    assert!(d.complete);
}

#[test]
fn the_server_keeps_to_its_rules() {
    let dir = tempfile::tempdir().unwrap();
    let s = basin(dir.path(), "simplest", &["--grid", "21x21"]);
    let bad = dir.path().join("bad.h5");
    std::fs::write(&bad, b"not an HDF5 file").unwrap();
    // a non-loopback address only when given explicitly
    let mut cfg = pdw_explore::Config::local(vec![s.clone(), bad], 0);
    cfg.addr = IpAddr::V4(Ipv4Addr::UNSPECIFIED);
    let refused = pdw_explore::start(cfg.clone()).err().expect("refused");
    assert!(refused.contains("--bind"), "{refused}");
    cfg.addr = IpAddr::V4(Ipv4Addr::LOCALHOST);
    cfg.save_dir = dir.path().to_path_buf();
    let server = pdw_explore::start(cfg).unwrap();
    let a = server.addr.to_string();
    let error = |(st, j): (u16, serde_json::Value), want: u16| {
        assert_eq!(st, want, "{j}");
        j["error"].as_str().expect("a JSON error").to_string()
    };
    // files by index only: out of range, a path in the body, a path in the URL
    error(http(&a, "GET", "/api/basin/7", ""), 404);
    let walk = r#"{"file": 0, "cell": [1, 1], "path": "../../etc/passwd"}"#;
    assert!(error(http(&a, "POST", "/api/walk", walk), 400).contains("path"));
    error(
        http(
            &a,
            "POST",
            "/api/walk",
            r#"{"file": "/etc/passwd", "cell": [1, 1]}"#,
        ),
        400,
    );
    error(http(&a, "GET", "/../../etc/passwd", ""), 404);
    error(
        http(&a, "GET", "/api/basin/..%2F..%2Fetc%2Fpasswd", ""),
        400,
    );
    // a malformed file is a clear error, the good one is served
    let e = error(http(&a, "GET", "/api/basin/1", ""), 422);
    assert!(e.contains("bad.h5"), "{e}");
    let (st, b) = http(&a, "GET", "/api/basin/0", "");
    assert_eq!(st, 200);
    assert_eq!(b["outcome"].as_array().unwrap().len(), 21 * 21);
    // request bodies are capped
    let big = format!(
        r#"{{"file": 0, "cell": [1, 1], "pad": "{}"}}"#,
        "x".repeat(40_000)
    );
    error(http(&a, "POST", "/api/walk", &big), 413);
    refines_cancel_and_save(&a, dir.path());
}

#[test]
fn a_sweep_point_walks_its_gait_with_the_files_period() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sweep.h5");
    let png = dir.path().join("sweep.png");
    let o = run(&[
        "fixedpoint",
        "--sweep",
        "slope=0.005:0.012:8",
        "--out",
        out.to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let server = pdw_explore::start(pdw_explore::Config::local(vec![out.clone()], 0)).unwrap();
    let a = server.addr.to_string();
    let (_, files) = http(&a, "GET", "/api/files", "");
    assert_eq!(files["files"][0]["kind"], "sweep");
    let (st, s) = http(&a, "GET", "/api/sweep/0", "");
    assert_eq!(st, 200, "{s}");
    let d = pdw_store::read_sweep(&out).unwrap();
    let b = d
        .branches
        .iter()
        .position(|b| b.stable.iter().any(|s| *s))
        .unwrap();
    let i = d.branches[b].stable.iter().position(|s| *s).unwrap();
    assert_eq!(s["branches"][b]["parameter"][i], d.branches[b].parameter[i]);
    let (st, g) = http(
        &a,
        "POST",
        "/api/gait",
        &format!(r#"{{"file": 0, "branch": {b}, "point": {i}}}"#),
    );
    assert_eq!(st, 200, "{g}");
    // a stable gait walks its periods without falling, each taking the file's period
    let k = d.branches[b].period_strides as usize;
    let w = &g["walk"];
    assert_eq!(w["steps_done"], pdw_explore::sweep::PERIODS_WALKED * k);
    let ends: Vec<f64> = w["events"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["ends_step"] == true)
        .map(|e| e["t"].as_f64().unwrap())
        .collect();
    assert!(w["events"]
        .as_array()
        .unwrap()
        .iter()
        .all(|e| e["fall"] == false));
    let t0 = w["t"][0].as_f64().unwrap();
    let want = pdw_explore::sweep::PERIODS_WALKED as f64 * d.branches[b].period[i];
    let got = ends[ends.len() - 1] - t0;
    assert!((got - want).abs() < 1e-6 * want, "{got} vs {want}");
    let (st, _) = http(
        &a,
        "POST",
        "/api/gait",
        r#"{"file": 0, "branch": 99, "point": 0}"#,
    );
    assert_eq!(st, 404);
}

/// A small design search in `dir`: compass walkers over the hip mass.
fn design_file(dir: &Path) -> PathBuf {
    let out = dir.join("design.h5");
    let png = dir.join("design.png");
    let o = run(&[
        "design",
        "--model",
        "compass",
        "--free",
        "hip_mass=4:16",
        "--budget",
        "4",
        "--init",
        "2",
        "--basin-grid",
        "4",
        "--max-strides",
        "10",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

/// The ends of the strides of a walk's JSON (times), and whether any event is a fall.
fn stride_ends(w: &serde_json::Value) -> (Vec<f64>, bool) {
    let ev = w["events"].as_array().unwrap();
    let ends = ev
        .iter()
        .filter(|e| e["ends_step"] == true)
        .map(|e| e["t"].as_f64().unwrap())
        .collect();
    (ends, ev.iter().any(|e| e["fall"] == true))
}

#[test]
fn a_design_files_table_is_the_files_and_a_design_walks_its_gait() {
    let dir = tempfile::tempdir().unwrap();
    let out = design_file(dir.path());
    let cols: Vec<&str> = pdw::design::COLUMNS.to_vec();
    let d = pdw_store::read_design(&out, &cols).unwrap();
    // the same search with design 1 recorded as having no gait
    let mut nog = d.clone();
    nog.status[1] = pdw_limit::design::status::NO_GAIT;
    nog.section[1] = [f64::NAN; 3];
    nog.reasons[1] = "no gait found".into();
    let out2 = dir.path().join("nogait.h5");
    pdw_store::write_design(&out2, &nog).unwrap();
    let server =
        pdw_explore::start(pdw_explore::Config::local(vec![out.clone(), out2], 0)).unwrap();
    let a = server.addr.to_string();
    let (_, files) = http(&a, "GET", "/api/files", "");
    assert_eq!(files["files"][0]["kind"], "design");
    assert_eq!(files["files"][0]["model"], "compass");
    let (st, t) = http(&a, "GET", "/api/design/0", "");
    assert_eq!(st, 200, "{t}");
    assert_eq!(t["designs"], d.params.len());
    let col = |name: &str| {
        t["columns"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["name"] == name)
            .unwrap_or_else(|| panic!("no column {name} in {t}"))
            .clone()
    };
    let hip: Vec<f64> = d.params.iter().map(|p| p[0]).collect();
    assert_eq!(col("hip_mass")["values"], serde_json::json!(hip));
    assert_eq!(
        col("period")["values"],
        serde_json::json!(d.column("period").unwrap())
    );
    assert_eq!(col("period")["units"], "s");
    for c in &cols {
        col(c);
    }
    // a feasible design walks its stored gait: each stride takes the stored period
    let i = d.status.iter().position(|s| *s == 0).unwrap();
    let (st, g) = http(
        &a,
        "POST",
        "/api/design_walk",
        &format!(r#"{{"file": 0, "design": {i}}}"#),
    );
    assert_eq!(st, 200, "{g}");
    let w = &g["walk"];
    assert_eq!(w["steps_done"], pdw_explore::design::STRIDES_WALKED);
    let (ends, fell) = stride_ends(w);
    assert!(!fell);
    let want = d.column("period").unwrap()[i];
    let got = ends[0] - w["t"][0].as_f64().unwrap();
    assert!((got - want).abs() < 1e-6 * want, "{got} vs {want}");
    // a design without a gait: a clear message naming its status and reason
    let (st, e) = http(
        &a,
        "POST",
        "/api/design_walk",
        r#"{"file": 1, "design": 1}"#,
    );
    assert_eq!(st, 422, "{e}");
    let msg = e["error"].as_str().unwrap();
    assert!(
        msg.contains("no gait") && msg.contains("no gait found"),
        "{msg}"
    );
    let (st, t2) = http(&a, "GET", "/api/design/1", "");
    assert_eq!(st, 200, "{t2}");
    assert_eq!(t2["status_words"][1], "no gait");
    let (st, _) = http(
        &a,
        "POST",
        "/api/design_walk",
        r#"{"file": 0, "design": 99}"#,
    );
    assert_eq!(st, 404);
}
