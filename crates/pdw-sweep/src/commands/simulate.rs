//! `pdw-sweep simulate`: the time series of a walk of N steps (states, mode, events, ground
//! reaction, knee-lock torque, energy, with units) to HDF5 or CSV.
//!
//! The walk starts from `--state` (section coordinates, or a full state just after a heel
//! strike) or from a gait of the model (`--gait stable|unstable`, found as `fixedpoint` finds
//! it). The trajectory itself is [`pdw_limit::trajectory::simulate`]; this file only parses,
//! converts to the store's plain columns and writes.

use super::fixedpoint::{report_failure, search};
use super::{build_model, BuiltModel};
use crate::args::{self, InputError};
use crate::cli::SimulateArgs;
use pdw_limit::trajectory::{self, Trajectory, TrajectoryOptions};
use pdw_store::{TrajColumn, TrajEvents, TrajectoryData};
use std::process::ExitCode;

/// Residual tolerance of the gait a walk starts from (`--gait`).
const GAIT_TOL: f64 = 1e-12;

/// Output formats by file extension.
enum Format {
    Hdf5,
    Csv,
}

fn format_of(path: &std::path::Path) -> Result<Format, InputError> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
    {
        Some(e) if e == "h5" || e == "hdf5" => Ok(Format::Hdf5),
        Some(e) if e == "csv" => Ok(Format::Csv),
        _ => Err(InputError(format!(
            "--out: '{}' must end in .h5, .hdf5 or .csv",
            path.display()
        ))),
    }
}

