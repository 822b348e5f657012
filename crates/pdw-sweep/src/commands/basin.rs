//! `pdw-sweep basin`: a basin of attraction over a grid of section states, streamed to HDF5 in
//! row blocks, with a PNG heatmap. See docs/cli.md and docs/hdf5.md.
//!
//! [`run`] reads as the command runs: [`parse`] the flags into the library's basin request
//! ([`pdw::basin`]), claim the outputs, [`plan`] the grid (the gait search and the box, shared
//! with `basin --over` and Python's `basin`), [`discover`] the attractors, open the file
//! ([`open_writer`], [`describe`]), [`compute_rows`], and [`write_results`] (metrics, picture,
//! summary).

use super::fixedpoint::report_failure;
use super::output::{Claim, Format, Output};
use super::{overrides, BuiltModel};
use crate::args::{self, InputError};
use crate::cli::BasinArgs;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use pdw::basin::{AxisFlags, BasinPlan, BasinRequest};
use pdw::limit::basin::{
    basin_metrics_slices, classify_cells, BasinOptions, Outcome, DEFAULT_ENTROPY_BOX,
};
use pdw::limit::{AttractorSet, OrbitValidity};
use pdw::store::format::{UnitContext, BASIN};
use pdw::store::{
    plot_basin_attractors, read_basin, read_basin_outcome, Attractor, BasinHeader, BasinMetrics,
    BasinWriter, ShardSpec, StoreError, ZAxis, BLOCK_ROWS,
};
use pdw::walkers::ModelInfo;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// Default grid of a basin.
const DEFAULT_GRID: &str = "401x401";

/// How the axes are named in messages.
pub(super) const AXIS_FLAGS: AxisFlags = AxisFlags {
    x: "--x",
    y: "--y",
    z: "--z",
};

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

/// Estimated peak memory (bytes) of a basin run on an `nx × ny` grid (rows: ny, or nz·ny for a
/// 3-D grid) with `d` section coordinates and `dim` state components: per-row bookkeeping
/// (axes, done/owned flags, the row list), the cells in flight in one engine call (start
/// states, integrator lanes, results), two pending chunk blocks, the outcome read back for
/// metrics and plot (three copies of nx·rows bytes), HDF5's 32 MiB chunk cache and a fixed
/// allowance.
fn memory_estimate(nx: usize, rows: usize, d: usize, dim: usize) -> u64 {
    let (nx, ny, d, dim) = (nx as u64, rows as u64, d as u64, dim as u64);
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
    pdw::memory::gib(b)
}

/// The grid as written on the command line: `NXxNY` or `NXxNYxNZ`.
fn grid_text(nx: usize, ny: usize, nz: Option<usize>) -> String {
    match nz {
        Some(nz) => format!("{nx}x{ny}x{nz}"),
        None => format!("{nx}x{ny}"),
    }
}

/// Refuses grids whose row of cells exceeds HDF5's chunk limit or whose estimated memory
/// exceeds what is available, before anything is computed (`nz`: the slices of a 3-D grid).
pub(super) fn check_memory(
    nx: usize,
    ny: usize,
    nz: Option<usize>,
    d: usize,
    dim: usize,
) -> Result<(), InputError> {
    let g = grid_text(nx, ny, nz);
    let chunk = BLOCK_ROWS.min(ny) as u64 * nx as u64 * d as u64 * 8;
    if chunk > MAX_CHUNK_BYTES {
        return Err(InputError(format!(
            "--grid {g}: rows of {nx} cells are too wide for the file's chunks ({} per \
             {}-row block, HDF5 allows 4 GiB); at most {} columns",
            gib(chunk),
            BLOCK_ROWS.min(ny),
            MAX_CHUNK_BYTES / (BLOCK_ROWS.min(ny) as u64 * d as u64 * 8)
        )));
    }
    let need = memory_estimate(nx, ny.saturating_mul(nz.unwrap_or(1)), d, dim);
    pdw::memory::check_memory(
        need,
        &format!("--grid {g}"),
        "use a smaller grid, or split it with --shard I/N across machines",
    )
}

/// `--x` or `--y` (`flag`), parsed and resolved against the model's section coordinates.
pub(super) fn axis(
    info: &ModelInfo,
    given: &Option<String>,
    flag: &str,
) -> Result<Option<pdw::basin::Axis>, InputError> {
    let range = given
        .as_deref()
        .map(|s| args::parse_axis(s, flag))
        .transpose()?;
    pdw::basin::resolve_axis(info, range, flag)
}

/// A step's outcome: go on with its value, or end the run with an exit code (its message
/// printed).
enum Step<T> {
    Go(T),
    Exit(ExitCode),
}

