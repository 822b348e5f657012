//! `pdw-sweep basin --over NAME=A:B:N`: basin stability over a model parameter (Menck, Heitzig,
//! Marwan & Kurths, "How basin stability complements the linear-stability paradigm", Nature
//! Physics 9, 89–92, 2013): at each of N evenly spaced values of the parameter, the fraction of
//! one fixed box of section states that reaches each attractor, falls, or neither.
//!
//! Every value is classified exactly as a plain `basin` run on the same box classifies it (the
//! same setup, [`pdw::basin`]: the gait search, the attractor discovery, the engine and its
//! options), so the fractions at a value equal that run's. The box is the same at every value:
//! `--x`/`--y`, else the default box of `basin` around the gait at A (stated in the output).
//!
//! [`run`] reads as the command runs: [`parse`], claim the outputs, [`plan`] (a model per value
//! and the box), the library's [`pdw::basin_over::at_value`] for every value, [`write()`] the
//! file and the chart, and print.

use super::basin::{axis, check_memory, fixed_json, progress_bar, AXIS_FLAGS};
use super::output::{Claim, Format, Output};
use super::overrides;
use crate::args::{self, InputError, Sweep};
use crate::cli::BasinArgs;
use pdw::basin::BasinRequest;
use pdw::basin_over::{AtValue, OverPlan};
use pdw::limit::basin::{BasinOptions, Outcome};
use pdw::limit::{Attractor, AttractorKind, OrbitValidity};
use pdw::store::{StabilityAttractor, StabilityData};
use pdw::walkers::ModelInfo;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

/// Default grid of `--over`: 41 × 41 cells per value.
pub const DEFAULT_OVER_GRID: &str = "41x41";

/// The command line, parsed and checked before any file is touched.
struct Parsed {
    over: Sweep,
    grid: (usize, usize),
    integrator: pdw::hybrid::Options,
    /// The model as named (its section coordinates name the box's axes).
    info: ModelInfo,
    /// Model parameters set on the command line (not the one varied).
    params: Vec<(String, f64)>,
    /// Section coordinates held fixed off the box's axes, by index.
    fixed: Vec<(usize, f64)>,
    out: PathBuf,
    png: PathBuf,
}

/// The file's contents and what the output prints besides.
struct Written {
    data: StabilityData,
    box_json: serde_json::Value,
    params: serde_json::Value,
    unit: String,
}

pub fn run(a: &BasinArgs) -> anyhow::Result<ExitCode> {
    let t0 = Instant::now();
    let p = parse(a)?;
    let _claim = claim_outputs(a, &p)?;
    let plan = plan(a, &p)?;
    let mut at_first = p.params.clone();
    at_first.push((p.over.name.clone(), plan.values[0]));
    pdw::integrator::check_integrator(&pdw::build(&a.model.model, &at_first)?, &p.integrator)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads)
        .build()?;
    let total = (plan.values.len() * p.grid.0 * p.grid.1) as u64;
    let pb = progress_bar(
        a.quiet,
        total,
        "{elapsed_precise} [{wide_bar}] {pos}/{len} cells  {msg}  ETA {eta}",
    );
    let mut results: Vec<AtValue> = Vec::with_capacity(plan.values.len());
    for (i, mu) in plan.values.iter().enumerate() {
        pb.set_message(format!("{} = {mu}", p.over.name));
        results.push(at_value(a, &p, &plan, i, &pool, &pb)?);
    }
    pb.finish_and_clear();
    let w = write(a, &p, &plan, &results, t0)?;
    if a.json {
        print_json(a, &p, &plan, &w)?;
    } else {
        print_table(a, &p, &plan, &w);
    }
    Ok(ExitCode::SUCCESS)
}

/// `--over`, the grid, integrator and model (`--set` split into parameters and fixed section
/// coordinates); the parameter varied must be one of the model's and set nowhere else.
fn parse(a: &BasinArgs) -> anyhow::Result<Parsed> {
    let over = args::parse_range_count(a.over.as_deref().unwrap_or_default(), "--over")?;
    let grid = args::parse_grid(a.grid.as_deref().unwrap_or(DEFAULT_OVER_GRID))?;
    let integrator = super::integrator(&a.integrator, BasinOptions::default_integrator())?;
    let info = pdw::walkers::model_info(&a.model.model).map_err(|e| InputError(e.to_string()))?;
    pdw::basin::check_section(&info, "box")?;
    check_memory(
        grid.0,
        grid.1,
        None,
        info.section_names.len(),
        info.state_names.len(),
    )?;
    let (params, fixed) = pdw::basin::split_overrides(overrides(&a.model)?, &info.section_names);
    pdw::basin_over::check_over(&info, &params, &over, "--over")?;
    let out = a.out_path();
    let png = a.png.clone().unwrap_or_else(|| out.with_extension("png"));
    Ok(Parsed {
        over,
        grid,
        integrator,
        info,
        params,
        fixed,
        out,
        png,
    })
}

