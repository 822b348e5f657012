//! `pdw_sweep`: the Python face of pdw-sweep (numpy in and out).
//!
//! Every function builds the model from the registry ([`pdw::walkers::model_info`]) with the
//! same parameter names as the CLI's `--set`, calls the library crates (pdw-limit), and converts
//! the result to Python objects. Computation runs on a worker thread with the interpreter
//! released (`interruptible`), while the calling thread watches for signals: Ctrl-C raises
//! `KeyboardInterrupt` within milliseconds; batched work runs on a rayon pool of `THREADS`
//! threads. Invalid input raises `ValueError` with the library's message (the one the CLI
//! prints).

use numpy::ndarray::Array2;
use numpy::{AllowTypeChange, Complex64, IntoPyArray, PyArrayLike2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use pdw::basin::{BasinPlan, BasinRequest};
use pdw::limit::basin::{self as lbasin, BasinOptions, Outcome};
use pdw::limit::gaits::{self, Found};
use pdw::limit::trajectory::{self, Trajectory, Validity};
use pdw::limit::{Attractor, AttractorKind, AttractorSet};
use pdw::limit::{Bifurcation, Branch, GridBranch, MeasuredPoint, StrideMap, StrideOutcome};
use pdw::simulate::{GaitKind, SimulateFlags, Start, StartError};

mod animate;
mod basin_over;
mod design;
mod explore;
mod follow;
mod gsn;
mod linear;
mod mfpt_over;
mod orbit;

/// Threads of the pool that runs batched strides and basins.
const THREADS: usize = 2;
/// Integration tolerance (DOP853) of `stride_map`, the basin engine's default.
const STRIDE_TOL: f64 = 1e-10;

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

pub(crate) fn err(msg: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(msg.to_string())
}

fn gib(b: u64) -> String {
    format!("{:.1} GiB", b as f64 / (1u64 << 30) as f64)
}

/// Refuses a basin grid held whole in memory (cells, results, the outcome array) that would
/// need more than 80 % of the memory available, naming the estimate.
fn check_basin_memory(grid: &[usize], d: usize) -> PyResult<()> {
    // per cell: its start state and its result (two vectors of d values with their headers
    // and allocations), the outcome byte twice (vector and numpy array)
    let per_cell = 2 * (24 + 16 + 8 * d as u64) + 8 + 2;
    let cells = grid.iter().fold(1u64, |a, &n| a.saturating_mul(n as u64));
    let need = cells.saturating_mul(per_cell).saturating_add(64 << 20);
    let have = pdw::limit::resources::memory_available();
    if need > have / 5 * 4 {
        let g = grid
            .iter()
            .map(|n| n.to_string())
            .collect::<Vec<_>>()
            .join(", ");
        return Err(err(format!(
            "grid: ({g}) needs about {} of memory, more than the {} available (80 % of \
             {}); use a smaller grid, or the command line's `pdw-sweep basin`, which streams rows \
             to a file and splits across machines with --shard",
            gib(need),
            gib(have / 5 * 4),
            gib(have)
        )));
    }
    Ok(())
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
fn give_warnings(py: Python<'_>) -> PyResult<()> {
    let queued = PENDING_WARNINGS
        .lock()
        .map(|mut q| std::mem::take(&mut *q))
        .unwrap_or_default();
    pdw::model::rearm_warnings();
    warn_all(py, &queued)
}

/// The swept range and start gait of `continuation` and `orbit_diagram`: at least two points,
/// a non-empty finite range, `stable` or `unstable`.
pub(crate) fn check_sweep_request(
    start: f64,
    stop: f64,
    points: usize,
    gait: &str,
) -> PyResult<()> {
    if points < 2 {
        return Err(err(format!("points: {points} must be an integer >= 2")));
    }
    if !(start.is_finite() && stop.is_finite()) || start == stop {
        return Err(err(format!("start, stop: range {start}:{stop} is empty")));
    }
    if !matches!(gait, "stable" | "unstable") {
        return Err(err(format!(
            "gait: '{gait}' is not one of stable, unstable"
        )));
    }
    Ok(())
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
fn model_choice(
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

pub(crate) fn rows_to_array<'py>(
    py: Python<'py>,
    v: Vec<f64>,
    cols: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let rows = v.len().checked_div(cols).unwrap_or(0);
    let a = Array2::from_shape_vec((rows, cols), v).map_err(err)?;
    Ok(a.into_pyarray(py).into_any())
}

fn complex_array<'py>(py: Python<'py>, m: &[pdw::limit::Multiplier]) -> Bound<'py, PyAny> {
    m.iter()
        .map(|l| Complex64::new(l.re, l.im))
        .collect::<Vec<_>>()
        .into_pyarray(py)
        .into_any()
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

fn validity_dict<'py>(py: Python<'py>, v: &Validity) -> PyResult<Bound<'py, PyDict>> {
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

/// Gaits found from `guess` (section coordinates) or the model's own guesses
/// ([`pdw::gaits`]), with the number of guesses tried.
pub(crate) fn find_gaits(
    m: &Model,
    guess: Option<Vec<f64>>,
    tol: f64,
) -> PyResult<(Vec<Found>, Vec<gaits::Failed>, usize)> {
    let guesses = pdw::gaits::guesses(m, guess, "guess").map_err(err)?;
    let n = guesses.len();
    let (found, failed) = pdw::gaits::search(m, &guesses, tol).map_err(err)?;
    Ok((found, failed, n))
}

pub(crate) fn no_gait_error(m: &Model, which: &str, n: usize, failed: &[gaits::Failed]) -> PyErr {
    err(pdw::gaits::no_gait_message(m, which, n, failed))
}

/// No start gait for a sweep: the values tried (Newton from the guesses, then a section scan at
/// each), the failed guesses at the first, and what to pass instead.
fn no_start_error(
    m: &Model,
    plan: &pdw::sweep::SweepPlan,
    which: &str,
    none: &pdw::sweep::NoStart,
) -> PyErr {
    let values: Vec<String> = none.tried.iter().map(|v| v.to_string()).collect();
    let mut msg = format!(
        "no {which} period-one gait of model '{}' at {} = {} to start the continuation from (at \
         each: Newton from the guesses, then a scan of the section with {} starts); pass \
         start_at= a value of the range with a gait (gaits() lists the gaits at one value)",
        m.info.name,
        plan.grid.name,
        values.join(", "),
        pdw::sweep::START_SCAN_STARTS
    );
    for (label, g, e) in &none.failed {
        msg.push_str(&format!("\n  guess '{label}' {g:?}: {e}"));
    }
    err(msg)
}

/// `fixed_point(model, slope=None, period=1, gait="all", tol=1e-12, guess=None,
/// jacobian=False, **params)`; with `jacobian=True` (period one) each gait also carries its
/// linear stability data ([`linear::set_linear`]).
#[pyfunction]
#[pyo3(
    signature = (model="simplest", slope=None, period=1, gait="all", tol=1e-12, guess=None, jacobian=false, **params),
    text_signature = "(model='simplest', slope=None, period=1, gait='all', tol=1e-12, guess=None, jacobian=False, **params)"
)]
#[allow(clippy::too_many_arguments)]
fn fixed_point<'py>(
    py: Python<'py>,
    model: &str,
    slope: Option<&Bound<'py, PyAny>>,
    period: usize,
    gait: &str,
    tol: f64,
    guess: Option<Vec<f64>>,
    jacobian: bool,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    if !(1..=64).contains(&period) {
        return Err(err(format!(
            "period: {period} must be between 1 and 64 strides"
        )));
    }
    check_gait_and_tol(gait, tol)?;
    let m = build_kw(model, slope, params)?;
    if period > 1 {
        if jacobian {
            return Err(err("jacobian: given for period-one gaits only (period=1)"));
        }
        return fixed_point_period_k(py, &m, period, gait, tol, guess);
    }
    let keep = |stable: bool| match gait {
        "stable" => stable,
        "unstable" => !stable,
        _ => true,
    };
    let (found, failed, n, validity, lin) = interruptible(py, || -> PyResult<_> {
        let (found, failed, n) = find_gaits(&m, guess, tol)?;
        let validity: Vec<Option<Validity>> = found
            .iter()
            .map(|f| Validity::along_step(m.walker.as_ref(), &f.fp.state))
            .collect();
        let lin = found
            .iter()
            .map(|f| {
                (jacobian && keep(f.fp.stable))
                    .then(|| linear::linear(&m, &f.fp.section))
                    .transpose()
            })
            .collect::<PyResult<Vec<_>>>()?;
        Ok((found, failed, n, validity, lin))
    })?;
    let out = PyList::empty(py);
    for ((f, v), l) in found.iter().zip(&validity).zip(&lin) {
        if !keep(f.fp.stable) {
            continue;
        }
        let d = fixed_point_dict(py, &m, &f.fp, &f.label, v.as_ref())?;
        if let Some(l) = l {
            linear::set_linear(py, &d, l)?;
        }
        out.append(d)?;
    }
    if out.is_empty() {
        return Err(no_gait_error(&m, gait, n, &failed));
    }
    Ok(out)
}

