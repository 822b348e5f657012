//! `pdw-sweep fixedpoint --follow pd|fold --sweep NAME=A:B:N --free NAME[=LO:HI]`: the curve of
//! period doublings or folds of the period-one gait in two parameters
//! ([`pdw::limit::codim2`]; the steps are the library's, [`pdw::follow`]).
//!
//! [`run`] reads as the command does: the flags checked ([`parse`]), the plan made from the
//! model's own values ([`plan`]), the outputs claimed, the corners, integrator and guess checked
//! ([`prepare`]), the gait, its bifurcation, the curve and the region map computed
//! ([`compute`]), the file and the picture written ([`write()`]), the curve printed ([`report`]).

use super::output::{Format, Output};
use super::BuiltModel;
use crate::args::{self, InputError, Sweep};
use crate::cli::FixedpointArgs;
use pdw::follow::{kind_long, FollowFlags, FollowPlan, Free, GaitChoice, StartSearch};
use pdw::hybrid::Options;
use pdw::limit::{
    Bifurcation, Codim2Kind, Codim2Options, ContinuationOptions, Curve, CurveEnd, Region,
    RegionOptions,
};
use pdw::store::{CurveData, RegionMap};
use std::path::Path;
use std::process::ExitCode;

/// Default `--map-grid`.
const MAP_GRID: &str = "40x40";

/// How the CLI names a curve's inputs in messages.
const FLAGS: FollowFlags = FollowFlags {
    kind: "--follow",
    sweep: "--sweep",
    free: "--free",
    free_range_hint: |n| format!("--free {n}=LO:HI"),
    set_hint: |n| {
        format!(
            "--set {n}=VALUE{}",
            if n == "slope" { " or --slope" } else { "" }
        )
    },
};

/// The flags of a curve run, checked without the model.
struct Parsed {
    kind: Codim2Kind,
    sweep: Sweep,
    free: Free,
    gait: GaitChoice,
    /// `--map-grid` (or its default) as cells `(nx, ny)`.
    grid: (usize, usize),
}

/// The plan and the models the run starts from: at the model's own values and at
/// `(A, free_own)`, the latter naming the file's parameters and units.
struct Planned {
    plan: FollowPlan,
    m_own: BuiltModel,
    m_a: BuiltModel,
    grid: (usize, usize),
}

/// What the run computed: the one-parameter start and the bifurcation it found, the curve
/// and its options, the region map (with `--png` and a curve) and its options.
struct Computed {
    start: ContinuationOptions,
    bif: Bifurcation,
    codim2: Codim2Options,
    curve: Curve,
    ropts: RegionOptions,
    map: Option<RegionMap>,
}

pub fn run(a: &FixedpointArgs) -> anyhow::Result<ExitCode> {
    let parsed = parse(a)?;
    let (plan, m_own) = plan(a, &parsed)?;
    let out = a.out_path();
    let _claim = claim(a, &out)?;
    let planned = prepare(a, plan, m_own, parsed.grid)?;
    let t0 = std::time::Instant::now();
    let Some(computed) = compute(a, &planned)? else {
        return Ok(ExitCode::from(2));
    };
    let elapsed = t0.elapsed().as_secs_f64();
    write(a, &out, &planned, &computed)?;
    report(a, &out, &planned, &computed, elapsed)
}

/// `--follow` as the curve's kind.
fn parse_kind(follow: Option<&str>) -> Result<Codim2Kind, InputError> {
    match follow {
        None => Err(InputError(
            "--free and --map-grid belong to --follow pd|fold (the bifurcation to follow in two \
             parameters); add --follow"
                .into(),
        )),
        Some(k) => pdw::follow::parse_kind(k, FLAGS.kind),
    }
}

