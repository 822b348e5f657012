//! `pdw-sweep simulate`: the time series of a walk of N steps (states, mode, events, ground
//! reaction, knee-lock torque, energy, with units) to HDF5 or CSV.
//!
//! The walk starts from `--state` (section coordinates, or a full state just after a heel
//! strike) or from a gait of the model (`--gait stable|unstable`, found as `fixedpoint` finds
//! it). The walk's setup and the walk are [`pdw::simulate`]'s; this file parses, converts to
//! the store's plain columns and writes.

use super::fixedpoint::report_failure;
use super::{build_model, BuiltModel};
use crate::args::{self, InputError};
use crate::cli::SimulateArgs;
use pdw::limit::trajectory::{self, Trajectory, TrajectoryOptions};
use pdw::simulate::{self, DtOut, GaitKind, SimulateFlags, Spacing, Start, StartError, Walk};
use pdw::store::{TrajColumn, TrajEvents, TrajectoryData};
use std::process::ExitCode;

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

/// The names of `simulate`'s options in messages.
const FLAGS: SimulateFlags = SimulateFlags {
    steps: "--steps",
    dt_out: "--dt-out",
    state: "--state",
    gait: "--gait",
    rk4_step: "--rk4-step",
};

pub fn run(a: &SimulateArgs) -> anyhow::Result<ExitCode> {
    let format = format_of(&a.out)?;
    let _claim = claim_out(a, &format)?;
    // Parse: the request is checked (and a bad --rtol reported) before any gait search.
    let asked = a.dt_out.unwrap_or(DtOut::Default);
    simulate::check_request(a.steps, asked.every(), &FLAGS)?;
    let integrator = super::integrator(&a.integrator, simulate::default_integrator())?;
    let m = build_model(&a.model)?;
    pdw::integrator::check_integrator(&m, &integrator)?;
    // Plan: where the walk starts and what it records.
    let walk = match simulate::start(&m, &start_of(a)?, &FLAGS) {
        Ok(walk) => walk,
        Err(StartError::Input(e)) => return Err(e.into()),
        Err(StartError::Limit(e)) => return Err(e.into()),
        Err(StartError::NoGait {
            which,
            tried,
            failed,
        }) => {
            eprintln!(
                "error: no {} period-one gait found for model '{}' at slope {} from {tried} \
                 guess(es); give a starting point with --state",
                which.name(),
                m.info.name,
                m.slope(),
            );
            for (label, g, e) in &failed {
                report_failure(label, g, e);
            }
            return Ok(ExitCode::from(2));
        }
    };
    let sp = simulate::spacing(&m, &walk, asked);
    let opts = simulate::options_spaced(&m, a.steps, &sp, integrator);
    simulate::check_samples(&walk, &opts, &FLAGS)?;
    // Run, write.
    let tr = simulate::run(&m, &walk, &opts)?;
    write(
        a,
        &format,
        to_store(&m, &tr, &opts, &sp, &walk.label),
        &tr,
        &opts,
        &sp,
    )?;
    summary(a, &m, &walk, &tr);
    // A fall is an outcome of the walk (in the file's `outcome`), not an error.
    Ok(ExitCode::SUCCESS)
}

/// Claims `--out` (refused if it exists without `--force`, or if it is the model file).
fn claim_out(a: &SimulateArgs, format: &Format) -> Result<super::output::Claim, InputError> {
    let inputs: Vec<_> = super::output::model_input(&a.model.model)
        .into_iter()
        .collect();
    super::output::claim(
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
    )
}

/// Where the walk starts: `--state` parsed, else `--gait` (default stable).
fn start_of(a: &SimulateArgs) -> Result<Start, InputError> {
    if let Some(s) = &a.state {
        let v = s
            .split(',')
            .map(|t| args::parse_f64(t, "--state"))
            .collect::<Result<Vec<f64>, _>>()?;
        return Ok(Start::State(v));
    }
    Ok(Start::Gait(GaitKind::parse(
        a.gait.as_deref().unwrap_or("stable"),
        "--gait",
    )?))
}

