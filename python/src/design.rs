//! `design`: a design search, as `pdw-sweep design` runs it ([`pdw::design`]): free
//! parameters of a chain walker searched within their bounds for the most robust (or most
//! stable) passive gait that is physically valid along the whole stride.

use numpy::ndarray::Array2;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::json_to_py;
use crate::errors::err;
use crate::{interruptible, THREADS};
use pdw::design::DesignPlan;
use pdw::design_command::DesignInput;
use pdw::limit::design::{status, DesignEval};
use pdw::pipeline::{Report, Silent, Spelling};

/// `free` as `NAME=LO:HI` texts: a dict `{name: (lo, hi)}`, a list of such texts, or one text.
fn free_texts(free: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
    if let Ok(d) = free.cast::<PyDict>() {
        let mut v = Vec::new();
        for (k, r) in d.iter() {
            let name: String = k.extract()?;
            let (lo, hi): (f64, f64) = r
                .extract()
                .map_err(|_| err(format!("free: {name}: give the bounds as a pair (lo, hi)")))?;
            v.push(format!("{name}={lo}:{hi}"));
        }
        return Ok(v);
    }
    if let Ok(s) = free.extract::<String>() {
        return Ok(vec![s]);
    }
    free.extract::<Vec<String>>().map_err(|_| {
        err("free: give a dict {name: (lo, hi)}, or texts 'NAME=LO:HI' (one or a list)")
    })
}

/// `design(model="compass", free=None, objective="basin", budget=60, seed=0, init=0, mu=0.6,
/// knee_margin=0.1, min_margin=0.0, basin_grid=15, basin_box=None, max_strides=40, threads=2,
/// out=None, png=None, force=False, slope=None, starts=1, **params)`: `pdw-sweep design` — the
/// same plan, search, files and report ([`pdw::design_command`]). `basin_box=None` scales the
/// box with each design's gait; `starts` local runs of the multi-start share `budget`
/// ([`pdw::limit::design::search_multi`]); `out` writes the design file `pdw-sweep design`
/// writes, and its picture (`png`, default beside it); an existing `out` of the same settings
/// continues its search, as the CLI does (`force=True` starts over). The dict holds the
/// report's fields (those of the CLI's `design --json`: `counts`, `best` — the closest design
/// with `closest_because` when nothing is feasible —, …) and every design as arrays; `fates`
/// and `bindings` give every design's gait-search fates and binding criterion.
#[pyfunction]
#[pyo3(
    signature = (model="compass", free=None, objective="basin", budget=60, seed=0, init=0, mu=0.6, knee_margin=0.1, min_margin=0.0, basin_grid=15, basin_box=None, max_strides=40, threads=THREADS, out=None, png=None, force=false, slope=None, starts=1, **params),
    text_signature = "(model='compass', free=None, objective='basin', budget=60, seed=0, init=0, mu=0.6, knee_margin=0.1, min_margin=0.0, basin_grid=15, basin_box=None, max_strides=40, threads=2, out=None, png=None, force=False, slope=None, starts=1, **params)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn design<'py>(
    py: Python<'py>,
    model: &str,
    free: Option<&Bound<'py, PyAny>>,
    objective: &str,
    budget: i64,
    seed: u64,
    init: usize,
    mu: f64,
    knee_margin: f64,
    min_margin: f64,
    basin_grid: i64,
    basin_box: Option<(f64, f64)>,
    max_strides: i64,
    threads: usize,
    out: Option<std::path::PathBuf>,
    png: Option<std::path::PathBuf>,
    force: bool,
    slope: Option<&Bound<'py, PyAny>>,
    starts: i64,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let free = match free {
        Some(f) => free_texts(f)?,
        None => Vec::new(),
    };
    let input = DesignInput {
        model: crate::model_choice(model, slope, params)?,
        command: format!(
            "python: pdw_sweep.design(model='{model}', free=[{}], budget={budget}, \
             seed={seed}, init={init}, starts={starts})",
            free.join(", ")
        ),
        free,
        objective: objective.to_string(),
        budget,
        seed,
        init,
        starts,
        mu,
        knee_margin,
        min_margin,
        basin_grid,
        basin_box: basin_box.map(|(a, b)| [a, b]),
        max_strides,
        out,
        png,
        threads,
        force,
    };
    let command = pdw::design_command::plan(&input, Spelling::Python).map_err(err)?;
    crate::give_warnings(py)?;
    let run = interruptible(py, || command.run(&Silent).map_err(err))?;
    let d = design_dict(py, &command.plan, &run.designs)?;
    if let serde_json::Value::Object(fields) = run.report.json() {
        for (k, v) in &fields {
            d.set_item(k, json_to_py(py, v)?)?;
        }
    }
    // A feasible best design on a face of the box is warned about (an infeasible one says
    // nothing about an optimum beyond the bound).
    for w in run.report.best.iter().flat_map(|b| &b.on_bound) {
        crate::queue_warning(w);
    }
    crate::give_warnings(py)?;
    Ok(d)
}

use pdw::design::{measures, COLUMNS};

/// The dict `design` returns: every design evaluated (in order) and the best one.
fn design_dict<'py>(
    py: Python<'py>,
    plan: &DesignPlan,
    hist: &[DesignEval],
) -> PyResult<Bound<'py, PyDict>> {
    let (n, k) = (hist.len(), plan.space.names.len());
    let d = PyDict::new(py);
    d.set_item("free_names", plan.space.names.clone())?;
    d.set_item("objective", plan.options.objective.name())?;
    let p: Vec<f64> = hist.iter().flat_map(|e| e.params.clone()).collect();
    let p = Array2::from_shape_vec((n, k), p).map_err(err)?;
    d.set_item("params", p.into_pyarray(py))?;
    let st: Vec<u8> = hist.iter().map(|e| e.status).collect();
    d.set_item("status", st.into_pyarray(py))?;
    d.set_item("status_names", status::NAMES.to_vec())?;
    d.set_item(
        "reasons",
        hist.iter().map(|e| e.reason.clone()).collect::<Vec<_>>(),
    )?;
    d.set_item(
        "bindings",
        hist.iter().map(|e| e.binding.clone()).collect::<Vec<_>>(),
    )?;
    d.set_item(
        "fates",
        hist.iter().map(|e| e.fates.clone()).collect::<Vec<_>>(),
    )?;
    let sec: Vec<f64> = hist.iter().flat_map(|e| e.section).collect();
    let sec = Array2::from_shape_vec((n, 3), sec).map_err(err)?;
    d.set_item("section", sec.into_pyarray(py))?;
    for (i, name) in COLUMNS.iter().enumerate() {
        let col: Vec<f64> = hist.iter().map(|e| measures(e)[i]).collect();
        d.set_item(*name, col.into_pyarray(py))?;
    }
    Ok(d)
}