/// `gait` one of stable, unstable, all; `tol` a positive number.
fn check_gait_and_tol(gait: &str, tol: f64) -> PyResult<()> {
    if !(tol.is_finite() && tol > 0.0) {
        return Err(err(format!("tol: {tol} must be a positive number")));
    }
    if !matches!(gait, "stable" | "unstable" | "all") {
        return Err(err(format!(
            "gait: '{gait}' is not one of stable, unstable, all"
        )));
    }
    Ok(())
}

/// One period-one gait as `fixed_point` returns it (the fields of `fixedpoint --json`).
fn fixed_point_dict<'py>(
    py: Python<'py>,
    m: &Model,
    fp: &pdw::limit::FixedPoint,
    label: &str,
    v: Option<&Validity>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("gait", if fp.stable { "stable" } else { "unstable" })?;
    d.set_item("guess", label)?;
    d.set_item("section", fp.section.clone().into_pyarray(py))?;
    d.set_item("state_names", m.info.state_names.to_vec())?;
    d.set_item("state", fp.state.clone().into_pyarray(py))?;
    d.set_item("period", fp.metrics.period)?;
    d.set_item("step_length", fp.metrics.step_length)?;
    d.set_item("speed", fp.metrics.speed)?;
    d.set_item("multipliers", complex_array(py, &fp.multipliers))?;
    d.set_item("stable", fp.stable)?;
    d.set_item("residual", fp.residual)?;
    d.set_item("iterations", fp.iterations)?;
    d.set_item("validity", v.map(|v| validity_dict(py, v)).transpose()?)?;
    d.set_item("period_k", 1)?;
    d.set_item(
        "orbit",
        rows_to_array(py, fp.section.clone(), fp.section.len())?,
    )?;
    Ok(d)
}

/// `gaits(model="simplest", slope=None, starts=256, search_box=None, gait="all", tol=1e-12,
/// threads=2, **params)`: every gait found without a guess, as `pdw-sweep fixedpoint --search`
/// finds them — Newton from `starts` states spread over a box of the section (the model's own,
/// with the coordinates named in `search_box`, a dict `{name: (lo, hi)}`, replaced), and the
/// stride map iterated from each. Returns a dict: `gaits` (the dicts of `fixed_point`, each with
/// `starts_newton` and `starts_settled`), `orbits` (period-K attractors: `period_k`, `orbit`
/// (K, d_s), `multipliers`, `stable`, `period`, `residual`, `starts_settled`), `starts`, `fell`,
/// `unsettled`, `fates` (`{fate: starts}`: every start by how it ended, e.g. `stance knee
/// buckled`), `fates_text` and `box` (`{name: (lo, hi)}`).
#[pyfunction]
#[pyo3(
    name = "gaits",
    signature = (model="simplest", slope=None, starts=pdw::gaits::SCAN_STARTS, search_box=None, gait="all", tol=1e-12, threads=THREADS, **params),
    text_signature = "(model='simplest', slope=None, starts=256, search_box=None, gait='all', tol=1e-12, threads=2, **params)"
)]
#[allow(clippy::too_many_arguments)]
fn scan_gaits<'py>(
    py: Python<'py>,
    model: &str,
    slope: Option<&Bound<'py, PyAny>>,
    starts: usize,
    search_box: Option<std::collections::BTreeMap<String, (f64, f64)>>,
    gait: &str,
    tol: f64,
    threads: usize,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    if !(1..=1_000_000).contains(&starts) {
        return Err(err(format!(
            "starts: {starts} must be between 1 and 1000000"
        )));
    }
    check_gait_and_tol(gait, tol)?;
    pdw::input::check_threads(threads, "threads").map_err(err)?;
    let m = build_kw(model, slope, params)?;
    let given: Vec<pdw::input::AxisRange> = search_box
        .unwrap_or_default()
        .into_iter()
        .map(|(name, (lo, hi))| pdw::input::AxisRange { name, lo, hi })
        .collect();
    let b = pdw::gaits::scan_box(&m, &given, "search_box").map_err(err)?;
    let sc = interruptible(py, || -> PyResult<_> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(err)?;
        let integrator = gaits::default_integrator(tol);
        pdw::gaits::scan(&m, &b, starts, tol, &integrator, &pool).map_err(err)
    })?;
    scan_dict(py, &m, &sc, gait)
}

/// The dict `gaits` returns.
fn scan_dict<'py>(
    py: Python<'py>,
    m: &Model,
    sc: &pdw::limit::scan::Scan,
    gait: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let keep = |stable: bool| match gait {
        "stable" => stable,
        "unstable" => !stable,
        _ => true,
    };
    let found = PyList::empty(py);
    for g in sc.gaits.iter().filter(|g| keep(g.fp.stable)) {
        let v = Validity::along_step(m.walker.as_ref(), &g.fp.state);
        let d = fixed_point_dict(py, m, &g.fp, "scan", v.as_ref())?;
        d.set_item("starts_newton", g.newton_starts)?;
        d.set_item("starts_settled", g.attracted_starts)?;
        d.set_item("starts_near_gaits", g.near_gaits)?;
        found.append(d)?;
    }
    let orbits = PyList::empty(py);
    for o in sc.orbits.iter().filter(|o| keep(o.orbit.stable)) {
        let (orbit, d) = (&o.orbit, PyDict::new(py));
        let ds = orbit.orbit[0].len();
        d.set_item("period_k", orbit.period_k)?;
        d.set_item("orbit", rows_to_array(py, orbit.orbit.concat(), ds)?)?;
        d.set_item("multipliers", complex_array(py, &orbit.multipliers))?;
        d.set_item("stable", orbit.stable)?;
        d.set_item("period", orbit.period)?;
        d.set_item("residual", orbit.residual)?;
        d.set_item("starts_settled", o.attracted_starts)?;
        d.set_item("starts_near_gaits", o.near_gaits)?;
        orbits.append(d)?;
    }
    let bx = PyDict::new(py);
    for (n, (lo, hi)) in m
        .info
        .section_names
        .iter()
        .zip(sc.scan_box.lo.iter().zip(&sc.scan_box.hi))
    {
        bx.set_item(n, (*lo, *hi))?;
    }
    let d = PyDict::new(py);
    d.set_item("gaits", found)?;
    d.set_item("orbits", orbits)?;
    d.set_item("starts", sc.starts)?;
    d.set_item("fell", sc.fell)?;
    d.set_item("unsettled", sc.unsettled)?;
    // every start by fate, most first: {fate: starts}, and the report's sentence
    let fates = PyDict::new(py);
    for (f, n) in sc.fates() {
        fates.set_item(f, n)?;
    }
    d.set_item("fates", fates)?;
    d.set_item(
        "fates_text",
        pdw::limit::scan::fates_text(sc.starts, &sc.fates()),
    )?;
    d.set_item("near_gait_starts", sc.near_gait_starts)?;
    d.set_item("box", bx)?;
    Ok(d)
}

