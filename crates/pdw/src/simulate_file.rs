//! The file of a walk (`pdw-sweep simulate --out`, Python's `simulate(out=…)`): the
//! trajectory as the store's plain columns (one per state component, so units can differ; the
//! mode, stride, ground reaction, knee-lock torque, validity flags, energy, positions) with the
//! run's attributes, written as HDF5 with provenance and units or as CSV
//! ([`pdw_store::write_trajectory_h5`], [`pdw_store::write_trajectory_csv`]).

use crate::model::BuiltModel;
use crate::simulate::Spacing;
use pdw_limit::trajectory::{self, Trajectory, TrajectoryOptions};
use pdw_store::{Provenance, StoreError, TrajColumn, TrajEvents, TrajectoryData};
use std::path::Path;

/// The format of a walk's file, by the extension of its path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Hdf5,
    Csv,
}

impl Format {
    /// `.h5`/`.hdf5` or `.csv` (any case); anything else is refused naming `flag`.
    pub fn of(path: &Path, flag: &str) -> Result<Format, crate::InputError> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
        {
            Some(e) if e == "h5" || e == "hdf5" => Ok(Format::Hdf5),
            Some(e) if e == "csv" => Ok(Format::Csv),
            _ => Err(crate::InputError(format!(
                "{flag}: '{}' must end in .h5, .hdf5 or .csv",
                path.display()
            ))),
        }
    }

    /// The claim's name of the format ([`crate::output::claim`]).
    pub fn claimed(self) -> crate::output::Format {
        match self {
            Format::Hdf5 => crate::output::Format::Hdf5,
            Format::Csv => crate::output::Format::Csv,
        }
    }
}

/// Writes the trajectory to `out` (claimed: its placeholder is replaced): HDF5 with provenance
/// and units, or CSV with the provenance as `# key: value` comment lines among the other
/// attributes.
pub fn write(
    out: &Path,
    format: Format,
    mut data: TrajectoryData,
    m: &BuiltModel,
    prov: &Provenance,
) -> Result<(), StoreError> {
    match format {
        Format::Hdf5 => {
            pdw_store::write_trajectory_h5(out, true, &data)?;
            let context = crate::model::unit_context(m);
            let units = pdw_store::format::TRAJECTORY.units(&context);
            pdw_store::annotate(
                out,
                &pdw_store::Annotations {
                    provenance: Some(prov),
                    units: &units,
                    slice: None,
                    scales: &[],
                    coordinates: None,
                },
            )
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
            pdw_store::write_trajectory_csv(out, true, &data)
        }
    }
}

/// The numerical options a walk's provenance records.
pub fn options_json(opts: &TrajectoryOptions, sp: &Spacing) -> serde_json::Value {
    serde_json::json!({
        "integrator": crate::integrator_json(&opts.integrator),
        "steps": opts.steps,
        "dt_out": opts.dt_out,
        "dt_out_source": sp.source,
        "event_samples": opts.event_samples,
        "gait_newton_tol": crate::simulate::GAIT_TOL,
    })
}

/// The store's plain columns from a trajectory, with the run's attributes.
pub fn to_store(
    m: &BuiltModel,
    tr: &Trajectory,
    opts: &TrajectoryOptions,
    sp: &Spacing,
    start: &str,
    command: &str,
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
    if let Some(e) = crate::simulate::fixed_frame_energy(m, tr) {
        columns.push(TrajColumn::scalar("energy_fixed_frame", &u.energy, e));
    }
    let positions = crate::simulate::positions(m, tr);
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
    let mut attrs = attrs(m, tr, opts, sp, start, command);
    attrs.extend(match &positions {
        Ok(p) => [
            ("point_names".into(), serde_json::json!(p.names).to_string()),
            (
                "positions_frame".into(),
                crate::simulate::POSITIONS_FRAME.to_string(),
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
    command: &str,
) -> Vec<(String, String)> {
    vec![
        ("command".into(), command.to_string()),
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
            crate::integrator_text(&opts.integrator),
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
fn position_columns(p: &crate::simulate::Positions, length: &str) -> Vec<TrajColumn> {
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
