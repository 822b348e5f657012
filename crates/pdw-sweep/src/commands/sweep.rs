//! `pdw-sweep fixedpoint --sweep NAME=A:B:N`: continuation of the gait in a parameter
//! (pseudo-arclength, with period-doubling, fold and Neimark–Sacker detection and the
//! period-doubling cascade followed down to `--max-period`, 2 by default: the period-2 branch
//! switched onto at the first period doubling), from the gait at A or, with `--from MU` (or when
//! A has no gait), both ways from a gait inside the range; plus a brute-force orbit diagram over
//! the N parameter values; written to HDF5 and drawn as a PNG bifurcation diagram.
//!
//! The output holds exactly the N requested values per branch ([`pdw::limit::branch_at_params`]
//! corrects the branch at each), every point measured (all K orbit points, the K-stride
//! period, step lengths, speed, validity along each stride, signed complex multipliers);
//! `--json` prints the same data, `--csv FILE` writes it as one row per orbit point.
//!
//! [`run`] reads as the command does: the sweep parsed ([`parse`]), the outputs claimed, the
//! plan made ([`plan`]), the gait, the branches and the orbit diagram computed by the library
//! ([`pdw::sweep`], [`compute`]), the file, picture and CSV written ([`write()`]), the result
//! printed ([`report`]).

use super::fixedpoint::report_failure;
use super::output::{Format, Output};
use super::BuiltModel;
use crate::args::{self, InputError, Sweep};
use crate::cli::FixedpointArgs;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use pdw::limit::{ContinuationOptions, GridBranch, MeasuredPoint, OrbitColumn, Validity};
use pdw::store::{
    plot_bifurcation, write_sweep, Bifurcation, OrbitDiagram, StrideValidity, SweepData,
};
use pdw::sweep::{StartChoice, SweepPlan};
use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};

/// A stride's validity in the file's form (unchecked where the model reports no forces).
fn store_validity(v: &Option<Validity>) -> StrideValidity {
    v.as_ref()
        .map_or_else(StrideValidity::unchecked, |v| StrideValidity {
            checked: true,
            valid: v.valid(),
            normal_force_negative: v.normal_force_negative,
            knee_unlocks: v.knee_unlocks,
            swing_foot_scuffs: v.swing_foot_scuffs,
            min_normal_force: v.min_normal_force,
            max_friction_required: v.max_friction_required,
            min_knee_torque: v.min_knee_torque.unwrap_or(f64::NAN),
            impact_violation: v.impact_violation,
            min_clearance: v.min_clearance.unwrap_or(f64::NAN),
            scuff_depth: v.scuff_depth,
            min_impact_margin: v
                .impacts
                .iter()
                .filter_map(|i| i.report.as_ref()?.min_margin().map(|m| m.0))
                .reduce(f64::min)
                .unwrap_or(f64::NAN),
            min_relative_margin: v.min_relative_margin().unwrap_or(f64::NAN),
            binding: binding_code(v),
        })
}

/// The binding criterion of `v` as a [`pdw::store::BINDING_CRITERIA`] code (every impact entry
/// is `impact`).
pub fn binding_code(v: &Validity) -> u8 {
    let name = v.binding().map_or("none", |m| {
        if m.name.contains(':') {
            "impact"
        } else {
            m.name.as_str()
        }
    });
    pdw::store::BINDING_CRITERIA
        .iter()
        .position(|n| *n == name)
        .unwrap_or(0) as u8
}

/// `"; N physically invalid (what fails)"` for a branch with points whose orbit needs a
/// pulling contact, knee lock or impact, or scuffs ([`pdw::store::invalid_reasons`], as the PNG
/// rings them); empty when every point is valid or unchecked.
fn invalid_summary(b: &pdw::store::Branch) -> String {
    let mut reasons: Vec<&str> = Vec::new();
    let mut n = 0;
    for i in 0..b.parameter.len() {
        if let Some(r) = pdw::store::invalid_reasons(b, i) {
            n += 1;
            for what in r {
                if !reasons.contains(&what) {
                    reasons.push(what);
                }
            }
        }
    }
    if n == 0 {
        return String::new();
    }
    format!("; {n} physically invalid ({})", reasons.join(", "))
}