/// Writes the trajectory to `--out`: HDF5 with provenance and units, or CSV with the
/// provenance as `# key: value` comment lines among the other attributes.
fn write(
    a: &SimulateArgs,
    format: &Format,
    mut data: TrajectoryData,
    tr: &Trajectory,
    opts: &TrajectoryOptions,
    sp: &Spacing,
) -> anyhow::Result<()> {
    let prov = super::provenance(serde_json::json!({
        "integrator": super::integrator_json(&opts.integrator),
        "steps": opts.steps,
        "dt_out": opts.dt_out,
        "dt_out_source": sp.source,
        "event_samples": opts.event_samples,
        "gait_newton_tol": simulate::GAIT_TOL,
    }));
    let state_units = super::units_list(&tr.units.state);
    match format {
        Format::Hdf5 => {
            // the claim refused an existing file without --force; its placeholder is replaced
            pdw::store::write_trajectory_h5(&a.out, true, &data)?;
            pdw::store::annotate(
                &a.out,
                &pdw::store::Annotations {
                    provenance: Some(&prov),
                    units: &|p: &str| match p {
                        "events/kind" | "events/step" | "events/mode_before"
                        | "events/mode_after" => Some("1".into()),
                        "events/pre" | "events/post" => Some(state_units.clone()),
                        _ => None,
                    },
                    slice: None,
                    scales: &[],
                    coordinates: None,
                },
            )?;
        }
        Format::Csv => {
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
            pdw::store::write_trajectory_csv(&a.out, true, &data)?
        }
    }
    Ok(())
}

/// The run's three lines: model and start, steps and samples with how it ended, the file.
fn summary(a: &SimulateArgs, m: &BuiltModel, walk: &Walk, tr: &Trajectory) {
    crate::outln!(
        "model {}  slope {} rad  from {}",
        m.info.name,
        m.slope(),
        walk.label
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
            outcome_name(tr)
        }
    );
    crate::outln!("wrote {}", a.out.display());
}

/// How a walk that stopped early ended, with the fall named.
fn outcome_name(tr: &Trajectory) -> String {
    match tr.outcome {
        pdw::limit::StrideOutcome::Fall { kind, .. } => format!("fell ({})", kind.name()),
        o => o.to_string(),
    }
}

/// The store's plain columns from a trajectory, with the run's attributes.
pub fn to_store(
    m: &BuiltModel,
    tr: &Trajectory,
    opts: &TrajectoryOptions,
    sp: &Spacing,
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
    if let Some(e) = pdw::simulate::fixed_frame_energy(m, tr) {
        columns.push(TrajColumn::scalar("energy_fixed_frame", &u.energy, e));
    }
    let positions = pdw::simulate::positions(m, tr);
    if let Ok(p) = &positions {
        columns.extend(position_columns(p, &m.walker.units().length));
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
    let mut attrs = attrs(m, tr, opts, sp, start);
    attrs.extend(match &positions {
        Ok(p) => [
            ("point_names".into(), serde_json::json!(p.names).to_string()),
            (
                "positions_frame".into(),
                pdw::simulate::POSITIONS_FRAME.to_string(),
            ),
        ],
        Err(why) => [
            ("point_names".into(), "[]".into()),
            ("positions_frame".into(), why.clone()),
        ],
    });
    TrajectoryData {
        attrs,
        columns,
        events,
        dim: d,
    }
}

/// The trajectory file's attributes: the command, model and parameters, where the walk
/// started, the steps asked and done, how it ended, the integrator and output spacing, and the
/// legend of the validity flags.
fn attrs(
    m: &BuiltModel,
    tr: &Trajectory,
    opts: &TrajectoryOptions,
    sp: &Spacing,
    start: &str,
) -> Vec<(String, String)> {
    vec![
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
        ("dt_out_source".into(), sp.source.clone()),
        (
            "mode_legend".into(),
            serde_json::Value::Object(
                m.walker
                    .mode_names()
                    .into_iter()
                    .enumerate()
                    .map(|(k, n)| (k.to_string(), n.into()))
                    .collect(),
            )
            .to_string(),
        ),
        ("coordinates".into(), m.coordinates_json()),
        (
            "flags_legend".into(),
            serde_json::json!({
                trajectory::FLAG_NORMAL_NEGATIVE.to_string(): "normal force negative",
                trajectory::FLAG_KNEE_UNLOCKS.to_string(): "knee unlocks",
                trajectory::FLAG_SWING_FOOT_SCUFFS.to_string(): "swing foot scuffs",
            })
            .to_string(),
        ),
    ]
}

/// One 2-wide column per named point, `pos_NAME` with components `pos_NAME_x`, `pos_NAME_y`,
/// and the centre of mass `com` (`com_x`, `com_y`), in the walk's fixed frame.
fn position_columns(p: &pdw::simulate::Positions, length: &str) -> Vec<TrajColumn> {
    let np = p.names.len();
    let column = |name: String, values: Vec<f64>| TrajColumn {
        width: 2,
        components: vec![format!("{name}_x"), format!("{name}_y")],
        ..TrajColumn::scalar(&name, length, values)
    };
    let mut v: Vec<TrajColumn> = p
        .names
        .iter()
        .enumerate()
        .map(|(j, name)| {
            let xy = p
                .points
                .chunks(2 * np)
                .flat_map(|row| [row[2 * j], row[2 * j + 1]])
                .collect();
            column(format!("pos_{name}"), xy)
        })
        .collect();
    v.push(column("com".into(), p.com.clone()));
    v
}
