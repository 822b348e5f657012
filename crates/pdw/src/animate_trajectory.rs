//! An animated GIF of a trajectory file written by `simulate` (the CLI's `animate --from`,
//! Python's `animate(from_file=…)`).
//!
//! The model is rebuilt from the file ([`model`]: the model's name, or the `--model` of the
//! command that wrote it, with every parameter value the file records), the poses re-derived
//! from the stored states ((the walker's `pose`)) and drawn as [`crate::animate`] draws
//! a gait: world coordinates, the slope descending to the right at angle γ, the stance foot
//! advancing by the swing foot's position at each heel strike (read from the events' states
//! before the strike). Frames are [`AnimOptions::frame_time`] apart from the first sample
//! (one GIF second is one model time unit), the state at a frame time interpolated linearly
//! between the two stored samples around it (exact when the file was written with `--dt-out`
//! equal to the frame time; never across an event); a walk that fell ends on a frame at the
//! fall, labelled with it.

use crate::animate::{check_frames, frame, world, AnimOptions, AnimateError};
use crate::input::InputError;
use crate::model::BuiltModel;
use pdw_store::{Frame, TrajectoryData};
use std::path::Path;

fn attr<'a>(data: &'a TrajectoryData, name: &str) -> Option<&'a str> {
    data.attrs
        .iter()
        .find(|(k, _)| k == name)
        .map(|(_, v)| v.as_str())
}

/// The `--model` value of the command line that wrote the file, if any.
fn command_model(data: &TrajectoryData) -> Option<String> {
    let cmd = attr(data, "command")?;
    let words: Vec<&str> = cmd.split_whitespace().collect();
    words.iter().enumerate().find_map(|(i, w)| {
        if let Some(v) = w.strip_prefix("--model=") {
            Some(v.to_string())
        } else if *w == "--model" {
            words.get(i + 1).map(|v| v.to_string())
        } else {
            None
        }
    })
}

/// The model of the trajectory file `path` (read as `data`), rebuilt: its recorded name (a
/// registry model), else the `--model` of the command that wrote it (a spec file), with every
/// recorded parameter value; its state must have the file's state columns.
pub fn model(data: &TrajectoryData, path: &Path) -> Result<BuiltModel, InputError> {
    let shown = path.display();
    let name = attr(data, "model").ok_or_else(|| {
        InputError(format!(
            "'{shown}' records no model: it was not written by `simulate`"
        ))
    })?;
    let params: serde_json::Map<String, serde_json::Value> = attr(data, "params")
        .and_then(|p| serde_json::from_str(p).ok())
        .ok_or_else(|| InputError(format!("'{shown}' records no parameter values")))?;
    let overrides: Vec<(String, f64)> = params
        .iter()
        .filter_map(|(k, v)| v.as_f64().map(|v| (k.clone(), v)))
        .collect();
    // the resolved spec the file records (HDF5 files of a chain walker), which rebuilds a
    // user's own walker without its spec file
    let spec = pdw_store::provenance::read_model_spec(path).ok().flatten();
    let mut tried = vec![name.to_string()];
    let mut built = crate::model::build_recorded(name, spec.as_deref(), &overrides);
    if built.is_err() {
        if let Some(cmd) = command_model(data).filter(|c| c != name) {
            built = crate::model::build(&cmd, &overrides);
            tried.push(cmd);
        }
    }
    let m = built.map_err(|e| {
        InputError(format!(
            "the model of '{shown}' cannot be rebuilt (tried {}): {e}",
            tried.join(", ")
        ))
    })?;
    let names = state_names(data, path)?;
    if names != m.info.state_names {
        return Err(InputError(format!(
            "'{shown}' holds the states {} but the rebuilt model '{}' has {}",
            names.join(", "),
            m.info.name,
            m.info.state_names.join(", ")
        )));
    }
    crate::animate::check_drawing(&m)?;
    Ok(m)
}

fn state_names(data: &TrajectoryData, path: &Path) -> Result<Vec<String>, InputError> {
    attr(data, "state_names")
        .and_then(|s| serde_json::from_str(s).ok())
        .ok_or_else(|| {
            InputError(format!(
                "'{}' records no state names: it was not written by `simulate`",
                path.display()
            ))
        })
}

/// The stored samples: times, states (one row each), steps and modes.
struct Samples {
    t: Vec<f64>,
    x: Vec<Vec<f64>>,
    step: Vec<usize>,
    mode: Vec<usize>,
}

fn samples(data: &TrajectoryData, names: &[String], path: &Path) -> Result<Samples, InputError> {
    let col = |n: &str| {
        data.column(n)
            .map(|c| c.values.clone())
            .ok_or_else(|| InputError(format!("'{}' has no column '{n}'", path.display())))
    };
    let cols = names
        .iter()
        .map(|n| col(n))
        .collect::<Result<Vec<_>, _>>()?;
    let t = col("t")?;
    if t.is_empty() {
        return Err(InputError(format!("'{}' holds no samples", path.display())));
    }
    let x = (0..t.len())
        .map(|i| cols.iter().map(|c| c[i]).collect())
        .collect();
    let ints = |v: Vec<f64>| -> Vec<usize> { v.into_iter().map(|s| s as usize).collect() };
    Ok(Samples {
        t,
        x,
        step: ints(col("step")?),
        mode: ints(col("mode")?),
    })
}