/// `fixed_point(period=K)`, K > 1: the period-K orbits of `fixedpoint --period K --json`, with
/// `orbit` a (K, d_s) array and the K-step map's `multipliers`.
fn fixed_point_period_k<'py>(
    py: Python<'py>,
    m: &Model,
    k: usize,
    gait: &str,
    tol: f64,
    guess: Option<Vec<f64>>,
) -> PyResult<Bound<'py, PyList>> {
    let w = m.walker.as_ref();
    let guesses = match guess {
        Some(g) if g.len() != w.section_dim() => {
            return Err(err(format!(
                "guess: {} values given, model '{}' has {} section coordinates ({})",
                g.len(),
                m.info.name,
                w.section_dim(),
                m.info.section_names.join(", ")
            )))
        }
        Some(g) => vec![("guess".to_string(), g)],
        None => gaits::model_guesses(w),
    };
    let (found, failed, validity) = interruptible(py, || -> PyResult<_> {
        let (found, failed) = gaits::search_periodic(w, &guesses, k, tol).map_err(err)?;
        let validity: Vec<Vec<Option<Validity>>> = found
            .iter()
            .map(|f| {
                f.orbit
                    .states
                    .iter()
                    .map(|x| Validity::along_step(w, x))
                    .collect()
            })
            .collect();
        Ok((found, failed, validity))
    })?;
    let out = PyList::empty(py);
    for (f, v) in found.iter().zip(&validity) {
        let o = &f.orbit;
        let keep = match gait {
            "stable" => o.stable,
            "unstable" => !o.stable,
            _ => true,
        };
        if !keep {
            continue;
        }
        let ds = o.orbit[0].len();
        let d = PyDict::new(py);
        d.set_item("gait", if o.stable { "stable" } else { "unstable" })?;
        d.set_item("guess", &f.label)?;
        d.set_item("period_k", k)?;
        d.set_item("section", o.orbit[0].clone().into_pyarray(py))?;
        d.set_item("orbit", rows_to_array(py, o.orbit.concat(), ds)?)?;
        d.set_item("state_names", m.info.state_names.to_vec())?;
        d.set_item("state", o.states[0].clone().into_pyarray(py))?;
        d.set_item("period", o.period)?;
        d.set_item(
            "stride_periods",
            o.strides
                .iter()
                .map(|s| s.period)
                .collect::<Vec<_>>()
                .into_pyarray(py),
        )?;
        d.set_item("step_length", o.total_step_length().map(|l| l / k as f64))?;
        d.set_item(
            "step_lengths",
            o.strides.iter().map(|s| s.step_length).collect::<Vec<_>>(),
        )?;
        d.set_item("speed", o.speed())?;
        d.set_item("multipliers", complex_array(py, &o.multipliers))?;
        d.set_item("stable", o.stable)?;
        d.set_item("residual", o.residual)?;
        d.set_item("iterations", o.iterations)?;
        d.set_item(
            "validity",
            v[0].as_ref().map(|v| validity_dict(py, v)).transpose()?,
        )?;
        let per = PyList::empty(py);
        for x in v {
            per.append(x.as_ref().map(|v| validity_dict(py, v)).transpose()?)?;
        }
        d.set_item("validity_per_stride", per)?;
        out.append(d)?;
    }
    if out.is_empty() {
        let mut msg = format!(
            "no {}period-{k} orbit found for model '{}' at slope {} from {} guess(es), their \
             iterates and the period-doubling predictors",
            if gait == "all" {
                String::new()
            } else {
                format!("{gait} ")
            },
            m.info.name,
            m.slope(),
            guesses.len()
        );
        for (label, g, e) in failed {
            msg.push_str(&format!("\n  guess '{label}' {g:?}: {e}"));
        }
        return Err(err(msg));
    }
    Ok(out)
}

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
fn stride_outcomes<'py>(
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
fn stride_map<'py>(
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

fn attractor_dict<'py>(py: Python<'py>, a: &Attractor) -> PyResult<Bound<'py, PyDict>> {
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

/// `basin(model="simplest", slope=None, grid=(nx, ny), x=None, y=None, z=None,
/// max_strides=100, threads=2, **params)`: every cell labelled by the attractor it reaches, as
/// `pdw-sweep basin` (the same setup, [`pdw::basin`]); with `z=(name, lo, hi)` and
/// `grid=(nx, ny, nz)` a 3-D grid, returned as an (nz × ny × nx) array.
#[pyfunction]
#[pyo3(
    signature = (model="simplest", slope=None, grid=vec![101, 101], x=None, y=None, z=None, max_strides=100, threads=THREADS, **params),
    text_signature = "(model='simplest', slope=None, grid=(101, 101), x=None, y=None, z=None, max_strides=100, threads=2, **params)"
)]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn basin<'py>(
    py: Python<'py>,
    model: &str,
    slope: Option<&Bound<'py, PyAny>>,
    grid: Vec<usize>,
    x: Option<(String, f64, f64)>,
    y: Option<(String, f64, f64)>,
    z: Option<(String, f64, f64)>,
    max_strides: u32,
    threads: usize,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>, Bound<'py, PyDict>)> {
    let (m, req) = basin_request(model, slope, &grid, [x, y, z], max_strides, threads, params)?;
    let gaits = interruptible(py, || pdw::basin::find_gaits(&m).map_err(err))?;
    let plan = basin_plan(&m, &req, gaits)?;
    let (outcome, metrics, set) = interruptible(py, || classify_basin(&m, &plan, threads))?;
    basin_result(py, &m, &plan, outcome, &metrics, &set)
}

/// A basin axis as given in Python, `(name, lo, hi)`.
type GivenAxis = Option<(String, f64, f64)>;