/// Ends a step with the exit code `$step` carries, or yields its value.
macro_rules! go {
    ($step:expr) => {
        match $step {
            Step::Go(v) => v,
            Step::Exit(code) => return Ok(code),
        }
    };
}

/// The command line, parsed and checked.
struct Parsed {
    req: BasinRequest,
    /// The model as named (its section coordinates name the grid's axes).
    info: ModelInfo,
    m: BuiltModel,
    shard: Option<ShardSpec>,
    out: PathBuf,
    png: PathBuf,
    /// The z-slice the picture draws (`--slice`; default the middle one).
    slice: Option<usize>,
}

impl Parsed {
    fn names(&self) -> &[String] {
        &self.info.section_names
    }
}

pub fn run(a: &BasinArgs) -> anyhow::Result<ExitCode> {
    if a.over.is_some() {
        return super::basin_over::run(a);
    }
    let t0 = Instant::now();
    // Signals first: Ctrl-C or SIGTERM at any moment exits 130, leaving a resumable file. The
    // handler sets the process-wide stop flag (pdw::hybrid::interrupt), which every integration
    // polls: the gait search, attractor discovery and a block of cells in progress end within
    // milliseconds, and their partial results are thrown away. A second handler cannot be
    // installed in tests that call run() twice; ignore that.
    let _ = ctrlc::set_handler(pdw::hybrid::interrupt::request);
    let p = parse(a)?;
    let mut claim = claim_outputs(a, &p)?;
    let plan = go!(plan(a, &p)?);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads)
        .build()?;
    let (set, seeds) = go!(discover(a, &p, &plan, &pool)?);
    warn_gait_drift(&p, &plan)?;
    let header = header(&p, &plan, &set, seeds);
    let mut writer = go!(open_writer(a, &p, &plan, &header, &mut claim)?);
    let described = describe(a, &p, &plan, &set, &mut writer)?;
    let todo = rows_to_do(&writer, &p);
    warn_slow_attractors(a, &set);
    if compute_rows(a, &p, &plan, &set, &pool, &mut writer, &todo)? {
        writer.close()?;
        eprintln!(
            "interrupted: finished rows are in {}; continue with --resume",
            p.out.display()
        );
        return Ok(ExitCode::from(130));
    }
    write_results(a, &p, &set, writer, &described, todo.len(), t0)?;
    Ok(ExitCode::SUCCESS)
}

/// The stop request of an interrupt (see [`run`]).
fn stopped() -> bool {
    pdw::hybrid::interrupt::requested()
}

/// An interrupt before the file was opened: nothing written, exit 130.
fn nothing_written<T>() -> Step<T> {
    eprintln!("interrupted before the grid was started; nothing written");
    Step::Exit(ExitCode::from(130))
}

/// Everything checked before any file is touched: the grid, integrator, shard, model (with
/// `--set` split into parameters and fixed section coordinates), memory and axes.
fn parse(a: &BasinArgs) -> anyhow::Result<Parsed> {
    let (grid, nz) = grid_dims(a)?;
    let integrator = super::integrator(&a.integrator, BasinOptions::default_integrator())?;
    let shard = match &a.shard {
        Some(s) => {
            let (index, count) = args::parse_shard(s)?;
            Some(ShardSpec { index, count })
        }
        None => None,
    };
    let info = pdw::walkers::model_info(&a.model.model).map_err(|e| InputError(e.to_string()))?;
    pdw::basin::check_section(&info, "grid")?;
    check_memory(
        grid.0,
        grid.1,
        nz,
        info.section_names.len(),
        info.state_names.len(),
    )?;
    let (params, fixed) = pdw::basin::split_overrides(overrides(&a.model)?, &info.section_names);
    let m = pdw::build(&a.model.model, &params)?;
    let z = axis(&info, &a.z, "--z")?.zip(nz);
    let req = BasinRequest {
        grid,
        x: axis(&info, &a.x, "--x")?,
        y: axis(&info, &a.y, "--y")?,
        z,
        fixed,
        max_strides: a.max_strides,
        integrator,
    };
    let out = a.out_path();
    let png = a.png.clone().unwrap_or_else(|| out.with_extension("png"));
    let slice = match (&a.slice, &req.z) {
        (Some(text), Some((z, nz))) => Some(slice_index(&parse_slice(text)?, z, *nz)?),
        _ => None,
    };
    Ok(Parsed {
        req,
        info,
        m,
        shard,
        out,
        png,
        slice,
    })
}

