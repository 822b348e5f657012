//! `continuation`: the gaits over a parameter grid, branch by branch, as `pdw-sweep fixedpoint
//! --sweep` continues them ([`pdw::sweep`]).

use numpy::ndarray::Array2;
use numpy::{Complex64, IntoPyArray};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert::{bifurcation_dict, coordinates_dict, rows_to_array, validity_dict};
use crate::errors::{err, no_start_error};
use crate::{give_warnings, interruptible, overrides, THREADS};
use pdw::limit::trajectory::Validity;
use pdw::limit::{Branch, GridBranch, MeasuredPoint};

/// The swept range and start gait of `continuation` and `orbit_diagram`: at least two points,
/// a non-empty finite range, `stable` or `unstable`.
pub(crate) fn check_sweep_request(
    start: f64,
    stop: f64,
    points: usize,
    gait: &str,
) -> PyResult<()> {
    if points < 2 {
        return Err(err(format!("points: {points} must be an integer >= 2")));
    }
    if !(start.is_finite() && stop.is_finite()) || start == stop {
        return Err(err(format!("start, stop: range {start}:{stop} is empty")));
    }
    if !matches!(gait, "stable" | "unstable") {
        return Err(err(format!(
            "gait: '{gait}' is not one of stable, unstable"
        )));
    }
    Ok(())
}

/// A branch on the output grid as arrays (n = its points on the grid, K = `period_k`).
fn branch_dict<'py>(
    py: Python<'py>,
    b: &GridBranch,
    continued: &Branch,
    ds: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let p = &b.points;
    let k = b.period_k;
    let n = p.len();
    d.set_item("name", &b.name)?;
    d.set_item("period_k", k)?;
    d.set_item(
        "parameter",
        p.iter()
            .map(|q| q.point.param)
            .collect::<Vec<_>>()
            .into_pyarray(py),
    )?;
    d.set_item(
        "section",
        rows_to_array(
            py,
            p.iter()
                .flat_map(|q| q.point.section.iter().copied())
                .collect(),
            ds,
        )?,
    )?;
    let orbit: Vec<f64> = p
        .iter()
        .flat_map(|q| q.point.orbit.iter().flatten().copied())
        .collect();
    d.set_item(
        "orbit",
        numpy::ndarray::Array3::from_shape_vec((n, k, ds), orbit)
            .map_err(err)?
            .into_pyarray(py),
    )?;
    d.set_item(
        "period",
        p.iter()
            .map(|q| q.point.period)
            .collect::<Vec<_>>()
            .into_pyarray(py),
    )?;
    d.set_item(
        "step_length",
        rows_to_array(
            py,
            p.iter()
                .flat_map(|q| q.step_length.iter().copied())
                .collect(),
            k,
        )?,
    )?;
    d.set_item(
        "speed",
        p.iter()
            .map(MeasuredPoint::speed)
            .collect::<Vec<_>>()
            .into_pyarray(py),
    )?;
    d.set_item(
        "stable",
        p.iter()
            .map(|q| q.point.stable)
            .collect::<Vec<_>>()
            .into_pyarray(py),
    )?;
    let valid: Vec<bool> = p
        .iter()
        .flat_map(|q| {
            q.validity
                .iter()
                .map(|v| v.as_ref().is_none_or(Validity::valid))
        })
        .collect();
    d.set_item(
        "valid",
        Array2::from_shape_vec((n, k), valid)
            .map_err(err)?
            .into_pyarray(py),
    )?;
    let validity = PyList::empty(py);
    for q in p {
        let per = PyList::empty(py);
        for v in &q.validity {
            per.append(v.as_ref().map(|v| validity_dict(py, v)).transpose()?)?;
        }
        validity.append(per)?;
    }
    d.set_item("validity", validity)?;
    let nm = p.first().map_or(0, |q| q.point.multipliers.len());
    let mult: Vec<Complex64> = p
        .iter()
        .flat_map(|q| {
            q.point
                .multipliers
                .iter()
                .map(|l| Complex64::new(l.re, l.im))
        })
        .collect();
    d.set_item(
        "multipliers",
        Array2::from_shape_vec((n, nm), mult)
            .map_err(err)?
            .into_pyarray(py),
    )?;
    let bifs = PyList::empty(py);
    for bf in &continued.bifurcations {
        bifs.append(bifurcation_dict(py, bf)?)?;
    }
    d.set_item("bifurcations", bifs)?;
    d.set_item("internal_points", continued.points.len())?;
    Ok(d)
}

/// `continuation(model, parameter="slope", start, stop, points=100, gait="stable", threads=2,
/// max_period=2, start_at=None, **params)`: `pdw-sweep fixedpoint --sweep
/// NAME=start:stop:points --max-period P --from MU`, branch by branch.
#[pyfunction]
#[pyo3(
    signature = (model="simplest", parameter="slope", start=0.001, stop=0.019, points=100, gait="stable", threads=THREADS, max_period=2, start_at=None, **params),
    text_signature = "(model='simplest', parameter='slope', start=0.001, stop=0.019, points=100, gait='stable', threads=2, max_period=2, start_at=None, **params)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn continuation<'py>(
    py: Python<'py>,
    model: &str,
    parameter: &str,
    start: f64,
    stop: f64,
    points: usize,
    gait: &str,
    threads: usize,
    max_period: usize,
    start_at: Option<f64>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    check_sweep_request(start, stop, points, gait)?;
    pdw::input::check_threads(threads, "threads").map_err(err)?;
    pdw::input::check_max_period(max_period, "max_period").map_err(err)?;
    let mut fixed = overrides(None, params)?;
    fixed.retain(|(n, _)| n != parameter);
    let grid = pdw::input::Sweep {
        name: parameter.to_string(),
        lo: start,
        hi: stop,
        n: points,
    };
    let from = start_at
        .map(|mu| pdw::input::check_from(mu, &grid, "start_at"))
        .transpose()
        .map_err(err)?;
    let plan = pdw::sweep::SweepPlan {
        model: model.to_string(),
        fixed,
        grid,
        start: match gait {
            "unstable" => pdw::sweep::StartChoice::Unstable,
            _ => pdw::sweep::StartChoice::Stable,
        },
        tol: 1e-12,
        integrator: None,
        from,
        max_period,
    };
    let m0 = plan.start_model();
    give_warnings(py)?;
    let m0 = m0.map_err(err)?;
    let ds = m0.walker.section_dim();
    let result = interruptible(py, || -> PyResult<pdw::limit::Sweep> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(err)?;
        let s = match pdw::sweep::find_start(&plan, None, &pool).map_err(err)? {
            Ok(s) => s,
            Err(none) => return Err(no_start_error(&m0, &plan, gait, &none)),
        };
        let silent = &pdw::limit::sweep::Silent;
        pdw::sweep::continuation(&plan, &s.section, s.param, &pool, silent).map_err(err)
    })?;
    for w in &result.warnings {
        let msg = std::ffi::CString::new(w.as_str()).map_err(err)?;
        PyErr::warn(
            py,
            &py.get_type::<pyo3::exceptions::PyUserWarning>(),
            &msg,
            1,
        )?;
    }
    let list = PyList::empty(py);
    let coordinates = coordinates_dict(py, &m0)?;
    for (b, (_, c)) in result.branches.iter().zip(&result.continued) {
        let bd = branch_dict(py, b, c, ds)?;
        bd.set_item("coordinates", &coordinates)?;
        list.append(bd)?;
    }
    Ok(list)
}
