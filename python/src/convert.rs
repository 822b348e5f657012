//! Conversions of the library's results into Python objects that several functions return:
//! arrays of rows, complex multipliers, a gait's validity report, attractors, bifurcations and
//! the meanings of the state coordinates.

use numpy::ndarray::Array2;
use numpy::{Complex64, IntoPyArray};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::errors::err;
use crate::Model;
use pdw::limit::trajectory::Validity;
use pdw::limit::{Attractor, AttractorKind, Bifurcation};

pub(crate) fn rows_to_array<'py>(
    py: Python<'py>,
    v: Vec<f64>,
    cols: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let rows = v.len().checked_div(cols).unwrap_or(0);
    let a = Array2::from_shape_vec((rows, cols), v).map_err(err)?;
    Ok(a.into_pyarray(py).into_any())
}

pub(crate) fn complex_array<'py>(
    py: Python<'py>,
    m: &[pdw::limit::Multiplier],
) -> Bound<'py, PyAny> {
    m.iter()
        .map(|l| Complex64::new(l.re, l.im))
        .collect::<Vec<_>>()
        .into_pyarray(py)
        .into_any()
}

/// A gait's validity as the dict of the CLI's `validity` ([`pdw::validity::validity_json`]):
/// the same keys, `None` where the CLI writes null (a number not defined, e.g. no knees).
pub(crate) fn validity_dict<'py>(py: Python<'py>, v: &Validity) -> PyResult<Bound<'py, PyAny>> {
    json_to_py_lists(py, &pdw::validity::validity_json(v))
}

pub(crate) fn attractor_dict<'py>(py: Python<'py>, a: &Attractor) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", &a.name)?;
    d.set_item("code", a.code)?;
    d.set_item(
        "kind",
        match a.kind {
            AttractorKind::Periodic => "periodic",
            AttractorKind::Chaotic => "chaotic",
        },
    )?;
    d.set_item("period_k", a.period_k)?;
    let ds = a.points.first().map_or(0, Vec::len);
    d.set_item("points", rows_to_array(py, a.points.concat(), ds)?)?;
    d.set_item("multipliers", complex_array(py, &a.multipliers))?;
    d.set_item("period_time", a.period_time)?;
    d.set_item("radius", a.radius)?;
    // Physical validity of the orbit: True, False, or None (not checked).
    let (valid, reasons): (Option<bool>, Vec<&str>) = match &a.validity {
        pdw::limit::OrbitValidity::Unchecked => (None, Vec::new()),
        pdw::limit::OrbitValidity::Valid => (Some(true), Vec::new()),
        pdw::limit::OrbitValidity::Invalid(r) => (Some(false), r.clone()),
    };
    d.set_item("valid", valid)?;
    d.set_item("invalid", reasons)?;
    Ok(d)
}

pub(crate) fn bifurcation_dict<'py>(
    py: Python<'py>,
    bf: &Bifurcation,
) -> PyResult<Bound<'py, PyDict>> {
    let bd = PyDict::new(py);
    bd.set_item("kind", bf.kind.name())?;
    bd.set_item("parameter", bf.param)?;
    bd.set_item("section", bf.section.clone().into_pyarray(py))?;
    bd.set_item("multipliers", complex_array(py, &bf.multipliers))?;
    Ok(bd)
}

/// What each state component of `m` means, state name → meaning (the files' `coordinates`
/// attribute).
pub(crate) fn coordinates_dict<'py>(py: Python<'py>, m: &Model) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (n, c) in m
        .walker
        .state_names()
        .into_iter()
        .zip(m.walker.coordinate_meanings())
    {
        d.set_item(n, c)?;
    }
    Ok(d)
}

/// A report of the library's pipeline ([`pdw::pipeline::Report::json`]) as Python objects: an
/// object a dict, a list of floats a NumPy array (a list of anything else a list), a string a
/// str, an integer an int, a float a float, null `None`. The CLI's `--json` and Python's dict
/// then hold the same fields under the same names.
pub(crate) fn json_to_py<'py>(
    py: Python<'py>,
    v: &serde_json::Value,
) -> PyResult<Bound<'py, PyAny>> {
    json_value(py, v, true)
}

/// [`json_to_py`] with every list a list (numbers and all): the nested objects a front end
/// compares with the CLI's JSON as they are (a gait's validity).
pub(crate) fn json_to_py_lists<'py>(
    py: Python<'py>,
    v: &serde_json::Value,
) -> PyResult<Bound<'py, PyAny>> {
    json_value(py, v, false)
}

fn json_value<'py>(
    py: Python<'py>,
    v: &serde_json::Value,
    arrays: bool,
) -> PyResult<Bound<'py, PyAny>> {
    use pyo3::IntoPyObjectExt;
    use serde_json::Value;
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_bound_py_any(py)?,
        Value::Number(n) => match (n.as_u64(), n.as_i64()) {
            (Some(u), _) => u.into_bound_py_any(py)?,
            (None, Some(i)) => i.into_bound_py_any(py)?,
            _ => n.as_f64().unwrap_or(f64::NAN).into_bound_py_any(py)?,
        },
        Value::String(s) => s.into_bound_py_any(py)?,
        Value::Array(items) => {
            let floats: Option<Vec<f64>> = if arrays {
                items
                    .iter()
                    .map(|x| {
                        x.as_number()
                            .filter(|n| n.is_f64())
                            .and_then(|n| n.as_f64())
                    })
                    .collect()
            } else {
                None
            };
            match floats {
                Some(f) if !f.is_empty() => f.into_pyarray(py).into_any(),
                _ => {
                    let l = PyList::empty(py);
                    for x in items {
                        l.append(json_value(py, x, arrays)?)?;
                    }
                    l.into_any()
                }
            }
        }
        Value::Object(map) => {
            let d = PyDict::new(py);
            for (k, x) in map {
                d.set_item(k, json_value(py, x, arrays)?)?;
            }
            d.into_any()
        }
    })
}
