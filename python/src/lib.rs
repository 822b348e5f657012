//! `pdw_sweep`: the Python face of pdw-sweep (numpy in and out).
//!
//! Every function builds the model from the registry ([`pdw::walkers::model_info`]) with the
//! same parameter names as the CLI's `--set`, calls the library crates (pdw-limit), and converts
//! the result to Python objects. Computation runs on a worker thread with the interpreter
//! released (`interruptible`), while the calling thread watches for signals: Ctrl-C raises
//! `KeyboardInterrupt` within milliseconds; batched work runs on a rayon pool of `THREADS`
//! threads. Invalid input raises `ValueError` with the library's message (the one the CLI
//! prints).
//!
//! Each Python function lives in the module of its command (`fixed_point`, `stride_map`,
//! `basin`, `continuation`, `mfpt`, `disturb`, `simulate`, `orbit`, ...); `convert` turns the
//! results several of them share into Python objects and `errors` builds the `ValueError`s. This
//! file holds what every function needs: the model from its keyword arguments, the library's
//! warnings, the interruptible worker thread, and the module's table of functions.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::errors::err;

mod animate;
mod basin;
mod basin_over;
mod continuation;
mod convert;
mod design;
mod disturb;
mod errors;
mod explore;
mod fixed_point;
mod follow;
mod gsn;
mod linear;
mod mfpt;
mod mfpt_over;
mod orbit;
mod simulate;
mod stride_map;

/// Threads of the pool that runs batched strides and basins.
const THREADS: usize = 2;

/// How often the calling thread looks for a pending signal while a computation runs.
const SIGNAL_POLL: std::time::Duration = std::time::Duration::from_millis(20);

/// Runs `f` on a scoped worker thread with the interpreter released, and checks for signals
/// ([`Python::check_signals`], which runs Python's handlers) every [`SIGNAL_POLL`]. When a
/// handler raises (Ctrl-C's `KeyboardInterrupt`), the computation is asked to stop
/// ([`pdw::hybrid::interrupt`]: every integration polls it), its partial result is dropped once
/// the worker has returned (milliseconds later), the request is withdrawn and the handler's
/// exception is raised. A computation that ends interrupted without a pending signal here
/// (the request came from a call in another thread) raises `KeyboardInterrupt` as well, never
/// a partial result.
pub(crate) fn interruptible<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> PyResult<T> + Send,
{
    let (tx, rx) = std::sync::mpsc::channel();
    // A receiver is not Sync; the released-interpreter closure borrows it through a lock.
    let rx = std::sync::Mutex::new(rx);
    std::thread::scope(|scope| {
        let worker = scope.spawn(move || {
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
            let _ = tx.send(());
            r
        });
        loop {
            let finished = py.detach(|| {
                rx.lock()
                    .map(|rx| rx.recv_timeout(SIGNAL_POLL).is_ok())
                    .unwrap_or(true)
            });
            if finished || worker.is_finished() {
                break;
            }
            if let Err(e) = py.check_signals() {
                pdw::hybrid::interrupt::request();
                let _ = worker.join();
                pdw::hybrid::interrupt::clear();
                return Err(e);
            }
        }
        let r = worker.join().unwrap_or_else(Err);
        // the models built on the worker (a sweep's) may have warned
        give_warnings(py)?;
        if pdw::hybrid::interrupt::requested() {
            return Err(pyo3::exceptions::PyKeyboardInterrupt::new_err(
                "interrupted: the computation was stopped by an interrupt",
            ));
        }
        match r {
            Ok(v) => v,
            Err(p) => std::panic::resume_unwind(p),
        }
    })
}

/// A model built by the library ([`pdw::build`]).
type Model = pdw::BuiltModel;

/// Parameter overrides from `slope` and the keyword arguments (checked by
/// [`pdw::model::overrides_from_values`]).
pub(crate) fn overrides(
    slope: Option<f64>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<Vec<(String, f64)>> {
    let mut values = Vec::new();
    if let Some(p) = params {
        for (k, v) in p.iter() {
            let name: String = k.extract()?;
            let value: f64 = v.extract().map_err(|_| {
                err(format!(
                    "{name}: {} is not a number",
                    v.repr().map_or_else(|_| "?".into(), |r| r.to_string())
                ))
            })?;
            values.push((name, value));
        }
    }
    pdw::model::overrides_from_values(values, slope).map_err(err)
}

/// `slope=` as given: a number (rad) or a string with the CLI's `--slope` syntax (`"3deg"`,
/// `"3°"`, `"0.05"`, `"0.05rad"`; [`pdw::input::parse_slope_for`]).
pub(crate) fn slope_arg(slope: Option<&Bound<'_, PyAny>>) -> PyResult<Option<f64>> {
    let Some(s) = slope else {
        return Ok(None);
    };
    if let Ok(v) = s.extract::<f64>() {
        return Ok(Some(v));
    }
    if let Ok(text) = s.extract::<String>() {
        return pdw::input::parse_slope_for(&text, "slope")
            .map(Some)
            .map_err(err);
    }
    Err(pyo3::exceptions::PyTypeError::new_err(format!(
        "slope: {} is neither a number (rad) nor a string like '3deg', '3°' or '0.05'",
        s.repr().map_or_else(|_| "?".into(), |r| r.to_string())
    )))
}

/// A keyword renamed to say what it counts (`strides`, `max_strides`), with its old spelling
/// still accepted: the old keyword's value when it was given (the new one left at its
/// `default` or equal to it), else the new one's; both given with different values is an
/// error.
pub(crate) fn old_spelling<T: PartialEq + Copy + std::fmt::Display>(
    new: T,
    default: T,
    old: Option<T>,
    new_name: &str,
    old_name: &str,
) -> PyResult<T> {
    match old {
        None => Ok(new),
        Some(o) if new == default || new == o => Ok(o),
        Some(o) => Err(errors::err(format!(
            "{old_name}={o} and {new_name}={new}: {old_name} is the old spelling of \
             {new_name}; give one"
        ))),
    }
}

/// The library's warnings of the current call, given to Python by [`give_warnings`].
static PENDING_WARNINGS: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());