/// The flags that belong together, checked in the order a user reads them.
fn parse(a: &FixedpointArgs) -> Result<Parsed, InputError> {
    let kind = parse_kind(a.follow.as_deref())?;
    if a.csv.is_some() {
        return Err(InputError(
            "--csv: a --follow curve is written to --out (HDF5) and printed by --json; --csv \
             belongs to a one-parameter --sweep"
                .into(),
        ));
    }
    let Some(sweep) = a.sweep.as_deref() else {
        return Err(InputError(
            "--follow needs --sweep NAME=A:B:N: the stepped parameter and the N points of the \
             curve (e.g. --sweep hip_mass=2:20:10)"
                .into(),
        ));
    };
    let Some(free_text) = a.free.as_deref() else {
        return Err(InputError(
            "--follow needs --free NAME: the parameter solved for along the curve (e.g. --free \
             slope)"
                .into(),
        ));
    };
    if a.period != 1 {
        return Err(InputError(format!(
            "--period {} with --follow: the curve follows a bifurcation of the period-one gait; \
             drop --period",
            a.period
        )));
    }
    let sweep = args::parse_sweep(sweep)?;
    let free = pdw::follow::parse_free(free_text, FLAGS.free)?;
    let (nx, ny) = args::parse_grid_for("--map-grid", a.map_grid.as_deref().unwrap_or(MAP_GRID))?;
    if nx < 2 || ny < 2 || nx * ny > 250_000 {
        return Err(InputError(format!(
            "--map-grid: {nx}x{ny}: need at least 2 cells per side and at most 250000 cells \
             (each cell iterates the stride map a few hundred times)"
        )));
    }
    Ok(Parsed {
        kind,
        sweep,
        free,
        gait: GaitChoice::from_name(&a.gait).expect("--gait is checked by clap"),
        grid: (nx, ny),
    })
}

/// Claims `--out` and `--png` (refusing existing files without `--force`, and the model file).
fn claim(a: &FixedpointArgs, out: &Path) -> Result<super::output::Claim, InputError> {
    let outputs = [
        Some(Output {
            flag: "--out",
            path: out,
            format: Format::Hdf5,
            may_exist: false,
        }),
        a.png.as_deref().map(|p| Output {
            flag: "--png",
            path: p,
            format: Format::Png,
            may_exist: false,
        }),
    ];
    let outputs: Vec<Output<'_>> = outputs.into_iter().flatten().collect();
    let inputs: Vec<_> = super::output::model_input(&a.model.model)
        .into_iter()
        .collect();
    super::output::claim(&outputs, &inputs, a.force)
}

/// The plan, from the model at its own values (returned too): both parameters exist and the
/// free domain holds the model's value ([`pdw::follow::plan`]).
fn plan(a: &FixedpointArgs, p: &Parsed) -> Result<(FollowPlan, BuiltModel), InputError> {
    pdw::follow::plan(
        super::choice(&a.model),
        p.kind,
        p.sweep.clone(),
        &p.free,
        p.gait,
        a.tol,
        &FLAGS,
    )
}

/// The checks made once the outputs are claimed: the integrator choice holds, every corner of
/// the plane is a model, the guess fits the section at the start; the model there.
fn prepare(
    a: &FixedpointArgs,
    mut plan: FollowPlan,
    m_own: BuiltModel,
    grid: (usize, usize),
) -> Result<Planned, InputError> {
    plan.integrator = super::integrator(&a.integrator, Options::dop853(1e-13))?;
    let user = a.guess.as_deref().map(args::parse_guess).transpose()?;
    let m_a = pdw::follow::start_model(&mut plan, user, "--guess")?;
    pdw::integrator::check_integrator(&m_a, &plan.integrator)
        .map_err(|e| InputError(e.to_string()))?;
    Ok(Planned {
        plan,
        m_own,
        m_a,
        grid,
    })
}

/// The four steps of [`pdw::follow`]; `None` after reporting why there is no curve to follow
/// (no gait to start from, no bifurcation on its branch).
fn compute(a: &FixedpointArgs, p: &Planned) -> anyhow::Result<Option<Computed>> {
    let plan = &p.plan;
    let gait = match pdw::follow::start_gait(plan, &p.m_a, &p.m_own)? {
        Ok(g) => g,
        Err(why) => {
            report_no_gait(plan, &p.m_a, why);
            return Ok(None);
        }
    };
    let StartSearch { options, found } = pdw::follow::locate_start(plan, &gait);
    let bif = match found {
        Ok(b) => b,
        Err(ends) => {
            report_no_bifurcation(plan, &ends);
            return Ok(None);
        }
    };
    let (codim2, curve) = pdw::follow::curve(plan, &bif)?;
    let ropts = RegionOptions::default();
    let map = match (&a.png, curve.points.is_empty()) {
        (Some(_), false) => Some(compute_map(a, p, &curve, &ropts)?),
        (Some(_), true) => {
            eprintln!("warning: no curve point, so no region map is drawn");
            None
        }
        _ => None,
    };
    Ok(Some(Computed {
        start: options,
        bif,
        codim2,
        curve,
        ropts,
        map,
    }))
}

