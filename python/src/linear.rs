//! Linear stability data ([`pdw::linear`]): `fixed_point(..., jacobian=True)`'s extra keys and
//! `lyapunov`.

use numpy::ndarray::Array2;
use numpy::{Complex64, IntoPyArray};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert::rows_to_array;
use crate::errors::err;
use crate::{build_kw, interruptible};
use pdw::linear::{Eigenpair, Impact};

/// Strides of the Lyapunov exponents `fixed_point(jacobian=True)` reports.
pub(crate) const LYAPUNOV_STRIDES: usize = 100;

/// What `jacobian=True` adds to a gait: computed off the interpreter.
pub(crate) struct Linear {
    dp: Vec<f64>,
    pairs: Vec<Eigenpair>,
    impacts: Vec<Impact>,
    lyapunov: Vec<f64>,
}

/// `DP`, its eigenpairs, the impacts' saltation matrices and the Lyapunov exponents over
/// [`LYAPUNOV_STRIDES`] strides, at section state `s` of `m`.
pub(crate) fn linear(m: &pdw::BuiltModel, s: &[f64]) -> PyResult<Linear> {
    let n = s.len();
    let (dp, _) = pdw::linear::jacobian(m, s).map_err(err)?;
    Ok(Linear {
        pairs: pdw::linear::eigenpairs(&dp, n).map_err(err)?,
        impacts: pdw::linear::impacts(m, s).map_err(err)?,
        lyapunov: pdw::linear::lyapunov(m, s, LYAPUNOV_STRIDES).map_err(err)?,
        dp,
    })
}

/// Sets `jacobian` (d_s, d_s), `eigenvalues` (d_s,) and `eigenvectors` (d_s, d_s; column k
/// belongs to eigenvalue k, unit norm), `impacts` (event, t, mode_before, mode_after, pre,
/// `saltation` (d, d)) and `lyapunov` (d_s,) on `d`.
pub(crate) fn set_linear<'py>(py: Python<'py>, d: &Bound<'py, PyDict>, l: &Linear) -> PyResult<()> {
    let n = l.pairs.len();
    d.set_item("jacobian", rows_to_array(py, l.dp.clone(), n)?)?;
    let c = |z: (f64, f64)| Complex64::new(z.0, z.1);
    let values: Vec<Complex64> = l.pairs.iter().map(|p| c(p.value)).collect();
    d.set_item("eigenvalues", values.into_pyarray(py))?;
    let vectors = Array2::from_shape_fn((n, n), |(i, k)| c(l.pairs[k].vector[i]));
    d.set_item("eigenvectors", vectors.into_pyarray(py))?;
    let impacts = PyList::empty(py);
    for im in &l.impacts {
        let e = PyDict::new(py);
        e.set_item("event", &im.event)?;
        e.set_item("t", im.t)?;
        e.set_item("mode_before", im.mode_before)?;
        e.set_item("mode_after", im.mode_after)?;
        e.set_item("pre", im.pre.clone().into_pyarray(py))?;
        e.set_item(
            "saltation",
            rows_to_array(py, im.saltation.clone(), im.pre.len())?,
        )?;
        impacts.append(e)?;
    }
    d.set_item("impacts", impacts)?;
    d.set_item("lyapunov", l.lyapunov.clone().into_pyarray(py))?;
    d.set_item("lyapunov_strides", LYAPUNOV_STRIDES)?;
    Ok(())
}

/// `lyapunov(model="simplest", state=None, strides=100, slope=None, **params)`: finite-time
/// Lyapunov exponents of the stride map (per stride, descending) over `strides` strides from
/// section state `state` (default: the stable gait, else the first found).
#[pyfunction]
#[pyo3(
    signature = (model="simplest", state=None, strides=100, slope=None, **params),
    text_signature = "(model='simplest', state=None, strides=100, slope=None, **params)"
)]
pub(crate) fn lyapunov<'py>(
    py: Python<'py>,
    model: &str,
    state: Option<Vec<f64>>,
    strides: usize,
    slope: Option<&Bound<'py, PyAny>>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    if !(1..=1_000_000).contains(&strides) {
        return Err(err(format!(
            "strides: {strides} must be between 1 and 1000000"
        )));
    }
    let m = build_kw(model, slope, params)?;
    let ds = m.walker.section_dim();
    if let Some(s) = &state {
        if s.len() != ds || s.iter().any(|v| !v.is_finite()) {
            return Err(err(format!(
                "state: {s:?} must be {ds} finite section coordinates ({})",
                m.info.section_names.join(", ")
            )));
        }
    }
    let exps = interruptible(py, || -> PyResult<_> {
        let s = match state {
            Some(s) => s,
            None => {
                let (found, failed, n) = crate::fixed_point::find_gaits(&m, None, 1e-12)?;
                let Some(f) = pdw::gaits::selected(&found) else {
                    return Err(crate::errors::no_gait_error(&m, "all", n, &failed));
                };
                f.fp.section.clone()
            }
        };
        pdw::linear::lyapunov(&m, &s, strides).map_err(err)
    })?;
    Ok(exps.into_pyarray(py).into_any())
}
