//! `gait_sensitivity`: the gait sensitivity norm of `pdw-sweep fixedpoint --gsn`
//! ([`pdw::gsn`]) with its linear system as numpy arrays.

use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::rows_to_array;
use crate::errors::{err, no_gait_error};
use crate::fixed_point::find_gaits;
use crate::{build_kw, interruptible};
use pdw::limit::gsn::Indicator;

/// The indicators as a comma-separated string or a list of names.
fn indicator_list(v: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<Indicator>> {
    let Some(v) = v else {
        return Ok(Indicator::DEFAULT.to_vec());
    };
    let s = match v.extract::<String>() {
        Ok(s) => s,
        Err(_) => v.extract::<Vec<String>>()?.join(","),
    };
    pdw::gsn::parse_indicators(&s, "indicators").map_err(err)
}

/// `gait_sensitivity(model="simplest", slope=None, indicators=None, guess=None, **params)`:
/// the gait sensitivity norm of the stable period-one gait (or of the gait Newton finds from
/// `guess`) against the slope of the next landing line; an unstable gait raises `ValueError`.
#[pyfunction]
#[pyo3(
    signature = (model="simplest", slope=None, indicators=None, guess=None, **params),
    text_signature = "(model='simplest', slope=None, indicators=None, guess=None, **params)"
)]
pub(crate) fn gait_sensitivity<'py>(
    py: Python<'py>,
    model: &str,
    slope: Option<&Bound<'py, PyAny>>,
    indicators: Option<&Bound<'py, PyAny>>,
    guess: Option<Vec<f64>>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let ind = indicator_list(indicators)?;
    let m = build_kw(model, slope, params)?;
    pdw::mfpt::check_model(&m).map_err(err)?;
    let user = guess.is_some();
    let (section, lin, g) = interruptible(py, || -> PyResult<_> {
        let (found, failed, n) = find_gaits(&m, guess, pdw::mfpt::GAIT_TOL)?;
        let f = match found.iter().find(|f| f.fp.stable || user) {
            Some(f) => f,
            None => return Err(no_gait_error(&m, "stable", n, &failed)),
        };
        let s = f.fp.section.clone();
        let (lin, g) = pdw::gsn::gait_sensitivity(&m, &s, &ind, pdw::gsn::default_integrator())
            .map_err(err)?;
        Ok((s, lin, g))
    })?;
    let d = PyDict::new(py);
    d.set_item("norm", g.norm)?;
    d.set_item("indicators", pdw::gsn::names(&ind))?;
    d.set_item("per_indicator", g.per_indicator.clone().into_pyarray(py))?;
    let n = lin.n;
    d.set_item("A", rows_to_array(py, lin.a.clone(), n)?)?;
    d.set_item("B", rows_to_array(py, lin.b.clone(), 1)?)?;
    d.set_item("C", rows_to_array(py, lin.c.clone(), n)?)?;
    d.set_item("D", rows_to_array(py, lin.d.clone(), 1)?)?;
    d.set_item("gramian", rows_to_array(py, g.gramian.clone(), n)?)?;
    d.set_item("indicator_values", lin.g0.clone().into_pyarray(py))?;
    d.set_item("spectral_radius", g.radius)?;
    d.set_item("fd_error", lin.fd_error)?;
    d.set_item("section", section.into_pyarray(py))?;
    d.set_item("slope", m.slope())?;
    Ok(d)
}
