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

pub(crate) fn validity_dict<'py>(py: Python<'py>, v: &Validity) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("valid", v.valid())?;
    d.set_item("min_normal_force", v.min_normal_force)?;
    d.set_item("max_friction_required", v.max_friction_required)?;
    d.set_item("min_knee_torque", v.min_knee_torque)?;
    d.set_item("normal_force_negative", v.normal_force_negative)?;
    d.set_item("knee_unlocks", v.knee_unlocks)?;
    d.set_item("swing_foot_scuffs", v.swing_foot_scuffs)?;
    // located on the dense solution (pdw::limit::validity): margins, clearance, impacts
    d.set_item("impact_violation", v.impact_violation)?;
    d.set_item("continuous", v.continuous)?;
    d.set_item("fell", v.fell.clone())?;
    d.set_item("t_min_normal_force", v.t_min_normal_force)?;
    d.set_item("t_max_friction_required", v.t_max_friction_required)?;
    let knees = PyDict::new(py);
    knees.set_item("stance", v.knee_torque[0])?;
    knees.set_item("swing", v.knee_torque[1])?;
    d.set_item("knee_torque", knees)?;
    d.set_item(
        "clearance_rule",
        v.clearance_rule.map(|r| match r {
            pdw::walkers::ClearanceRule::WholeSwing => "whole_swing",
            pdw::walkers::ClearanceRule::AfterMidStance => "after_mid_stance",
        }),
    )?;
    d.set_item("min_clearance", v.min_clearance)?;
    d.set_item("scuff_depth", v.scuff_depth)?;
    d.set_item(
        "t_min_clearance",
        v.min_clearance.map(|_| v.t_min_clearance),
    )?;
    let intervals: Vec<[f64; 2]> = v.scuff_intervals.iter().map(|&(a, b)| [a, b]).collect();
    d.set_item("scuff_intervals", intervals)?;
    d.set_item("t_mid_stance", v.t_mid_stance)?;
    d.set_item("impact_friction_required", v.impact_friction_required)?;
    let impacts = PyList::empty(py);
    for i in &v.impacts {
        let e = PyDict::new(py);
        e.set_item("event", &i.event)?;
        e.set_item("t", i.t)?;
        e.set_item("checked", i.report.is_some())?;
        for k in ["friction_required", "energy_lost", "min_margin", "entries"] {
            e.set_item(k, py.None())?;
        }
        if let Some(r) = &i.report {
            e.set_item("friction_required", r.friction_required)?;
            e.set_item("energy_lost", r.energy_lost)?;
            e.set_item("min_margin", r.min_margin().map(|m| m.0))?;
            let entries = PyList::empty(py);
            for en in &r.entries {
                let x = PyDict::new(py);
                x.set_item("name", &en.name)?;
                x.set_item("kind", format!("{:?}", en.kind))?;
                x.set_item("unilateral", en.unilateral)?;
                x.set_item("active", en.active)?;
                x.set_item("impulse", en.impulse)?;
                x.set_item("rate_after", en.rate_after)?;
                x.set_item("margin", en.margin())?;
                entries.append(x)?;
            }
            e.set_item("entries", entries)?;
        }
        impacts.append(e)?;
    }
    d.set_item("impacts", impacts)?;
    d.set_item(
        "scales",
        v.scales
            .map(|s| {
                let x = PyDict::new(py);
                x.set_item("mass", s.mass)?;
                x.set_item("length", s.length)?;
                x.set_item("gravity", s.gravity)?;
                Ok::<_, PyErr>(x)
            })
            .transpose()?,
    )?;
    let margins = PyList::empty(py);
    for m in &v.margins {
        let x = PyDict::new(py);
        x.set_item("name", &m.name)?;
        x.set_item("raw", m.raw)?;
        x.set_item("scale", m.scale)?;
        x.set_item("scale_name", m.scale_name)?;
        x.set_item("relative", m.relative)?;
        x.set_item("t", m.t)?;
        margins.append(x)?;
    }
    d.set_item("margins", margins)?;
    d.set_item("binding", v.binding().map(|m| m.name.clone()))?;
    d.set_item("min_relative_margin", v.min_relative_margin())?;
    let violations = PyList::empty(py);
    for x in &v.violations {
        let y = PyDict::new(py);
        y.set_item("criterion", &x.criterion)?;
        y.set_item("t_start", x.t_start)?;
        y.set_item("t_end", x.t_end)?;
        y.set_item("worst", x.worst)?;
        violations.append(y)?;
    }
    d.set_item("violations", violations)?;
    Ok(d)
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
            let floats: Option<Vec<f64>> = items
                .iter()
                .map(|x| {
                    x.as_number()
                        .filter(|n| n.is_f64())
                        .and_then(|n| n.as_f64())
                })
                .collect();
            match floats {
                Some(f) if !f.is_empty() => f.into_pyarray(py).into_any(),
                _ => {
                    let l = PyList::empty(py);
                    for x in items {
                        l.append(json_to_py(py, x)?)?;
                    }
                    l.into_any()
                }
            }
        }
        Value::Object(map) => {
            let d = PyDict::new(py);
            for (k, x) in map {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}
