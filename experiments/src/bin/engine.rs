//! The integration engine against a plain C++ DOPRI5 (../shared/peers/sw_map.cpp), side by side
//! in the same minute: time per stride of the simplest walker (Garcia 1998, γ = 0.009) against
//! the accuracy it buys, for every method, with right-hand-side evaluation counts.
//!
//! - Accuracy is the error of the fixed point found with that setting, `‖s − s_ref‖∞`, against
//!   the reference `s_ref` (DOP853 at rtol = atol = 1e-14, Newton to 1e-13): the one number
//!   both engines print. Our Newton runs on the plain stride map at that setting (Jacobian by
//!   batched Richardson finite differences), as the peer's does. The peer prints its fixed point with 10 decimals, so its errors below
//!   ~5e-11 are print-limited (marked in the table). Our per-stride error
//!   `‖P(s_ref) − P_ref(s_ref)‖∞` is listed too.
//! - Error norms: both engines use HNW's RMS norm `√(1/d Σ (errᵢ/(atol + rtol·max(|x₀ᵢ|, |x₁ᵢ|)))²)`
//!   with rtol = atol = tol (DOP853: the code's stretched 5th/3rd-order estimate). The peer
//!   uses an elementary controller (no PI term, h ∈ [0.2, 5]·h) and starts every stride at
//!   h = 0.05; pdw-sweep starts each stride with HNW's starting-step heuristic and runs DOPRI5
//!   with the PI controller of the code dopri5 — and, in the rows "DOPRI5 elementary,
//!   h₀ = 0.05", with the peer's controller (`Controller::Elementary`) and first step.
//! - Scalar: one stride at a time from the fixed point (one reused integrator). Batched: 1024
//!   perturbed copies (relative 1e-4, seeded) through the lockstep engine, 256 lanes per batch
//!   (the basin's default; 64 before 25 Nov 17:00 UTC), blocks of 256, on a 2-thread pool;
//!   time per lane-stride (mean over ≥ 1.5 s of repeated calls).
//! - The default basin: 1000 × 1000 cells over θ ∈ [0.15, 0.25], θ̇ ∈ [−0.25, −0.15], 100
//!   strides, `BasinOptions::default()` (DOP853 1e-9), 2 threads, without file output; the
//!   median of three runs (all three printed; one run before 25 Nov 17:30 UTC).
//! - Where a batched stride's time goes: the batched times of each method over the tolerances
//!   fitted as `a + b·steps` (per-stride and per-step cost), and the per-step cost split into
//!   the right-hand side (`flow_batch` timed alone, on the same pool and on one thread) and
//!   the rest.
//!
//! Run with nothing else on the machine; the load average is printed with the figures.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::Command;

use anyhow::Context;
use pdw_experiments::{
    command, fit_line, results_dir, sci, time_mean, time_once, write_text, Table,
};
use pdw_hybrid::{Controller, Integrator, Options};
use pdw_limit::{
    classify_cells, find_fixed_point, grid_cells, linspace, BasinOptions, BasinProblem, DpMethod,
    FdScheme, NewtonOptions, Outcome, StrideMap,
};
use pdw_walkers::simplest::{GarciaGait, Simplest, SimplestParams};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The method label of DOPRI5 run with the peer's controller and first step.
const PEER_SETTINGS: &str = "DOPRI5 elementary, h₀ = 0.05";
const GAMMA: f64 = 0.009;
const TOLS: [f64; 4] = [1e-6, 1e-8, 1e-10, 1e-12];

struct Row {
    engine: &'static str,
    method: String,
    tol: String,
    scalar_us: f64,
    batch_us: f64,
    evals: f64,
    /// Step attempts (accepted + rejected) per stride.
    steps: f64,
    err_fp: f64,
    err_stride: f64,
    print_limited: bool,
}

/// Lanes per lockstep batch of the batched rows (the basin's default, `BasinOptions::lanes`).
const BATCH_LANES: usize = 256;

fn loadavg() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unavailable".into())
}

/// One line of the peer's output: tolerance, µs per stride, evaluations per stride, θ*, θ̇*.
type PeerRow = (f64, f64, f64, f64, f64);