pub fn run(a: &SimulateArgs) -> anyhow::Result<ExitCode> {
    let format = format_of(&a.out)?;
    let inputs: Vec<_> = super::output::model_input(&a.model.model)
        .into_iter()
        .collect();
    let _claim = super::output::claim(
        &[super::output::Output {
            flag: "--out",
            path: &a.out,
            format: match format {
                Format::Hdf5 => super::output::Format::Hdf5,
                Format::Csv => super::output::Format::Csv,
            },
            may_exist: false,
        }],
        &inputs,
        a.force,
    )?;
    if a.steps == 0 {
        return Err(InputError("--steps: 0 must be an integer >= 1".into()).into());
    }
    if let Some(h) = a.dt_out {
        if !(h.is_finite() && h > 0.0) {
            return Err(InputError(format!("--dt-out: {h} must be a positive time step")).into());
        }
    }
    // The integrator first: a bad --rtol is reported before any gait search.
    super::integrator(&a.integrator, TrajectoryOptions::new(1).integrator)?;
    if a.state.is_some() && a.gait.is_some() {
        return Err(InputError("--state and --gait: give one or the other".into()).into());
    }
    let m = build_model(&a.model)?;
    let w = m.walker.as_ref();
    let (x0, start, period) = match &a.state {
        Some(s) => {
            let v = s
                .split(',')
                .map(|t| args::parse_f64(t, "--state"))
                .collect::<Result<Vec<f64>, _>>()?;
            let x0 = trajectory::initial_state(w, &v)
                .map_err(|e| InputError(format!("--state: {e}")))?;
            (x0, format!("state {v:?}"), None)
        }
        None => {
            let which = a.gait.as_deref().unwrap_or("stable");
            if !matches!(which, "stable" | "unstable") {
                return Err(InputError(format!(
                    "--gait: '{which}' is not one of stable, unstable"
                ))
                .into());
            }
            let guesses = pdw_limit::gaits::model_guesses(w);
            let (found, failed) = search(&m, &guesses, GAIT_TOL)?;
            let Some(g) = found.iter().find(|f| f.fp.stable == (which == "stable")) else {
                eprintln!(
                    "error: no {which} period-one gait found for model '{}' at slope {} from {} \
                     guess(es); give a starting point with --state",
                    m.info.name,
                    m.slope(),
                    guesses.len()
                );
                for (label, g, e) in &failed {
                    report_failure(label, g, e);
                }
                return Ok(ExitCode::from(2));
            };
            (
                g.fp.state.clone(),
                format!("{which} gait {:?}", g.fp.section),
                Some(g.fp.metrics.period),
            )
        }
    };
    let base = TrajectoryOptions::new(a.steps);
    // Samples are bounded by the memory available (a tiny --dt-out or --rk4-step is refused
    // when the walk reaches the bound, not an out-of-memory kill).
    let opts = TrajectoryOptions {
        dt_out: a.dt_out,
        integrator: super::integrator(&a.integrator, base.integrator)?,
        max_samples: (pdw_limit::resources::memory_available()
            / 2
            / pdw_limit::bytes_per_sample(w.dim()) as u64)
            .min(usize::MAX as u64) as usize,
        ..base
    };
    // From a gait its period tells the samples ahead: refuse before computing.
    let per_stride = match (opts.dt_out, opts.integrator.method) {
        (Some(h), _) => period.map(|p| p / h),
        (None, pdw_hybrid::Method::Rk4 { h }) => period.map(|p| p / h),
        _ => None,
    };
    if let Some(n) = per_stride.map(|k| k * a.steps as f64) {
        if n > opts.max_samples as f64 {
            return Err(InputError(format!(
                "{}: {} steps of this gait (period {:.4}) would record about {n:.2e} samples, \
                 more than the {} that fit in half the memory available; give a larger step or \
                 fewer --steps",
                if opts.dt_out.is_some() {
                    "--dt-out"
                } else {
                    "--rk4-step"
                },
                a.steps,
                period.unwrap_or(f64::NAN),
                opts.max_samples
            ))
            .into());
        }
    }
    let tr = trajectory::simulate(w, &x0, &opts).map_err(|e| InputError(e.to_string()))?;
    let data = to_store(&m, &tr, &opts, &start);
    let prov = super::provenance(serde_json::json!({
        "integrator": super::integrator_json(&opts.integrator),
        "steps": opts.steps,
        "dt_out": opts.dt_out,
        "gait_newton_tol": GAIT_TOL,
    }));
    let state_units = super::units_list(&tr.units.state);
    match format {
        Format::Hdf5 => {
            // the claim refused an existing file without --force; its placeholder is replaced
            pdw_store::write_trajectory_h5(&a.out, true, &data)?;
            pdw_store::annotate(
                &a.out,
                &pdw_store::Annotations {
                    provenance: Some(&prov),
                    units: &|p: &str| match p {
                        "events/kind" | "events/step" | "events/mode_before"
                        | "events/mode_after" => Some("1".into()),
                        "events/pre" | "events/post" => Some(state_units.clone()),
                        _ => None,
                    },
                    slice: None,
                    scales: &[],
                },
            )?;
        }
        Format::Csv => {
            // CSV: the provenance as `# key: value` comment lines with the other attributes.
            let mut data = data;
            for (k, v) in [
                ("crate_version", &prov.crate_version),
                ("git_commit", &prov.git_commit),
                ("build_profile", &prov.build_profile),
                ("simd_path", &prov.simd_path),
                ("host", &prov.host),
                ("options", &prov.options),
            ] {
                data.attrs.push((k.to_string(), v.clone()));
            }
            pdw_store::write_trajectory_csv(&a.out, true, &data)?
        }
    }
    crate::outln!(
        "model {}  slope {} rad  from {}",
        m.info.name,
        m.slope(),
        start
    );
    crate::outln!(
        "{} of {} steps, {} samples, {} events; ended: {}",
        tr.steps_done,
        a.steps,
        tr.len(),
        tr.events.len(),
        if tr.outcome.is_ok() {
            "all steps done".to_string()
        } else {
            outcome_name(w, &tr)
        }
    );
    crate::outln!("wrote {}", a.out.display());
    // A fall is an outcome of the walk (in the file's `outcome`), not an error.
    Ok(ExitCode::SUCCESS)
}

/// How a walk that stopped early ended, with the fall named.
fn outcome_name(_w: &dyn pdw_walkers::Walker, tr: &Trajectory) -> String {
    match tr.outcome {
        pdw_limit::StrideOutcome::Fall { kind, .. } => format!("fell ({})", kind.name()),
        o => o.to_string(),
    }
}

