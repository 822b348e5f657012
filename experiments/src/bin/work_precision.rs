//! Work-precision: accuracy of fixed points, Floquet multipliers and basin labels against CPU
//! time, for fixed-step RK4 and adaptive DOPRI5 / DOP853 (Hairer–Nørsett–Wanner I, §II.4–II.10).
//!
//! For each model (simplest walker at γ = 0.009, compass gait at 3°) and integrator setting, the
//! stable period-one gait is found from the model's own guess with the engine's Newton solver
//! (variational DP, as `pdw-sweep fixedpoint` does). Errors are measured against a reference
//! computed with DOP853 at rtol = atol = 1e-14; the reference itself is cross-checked against
//! DOPRI5 at 1e-13 and RK4 with 20 000 steps per stride (a different method family). The
//! fixed-point error is `‖s − s_ref‖∞`, the multiplier error the largest distance between matched
//! multipliers in ℂ. Time is the mean wall time of one whole fixed-point solve (Newton from the
//! guess, the verification stride and the reported DP), single-threaded.
//!
//! Basins: a 100 × 100 grid of the simplest walker at γ = 0.009 over θ ∈ [0.15, 0.25],
//! θ̇ ∈ [−0.25, −0.15] (the CLI's default window), 100 strides per cell, each setting with its own
//! fixed point; labels compared cell by cell with the reference labels (DOP853 1e-14), time on
//! a 2-thread pool.

use anyhow::Context;
use pdw_experiments::{
    command, fmt_multipliers, max_abs_diff, multiplier_error, results_dir, sci, time_mean,
    time_once, write_text, Table,
};
use pdw_hybrid::Options;
use pdw_limit::{
    basin_metrics, classify_cells, dp_finite_difference, find_fixed_point, grid_cells, linspace,
    multipliers, BasinOptions, BasinProblem, FdScheme, FixedPoint, NewtonOptions, Outcome,
    StrideMap,
};
use pdw_walkers::Walker;
use std::fmt::Write as _;

/// One integrator setting.
#[derive(Clone)]
struct Setting {
    family: &'static str,
    label: String,
    opts: Options,
}

fn settings(
    period: f64,
    rk4_steps: &[f64],
    dopri_tols: &[f64],
    dop853_tols: &[f64],
) -> Vec<Setting> {
    let mut v = Vec::new();
    for &n in rk4_steps {
        v.push(Setting {
            family: "RK4",
            label: format!("RK4 {n} steps/stride (h = {:.3e})", period / n),
            opts: Options::rk4(period / n),
        });
    }
    for &t in dopri_tols {
        v.push(Setting {
            family: "DOPRI5",
            label: format!("DOPRI5 tol {t:.0e}"),
            opts: Options::dopri5(t),
        });
    }
    for &t in dop853_tols {
        v.push(Setting {
            family: "DOP853",
            label: format!("DOP853 tol {t:.0e}"),
            opts: Options::dop853(t),
        });
    }
    v
}

/// Newton tolerances tried in turn: the map computed with a loose integrator is only accurate
/// (and smooth) to about its tolerance, so a tight residual target may be unreachable.
const NEWTON_TOLS: [f64; 5] = [1e-12, 1e-10, 1e-8, 1e-6, 1e-4];

/// Fixed point with `opts`, trying the Newton tolerances in turn; (fixed point, Newton tol).
fn solve(w: &dyn Walker, opts: Options, guess: &[f64]) -> Option<(FixedPoint, f64)> {
    solve_from(w, opts, guess, &NEWTON_TOLS)
}

/// Same with a tighter first Newton target, for the reference and its cross-checks.
fn solve_tight(w: &dyn Walker, opts: Options, guess: &[f64]) -> Option<(FixedPoint, f64)> {
    solve_from(w, opts, guess, &[1e-13, 1e-12, 1e-11])
}

fn solve_from(
    w: &dyn Walker,
    opts: Options,
    guess: &[f64],
    tols: &[f64],
) -> Option<(FixedPoint, f64)> {
    let map = StrideMap::new(w, opts).ok()?;
    for &tol in tols {
        let no = NewtonOptions {
            tol,
            ..NewtonOptions::default()
        };
        if let Ok(fp) = find_fixed_point(&map, guess, &no) {
            return Some((fp, tol));
        }
    }
    None
}