/// The branch in the file's form, from its measured points on the output grid.
fn store_branch(b: &GridBranch) -> pdw::store::Branch {
    let pts = &b.points;
    pdw::store::Branch {
        name: b.name.clone(),
        period_strides: b.period_k as u32,
        parameter: pts.iter().map(|p| p.point.param).collect(),
        section: pts.iter().map(|p| p.point.section.clone()).collect(),
        multipliers: pts
            .iter()
            .map(|p| p.point.multipliers.iter().map(|l| (l.re, l.im)).collect())
            .collect(),
        stable: pts.iter().map(|p| p.point.stable).collect(),
        orbit: pts.iter().map(|p| p.point.orbit.clone()).collect(),
        period: pts.iter().map(|p| p.point.period).collect(),
        speed: pts.iter().map(MeasuredPoint::speed).collect(),
        step_length: pts.iter().map(|p| p.step_length.clone()).collect(),
        validity: pts
            .iter()
            .map(|p| p.validity.iter().map(store_validity).collect())
            .collect(),
    }
}

/// Progress of a sweep: one bar through its stages (the continuation, by the share of the
/// parameter range reached; the points on the output grid; the orbit diagram, by values
/// started). Hidden with `--quiet` or when stderr is not a terminal.
struct Progress {
    pb: ProgressBar,
    /// Range of the current continuation stage (f64 bits), and the furthest position reached.
    from: AtomicU64,
    to: AtomicU64,
    best: AtomicU64,
    tracking: std::sync::atomic::AtomicBool,
}

impl Progress {
    fn new(quiet: bool) -> Self {
        let pb = if quiet || !std::io::stderr().is_terminal() {
            ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::hidden())
        } else {
            ProgressBar::new(1000)
        };
        pb.set_style(
            ProgressStyle::with_template("{elapsed_precise} [{wide_bar}] {pos}/{len} {msg}")
                .expect("valid template"),
        );
        Self {
            pb,
            from: AtomicU64::new(0f64.to_bits()),
            to: AtomicU64::new(1f64.to_bits()),
            best: AtomicU64::new(0),
            tracking: std::sync::atomic::AtomicBool::new(false),
        }
    }

    /// A stage with `len` units; `range` = Some((from, to)) tracks the parameter reached.
    fn stage(&self, msg: &str, len: u64, range: Option<(f64, f64)>) {
        self.pb.set_length(len.max(1));
        self.pb.set_position(0);
        self.pb.set_message(msg.to_string());
        self.best.store(0, Ordering::Relaxed);
        if let Some((a, b)) = range {
            self.from.store(a.to_bits(), Ordering::Relaxed);
            self.to.store(b.to_bits(), Ordering::Relaxed);
        }
        self.tracking.store(range.is_some(), Ordering::Relaxed);
    }

    /// A model is built at `mu`: in a continuation stage, the range share reached.
    fn at(&self, mu: f64) {
        let from = f64::from_bits(self.from.load(Ordering::Relaxed));
        let to = f64::from_bits(self.to.load(Ordering::Relaxed));
        if self.tracking.load(Ordering::Relaxed) && to != from {
            let len = self.pb.length().unwrap_or(1);
            let f = ((mu - from) / (to - from)).clamp(0.0, 1.0);
            let pos = (f * len as f64).round() as u64;
            if self.best.fetch_max(pos, Ordering::Relaxed) < pos {
                self.pb.set_position(pos);
            }
        }
    }

    fn inc(&self) {
        self.pb.inc(1);
    }
}

impl pdw::limit::SweepProgress for Progress {
    fn stage(&self, msg: &str, len: u64, range: Option<(f64, f64)>) {
        Progress::stage(self, msg, len, range);
    }
    fn inc(&self) {
        Progress::inc(self);
    }
}

impl pdw::sweep::Progress for Progress {
    fn at(&self, mu: f64) {
        Progress::at(self, mu);
    }
}

/// What the run computed: the branches on the grid and the orbit diagram's columns.
struct Computed {
    /// The value of the swept parameter the start gait was at.
    from: f64,
    sweep: pdw::limit::Sweep,
    columns: Vec<OrbitColumn>,
}

/// The files of a sweep: the HDF5 file, the picture and the CSV (with `--csv`).
struct Files<'a> {
    out: &'a Path,
    png: &'a Path,
    csv: Option<&'a Path>,
}

