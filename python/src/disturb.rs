//! `disturb`: the gait's response to one disturbed step, or the largest disturbance survived
//! each way, as `pdw-sweep disturb` ([`pdw::disturb`]).

use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::err;
use crate::mfpt::MFPT_FLAGS;
use crate::{build_kw, interruptible};

/// `disturb(model="simplest", terrain="step-down", once=None, largest=False, steps=200,
/// tol=1e-5, slope=None, **params)`: `pdw-sweep disturb` — with `once=d` one disturbed step
/// from the gait (a dict: `fell`, `steps`, `fall`, `deviation` array, `returned_after`); with
/// `largest=True` the largest disturbance survived each way (a dict of `(survived, fell)`
/// pairs: `down`/`up` for step heights, `steeper`/`shallower` for slopes).
#[pyfunction]
#[pyo3(
    signature = (model="simplest", terrain="step-down", once=None, largest=false, steps=200, tol=1e-5, slope=None, **params),
    text_signature = "(model='simplest', terrain='step-down', once=None, largest=False, steps=200, tol=1e-5, slope=None, **params)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn disturb<'py>(
    py: Python<'py>,
    model: &str,
    terrain: &str,
    once: Option<f64>,
    largest: bool,
    steps: usize,
    tol: f64,
    slope: Option<&Bound<'py, PyAny>>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    use pdw::limit::terrain::TerrainKind;
    let kind = pdw::mfpt::check_terrain(terrain, &MFPT_FLAGS).map_err(err)?;
    let m = build_kw(model, slope, params)?;
    pdw::disturb::check(&m, kind).map_err(err)?;
    if steps == 0 {
        return Err(err("steps: 0 must be an integer >= 1"));
    }
    let integ = pdw::mfpt::default_integrator();
    let d = PyDict::new(py);
    match (once, largest) {
        (Some(v), false) => {
            if !v.is_finite() {
                return Err(err(format!("once: {v} is not a finite disturbance")));
            }
            let r = interruptible(py, || {
                pdw::disturb::respond(&m, kind, v, steps, integ).map_err(err)
            })?;
            d.set_item("fell", !r.survived())?;
            d.set_item("steps", r.steps)?;
            d.set_item("fall", r.fall.map(|o| o.to_string()))?;
            d.set_item("deviation", r.deviation.clone().into_pyarray(py))?;
            d.set_item("returned_after", r.returned_after)?;
        }
        (None, true) => {
            if !(tol.is_finite() && tol > 0.0) {
                return Err(err(format!("tol: {tol} must be > 0")));
            }
            let (names, limit) = match kind {
                TerrainKind::Slope => (["steeper", "shallower"], 1.5),
                TerrainKind::StepDown => (["down", "up"], 1e3),
            };
            for (name, sign) in names.into_iter().zip([1.0, -1.0]) {
                let pair = interruptible(py, || {
                    pdw::disturb::largest(&m, kind, sign, tol, limit, steps, integ).map_err(err)
                })?;
                d.set_item(name, pair)?;
            }
        }
        _ => return Err(err("give once=D or largest=True (one of them)")),
    }
    d.set_item("terrain", kind.name())?;
    Ok(d)
}
