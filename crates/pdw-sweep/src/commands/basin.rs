//! `pdw-sweep basin`: a basin of attraction over a grid of section states, streamed to HDF5 in
//! row blocks, with a PNG heatmap. See docs/cli.md and docs/hdf5.md.

use super::fixedpoint::{report_failure, search};
use super::output::{Format, Output};
use super::{build_with, overrides, BuiltModel};
use crate::args::{self, AxisRange, InputError};
use crate::cli::BasinArgs;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use pdw_limit::attractors::{Attractor as LimitAttractor, DiscoveryOptions};
use pdw_limit::basin::{
    basin_metrics, classify_cells, grid_cells, BasinOptions, Outcome, DEFAULT_ENTROPY_BOX,
};
use pdw_store::{
    plot_basin_attractors, read_basin_outcome, Attractor, BasinHeader, BasinMetrics, BasinWriter,
    ShardSpec, StoreError, BLOCK_ROWS,
};
use std::io::IsTerminal;
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// Most rows handed to the engine per call (written and flushed as soon as their block is
/// complete).
const MAX_ROWS_PER_CALL: usize = 4 * BLOCK_ROWS;
/// Most cells per engine call (bounds the memory in flight on wide grids).
const MAX_CELLS_PER_CALL: usize = 1 << 16;
/// Target duration of one engine call: an interrupt is honoured between calls, so this bounds
/// the wait after Ctrl-C. Rows per call adapt to the measured time per row (results do not
/// depend on how the grid is batched).
const CALL_TARGET_S: f64 = 0.4;

/// Rows for the next engine call, from the measured seconds per row so far.
fn rows_for_next_call(secs_per_row: Option<f64>, nx: usize) -> usize {
    let by_cells = (MAX_CELLS_PER_CALL / nx).max(1);
    let by_time = match secs_per_row {
        None => 1,
        Some(t) if t > 0.0 => (CALL_TARGET_S / t).floor().max(1.0) as usize,
        Some(_) => MAX_ROWS_PER_CALL,
    };
    by_time.min(by_cells).min(MAX_ROWS_PER_CALL)
}

/// HDF5's largest chunk (4 GiB − 1 byte).
const MAX_CHUNK_BYTES: u64 = (1 << 32) - 1;

/// Estimated peak memory (bytes) of a basin run on an `nx × ny` grid with `d` section
/// coordinates and `dim` state components: per-row bookkeeping (axes, done/owned flags, the
/// row list), the cells in flight in one engine call (start states, integrator lanes, results),
/// two pending chunk blocks, the outcome read back for metrics and plot (three copies of
/// nx·ny bytes), HDF5's 32 MiB chunk cache and a fixed allowance.
fn memory_estimate(nx: usize, ny: usize, d: usize, dim: usize) -> u64 {
    let (nx, ny, d, dim) = (nx as u64, ny as u64, d as u64, dim as u64);
    let per_row = 56;
    let per_col = 32;
    let per_cell_in_flight = 96 + 24 * d + 8 * dim * 20;
    let cells_in_flight = (MAX_CELLS_PER_CALL as u64).max(nx).min(nx * ny);
    let block = BLOCK_ROWS as u64 * nx * (3 + 8 * d);
    per_row * ny
        + per_col * nx
        + per_cell_in_flight * cells_in_flight
        + 2 * block
        + 3 * nx * ny
        + (96 << 20)
}

pub(super) fn gib(b: u64) -> String {
    format!("{:.1} GiB", b as f64 / (1u64 << 30) as f64)
}