fn report_no_gait(plan: &FollowPlan, m_a: &BuiltModel, why: pdw::follow::NoStartGait) {
    eprintln!("error: {}", pdw::follow::no_gait_message(plan, m_a, &why));
    eprintln!("try: --guess (section coordinates), or another start of --sweep");
}

fn report_no_bifurcation(plan: &FollowPlan, ends: &[String]) {
    eprintln!("error: {}", pdw::follow::no_bifurcation_message(plan, ends));
    eprintln!(
        "try: another --free range (NAME=LO:HI), another start of --sweep, or the other gait \
         (--gait)"
    );
}

/// The region map on `--threads` workers (progress bar on stderr unless `--quiet` or stderr
/// is not a terminal), in the file's form.
fn compute_map(
    a: &FixedpointArgs,
    p: &Planned,
    curve: &Curve,
    ropts: &RegionOptions,
) -> anyhow::Result<RegionMap> {
    let (nx, _) = p.grid;
    let bar = if a.quiet || !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(2 * nx as u64)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "region map {bar:40} {pos}/{len} columns x 2 passes [{elapsed_precise} < {eta}]",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads.unwrap_or(2))
        .build()?;
    let grid =
        pdw::follow::region_map(&p.plan, curve, p.grid, ropts, &pool, &|k| bar.inc(k as u64))?;
    bar.finish_and_clear();
    Ok(RegionMap {
        step: grid.step,
        free: grid.free,
        region: grid
            .region
            .iter()
            .map(|r| r.iter().map(|g| g.code()).collect())
            .collect(),
        legend: Region::ALL
            .iter()
            .map(|r| (r.code(), r.name().to_string()))
            .collect(),
    })
}

/// The curve file (replacing the claim's placeholder) with provenance and units, and the
/// picture with `--png`.
fn write(a: &FixedpointArgs, out: &Path, p: &Planned, c: &Computed) -> anyhow::Result<()> {
    let (plan, m) = (&p.plan, &p.m_a);
    let data = curve_data(m, &plan.step.name, &plan.free, &c.curve, c.map.clone());
    pdw::store::write_curve(out, true, &data)?;
    annotate(
        out,
        m,
        &plan.step.name,
        &plan.free,
        &c.start,
        &c.codim2,
        &c.ropts,
    )?;
    if let Some(png) = &a.png {
        let label = |n: &str| format!("{n} [{}]", super::param_unit(m, n));
        pdw::store::plot_curve(
            png,
            &data,
            &label(&plan.step.name),
            &label(&plan.free),
            &format!(
                "{}: {} curve in ({}, {})",
                m.info.name,
                kind_long(plan.kind),
                plan.step.name,
                plan.free
            ),
        )?;
    }
    Ok(())
}

/// The curve as JSON or a table on stdout; a curve lost on the way is an error (exit 2) after
/// its points are written.
fn report(
    a: &FixedpointArgs,
    out: &Path,
    p: &Planned,
    c: &Computed,
    elapsed: f64,
) -> anyhow::Result<ExitCode> {
    if a.json {
        let j = curve_json(a, out, p, c, elapsed);
        crate::outln!("{}", serde_json::to_string_pretty(&j)?);
    } else {
        print_table(a, out, p, c, elapsed);
    }
    if let Some(lost) = pdw::follow::lost_message(&p.plan, &c.curve) {
        eprintln!(
            "error: {lost}; the {} points reached are written",
            c.curve.points.len()
        );
        return Ok(ExitCode::from(2));
    }
    Ok(ExitCode::SUCCESS)
}

