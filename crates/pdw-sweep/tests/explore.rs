//! `pdw-sweep explore`: the cells the explorer walks get the labels their basin file records, a
//! refined window is `pdw-sweep basin` on that box cell for cell, and the server keeps to its
//! rules (loopback unless told, only its own page — token, Host, Origin, JSON POSTs —, files by
//! index only, JSON errors, body cap, bounded connections, responses and cache, disconnects,
//! cancels and rapid refines).

use crate::common::run;
use pdw::limit::trajectory::Trajectory;
use pdw_explore::jobs::{compute, Computed, Phase};
use pdw_explore::source::{self, Window};
use std::io::{Read, Write};
use std::net::{IpAddr, Ipv4Addr, TcpStream};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
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
    matches!(tr.outcome, pdw::limit::StrideOutcome::Fall { .. })
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
    let (stop, done) = (Arc::new(AtomicBool::new(false)), AtomicUsize::new(0));
    let Computed::Done(_, outcome, strides, _) =
        compute(&src, &w, &pool(), &stop, &done, &|_| {}).unwrap()
    else {
        panic!("cancelled")
    };
    let h = &src.data.header;
    let x = format!("{}={}:{}", h.x_name, bx.0, bx.1);
    let y = format!("{}={}:{}", h.y_name, bx.2, bx.3);
    let grid = format!("{}x{}", n.0, n.1);
    let mut args = vec!["--x", &x, "--y", &y, "--grid", &grid];
    args.extend_from_slice(cli);
    let b = basin(dir, "box", &args);
    let d = pdw::store::read_basin(&b).unwrap();
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
    let h = pdw::store::read_basin_header(&c).unwrap();
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

/// A response to the raw request text `req`: status, headers and JSON body (`Null` if none).
fn raw(addr: &str, req: &str) -> (u16, String, serde_json::Value) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(120))).unwrap();
    s.write_all(req.as_bytes()).unwrap();
    let mut text = String::new();
    s.read_to_string(&mut text).unwrap();
    let status: u16 = text[9..12].parse().unwrap();
    let (head, body) = text.split_once("\r\n\r\n").unwrap_or((&text, ""));
    let json = serde_json::from_str(body).unwrap_or(serde_json::Value::Null);
    (status, head.to_string(), json)
}