/// The keyword arguments of `basin` as the library's request, with the model: the grid, stride
/// budget and thread count checked, the memory the grid needs, the axes resolved against the
/// model's section.
fn basin_request(
    model: &str,
    slope: Option<&Bound<'_, PyAny>>,
    grid: &[usize],
    [x, y, z]: [GivenAxis; 3],
    max_strides: u32,
    threads: usize,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<(Model, BasinRequest)> {
    let (nx, ny, nz) = basin_grid(grid, z.is_some())?;
    let max_strides = pdw::basin::check_max_strides(max_strides, "max_strides").map_err(err)?;
    pdw::input::check_threads(threads, "threads").map_err(err)?;
    let m = build_kw(model, slope, params)?;
    pdw::basin::check_section(&m.info, "grid").map_err(err)?;
    check_basin_memory(grid, m.info.section_names.len())?;
    let axis = |given: GivenAxis, which: &str| {
        let range = given.map(|(name, lo, hi)| pdw::input::AxisRange { name, lo, hi });
        pdw::basin::resolve_axis(&m.info, range, which).map_err(err)
    };
    let z = axis(z, "z")?.zip(nz);
    let req = BasinRequest {
        grid: (nx, ny),
        x: axis(x, "x")?,
        y: axis(y, "y")?,
        z,
        fixed: Vec::new(),
        max_strides,
        integrator: BasinOptions::default_integrator(),
    };
    Ok((m, req))
}

/// `grid` as (nx, ny) and nz: three sizes exactly when a z axis is given (`three_d`), each
/// positive, at most 10⁹ cells in all.
fn basin_grid(grid: &[usize], three_d: bool) -> PyResult<(usize, usize, Option<usize>)> {
    let g = grid
        .iter()
        .map(|n| n.to_string())
        .collect::<Vec<_>>()
        .join(", ");
    match (grid.len(), three_d) {
        (2, false) | (3, true) => {}
        (3, false) => {
            return Err(err(format!(
                "grid: ({g}) has three sizes, but no z axis was given; give z=(name, lo, hi) \
                 for a 3-D grid, or grid=(nx, ny)"
            )))
        }
        (_, true) => {
            return Err(err(format!(
                "z needs a 3-D grid: grid=(nx, ny, nz), not ({g})"
            )))
        }
        _ => return Err(err(format!("grid: ({g}) must be (nx, ny)"))),
    }
    let cells = grid.iter().fold(1usize, |a, &n| a.saturating_mul(n));
    if grid.contains(&0) || cells > 1_000_000_000 {
        return Err(err(format!(
            "grid: ({g}) must have positive sizes and at most 10^9 cells"
        )));
    }
    Ok((grid[0], grid[1], grid.get(2).copied()))
}

/// The grid of `req` around the gait (the stable one, else the first found; with both axes
/// given and no gait, the model's first guess), or why there is none.
fn basin_plan(m: &Model, req: &BasinRequest, gaits: pdw::basin::Gaits) -> PyResult<BasinPlan> {
    let Some(centre) = pdw::basin::grid_centre(m, &gaits, req.axes_given()) else {
        let mut e = format!(
            "no period-one orbit found for model '{}' at slope {} from {} guess(es) to centre \
             the default grid on; give both x and y",
            m.info.name,
            m.slope(),
            gaits.tried
        );
        for (label, g, le) in &gaits.failed {
            e.push_str(&format!("\n  guess '{label}' {g:?}: {le}"));
        }
        return Err(err(e));
    };
    let flags = pdw::basin::AxisFlags {
        x: "x",
        y: "y",
        z: "z",
    };
    let bx =
        pdw::basin::choose_box(req, &m.info.section_names, &centre, flags, "grid").map_err(err)?;
    Ok(BasinPlan::new(req, bx, gaits, centre))
}

/// Every cell of the plan labelled by the attractor it reaches (found first over the box), with
/// the basin's metrics and the attractors.
fn classify_basin(
    m: &Model,
    plan: &BasinPlan,
    threads: usize,
) -> PyResult<(Vec<u8>, lbasin::BasinMetrics, AttractorSet)> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(err)?;
    let (set, _) = plan.attractors(m, &pool).map_err(err)?;
    let fall = Outcome::of_fall;
    let problem = set.problem(m.walker.as_ref(), &fall);
    let rows: Vec<usize> = (0..plan.bx.ny * plan.bx.nz).collect();
    let cells = plan.row_cells(&rows);
    let mut res =
        lbasin::classify_cells(&problem, &cells, &plan.opts, &pool, &|_| {}).map_err(err)?;
    set.relabel(&mut res);
    let outcome: Vec<u8> = res.iter().map(|c| c.outcome).collect();
    let (nx, ny, nz) = (plan.bx.nx, plan.bx.ny, plan.bx.nz);
    let metrics = lbasin::basin_metrics_slices(&outcome, nx, ny, nz, lbasin::DEFAULT_ENTROPY_BOX)
        .map_err(err)?;
    Ok((outcome, metrics, set))
}

/// `basin`'s result: the outcome array (ny × nx; nz × ny × nx for a 3-D grid), the legend
/// (code → name) and a dict of the metrics, axes (`z_name`, `z` too for a 3-D grid),
/// attractors and gait.
fn basin_result<'py>(
    py: Python<'py>,
    m: &Model,
    plan: &BasinPlan,
    outcome: Vec<u8>,
    metrics: &lbasin::BasinMetrics,
    set: &AttractorSet,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>, Bound<'py, PyDict>)> {
    let (nx, ny, nz) = (plan.bx.nx, plan.bx.ny, plan.bx.nz);
    let arr = match &plan.bx.z {
        None => Array2::from_shape_vec((ny, nx), outcome)
            .map_err(err)?
            .into_pyarray(py)
            .into_any(),
        Some(_) => numpy::ndarray::Array3::from_shape_vec((nz, ny, nx), outcome)
            .map_err(err)?
            .into_pyarray(py)
            .into_any(),
    };
    let legend = PyDict::new(py);
    let fr = PyDict::new(py);
    // the codes the outcome can hold: code 0 (`gait`) only with a gait to reach
    let has_gait = set.gait().is_some();
    for (c, name) in set.legend() {
        if c == Outcome::Gait.code() && !has_gait {
            continue;
        }
        let f = metrics
            .fractions
            .iter()
            .find(|(code, _, _)| *code == c)
            .map_or(0.0, |(_, _, f)| *f);
        fr.set_item(&name, f)?;
        legend.set_item(c, name)?;
    }
    let md = PyDict::new(py);
    md.set_item("fractions", fr)?;
    md.set_item("basin_entropy", metrics.basin_entropy)?;
    md.set_item("boundary_entropy", metrics.boundary_entropy)?;
    md.set_item("box_size", metrics.box_size)?;
    md.set_item("x_name", &m.info.section_names[plan.bx.x.index])?;
    md.set_item("y_name", &m.info.section_names[plan.bx.y.index])?;
    md.set_item("x", plan.xs.clone().into_pyarray(py))?;
    md.set_item("y", plan.ys.clone().into_pyarray(py))?;
    if let Some(z) = &plan.bx.z {
        md.set_item("z_name", &m.info.section_names[z.index])?;
        md.set_item("z", plan.zs.clone().into_pyarray(py))?;
    }
    let atts = PyList::empty(py);
    for a in &set.attractors {
        atts.append(attractor_dict(py, a)?)?;
    }
    md.set_item("attractors", atts)?;
    let gait = plan.gait();
    md.set_item("gait", gait.map(|fp| fp.section.clone().into_pyarray(py)))?;
    md.set_item("coordinates", coordinates_dict(py, m)?)?;
    md.set_item(
        "gait_multipliers",
        gait.map(|fp| complex_array(py, &fp.multipliers)),
    )?;
    Ok((arr, legend, md))
}

fn bifurcation_dict<'py>(py: Python<'py>, bf: &Bifurcation) -> PyResult<Bound<'py, PyDict>> {
    let bd = PyDict::new(py);
    bd.set_item("kind", bf.kind.name())?;
    bd.set_item("parameter", bf.param)?;
    bd.set_item("section", bf.section.clone().into_pyarray(py))?;
    bd.set_item("multipliers", complex_array(py, &bf.multipliers))?;
    Ok(bd)
}

