//! A clicked cell, walked: the cell's start state classified by the basin's own engine (the
//! label the page shows, [`classify`]) and a dense walk of the same model and integrator from
//! it for the strides the classification used ([`walk_json`]), with every body point, the
//! energy, the constraint loads and the events, for the page's stick figure and time plots.

use crate::error::ApiError;
use crate::source::Rebuilt;
use pdw::limit::basin::{classify_cells, CellResult, Outcome};
use pdw::limit::trajectory::Trajectory;
use pdw::simulate::{DtOut, SimulateFlags, Start};
use pdw::BuiltModel;
use serde_json::{json, Value};

/// Most steps a walk shows: a slowly converging cell needs up to the stride budget, but the
/// page animates its first steps.
pub const MAX_WALK_STEPS: usize = 200;
/// Fewest steps a walk shows: a cell next to the gait is labelled after a stride or two,
/// too short to watch (a fall ends the walk sooner).
pub const MIN_WALK_STEPS: usize = 8;

/// How the explorer's walk names its options in messages.
const FLAGS: SimulateFlags = SimulateFlags {
    steps: "steps",
    dt_out: "dt_out",
    state: "cell",
    gait: "gait",
    rk4_step: "rk4_step",
};

/// The basin engine's label of the cell starting at `cell` (a section state), exactly as a
/// basin run labels it: one lane of [`classify_cells`] (a lane's result does not depend on the
/// others in its batch), relabelled by the run's attractors.
pub fn classify(
    r: &Rebuilt,
    cell: &[f64],
    pool: &rayon::ThreadPool,
) -> Result<CellResult, ApiError> {
    let fall = Outcome::of_fall;
    let problem = r.set.problem(r.m.walker.as_ref(), &fall);
    let mut res = classify_cells(&problem, &[cell.to_vec()], &r.plan.opts, pool, &|_| {})
        .map_err(|e| ApiError::internal(format!("classifying the cell: {e}")))?;
    r.set.relabel(&mut res);
    res.pop()
        .ok_or_else(|| ApiError::internal("the engine returned no cell"))
}

/// The name of outcome `code` in the run's legend.
pub fn outcome_name(r: &Rebuilt, code: u8) -> String {
    r.set
        .legend()
        .into_iter()
        .find(|(c, _)| *c == code)
        .map_or_else(|| format!("code {code}"), |(_, n)| n)
}

/// The walk of `steps` steps from section state `cell` with the cells' integrator, sampled
/// densely (the default spacing of `simulate`, every event included).
pub fn walk(r: &Rebuilt, cell: &[f64], steps: usize) -> Result<Trajectory, ApiError> {
    walk_model(&r.m, r.plan.opts.integrator, cell, steps)
}

/// The walk of `steps` steps of model `m` from section state `cell` with `integrator`.
pub fn walk_model(
    m: &BuiltModel,
    integrator: pdw::hybrid::Options,
    cell: &[f64],
    steps: usize,
) -> Result<Trajectory, ApiError> {
    let w = pdw::simulate::start(m, &Start::State(cell.to_vec()), &FLAGS).map_err(|e| match e {
        pdw::simulate::StartError::Input(e) => ApiError::bad_request(e.0),
        _ => ApiError::internal("the walk has no start"),
    })?;
    let sp = pdw::simulate::spacing(m, &w, DtOut::Default);
    let opts = pdw::simulate::options_spaced(m, steps, &sp, integrator);
    pdw::simulate::run(m, &w, &opts).map_err(|e| ApiError::internal(e.0))
}

/// Body points at every sample in one frame of the slope: [`pdw::simulate::positions`], or,
/// where it leaves them out (round feet), each sample's stance frame moved down the slope by
/// the step lengths before it (the rolling contact's travel is not added).
fn points(m: &BuiltModel, tr: &Trajectory) -> (Vec<String>, Vec<f32>, String) {
    if let Ok(p) = pdw::simulate::positions(m, tr) {
        let pts = p.points.iter().map(|&v| v as f32).collect();
        return (p.names, pts, "slope".into());
    }
    let w = m.walker.as_ref();
    let mut offsets = vec![0.0];
    for e in tr.events.iter().filter(|e| e.ends_step) {
        let last = *offsets.last().unwrap_or(&0.0);
        offsets.push(last + w.step_length(&e.pre));
    }
    let (mut names, mut pts) = (Vec::new(), Vec::new());
    // one kernel scratch for every sample
    let mut ws = pdw::hybrid::Scratch::new();
    for i in 0..tr.len() {
        let Some(b) = w.body_points_in(&mut ws, tr.state(i)) else {
            return (Vec::new(), Vec::new(), "none".into());
        };
        let dx = offsets
            .get(tr.step[i] as usize)
            .or(offsets.last())
            .copied()
            .unwrap_or(0.0);
        for p in &b.points {
            pts.extend_from_slice(&[(p[0] + dx) as f32, p[1] as f32]);
        }
        names = b.names;
    }
    (names, pts, "stance frame moved by the step lengths".into())
}

/// Floats as f32 for the page (plots and figure need no more).
fn f32s(v: &[f64]) -> Vec<f32> {
    v.iter().map(|&x| x as f32).collect()
}

/// The walk as the page's JSON: samples (t, state, body points, energy, loads), events,
/// the model's geometry for drawing.
pub fn walk_json(m: &BuiltModel, tr: &Trajectory) -> Value {
    let (names, pts, frame) = points(m, tr);
    // In one fixed frame (constant between impacts) where the model allows, else the model's.
    let energy = pdw::simulate::fixed_frame_energy(m, tr).or_else(|| tr.energy.clone());
    let events: Vec<Value> = tr
        .events
        .iter()
        .map(|e| json!({"t": e.t, "kind": e.kind, "step": e.step, "ends_step": e.ends_step, "fall": e.fall}))
        .collect();
    let forces = tr.forces.as_ref().map(|f| {
        json!({"normal": f32s(&f.normal), "knee_torque": f32s(&f.knee_torque),
               "friction_required": f32s(&f.friction_required)})
    });
    let foot_radius = m
        .params
        .iter()
        .find(|(n, _)| n == "foot_radius")
        .map_or(0.0, |p| p.1);
    json!({
        "t": f32s(&tr.t),
        "state_names": tr.state_names,
        "x": f32s(&tr.x),
        "step": tr.step,
        "point_names": names,
        "points": pts,
        "frame": frame,
        "energy": energy.as_deref().map(f32s),
        "forces": forces,
        "events": events,
        "steps_done": tr.steps_done,
        "slope": m.slope(),
        "foot_radius": foot_radius,
        "units": {"time": tr.units.time, "force": tr.units.force, "torque": tr.units.torque,
                  "energy": tr.units.energy},
    })
}
