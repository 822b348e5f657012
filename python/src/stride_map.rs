//! `stride_map` and `stride_outcomes`: one stride from each of many states, batched on the
//! pool, with the outcome codes and their legend.

use numpy::{AllowTypeChange, IntoPyArray, PyArrayLike2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::rows_to_array;
use crate::errors::err;
use crate::{build_kw, interruptible, THREADS};
use pdw::limit::basin::BasinOptions;
use pdw::limit::{StrideMap, StrideOutcome};

/// Integration tolerance (DOP853) of `stride_map`, the basin engine's default.
const STRIDE_TOL: f64 = 1e-10;

/// Outcome code of one stride (see `stride_outcomes`).
fn stride_code(o: StrideOutcome) -> u8 {
    match o {
        StrideOutcome::Ok => 0,
        StrideOutcome::Timeout => 1,
        StrideOutcome::NonFinite => 2,
        StrideOutcome::StepTooSmall => 3,
        StrideOutcome::MaxSteps => 4,
        StrideOutcome::TooManyEvents => 5,
        StrideOutcome::Fall { kind, .. } => 16u8.saturating_add(kind.code()),
    }
}

/// `stride_outcomes(model="simplest", **params)`: legend of `stride_map`'s outcome codes.
#[pyfunction]
#[pyo3(signature = (model="simplest", **params), text_signature = "(model='simplest', **params)")]
pub(crate) fn stride_outcomes<'py>(
    py: Python<'py>,
    model: &str,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = build_kw(model, None, params)?;
    let d = PyDict::new(py);
    for (c, n) in [
        (0u8, "ok"),
        (1, "timeout"),
        (2, "nonfinite"),
        (3, "step_too_small"),
        (4, "max_steps"),
        (5, "too_many_events"),
    ] {
        d.set_item(c, n)?;
    }
    let mut seen = Vec::new();
    for mode in 0..m.walker.n_modes() {
        for g in m.walker.guards(mode) {
            if let pdw::hybrid::GuardKind::Terminal(kind) = g.kind {
                if !seen.contains(&kind) {
                    seen.push(kind);
                    d.set_item(16u8.saturating_add(kind.code()), kind.name())?;
                }
            }
        }
    }
    Ok(d)
}

/// `stride_map(model, states, slope=None, **params)` → `(next, outcome, time)`.
#[pyfunction]
#[pyo3(signature = (model, states, slope=None, **params), text_signature = "(model, states, slope=None, **params)")]
pub(crate) fn stride_map<'py>(
    py: Python<'py>,
    model: &str,
    states: PyArrayLike2<'py, f64, AllowTypeChange>,
    slope: Option<&Bound<'py, PyAny>>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let m = build_kw(model, slope, params)?;
    let ds = m.walker.section_dim();
    let view = states.as_array();
    if view.ncols() != ds {
        return Err(err(format!(
            "states: {} columns given, model '{}' has {} section coordinates ({})",
            view.ncols(),
            m.info.name,
            ds,
            m.info.section_names.join(", ")
        )));
    }
    let rows: Vec<Vec<f64>> = view.rows().into_iter().map(|r| r.to_vec()).collect();
    if let Some(r) = rows.iter().position(|r| r.iter().any(|v| !v.is_finite())) {
        return Err(err(format!(
            "states: row {r} {:?} has a non-finite value",
            rows[r]
        )));
    }
    let strides = interruptible(py, || -> PyResult<_> {
        let w = m.walker.as_ref();
        let map = StrideMap::new(w, pdw::hybrid::Options::dop853(STRIDE_TOL)).map_err(err)?;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(THREADS)
            .build()
            .map_err(err)?;
        let opts = BasinOptions::default();
        map.strides_par(&rows, opts.lanes, &pool, opts.chunk, &|_| {})
            .map_err(err)
    })?;
    let n = strides.len();
    let next: Vec<f64> = strides
        .iter()
        .flat_map(|s| s.next.iter().copied())
        .collect();
    let codes: Vec<u8> = strides.iter().map(|s| stride_code(s.outcome)).collect();
    let times: Vec<f64> = strides.iter().map(|s| s.period).collect();
    debug_assert_eq!(next.len(), n * ds);
    Ok((
        rows_to_array(py, next, ds)?,
        codes.into_pyarray(py).into_any(),
        times.into_pyarray(py).into_any(),
    ))
}