/// A branch on the output grid as arrays (n = its points on the grid, K = `period_k`).
fn branch_dict<'py>(
    py: Python<'py>,
    b: &GridBranch,
    continued: &Branch,
    ds: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let p = &b.points;
    let k = b.period_k;
    let n = p.len();
    d.set_item("name", &b.name)?;
    d.set_item("period_k", k)?;
    d.set_item(
        "parameter",
        p.iter()
            .map(|q| q.point.param)
            .collect::<Vec<_>>()
            .into_pyarray(py),
    )?;
    d.set_item(
        "section",
        rows_to_array(
            py,
            p.iter()
                .flat_map(|q| q.point.section.iter().copied())
                .collect(),
            ds,
        )?,
    )?;
    let orbit: Vec<f64> = p
        .iter()
        .flat_map(|q| q.point.orbit.iter().flatten().copied())
        .collect();
    d.set_item(
        "orbit",
        numpy::ndarray::Array3::from_shape_vec((n, k, ds), orbit)
            .map_err(err)?
            .into_pyarray(py),
    )?;
    d.set_item(
        "period",
        p.iter()
            .map(|q| q.point.period)
            .collect::<Vec<_>>()
            .into_pyarray(py),
    )?;
    d.set_item(
        "step_length",
        rows_to_array(
            py,
            p.iter()
                .flat_map(|q| q.step_length.iter().copied())
                .collect(),
            k,
        )?,
    )?;
    d.set_item(
        "speed",
        p.iter()
            .map(MeasuredPoint::speed)
            .collect::<Vec<_>>()
            .into_pyarray(py),
    )?;
    d.set_item(
        "stable",
        p.iter()
            .map(|q| q.point.stable)
            .collect::<Vec<_>>()
            .into_pyarray(py),
    )?;
    let valid: Vec<bool> = p
        .iter()
        .flat_map(|q| {
            q.validity
                .iter()
                .map(|v| v.as_ref().is_none_or(Validity::valid))
        })
        .collect();
    d.set_item(
        "valid",
        Array2::from_shape_vec((n, k), valid)
            .map_err(err)?
            .into_pyarray(py),
    )?;
    let validity = PyList::empty(py);
    for q in p {
        let per = PyList::empty(py);
        for v in &q.validity {
            per.append(v.as_ref().map(|v| validity_dict(py, v)).transpose()?)?;
        }
        validity.append(per)?;
    }
    d.set_item("validity", validity)?;
    let nm = p.first().map_or(0, |q| q.point.multipliers.len());
    let mult: Vec<Complex64> = p
        .iter()
        .flat_map(|q| {
            q.point
                .multipliers
                .iter()
                .map(|l| Complex64::new(l.re, l.im))
        })
        .collect();
    d.set_item(
        "multipliers",
        Array2::from_shape_vec((n, nm), mult)
            .map_err(err)?
            .into_pyarray(py),
    )?;
    let bifs = PyList::empty(py);
    for bf in &continued.bifurcations {
        bifs.append(bifurcation_dict(py, bf)?)?;
    }
    d.set_item("bifurcations", bifs)?;
    d.set_item("internal_points", continued.points.len())?;
    Ok(d)
}

/// `continuation(model, parameter="slope", start, stop, points=100, gait="stable", threads=2,
/// max_period=2, start_at=None, **params)`: `pdw-sweep fixedpoint --sweep
/// NAME=start:stop:points --max-period P --from MU`, branch by branch.
#[pyfunction]
#[pyo3(
    signature = (model="simplest", parameter="slope", start=0.001, stop=0.019, points=100, gait="stable", threads=THREADS, max_period=2, start_at=None, **params),
    text_signature = "(model='simplest', parameter='slope', start=0.001, stop=0.019, points=100, gait='stable', threads=2, max_period=2, start_at=None, **params)"
)]
#[allow(clippy::too_many_arguments)]
fn continuation<'py>(
    py: Python<'py>,
    model: &str,
    parameter: &str,
    start: f64,
    stop: f64,
    points: usize,
    gait: &str,
    threads: usize,
    max_period: usize,
    start_at: Option<f64>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    check_sweep_request(start, stop, points, gait)?;
    pdw::input::check_threads(threads, "threads").map_err(err)?;
    pdw::input::check_max_period(max_period, "max_period").map_err(err)?;
    let mut fixed = overrides(None, params)?;
    fixed.retain(|(n, _)| n != parameter);
    let grid = pdw::input::Sweep {
        name: parameter.to_string(),
        lo: start,
        hi: stop,
        n: points,
    };
    let from = start_at
        .map(|mu| pdw::input::check_from(mu, &grid, "start_at"))
        .transpose()
        .map_err(err)?;
    let plan = pdw::sweep::SweepPlan {
        model: model.to_string(),
        fixed,
        grid,
        start: match gait {
            "unstable" => pdw::sweep::StartChoice::Unstable,
            _ => pdw::sweep::StartChoice::Stable,
        },
        tol: 1e-12,
        integrator: None,
        from,
        max_period,
    };
    let m0 = plan.start_model();
    give_warnings(py)?;
    let m0 = m0.map_err(err)?;
    let ds = m0.walker.section_dim();
    let result = interruptible(py, || -> PyResult<pdw::limit::Sweep> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(err)?;
        let s = match pdw::sweep::find_start(&plan, None, &pool).map_err(err)? {
            Ok(s) => s,
            Err(none) => return Err(no_start_error(&m0, &plan, gait, &none)),
        };
        let silent = &pdw::limit::sweep::Silent;
        pdw::sweep::continuation(&plan, &s.section, s.param, &pool, silent).map_err(err)
    })?;
    for w in &result.warnings {
        let msg = std::ffi::CString::new(w.as_str()).map_err(err)?;
        PyErr::warn(
            py,
            &py.get_type::<pyo3::exceptions::PyUserWarning>(),
            &msg,
            1,
        )?;
    }
    let list = PyList::empty(py);
    let coordinates = coordinates_dict(py, &m0)?;
    for (b, (_, c)) in result.branches.iter().zip(&result.continued) {
        let bd = branch_dict(py, b, c, ds)?;
        bd.set_item("coordinates", &coordinates)?;
        list.append(bd)?;
    }
    Ok(list)
}

/// What each state component of `m` means, state name → meaning (the files' `coordinates`
/// attribute).
fn coordinates_dict<'py>(py: Python<'py>, m: &Model) -> PyResult<Bound<'py, PyDict>> {
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

/// The names of `mfpt`'s keyword arguments in its messages.
pub(crate) const MFPT_FLAGS: pdw::mfpt::MfptFlags = pdw::mfpt::MfptFlags {
    terrain: "terrain",
    sd: "sd",
    mean: "slope",
    walkers: "walkers",
    max_steps: "max_steps",
    dist: "dist",
};

/// `mfpt(..., sd="A:B:N")`: one Monte Carlo run per standard deviation (the same seed: common
/// random numbers), as `pdw-sweep mfpt --sd A:B:N`; a dict of arrays, one value per σ.
fn mfpt_curve<'py>(
    py: Python<'py>,
    m: &Model,
    sds: &[f64],
    (kind, dist): (
        pdw::limit::terrain::TerrainKind,
        &pdw::limit::terrain::TerrainDist,
    ),
    (walkers, max_steps, seed, threads): (usize, usize, u64, usize),
    stride_map: pdw::mfpt::StrideMap,
) -> PyResult<Bound<'py, PyDict>> {
    pdw::input::check_threads(threads, "threads").map_err(err)?;
    pdw::mfpt::check_model_for(m, kind).map_err(err)?;
    let plan = |sd: f64| mfpt_plan(m, (kind, dist), sd, (walkers, max_steps, seed), stride_map);
    pdw::mfpt::check_plan(&plan(sds[sds.len() - 1]), &MFPT_FLAGS).map_err(err)?;
    pdw::mfpt::check_heights(m, &plan(sds[sds.len() - 1]), &MFPT_FLAGS).map_err(err)?;
    pdw::mfpt::check_memory(
        m,
        &plan(sds[sds.len() - 1]),
        None,
        &MFPT_FLAGS,
        CHAIN_FLAGS.mesh,
    )
    .map_err(err)?;
    let ests = interruptible(py, || -> PyResult<_> {
        let (x0, _) = pdw::mfpt::start(m).map_err(err)?;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(err)?;
        sds.iter()
            .map(|&sd| {
                pdw::mfpt::run(m, &plan(sd), &x0, &pool, &|_| {})
                    .map(|r| r.1)
                    .map_err(err)
            })
            .collect::<PyResult<Vec<_>>>()
    })?;
    let d = PyDict::new(py);
    d.set_item("sd", sds.to_vec().into_pyarray(py))?;
    type Column = fn(&pdw::limit::terrain::MfptEstimate) -> f64;
    let columns: [(&str, Column); 6] = [
        ("mfpt", |e| e.mfpt),
        ("stderr", |e| e.stderr),
        ("restricted_mean", |e| e.restricted_mean),
        ("falls", |e| e.falls as f64),
        ("censored", |e| e.censored as f64),
        ("total_steps", |e| e.total_steps as f64),
    ];
    for (k, f) in columns {
        d.set_item(k, ests.iter().map(f).collect::<Vec<f64>>().into_pyarray(py))?;
    }
    d.set_item("mean", terrain_mean(m, kind))?;
    d.set_item("stride_map", stride_map.describe(m))?;
    d.set_item("terrain", kind.name())?;
    d.set_item("dist", pdw::mfpt::dist_words(dist))?;
    Ok(d)
}

