//! `simulate`: a walk of N strides as a dict of arrays — states, events, the walker's points,
//! units — as `pdw-sweep simulate` ([`pdw::simulate`]).

use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{json_to_py, rows_to_array};
use crate::errors::err;
use crate::{interruptible, model_choice, Model};
use pdw::limit::trajectory::{self, Trajectory};
use pdw::pipeline::{Report, Silent, Spelling};
use pdw::simulate::SimulateInput;

/// `simulate(model="simplest", slope=None, state=None, gait="stable", strides=10, dt_out=None,
/// out=None, force=False, **params)`: the walk of `pdw-sweep simulate` as a dict — the report's
/// fields (`model`, `slope`, `start`, `strides`, `strides_done`, `samples`, `events`,
/// `outcome`, `fell`, `dt_out`, `dt_out_source`, `out`) and the arrays. With `out` the same
/// file as the CLI's `--out` is written. `steps` is the old spelling of `strides`, and
/// `steps_done` of `strides_done`.
#[pyfunction]
#[pyo3(
    signature = (model="simplest", slope=None, state=None, gait=None, strides=10, dt_out=None, out=None, force=false, steps=None, **params),
    text_signature = "(model='simplest', slope=None, state=None, gait=None, strides=10, dt_out=None, out=None, force=False, **params)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn simulate<'py>(
    py: Python<'py>,
    model: &str,
    slope: Option<&Bound<'py, PyAny>>,
    state: Option<Vec<f64>>,
    gait: Option<String>,
    strides: i64,
    dt_out: Option<&Bound<'py, PyAny>>,
    out: Option<std::path::PathBuf>,
    force: bool,
    steps: Option<i64>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let strides = steps.unwrap_or(strides);
    let input = SimulateInput {
        model: model_choice(model, slope, params)?,
        integrator: Default::default(),
        // a negative count is refused by the plan as 0 is
        strides: usize::try_from(strides).unwrap_or(0),
        dt_out: dt_out_of(dt_out)?,
        state,
        gait,
        out,
        force,
        command: format!("pdw_sweep.simulate(model={model:?}, …)"),
    };
    let plan = pdw::simulate::plan(&input, Spelling::Python).map_err(err)?;
    crate::give_warnings(py)?;
    let run = interruptible(py, || plan.run(&Silent).map_err(err))?;
    let m = &plan.model;
    let d = trajectory_dict(py, m, &run.trajectory)?;
    if let serde_json::Value::Object(fields) = run.report.json() {
        for (k, v) in &fields {
            d.set_item(k, json_to_py(py, v)?)?;
        }
    }
    d.set_item("steps_done", run.report.strides_done)?;
    positions_items(py, &d, m, &run.trajectory)?;
    Ok(d)
}

fn dt_out_of(v: Option<&Bound<'_, PyAny>>) -> PyResult<pdw::simulate::DtOut> {
    use pdw::simulate::DtOut;
    let Some(v) = v.filter(|v| !v.is_none()) else {
        return Ok(DtOut::Default);
    };
    if let Ok(s) = v.extract::<String>() {
        return DtOut::parse(&s, "dt_out").map_err(err);
    }
    match v.extract::<f64>() {
        Ok(h) => Ok(DtOut::Every(h)),
        Err(_) => Err(err(format!(
            "dt_out: {} is neither a positive time step nor the word steps",
            v.repr().map(|r| r.to_string()).unwrap_or_default()
        ))),
    }
}

/// The walker's points and centre of mass in the walk's fixed frame: `positions` (n, P, 2),
/// `point_names`, `com` (n, 2) and `positions_frame`; where there are none, `point_names` is
/// empty and `positions_frame` says why.
fn positions_items<'py>(
    py: Python<'py>,
    d: &Bound<'py, PyDict>,
    m: &Model,
    tr: &Trajectory,
) -> PyResult<()> {
    match pdw::simulate::positions(m, tr) {
        Ok(p) => {
            let (n, np) = (tr.len(), p.names.len());
            let a = numpy::ndarray::Array3::from_shape_vec((n, np, 2), p.points).map_err(err)?;
            d.set_item("positions", a.into_pyarray(py))?;
            d.set_item("com", rows_to_array(py, p.com, 2)?)?;
            d.set_item("point_names", p.names)?;
            d.set_item("positions_frame", pdw::simulate::POSITIONS_FRAME)?;
        }
        Err(why) => {
            d.set_item("point_names", Vec::<String>::new())?;
            d.set_item("positions_frame", why)?;
        }
    }
    Ok(())
}