/// Refuses grids whose row of cells exceeds HDF5's chunk limit or whose estimated memory
/// exceeds what is available, before anything is computed.
pub(super) fn check_memory(nx: usize, ny: usize, d: usize, dim: usize) -> Result<(), InputError> {
    let chunk = BLOCK_ROWS.min(ny) as u64 * nx as u64 * d as u64 * 8;
    if chunk > MAX_CHUNK_BYTES {
        return Err(InputError(format!(
            "--grid {nx}x{ny}: rows of {nx} cells are too wide for the file's chunks ({} per \
             {}-row block, HDF5 allows 4 GiB); at most {} columns",
            gib(chunk),
            BLOCK_ROWS.min(ny),
            MAX_CHUNK_BYTES / (BLOCK_ROWS.min(ny) as u64 * d as u64 * 8)
        )));
    }
    let need = memory_estimate(nx, ny, d, dim);
    // `MemAvailable` and the room under the cgroup's limit, whichever is smaller
    let have = pdw_limit::resources::memory_available();
    if need > have * 4 / 5 {
        return Err(InputError(format!(
            "--grid {nx}x{ny}: needs about {} of memory, more than the {} available (80 % of \
             {}); use a smaller grid, or split it with --shard I/N across machines",
            gib(need),
            gib(have * 4 / 5),
            gib(have)
        )));
    }
    Ok(())
}

/// Default half-width of an axis around the fixed point: 25 % of the coordinate, at least 0.05.
/// For the simplest walker at γ = 0.009 this gives θ ∈ [0.150, 0.250], θ̇ ∈ [−0.250, −0.150].
pub(super) fn default_axis(name: &str, centre: f64) -> AxisRange {
    let half = (0.25 * centre.abs()).max(0.05);
    AxisRange {
        name: name.to_string(),
        lo: centre - half,
        hi: centre + half,
    }
}

/// `--set` values: model parameters by name, and fixed section coordinates by index.
pub(super) type SplitSets = (Vec<(String, f64)>, Vec<(usize, f64)>);