/// `--json`: the curve, its start, every point's gait and multipliers, the files.
fn curve_json(
    a: &FixedpointArgs,
    out: &Path,
    p: &Planned,
    c: &Computed,
    elapsed: f64,
) -> serde_json::Value {
    let (plan, m, curve) = (&p.plan, &p.m_a, &c.curve);
    let (sn, fnm) = (&plan.step.name, &plan.free);
    let (su, fu) = (super::param_unit(m, sn), super::param_unit(m, fnm));
    serde_json::json!({
        "curve": {
            "kind": plan.kind.name(),
            "params": [sn, fnm],
            "points": curve.points.iter().map(|p| [p.p_step, p.p_free]).collect::<Vec<_>>(),
        },
        "model": m.info.name,
        "units": {sn.clone(): su, fnm.clone(): fu},
        "complete": matches!(curve.end, CurveEnd::Complete),
        "end": end_json(&curve.end),
        "start": {
            "step": plan.step.lo,
            "free": c.bif.param,
            "bracket": c.bif.param_bracket,
            "method": "one-parameter pseudo-arclength continuation in the free parameter",
        },
        "section_names": m.info.section_names,
        "state_names": m.info.state_names,
        "gaits": curve.points.iter().map(|p| serde_json::json!({
            "section": p.section,
            "state": p.state,
            "critical_multiplier": p.critical,
            "multipliers": p.multipliers.iter().map(|l| serde_json::json!({"re": l.re, "im": l.im})).collect::<Vec<_>>(),
            "period": p.period,
            "residual": p.residual,
            "test_value": p.test_value,
            "newton_iterations": p.newton_iters,
        })).collect::<Vec<_>>(),
        "integrator": super::integrator_json(&plan.integrator),
        "out": out.display().to_string(),
        "png": a.png.as_ref().map(|p| p.display().to_string()),
        "elapsed_s": elapsed,
    })
}

/// The curve as a table: one line per point (a slope also in degrees).
fn print_table(a: &FixedpointArgs, out: &Path, p: &Planned, c: &Computed, elapsed: f64) {
    let (plan, m, curve) = (&p.plan, &p.m_a, &c.curve);
    let (sn, fnm) = (&plan.step.name, &plan.free);
    let (su, fu) = (super::param_unit(m, sn), super::param_unit(m, fnm));
    crate::outln!(
        "model {}: {} curve in ({sn}, {fnm}); start at {sn} = {} from the one-parameter \
         continuation: {fnm} = {:.12} {fu}",
        m.info.name,
        kind_long(plan.kind),
        plan.step.lo,
        c.bif.param
    );
    let deg = fnm == "slope";
    crate::outln!(
        "  {:>16} {:>22}{} {:>20} {:>10} {:>6}",
        format!("{sn} [{su}]"),
        format!("{fnm} [{fu}]"),
        if deg { "       (deg)" } else { "" },
        "critical multiplier",
        "residual",
        "Newton"
    );
    for p in &curve.points {
        crate::outln!(
            "  {:>16.10} {:>22.15}{} {:>20.12} {:>10.2e} {:>6}",
            p.p_step,
            p.p_free,
            if deg {
                format!(" ({:>10.6})", p.p_free.to_degrees())
            } else {
                String::new()
            },
            p.critical,
            p.residual,
            p.newton_iters
        );
    }
    crate::outln!(
        "  {} of {} points in {} corrector solves; wrote {}{} in {elapsed:.2} s",
        curve.points.len(),
        plan.step.n,
        curve.solves,
        out.display(),
        a.png
            .as_ref()
            .map(|p| format!(" and {}", p.display()))
            .unwrap_or_default()
    );
}

fn end_json(e: &CurveEnd) -> serde_json::Value {
    match e {
        CurveEnd::Complete => serde_json::Value::Null,
        CurveEnd::Lost {
            last,
            tried,
            reason,
        } => serde_json::json!({"last": last, "tried": tried, "reason": reason.to_string()}),
    }
}