struct FpRow {
    family: &'static str,
    label: String,
    time: f64,
    newton_tol: f64,
    err_fp: f64,
    err_mult: f64,
    iterations: u64,
}

struct ModelResult {
    name: &'static str,
    reference: FixedPoint,
    cross: Vec<(String, f64, f64)>,
    rows: Vec<FpRow>,
}

fn fixed_point_study(
    name: &'static str,
    w: &dyn Walker,
    settings: &[Setting],
) -> anyhow::Result<ModelResult> {
    let guess = w
        .gait_guesses()
        .into_iter()
        .find(|g| g.gait == "stable")
        .context("model has no stable-gait guess")?
        .section;
    let (reference, ref_tol) = solve_tight(w, Options::dop853(1e-14), &guess)
        .context("reference fixed point not found")?;
    eprintln!(
        "{name}: reference s* = {:?}, λ = {}",
        reference.section,
        fmt_multipliers(&reference.multipliers, 12)
    );
    // Cross-checks of the reference with two other methods.
    let mut cross = Vec::new();
    for (label, opts) in [
        ("DOPRI5 tol 1e-13".to_string(), Options::dopri5(1e-13)),
        (
            "RK4 20000 steps/stride".to_string(),
            Options::rk4(reference.metrics.period / 20000.0),
        ),
    ] {
        let (fp, tol) = solve_tight(w, opts, &guess).context("cross-check failed")?;
        cross.push((
            format!("{label} (Newton tol {tol:.0e}; reference: {ref_tol:.0e})"),
            max_abs_diff(&fp.section, &reference.section),
            multiplier_error(&fp.multipliers, &reference.multipliers),
        ));
    }
    // The multipliers a second way: Richardson-extrapolated central differences of the
    // reference map itself (no variational equations, no flow Jacobian).
    let map = StrideMap::new(w, Options::dop853(1e-14))?;
    for rel in [1e-3, 3e-4, 1e-4] {
        let dp = dp_finite_difference(
            &map,
            &reference.section,
            FdScheme::Richardson { rel_step: rel },
            16,
        )?;
        let m = multipliers(&dp, reference.section.len())?;
        cross.push((
            format!("Richardson finite-difference DP of the reference map, rel. step {rel:.0e}"),
            0.0,
            multiplier_error(&m, &reference.multipliers),
        ));
    }
    let mut rows = Vec::new();
    for s in settings {
        let Some((_, newton_tol)) = solve(w, s.opts, &guess) else {
            eprintln!("{name}: {}: no fixed point", s.label);
            rows.push(FpRow {
                family: s.family,
                label: s.label.clone(),
                time: f64::NAN,
                newton_tol: f64::NAN,
                err_fp: f64::INFINITY,
                err_mult: f64::INFINITY,
                iterations: 0,
            });
            continue;
        };
        let map = StrideMap::new(w, s.opts)?;
        let no = NewtonOptions {
            tol: newton_tol,
            ..NewtonOptions::default()
        };
        let (fp, time) = time_mean(0.3, || find_fixed_point(&map, &guess, &no));
        let fp = fp?;
        let row = FpRow {
            family: s.family,
            label: s.label.clone(),
            time,
            newton_tol,
            err_fp: max_abs_diff(&fp.section, &reference.section),
            err_mult: multiplier_error(&fp.multipliers, &reference.multipliers),
            iterations: fp.iterations,
        };
        eprintln!(
            "{name}: {:<40} {:>9.3e} s  fp err {:.2e}  λ err {:.2e}  (Newton tol {:.0e})",
            row.label, row.time, row.err_fp, row.err_mult, row.newton_tol
        );
        rows.push(row);
    }
    Ok(ModelResult {
        name,
        reference,
        cross,
        rows,
    })
}

fn chart(dir: &std::path::Path, m: &ModelResult, title: &str) -> anyhow::Result<()> {
    let mut series = Vec::new();
    for fam in ["RK4", "DOPRI5", "DOP853"] {
        let pts = |f: &dyn Fn(&FpRow) -> f64| {
            m.rows
                .iter()
                .filter(|r| r.family == fam)
                .map(|r| (r.time, f(r).max(1e-17)))
                .collect::<Vec<_>>()
        };
        series.push((format!("{fam}: fixed point"), pts(&|r| r.err_fp)));
        series.push((format!("{fam}: multipliers"), pts(&|r| r.err_mult)));
    }
    pdw_store::plot_lines(
        dir.join(format!("{}.png", m.name)),
        title,
        "CPU time per fixed-point solve (s)",
        "error vs DOP853 1e-14 (∞-norm)",
        &series,
        true,
        true,
    )?;
    Ok(())
}

