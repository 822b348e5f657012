//! `disturb`: the gait's response to one disturbed stride, or the largest disturbance survived
//! each way — the plan, run and report of `pdw-sweep disturb` ([`pdw::disturb`]), the report
//! returned as a dict with the fields of the CLI's `--json`.

use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::json_to_py;
use crate::errors::err;
use crate::{interruptible, model_choice};
use pdw::pipeline::{Report, Silent, Spelling};

/// `disturb(model="simplest", terrain="step-down", once=None, largest=False, strides=200,
/// tol=1e-5, slope=None, **params)`: `pdw-sweep disturb` — with `once=d` one disturbed stride
/// from the gait (`once` a number, or for slopes a string with its unit, `'0.5deg'`); with
/// `largest=True` the largest disturbance survived each way. Returns the report as a dict:
/// `model`, `terrain`, `parameter`, `nominal`, `unit`, `strides`, and `once` (`disturbance`,
/// `fell`, `strides`, `fall`, `deviation` array, `returned_after`, `return_tol`) or `largest`
/// (a list of `direction`, `survived`, `falls_at`, `at_double_spacing`) with `tol`. `steps` is
/// the old spelling of `strides`.
#[pyfunction]
#[pyo3(
    signature = (model="simplest", terrain="step-down", once=None, largest=false, strides=200, tol=1e-5, slope=None, steps=None, **params),
    text_signature = "(model='simplest', terrain='step-down', once=None, largest=False, strides=200, tol=1e-5, slope=None, **params)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn disturb<'py>(
    py: Python<'py>,
    model: &str,
    terrain: &str,
    once: Option<&Bound<'py, PyAny>>,
    largest: bool,
    strides: i64,
    tol: f64,
    slope: Option<&Bound<'py, PyAny>>,
    steps: Option<i64>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let strides = steps.unwrap_or(strides);
    let input = pdw::disturb::DisturbInput {
        model: model_choice(model, slope, params)?,
        terrain: terrain.to_string(),
        once: once.map(typed).transpose()?,
        largest,
        // a negative count is refused by the plan's range check (as 0 is)
        strides: usize::try_from(strides).unwrap_or(0),
        tol,
        ..Default::default()
    };
    let plan = pdw::disturb::plan(&input, Spelling::Python).map_err(err)?;
    crate::give_warnings(py)?;
    let report = interruptible(py, || plan.run(&Silent).map_err(err))?;
    json_to_py(py, &report.json())
}

/// A disturbance as typed: a number (its shortest exact text) or a string (`'0.5deg'`).
fn typed(v: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(x) = v.extract::<f64>() {
        return Ok(format!("{x:?}"));
    }
    v.extract::<String>().map_err(|_| {
        err(format!(
            "once: {} is neither a number nor a string like '0.5deg'",
            v.repr().map_or_else(|_| "?".into(), |r| r.to_string())
        ))
    })
}
