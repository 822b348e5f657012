//! `basin_over`: basin stability over a model parameter, as `pdw-sweep basin --over
//! NAME=A:B:N` computes it ([`pdw::basin_over`]; Menck et al. 2013).

use numpy::ndarray::Array2;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::basin::GivenAxis;
use crate::convert::attractor_dict;
use crate::errors::err;
use crate::{build_kw, interruptible, overrides, THREADS};
use pdw::basin::{AxisFlags, BasinRequest};
use pdw::basin_over::{AtValue, OverPlan};
use pdw::limit::basin::{BasinOptions, Outcome};

/// The names of the axes in messages.
const FLAGS: AxisFlags = AxisFlags {
    x: "x",
    y: "y",
    z: "z",
};

/// The parameter varied: `over="NAME=A:B:N"`, else `parameter`, `start`, `stop`, `points`.
fn over_range(
    over: Option<&str>,
    (parameter, start, stop, points): (Option<&str>, Option<f64>, Option<f64>, usize),
) -> PyResult<pdw::input::Sweep> {
    match (over, parameter, start, stop) {
        (Some(o), None, None, None) => pdw::input::parse_range_count(o, "over").map_err(err),
        (None, Some(name), Some(lo), Some(hi)) => {
            let text = format!("{name}={lo}:{hi}:{points}");
            pdw::input::parse_range_count(&text, "over").map_err(err)
        }
        _ => Err(err(
            "over: give either over=\"NAME=A:B:N\" or parameter, start, stop (and points)",
        )),
    }
}

/// `basin_over(model="simplest", over=None, parameter=None, start=None, stop=None, points=6,
/// slope=None, grid=(41, 41), x=None, y=None, max_strides=100, threads=2, **params)`.
#[pyfunction]
#[pyo3(
    signature = (model="simplest", over=None, parameter=None, start=None, stop=None, points=6, slope=None, grid=(41, 41), x=None, y=None, max_strides=100, threads=THREADS, **params),
    text_signature = "(model='simplest', over=None, parameter=None, start=None, stop=None, points=6, slope=None, grid=(41, 41), x=None, y=None, max_strides=100, threads=2, **params)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn basin_over<'py>(
    py: Python<'py>,
    model: &str,
    over: Option<&str>,
    parameter: Option<&str>,
    start: Option<f64>,
    stop: Option<f64>,
    points: usize,
    slope: Option<&Bound<'py, PyAny>>,
    grid: (usize, usize),
    x: GivenAxis,
    y: GivenAxis,
    max_strides: u32,
    threads: usize,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let range = over_range(over, (parameter, start, stop, points))?;
    let (nx, ny) = grid;
    if nx == 0 || ny == 0 || nx.saturating_mul(ny) > 100_000_000 {
        return Err(err(format!(
            "grid: ({nx}, {ny}) must have positive sizes and at most 10^8 cells"
        )));
    }
    let max_strides = pdw::basin::check_max_strides(max_strides, "max_strides").map_err(err)?;
    pdw::input::check_threads(threads, "threads").map_err(err)?;
    let info = pdw::walkers::model_info(model).map_err(err)?;
    pdw::basin::check_section(&info, "box").map_err(err)?;
    crate::basin::check_basin_memory(&[nx, ny], info.section_names.len())?;
    let ov = overrides(crate::slope_arg(slope)?, params)?;
    let (given, fixed) = pdw::basin::split_overrides(ov, &info.section_names);
    pdw::basin_over::check_over(&info, &given, &range, "over").map_err(err)?;
    // the model as given (warnings, e.g. a steep slope)
    build_kw(model, slope, params)?;
    let axis = |g: GivenAxis, which: &str| {
        let r = g.map(|(name, lo, hi)| pdw::input::AxisRange { name, lo, hi });
        pdw::basin::resolve_axis(&info, r, which).map_err(err)
    };
    let req = BasinRequest {
        grid,
        x: axis(x, "x")?,
        y: axis(y, "y")?,
        z: None,
        fixed,
        max_strides,
        integrator: BasinOptions::default_integrator(),
    };
    let (plan, results) = interruptible(py, || -> PyResult<_> {
        let plan = pdw::basin_over::plan(model, &given, &range, req, FLAGS, "over").map_err(err)?;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(err)?;
        let mut slow = Vec::new();
        let mut results = Vec::with_capacity(plan.values.len());
        for (i, mu) in plan.values.iter().enumerate() {
            let mut on_slow = |s: &pdw::basin::SlowAttractor<'_>| {
                slow.push(format!(
                    "{} = {mu}: attractor `{}` has |λ| = {:.4} per {} stride(s); cells \
                     converge in about {} strides, more than max_strides {}: expect `timeout` \
                     there",
                    range.name,
                    s.attractor.name,
                    s.modulus,
                    s.attractor.period_k,
                    s.strides,
                    max_strides
                ))
            };
            let r = pdw::basin_over::at_value(&plan, i, &pool, &mut on_slow, &|_| {});
            results.push(r.map_err(err)?);
        }
        Ok(((plan, slow), results))
    })?;
    let (plan, slow) = plan;
    crate::warn_all(py, &slow)?;
    over_dict(py, &plan, &range, &results)
}

