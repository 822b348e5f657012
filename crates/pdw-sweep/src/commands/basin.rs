//! `pdw-sweep basin`: a basin of attraction over a grid of section states, streamed to HDF5 in
//! row blocks, with a PNG heatmap. See shared/DESIGN.md "Basins" and "HDF5 file".

use super::fixedpoint::{report_failure, search};
use super::{build_with, overrides, BuiltModel};
use crate::args::{self, AxisRange, InputError};
use crate::cli::BasinArgs;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use pdw_limit::basin::{
    basin_metrics, classify_cells, grid_cells, legend, BasinOptions, BasinProblem, Outcome,
    DEFAULT_ENTROPY_BOX,
};
use pdw_store::{
    plot_basin, read_basin_outcome, Attractor, BasinHeader, BasinMetrics, BasinWriter, ShardSpec,
    BLOCK_ROWS,
};
use std::io::IsTerminal;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Rows handed to the engine per call: several chunk blocks, so that both threads stay busy,
/// written (and flushed) as soon as they finish.
const ROWS_PER_CALL: usize = 4 * BLOCK_ROWS;

/// Default half-width of an axis around the fixed point: 25 % of the coordinate, at least 0.05.
/// For the simplest walker at γ = 0.009 this gives θ ∈ [0.150, 0.250], θ̇ ∈ [−0.250, −0.150].
fn default_axis(name: &str, centre: f64) -> AxisRange {
    let half = (0.25 * centre.abs()).max(0.05);
    AxisRange {
        name: name.to_string(),
        lo: centre - half,
        hi: centre + half,
    }
}

/// `--set` values: model parameters by name, and fixed section coordinates by index.
type SplitSets = (Vec<(String, f64)>, Vec<(usize, f64)>);

/// Splits `--set` into model parameters and fixed section coordinates.
fn split_sets(a: &BasinArgs, section_names: &[&str]) -> Result<SplitSets, InputError> {
    let mut fixed = Vec::new();
    let mut rest = Vec::new();
    for (n, v) in overrides(&a.model)? {
        match section_names.iter().position(|s| *s == n) {
            Some(i) => fixed.push((i, v)),
            None => rest.push((n, v)),
        }
    }
    Ok((rest, fixed))
}