/// A trajectory as `simulate` returns it: time, states (rows), mode, step, forces, flags,
/// energy where the model has them, the events, the section points, the outcome, the units.
fn trajectory_dict<'py>(
    py: Python<'py>,
    m: &Model,
    tr: &Trajectory,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("state_names", tr.state_names.clone())?;
    d.set_item("t", tr.t.clone().into_pyarray(py))?;
    d.set_item("x", rows_to_array(py, tr.x.clone(), tr.dim())?)?;
    d.set_item("mode", tr.mode.clone().into_pyarray(py))?;
    // What the mode codes and the state components mean (`pdw-sweep models` lists the same).
    d.set_item("mode_names", m.walker.mode_names())?;
    d.set_item("coordinates", m.walker.coordinate_meanings())?;
    d.set_item("step", tr.step.clone().into_pyarray(py))?;
    if let Some(f) = &tr.forces {
        d.set_item("normal_force", f.normal.clone().into_pyarray(py))?;
        d.set_item("tangential_force", f.tangential.clone().into_pyarray(py))?;
        d.set_item(
            "friction_required",
            f.friction_required.clone().into_pyarray(py),
        )?;
        d.set_item("knee_torque", rows_to_array(py, f.knee_torque.clone(), 2)?)?;
    }
    if let Some(fl) = &tr.flags {
        d.set_item("flags", fl.clone().into_pyarray(py))?;
    }
    if let Some(e) = pdw::simulate::fixed_frame_energy(m, tr) {
        d.set_item("energy_fixed_frame", e.into_pyarray(py))?;
    }
    if let Some(e) = &tr.energy {
        d.set_item("energy", e.clone().into_pyarray(py))?;
    }
    d.set_item("events", events_dict(py, &tr.events, tr.dim())?)?;
    d.set_item(
        "section",
        rows_to_array(py, tr.section.clone(), m.walker.section_dim())?,
    )?;
    d.set_item("units", units_dict(py, tr)?)?;
    Ok(d)
}

/// The events of a trajectory as columns: time, kind, step, whether it ends a step, the modes
/// before and after, the states before and after (rows of `dim`).
fn events_dict<'py>(
    py: Python<'py>,
    e: &[trajectory::TrajectoryEvent],
    dim: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let ev = PyDict::new(py);
    let column = |f: &dyn Fn(&trajectory::TrajectoryEvent) -> u32| -> Bound<'py, PyAny> {
        e.iter()
            .map(f)
            .collect::<Vec<_>>()
            .into_pyarray(py)
            .into_any()
    };
    ev.set_item(
        "t",
        e.iter().map(|e| e.t).collect::<Vec<_>>().into_pyarray(py),
    )?;
    ev.set_item("kind", e.iter().map(|e| e.kind.clone()).collect::<Vec<_>>())?;
    ev.set_item("step", column(&|e| e.step as u32))?;
    ev.set_item(
        "ends_step",
        e.iter()
            .map(|e| e.ends_step)
            .collect::<Vec<_>>()
            .into_pyarray(py),
    )?;
    ev.set_item("mode_before", column(&|e| e.mode_before as u32))?;
    ev.set_item("mode_after", column(&|e| e.mode_after as u32))?;
    let states = |f: &dyn Fn(&trajectory::TrajectoryEvent) -> &[f64]| {
        rows_to_array(
            py,
            e.iter().flat_map(|e| f(e).iter().copied()).collect(),
            dim,
        )
    };
    ev.set_item("pre", states(&|e| &e.pre)?)?;
    ev.set_item("post", states(&|e| &e.post)?)?;
    Ok(ev)
}

/// The unit of every column of a trajectory, by the column's name.
fn units_dict<'py>(py: Python<'py>, tr: &Trajectory) -> PyResult<Bound<'py, PyDict>> {
    let u = &tr.units;
    let ud = PyDict::new(py);
    ud.set_item("t", &u.time)?;
    for (name, unit) in tr.state_names.iter().zip(&u.state) {
        ud.set_item(name, unit)?;
    }
    ud.set_item("normal_force", &u.force)?;
    ud.set_item("tangential_force", &u.force)?;
    ud.set_item("friction_required", "1")?;
    ud.set_item("knee_torque", &u.torque)?;
    ud.set_item("energy", &u.energy)?;
    Ok(ud)
}