/// A request's text: `method path` with `headers` and `body`, closing the connection after.
fn request(method: &str, path: &str, headers: &[(&str, &str)], body: &str) -> String {
    let mut r = format!("{method} {path} HTTP/1.1\r\n");
    for (k, v) in headers {
        r += &format!("{k}: {v}\r\n");
    }
    r + &format!(
        "Content-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    )
}

/// A client of a server's API as its page is: the server's Host, its token, JSON bodies.
struct Client {
    addr: String,
    token: String,
}

impl Client {
    fn of(s: &pdw_explore::Server) -> Client {
        Client {
            addr: s.addr.to_string(),
            token: s.token.clone(),
        }
    }

    /// The answer to `method path` with `body`: status and JSON.
    fn call(&self, method: &str, path: &str, body: &str) -> (u16, serde_json::Value) {
        let auth = format!("token {}", self.token);
        let h = [
            ("Host", self.addr.as_str()),
            ("Authorization", auth.as_str()),
            ("Content-Type", "application/json"),
        ];
        let (st, _, j) = raw(&self.addr, &request(method, path, &h, body));
        (st, j)
    }
}

/// Polls job `id` until it leaves `queued`/`running`; its final JSON.
fn wait_job(c: &Client, id: u64) -> serde_json::Value {
    wait_status(c, id, |s| s != "queued" && s != "running")
}

/// Polls job `id` until its status satisfies `done`; its JSON then.
fn wait_status(c: &Client, id: u64, done: impl Fn(&str) -> bool) -> serde_json::Value {
    let t0 = Instant::now();
    loop {
        let (st, j) = c.call("GET", &format!("/api/job/{id}"), "");
        assert_eq!(st, 200, "{j}");
        if done(j["status"].as_str().unwrap()) {
            return j;
        }
        assert!(t0.elapsed() < Duration::from_secs(300), "job {id}: {j}");
        std::thread::yield_now();
    }
}

/// The refine request of a box `[lo, 0.24] x [-0.24, -0.16]` at `n` x `n` cells.
fn refine_body(lo: f64, n: usize, wait: bool) -> String {
    format!(
        r#"{{"file": 0, "box": {{"x": [{lo}, 0.24], "y": [-0.24, -0.16]}}, "nx": {n}, "ny": {n}, "wait": {wait}}}"#
    )
}

/// A client that disconnects mid-refine cancels it and leaves the server serving; of 20 refines
/// sent while the worker is held only the last computes; cancelling a finished job says it had
/// finished; save writes the window into the save directory `dir` with `basin`'s header, past a
/// dangling link named like the next save.
fn refines_cancel_and_save(server: &pdw_explore::Server, dir: &Path) {
    let c = Client::of(server);
    // a client that disconnects while its refine runs (1000x1000 cells: far longer than the
    // test's steps): the refine is cancelled, the server goes on serving
    let mut conn = TcpStream::connect(&c.addr).unwrap();
    let auth = format!("token {}", c.token);
    let h = [
        ("Host", c.addr.as_str()),
        ("Authorization", auth.as_str()),
        ("Content-Type", "application/json"),
    ];
    let body = refine_body(0.16, 1000, true);
    conn.write_all(request("POST", "/api/refine", &h, &body).as_bytes())
        .unwrap();
    // job 1 once the server has it, and until it runs
    let t0 = Instant::now();
    while c.call("GET", "/api/job/1", "").1["status"] != "running" {
        assert!(t0.elapsed() < Duration::from_secs(300), "job 1 never runs");
        std::thread::yield_now();
    }
    drop(conn);
    let (st, _) = c.call("GET", "/api/files", "");
    assert_eq!(st, 200);
    let first = wait_job(&c, 1);
    assert_eq!(first["status"], "cancelled", "{first}");
    // 20 refines while the worker is held: only the last computes
    let (_, before) = c.call("GET", "/api/stats", "");
    let mut ids = Vec::new();
    {
        let _hold = server.state.jobs.hold();
        for k in 0..20 {
            let body = refine_body(0.16 + 0.001 * k as f64, 40, false);
            let (st, j) = c.call("POST", "/api/refine", &body);
            assert_eq!(st, 200, "{j}");
            ids.push(j["job"].as_u64().unwrap());
        }
    }
    let last = wait_job(&c, *ids.last().unwrap());
    assert_eq!(last["status"], "done");
    for id in &ids[..19] {
        assert_eq!(wait_job(&c, *id)["status"], "cancelled", "job {id}");
    }
    let (_, after) = c.call("GET", "/api/stats", "");
    let n = |v: &serde_json::Value, k: &str| v[k].as_u64().unwrap();
    assert_eq!(
        n(&after, "refines_started") - n(&before, "refines_started"),
        1
    );
    assert_eq!(
        n(&after, "refines_completed") - n(&before, "refines_completed"),
        1
    );
    // cancelling a finished job says it had finished
    let (st, j) = c.call("POST", &format!("/api/job/{}/cancel", ids[19]), "{}");
    assert_eq!(st, 200, "{j}");
    assert_eq!(j["cancelled"], false, "{j}");
    assert_eq!(j["status"], "done", "{j}");
    assert!(j["message"].as_str().unwrap().contains("already finished"));
    // a dangling link named like the next save: the save takes the next name, the link stays
    let link = dir.join("explore-simplest-40x40-1.h5");
    std::os::unix::fs::symlink(dir.join("nowhere"), &link).unwrap();
    // ... and a save of that next name killed before its rename left its temporary file (the
    // pid of no running process): the save's claim removes it, as every writer's does
    let stale = dir.join(".explore-simplest-40x40-2.h5.partial-4194303");
    std::fs::write(&stale, b"half a file").unwrap();
    let (st, j) = c.call("POST", "/api/save", &format!(r#"{{"job": {}}}"#, ids[19]));
    assert_eq!(st, 200, "{j}");
    assert_eq!(j["saved"], "explore-simplest-40x40-2.h5");
    assert!(std::fs::symlink_metadata(&link).unwrap().is_symlink());
    assert!(!dir.join("nowhere").exists());
    assert!(!stale.exists(), "the killed save's temporary file is left");
    let saved = dir.join(j["saved"].as_str().unwrap());
    let d = pdw::store::read_basin(&saved).unwrap();
    assert_eq!(d.header.nx(), 40);
    assert!(d.complete);
    // the saved window's header is `basin`'s on that box, the discovery's settings included
    let h = &d.header;
    let x = format!("{}={}:{}", h.x_name, h.x[0], h.x[h.nx() - 1]);
    let y = format!("{}={}:{}", h.y_name, h.y[0], h.y[h.ny() - 1]);
    let b = basin(dir, "box40", &["--x", &x, "--y", &y, "--grid", "40x40"]);
    let cli = pdw::store::read_basin_header(&b).unwrap();
    let tol = |t: &str| serde_json::from_str::<serde_json::Value>(t).unwrap();
    let (mine, theirs) = (tol(&h.tolerances), tol(&cli.tolerances));
    for k in [
        "attractor_seeds",
        "seed_strides",
        "chaos_radius",
        "chaos_sample",
    ] {
        assert!(!theirs[k].is_null(), "basin writes {k}");
    }
    assert_eq!(mine, theirs);
    assert_eq!(h.legend, cli.legend);
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
    let c = Client::of(&server);
    let error = |(st, j): (u16, serde_json::Value), want: u16| {
        assert_eq!(st, want, "{j}");
        j["error"].as_str().expect("a JSON error").to_string()
    };
    // files by index only: out of range, a path in the body, a path in the URL
    error(c.call("GET", "/api/basin/7", ""), 404);
    let walk = r#"{"file": 0, "cell": [1, 1], "path": "../../etc/passwd"}"#;
    assert!(error(c.call("POST", "/api/walk", walk), 400).contains("path"));
    error(
        c.call(
            "POST",
            "/api/walk",
            r#"{"file": "/etc/passwd", "cell": [1, 1]}"#,
        ),
        400,
    );
    error(c.call("GET", "/../../etc/passwd", ""), 404);
    error(c.call("GET", "/api/basin/..%2F..%2Fetc%2Fpasswd", ""), 400);
    // a malformed file is a clear error, the good one is served
    let e = error(c.call("GET", "/api/basin/1", ""), 422);
    assert!(e.contains("bad.h5"), "{e}");
    let (st, b) = c.call("GET", "/api/basin/0", "");
    assert_eq!(st, 200);
    assert_eq!(b["outcome"].as_array().unwrap().len(), 21 * 21);
    // request bodies are capped
    let big = format!(
        r#"{{"file": 0, "cell": [1, 1], "pad": "{}"}}"#,
        "x".repeat(40_000)
    );
    error(c.call("POST", "/api/walk", &big), 413);
    refines_cancel_and_save(&server, dir.path());
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
    let c = Client::of(&server);
    let (_, files) = c.call("GET", "/api/files", "");
    assert_eq!(files["files"][0]["kind"], "sweep");
    let (st, s) = c.call("GET", "/api/sweep/0", "");
    assert_eq!(st, 200, "{s}");
    let d = pdw::store::read_sweep(&out).unwrap();
    let b = d
        .branches
        .iter()
        .position(|b| b.stable.iter().any(|s| *s))
        .unwrap();
    let i = d.branches[b].stable.iter().position(|s| *s).unwrap();
    assert_eq!(s["branches"][b]["parameter"][i], d.branches[b].parameter[i]);
    let (st, g) = c.call(
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
    let (st, _) = c.call(
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
    let d = pdw::store::read_design(&out, &cols).unwrap();
    // the same search with design 1 recorded as having no gait
    let mut nog = d.clone();
    nog.status[1] = pdw::limit::design::status::NO_GAIT;
    nog.section[1] = [f64::NAN; 3];
    nog.reasons[1] = "no gait found".into();
    let out2 = dir.path().join("nogait.h5");
    pdw::store::write_design(&out2, &nog).unwrap();
    let server =
        pdw_explore::start(pdw_explore::Config::local(vec![out.clone(), out2], 0)).unwrap();
    let c = Client::of(&server);
    let (_, files) = c.call("GET", "/api/files", "");
    assert_eq!(files["files"][0]["kind"], "design");
    assert_eq!(files["files"][0]["model"], "compass");
    let (st, t) = c.call("GET", "/api/design/0", "");
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
    let (st, g) = c.call(
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
    let (st, e) = c.call("POST", "/api/design_walk", r#"{"file": 1, "design": 1}"#);
    assert_eq!(st, 422, "{e}");
    let msg = e["error"].as_str().unwrap();
    assert!(
        msg.contains("no gait") && msg.contains("no gait found"),
        "{msg}"
    );
    let (st, t2) = c.call("GET", "/api/design/1", "");
    assert_eq!(st, 200, "{t2}");
    assert_eq!(t2["status_words"][1], "no gait");
    let (st, _) = c.call("POST", "/api/design_walk", r#"{"file": 0, "design": 99}"#);
    assert_eq!(st, 404);
}

/// A served simplest-walker basin (21x21) in `dir`, on a server configured by `tune`.
fn served(dir: &Path, tune: impl FnOnce(&mut pdw_explore::Config)) -> pdw_explore::Server {
    let s = basin(dir, "simplest", &["--grid", "21x21"]);
    let mut cfg = pdw_explore::Config::local(vec![s], 0);
    cfg.save_dir = dir.to_path_buf();
    tune(&mut cfg);
    pdw_explore::start(cfg).unwrap()
}

/// The files "save" wrote into `dir`.
fn saves(dir: &Path) -> usize {
    std::fs::read_dir(dir)
        .unwrap()
        .filter(|e| {
            let n = e.as_ref().unwrap().file_name();
            n.to_string_lossy().starts_with("explore-")
        })
        .count()
}

#[test]
fn the_server_answers_only_its_own_page() {
    let dir = tempfile::tempdir().unwrap();
    let server = served(dir.path(), |_| {});
    let c = Client::of(&server);
    let (a, port) = (c.addr.as_str(), server.addr.port());
    // a window to save, made by the page's own client
    let (st, j) = c.call("POST", "/api/refine", &refine_body(0.18, 10, true));
    assert_eq!(st, 200, "{j}");
    let job = j["job"].as_u64().unwrap();
    let (_, stats0) = c.call("GET", "/api/stats", "");
    let refused = |req: String, want: u16, says: &str| {
        let (st, _, j) = raw(a, &req);
        assert_eq!(st, want, "{req}: {j}");
        let e = j["error"].as_str().expect("a JSON error");
        assert!(e.contains(says), "{e} (wanted '{says}')");
    };
    let auth = format!("token {}", c.token);
    let refine =
        r#"{"file":0,"box":{"x":[0.19,0.21],"y":[-0.21,-0.19]},"nx":100,"ny":100,"wait":true}"#;
    let save = format!(r#"{{"job":{job}}}"#);
    // the issue's reproduction: a text/plain cross-site POST with a rebound Host, no token
    let evil = [
        ("Host", "rebind.attacker.example"),
        ("Origin", "http://evil.example"),
        ("Content-Type", "text/plain"),
    ];
    refused(
        request("POST", "/api/refine", &evil, refine),
        403,
        "rebind.attacker.example",
    );
    refused(request("POST", "/api/save", &evil, &save), 403, "Host");
    // each check alone, everything else right
    let ok_host = a.to_string();
    let with = |host: &str, origin: Option<&str>, token: Option<&str>, ct: Option<&str>| {
        let mut h = vec![("Host", host.to_string())];
        if let Some(o) = origin {
            h.push(("Origin", o.to_string()));
        }
        if let Some(t) = token {
            h.push(("Authorization", format!("token {t}")));
        }
        if let Some(ct) = ct {
            h.push(("Content-Type", ct.to_string()));
        }
        h
    };
    let send = |m: &str, path: &str, h: Vec<(&str, String)>, body: &str| {
        let h: Vec<(&str, &str)> = h.iter().map(|(k, v)| (*k, v.as_str())).collect();
        request(m, path, &h, body)
    };
    let tok = Some(c.token.as_str());
    let json = Some("application/json");
    for host in [
        format!("rebind.attacker.example:{port}"),
        format!("127.0.0.1:{}", port.wrapping_add(1)),
        format!("127.0.0.2:{port}"),
        "127.0.0.1".to_string(),
    ] {
        refused(
            send("POST", "/api/save", with(&host, None, tok, json), &save),
            403,
            &host,
        );
        refused(
            send("GET", "/", with(&host, None, None, None), ""),
            403,
            "Host",
        );
    }
    refused(
        format!("GET /api/files HTTP/1.0\r\nAuthorization: {auth}\r\n\r\n"),
        403,
        "(none)",
    );
    for origin in [
        "http://evil.example".to_string(),
        format!("http://127.0.0.1:{}", port.wrapping_add(1)),
        format!("https://{a}"),
        "null".to_string(),
    ] {
        let h = with(&ok_host, Some(&origin), tok, json);
        refused(send("POST", "/api/save", h, &save), 403, &origin);
    }
    let mut h = with(&ok_host, None, tok, json);
    h.push(("Sec-Fetch-Site", "cross-site".into()));
    refused(send("POST", "/api/save", h, &save), 403, "cross-site");
    let mut h = with(&ok_host, None, None, None);
    h.push(("Sec-Fetch-Site", "same-site".into()));
    refused(send("GET", "/api/files", h, ""), 403, "same-site");
    // no token, a wrong one, one of another length, in the header, the query or a cookie
    let wrong = "0".repeat(64);
    refused(
        send("POST", "/api/save", with(&ok_host, None, None, json), &save),
        403,
        "token",
    );
    refused(
        send(
            "POST",
            "/api/save",
            with(&ok_host, None, Some(&wrong), json),
            &save,
        ),
        403,
        "token",
    );
    refused(
        send(
            "GET",
            "/api/files",
            with(&ok_host, None, Some("abc"), None),
            "",
        ),
        403,
        "token",
    );
    refused(
        send(
            "GET",
            &format!("/api/files?token={wrong}"),
            with(&ok_host, None, None, None),
            "",
        ),
        403,
        "token",
    );
    let mut h = with(&ok_host, None, None, None);
    h.push(("Cookie", format!("pdw_explore_{port}={wrong}")));
    refused(send("GET", "/api/files", h, ""), 403, "token");
    refused(
        send(
            "GET",
            &format!("/?token={wrong}"),
            with(&ok_host, None, None, None),
            "",
        ),
        403,
        "token",
    );
    // API POSTs are JSON only
    for ct in [
        Some("text/plain"),
        Some("application/x-www-form-urlencoded"),
        None,
    ] {
        let h = with(&ok_host, None, tok, ct);
        refused(
            send("POST", "/api/save", h.clone(), &save),
            415,
            "application/json",
        );
        refused(send("POST", "/api/refine", h, refine), 415, "Content-Type");
    }
    // nothing refused ran: no refine started, no file saved
    let (_, stats1) = c.call("GET", "/api/stats", "");
    assert_eq!(stats0["refines_started"], stats1["refines_started"]);
    assert_eq!(saves(dir.path()), 0);
    // admitted: the bound address or localhost with the port, the server's own Origin, the
    // token by header, query or the cookie the page sets
    let (st, head, _) = raw(
        a,
        &send(
            "GET",
            &format!("/?token={}", c.token),
            with(&ok_host, None, None, None),
            "",
        ),
    );
    assert_eq!(st, 200);
    let cookie = head
        .lines()
        .find_map(|l| l.strip_prefix("set-cookie: "))
        .expect("the page sets its cookie")
        .split(';')
        .next()
        .unwrap()
        .to_string();
    assert_eq!(cookie, format!("pdw_explore_{port}={}", c.token));
    let local = format!("localhost:{port}");
    for (host, origin) in [
        (ok_host.clone(), format!("http://{ok_host}")),
        (local.clone(), format!("http://{local}")),
    ] {
        let mut h = with(&host, Some(&origin), None, json);
        h.push(("Cookie", format!("other=1; {cookie}")));
        h.push(("Sec-Fetch-Site", "same-origin".into()));
        let (st, _, j) = raw(a, &send("POST", "/api/save", h, &save));
        assert_eq!(st, 200, "{host}: {j}");
    }
    let (st, _, j) = raw(
        a,
        &send(
            "GET",
            &format!("/api/files?token={}", c.token),
            with(&local, None, None, None),
            "",
        ),
    );
    assert_eq!(st, 200, "{j}");
    assert_eq!(saves(dir.path()), 2);
    assert!(
        server.url.ends_with(&format!("/?token={}", c.token)),
        "{}",
        server.url
    );
    assert_eq!(c.token.len(), 64);
}

/// What the server sent on `s` before it closed it (a reset counts as closed; the test's own
/// read timeout does not).
fn closed_by_server(s: &mut TcpStream) -> Vec<u8> {
    let mut buf = Vec::new();
    if let Err(e) = s.read_to_end(&mut buf) {
        assert_eq!(e.kind(), std::io::ErrorKind::ConnectionReset, "{e}");
    }
    buf
}

#[test]
fn slow_clients_time_out_and_connections_are_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let server = served(dir.path(), |cfg| {
        cfg.limits.header_timeout = Duration::from_millis(300);
        cfg.limits.body_timeout = Duration::from_millis(300);
    });
    let c = Client::of(&server);
    // a half-sent head: the server closes the connection (read ends) and serves others meanwhile
    let mut half = TcpStream::connect(&c.addr).unwrap();
    half.set_read_timeout(Some(Duration::from_secs(120)))
        .unwrap();
    half.write_all(b"GET /api/files HTTP/1.1\r\nHo").unwrap();
    assert_eq!(c.call("GET", "/api/files", "").0, 200);
    closed_by_server(&mut half);
    // a body that never comes: 408, and no work
    let mut slow = TcpStream::connect(&c.addr).unwrap();
    slow.set_read_timeout(Some(Duration::from_secs(120)))
        .unwrap();
    let auth = format!("token {}", c.token);
    write!(
        slow,
        "POST /api/save HTTP/1.1\r\nHost: {}\r\nAuthorization: {auth}\r\nContent-Type: \
         application/json\r\nContent-Length: 100\r\n\r\n{{\"job\"",
        c.addr
    )
    .unwrap();
    // the answer's head (the server need not close the connection after it)
    let mut head = Vec::new();
    let mut byte = [0u8; 1];
    while !head.ends_with(b"\r\n\r\n") && slow.read(&mut byte).unwrap() == 1 {
        head.push(byte[0]);
    }
    let text = String::from_utf8_lossy(&head);
    assert!(text.starts_with("HTTP/1.1 408"), "{text}");
    drop(server);
    // at most max_connections at once: one more is closed at once, without an answer; once one
    // closes, the server answers again
    let dir = tempfile::tempdir().unwrap();
    let server = served(dir.path(), |cfg| cfg.max_connections = 3);
    let c = Client::of(&server);
    let held: Vec<TcpStream> = (0..3)
        .map(|_| TcpStream::connect(&c.addr).unwrap())
        .collect();
    let mut extra = TcpStream::connect(&c.addr).unwrap();
    extra
        .set_read_timeout(Some(Duration::from_secs(120)))
        .unwrap();
    assert!(closed_by_server(&mut extra).is_empty());
    drop(held);
    let t0 = Instant::now();
    loop {
        let mut s = TcpStream::connect(&c.addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(120))).unwrap();
        let auth = format!("token {}", c.token);
        let h = [("Host", c.addr.as_str()), ("Authorization", auth.as_str())];
        s.write_all(request("GET", "/api/files", &h, "").as_bytes())
            .unwrap();
        let mut text = String::new();
        let _ = s.read_to_string(&mut text);
        if text.starts_with("HTTP/1.1 200") {
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(120),
            "never answered again"
        );
    }
}

#[test]
fn heavy_responses_and_the_window_cache_are_bounded() {
    let dir = tempfile::tempdir().unwrap();
    // a 10x10 window of the simplest walker: 100 + 200 + 8 (200 + 20) bytes
    let window = 100 + 200 + 8 * (200 + 20);
    let server = served(dir.path(), |cfg| {
        cfg.heavy = (1, 0);
        cfg.cache_bytes = 2 * window + window / 2;
    });
    let c = Client::of(&server);
    // the gate full: a large response is refused at once with 503, then served
    let permit = server.state.heavy.try_enter().expect("a permit");
    let (st, j) = c.call("GET", "/api/basin/0", "");
    assert_eq!(st, 503, "{j}");
    assert!(j["error"].as_str().unwrap().contains("busy"));
    drop(permit);
    let (st, j) = c.call("GET", "/api/basin/0", "");
    assert_eq!(st, 200, "{j}");
    assert_eq!(j["outcome"].as_array().unwrap().len(), 21 * 21);
    // three windows with room for two and a half: the least recently used leaves
    let job = |lo: f64| {
        let (st, j) = c.call("POST", "/api/refine", &refine_body(lo, 10, true));
        assert_eq!(st, 200, "{j}");
        assert_eq!(j["status"], "done", "{j}");
        j["job"].as_u64().unwrap()
    };
    let (a, b) = (job(0.17), job(0.18));
    assert_eq!(
        c.call("GET", &format!("/api/job/{a}"), "").1["status"],
        "done"
    );
    let x = job(0.19);
    let status = |id: u64| c.call("GET", &format!("/api/job/{id}"), "").1;
    assert_eq!(status(a)["status"], "done");
    assert_eq!(status(x)["status"], "done");
    let e = status(b);
    assert_eq!(e["status"], "evicted", "{e}");
    assert!(e["error"].as_str().unwrap().contains("refine it again"));
    let (_, st) = c.call("GET", "/api/stats", "");
    assert_eq!(st["cache_bytes"], 2 * window);
    assert_eq!(st["windows_evicted"], 1);
    // an evicted window is computed again when asked again
    assert_ne!(job(0.18), b);
    // the job table is bounded too: refines queued while the worker is held
    {
        let _hold = server.state.jobs.hold();
        for k in 0..pdw_explore::jobs::MAX_RECORDS + 20 {
            let body = refine_body(0.16 + 1e-6 * k as f64, 10, false);
            assert_eq!(c.call("POST", "/api/refine", &body).0, 200);
        }
    }
    assert!(server.state.jobs.records() <= pdw_explore::jobs::MAX_RECORDS);
}

/// A window of `src` (the slope changed: its gaits are searched again) cancelled as phase `at`
/// starts (`None`: never).
fn cancelled_in(src: &source::BasinSource, at: Option<Phase>) -> Computed {
    let w = Window {
        bounds: Some((0.17, 0.23, -0.23, -0.17)),
        grid: Some((30, 30)),
        z_fixed: None,
        overrides: vec![("slope".into(), 0.0095)],
    };
    let stop = Arc::new(AtomicBool::new(false));
    let done = AtomicUsize::new(0);
    let on_phase = |p: Phase| {
        if Some(p) == at {
            stop.store(true, Ordering::SeqCst);
        }
    };
    compute(src, &w, &pool(), &stop, &done, &on_phase).unwrap()
}

/// A cancel is seen at the window's next step: the gait search, the attractor discovery and
/// the cells are each not started once it is set.
#[test]
fn a_cancel_stops_a_window_at_each_phase() {
    let dir = tempfile::tempdir().unwrap();
    let s = basin(dir.path(), "simplest", &["--grid", "11x11"]);
    let src = source::load(&s).unwrap();
    for at in [Phase::GaitSearch, Phase::Attractors, Phase::Cells] {
        match cancelled_in(&src, Some(at)) {
            Computed::Cancelled(p) => assert_eq!(p, at),
            Computed::Done(..) => panic!("a cancel at {} was not seen", at.name()),
        }
    }
    // the process-wide interrupt is untouched (walks go on): the next window computes
    assert!(!pdw::hybrid::interrupt::requested());
    assert!(matches!(cancelled_in(&src, None), Computed::Done(..)));
}

/// A cancel reaches a gait search under way: at a slope with no kneed gait the search walks
/// every start for seconds (then the window's cells are all falls); cancelled 50 ms into it, the window ends as cancelled in the gait
/// search within a small part of that time (the walks of other threads are not stopped: the
/// process-wide interrupt stays clear).
#[test]
fn a_cancel_reaches_a_gait_search_under_way() {
    let dir = tempfile::tempdir().unwrap();
    let k = basin(dir.path(), "kneed", &["--model", "kneed", "--grid", "4x4"]);
    let src = source::load(&k).unwrap();
    let w = Window {
        bounds: None,
        grid: Some((4, 4)),
        z_fixed: None,
        overrides: vec![("slope".into(), 0.002)],
    };
    let done = AtomicUsize::new(0);
    // the whole window, not cancelled: a search for seconds that finds no gait, then cells
    let t0 = Instant::now();
    let whole = compute(
        &src,
        &w,
        &pool(),
        &Arc::new(AtomicBool::new(false)),
        &done,
        &|_| {},
    );
    let whole_s = t0.elapsed().as_secs_f64();
    assert!(matches!(whole, Ok(Computed::Done(..))), "not computed");
    assert!(
        whole_s > 1.0,
        "the window took only {whole_s} s: too short to test a cancel in"
    );
    // cancelled 50 ms after the search starts
    let stop = Arc::new(AtomicBool::new(false));
    let cancelled_at = std::sync::Mutex::new(None);
    let on_phase = |p: Phase| {
        if p == Phase::GaitSearch {
            let stop = stop.clone();
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_millis(50));
                stop.store(true, Ordering::SeqCst);
            });
            *cancelled_at.lock().unwrap() = Some(Instant::now() + Duration::from_millis(50));
        }
    };
    let got = compute(&src, &w, &pool(), &stop, &done, &on_phase).unwrap();
    let after = cancelled_at
        .lock()
        .unwrap()
        .unwrap()
        .elapsed()
        .as_secs_f64();
    assert!(
        matches!(got, Computed::Cancelled(Phase::GaitSearch)),
        "not cancelled in the gait search"
    );
    assert!(
        after < whole_s / 4.0,
        "the search went on {after:.2} s after the cancel (whole search {whole_s:.2} s)"
    );
    assert!(!pdw::hybrid::interrupt::requested());
}

#[test]
fn a_private_directory_is_new_and_only_the_users() {
    use pdw_explore::private_dir::PrivateDir;
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("d");
    let d = PrivateDir::create(&p).unwrap();
    let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o700);
    std::fs::write(p.join("f"), b"x").unwrap();
    // an existing directory, file or link (dangling too) is never reused
    let e = PrivateDir::create(&p).unwrap_err();
    assert!(e.contains("never reused"), "{e}");
    drop(d);
    assert!(!p.exists());
    let link = dir.path().join("l");
    std::os::unix::fs::symlink(dir.path().join("elsewhere"), &link).unwrap();
    assert!(PrivateDir::create(&link).is_err());
    assert!(!dir.path().join("elsewhere").exists());
    let a = PrivateDir::new("pdw-explore-test-").unwrap();
    let b = PrivateDir::new("pdw-explore-test-").unwrap();
    assert_ne!(a.path(), b.path());
}

#[test]
fn a_save_dir_that_cannot_take_saves_is_refused_at_start() {
    let dir = tempfile::tempdir().unwrap();
    let s = basin(dir.path(), "simplest", &["--grid", "5x5"]);
    let f = dir.path().join("plain");
    std::fs::write(&f, b"").unwrap();
    let missing = dir.path().join("missing");
    for (sd, says) in [(&missing, "No such file"), (&f, "not a directory")] {
        let o = run(&[
            "explore",
            s.to_str().unwrap(),
            "--port",
            "0",
            "--save-dir",
            sd.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2));
        let e = crate::common::stderr(&o);
        assert!(e.contains(sd.to_str().unwrap()) && e.contains(says), "{e}");
    }
}

#[test]
fn explore_without_a_file_computes_into_a_private_directory_removed_on_ctrl_c() {
    use std::io::BufRead;
    use std::os::unix::fs::PermissionsExt;
    let sd = tempfile::tempdir().unwrap();
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_pdw-sweep"))
        .args(["explore", "--port", "0", "--save-dir"])
        .arg(sd.path())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    err.read_line(&mut line).unwrap();
    let tmp = line
        .split("(into ")
        .nth(1)
        .and_then(|r| r.split(", removed").next())
        .map(PathBuf::from)
        .unwrap_or_else(|| panic!("no directory named: {line}"));
    assert!(tmp.file_name().unwrap().to_string_lossy().len() > "pdw-explore-".len() + 8);
    let mode = std::fs::metadata(&tmp).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o700, "{}", tmp.display());
    // stdout: the default basin's summary, then the URL
    let mut out = std::io::BufReader::new(child.stdout.take().unwrap());
    let mut url = String::new();
    while !url.contains("http://") {
        url.clear();
        assert!(out.read_line(&mut url).unwrap() > 0, "no URL printed");
    }
    assert!(url.contains("/?token="), "{url}");
    assert!(tmp.join("basin.h5").exists());
    let pid = i32::try_from(child.id()).unwrap();
    assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
    let st = child.wait().unwrap();
    assert_eq!(st.code(), Some(0));
    assert!(!tmp.exists(), "{} left behind", tmp.display());
}
