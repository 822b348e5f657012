//! `stride_map` and `stride_outcomes`: one stride from each of many states, batched on the
//! pool, with the codes of how each stride ended and their legend: the one table of ends
//! (`pdw::limit::End`), whose codes are those of `/basin/outcome`.

use numpy::{AllowTypeChange, IntoPyArray, PyArrayLike2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::rows_to_array;
use crate::errors::err;
use crate::{build_kw, interruptible, THREADS};
use pdw::limit::basin::BasinOptions;
use pdw::limit::{End, StrideMap};

/// Integration tolerance (DOP853) of `stride_map`, the basin engine's default.
const STRIDE_TOL: f64 = 1e-10;

/// `stride_outcomes(model="simplest", **params)`: legend of `stride_map`'s codes, `{code:
/// name}` for every end a stride of the model can have (names and codes of the one table,
/// `End::ALL`: the basin file's for the same ends).
#[pyfunction]
#[pyo3(signature = (model="simplest", **params), text_signature = "(model='simplest', **params)")]
pub(crate) fn stride_outcomes<'py>(
    py: Python<'py>,
    model: &str,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = build_kw(model, None, params)?;
    let mut ends = vec![
        End::HeelStrike,
        End::FallNoHeelStrike,
        End::NonFinite,
        End::IntegratorFailure,
    ];
    for mode in 0..m.walker.n_modes() {
        for g in m.walker.guards(mode) {
            if let pdw::hybrid::GuardKind::Terminal(kind) = g.kind {
                ends.push(End::of_fall(kind));
            }
        }
    }
    ends.sort_unstable();
    ends.dedup();
    let d = PyDict::new(py);
    for e in ends {
        d.set_item(e.code(), e.name())?;
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
    let codes: Vec<u8> = strides.iter().map(|s| s.outcome.end().code()).collect();
    let times: Vec<f64> = strides.iter().map(|s| s.period).collect();
    debug_assert_eq!(next.len(), n * ds);
    Ok((
        rows_to_array(py, next, ds)?,
        codes.into_pyarray(py).into_any(),
        times.into_pyarray(py).into_any(),
    ))
}