/// The library's warning sink ([`pdw::model::set_warning_sink`]): queued, because a model
/// may be built on a worker thread without the interpreter.
pub(crate) fn queue_warning(msg: &str) {
    if let Ok(mut q) = PENDING_WARNINGS.lock() {
        q.push(msg.to_string());
    }
}

/// Gives the queued warnings through `warnings.warn` (`UserWarning`; Python's filters decide
/// whether and how often they show), and lets the library warn again in the next call.
pub(crate) fn give_warnings(py: Python<'_>) -> PyResult<()> {
    let queued = PENDING_WARNINGS
        .lock()
        .map(|mut q| std::mem::take(&mut *q))
        .unwrap_or_default();
    pdw::model::rearm_warnings();
    warn_all(py, &queued)
}

/// Gives each of `msgs` through `warnings.warn` (`UserWarning`).
fn warn_all(py: Python<'_>, msgs: &[String]) -> PyResult<()> {
    for w in msgs {
        let msg = std::ffi::CString::new(w.as_str()).map_err(err)?;
        PyErr::warn(
            py,
            &py.get_type::<pyo3::exceptions::PyUserWarning>(),
            &msg,
            1,
        )?;
    }
    Ok(())
}

/// The model and its overrides (`slope` and the keyword arguments, checked) as the library's
/// [`pdw::ModelChoice`], for the plans that build models with further values on top.
pub(crate) fn model_choice(
    model: &str,
    slope: Option<&Bound<'_, PyAny>>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<pdw::ModelChoice> {
    let ov = overrides(slope_arg(slope)?, params)?;
    Ok(pdw::ModelChoice {
        model: model.to_string(),
        slope: None,
        // f64's Display is the shortest text that reads back as the same number
        set: ov.iter().map(|(n, v)| format!("{n}={v}")).collect(),
    })
}

/// Builds the model ([`pdw::build`]) and gives its warnings (a steep slope).
fn build(model: &str, ov: &[(String, f64)]) -> PyResult<Model> {
    let m = pdw::build(model, ov).map_err(err)?;
    Python::attach(give_warnings)?;
    Ok(m)
}

pub(crate) fn build_kw(
    model: &str,
    slope: Option<&Bound<'_, PyAny>>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<Model> {
    build(model, &overrides(slope_arg(slope)?, params)?)
}

/// `models()`: every registered model with its parameters (units, defaults) and coordinates.
#[pyfunction]
fn models(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let out = PyList::empty(py);
    for m in pdw::walkers::models() {
        let d = PyDict::new(py);
        d.set_item("name", &m.name)?;
        d.set_item("description", &m.description)?;
        let ps = PyList::empty(py);
        for p in &m.params {
            let pd = PyDict::new(py);
            pd.set_item("name", &p.name)?;
            pd.set_item("unit", &p.unit)?;
            pd.set_item("default", p.default)?;
            pd.set_item("description", &p.description)?;
            ps.append(pd)?;
        }
        d.set_item("parameters", ps)?;
        d.set_item("state_names", m.state_names.to_vec())?;
        d.set_item("section_names", m.section_names.to_vec())?;
        out.append(d)?;
    }
    Ok(out)
}

/// Fixed points, stride maps, basins, continuation and trajectories of passive dynamic walkers.
#[pymodule]
fn pdw_sweep(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // numpy's C API is imported here, once: imported lazily by the first array a function
    // returns, an import interrupted by a pending KeyboardInterrupt would panic.
    let _ = numpy::PyArray1::<f64>::zeros(m.py(), 0, false);
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    pdw::model::set_warning_sink(queue_warning);
    m.add_function(wrap_pyfunction!(models, m)?)?;
    m.add_function(wrap_pyfunction!(fixed_point::fixed_point, m)?)?;
    m.add_function(wrap_pyfunction!(fixed_point::scan_gaits, m)?)?;
    m.add_function(wrap_pyfunction!(stride_map::stride_map, m)?)?;
    m.add_function(wrap_pyfunction!(stride_map::stride_outcomes, m)?)?;
    m.add_function(wrap_pyfunction!(basin::basin, m)?)?;
    m.add_function(wrap_pyfunction!(continuation::continuation, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(mfpt::mfpt, m)?)?;
    m.add_function(wrap_pyfunction!(disturb::disturb, m)?)?;
    m.add_function(wrap_pyfunction!(orbit::orbit_diagram, m)?)?;
    m.add_function(wrap_pyfunction!(basin_over::basin_over, m)?)?;
    m.add_function(wrap_pyfunction!(follow::follow, m)?)?;
    m.add_function(wrap_pyfunction!(design::design, m)?)?;
    m.add_function(wrap_pyfunction!(animate::animate, m)?)?;
    m.add_function(wrap_pyfunction!(explore::explore, m)?)?;
    m.add_function(wrap_pyfunction!(linear::lyapunov, m)?)?;
    m.add_function(wrap_pyfunction!(gsn::gait_sensitivity, m)?)?;
    m.add_function(wrap_pyfunction!(mfpt_over::mfpt_over, m)?)?;
    Ok(())
}