pub fn run(a: &BasinArgs) -> anyhow::Result<ExitCode> {
    let t0 = Instant::now();
    // ---- validate everything before touching any file
    let (nx, ny) = args::parse_grid(&a.grid)?;
    if a.max_strides == 0 || a.max_strides > u32::from(u16::MAX) {
        return Err(InputError(format!(
            "--max-strides: {} must be between 1 and {}",
            a.max_strides,
            u16::MAX
        ))
        .into());
    }
    if a.threads == 0 || a.threads > 1024 {
        return Err(InputError(format!(
            "--threads: {} must be between 1 and 1024",
            a.threads
        ))
        .into());
    }
    let shard = match &a.shard {
        Some(s) => {
            let (index, count) = args::parse_shard(s)?;
            Some(ShardSpec { index, count })
        }
        None => None,
    };
    let info = pdw_walkers::model_info(&a.model.model).map_err(|e| InputError(e.to_string()))?;
    let names_owned = info.section_names.clone();
    let names: Vec<&str> = names_owned.iter().map(|s| s.as_str()).collect();
    let names = &names[..];
    if names.len() < 2 {
        return Err(InputError(format!(
            "model '{}' has one section coordinate ({}); a basin grid needs two",
            info.name,
            names.join(", ")
        ))
        .into());
    }
    let (param_sets, fixed) = split_sets(a, names)?;
    let m: BuiltModel = build_with(
        &crate::cli::ModelOpts {
            model: a.model.model.clone(),
            slope: None,
            set: Vec::new(),
        },
        &param_sets,
    )?;
    let axis =
        |opt: &Option<String>, flag: &str| -> Result<Option<(usize, AxisRange)>, InputError> {
            let Some(s) = opt else { return Ok(None) };
            let r = args::parse_axis(s, flag)?;
            let i = names.iter().position(|n| *n == r.name).ok_or_else(|| {
                InputError(format!(
                    "{flag}: model '{}' has no section coordinate '{}'; its coordinates are {}",
                    info.name,
                    r.name,
                    names.join(", ")
                ))
            })?;
            Ok(Some((i, r)))
        };
    let xa = axis(&a.x, "--x")?;
    let ya = axis(&a.y, "--y")?;
    let png = a.png.clone().unwrap_or_else(|| a.out.with_extension("png"));
    if !a.resume && !a.force {
        for p in [&a.out, &png] {
            if p.exists() {
                return Err(InputError(format!(
                    "{} exists; pass --force to overwrite it or --resume to continue it",
                    p.display()
                ))
                .into());
            }
        }
    }

    // ---- the attractor: the model's stable gait
    let guesses: Vec<(String, Vec<f64>)> = m
        .walker
        .gait_guesses()
        .into_iter()
        .map(|g| (g.gait.to_string(), g.section))
        .collect();
    let (found, failed) = search(&m, &guesses, 1e-12)?;
    let Some(gait) = found.iter().find(|f| f.fp.stable) else {
        eprintln!(
            "error: no stable period-one gait found for model '{}' at slope {}; a basin needs one",
            info.name,
            m.slope()
        );
        for f in &found {
            eprintln!("  unstable gait at {:?}", f.fp.section);
        }
        for (label, g, e) in &failed {
            report_failure(label, g, e);
        }
        return Ok(ExitCode::from(2));
    };
    let fp = &gait.fp;
    // Strides a perturbation of 1e-2 needs to shrink below the 1e-6 gait tolerance at the slowest
    // multiplier: near a bifurcation (|λ| → 1) the default budget labels converging cells `timeout`.
    if let Some(lmax) = fp.multipliers.first().map(|l| l.modulus()) {
        let needed = ((1e-4f64).ln() / lmax.ln()).ceil();
        if lmax < 1.0 && needed > f64::from(a.max_strides) {
            eprintln!(
                "warning: the gait's slowest multiplier has |λ| = {lmax:.4}; cells converge in about \
                 {needed} strides, more than --max-strides {}: expect `timeout` where the gait is slow",
                a.max_strides
            );
        }
    }
    let (ix, xr) = xa.unwrap_or_else(|| (0, default_axis(names[0], fp.section[0])));
    let (iy, yr) = ya.unwrap_or_else(|| (1, default_axis(names[1], fp.section[1])));
    if ix == iy {
        return Err(InputError(format!(
            "--x and --y both name '{}'; choose two different coordinates",
            names[ix]
        ))
        .into());
    }
    let mut base = fp.section.clone();
    for (i, v) in &fixed {
        if *i == ix || *i == iy {
            return Err(InputError(format!(
                "--set {}: that coordinate is an axis of the grid",
                names[*i]
            ))
            .into());
        }
        base[*i] = *v;
    }
    let xs = pdw_limit::basin::linspace(xr.lo, xr.hi, nx);
    let ys = pdw_limit::basin::linspace(yr.lo, yr.hi, ny);

    let opts = BasinOptions {
        max_strides: a.max_strides as u16,
        ..BasinOptions::default()
    };
    let header = BasinHeader {
        command: std::env::args().collect::<Vec<_>>().join(" "),
        model: info.name.to_string(),
        slope: m.slope(),
        params: m.params_json().to_string(),
        integrator: format!("{:?}", opts.integrator.method),
        tolerances: serde_json::json!({
            "rtol": opts.integrator.rtol, "atol": opts.integrator.atol,
            "tol_gait": opts.tol_gait, "tol_recur": opts.tol_recur,
            "confirm": opts.confirm, "max_period": opts.max_period,
            "fixed_point_residual": fp.residual,
            "fixed": fixed.iter().map(|(i, v)| (names[*i].to_string(), *v)).collect::<std::collections::BTreeMap<_, _>>(),
        })
        .to_string(),
        max_strides: a.max_strides,
        x_name: names[ix].to_string(),
        x: xs.clone(),
        y_name: names[iy].to_string(),
        y: ys.clone(),
        state_names: names.iter().map(|s| s.to_string()).collect(),
        legend: legend().into_iter().map(|(c, n)| (c, n.to_string())).collect(),
        shard,
    };
    let mut writer = BasinWriter::start(&a.out, &header, a.resume, a.force)?;
    let todo = writer.rows_todo();

    // ---- signals: stop between row blocks, leave a resumable file
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        // A second handler cannot be installed in tests that call run() twice; ignore that.
        let _ = ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst));
    }

    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads)
        .build()?;
    let walker = m.walker.as_ref();
    let fall = Outcome::of_fall;
    let problem = BasinProblem::new(walker, fp.section.clone(), &fall);

    let total_cells = (todo.len() * nx) as u64;
    let pb = if a.quiet || !std::io::stderr().is_terminal() {
        ProgressBar::with_draw_target(Some(total_cells), ProgressDrawTarget::hidden())
    } else {
        ProgressBar::new(total_cells)
    };
    pb.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{wide_bar}] {pos}/{len} cells  {per_sec}  ETA {eta}",
        )
        .expect("valid template"),
    );
    let mut k = 0;
    let mut interrupted = false;
    while k < todo.len() {
        if stop.load(Ordering::SeqCst) {
            interrupted = true;
            break;
        }
        // Consecutive rows only, at most ROWS_PER_CALL.
        let mut end = k + 1;
        while end < todo.len() && end - k < ROWS_PER_CALL && todo[end] == todo[end - 1] + 1 {
            end += 1;
        }
        let rows = &todo[k..end];
        let row_ys: Vec<f64> = rows.iter().map(|&r| ys[r]).collect();
        let cells = grid_cells(&base, ix, &xs, iy, &row_ys);
        let done_before = pb.position();
        let res = classify_cells(&problem, &cells, &opts, &pool, &|n| {
            pb.set_position(done_before + n as u64)
        })?;
        let outcome: Vec<u8> = res.iter().map(|c| c.outcome).collect();
        let strides: Vec<u16> = res.iter().map(|c| c.strides).collect();
        let fin: Vec<f64> = res
            .iter()
            .flat_map(|c| c.final_state.iter().copied())
            .collect();
        writer.write_rows(rows[0], &outcome, &strides, &fin)?;
        k = end;
    }
    pb.finish_and_clear();
    if interrupted {
        writer.close()?;
        eprintln!(
            "interrupted: finished rows are in {}; continue with --resume",
            a.out.display()
        );
        return Ok(ExitCode::from(130));
    }

    // ---- metrics, attractor, plot
    let attractor = Attractor {
        name: "gait".into(),
        period_strides: 1,
        period_time: fp.metrics.period,
        section: vec![fp.section.clone()],
        multipliers: fp.multipliers.iter().map(|l| (l.re, l.im)).collect(),
    };
    let out_metrics = if shard.is_none() {
        let outcome = writer.read_outcome()?;
        let flat: Vec<u8> = outcome.iter().copied().collect();
        Some(store_metrics(&basin_metrics(
            &flat,
            nx,
            ny,
            DEFAULT_ENTROPY_BOX,
        )?))
    } else {
        None
    };
    let metrics = out_metrics.clone().unwrap_or(BasinMetrics {
        fractions: Vec::new(),
        basin_entropy: f64::NAN,
        boundary_entropy: f64::NAN,
        entropy_box: DEFAULT_ENTROPY_BOX,
    });
    writer.finish(&metrics, &[attractor])?;
    let elapsed = t0.elapsed().as_secs_f64();
    if let Some(mt) = &out_metrics {
        let (h, outcome) = read_basin_outcome(&a.out)?;
        let marker = Some((fp.section[ix], fp.section[iy]));
        let title = format!(
            "{} walker basin, slope {} rad, {} strides",
            info.name,
            m.slope(),
            a.max_strides
        );
        plot_basin(&png, &h, outcome.view(), marker, &title)?;
        print_summary(&m, a, mt, nx, ny, elapsed, &a.out, Some(&png));
    } else {
        crate::outln!(
            "shard {} of {}: {} rows written to {} in {:.2} s; join the shards with `pdw-sweep merge`",
            shard.map(|s| s.index).unwrap_or(0),
            shard.map(|s| s.count).unwrap_or(1),
            todo.len(),
            a.out.display(),
            elapsed
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// The engine's metrics in the file's plain form.
pub fn store_metrics(m: &pdw_limit::basin::BasinMetrics) -> BasinMetrics {
    BasinMetrics {
        fractions: m
            .fractions
            .iter()
            .map(|(_, n, f)| (n.to_string(), *f))
            .collect(),
        basin_entropy: m.basin_entropy,
        boundary_entropy: m.boundary_entropy,
        entropy_box: m.box_size,
    }
}

#[allow(clippy::too_many_arguments)]
fn print_summary(
    m: &BuiltModel,
    a: &BasinArgs,
    mt: &BasinMetrics,
    nx: usize,
    ny: usize,
    elapsed: f64,
    out: &std::path::Path,
    png: Option<&std::path::Path>,
) {
    crate::outln!(
        "basin of the {} walker at slope {} rad: {}x{} cells, up to {} strides, {} thread(s)",
        m.info.name,
        m.slope(),
        nx,
        ny,
        a.max_strides,
        a.threads
    );
    for (name, f) in mt.fractions.iter().filter(|(_, f)| *f > 0.0) {
        crate::outln!("  {name:<24} {:>8.4} %", 100.0 * f);
    }
    crate::outln!(
        "  basin entropy S_b = {:.4}, boundary basin entropy S_bb = {:.4} (boxes of {}x{} cells)",
        mt.basin_entropy,
        mt.boundary_entropy,
        mt.entropy_box,
        mt.entropy_box
    );
    crate::outln!(
        "  {:.2} s, {:.0} cells/s; wrote {}{}",
        elapsed,
        (nx * ny) as f64 / elapsed,
        out.display(),
        png.map(|p| format!(" and {}", p.display()))
            .unwrap_or_default()
    );
}