/// Compile and run the C++ peer; `Err` (with the reason) when g++ or the source is missing.
fn run_peer() -> Result<Vec<PeerRow>, String> {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/peers/sw_map.cpp");
    if !src.exists() {
        return Err(format!("{} not found", src.display()));
    }
    let dir = std::env::temp_dir().join(format!("pdw-engine-peer-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let exe = dir.join("sw_map");
    let st = Command::new("g++")
        .args(["-O3", "-march=native"])
        .arg(&src)
        .arg("-o")
        .arg(&exe)
        .status()
        .map_err(|e| format!("g++: {e}"))?;
    if !st.success() {
        return Err("g++ failed".into());
    }
    let out = Command::new(&exe).output().map_err(|e| e.to_string())?;
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let _ = std::fs::remove_dir_all(&dir);
    // tol=1e-10 newton_iters=3 newton_ms=0.133 nf_newton=4210 | map_us=77.55 nf_per_map=421 |
    // theta*=0.2003109006 thetadot*=-0.1998324731 | eig = ...
    let field = |line: &str, key: &str| -> Option<f64> {
        let i = line.find(key)? + key.len();
        line[i..].split_whitespace().next()?.parse().ok()
    };
    let rows: Vec<_> = text
        .lines()
        .filter_map(|l| {
            Some((
                field(l, "tol=")?,
                field(l, "map_us=")?,
                field(l, "nf_per_map=")?,
                field(l, "theta*=")?,
                field(l, "thetadot*=")?,
            ))
        })
        .collect();
    if rows.is_empty() {
        return Err(format!("could not parse the peer's output:\n{text}"));
    }
    Ok(rows)
}

/// Wall time per lane-evaluation of the simplest walker's batched right-hand side
/// (`flow_batch` on blocks of 256 lanes, as the lockstep engine calls it) on `pool`, each thread
/// on its own block (seconds).
fn rhs_per_lane_eval(sys: &Simplest, states: &[Vec<f64>], pool: &rayon::ThreadPool) -> f64 {
    use faer::{MatMut, MatRef};
    use pdw_hybrid::{HybridSystem, Section};
    const LANES: usize = 256;
    const REPS: usize = 20_000;
    let mut x0 = vec![0.0; 4 * LANES];
    let mut x = [0.0; 4];
    for l in 0..LANES {
        sys.lift(&states[l % states.len()], &mut x);
        for j in 0..4 {
            x0[j * LANES + l] = x[j];
        }
    }
    let (_, t) = time_mean(0.5, || {
        pool.broadcast(|_| {
            let mut x = x0.clone();
            let mut k = vec![0.0; 4 * LANES];
            let mut ws = pdw_hybrid::Scratch::new();
            let mut acc = 0.0;
            for _ in 0..REPS {
                let xv = MatRef::from_column_major_slice_with_stride(&x, LANES, 4, LANES);
                let kv = MatMut::from_column_major_slice_with_stride_mut(&mut k, LANES, 4, LANES);
                sys.flow_batch(&mut ws, 0, xv, kv);
                // Feed a tiny step back so that no evaluation can be hoisted out of the loop.
                for (xi, ki) in x.iter_mut().zip(&k) {
                    *xi += 1e-12 * ki;
                }
                acc += k[3 * LANES];
            }
            acc
        })
    });
    t / (pool.current_num_threads() * REPS * LANES) as f64
}

/// Where a batched lane-stride's time goes: the batched times over the tolerances fitted as
/// `a + b·(steps per stride)` (a: per-stride cost — segment start, event location, driver; b:
/// per step attempt), and b split into the right-hand side (evaluations per step × the measured
/// cost of one lane-evaluation) and the rest.
fn cost_model(md: &mut String, rows: &[Row], t_rhs: f64, t_rhs1: f64) {
    let _ = writeln!(md, "\n## Where a batched stride's time goes\n");
    let _ = writeln!(
        md,
        "The batched times above, per method over the four tolerances, fitted as `a + b·steps` \
         (steps: attempts per stride, from the scalar run: the same steps). One lane-evaluation \
         of the batched right-hand side (`flow_batch`, 256 lanes): {:.2} ns on 2 threads, \
         {:.2} ns on one (the two threads give {:.2}× on the right-hand side alone).\n",
        t_rhs * 1e9,
        t_rhs1 * 1e9,
        t_rhs1 / t_rhs
    );
    let _ = writeln!(
        md,
        "| method | steps at 1e-6 … 1e-12 | a: per stride (µs) | b: per step (ns) | of b: right-hand side (ns) | of b: the rest (ns) | at 1e-10: a / steps·b (µs) |\n|---|---|---|---|---|---|---|"
    );
    for (method, evals_per_step) in [("DOPRI5", 6.0), ("DOP853", 12.0)] {
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.engine == "pdw-sweep" && r.method == method)
            .map(|r| (r.steps, r.batch_us))
            .collect();
        if pts.len() < 2 {
            continue;
        }
        let (a, b) = fit_line(&pts);
        let rhs = evals_per_step * t_rhs * 1e9;
        let steps: Vec<String> = pts.iter().map(|p| format!("{:.0}", p.0)).collect();
        let at = rows
            .iter()
            .find(|r| r.engine == "pdw-sweep" && r.method == method && r.tol == sci(1e-10))
            .map_or(String::from("–"), |r| {
                format!("{a:.2} / {:.2}", r.steps * b)
            });
        let _ = writeln!(
            md,
            "| {method} | {} | {a:.2} | {:.0} | {rhs:.0} ({evals_per_step:.0} × {:.2}) | {:.0} | {at} |",
            steps.join(", "),
            b * 1e3,
            t_rhs * 1e9,
            b * 1e3 - rhs
        );
    }
}

/// The basin, fixed-point and right-hand-side timings.
struct Timings {
    /// Median of the three basin runs (s).
    t_basin: f64,
    /// The three basin runs (s), as printed.
    basin_runs: String,
    /// Basin cells that reach the gait.
    gait_cells: usize,
    /// Mean time of the fixed point at the CLI's settings (s).
    t_fp: f64,
    /// One lane-evaluation of the batched right-hand side on 2 threads, on 1 (s).
    t_rhs: f64,
    t_rhs1: f64,
}

fn main() -> anyhow::Result<()> {
    let dir = results_dir("engine")?;
    let load_start = loadavg();
    let sys = Simplest::new(SimplestParams {
        slope: GAMMA,
        ..Default::default()
    })?;
    let guess = GarciaGait::LongPeriod.section_guess(GAMMA);
    let refmap = StrideMap::new(&sys, Options::dop853(1e-14))?;
    let newton_ref = NewtonOptions {
        tol: 1e-13,
        ..NewtonOptions::default()
    };
    let s_ref = find_fixed_point(&refmap, &guess, &newton_ref)
        .context("reference fixed point")?
        .section;
    let p_ref = refmap.stride(&s_ref)?.next;
    let mut rng = ChaCha8Rng::seed_from_u64(20_261_122);
    let states: Vec<Vec<f64>> = (0..1024)
        .map(|_| {
            s_ref
                .iter()
                .map(|v| v * (1.0 + rng.random_range(-1e-4..1e-4)))
                .collect()
        })
        .collect();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;

    let mut rows = Vec::new();
    for (method, tol, opts) in &settings() {
        rows.push(measure(
            &sys, method, tol, opts, &s_ref, &p_ref, &states, &guess, &pool,
        )?);
    }
    let peer = run_peer();
    let peer_1e10 = add_peer_rows(&peer, &s_ref, &mut rows);
    let tm = basin_and_fixed_point(&sys, &s_ref, &refmap, &guess, &states, &pool)?;
    let load_end = loadavg();
    let tab = results_table(&rows);
    let md = report(&rows, &tab, &peer, peer_1e10, &tm, &load_start, &load_end);
    write_text(&dir, "table.md", &md)?;
    plot(&dir, &rows)?;
    print!("{md}");
    Ok(())
}

/// The settings measured: DOPRI5, DOP853 and DOPRI5 at the peer's settings at each of
/// [`TOLS`], and RK4 at 40, 160 and 640 steps per stride.
fn settings() -> Vec<(&'static str, String, Options)> {
    let mut settings: Vec<(&'static str, String, Options)> = Vec::new();
    for tol in TOLS {
        settings.push(("DOPRI5", sci(tol), Options::dopri5(tol)));
        settings.push(("DOP853", sci(tol), Options::dop853(tol)));
        // DOPRI5 as the peer runs it: elementary controller, every stride from h = 0.05.
        settings.push((
            PEER_SETTINGS,
            sci(tol),
            Options {
                controller: Controller::Elementary,
                h_init: Some(0.05),
                ..Options::dopri5(tol)
            },
        ));
    }
    for n in [40.0, 160.0, 640.0] {
        // RK4 with a fixed step: n steps over the stride period (≈ 3.85).
        settings.push(("RK4", format!("{n} steps"), Options::rk4(3.85 / n)));
    }
    settings
}

/// One setting's row: a stride from the fixed point (scalar, timed), the batched strides of
/// `states` (2 threads, timed), the stride's error against `p_ref` and Newton's against `s_ref`.
#[allow(clippy::too_many_arguments)]
fn measure(
    sys: &Simplest,
    method: &str,
    tol: &str,
    opts: &Options,
    s_ref: &[f64],
    p_ref: &[f64],
    states: &[Vec<f64>],
    guess: &[f64],
    pool: &rayon::ThreadPool,
) -> anyhow::Result<Row> {
    let map = StrideMap::new(sys, *opts)?;
    let mut integ = Integrator::new(4, *opts)?;
    let (st, t) = time_mean(0.4, || map.stride_with(&mut integ, s_ref));
    let st = st?;
    integ.reset_stats();
    map.stride_with(&mut integ, s_ref)?;
    let evals = integ.stats().rhs_evals as f64;
    let steps = (integ.stats().accepted + integ.stats().rejected) as f64;
    let err_stride = pdw_experiments::max_abs_diff(&st.next, p_ref);
    let (_, tb) = time_mean(1.5, || {
        map.strides_par(states, BATCH_LANES, pool, 256, &|_| {})
            .map(|v| v.len())
    });
    // Newton on the plain map at this setting: finite-difference Jacobians (with the
    // variational Jacobian the iterates would follow the variational integration, whose
    // steps are controlled on the tangent block as well — a more accurate map than the one
    // being measured).
    let newton = NewtonOptions {
        tol: (opts.rtol * 100.0).clamp(1e-12, 1e-4),
        dp: DpMethod::FiniteDifference {
            scheme: FdScheme::default(),
            lanes: 8,
        },
        ..NewtonOptions::default()
    };
    let err_fp = match find_fixed_point(&map, guess, &newton) {
        Ok(fp) => pdw_experiments::max_abs_diff(&fp.section, s_ref),
        Err(_) => f64::NAN,
    };
    let row = Row {
        engine: "pdw-sweep",
        method: method.to_string(),
        tol: tol.to_string(),
        scalar_us: t * 1e6,
        batch_us: tb / states.len() as f64 * 1e6,
        evals,
        steps,
        err_fp,
        err_stride,
        print_limited: false,
    };
    eprintln!("{method} {tol}: {:.2} µs/stride", t * 1e6);
    Ok(row)
}

/// The peer's rows (if it ran) added to `rows`; returns its µs per stride at 1e-10.
fn add_peer_rows(
    peer: &Result<Vec<PeerRow>, String>,
    s_ref: &[f64],
    rows: &mut Vec<Row>,
) -> Option<f64> {
    let mut peer_1e10 = None;
    match peer {
        Ok(p) => {
            for &(tol, us, nf, th, thd) in p {
                let err = (th - s_ref[0]).abs().max((thd - s_ref[1]).abs());
                if tol == 1e-10 {
                    peer_1e10 = Some(us);
                }
                rows.push(Row {
                    engine: "C++ peer",
                    method: "DOPRI5".into(),
                    tol: sci(tol),
                    scalar_us: us,
                    batch_us: f64::NAN,
                    evals: nf,
                    steps: f64::NAN,
                    err_fp: err,
                    err_stride: f64::NAN,
                    print_limited: err < 5e-11,
                });
            }
        }
        Err(e) => eprintln!("peer not run: {e}"),
    }
    peer_1e10
}

/// The default basin on 2 threads (no file output), and the fixed point to 1e-12 (CLI); the
/// right-hand side's cost per lane on 2 threads and on 1.
fn basin_and_fixed_point(
    sys: &Simplest,
    s_ref: &[f64],
    refmap: &StrideMap,
    guess: &[f64],
    states: &[Vec<f64>],
    pool: &rayon::ThreadPool,
) -> anyhow::Result<Timings> {
    let fall = Outcome::of_fall;
    let prob = BasinProblem::new(sys, s_ref.to_vec(), &fall);
    let cells = grid_cells(
        s_ref,
        0,
        &linspace(0.15, 0.25, 1000),
        1,
        &linspace(-0.25, -0.15, 1000),
    );
    let mut runs = Vec::new();
    let mut basin = None;
    for _ in 0..3 {
        let (b, t) =
            time_once(|| classify_cells(&prob, &cells, &BasinOptions::default(), pool, &|_| {}));
        runs.push(t);
        basin = Some(b);
    }
    let mut sorted = runs.clone();
    sorted.sort_by(f64::total_cmp);
    let t_basin = sorted[1];
    let basin_runs = runs
        .iter()
        .map(|t| format!("{t:.2}"))
        .collect::<Vec<_>>()
        .join(", ");
    let gait_cells = basin
        .expect("three runs")?
        .iter()
        .filter(|c| c.outcome() == Outcome::Gait)
        .count();
    let (_, t_fp) = time_mean(1.0, || {
        find_fixed_point(refmap, guess, &NewtonOptions::default()).map(|f| f.residual)
    });
    let t_rhs = rhs_per_lane_eval(sys, states, pool);
    let pool1 = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let t_rhs1 = rhs_per_lane_eval(sys, states, &pool1);
    Ok(Timings {
        t_basin,
        basin_runs,
        gait_cells,
        t_fp,
        t_rhs,
        t_rhs1,
    })
}

/// The table of every row.
fn results_table(rows: &[Row]) -> Table {
    let mut tab = Table::new(&[
        "engine",
        "method",
        "tol",
        "µs / stride (scalar)",
        "µs / lane-stride (batch, 2 threads)",
        "RHS evals / stride",
        "ns / eval (scalar)",
        "fixed-point error",
        "stride error",
    ]);
    for r in rows {
        let fmt = |v: f64| {
            if v.is_nan() {
                "–".to_string()
            } else {
                format!("{v:.2}")
            }
        };
        tab.row(vec![
            r.engine.into(),
            r.method.clone(),
            r.tol.clone(),
            fmt(r.scalar_us),
            fmt(r.batch_us),
            format!("{:.0}", r.evals),
            format!("{:.0}", r.scalar_us * 1e3 / r.evals),
            if r.print_limited {
                format!("≤ {} (print-limited)", sci(r.err_fp.max(5e-11)))
            } else {
                sci(r.err_fp)
            },
            if r.err_stride.is_nan() {
                "–".into()
            } else {
                sci(r.err_stride)
            },
        ]);
    }
    tab
}

/// `table.md`: the table, the targets and the cost model.
fn report(
    rows: &[Row],
    tab: &Table,
    peer: &Result<Vec<PeerRow>, String>,
    peer_1e10: Option<f64>,
    tm: &Timings,
    load_start: &str,
    load_end: &str,
) -> String {
    let Timings {
        t_basin,
        ref basin_runs,
        gait_cells,
        t_fp,
        t_rhs,
        t_rhs1,
    } = *tm;
    let pick = |m: &str, t: &str| {
        rows.iter()
            .find(|r| r.engine == "pdw-sweep" && r.method == m && r.tol == t)
            .map(|r| (r.scalar_us, r.batch_us))
    };
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# The engine against a plain C++ DOPRI5, side by side\n"
    );
    let _ = writeln!(
        md,
        "Reproduce: `{}` (≈ 1 min; needs g++ for the peer).\n",
        command("engine")
    );
    let _ = writeln!(
        md,
        "Load average at start: {load_start}; at end: {load_end}. SIMD path: {}.\n",
        pdw_simd::path()
    );
    let _ = writeln!(md, "![time vs accuracy](engine.png)\n");
    let _ = writeln!(md, "{}", tab.markdown());
    let _ = writeln!(md, "## Against the targets\n");
    if let Some(p) = peer_1e10 {
        if let (Some((d5, b5)), Some((d8, b8))) =
            (pick("DOPRI5", &sci(1e-10)), pick("DOP853", &sci(1e-10)))
        {
            let _ = writeln!(md, "| quantity | measured | target |\n|---|---|---|");
            let _ = writeln!(md, "| scalar DOPRI5 1e-10 / peer DOPRI5 1e-10 | {d5:.2} / {p:.2} µs = {:.2}× | ≤ 1.0× |", d5 / p);
            if let Some((e5, _)) = pick(PEER_SETTINGS, &sci(1e-10)) {
                let _ = writeln!(md, "| the same at the peer's settings (elementary controller, h₀ = 0.05) | {e5:.2} / {p:.2} µs = {:.2}× | ≤ 1.0× |", e5 / p);
            }
            let _ = writeln!(md, "| scalar DOP853 1e-10 / peer DOPRI5 1e-10 | {d8:.2} / {p:.2} µs = {:.2}× | ≤ 0.6× |", d8 / p);
            let _ = writeln!(md, "| batched DOP853 1e-10, 2 threads | {b8:.3} µs / lane-stride (DOPRI5: {b5:.3}) | ≤ 0.6 µs |");
            let _ = writeln!(md, "| 1000×1000 basin, 2 threads (no file; median of {basin_runs} s) | {t_basin:.2} s = {:.3} s per µs of the peer's stride | ≤ 0.2 s/µs |", t_basin / p);
            let _ = writeln!(md, "| simplest fixed point to 1e-12 (DOP853 1e-14, CLI settings) | {:.3} ms | ≤ 0.15 ms |", t_fp * 1e3);
        }
    } else {
        let _ = writeln!(
            md,
            "The peer did not run ({}); basin 1000×1000: {t_basin:.2} s; fixed point: {:.3} ms.",
            peer.as_ref().err().cloned().unwrap_or_default(),
            t_fp * 1e3
        );
    }
    let _ = writeln!(md, "\nBasin: {gait_cells} of 10⁶ cells reach the gait.");
    cost_model(&mut md, rows, t_rhs, t_rhs1);
    md
}

/// `engine.png`: time per stride against the fixed point's error, every engine and method.
fn plot(dir: &std::path::Path, rows: &[Row]) -> anyhow::Result<()> {
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for (engine, method) in [
        ("pdw-sweep", "DOPRI5"),
        ("pdw-sweep", PEER_SETTINGS),
        ("pdw-sweep", "DOP853"),
        ("pdw-sweep", "RK4"),
        ("C++ peer", "DOPRI5"),
    ] {
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.engine == engine && r.method == method)
            .map(|r| (r.scalar_us, r.err_fp.max(1e-16)))
            .collect();
        series.push((format!("{engine} {method} (scalar)"), pts));
    }
    for method in ["DOPRI5", "DOP853"] {
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.engine == "pdw-sweep" && r.method == method)
            .map(|r| (r.batch_us, r.err_fp.max(1e-16)))
            .collect();
        series.push((
            format!("pdw-sweep {method} (batched, per lane, 2 threads)"),
            pts,
        ));
    }
    pdw_store::plot_lines(
        dir.join("engine.png"),
        "simplest walker γ = 0.009: time per stride vs fixed-point accuracy",
        "time per stride (µs)",
        "fixed-point error vs DOP853 1e-14 (∞-norm)",
        &series,
        true,
        true,
    )?;
    Ok(())
}