/// The terrain's mean: the model's slope, or its `step_down` (0 where it has none).
fn terrain_mean(m: &Model, kind: pdw::limit::terrain::TerrainKind) -> f64 {
    let p = kind.param();
    m.params.iter().find(|q| q.0 == p).map_or(0.0, |q| q.1)
}

/// The Monte Carlo plan of `mfpt(...)`: the terrain of kind `kind` around the model's own
/// slope or step down, with standard deviation `sd`.
fn mfpt_plan(
    m: &Model,
    (kind, dist): (
        pdw::limit::terrain::TerrainKind,
        &pdw::limit::terrain::TerrainDist,
    ),
    sd: f64,
    (walkers, max_steps, seed): (usize, usize, u64),
    stride_map: pdw::mfpt::StrideMap,
) -> pdw::mfpt::MfptPlan {
    pdw::mfpt::MfptPlan {
        terrain: pdw::limit::terrain::SlopeTerrain {
            mean: terrain_mean(m, kind),
            sd,
            seed,
            kind,
            dist: dist.clone(),
        },
        walkers,
        max_steps,
        integrator: pdw::mfpt::default_integrator(),
        stride_map,
    }
}

/// The names of the chain's keyword arguments in `mfpt`'s messages.
const CHAIN_FLAGS: pdw::mfpt::ChainFlags = pdw::mfpt::ChainFlags {
    chain: "chain",
    mesh: "mesh",
    nodes: "nodes",
    section: "chain_section",
};

/// `mfpt(model="simplest", slope=None, sd=..., walkers=1000, max_steps=1000, seed=0,
/// threads=2, terrain="slope", chain=False, mesh=None, nodes=None, dist="normal", **params)`:
/// the Monte Carlo of `pdw-sweep mfpt` (the slope is the mean slope; with
/// `terrain="step-down"` the model's `step_down` is the mean step down and `sd` a plain
/// length; `dist` the distribution of the standardised draws: `normal`, `uniform`,
/// `file:PATH`). With `chain=True` also the Markov chain at `mesh` and `2 mesh` nodes per axis
/// (`chain_dict`), on the section `chain_section` (`landing`, or `mid-stance`: no layers), its
/// nodes laid out as `chain_mesh` says (`grid`, or `cloud`: the visited states thinned to the
/// grid's spacing, mid-stance only). `stride_map`: `auto` (in closed form where the model has
/// one, the rimless wheel; integrated otherwise), `closed-form` or `integrated` (the
/// `"stride_map"` key says which ran). With `sd="A:B:N"` the curve of `mfpt --sd A:B:N` (one run per σ, a dict of
/// arrays; without the chain).
#[pyfunction]
#[pyo3(
    signature = (model="simplest", slope=None, sd=None, walkers=1000, max_steps=1000, seed=0, threads=2, terrain="slope", chain=false, mesh=None, nodes=None, dist="normal", chain_section="landing", chain_mesh="grid", stride_map="auto", **params),
    text_signature = "(model='simplest', slope=None, sd=None, walkers=1000, max_steps=1000, seed=0, threads=2, terrain='slope', chain=False, mesh=None, nodes=None, dist='normal', chain_section='landing', chain_mesh='grid', stride_map='auto', **params)"
)]
#[allow(clippy::too_many_arguments)]
fn mfpt<'py>(
    py: Python<'py>,
    model: &str,
    slope: Option<&Bound<'py, PyAny>>,
    sd: Option<&Bound<'py, PyAny>>,
    walkers: usize,
    max_steps: usize,
    seed: u64,
    threads: usize,
    terrain: &str,
    chain: bool,
    mesh: Option<usize>,
    nodes: Option<usize>,
    dist: &str,
    chain_section: &str,
    chain_mesh: &str,
    stride_map: &str,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    pdw::input::check_threads(threads, "threads").map_err(err)?;
    let kind = pdw::mfpt::check_terrain(terrain, &MFPT_FLAGS).map_err(err)?;
    let stride_map = pdw::mfpt::StrideMap::parse(stride_map, "stride_map").map_err(err)?;
    let section =
        pdw::mfpt::ChainSection::parse(chain_section, CHAIN_FLAGS.section).map_err(err)?;
    let dist = pdw::mfpt::parse_dist(dist, &MFPT_FLAGS).map_err(err)?;
    if !chain && (mesh.is_some() || nodes.is_some()) {
        return Err(err("mesh, nodes: set only with chain=True"));
    }
    let sds = mfpt_sds(sd, kind)?;
    let m = build_kw(model, slope, params)?;
    stride_map.closed_form(&m, "stride_map").map_err(err)?;
    if sds.len() > 1 {
        if chain {
            return Err(err(
                "chain: runs at one sd; give sd a single value, not a range A:B:N",
            ));
        }
        return mfpt_curve(
            py,
            &m,
            &sds,
            (kind, &dist),
            (walkers, max_steps, seed, threads),
            stride_map,
        );
    }
    pdw::mfpt::check_model_for(&m, kind).map_err(err)?;
    let plan = mfpt_plan(
        &m,
        (kind, &dist),
        sds[0],
        (walkers, max_steps, seed),
        stride_map,
    );
    pdw::mfpt::check_plan(&plan, &MFPT_FLAGS).map_err(err)?;
    pdw::mfpt::check_heights(&m, &plan, &MFPT_FLAGS).map_err(err)?;
    let chain_plan = if chain {
        pdw::mfpt::check_chain_terrain(&m, kind, "chain").map_err(err)?;
        let c = pdw::mfpt::check_chain(&m, mesh, nodes, section, &CHAIN_FLAGS).map_err(err)?;
        Some(pdw::mfpt::check_layout(c, chain_mesh, "chain_mesh").map_err(err)?)
    } else {
        None
    };
    // the same memory estimate as `pdw-sweep mfpt`, before any walker walks
    pdw::mfpt::check_memory(
        &m,
        &plan,
        chain_plan.as_ref(),
        &MFPT_FLAGS,
        CHAIN_FLAGS.mesh,
    )
    .map_err(err)?;
    let (est, start, pair) = interruptible(py, || -> PyResult<_> {
        let (x0, section) = pdw::mfpt::start(&m).map_err(err)?;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(err)?;
        let (_, est) = pdw::mfpt::run(&m, &plan, &x0, &pool, &|_| {}).map_err(err)?;
        let pair = match &chain_plan {
            Some(c) => Some(pdw::mfpt::chain_pair(&m, &plan, c, &x0, &pool, &|_| {}).map_err(err)?),
            None => None,
        };
        Ok((est, section, pair))
    })?;
    let d = estimate_dict(py, &est, &plan)?;
    d.set_item("start", start)?;
    d.set_item("stride_map", plan.stride_map.describe(&m))?;
    if let (Some(c), Some(pair)) = (&chain_plan, &pair) {
        d.set_item("chain", chain_dict(py, &plan, c, pair, &est)?)?;
    }
    Ok(d)
}