/// Claims `--out` and `--png` (one small file written whole: neither may exist without
/// --force).
fn claim_outputs(a: &BasinArgs, p: &Parsed) -> Result<Claim, InputError> {
    let inputs: Vec<_> = super::output::model_input(&a.model.model)
        .into_iter()
        .collect();
    super::output::claim(
        &[
            Output {
                flag: "--out",
                path: &p.out,
                format: Format::Hdf5,
                may_exist: false,
            },
            Output {
                flag: "--png",
                path: &p.png,
                format: Format::Png,
                may_exist: false,
            },
        ],
        &inputs,
        a.force,
    )
}

/// The model at every value and the box ([`pdw::basin_over::plan`]): `--x`/`--y`, else
/// `basin`'s default box around the gait at A, for every value.
fn plan(a: &BasinArgs, p: &Parsed) -> anyhow::Result<OverPlan> {
    let req = BasinRequest {
        grid: p.grid,
        x: axis(&p.info, &a.x, "--x")?,
        y: axis(&p.info, &a.y, "--y")?,
        z: None,
        fixed: p.fixed.clone(),
        max_strides: a.max_strides,
        integrator: p.integrator,
    };
    Ok(pdw::basin_over::plan(
        &a.model.model,
        &p.params,
        &p.over,
        req,
        AXIS_FLAGS,
        "--over",
    )?)
}

/// The box classified at value `i` ([`pdw::basin_over::at_value`]), warning as `basin` warns:
/// cells near a slowly attracting orbit need more strides than given.
fn at_value(
    a: &BasinArgs,
    p: &Parsed,
    plan: &OverPlan,
    i: usize,
    pool: &rayon::ThreadPool,
    pb: &indicatif::ProgressBar,
) -> anyhow::Result<AtValue> {
    let mu = plan.values[i];
    let mut slow = |s: &pdw::basin::SlowAttractor<'_>| {
        let at = s.attractor;
        pb.suspend(|| {
            eprintln!(
                "warning: {} = {mu}: attractor `{}` has |λ| = {:.4} per {} \
                 stride(s); cells converge in about {} strides, more than \
                 --max-strides {}: expect `timeout` there",
                p.over.name, at.name, s.modulus, at.period_k, s.strides, a.max_strides
            )
        });
    };
    let done = pb.position();
    Ok(pdw::basin_over::at_value(plan, i, pool, &mut slow, &|k| {
        pb.set_position(done + k as u64)
    })?)
}

/// An attractor in the file's form (period 0 for a chaotic one).
fn stability_attractor(at: &Attractor) -> StabilityAttractor {
    StabilityAttractor {
        name: at.name.clone(),
        period_strides: if at.kind == AttractorKind::Chaotic {
            0
        } else {
            at.period_k as u32
        },
        period_time: at.period_time.is_finite().then_some(at.period_time),
        points: at.points.clone(),
        multipliers: at.multipliers.iter().map(|l| [l.re, l.im]).collect(),
        validity: match &at.validity {
            OrbitValidity::Unchecked => "not checked",
            OrbitValidity::Valid => "valid",
            OrbitValidity::Invalid(_) => "invalid",
        }
        .to_string(),
        invalid_reasons: match &at.validity {
            OrbitValidity::Invalid(r) => r.iter().map(|s| s.to_string()).collect(),
            _ => Vec::new(),
        },
    }
}

/// The file (HDF5, with provenance and units) and the stacked chart.
fn write(
    a: &BasinArgs,
    p: &Parsed,
    plan: &OverPlan,
    results: &[AtValue],
    t0: Instant,
) -> anyhow::Result<Written> {
    let (over, bx, names) = (&p.over, &plan.bx, &p.info.section_names);
    let (x, y) = (&bx.x.range, &bx.y.range);
    let columns = pdw::basin_over::columns(results);
    let unit = super::param_unit(&plan.models[0], &over.name);
    let sec_units = super::section_units(&plan.models[0]);
    let box_json = serde_json::json!({
        "x": {"name": x.name, "lo": x.lo, "hi": x.hi, "n": bx.nx, "unit": sec_units[bx.x.index]},
        "y": {"name": y.name, "lo": y.lo, "hi": y.hi, "n": bx.ny, "unit": sec_units[bx.y.index]},
        "fixed": fixed_json(names, &plan.req.fixed),
        "off_axis": "other section coordinates at each value's period-one gait (else --set)",
        "source": plan.box_source,
    });
    let opts = plan.req.options();
    let options = serde_json::json!({
        "integrator": super::integrator_json(&opts.integrator),
        "max_strides": opts.max_strides,
        "tol_gait": opts.tol_gait,
        "confirm": opts.confirm,
        "tol_recur": opts.tol_recur,
        "max_period": opts.max_period,
        "grid": [bx.nx, bx.ny],
        "over": {"name": over.name, "from": over.lo, "to": over.hi, "n": over.n, "unit": unit},
        "threads": a.threads,
    });
    let mut params = plan.models[0].params_json();
    if let Some(o) = params.as_object_mut() {
        o.remove(&over.name);
    }
    let data = StabilityData {
        command: super::command_line(),
        model: p.info.name.to_string(),
        parameter: over.name.clone(),
        params: params.to_string(),
        box_json: box_json.to_string(),
        max_strides: u32::from(a.max_strides),
        values: plan.values.clone(),
        columns: columns.iter().map(|c| c.0.clone()).collect(),
        kinds: columns.iter().map(|c| c.1.to_string()).collect(),
        fractions: pdw::basin_over::fraction_table(results, &columns),
        outcome_columns: Outcome::CELL_ENDS
            .iter()
            .map(|o| o.name().to_string())
            .collect(),
        outcome_fractions: results.iter().map(|r| r.outcomes.clone()).collect(),
        attractors: results
            .iter()
            .map(|r| r.attractors.iter().map(stability_attractor).collect())
            .collect(),
        settings: vec![("options".into(), options.to_string())],
        elapsed_s: t0.elapsed().as_secs_f64(),
    };
    // the claim refused an existing file without --force; its placeholder is replaced
    pdw::store::write_stability(&p.out, true, &data)?;
    annotate(&p.out, options, &unit, &plan.models[0].coordinates_json())?;
    let title = format!(
        "{} walker: basin stability, {}x{} box {} x {}",
        p.info.name, bx.nx, bx.ny, x.name, y.name
    );
    pdw::store::plot_basin_stability(&p.png, &data, &format!("{} [{unit}]", over.name), &title)?;
    Ok(Written {
        data,
        box_json,
        params,
        unit,
    })
}