/// The dict `basin_over` returns: the values, the table of fractions (one column per
/// attractor met, then fall, timeout, other), the fractions of the fixed outcome codes, every
/// value's attractors, the box.
fn over_dict<'py>(
    py: Python<'py>,
    plan: &OverPlan,
    range: &pdw::input::Sweep,
    results: &[AtValue],
) -> PyResult<Bound<'py, PyDict>> {
    let columns = pdw::basin_over::columns(results);
    let table = pdw::basin_over::fraction_table(results, &columns);
    let n = results.len();
    let d = PyDict::new(py);
    d.set_item("parameter", &range.name)?;
    d.set_item("values", plan.values.clone().into_pyarray(py))?;
    d.set_item(
        "columns",
        columns.iter().map(|c| c.0.clone()).collect::<Vec<_>>(),
    )?;
    d.set_item("kinds", columns.iter().map(|c| c.1).collect::<Vec<_>>())?;
    d.set_item(
        "fractions",
        Array2::from_shape_vec((n, columns.len()), table.concat())
            .map_err(err)?
            .into_pyarray(py),
    )?;
    d.set_item(
        "outcome_columns",
        Outcome::CELL_ENDS
            .iter()
            .map(|o| o.name())
            .collect::<Vec<_>>(),
    )?;
    let outcomes: Vec<f64> = results.iter().flat_map(|r| r.outcomes.clone()).collect();
    d.set_item(
        "outcome_fractions",
        Array2::from_shape_vec((n, Outcome::CELL_ENDS.len()), outcomes)
            .map_err(err)?
            .into_pyarray(py),
    )?;
    let atts = PyList::empty(py);
    for r in results {
        let at = PyList::empty(py);
        for a in &r.attractors {
            at.append(attractor_dict(py, a)?)?;
        }
        atts.append(at)?;
    }
    d.set_item("attractors", atts)?;
    let (bx, names) = (&plan.bx, &plan.models[0].info.section_names);
    let bd = PyDict::new(py);
    for (k, a, n) in [("x", &bx.x, bx.nx), ("y", &bx.y, bx.ny)] {
        bd.set_item(k, (a.range.name.clone(), a.range.lo, a.range.hi, n))?;
    }
    let fixed = PyDict::new(py);
    for (i, v) in &plan.req.fixed {
        fixed.set_item(&names[*i], v)?;
    }
    bd.set_item("fixed", fixed)?;
    bd.set_item("source", &plan.box_source)?;
    d.set_item("box", bd)?;
    d.set_item("max_strides", plan.req.max_strides)?;
    Ok(d)
}