/// Splits `--set` into model parameters and fixed section coordinates.
pub(super) fn split_sets(a: &BasinArgs, section_names: &[&str]) -> Result<SplitSets, InputError> {
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
    if a.over.is_some() {
        return super::basin_over::run(a);
    }
    if a.json {
        return Err(InputError(
            "--json: a basin writes its grid to --out (HDF5) and --png; only `basin --over` \
             prints JSON (add --over NAME=A:B:N, or drop --json)"
                .into(),
        )
        .into());
    }
    let t0 = Instant::now();
    // ---- signals first: Ctrl-C or SIGTERM at any moment exits 130, leaving a resumable file
    // The handler sets the process-wide stop flag (pdw_hybrid::interrupt), which every
    // integration polls: the gait search, attractor discovery and a block of cells in progress
    // end within milliseconds, and their partial results are thrown away below.
    // A second handler cannot be installed in tests that call run() twice; ignore that.
    let _ = ctrlc::set_handler(pdw_hybrid::interrupt::request);
    let stopped = pdw_hybrid::interrupt::requested;
    let nothing_written = || {
        eprintln!("interrupted before the grid was started; nothing written");
        Ok(ExitCode::from(130))
    };
    // ---- validate everything before touching any file
    let (nx, ny) = args::parse_grid(a.grid.as_deref().unwrap_or("401x401"))?;
    if a.max_strides == 0 || a.max_strides > u32::from(u16::MAX) {
        return Err(InputError(format!(
            "--max-strides: {} must be between 1 and {}",
            a.max_strides,
            u16::MAX
        ))
        .into());
    }
    let integrator = super::integrator(&a.integrator, BasinOptions::default_integrator())?;
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
    check_memory(nx, ny, names.len(), info.state_names.len())?;
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
    let out = a.out_path();
    let png = a.png.clone().unwrap_or_else(|| out.with_extension("png"));
    // A shard writes no picture. With --resume an existing --out is expected, and an existing
    // picture is refused below unless the file turns out complete (then nothing is written).
    let mut outputs = vec![Output {
        flag: "--out",
        path: &out,
        format: Format::Hdf5,
        may_exist: a.resume,
    }];
    if shard.is_none() {
        outputs.push(Output {
            flag: "--png",
            path: &png,
            format: Format::Png,
            may_exist: a.resume,
        });
    }
    let inputs: Vec<_> = super::output::model_input(&a.model.model)
        .into_iter()
        .collect();
    let mut claim = super::output::claim(&outputs, &inputs, a.force).map_err(|e| {
        if e.0.contains("; pass --force to overwrite") && e.0.starts_with("--out") {
            InputError(format!("{}, or --resume to continue it", e.0))
        } else {
            e
        }
    })?;

    // ---- the period-one gaits: the stable one (if any) is the selected gait, code 0
    let guesses = pdw::gaits::model_guesses(m.walker.as_ref());
    if !a.quiet {
        eprintln!(
            "finding the period-one gaits from {} guess(es) (Ctrl-C stops)",
            guesses.len()
        );
    }
    let searched = search(&m, &guesses, 1e-12);
    if stopped() {
        return nothing_written();
    }
    let (found, failed) = searched?;
    let gait = found.iter().find(|f| f.fp.stable).map(|f| &f.fp);
    // The default grid is centred on the stable gait, else on the first period-one orbit.
    let Some(centre) =
        pdw_limit::grid_centre(m.walker.as_ref(), &found, xa.is_some() && ya.is_some())
    else {
        eprintln!(
            "error: no period-one orbit found for model '{}' at slope {} to centre the \
             default grid on; give both --x and --y",
            info.name,
            m.slope()
        );
        for (label, g, e) in &failed {
            report_failure(label, g, e);
        }
        return Ok(ExitCode::from(2));
    };
    let (ix, xr) = xa.unwrap_or_else(|| (0, default_axis(names[0], centre[0])));
    let (iy, yr) = ya.unwrap_or_else(|| (1, default_axis(names[1], centre[1])));
    if ix == iy {
        return Err(InputError(format!(
            "--x and --y both name '{}'; choose two different coordinates",
            names[ix]
        ))
        .into());
    }
    let mut base = centre.clone();
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
        integrator,
        ..BasinOptions::default()
    };

    // ---- every attractor reached from the grid's box, found up front from a fixed seed set
    // (identical for every shard and thread count; see pdw_limit::attractors)
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads)
        .build()?;
    let walker = m.walker.as_ref();
    let fall = Outcome::of_fall;
    let disc = DiscoveryOptions::default();
    let t_disc = Instant::now();
    let discovered = box_attractors(
        walker,
        &found,
        gait,
        &fixed,
        &base,
        (ix, &xr),
        (iy, &yr),
        &opts,
        &pool,
    );
    if stopped() {
        return nothing_written();
    }
    let (set, seeds) = discovered?;
    if !a.quiet {
        eprintln!(
            "attractors from {} seeds in {:.2} s: {}",
            seeds,
            t_disc.elapsed().as_secs_f64(),
            if set.attractors.is_empty() {
                "none (every seed fell)".to_string()
            } else {
                set.attractors
                    .iter()
                    .map(|at| at.name.clone())
                    .collect::<Vec<_>>()
                    .join(", ")
            }
        );
    }
    // The gait was found on an accurate stride map; the cells run on the basin's integrator.
    // If that map moves the gait by more than a tenth of the gait tolerance, cells converge to
    // a point the classifier does not recognise: say so rather than label them `other`.
    if let Some(fp) = gait {
        let r = super::stride_residual(&m, opts.integrator, &fp.section)?;
        let close_enough = r <= 0.1 * opts.tol_gait;
        if !close_enough {
            eprintln!(
                "warning: with {} the gait is a fixed point only to {r:.2e} (the cells' gait \
                 tolerance is {:e}): cells may come out `other` or `timeout`; use a tighter \
                 --rtol/--atol or a smaller --rk4-step",
                super::integrator_text(&opts.integrator),
                opts.tol_gait
            );
        }
    }
    let header = BasinHeader {
        command: std::env::args().collect::<Vec<_>>().join(" "),
        model: info.name.to_string(),
        slope: m.slope(),
        params: m.params_json().to_string(),
        model_resolved: m.walker.fingerprint(),
        integrator: super::integrator_text(&opts.integrator),
        tolerances: serde_json::json!({
            "rtol": opts.integrator.rtol, "atol": opts.integrator.atol,
            "tol_gait": opts.tol_gait, "tol_recur": opts.tol_recur,
            "confirm": opts.confirm, "max_period": opts.max_period,
            "fixed_point_residual": gait.map(|fp| fp.residual),
            "attractor_seeds": seeds, "seed_strides": disc.seed_strides,
            "chaos_radius": disc.chaos_radius, "chaos_sample": disc.cloud_points,
            "fixed": fixed.iter().map(|(i, v)| (names[*i].to_string(), *v)).collect::<std::collections::BTreeMap<_, _>>(),
        })
        .to_string(),
        max_strides: a.max_strides,
        x_name: names[ix].to_string(),
        x: xs.clone(),
        y_name: names[iy].to_string(),
        y: ys.clone(),
        state_names: names.iter().map(|s| s.to_string()).collect(),
        legend: set.legend(),
        shard,
    };
    // the basin writer takes the output's lock itself, creating or continuing the file
    if stopped() {
        return nothing_written();
    }
    claim.hand_over(&out);
    let mut writer = match BasinWriter::start(&out, &header, a.resume, a.force) {
        Ok(w) => w,
        Err(StoreError::AlreadyComplete { .. }) => {
            // A requeued cluster task that had finished: success, nothing to do.
            crate::outln!(
                "{} is already complete for this command (checked: same run, every block's \
                 checksum); nothing to do",
                out.display()
            );
            return Ok(ExitCode::SUCCESS);
        }
        // A file that is not a readable basin file cannot be continued: say what to do.
        Err(e @ (StoreError::Hdf5 { .. } | StoreError::Format { .. })) if a.resume => {
            return Err(InputError(format!(
                "{e}\n  --resume: it cannot be continued (truncated, damaged or not a basin \
                 file); start it over with --force instead of --resume, or give another --out"
            ))
            .into())
        }
        Err(e) => return Err(e.into()),
    };
    if shard.is_none() && a.resume && !a.force && claim.existed(&png) {
        writer.close()?;
        return Err(InputError(format!(
            "--png: '{}' exists; pass --force to overwrite it (with --resume, only a complete \
             file leaves the picture untouched)",
            png.display()
        ))
        .into());
    }
    // ---- self-description: provenance, units, the slice, dimension scales
    let sec_units = super::section_units(&m);
    let slice = basin_slice(
        names,
        &sec_units,
        ix,
        iy,
        &base,
        gait.map_or(&centre[..], |fp| &fp.section[..]),
        &fixed,
    );
    let options = serde_json::json!({
        "integrator": super::integrator_json(&opts.integrator),
        "max_strides": opts.max_strides,
        "tol_gait": opts.tol_gait,
        "confirm": opts.confirm,
        "tol_recur": opts.tol_recur,
        "max_period": opts.max_period,
        "lanes": opts.lanes,
        "chunk": opts.chunk,
        "grid": [nx, ny],
        "x": {"name": names[ix], "lo": xr.lo, "hi": xr.hi},
        "y": {"name": names[iy], "lo": yr.lo, "hi": yr.hi},
        "fixed_point": gait.map(|fp| serde_json::json!({
            "integrator": super::integrator_json(&pdw_limit::gaits::default_integrator(1e-12)),
            "newton_tol": 1e-12,
            "residual": fp.residual,
            "section": fp.section,
        })),
        "attractors": set.attractors.iter().map(|at| at.name.clone()).collect::<Vec<_>>(),
        "entropy_box": DEFAULT_ENTROPY_BOX,
        "threads": a.threads,
        "shard": a.shard,
    });
    let prov = super::provenance(options);
    let units = basin_units(names, &sec_units, ix, iy);
    let scales = pdw_store::provenance::basin_scales();
    writer.annotate(&pdw_store::Annotations {
        provenance: Some(&prov),
        units: &units,
        slice: Some(&slice),
        scales: &scales,
    })?;
    let damaged = writer.damaged_rows();
    if !damaged.is_empty() {
        eprintln!(
            "warning: {} row(s) of {} were damaged on disk (checksum or content); recomputing them",
            damaged.len(),
            out.display()
        );
    }
    let todo = writer.rows_todo();

    // Strides a perturbation of 1e-2 needs to shrink below the 1e-6 tolerance at an attractor's
    // slowest multiplier (per K strides): near a bifurcation (|λ| → 1) the default budget
    // labels converging cells `timeout`.
    for at in set
        .attractors
        .iter()
        .filter(|at| at.kind == pdw_limit::AttractorKind::Periodic)
    {
        if let Some(lmax) = at.multipliers.first().map(|l| l.modulus()) {
            let needed = (at.period_k as f64 * (1e-4f64).ln() / lmax.ln()).ceil();
            if lmax < 1.0 && needed > f64::from(a.max_strides) {
                eprintln!(
                    "warning: attractor `{}`: its slowest multiplier has |λ| = {lmax:.4} per {} \
                     stride(s); cells converge in about {needed} strides, more than --max-strides \
                     {}: expect `timeout` where `{}` is slow",
                    at.name, at.period_k, a.max_strides, at.name
                );
            }
        }
    }
    let problem = set.problem(walker, &fall);

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
    let mut secs_per_row: Option<f64> = None;
    let signal_after = signal_after_rows();
    let mut rows_written = 0;
    while k < todo.len() {
        if stopped() {
            interrupted = true;
            break;
        }
        // Consecutive rows only, as many as fit the call's time and memory budget.
        let max_rows = match signal_after {
            Some(_) => 1,
            None => rows_for_next_call(secs_per_row, nx),
        };
        let mut end = k + 1;
        while end < todo.len() && end - k < max_rows && todo[end] == todo[end - 1] + 1 {
            end += 1;
        }
        let call_start = Instant::now();
        let rows = &todo[k..end];
        let row_ys: Vec<f64> = rows.iter().map(|&r| ys[r]).collect();
        let cells = grid_cells(&base, ix, &xs, iy, &row_ys);
        let done_before = pb.position();
        let res = classify_cells(&problem, &cells, &opts, &pool, &|n| {
            pb.set_position(done_before + n as u64)
        });
        // A block cut short by an interrupt is not written: its cells would be wrong.
        if stopped() {
            interrupted = true;
            break;
        }
        let mut res = res?;
        set.relabel(&mut res);
        let outcome: Vec<u8> = res.iter().map(|c| c.outcome).collect();
        let strides: Vec<u16> = res.iter().map(|c| c.strides).collect();
        let fin: Vec<f64> = res
            .iter()
            .flat_map(|c| c.final_state.iter().copied())
            .collect();
        writer.write_rows(rows[0], &outcome, &strides, &fin)?;
        let t_row = call_start.elapsed().as_secs_f64() / rows.len() as f64;
        // Slowest recent row cost, decaying: a costly band keeps calls short.
        secs_per_row = Some(secs_per_row.map_or(t_row, |t| t_row.max(0.7 * t)));
        k = end;
        rows_written += rows.len();
        if signal_after == Some(rows_written) {
            terminate_self_and_wait(stopped);
        }
    }
    pb.finish_and_clear();
    if interrupted {
        writer.close()?;
        eprintln!(
            "interrupted: finished rows are in {}; continue with --resume",
            out.display()
        );
        return Ok(ExitCode::from(130));
    }

    // ---- metrics, attractors, plot
    let attractors: Vec<Attractor> = set.attractors.iter().map(store_attractor).collect();
    let out_metrics = if shard.is_none() {
        let outcome = writer.read_outcome()?;
        let flat: Vec<u8> = outcome.iter().copied().collect();
        Some(store_metrics(
            &basin_metrics(&flat, nx, ny, DEFAULT_ENTROPY_BOX)?,
            &header.legend,
            nx,
            ny,
        ))
    } else {
        None
    };
    let metrics = out_metrics.clone().unwrap_or(BasinMetrics {
        fractions: Vec::new(),
        basin_entropy: f64::NAN,
        boundary_entropy: f64::NAN,
        entropy_box: DEFAULT_ENTROPY_BOX,
    });
    writer.finish(&metrics, &attractors)?;
    // The attractors exist now: their datasets get units too.
    pdw_store::annotate(
        &out,
        &pdw_store::Annotations {
            provenance: None,
            units: &units,
            slice: None,
            scales: &[],
        },
    )?;
    let elapsed = t0.elapsed().as_secs_f64();
    if let Some(mt) = &out_metrics {
        let (h, outcome) = read_basin_outcome(&out)?;
        // Orbit points are drawn only where the slice passes through the gait: off the slice
        // their projection would mislead.
        let shown: &[Attractor] = if slice.on_fixed_point {
            &attractors
        } else {
            &[]
        };
        let title = basin_title(&info.name, m.slope(), a.max_strides, &slice);
        plot_basin_attractors(
            &png,
            &labelled(&h, &sec_units[ix], &sec_units[iy]),
            outcome.view(),
            shown,
            &title,
        )?;
        print_summary(&m, a, mt, nx, ny, elapsed, &out, Some(&png));
    } else {
        crate::outln!(
            "shard {} of {}: {} rows written to {} in {:.2} s; join the shards with `pdw-sweep merge`",
            shard.map(|s| s.index).unwrap_or(0),
            shard.map(|s| s.count).unwrap_or(1),
            todo.len(),
            out.display(),
            elapsed
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Every attractor reached from the box of a basin grid: [`pdw_limit::box_attractors`] with
/// the axes as given on the command line. Shared by `basin` and `basin --over` (and, through
/// the library, Python's `basin`), so all label the same box identically.
#[allow(clippy::too_many_arguments)]
pub fn box_attractors(
    walker: &dyn pdw_walkers::Walker,
    found: &[super::fixedpoint::Found],
    gait: Option<&pdw_limit::FixedPoint>,
    fixed: &[(usize, f64)],
    base: &[f64],
    (ix, xr): (usize, &AxisRange),
    (iy, yr): (usize, &AxisRange),
    opts: &BasinOptions,
    pool: &rayon::ThreadPool,
) -> anyhow::Result<(pdw_limit::AttractorSet, usize)> {
    Ok(pdw_limit::box_attractors(
        walker,
        found,
        gait,
        fixed,
        base,
        (ix, (xr.lo, xr.hi)),
        (iy, (yr.lo, yr.hi)),
        opts,
        pool,
    )?)
}

/// An attractor in the file's plain form (`period_strides` 0 and no multipliers for a chaotic
/// one, whose `section` is a sample of points on it).
pub fn store_attractor(a: &LimitAttractor) -> Attractor {
    Attractor {
        name: a.name.clone(),
        period_strides: a.period_k as u32,
        period_time: a.period_time,
        section: a.points.clone(),
        multipliers: a.multipliers.iter().map(|l| (l.re, l.im)).collect(),
    }
}

/// The slice of the section the grid lies on: every coordinate but the two axes, at its
/// `--set` value or the gait's.
fn basin_slice(
    names: &[&str],
    units: &[String],
    ix: usize,
    iy: usize,
    base: &[f64],
    gait: &[f64],
    set: &[(usize, f64)],
) -> pdw_store::Slice {
    let fixed: Vec<(String, f64, String, String)> = (0..names.len())
        .filter(|&i| i != ix && i != iy)
        .map(|i| {
            let source = if set.iter().any(|(j, _)| *j == i) {
                "--set"
            } else {
                "fixed point"
            };
            (
                names[i].to_string(),
                base[i],
                units[i].clone(),
                source.to_string(),
            )
        })
        .collect();
    let on = (0..names.len())
        .filter(|&i| i != ix && i != iy)
        .all(|i| (base[i] - gait[i]).abs() <= 1e-12 * (1.0 + gait[i].abs()));
    pdw_store::Slice {
        x: names[ix].to_string(),
        y: names[iy].to_string(),
        fixed,
        on_fixed_point: on,
    }
}

/// The unit of every dataset of a basin file, by path.
fn basin_units(
    names: &[&str],
    units: &[String],
    ix: usize,
    iy: usize,
) -> impl Fn(&str) -> Option<String> {
    let (ux, uy) = (units[ix].clone(), units[iy].clone());
    let list = super::units_list(units);
    let _ = names;
    move |p: &str| -> Option<String> {
        match p {
            "grid/x" => Some(ux.clone()),
            "grid/y" => Some(uy.clone()),
            "basin/outcome" | "basin/strides" | "basin/rows_done" | "basin/block_digest" => {
                Some("1".into())
            }
            "basin/final" => Some(list.clone()),
            _ if p.starts_with("attractors/") && p.ends_with("/section") => Some(list.clone()),
            _ if p.starts_with("attractors/") && p.contains("/multipliers_") => Some("1".into()),
            _ => None,
        }
    }
}

/// The picture's title: model, slope, stride budget, and the slice when the section has more
/// coordinates than the two axes.
pub fn basin_title(model: &str, slope: f64, max_strides: u32, slice: &pdw_store::Slice) -> String {
    let slope = pdw_store::provenance::short(slope);
    if slice.fixed.is_empty() {
        return format!("{model} walker basin, slope {slope} rad, {max_strides} strides");
    }
    // Short enough to fit the picture's width: the slice replaces the stride budget.
    let mut t = format!("{model}, slope {slope} rad | {}", slice.describe());
    if !slice.on_fixed_point {
        t.push_str(", gait off slice");
    }
    t
}

/// The header with units in the axis names, for the picture's axis labels.
fn labelled(h: &pdw_store::BasinHeader, ux: &str, uy: &str) -> pdw_store::BasinHeader {
    let mut h = h.clone();
    h.x_name = format!("{} [{ux}]", h.x_name);
    h.y_name = format!("{} [{uy}]", h.y_name);
    h
}

/// The engine's metrics in the file's plain form, one fraction per entry of the file's
/// `legend` (attractor codes named by it). The entropies are NaN ("not defined") when no box of
/// the entropy's size fits the `nx × ny` grid.
pub fn store_metrics(
    m: &pdw_limit::basin::BasinMetrics,
    legend: &[(u8, String)],
    nx: usize,
    ny: usize,
) -> BasinMetrics {
    let defined = nx >= m.box_size && ny >= m.box_size;
    let or_nan = |v: f64| if defined { v } else { f64::NAN };
    BasinMetrics {
        fractions: legend
            .iter()
            .map(|(c, n)| {
                let f = m
                    .fractions
                    .iter()
                    .find(|(code, _, _)| code == c)
                    .map_or(0.0, |(_, _, f)| *f);
                (n.clone(), f)
            })
            .collect(),
        basin_entropy: or_nan(m.basin_entropy),
        boundary_entropy: or_nan(m.boundary_entropy),
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
    if mt.basin_entropy.is_finite() {
        crate::outln!(
            "  basin entropy S_b = {:.4}, boundary basin entropy S_bb = {:.4} (boxes of {}x{} cells)",
            mt.basin_entropy,
            mt.boundary_entropy,
            mt.entropy_box,
            mt.entropy_box
        );
    } else {
        crate::outln!(
            "  basin entropy: not defined (no {}x{}-cell box fits a {nx}x{ny} grid)",
            mt.entropy_box,
            mt.entropy_box
        );
    }
    crate::outln!(
        "  {:.2} s, {:.0} cells/s; wrote {}{}",
        elapsed,
        (nx * ny) as f64 / elapsed,
        out.display(),
        png.map(|p| format!(" and {}", p.display()))
            .unwrap_or_default()
    );
}

/// Test hook: with `PDW_SWEEP_SIGNAL_AFTER_ROWS=N` the grid is computed one row per call and the
/// run sends itself SIGTERM right after writing its N-th row, then waits for the signal handler's
/// stop request; the next row is then never started. A test thereby interrupts a run at an exact
/// row through the real signal path, on every run. Unset in normal use.
fn signal_after_rows() -> Option<usize> {
    std::env::var("PDW_SWEEP_SIGNAL_AFTER_ROWS")
        .ok()?
        .parse()
        .ok()
}

/// Raises SIGTERM in this process and waits (at most 30 s) until `stopped()` says the handler
/// has requested the stop.
fn terminate_self_and_wait(stopped: fn() -> bool) {
    #[cfg(unix)]
    // SAFETY: raise(3) with a valid signal number; the installed handler only sets a flag.
    unsafe {
        libc::raise(libc::SIGTERM);
    }
    #[cfg(not(unix))]
    pdw_hybrid::interrupt::request();
    let t0 = Instant::now();
    while !stopped() && t0.elapsed() < Duration::from_secs(30) {
        std::thread::sleep(Duration::from_millis(1));
    }
}