struct BasinRow {
    family: &'static str,
    label: String,
    time: f64,
    mismatched: usize,
    gait_fraction: f64,
}

fn basin_study(w: &dyn Walker, settings: &[Setting]) -> anyhow::Result<(Vec<BasinRow>, String)> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    let (nx, ny) = (100, 100);
    let xs = linspace(0.15, 0.25, nx);
    let ys = linspace(-0.25, -0.15, ny);
    let guess = w.gait_guesses()[0].section.clone();
    let fall = Outcome::of_fall;
    let run = |opts: Options, gait: &[f64]| -> anyhow::Result<(Vec<u8>, f64)> {
        let problem = BasinProblem::new(w, gait.to_vec(), &fall);
        let cells = grid_cells(gait, 0, &xs, 1, &ys);
        let bo = BasinOptions {
            integrator: opts,
            ..BasinOptions::default()
        };
        let (res, t) = time_once(|| classify_cells(&problem, &cells, &bo, &pool, &|_| {}));
        Ok((res?.iter().map(|c| c.outcome).collect(), t))
    };
    let (ref_fp, _) = solve(w, Options::dop853(1e-14), &guess).context("reference")?;
    let (ref_labels, ref_time) = run(Options::dop853(1e-14), &ref_fp.section)?;
    let m = basin_metrics(&ref_labels, nx, ny, 5)?;
    let mut summary = String::new();
    let _ = writeln!(
        summary,
        "Reference basin (DOP853 1e-14, {nx}×{ny}, 100 strides): {:.2} s on 2 threads; \
         fractions {}; basin entropy {:.4}, boundary entropy {:.4}.",
        ref_time,
        m.fractions
            .iter()
            .filter(|f| f.2 > 0.0)
            .map(|f| format!("{} {:.4}", f.1, f.2))
            .collect::<Vec<_>>()
            .join(", "),
        m.basin_entropy,
        m.boundary_entropy
    );
    let mut rows = Vec::new();
    for s in settings {
        let gait = solve(w, s.opts, &guess)
            .map(|f| f.0.section)
            .unwrap_or_else(|| ref_fp.section.clone());
        // Best of two runs: the machine is shared, the faster run is the less disturbed one.
        let (labels, t1) = run(s.opts, &gait)?;
        let (_, t2) = run(s.opts, &gait)?;
        let mismatched = labels
            .iter()
            .zip(&ref_labels)
            .filter(|(a, b)| a != b)
            .count();
        let gait_fraction = labels
            .iter()
            .filter(|&&c| c == Outcome::Gait.code())
            .count() as f64
            / labels.len() as f64;
        eprintln!(
            "basin: {:<40} {:>7.3} s  mismatched {mismatched}",
            s.label,
            t1.min(t2)
        );
        rows.push(BasinRow {
            family: s.family,
            label: s.label.clone(),
            time: t1.min(t2),
            mismatched,
            gait_fraction,
        });
    }
    Ok((rows, summary))
}