impl Samples {
    /// The state and step at time `tk`: linear between the samples around it when no event
    /// lies between them, else the last sample at or before it.
    fn at(&self, tk: f64) -> (Vec<f64>, usize) {
        let i = self.t.partition_point(|&t| t <= tk).max(1) - 1;
        let j = i + 1;
        let same = j < self.t.len()
            && self.t[j] > self.t[i]
            && self.step[j] == self.step[i]
            && self.mode[j] == self.mode[i];
        if !same {
            return (self.x[i].clone(), self.step[i]);
        }
        let w = ((tk - self.t[i]) / (self.t[j] - self.t[i])).clamp(0.0, 1.0);
        let x = self.x[i]
            .iter()
            .zip(&self.x[j])
            .map(|(a, b)| a + w * (b - a))
            .collect();
        (x, self.step[i])
    }
}

/// The stance foot's position along the slope during each step: the running sum of the swing
/// foot's position at the heel strikes (the section's events, states before the strike).
fn stance_offsets(m: &BuiltModel, data: &TrajectoryData) -> Vec<f64> {
    let w = m.walker.as_ref();
    let (mode, guard) = w.section_guard();
    let name = &w.guards(mode)[guard].name;
    let e = &data.events;
    let d = data.dim;
    let mut off = vec![0.0];
    for k in 0..e.t.len() {
        if e.kind[k] == *name && e.mode_before[k] as usize == mode {
            let pre = &e.pre[k * d..(k + 1) * d];
            let step = w.pose(pre).and_then(|p| p.swing_foot).map_or(0.0, |f| f[0]);
            let last = *off.last().unwrap_or(&0.0);
            off.push(last + step);
        }
    }
    off
}

/// How the walk ended, from the file: `None` when every step was done.
pub fn fall(data: &TrajectoryData) -> Option<String> {
    attr(data, "outcome")
        .filter(|o| *o != "ok")
        .map(str::to_string)
}

/// The frames of the trajectory `data` (of the model `m`, [`model`]) at `opts`' frame rate;
/// a fall ends on a frame at the fall's time.
pub fn frames(
    m: &BuiltModel,
    data: &TrajectoryData,
    opts: &AnimOptions,
    path: &Path,
) -> Result<Vec<Frame>, AnimateError> {
    let names = state_names(data, path).map_err(AnimateError::Input)?;
    let s = samples(data, &names, path).map_err(AnimateError::Input)?;
    let offsets = stance_offsets(m, data);
    let (t0, t_end) = (s.t[0], s.t[s.t.len() - 1]);
    let dt = opts.frame_time();
    let k_last = ((t_end - t0) / dt + 1e-9).floor() as usize;
    let fell = fall(data);
    let mut times: Vec<f64> = (0..=k_last).map(|k| t0 + k as f64 * dt).collect();
    if fell.is_some() && times.last().is_some_and(|&t| t < t_end - 1e-12) {
        times.push(t_end);
    }
    check_frames(times.len())?;
    let mut trace = Vec::new();
    let mut out = Vec::with_capacity(times.len());
    for (k, &tk) in times.iter().enumerate() {
        let (x, step) = s.at(tk);
        let off = offsets[step.min(offsets.len() - 1)];
        if let Some(f) = m.walker.pose(&x).and_then(|p| p.swing_foot) {
            trace.push(world(m.slope(), f, off));
        }
        let label = match &fell {
            Some(f) if k + 1 == times.len() => format!("t = {tk:.3}   FELL: {f}"),
            _ => format!("t = {tk:.3}   step {}", step + 1),
        };
        out.push(frame(m, &x, off, &trace, label));
    }
    Ok(out)
}

/// The picture's title: model, slope, the steps the file holds and how the walk ended.
pub fn title(m: &BuiltModel, data: &TrajectoryData) -> String {
    let done = attr(data, "steps_done").unwrap_or("?");
    format!(
        "{} walker, slope {:.4} rad: simulated walk, {done} steps{}",
        m.info.name,
        m.slope(),
        if fall(data).is_some() { ", FELL" } else { "" }
    )
}

/// What [`animate_file`] drew: the frames, the rebuilt model and how the walk ended.
pub struct Drawn {
    pub frames: usize,
    pub model: BuiltModel,
    pub fall: Option<String>,
}

/// Reads the trajectory file `from`, rebuilds its model ([`model`]; errors name `flag`) and
/// writes its animation to `out` ([`frames`], [`title`]).
pub fn animate_file(
    from: &Path,
    out: &Path,
    opts: &AnimOptions,
    flag: &str,
) -> Result<Drawn, AnimateError> {
    let data = pdw_store::read_trajectory_h5(from).map_err(AnimateError::Store)?;
    let m = model(&data, from)
        .map_err(|e| AnimateError::Input(InputError(format!("{flag}: {}", e.0))))?;
    let f = frames(&m, &data, opts, from)?;
    crate::animate::write_titled(out, &f, opts, &title(&m, &data))?;
    Ok(Drawn {
        frames: f.len(),
        model: m,
        fall: fall(&data),
    })
}