/// `--grid` as (nx, ny) and, for a 3-D grid, nz: three sizes exactly when `--z` is given.
fn grid_dims(a: &BasinArgs) -> Result<((usize, usize), Option<usize>), InputError> {
    let text = a.grid.as_deref().unwrap_or(DEFAULT_GRID);
    let dims = args::parse_grid_dims("--grid", text)?;
    match (dims.len(), a.z.is_some()) {
        (2, false) => Ok(((dims[0], dims[1]), None)),
        (3, true) => Ok(((dims[0], dims[1]), Some(dims[2]))),
        (3, false) => Err(InputError(format!(
            "--grid {text} has three sizes, but no --z axis was given; give --z NAME=A:B for a \
             3-D grid, or --grid NXxNY"
        ))),
        _ => Err(InputError(format!(
            "--z needs a 3-D grid: --grid NXxNYxNZ (e.g. {}x5), not '{text}'",
            text.trim()
        ))),
    }
}

/// The slice of the `nz` z values over axis `z` nearest `--slice NAME=VALUE`; NAME must be the
/// z coordinate (or `z`) and VALUE within its range.
fn slice_index(
    (name, v): &(String, f64),
    z: &pdw::basin::Axis,
    nz: usize,
) -> Result<usize, InputError> {
    let r = &z.range;
    if *name != r.name && name != "z" {
        return Err(InputError(format!(
            "--slice {name}={v}: the slices are of the --z coordinate '{}'; give --slice {}=VALUE",
            r.name, r.name
        )));
    }
    let tol = 1e-9 * (r.hi - r.lo);
    if *v < r.lo - tol || *v > r.hi + tol {
        return Err(InputError(format!(
            "--slice {name}={v}: outside the --z range {}:{}",
            r.lo, r.hi
        )));
    }
    let zs = pdw::limit::basin::linspace(r.lo, r.hi, nz);
    let k = (0..nz)
        .min_by(|&i, &j| (zs[i] - v).abs().total_cmp(&(zs[j] - v).abs()))
        .unwrap_or(0);
    Ok(k)
}

/// `--slice NAME=VALUE`.
fn parse_slice(s: &str) -> Result<(String, f64), InputError> {
    let bad = || {
        InputError(format!(
            "--slice: '{s}' is not of the form NAME=VALUE (e.g. z=0.3)"
        ))
    };
    let (n, v) = s.split_once('=').ok_or_else(bad)?;
    let v: f64 = v.trim().parse().map_err(|_| bad())?;
    if !v.is_finite() {
        return Err(bad());
    }
    Ok((n.trim().to_string(), v))
}

/// Claims `--out` and (unless a shard, which writes no picture) `--png`. With --resume an
/// existing --out is expected, and an existing picture is refused in [`open_writer`] unless
/// the file turns out complete (then nothing is written).
fn claim_outputs(a: &BasinArgs, p: &Parsed) -> Result<Claim, InputError> {
    let mut outputs = vec![Output {
        flag: "--out",
        path: &p.out,
        format: Format::Hdf5,
        may_exist: a.resume,
    }];
    if p.shard.is_none() {
        outputs.push(Output {
            flag: "--png",
            path: &p.png,
            format: Format::Png,
            may_exist: a.resume,
        });
    }
    let inputs: Vec<_> = super::output::model_input(&a.model.model)
        .into_iter()
        .collect();
    super::output::claim(&outputs, &inputs, a.force).map_err(|e| {
        if e.0.contains("; pass --force to overwrite") && e.0.starts_with("--out") {
            InputError(format!("{}, or --resume to continue it", e.0))
        } else {
            e
        }
    })
}

/// The period-one gaits (the stable one, if any, is the selected gait, code 0) and the grid:
/// centred on the stable gait, else on the first period-one orbit ([`pdw::basin`]).
fn plan(a: &BasinArgs, p: &Parsed) -> anyhow::Result<Step<BasinPlan>> {
    if !a.quiet {
        eprintln!(
            "finding the period-one gaits from {} guess(es) (Ctrl-C stops)",
            pdw::gaits::model_guesses(p.m.walker.as_ref()).len()
        );
    }
    let searched = pdw::basin::find_gaits(&p.m);
    if stopped() {
        return Ok(nothing_written());
    }
    let gaits = searched?;
    let Some(centre) = pdw::basin::grid_centre(&p.m, &gaits, p.req.axes_given()) else {
        eprintln!(
            "error: no period-one orbit found for model '{}' at slope {} to centre the \
             default grid on; give both --x and --y",
            p.info.name,
            p.m.slope()
        );
        for (label, g, e) in &gaits.failed {
            report_failure(label, g, e);
        }
        return Ok(Step::Exit(ExitCode::from(2)));
    };
    let bx = pdw::basin::choose_box(&p.req, p.names(), &centre, AXIS_FLAGS, "grid")?;
    Ok(Step::Go(BasinPlan::new(&p.req, bx, gaits, centre)))
}