fn curve_data(
    m: &BuiltModel,
    step: &str,
    free: &str,
    c: &Curve,
    map: Option<RegionMap>,
) -> CurveData {
    let end = match &c.end {
        CurveEnd::Complete => "complete".to_string(),
        CurveEnd::Lost {
            last,
            tried,
            reason,
        } => format!("lost after {step} = {last:?} (step to {tried} failed): {reason}"),
    };
    CurveData {
        command: super::command_line(),
        model: m.info.name.to_string(),
        kind: c.kind.name().into(),
        step_parameter: step.into(),
        free_parameter: free.into(),
        params: m.params_json().to_string(),
        section_names: m.info.section_names.iter().map(|s| s.to_string()).collect(),
        state_names: m.info.state_names.iter().map(|s| s.to_string()).collect(),
        p_step: c.points.iter().map(|p| p.p_step).collect(),
        p_free: c.points.iter().map(|p| p.p_free).collect(),
        section: c.points.iter().map(|p| p.section.clone()).collect(),
        state: c.points.iter().map(|p| p.state.clone()).collect(),
        multipliers: c
            .points
            .iter()
            .map(|p| p.multipliers.iter().map(|l| (l.re, l.im)).collect())
            .collect(),
        critical: c.points.iter().map(|p| p.critical).collect(),
        period: c.points.iter().map(|p| p.period).collect(),
        residual: c.points.iter().map(|p| p.residual).collect(),
        complete: matches!(c.end, CurveEnd::Complete),
        end,
        map,
    }
}

/// Provenance (every numerical option) and units on every dataset of the curve file.
fn annotate(
    out: &std::path::Path,
    m: &BuiltModel,
    step: &str,
    free: &str,
    c: &ContinuationOptions,
    o: &Codim2Options,
    r: &RegionOptions,
) -> anyhow::Result<()> {
    let options = serde_json::json!({
        "one_parameter_start": {
            "method": format!("{:?}", c.method),
            "integrator": super::integrator_json(&c.integrator),
            "ds_init": c.ds_init, "ds_min": c.ds_min, "ds_max": c.ds_max,
            "mu_min": c.mu_min, "mu_max": c.mu_max,
            "newton_tol": c.newton_tol, "dmu": c.dmu, "locate_tol": c.locate_tol,
        },
        "curve": {
            "system": "minimally augmented: P(x) - x = 0, g = 0 from the bordered [[DP -+ I, b], [c^T, 0]]",
            "integrator": super::integrator_json(&o.integrator),
            "newton_tol": o.newton_tol, "max_newton": o.max_newton,
            "max_backtracks": o.max_backtracks,
            "dtest_rel": o.dtest_rel,
            "free_min": o.free_min, "free_max": o.free_max,
            "min_step_fraction": o.min_step_fraction,
            "critical_tol": o.critical_tol,
        },
        "region_map": {
            "newton_tol": r.newton.tol,
            "newton_integrator": super::integrator_json(&r.integrator),
            "orbit_integrator": super::integrator_json(&r.orbit.integrator),
            "transient": r.orbit.transient, "record": r.orbit.record,
            "max_period": r.orbit.max_period, "tol_period": r.orbit.tol_period,
            "nudge": r.nudge,
        },
    });
    let prov = super::provenance(options);
    let (su, fu) = (super::param_unit(m, step), super::param_unit(m, free));
    let sec = super::units_list(&super::section_units(m));
    let state = super::units_list(&super::model_units(m).state);
    let tu = super::time_unit(m);
    let units = move |p: &str| -> Option<String> {
        Some(match p {
            "curve/p_step" | "map/step" => su.clone(),
            "curve/p_free" | "map/free" => fu.clone(),
            "curve/section" => sec.clone(),
            "curve/residual" => format!("max over /curve/section's coordinates {sec}"),
            "curve/state" => state.clone(),
            "curve/period" => tu.clone(),
            "curve/multipliers_re" | "curve/multipliers_im" | "curve/critical" | "map/region" => {
                "1".into()
            }
            _ => return None,
        })
    };
    pdw::store::annotate(
        out,
        &pdw::store::Annotations {
            provenance: Some(&prov),
            units: &units,
            slice: None,
            scales: &[],
            coordinates: Some(&m.coordinates_json()),
        },
    )?;
    Ok(())
}