pub fn run(a: &FixedpointArgs) -> anyhow::Result<ExitCode> {
    let sw = parse(a)?;
    let out = a.out_path();
    let png = a.png.clone().unwrap_or_else(|| out.with_extension("png"));
    let files = Files {
        out: &out,
        png: &png,
        csv: a.csv.as_deref(),
    };
    let _claim = claim(&files, a)?;
    let (plan, m0, user) = plan(a, sw)?;
    let threads = a.threads.unwrap_or(2);
    let progress = Progress::new(a.quiet);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    let t0 = std::time::Instant::now();
    let Some(computed) = compute(&plan, &m0, user.as_deref(), &pool, &progress)? else {
        return Ok(ExitCode::from(2));
    };
    let data = sweep_data(&plan, &m0, &computed, threads, t0.elapsed().as_secs_f64());
    write(&files, &plan, &m0, &data, threads)?;
    report(a, &files, &plan, &m0, &computed, &data)?;
    Ok(ExitCode::SUCCESS)
}

/// `--sweep NAME=A:B:N`, the swept parameter not also given a value (it would be silently
/// overridden).
fn parse(a: &FixedpointArgs) -> Result<Sweep, InputError> {
    let sw = args::parse_sweep(a.sweep.as_deref().unwrap_or_default())?;
    if let Some((_, v)) = super::overrides(&a.model)?
        .into_iter()
        .find(|(n, _)| *n == sw.name)
    {
        return Err(InputError(format!(
            "--sweep {}: the parameter is also set to {v} (--slope or --set); give it once",
            sw.name
        )));
    }
    Ok(sw)
}

/// Claims the sweep's files (refusing existing ones without `--force`, and the model file).
fn claim(f: &Files<'_>, a: &FixedpointArgs) -> Result<super::output::Claim, InputError> {
    let mut outputs = vec![
        Output {
            flag: "--out",
            path: f.out,
            format: Format::Hdf5,
            may_exist: false,
        },
        Output {
            flag: "--png",
            path: f.png,
            format: Format::Png,
            may_exist: false,
        },
    ];
    if let Some(c) = f.csv {
        outputs.push(Output {
            flag: "--csv",
            path: c,
            format: Format::Csv,
            may_exist: false,
        });
    }
    let inputs: Vec<_> = super::output::model_input(&a.model.model)
        .into_iter()
        .collect();
    super::output::claim(&outputs, &inputs, a.force)
}

/// The plan, the model at A (both ends of the range checked) and the user's guess (its length
/// checked against the model's section).
/// `--integrator`, `--rtol`, `--atol`, `--rk4-step` or `--controller`, when given, integrate
/// every stride of the sweep (the gait search, the continuation and the orbit diagram);
/// otherwise each stage keeps its default.
fn plan(
    a: &FixedpointArgs,
    grid: Sweep,
) -> anyhow::Result<(SweepPlan, BuiltModel, Option<Vec<f64>>)> {
    let from = a
        .from
        .map(|mu| pdw::input::check_from(mu, &grid, "--from"))
        .transpose()?;
    let mut plan = SweepPlan {
        model: a.model.model.clone(),
        fixed: super::overrides(&a.model)?,
        grid,
        start: match a.gait.as_str() {
            "unstable" => StartChoice::Unstable,
            _ => StartChoice::Stable,
        },
        tol: a.tol,
        integrator: None,
        from,
        max_period: a.max_period,
    };
    let m0 = plan.start_model()?;
    let user = a.guess.as_deref().map(args::parse_guess).transpose()?;
    pdw::gaits::guesses(&m0, user.clone(), "--guess")?;
    let o = &a.integrator;
    plan.integrator = (o.integrator.is_some()
        || o.rtol.is_some()
        || o.atol.is_some()
        || o.rk4_step.is_some()
        || o.controller.is_some())
    .then(|| super::integrator(o, pdw::limit::gaits::default_integrator(a.tol)))
    .transpose()?;
    if let Some(i) = &plan.integrator {
        pdw::integrator::check_integrator(&m0, i).map_err(|e| InputError(e.to_string()))?;
    }
    Ok((plan, m0, user))
}