/// Every attractor reached from the grid's box, found up front from a fixed seed set
/// (identical for every shard and thread count; see [`pdw::limit::attractors`]), with the
/// number of seeds.
fn discover(
    a: &BasinArgs,
    p: &Parsed,
    plan: &BasinPlan,
    pool: &rayon::ThreadPool,
) -> anyhow::Result<Step<(AttractorSet, usize)>> {
    let t_disc = Instant::now();
    let discovered = plan.attractors(&p.m, pool);
    if stopped() {
        return Ok(nothing_written());
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
                    .map(|at| match &at.validity {
                        OrbitValidity::Invalid(_) => {
                            format!("{} ({})", at.name, at.validity.describe())
                        }
                        _ => at.name.clone(),
                    })
                    .collect::<Vec<_>>()
                    .join(", ")
            }
        );
    }
    Ok(Step::Go((set, seeds)))
}

/// Warns when the cells' integrator moves the gait too far for the classifier to recognise it
/// ([`BasinPlan::gait_drift`]): cells would come out `other` or `timeout`.
fn warn_gait_drift(p: &Parsed, plan: &BasinPlan) -> anyhow::Result<()> {
    if let Some(r) = plan.gait_drift(&p.m)? {
        let w = pdw::integrator::drift_warning(&plan.opts.integrator, r, plan.opts.tol_gait);
        eprintln!("warning: {w} (cells may come out `other` or `timeout`)");
    }
    Ok(())
}

/// The file's header: the run (command, model, integrator and tolerances), the grid and the
/// legend of the attractors ([`pdw::basin::file_header`], the explorer's too).
fn header(p: &Parsed, plan: &BasinPlan, set: &AttractorSet, seeds: usize) -> BasinHeader {
    let grid = pdw::basin::FileGrid {
        x: (plan.bx.x.range.name.clone(), plan.xs.clone()),
        y: (plan.bx.y.range.name.clone(), plan.ys.clone()),
        z: plan.bx.z.as_ref().map(|z| ZAxis {
            name: z.range.name.clone(),
            values: plan.zs.clone(),
        }),
    };
    pdw::basin::file_header(
        (super::command_line(), p.info.name.to_string()),
        &p.m,
        plan,
        (set, seeds),
        grid,
        p.shard,
    )
}

/// The fixed section coordinates by name.
pub(super) fn fixed_json(
    names: &[String],
    fixed: &[(usize, f64)],
) -> std::collections::BTreeMap<String, f64> {
    fixed.iter().map(|(i, v)| (names[*i].clone(), *v)).collect()
}