fn main() -> anyhow::Result<()> {
    faer::set_global_parallelism(faer::Par::Seq);
    let dir = results_dir("work_precision")?;
    let rk4 = [20.0, 40.0, 80.0, 160.0, 320.0, 640.0, 1280.0, 2560.0];
    let dopri = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12];
    let dop853 = [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13];

    let simplest = pdw_walkers::build("simplest", &[("slope", 0.009)])?;
    let compass = pdw_walkers::build("compass", &[])?;
    let mut models = Vec::new();
    for (name, w, title) in [
        (
            "simplest",
            simplest.as_ref(),
            "Simplest walker, γ = 0.009: fixed point and multipliers",
        ),
        (
            "compass",
            compass.as_ref(),
            "Compass gait (Goswami preset), slope 3°: fixed point and multipliers",
        ),
    ] {
        let guess = w.gait_guesses()[0].section.clone();
        let period = solve(w, Options::dop853(1e-12), &guess)
            .context("period")?
            .0
            .metrics
            .period;
        let set = settings(period, &rk4, &dopri, &dop853);
        let r = fixed_point_study(name, w, &set)?;
        chart(&dir, &r, title)?;
        models.push(r);
    }

    let bset = settings(
        models[0].reference.metrics.period,
        &[20.0, 40.0, 80.0, 160.0, 320.0],
        &[1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11],
        &[1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11],
    );
    let (brows, bsummary) = basin_study(simplest.as_ref(), &bset)?;
    let mut series = Vec::new();
    for fam in ["RK4", "DOPRI5", "DOP853"] {
        series.push((
            fam.to_string(),
            brows
                .iter()
                .filter(|r| r.family == fam)
                .map(|r| (r.time, r.mismatched as f64))
                .collect(),
        ));
    }
    pdw_store::plot_lines(
        dir.join("basin_simplest.png"),
        "Simplest walker basin 100×100, γ = 0.009: labels differing from DOP853 1e-14",
        "wall time for the grid, 2 threads (s)",
        "cells with a different label (of 10 000)",
        &series,
        true,
        false,
    )?;

    // Tables.
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Work-precision: fixed points, multipliers and basin labels\n"
    );
    let _ = writeln!(
        md,
        "Reproduce: `{}` (≈ 1–2 min on 2 cores).\n",
        command("work_precision")
    );
    let _ = writeln!(
        md,
        "Errors against DOP853 at rtol = atol = 1e-14. Time: mean wall time of one whole \
         fixed-point solve (Newton from the model's guess with variational DP, the independent \
         verification stride, the reported DP), one thread. The Newton tolerance is the first of \
         1e-12, 1e-10, … 1e-4 at which the solve converged with that integrator (a map computed \
         to tolerance τ is only smooth to about τ).\n"
    );
    let mut csv = String::from(
        "model,family,setting,time_s,newton_tol,err_fixed_point,err_multipliers,iterations\n",
    );
    for m in &models {
        let _ = writeln!(md, "## {}\n", m.name);
        let _ = writeln!(md, "![{0}]({0}.png)\n", m.name);
        let _ = writeln!(
            md,
            "Reference: s* = {:?}, period {:.12}, multipliers {}.\n",
            m.reference.section,
            m.reference.metrics.period,
            fmt_multipliers(&m.reference.multipliers, 12)
        );
        let _ = writeln!(md, "Cross-check of the reference:\n");
        for (l, e1, e2) in &m.cross {
            let _ = writeln!(
                md,
                "- {l}: fixed point differs by {}, multipliers by {}",
                sci(*e1),
                sci(*e2)
            );
        }
        let mut t = Table::new(&[
            "setting",
            "time (s)",
            "Newton tol",
            "‖s − s_ref‖∞",
            "multiplier error",
            "Newton its",
        ]);
        for r in &m.rows {
            t.row(vec![
                r.label.clone(),
                sci(r.time),
                sci(r.newton_tol),
                sci(r.err_fp),
                sci(r.err_mult),
                r.iterations.to_string(),
            ]);
            let _ = writeln!(
                csv,
                "{},{},{},{:e},{:e},{:e},{:e},{}",
                m.name, r.family, r.label, r.time, r.newton_tol, r.err_fp, r.err_mult, r.iterations
            );
        }
        let _ = writeln!(md, "\n{}", t.markdown());
    }
    let _ = writeln!(md, "## Basin labels (simplest walker)\n");
    let _ = writeln!(md, "![basin](basin_simplest.png)\n");
    let _ = writeln!(md, "{bsummary}");
    let mut t = Table::new(&[
        "setting",
        "time (s, 2 threads)",
        "cells differing",
        "gait fraction",
    ]);
    let mut bcsv = String::from("family,setting,time_s,mismatched,gait_fraction\n");
    for r in &brows {
        t.row(vec![
            r.label.clone(),
            format!("{:.3}", r.time),
            r.mismatched.to_string(),
            format!("{:.4}", r.gait_fraction),
        ]);
        let _ = writeln!(
            bcsv,
            "{},{},{:e},{},{}",
            r.family, r.label, r.time, r.mismatched, r.gait_fraction
        );
    }
    let _ = writeln!(md, "{}", t.markdown());
    write_text(&dir, "table.md", &md)?;
    write_text(&dir, "fixed_points.csv", &csv)?;
    write_text(&dir, "basin.csv", &bcsv)?;
    Ok(())
}