/// The store's plain columns from a trajectory, with the run's attributes.
pub fn to_store(
    m: &BuiltModel,
    tr: &Trajectory,
    opts: &TrajectoryOptions,
    start: &str,
) -> TrajectoryData {
    let u = &tr.units;
    let n = tr.len();
    let d = tr.dim();
    let mut columns = vec![TrajColumn::scalar("t", &u.time, tr.t.clone())];
    let int_col = |name: &str, v: Vec<f64>| TrajColumn {
        integer: true,
        ..TrajColumn::scalar(name, "1", v)
    };
    // One column per state component, so that units can differ (angles, rates).
    for (j, name) in tr.state_names.iter().enumerate() {
        let v = (0..n).map(|i| tr.x[i * d + j]).collect();
        columns.push(TrajColumn::scalar(name, &u.state[j], v));
    }
    columns.push(int_col(
        "mode",
        tr.mode.iter().map(|&v| f64::from(v)).collect(),
    ));
    columns.push(int_col(
        "step",
        tr.step.iter().map(|&v| f64::from(v)).collect(),
    ));
    if let Some(f) = &tr.forces {
        columns.push(TrajColumn::scalar(
            "normal_force",
            &u.force,
            f.normal.clone(),
        ));
        columns.push(TrajColumn::scalar(
            "tangential_force",
            &u.force,
            f.tangential.clone(),
        ));
        columns.push(TrajColumn::scalar(
            "friction_required",
            "1",
            f.friction_required.clone(),
        ));
        columns.push(TrajColumn {
            width: 2,
            components: vec!["stance_knee_torque".into(), "swing_knee_torque".into()],
            ..TrajColumn::scalar("knee_torque", &u.torque, f.knee_torque.clone())
        });
    }
    if let Some(fl) = &tr.flags {
        columns.push(int_col("flags", fl.iter().map(|&b| f64::from(b)).collect()));
    }
    if let Some(e) = &tr.energy {
        columns.push(TrajColumn::scalar("energy", &u.energy, e.clone()));
    }
    let ev = &tr.events;
    let events = TrajEvents {
        t: ev.iter().map(|e| e.t).collect(),
        step: ev.iter().map(|e| e.step as u32).collect(),
        kind: ev.iter().map(|e| e.kind.clone()).collect(),
        mode_before: ev.iter().map(|e| e.mode_before as u32).collect(),
        mode_after: ev.iter().map(|e| e.mode_after as u32).collect(),
        pre: ev.iter().flat_map(|e| e.pre.iter().copied()).collect(),
        post: ev.iter().flat_map(|e| e.post.iter().copied()).collect(),
    };
    let attrs = vec![
        (
            "command".into(),
            std::env::args().collect::<Vec<_>>().join(" "),
        ),
        ("model".into(), m.info.name.to_string()),
        ("slope".into(), format!("{:?}", m.slope())),
        ("params".into(), m.params_json().to_string()),
        ("start".into(), start.to_string()),
        (
            "state_names".into(),
            serde_json::json!(tr.state_names).to_string(),
        ),
        ("steps".into(), opts.steps.to_string()),
        ("steps_done".into(), tr.steps_done.to_string()),
        (
            "outcome".into(),
            if tr.outcome.is_ok() {
                "ok".to_string()
            } else {
                tr.outcome.to_string()
            },
        ),
        (
            "integrator".into(),
            super::integrator_text(&opts.integrator),
        ),
        (
            "dt_out".into(),
            opts.dt_out
                .map_or("every accepted step and event".to_string(), |h| {
                    format!("{h:?}")
                }),
        ),
        (
            "flags_legend".into(),
            serde_json::json!({
                trajectory::FLAG_NORMAL_NEGATIVE.to_string(): "normal force negative",
                trajectory::FLAG_KNEE_UNLOCKS.to_string(): "knee unlocks",
                trajectory::FLAG_SWING_FOOT_SCUFFS.to_string(): "swing foot scuffs",
            })
            .to_string(),
        ),
    ];
    TrajectoryData {
        attrs,
        columns,
        events,
        dim: d,
    }
}