/// The library's steps ([`pdw::sweep`]); `None` after reporting that no gait was found to
/// start from. A start other than the guesses' gait at A is said on stderr.
fn compute(
    plan: &SweepPlan,
    m0: &BuiltModel,
    user: Option<&[f64]>,
    pool: &rayon::ThreadPool,
    progress: &Progress,
) -> anyhow::Result<Option<Computed>> {
    let start = match pdw::sweep::find_start(plan, user, pool)? {
        Ok(s) => s,
        Err(none) => {
            report_no_start(plan, m0, &none);
            return Ok(None);
        }
    };
    if start.param != plan.grid.lo || start.how != "the guesses" {
        eprintln!(
            "starting from the gait at {} = {} (found by {}), continued both ways",
            plan.grid.name, start.param, start.how
        );
    }
    let sweep = pdw::sweep::continuation(plan, &start.section, start.param, pool, progress)?;
    for w in &sweep.warnings {
        eprintln!("warning: {w}");
    }
    let columns = pdw::sweep::orbit_diagram(plan, &sweep, &start.section, pool, progress)?;
    progress.pb.finish_and_clear();
    Ok(Some(Computed {
        from: start.param,
        sweep,
        columns,
    }))
}

/// No gait at any value tried: the values, the failed guesses at the first, what to try.
fn report_no_start(plan: &SweepPlan, m0: &BuiltModel, none: &pdw::sweep::NoStart) {
    let values: Vec<String> = none.tried.iter().map(|v| v.to_string()).collect();
    eprintln!(
        "no period-one gait of model '{}' at {} = {} to start the continuation from (at each: \
         Newton from the guesses, then a scan of the section with {} starts)",
        m0.info.name,
        plan.grid.name,
        values.join(", "),
        pdw::sweep::START_SCAN_STARTS
    );
    for (label, g, e) in &none.failed {
        report_failure(label, g, e);
    }
    let at = match plan.grid.name.as_str() {
        "slope" => "--slope VALUE".to_string(),
        name => format!("--set {name}=VALUE"),
    };
    eprintln!(
        "try: --from VALUE at a value of the range with a gait (list the gaits at one value with \
         fixedpoint {at} --search), or --guess"
    );
}

/// The sweep in the file's form: the branches, their bifurcations, the orbit diagram (its
/// first section coordinate, NaN-padded to the recorded strides) and the settings.
fn sweep_data(
    plan: &SweepPlan,
    m0: &BuiltModel,
    c: &Computed,
    threads: usize,
    elapsed: f64,
) -> SweepData {
    let mut bifurcations = Vec::new();
    for (i, (_, b)) in c.sweep.continued.iter().enumerate() {
        for bf in &b.bifurcations {
            bifurcations.push(Bifurcation {
                kind: bf.kind.name().into(),
                parameter: bf.param,
                branch: i,
                section: bf.section.clone(),
            });
        }
    }
    let record = plan.orbit_options().record;
    let orbit = OrbitDiagram {
        coordinate: m0.info.section_names[0].to_string(),
        parameter: c.sweep.params.clone(),
        points: c
            .columns
            .iter()
            .map(|col| {
                let mut v: Vec<f64> = col.points.iter().map(|p| p[0]).collect();
                v.resize(record, f64::NAN);
                v
            })
            .collect(),
    };
    SweepData {
        command: super::command_line(),
        model: m0.info.name.to_string(),
        parameter: plan.grid.name.clone(),
        params: m0.params_json().to_string(),
        section_names: m0
            .info
            .section_names
            .iter()
            .map(|s| s.to_string())
            .collect(),
        branches: c.sweep.branches.iter().map(store_branch).collect(),
        bifurcations,
        orbit: Some(orbit),
        settings: sweep_settings(plan, m0, c.from, threads),
        elapsed_s: elapsed,
    }
}

/// The HDF5 file (replacing the claim's placeholder) with provenance and units, the picture
/// (units on its axes; the file keeps the bare names, with units attributes) and the CSV.
fn write(
    f: &Files<'_>,
    plan: &SweepPlan,
    m0: &BuiltModel,
    data: &SweepData,
    threads: usize,
) -> anyhow::Result<()> {
    let name = &plan.grid.name;
    write_sweep(f.out, true, data)?;
    annotate_sweep(f.out, plan, m0, threads)?;
    let mut shown = data.clone();
    shown.parameter = format!("{name} [{}]", super::param_unit(m0, name));
    for (n, u) in shown.section_names.iter_mut().zip(super::section_units(m0)) {
        *n = format!("{n} [{u}]");
    }
    plot_bifurcation(f.png, &shown, 0)?;
    if let Some(c) = f.csv {
        let comments = csv_comments(m0, name);
        pdw::store::write_sweep_csv(c, true, data, &comments)?;
    }
    Ok(())
}