/// `sd` of `mfpt(...)`: a number or a string, one value or a range `A:B:N`.
fn mfpt_sds(
    sd: Option<&Bound<'_, PyAny>>,
    kind: pdw::limit::terrain::TerrainKind,
) -> PyResult<Vec<f64>> {
    let parse = |s: &str| pdw::mfpt::parse_sd_values_for(s, kind, &MFPT_FLAGS).map_err(err);
    match sd {
        None => Err(err(
            "sd: give the terrain's standard deviation (slope: rad, or '1deg'; step-down: a \
             length)",
        )),
        Some(v) => match v.extract::<f64>() {
            Ok(x) => parse(&x.to_string()),
            Err(_) => parse(&v.extract::<String>()?),
        },
    }
}

/// The Monte Carlo estimate of `mfpt(...)` as a dict.
fn estimate_dict<'py>(
    py: Python<'py>,
    est: &pdw::limit::terrain::MfptEstimate,
    plan: &pdw::mfpt::MfptPlan,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (k, v) in [
        ("mfpt", est.mfpt),
        ("stderr", est.stderr),
        ("restricted_mean", est.restricted_mean),
        ("restricted_stderr", est.restricted_stderr),
        ("mean", plan.terrain.mean),
        ("sd", plan.terrain.sd),
    ] {
        d.set_item(k, v)?;
    }
    for (k, v) in [
        ("walkers", est.walkers),
        ("falls", est.falls),
        ("censored", est.censored),
    ] {
        d.set_item(k, v)?;
    }
    d.set_item("total_steps", est.total_steps)?;
    d.set_item("survival", est.survival.clone().into_pyarray(py))?;
    let f = PyDict::new(py);
    for (k, n) in &est.failures {
        f.set_item(k, n)?;
    }
    d.set_item("failures", f)?;
    d.set_item("terrain", plan.terrain.kind.name())?;
    d.set_item("dist", pdw::mfpt::dist_words(&plan.terrain.dist))?;
    Ok(d)
}

/// The chain's results as `mfpt(..., chain=True)["chain"]`: per mesh (arrays of two: `mesh`,
/// `mfpt`, `lambda`, `mfpt_lambda` = 1/(1 − λ) − 1, `mfpt_quasi_stationary`, `fall_per_step`,
/// `out_of_mesh`, `states`), `refinement_change`, `warning` (None when converged),
/// `agreement` (the chain against the walkers `est`, None when they agree), `node_warning` (a
/// node of the rule at a step height of exactly 0, else None), `nodes`,
/// `quadrature`, `section` (`landing` or `mid-stance`), `layout` (`grid` or `cloud`), and
/// `box`: `corner`, `edges` (rows), `widening_passes`, `out_share`; on a cloud also `cloud`
/// (arrays of two: `cell`, `seeds`, `nodes`, `passes`).
fn chain_dict<'py>(
    py: Python<'py>,
    plan: &pdw::mfpt::MfptPlan,
    c: &pdw::mfpt::ChainPlan,
    pair: &pdw::mfpt::ChainPair,
    est: &pdw::limit::terrain::MfptEstimate,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    type Column = fn(&pdw::limit::markov::ChainResult) -> f64;
    let columns: [(&str, Column); 7] = [
        ("mfpt", |r| r.mfpt),
        ("lambda", |r| r.lambda),
        ("mfpt_lambda", |r| r.mfpt_lambda),
        ("mfpt_quasi_stationary", |r| r.mfpt_quasi_stationary),
        ("fall_per_step", |r| r.fall_per_step),
        ("out_of_mesh", |r| r.out_of_mesh),
        ("states", |r| r.states as f64),
    ];
    for (k, f) in columns {
        d.set_item(
            k,
            pair.results
                .iter()
                .map(f)
                .collect::<Vec<f64>>()
                .into_pyarray(py),
        )?;
    }
    d.set_item(
        "mesh",
        vec![c.mesh as u64, 2 * c.mesh as u64].into_pyarray(py),
    )?;
    d.set_item("refinement_change", pair.change)?;
    d.set_item("warning", pair.warning.clone())?;
    let [coarse, fine] = &pair.results;
    d.set_item(
        "agreement",
        pdw::mfpt::agreement_warning(coarse.mfpt, fine.mfpt, est, "nodes"),
    )?;
    d.set_item(
        "node_warning",
        pdw::mfpt::zero_height_node_warning(plan, c.nodes, "nodes"),
    )?;
    d.set_item("nodes", c.nodes)?;
    d.set_item("section", c.section.name())?;
    d.set_item("quadrature", pdw::mfpt::quadrature_name(&plan.terrain.dist))?;
    let cb = &pair.chain_box;
    let (corner, edges) = cb.frame.edges(&cb.bounds);
    let b = PyDict::new(py);
    b.set_item("corner", corner.into_pyarray(py))?;
    let flat: Vec<f64> = edges.iter().flatten().copied().collect();
    let n = edges.len();
    let edges = Array2::from_shape_vec((n, n), flat).map_err(err)?;
    b.set_item("edges", edges.into_pyarray(py))?;
    b.set_item("widening_passes", cb.passes)?;
    b.set_item("out_share", cb.out_share)?;
    d.set_item("box", b)?;
    d.set_item("layout", c.layout.name())?;
    if let Some(cl) = &pair.clouds {
        let cd = PyDict::new(py);
        cd.set_item(
            "cell",
            cl.iter()
                .map(|s| s.cell)
                .collect::<Vec<f64>>()
                .into_pyarray(py),
        )?;
        type Count = fn(&pdw::mfpt::CloudStats) -> usize;
        let counts: [(&str, Count); 3] = [
            ("seeds", |s| s.seeds),
            ("nodes", |s| s.nodes),
            ("passes", |s| s.passes),
        ];
        for (k, f) in counts {
            let v: Vec<u64> = cl.iter().map(|s| f(s) as u64).collect();
            cd.set_item(k, v.into_pyarray(py))?;
        }
        d.set_item("cloud", cd)?;
    }
    Ok(d)
}

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
fn disturb<'py>(
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

/// `simulate(model="simplest", slope=None, state=None, gait="stable", steps=10, dt_out=None, **params)`.
#[pyfunction]
#[pyo3(
    signature = (model="simplest", slope=None, state=None, gait="stable", steps=10, dt_out=None, **params),
    text_signature = "(model='simplest', slope=None, state=None, gait='stable', steps=10, dt_out=None, **params)"
)]
#[allow(clippy::too_many_arguments)]
fn simulate<'py>(
    py: Python<'py>,
    model: &str,
    slope: Option<&Bound<'py, PyAny>>,
    state: Option<Vec<f64>>,
    gait: &str,
    steps: usize,
    dt_out: Option<&Bound<'py, PyAny>>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    const FLAGS: SimulateFlags = SimulateFlags {
        steps: "steps",
        dt_out: "dt_out",
        state: "state",
        gait: "gait",
        rk4_step: "rk4_step",
    };
    let which = GaitKind::parse(gait, "gait").map_err(err)?;
    let asked = dt_out_of(dt_out)?;
    pdw::simulate::check_request(steps, asked.every(), &FLAGS).map_err(err)?;
    let m = build_kw(model, slope, params)?;
    let tr = interruptible(py, || -> PyResult<_> {
        let start = match state {
            Some(v) => Start::State(v),
            None => Start::Gait(which),
        };
        let walk = pdw::simulate::start(&m, &start, &FLAGS).map_err(|e| match e {
            StartError::Input(e) => err(e),
            StartError::Limit(e) => err(e),
            StartError::NoGait {
                which,
                tried,
                failed,
            } => no_gait_error(&m, which.name(), tried, &failed),
        })?;
        let sp = pdw::simulate::spacing(&m, &walk, asked);
        let opts =
            pdw::simulate::options_spaced(&m, steps, &sp, pdw::simulate::default_integrator());
        pdw::simulate::check_samples(&walk, &opts, &FLAGS).map_err(err)?;
        Ok((pdw::simulate::run(&m, &walk, &opts).map_err(err)?, sp))
    })?;
    let (tr, sp) = tr;
    let d = trajectory_dict(py, &m, &tr)?;
    d.set_item("dt_out", sp.dt_out)?;
    d.set_item("dt_out_source", sp.source)?;
    positions_items(py, &d, &m, &tr)?;
    Ok(d)
}