/// Opens `--out` (the basin writer takes the output's lock itself, creating or continuing the
/// file). A file already complete for this command ends the run with success, drawing its
/// picture first if it is missing (a run killed between finishing the file and renaming the
/// picture into place); an existing picture is refused when resuming an unfinished file
/// without --force.
fn open_writer(
    a: &BasinArgs,
    p: &Parsed,
    plan: &BasinPlan,
    header: &BasinHeader,
    claim: &mut Claim,
) -> anyhow::Result<Step<BasinWriter>> {
    if stopped() {
        return Ok(nothing_written());
    }
    claim.hand_over(&p.out);
    let writer = match BasinWriter::start(&p.out, header, a.resume, a.force) {
        Ok(w) => w,
        Err(StoreError::AlreadyComplete { .. }) => {
            // A requeued cluster task that had finished: success, nothing to do but the
            // picture, if the kill came before it was in place.
            if p.shard.is_none() && !claim.existed(&p.png) {
                let attractors = read_basin(&p.out)?.attractors;
                plot(a, p, &on_picture(described(p, plan), p, plan), &attractors)?;
                crate::outln!(
                    "{} was missing: drawn from the complete file",
                    p.png.display()
                );
            }
            crate::outln!(
                "{} is already complete for this command (checked: same run, every block's \
                 checksum); nothing to do",
                p.out.display()
            );
            return Ok(Step::Exit(ExitCode::SUCCESS));
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
    if p.shard.is_none() && a.resume && !a.force && claim.existed(&p.png) {
        writer.close()?;
        return Err(InputError(format!(
            "--png: '{}' exists; pass --force to overwrite it (with --resume, only a complete \
             file leaves the picture untouched)",
            p.png.display()
        ))
        .into());
    }
    Ok(Step::Go(writer))
}

/// What the file says about itself, kept for the picture and the attractors' units.
struct Described {
    /// Unit of every section coordinate.
    sec_units: Vec<String>,
    /// The section coordinates along x and y.
    axes: (usize, usize),
    /// The section coordinate along z (3-D grids).
    z: Option<usize>,
    slice: pdw::store::Slice,
}

/// The units, axes and slice of the run, as the file records them (before [`on_picture`]).
fn described(p: &Parsed, plan: &BasinPlan) -> Described {
    let bx = &plan.bx;
    let sec_units = super::section_units(&p.m);
    let gait = plan.gait();
    let slice = basin_slice(
        p.names(),
        &sec_units,
        plan,
        gait.map_or(&plan.centre[..], |fp| &fp.section[..]),
    );
    Described {
        sec_units,
        axes: (bx.x.index, bx.y.index),
        z: bx.z.as_ref().map(|z| z.index),
        slice,
    }
}

/// `d` for the picture: a 3-D grid's picture is one z-slice, and the gait lies on it only
/// within half a z-step.
fn on_picture(mut d: Described, p: &Parsed, plan: &BasinPlan) -> Described {
    if let Some(i) = d.z {
        let g = plan.gait().map_or(plan.centre[i], |fp| fp.section[i]);
        let k = p.slice.unwrap_or(plan.zs.len() / 2);
        d.slice.on_fixed_point &= near_slice(&plan.zs, k, g);
    }
    d
}

/// Self-description: provenance (every numerical option), units, the slice, dimension scales.
fn describe(
    a: &BasinArgs,
    p: &Parsed,
    plan: &BasinPlan,
    set: &AttractorSet,
    writer: &mut BasinWriter,
) -> anyhow::Result<Described> {
    let (opts, bx) = (&plan.opts, &plan.bx);
    let gait = plan.gait();
    let d = described(p, plan);
    let mut options = serde_json::json!({
        "integrator": super::integrator_json(&opts.integrator),
        "max_strides": opts.max_strides,
        "tol_gait": opts.tol_gait,
        "confirm": opts.confirm,
        "tol_recur": opts.tol_recur,
        "max_period": opts.max_period,
        "lanes": opts.lanes,
        "chunk": opts.chunk,
        "grid": [bx.nx, bx.ny],
        "x": {"name": bx.x.range.name, "lo": bx.x.range.lo, "hi": bx.x.range.hi},
        "y": {"name": bx.y.range.name, "lo": bx.y.range.lo, "hi": bx.y.range.hi},
        "fixed_point": gait.map(|fp| serde_json::json!({
            "integrator": super::integrator_json(&pdw::limit::gaits::default_integrator(pdw::basin::GAIT_NEWTON_TOL)),
            "newton_tol": pdw::basin::GAIT_NEWTON_TOL,
            "residual": fp.residual,
            "section": fp.section,
        })),
        "attractors": set.attractors.iter().map(|at| at.name.clone()).collect::<Vec<_>>(),
        "entropy_box": DEFAULT_ENTROPY_BOX,
        "threads": a.threads,
        "shard": a.shard,
    });
    if let Some(z) = &bx.z {
        options["grid"] = serde_json::json!([bx.nx, bx.ny, bx.nz]);
        options["z"] = serde_json::json!({"name": z.range.name, "lo": z.range.lo, "hi": z.range.hi,
            "discovery_levels": plan.discovery_levels()});
    }
    let prov = super::provenance(options);
    let iz = d.z;
    let units = basin_units(&p.m, bx.x.index, bx.y.index, iz);
    let scales = if iz.is_some() {
        pdw::store::provenance::basin_scales_3d()
    } else {
        pdw::store::provenance::basin_scales()
    };
    let coordinates = p.m.coordinates_json();
    writer.annotate(&pdw::store::Annotations {
        provenance: Some(&prov),
        units: &BASIN.units(&units),
        slice: Some(&d.slice),
        scales: &scales,
        coordinates: Some(&coordinates),
    })?;
    Ok(on_picture(d, p, plan))
}

/// The rows still to compute, warning about rows found damaged on disk (recomputed).
fn rows_to_do(writer: &BasinWriter, p: &Parsed) -> Vec<usize> {
    let damaged = writer.damaged_rows();
    if !damaged.is_empty() {
        eprintln!(
            "warning: {} row(s) of {} were damaged on disk (checksum or content); recomputing them",
            damaged.len(),
            p.out.display()
        );
    }
    writer.rows_todo()
}

/// Warns about attractors whose cells need more strides than --max-strides
/// ([`pdw::basin::slow_attractors`]): near a bifurcation (|λ| → 1) the default budget labels
/// converging cells `timeout`.
fn warn_slow_attractors(a: &BasinArgs, set: &AttractorSet) {
    for s in pdw::basin::slow_attractors(set, a.max_strides) {
        let at = s.attractor;
        eprintln!(
            "warning: attractor `{}`: its slowest multiplier has |λ| = {:.4} per {} \
             stride(s); cells converge in about {} strides, more than --max-strides \
             {}: expect `timeout` where `{}` is slow",
            at.name, s.modulus, at.period_k, s.strides, a.max_strides, at.name
        );
    }
}

/// A progress bar over `total` cells on stderr (hidden with --quiet or off a terminal).
pub(super) fn progress_bar(quiet: bool, total: u64, template: &str) -> ProgressBar {
    let pb = if quiet || !std::io::stderr().is_terminal() {
        ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden())
    } else {
        ProgressBar::new(total)
    };
    pb.set_style(ProgressStyle::with_template(template).expect("valid template"));
    pb
}

/// The rows `todo`, classified and written block by block: consecutive rows per engine call,
/// as many as fit the call's time and memory budget. Returns whether an interrupt stopped it
/// (a block cut short is not written: its cells would be wrong).
fn compute_rows(
    a: &BasinArgs,
    p: &Parsed,
    plan: &BasinPlan,
    set: &AttractorSet,
    pool: &rayon::ThreadPool,
    writer: &mut BasinWriter,
    todo: &[usize],
) -> anyhow::Result<bool> {
    let nx = plan.bx.nx;
    let fall = Outcome::of_fall;
    let problem = set.problem(p.m.walker.as_ref(), &fall);
    let pb = progress_bar(
        a.quiet,
        (todo.len() * nx) as u64,
        "{elapsed_precise} [{wide_bar}] {pos}/{len} cells  {per_sec}  ETA {eta}",
    );
    let (mut k, mut rows_written) = (0, 0);
    let mut interrupted = false;
    let mut secs_per_row: Option<f64> = None;
    let signal_after = signal_after_rows();
    let stall_after = test_hook("PDW_SWEEP_STALL_AFTER_ROWS");
    while k < todo.len() {
        if stopped() {
            interrupted = true;
            break;
        }
        let max_rows = match signal_after.or(stall_after) {
            Some(_) => 1,
            None => rows_for_next_call(secs_per_row, nx),
        };
        let end = consecutive_end(todo, k, max_rows);
        let call_start = Instant::now();
        let rows = &todo[k..end];
        let done_before = pb.position();
        let res = classify_cells(&problem, &plan.row_cells(rows), &plan.opts, pool, &|n| {
            pb.set_position(done_before + n as u64)
        });
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
        if stall_after == Some(rows_written) {
            // the test kills the process here (SIGKILL: no handler runs, nothing is closed)
            loop {
                std::thread::sleep(Duration::from_secs(1));
            }
        }
    }
    pb.finish_and_clear();
    Ok(interrupted)
}

/// End of the run of consecutive rows of `todo` that starts at `k`, at most `max_rows` long.
fn consecutive_end(todo: &[usize], k: usize, max_rows: usize) -> usize {
    let mut end = k + 1;
    while end < todo.len() && end - k < max_rows && todo[end] == todo[end - 1] + 1 {
        end += 1;
    }
    end
}

/// Metrics (whole grids only), the attractors and their units, the picture and the summary;
/// a shard says how to join it.
fn write_results(
    a: &BasinArgs,
    p: &Parsed,
    set: &AttractorSet,
    writer: BasinWriter,
    described: &Described,
    rows: usize,
    t0: Instant,
) -> anyhow::Result<()> {
    let (nx, ny) = p.req.grid;
    let nz = p.req.z.as_ref().map_or(1, |(_, n)| *n);
    let attractors: Vec<Attractor> = set
        .attractors
        .iter()
        .map(pdw::basin::store_attractor)
        .collect();
    let legend = set.legend();
    let out_metrics = if p.shard.is_none() {
        let outcome = writer.read_outcome()?;
        let flat: Vec<u8> = outcome.iter().copied().collect();
        let m = basin_metrics_slices(&flat, nx, ny, nz, DEFAULT_ENTROPY_BOX)?;
        Some(store_metrics(&m, &legend, nx, ny))
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
    let (ix, iy) = described.axes;
    pdw::store::annotate(
        &p.out,
        &pdw::store::Annotations {
            provenance: None,
            units: &BASIN.units(&basin_units(&p.m, ix, iy, described.z)),
            slice: None,
            scales: &[],
            coordinates: None,
        },
    )?;
    let elapsed = t0.elapsed().as_secs_f64();
    match &out_metrics {
        Some(mt) => {
            plot(a, p, described, &attractors)?;
            print_summary(a, p, mt, &attractors, elapsed);
        }
        None => crate::outln!(
            "shard {} of {}: {} rows written to {} in {:.2} s; join the shards with `pdw-sweep merge`",
            p.shard.map(|s| s.index).unwrap_or(0),
            p.shard.map(|s| s.count).unwrap_or(1),
            rows,
            p.out.display(),
            elapsed
        ),
    }
    Ok(())
}

/// The PNG heatmap of the finished file (of a 3-D grid: the chosen z-slice, recorded in
/// `/slice`). Orbit points are drawn only where the slice passes through the gait: off the
/// slice their projection would mislead.
fn plot(
    a: &BasinArgs,
    p: &Parsed,
    described: &Described,
    attractors: &[Attractor],
) -> anyhow::Result<()> {
    let (h, outcome) = read_basin_outcome(&p.out)?;
    let slice = &described.slice;
    let (ix, iy) = described.axes;
    let u = &described.sec_units;
    let (view, label) = match (&h.z, described.z) {
        (Some(z), Some(iz)) => {
            let k = p.slice.unwrap_or(z.values.len() / 2);
            let (view, label) = slice_view(&p.out, &h, &outcome, k, &u[iz])?;
            (view, Some(label))
        }
        _ => (outcome, None),
    };
    let budget = u32::from(a.max_strides);
    let title = basin_title(&p.info.name, p.m.slope(), budget, slice, label.as_deref());
    let shown: &[Attractor] = if slice.on_fixed_point {
        attractors
    } else {
        &[]
    };
    plot_basin_attractors(
        &p.png,
        &labelled(&h, &u[ix], &u[iy]),
        view.view(),
        shown,
        &title,
    )?;
    Ok(())
}

/// Whether `g` lies within half a z-step of slice `k` of `zs` (the slice passes through it).
fn near_slice(zs: &[f64], k: usize, g: f64) -> bool {
    let step = if zs.len() > 1 {
        (zs[zs.len() - 1] - zs[0]) / (zs.len() - 1) as f64
    } else {
        0.0
    };
    (g - zs[k]).abs() <= 0.5 * step + 1e-12 * (1.0 + g.abs())
}

/// Slice `k` of a 3-D basin's (rows × nx) `outcome`, written into the file's `/slice`
/// ([`pdw::store::provenance::write_slice_view`]), and its label for the picture's title
/// (`hip_rate = 0.3 rad/s`, `unit` the z coordinate's).
pub(super) fn slice_view(
    path: &std::path::Path,
    h: &BasinHeader,
    outcome: &pdw::store::ndarray::Array2<u8>,
    k: usize,
    unit: &str,
) -> anyhow::Result<(pdw::store::ndarray::Array2<u8>, String)> {
    let z = h.z.as_ref().expect("a 3-D grid");
    let ny = h.ny();
    let view = outcome
        .slice(pdw::store::ndarray::s![k * ny..(k + 1) * ny, ..])
        .to_owned();
    let v = z.values[k];
    pdw::store::provenance::write_slice_view(path, &z.name, k, v, view.view())?;
    let label = format!(
        "{} = {} {unit} (slice {} of {})",
        z.name,
        pdw::store::provenance::short(v),
        k + 1,
        z.values.len()
    );
    Ok((view, label))
}

/// The slice of the section the grid lies on: every coordinate but the two axes, at its
/// `--set` value or the gait's (`gait`: the gait's section state, else the grid's centre).
fn basin_slice(
    names: &[String],
    units: &[String],
    plan: &BasinPlan,
    gait: &[f64],
) -> pdw::store::Slice {
    let (ix, iy, base) = (plan.bx.x.index, plan.bx.y.index, &plan.base);
    let iz = plan.bx.z.as_ref().map(|z| z.index);
    let off_axes = || (0..names.len()).filter(move |&i| i != ix && i != iy && Some(i) != iz);
    let fixed: Vec<(String, f64, String, String)> = off_axes()
        .map(|i| {
            let source = if plan.fixed.iter().any(|(j, _)| *j == i) {
                "--set"
            } else {
                "fixed point"
            };
            (
                names[i].clone(),
                base[i],
                units[i].clone(),
                source.to_string(),
            )
        })
        .collect();
    let on = off_axes().all(|i| (base[i] - gait[i]).abs() <= 1e-12 * (1.0 + gait[i].abs()));
    pdw::store::Slice {
        x: names[ix].clone(),
        y: names[iy].clone(),
        fixed,
        on_fixed_point: on,
    }
}

/// The units of a basin file by path ([`pdw::store::format::BASIN`]'s rules; `iz`: the z
/// coordinate of a 3-D grid).
fn basin_units(m: &pdw::BuiltModel, ix: usize, iy: usize, iz: Option<usize>) -> UnitContext {
    let axes: Vec<usize> = [ix, iy].into_iter().chain(iz).collect();
    pdw::basin::file_units(m, &axes)
}

/// The picture's title: model, slope, stride budget, and the slice when the section has more
/// coordinates than the two axes (`z`: the drawn z-slice of a 3-D grid, as [`slice_view`]
/// labels it).
pub fn basin_title(
    model: &str,
    slope: f64,
    max_strides: u32,
    slice: &pdw::store::Slice,
    z: Option<&str>,
) -> String {
    let slope = pdw::store::provenance::short(slope);
    if slice.fixed.is_empty() && z.is_none() {
        return format!("{model} walker basin, slope {slope} rad, {max_strides} strides");
    }
    // Short enough to fit the picture's width: the slice replaces the stride budget.
    let mut parts: Vec<String> = z.map(str::to_string).into_iter().collect();
    if !slice.fixed.is_empty() {
        parts.push(slice.describe());
    }
    let mut t = format!("{model}, slope {slope} rad | {}", parts.join(", "));
    if !slice.on_fixed_point {
        t.push_str(", gait off slice");
    }
    t
}

/// The header with units in the axis names, for the picture's axis labels.
fn labelled(h: &pdw::store::BasinHeader, ux: &str, uy: &str) -> pdw::store::BasinHeader {
    let mut h = h.clone();
    h.x_name = format!("{} [{ux}]", h.x_name);
    h.y_name = format!("{} [{uy}]", h.y_name);
    h
}

/// The engine's metrics in the file's plain form, one fraction per entry of the file's
/// `legend` (attractor codes named by it). The entropies are NaN ("not defined") when no box of
/// the entropy's size fits the `nx × ny` grid.
pub fn store_metrics(
    m: &pdw::limit::basin::BasinMetrics,
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

/// The summary on stdout: the grid, the fraction of each outcome, the basin entropies and the
/// files written.
fn print_summary(
    a: &BasinArgs,
    p: &Parsed,
    mt: &BasinMetrics,
    attractors: &[Attractor],
    elapsed: f64,
) {
    let (m, (nx, ny)) = (&p.m, p.req.grid);
    let nz = p.req.z.as_ref().map(|(_, n)| *n);
    crate::outln!(
        "basin of the {} walker at slope {} rad: {} cells, up to {} strides, {} thread(s)",
        m.info.name,
        m.slope(),
        grid_text(nx, ny, nz),
        a.max_strides,
        a.threads
    );
    for (name, f) in mt.fractions.iter().filter(|(_, f)| *f > 0.0) {
        let invalid = attractors
            .iter()
            .find(|at| at.name == *name)
            .and_then(|at| at.validity.reasons())
            .map_or(String::new(), |r| {
                format!("  (physically invalid: {})", r.join(", "))
            });
        crate::outln!("  {name:<24} {:>8.4} %{invalid}", 100.0 * f);
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
        "  {:.2} s, {:.0} cells/s; wrote {} and {}",
        elapsed,
        (nx * ny * nz.unwrap_or(1)) as f64 / elapsed,
        p.out.display(),
        p.png.display()
    );
}

/// Test hook: with `PDW_SWEEP_SIGNAL_AFTER_ROWS=N` the grid is computed one row per call and the
/// run sends itself SIGTERM right after writing its N-th row, then waits for the signal handler's
/// stop request; the next row is then never started. A test thereby interrupts a run at an exact
/// row through the real signal path, on every run. Unset in normal use.
fn signal_after_rows() -> Option<usize> {
    test_hook("PDW_SWEEP_SIGNAL_AFTER_ROWS")
}

/// A test hook's row count from the environment variable `name`. With
/// `PDW_SWEEP_STALL_AFTER_ROWS=N` the grid is computed one row per call and the run stops
/// making progress right after writing its N-th row (the rows of complete blocks flushed),
/// without exiting: a test waits until the file shows them, then kills the process with
/// SIGKILL at a known row. Unset in normal use.
fn test_hook(name: &str) -> Option<usize> {
    std::env::var(name).ok()?.parse().ok()
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
    pdw::hybrid::interrupt::request();
    let t0 = Instant::now();
    while !stopped() && t0.elapsed() < Duration::from_secs(30) {
        std::thread::sleep(Duration::from_millis(1));
    }
}