/// Provenance (every numerical option) and units on the file.
fn annotate(
    out: &std::path::Path,
    options: serde_json::Value,
    unit: &str,
    coordinates: &str,
) -> anyhow::Result<()> {
    let prov = super::provenance(options);
    let pu = unit.to_string();
    let units = move |p: &str| -> Option<String> {
        match p {
            "parameter" => Some(pu.clone()),
            "fractions" | "outcome_fractions" => Some("1".into()),
            _ => None,
        }
    };
    pdw::store::annotate(
        out,
        &pdw::store::Annotations {
            provenance: Some(&prov),
            units: &units,
            slice: None,
            scales: &[],
            coordinates: Some(coordinates),
        },
    )?;
    Ok(())
}

/// `--json`: the fractions at every value as one JSON object.
fn print_json(a: &BasinArgs, p: &Parsed, plan: &OverPlan, w: &Written) -> anyhow::Result<()> {
    let data = &w.data;
    let j = serde_json::json!({
        "model": data.model,
        "parameter": data.parameter,
        "parameter_unit": w.unit,
        "params": w.params,
        "box": w.box_json,
        "max_strides": a.max_strides,
        "columns": data.columns,
        "kinds": data.kinds,
        "values": plan.values.iter().zip(&data.fractions).zip(&data.attractors).map(|((mu, f), ats)| serde_json::json!({
            "param": mu,
            "fractions": data.columns.iter().cloned().zip(f.iter().map(|x| serde_json::json!(x))).collect::<serde_json::Map<String, serde_json::Value>>(),
            "attractors": ats,
        })).collect::<Vec<_>>(),
        "outcome_columns": data.outcome_columns,
        "outcome_fractions": data.outcome_fractions,
        "elapsed_s": data.elapsed_s,
        "files": {"hdf5": p.out.display().to_string(), "png": p.png.display().to_string()},
    });
    crate::outln!("{}", serde_json::to_string_pretty(&j)?);
    Ok(())
}

/// The fractions at every value as a table.
fn print_table(a: &BasinArgs, p: &Parsed, plan: &OverPlan, w: &Written) {
    let (over, bx, data, unit) = (&p.over, &plan.bx, &w.data, &w.unit);
    let (x, y) = (&bx.x.range, &bx.y.range);
    crate::outln!(
        "basin stability of the {} walker over {} = {} .. {} {unit} ({} values), box {} = \
         {}..{} x {} = {}..{} ({}x{} cells; {}), up to {} strides:",
        p.info.name,
        over.name,
        over.lo,
        over.hi,
        over.n,
        x.name,
        x.lo,
        x.hi,
        y.name,
        y.lo,
        y.hi,
        bx.nx,
        bx.ny,
        plan.box_source,
        a.max_strides
    );
    crate::outln!(
        "  {:>14}{}",
        over.name,
        data.columns
            .iter()
            .map(|c| format!("{c:>12}"))
            .collect::<String>()
    );
    for (mu, f) in plan.values.iter().zip(&data.fractions) {
        crate::outln!(
            "  {mu:>14.6}{}",
            f.iter().map(|x| format!("{x:>12.4}")).collect::<String>()
        );
    }
    crate::outln!(
        "  wrote {} and {} in {:.2} s ({} thread(s))",
        p.out.display(),
        p.png.display(),
        data.elapsed_s,
        a.threads
    );
}
