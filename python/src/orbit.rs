//! `orbit_diagram`: the orbit diagram of `pdw-sweep fixedpoint --sweep NAME=A:B:N`
//! ([`pdw::sweep::orbit_diagram`]): at each of the N values the stride map iterated from the
//! continued period-one gait, 300 transient strides dropped and 64 recorded.

use numpy::ndarray::Array3;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{err, no_gait_error};
use crate::{give_warnings, interruptible, overrides, THREADS};
use pdw::limit::{OrbitColumn, StrideOutcome};
use pdw::sweep::{StartChoice, SweepPlan};

/// The plan of a sweep of `parameter` over `start..stop` (`points` values) from the `gait`
/// (`stable`/`unstable`), the other parameters from `params`.
pub(crate) fn sweep_plan(
    model: &str,
    (parameter, start, stop, points): (&str, f64, f64, usize),
    gait: &str,
    tol: f64,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<SweepPlan> {
    crate::continuation::check_sweep_request(start, stop, points, gait)?;
    crate::fixed_point::check_gait_and_tol("all", tol)?;
    let mut fixed = overrides(None, params)?;
    if let Some((_, v)) = fixed.iter().find(|(n, _)| n == parameter) {
        return Err(err(format!(
            "parameter {parameter}: the parameter is also set to {v}; give it once"
        )));
    }
    fixed.retain(|(n, _)| n != parameter);
    Ok(SweepPlan {
        model: model.to_string(),
        fixed,
        grid: pdw::input::Sweep {
            name: parameter.to_string(),
            lo: start,
            hi: stop,
            n: points,
        },
        start: match gait {
            "unstable" => StartChoice::Unstable,
            _ => StartChoice::Stable,
        },
        tol,
        integrator: None,
        from: None,
        max_period: 2,
    })
}

/// `orbit_diagram(model="simplest", parameter="slope", start=0.001, stop=0.019, points=100,
/// gait="stable", guess=None, tol=1e-12, threads=2, **params)`: the orbit diagram of
/// `pdw-sweep fixedpoint --sweep parameter=start:stop:points`. Returns a dict: `parameter`
/// (the name), `values` (N,), `points` (N, 64, d_s) — the 64 recorded section states at each
/// value, NaN after a fall —, `section_names`, `period` (N,) — the detected period in strides,
/// 0 for none —, `fall_stride` (N,) — the failed stride's index counting the 300 transient
/// strides, -1 for none —, `fall` (N names or None), `transient`, `record`.
#[pyfunction]
#[pyo3(
    signature = (model="simplest", parameter="slope", start=0.001, stop=0.019, points=100, gait="stable", guess=None, tol=1e-12, threads=THREADS, **params),
    text_signature = "(model='simplest', parameter='slope', start=0.001, stop=0.019, points=100, gait='stable', guess=None, tol=1e-12, threads=2, **params)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn orbit_diagram<'py>(
    py: Python<'py>,
    model: &str,
    parameter: &str,
    start: f64,
    stop: f64,
    points: usize,
    gait: &str,
    guess: Option<Vec<f64>>,
    tol: f64,
    threads: usize,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    pdw::input::check_threads(threads, "threads").map_err(err)?;
    let plan = sweep_plan(model, (parameter, start, stop, points), gait, tol, params)?;
    let m0 = plan.start_model();
    give_warnings(py)?;
    let m0 = m0.map_err(err)?;
    let (values, columns) = interruptible(py, || -> PyResult<_> {
        let guesses = pdw::gaits::guesses(&m0, guess, "guess").map_err(err)?;
        let (s, failed) = pdw::sweep::start_gait(&plan, &m0, &guesses).map_err(err)?;
        let Some(s) = s else {
            return Err(no_gait_error(&m0, gait, guesses.len(), &failed));
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(err)?;
        let quiet = &pdw::limit::sweep::Silent;
        let sweep = pdw::sweep::continuation(&plan, &s, plan.grid.lo, &pool, quiet).map_err(err)?;
        let cols = pdw::sweep::orbit_diagram(&plan, &sweep, &s, &pool, quiet).map_err(err)?;
        Ok((sweep.params, cols))
    })?;
    let ds = m0.walker.section_dim();
    orbit_dict(py, &plan, &m0, values, &columns, ds)
}

/// The dict `orbit_diagram` returns.
fn orbit_dict<'py>(
    py: Python<'py>,
    plan: &SweepPlan,
    m0: &pdw::BuiltModel,
    values: Vec<f64>,
    columns: &[OrbitColumn],
    ds: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let oo = plan.orbit_options();
    let n = columns.len();
    let mut pts = vec![f64::NAN; n * oo.record * ds];
    for (i, c) in columns.iter().enumerate() {
        for (j, p) in c.points.iter().take(oo.record).enumerate() {
            let at = (i * oo.record + j) * ds;
            pts[at..at + ds].copy_from_slice(p);
        }
    }
    let d = PyDict::new(py);
    d.set_item("parameter", &plan.grid.name)?;
    d.set_item("values", values.into_pyarray(py))?;
    d.set_item(
        "points",
        Array3::from_shape_vec((n, oo.record, ds), pts)
            .map_err(err)?
            .into_pyarray(py),
    )?;
    d.set_item("section_names", m0.info.section_names.to_vec())?;
    let period: Vec<i64> = columns
        .iter()
        .map(|c| c.period.map_or(0, |p| p as i64))
        .collect();
    d.set_item("period", period.into_pyarray(py))?;
    let fall_stride: Vec<i64> = columns
        .iter()
        .map(|c| c.fall.map_or(-1, |(k, _)| k as i64))
        .collect();
    d.set_item("fall_stride", fall_stride.into_pyarray(py))?;
    let fall: Vec<Option<String>> = columns
        .iter()
        .map(|c| {
            c.fall.map(|(_, o)| match o {
                StrideOutcome::Fall { kind, .. } => kind.name().to_string(),
                o => o.to_string(),
            })
        })
        .collect();
    d.set_item("fall", fall)?;
    d.set_item("transient", oo.transient)?;
    d.set_item("record", oo.record)?;
    Ok(d)
}