/// The sweep as JSON (the file's data with units and file names) or as a summary: the
/// branches, their bifurcations, the orbit diagram's falls, the files.
fn report(
    a: &FixedpointArgs,
    f: &Files<'_>,
    plan: &SweepPlan,
    m0: &BuiltModel,
    c: &Computed,
    data: &SweepData,
) -> anyhow::Result<()> {
    let (sw, threads) = (&plan.grid, a.threads.unwrap_or(2));
    let pu = super::param_unit(m0, &sw.name);
    if a.json {
        let mut j = pdw::store::sweep_json(data);
        j["parameter_unit"] = serde_json::json!(pu);
        j["section_units"] = serde_json::json!(super::section_units(m0));
        j["time_unit"] = serde_json::json!(super::time_unit(m0));
        j["length_unit"] = serde_json::json!(super::length_unit(m0));
        j["files"] = serde_json::json!({
            "hdf5": f.out.display().to_string(),
            "png": f.png.display().to_string(),
            "csv": f.csv.map(|c| c.display().to_string()),
        });
        crate::outln!("{}", serde_json::to_string_pretty(&j)?);
        return Ok(());
    }
    let main = &c.sweep.continued[0].1;
    let both = if c.from != sw.lo {
        format!(" both ways from {}", c.from)
    } else {
        String::new()
    };
    crate::outln!(
        "model {}: {} continued from {} to {}{both} ({} internal steps on the period-1 branch; \
         end: {})",
        m0.info.name,
        sw.name,
        sw.lo,
        sw.hi,
        main.points.len(),
        main.end
    );
    for (b, (_, cb)) in data.branches.iter().zip(&c.sweep.continued) {
        // Down the cascade (period 4 and more) a branch may end inside the range: say why.
        let end = match &cb.end {
            pdw::limit::BranchEnd::ParamBound { .. } => String::new(),
            e if cb.period_strides >= 4 => format!(" (the branch ended: {e})"),
            _ => String::new(),
        };
        crate::outln!(
            "  {:<16} {} points on the output grid of {} values{}{end}",
            b.name,
            b.parameter.len(),
            sw.n,
            invalid_summary(b)
        );
    }
    let grid_failures = c.sweep.grid_failures;
    if grid_failures > 0 {
        crate::outln!("  {grid_failures} point(s) of the output grid left out (see the warnings)");
    }
    for (_, b) in &c.sweep.continued {
        for bf in &b.bifurcations {
            crate::outln!(
                "  {:<16} on the period-{} branch at {} = {:.12} {pu}",
                bf.kind.name(),
                b.period_strides,
                sw.name,
                bf.param
            );
        }
    }
    let falls = c.columns.iter().filter(|c| c.fall.is_some()).count();
    crate::outln!(
        "  orbit diagram: {} values, {} with a fall; wrote {} and {}{} in {:.2} s ({} thread(s))",
        c.sweep.params.len(),
        falls,
        f.out.display(),
        f.png.display(),
        f.csv
            .map(|c| format!(" and {}", c.display()))
            .unwrap_or_default(),
        data.elapsed_s,
        threads
    );
    Ok(())
}

/// The CSV's comment lines: units of every column and the command.
fn csv_comments(m: &BuiltModel, parameter: &str) -> Vec<(String, String)> {
    let su = super::section_units(m);
    let (tu, lu) = (super::time_unit(m), super::length_unit(m));
    let u = super::model_units(m);
    let mut units = vec![format!("param={}", super::param_unit(m, parameter))];
    for (n, x) in m.info.section_names.iter().zip(&su) {
        units.push(format!("{n}={x}"));
    }
    units.push(format!("period={tu}"));
    units.push(format!("step_length={lu}"));
    units.push(format!("speed={lu}/{tu}"));
    units.push(format!("min_normal_force={}", u.force));
    units.push("max_friction_required=1".into());
    units.push(format!("min_knee_torque={}", u.torque));
    units.push(format!("min_clearance={}", super::length_unit(m)));
    units.push(format!("scuff_depth={}", super::length_unit(m)));
    units.push("min_relative_margin=1".into());
    units.push("lambda*=1".into());
    vec![
        ("command".into(), super::command_line()),
        ("units".into(), units.join(",")),
        (
            "rows".into(),
            "one per orbit point (point = 0..period_k-1) of every branch point; period, speed, \
             stable and the multipliers (of the period_k-stride map) belong to the whole orbit"
                .into(),
        ),
    ]
}