/// `simulate`'s `dt_out`: `None` (the default spacing), `"steps"` or a time step.
fn dt_out_of(v: Option<&Bound<'_, PyAny>>) -> PyResult<pdw::simulate::DtOut> {
    use pdw::simulate::DtOut;
    let Some(v) = v.filter(|v| !v.is_none()) else {
        return Ok(DtOut::Default);
    };
    if let Ok(s) = v.extract::<String>() {
        return DtOut::parse(&s, "dt_out").map_err(err);
    }
    match v.extract::<f64>() {
        Ok(h) => Ok(DtOut::Every(h)),
        Err(_) => Err(err(format!(
            "dt_out: {} is neither a positive time step nor the word steps",
            v.repr().map(|r| r.to_string()).unwrap_or_default()
        ))),
    }
}

/// The walker's points and centre of mass in the walk's fixed frame: `positions` (n, P, 2),
/// `point_names`, `com` (n, 2) and `positions_frame`; where there are none, `point_names` is
/// empty and `positions_frame` says why.
fn positions_items<'py>(
    py: Python<'py>,
    d: &Bound<'py, PyDict>,
    m: &Model,
    tr: &Trajectory,
) -> PyResult<()> {
    match pdw::simulate::positions(m, tr) {
        Ok(p) => {
            let (n, np) = (tr.len(), p.names.len());
            let a = numpy::ndarray::Array3::from_shape_vec((n, np, 2), p.points).map_err(err)?;
            d.set_item("positions", a.into_pyarray(py))?;
            d.set_item("com", rows_to_array(py, p.com, 2)?)?;
            d.set_item("point_names", p.names)?;
            d.set_item("positions_frame", pdw::simulate::POSITIONS_FRAME)?;
        }
        Err(why) => {
            d.set_item("point_names", Vec::<String>::new())?;
            d.set_item("positions_frame", why)?;
        }
    }
    Ok(())
}

/// A trajectory as `simulate` returns it: time, states (rows), mode, step, forces, flags,
/// energy where the model has them, the events, the section points, the outcome, the units.
fn trajectory_dict<'py>(
    py: Python<'py>,
    m: &Model,
    tr: &Trajectory,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("state_names", tr.state_names.clone())?;
    d.set_item("t", tr.t.clone().into_pyarray(py))?;
    d.set_item("x", rows_to_array(py, tr.x.clone(), tr.dim())?)?;
    d.set_item("mode", tr.mode.clone().into_pyarray(py))?;
    // What the mode codes and the state components mean (`pdw-sweep models` lists the same).
    d.set_item("mode_names", m.walker.mode_names())?;
    d.set_item("coordinates", m.walker.coordinate_meanings())?;
    d.set_item("step", tr.step.clone().into_pyarray(py))?;
    if let Some(f) = &tr.forces {
        d.set_item("normal_force", f.normal.clone().into_pyarray(py))?;
        d.set_item("tangential_force", f.tangential.clone().into_pyarray(py))?;
        d.set_item(
            "friction_required",
            f.friction_required.clone().into_pyarray(py),
        )?;
        d.set_item("knee_torque", rows_to_array(py, f.knee_torque.clone(), 2)?)?;
    }
    if let Some(fl) = &tr.flags {
        d.set_item("flags", fl.clone().into_pyarray(py))?;
    }
    if let Some(e) = pdw::simulate::fixed_frame_energy(m, tr) {
        d.set_item("energy_fixed_frame", e.into_pyarray(py))?;
    }
    if let Some(e) = &tr.energy {
        d.set_item("energy", e.clone().into_pyarray(py))?;
    }
    d.set_item("events", events_dict(py, &tr.events, tr.dim())?)?;
    d.set_item(
        "section",
        rows_to_array(py, tr.section.clone(), m.walker.section_dim())?,
    )?;
    d.set_item("steps_done", tr.steps_done)?;
    d.set_item(
        "outcome",
        match tr.outcome {
            StrideOutcome::Ok => "ok".to_string(),
            StrideOutcome::Fall { kind, .. } => kind.name().to_string(),
            o => o.to_string(),
        },
    )?;
    d.set_item("units", units_dict(py, tr)?)?;
    Ok(d)
}

/// The events of a trajectory as columns: time, kind, step, whether it ends a step, the modes
/// before and after, the states before and after (rows of `dim`).
fn events_dict<'py>(
    py: Python<'py>,
    e: &[trajectory::TrajectoryEvent],
    dim: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let ev = PyDict::new(py);
    let column = |f: &dyn Fn(&trajectory::TrajectoryEvent) -> u32| -> Bound<'py, PyAny> {
        e.iter()
            .map(f)
            .collect::<Vec<_>>()
            .into_pyarray(py)
            .into_any()
    };
    ev.set_item(
        "t",
        e.iter().map(|e| e.t).collect::<Vec<_>>().into_pyarray(py),
    )?;
    ev.set_item("kind", e.iter().map(|e| e.kind.clone()).collect::<Vec<_>>())?;
    ev.set_item("step", column(&|e| e.step as u32))?;
    ev.set_item(
        "ends_step",
        e.iter()
            .map(|e| e.ends_step)
            .collect::<Vec<_>>()
            .into_pyarray(py),
    )?;
    ev.set_item("mode_before", column(&|e| e.mode_before as u32))?;
    ev.set_item("mode_after", column(&|e| e.mode_after as u32))?;
    let states = |f: &dyn Fn(&trajectory::TrajectoryEvent) -> &[f64]| {
        rows_to_array(
            py,
            e.iter().flat_map(|e| f(e).iter().copied()).collect(),
            dim,
        )
    };
    ev.set_item("pre", states(&|e| &e.pre)?)?;
    ev.set_item("post", states(&|e| &e.post)?)?;
    Ok(ev)
}

/// The unit of every column of a trajectory, by the column's name.
fn units_dict<'py>(py: Python<'py>, tr: &Trajectory) -> PyResult<Bound<'py, PyDict>> {
    let u = &tr.units;
    let ud = PyDict::new(py);
    ud.set_item("t", &u.time)?;
    for (name, unit) in tr.state_names.iter().zip(&u.state) {
        ud.set_item(name, unit)?;
    }
    ud.set_item("normal_force", &u.force)?;
    ud.set_item("tangential_force", &u.force)?;
    ud.set_item("friction_required", "1")?;
    ud.set_item("knee_torque", &u.torque)?;
    ud.set_item("energy", &u.energy)?;
    Ok(ud)
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
    m.add_function(wrap_pyfunction!(fixed_point, m)?)?;
    m.add_function(wrap_pyfunction!(scan_gaits, m)?)?;
    m.add_function(wrap_pyfunction!(stride_map, m)?)?;
    m.add_function(wrap_pyfunction!(stride_outcomes, m)?)?;
    m.add_function(wrap_pyfunction!(basin, m)?)?;
    m.add_function(wrap_pyfunction!(continuation, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(mfpt, m)?)?;
    m.add_function(wrap_pyfunction!(disturb, m)?)?;
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