/// The file's settings attributes: the output grid, the continuation, the integrators and
/// tolerances of every stage, the thread count. The grid names the start value (`start`) when
/// it is not A, and the cascade's depth (`max_period`) when it is not 2.
fn sweep_settings(
    plan: &SweepPlan,
    m: &BuiltModel,
    from: f64,
    threads: usize,
) -> Vec<(String, String)> {
    let (sw, c, o) = (
        &plan.grid,
        &plan.continuation_options(),
        &plan.orbit_options(),
    );
    let fp_integrator = &plan.fixed_point_integrator();
    let j = |v: serde_json::Value| v.to_string();
    let mut grid = serde_json::json!({
        "parameter": sw.name, "from": sw.lo, "to": sw.hi, "n": sw.n,
        "unit": super::param_unit(m, &sw.name),
    });
    if from != sw.lo {
        grid["start"] = serde_json::json!(from);
    }
    if plan.max_period != 2 {
        grid["max_period"] = serde_json::json!(plan.max_period);
    }
    vec![
        ("continuation".into(), j(continuation_json(c))),
        ("grid".into(), j(grid)),
        (
            "integrator".into(),
            j(serde_json::json!({
                "fixed_point": super::integrator_json(fp_integrator),
                "continuation": super::integrator_json(&c.integrator),
                "orbit_diagram": super::integrator_json(&o.integrator),
            })),
        ),
        ("threads".into(), j(serde_json::json!(threads))),
        (
            "tolerances".into(),
            j(serde_json::json!({
                "fixed_point_newton_tol": plan.newton_tol(),
                "continuation_newton_tol": c.newton_tol,
                "bifurcation_locate_tol": c.locate_tol,
                "orbit_diagram_tol_period": o.tol_period,
            })),
        ),
    ]
}

fn continuation_json(c: &ContinuationOptions) -> serde_json::Value {
    serde_json::json!({
        "method": format!("{:?}", c.method),
        "integrator": super::integrator_json(&c.integrator),
        "direction": c.direction,
        "ds_init": c.ds_init, "ds_min": c.ds_min, "ds_max": c.ds_max,
        "max_points": c.max_points,
        "mu_min": c.mu_min, "mu_max": c.mu_max,
        "newton_tol": c.newton_tol, "max_newton": c.max_newton,
        "dmu": c.dmu, "max_turn": c.max_turn,
        "locate_tol": c.locate_tol, "switch_eps": c.switch_eps,
    })
}

/// Provenance (every numerical option: the gait search, the continuation, the orbit diagram)
/// and units on every dataset of the sweep file.
fn annotate_sweep(
    out: &Path,
    plan: &SweepPlan,
    m: &BuiltModel,
    threads: usize,
) -> anyhow::Result<()> {
    let (c, o) = (&plan.continuation_options(), &plan.orbit_options());
    let parameter = &plan.grid.name;
    let options = serde_json::json!({
        "fixed_point": {
            "newton_tol": plan.newton_tol(),
            "integrator": super::integrator_json(&plan.fixed_point_integrator()),
        },
        "continuation": continuation_json(c),
        "threads": threads,
        "orbit_diagram": {
            "integrator": super::integrator_json(&o.integrator),
            "transient": o.transient,
            "record": o.record,
            "max_period": o.max_period,
            "tol_period": o.tol_period,
        },
    });
    let prov = super::provenance(options);
    let units = pdw::store::format::UnitContext {
        parameter: super::param_unit(m, parameter),
        ..pdw::model::unit_context(m)
    };
    pdw::store::annotate(
        out,
        &pdw::store::Annotations {
            provenance: Some(&prov),
            units: &pdw::store::format::SWEEP.units(&units),
            slice: None,
            scales: &[],
            coordinates: Some(&m.coordinates_json()),
        },
    )?;
    Ok(())
}
