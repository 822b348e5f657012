//! `design`: a design search, as `pdw-sweep design` runs it ([`pdw::design`]): free
//! parameters of a chain walker searched within their bounds for the most robust (or most
//! stable) passive gait that is physically valid along the whole stride.

use numpy::ndarray::Array2;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::err;
use crate::{interruptible, THREADS};
use pdw::design::DesignPlan;
use pdw::limit::basin::BasinOptions;
use pdw::limit::design::{status, DesignEval, DesignOptions};

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

/// The search's options from the keyword arguments, each checked as the CLI checks its flag.
#[allow(clippy::too_many_arguments)]
fn options(
    objective: &str,
    budget: i64,
    seed: u64,
    init: usize,
    (mu, knee_margin, min_margin): (f64, f64, f64),
    basin_grid: i64,
    basin_box: Option<(f64, f64)>,
    max_strides: i64,
) -> PyResult<DesignOptions> {
    let basin_box = basin_box
        .map(|(a, b)| {
            pdw::design::check_basin_box(&[a, b], &format!("{a},{b}"), "basin_box").map_err(err)
        })
        .transpose()?;
    Ok(DesignOptions {
        objective: pdw::design::parse_objective(objective, "objective").map_err(err)?,
        mu: pdw::design::check_mu(mu, "mu").map_err(err)?,
        knee_margin: pdw::design::check_knee_margin(knee_margin, "knee_margin").map_err(err)?,
        min_margin: pdw::design::check_min_margin(min_margin, "min_margin").map_err(err)?,
        budget: pdw::design::check_budget(budget, "budget").map_err(err)?,
        seed,
        start: None,
        init,
        basin_grid: pdw::design::check_basin_grid(basin_grid, "basin_grid").map_err(err)?,
        basin_box,
        basin: BasinOptions {
            max_strides: pdw::design::check_max_strides(max_strides, "max_strides").map_err(err)?,
            ..BasinOptions::default()
        },
        newton_tol: 1e-10,
    })
}

/// `design(model="compass", free=None, objective="basin", budget=60, seed=0, init=0, mu=0.6,
/// knee_margin=0.1, min_margin=0.0, basin_grid=15, basin_box=None, max_strides=40, threads=2,
/// out=None, force=False, slope=None, starts=1, **params)`. `basin_box=None` scales the box
/// with each design's gait; `starts` local runs of the multi-start share `budget`
/// ([`pdw::limit::design::search_multi`]); `out` writes the design file `pdw-sweep design`
/// writes (an existing one only with `force=True`). The dict's `best` is the closest design
/// (the smallest graded cost) with `closest_because` when nothing is feasible; `fates` and
/// `bindings` give every design's gait-search fates and binding criterion.
#[pyfunction]
#[pyo3(
    signature = (model="compass", free=None, objective="basin", budget=60, seed=0, init=0, mu=0.6, knee_margin=0.1, min_margin=0.0, basin_grid=15, basin_box=None, max_strides=40, threads=THREADS, out=None, force=false, slope=None, starts=1, **params),
    text_signature = "(model='compass', free=None, objective='basin', budget=60, seed=0, init=0, mu=0.6, knee_margin=0.1, min_margin=0.0, basin_grid=15, basin_box=None, max_strides=40, threads=2, out=None, force=False, slope=None, starts=1, **params)"
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
    force: bool,
    slope: Option<&Bound<'py, PyAny>>,
    starts: i64,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let starts = pdw::design::check_starts(starts, "starts").map_err(err)?;
    let free = match free {
        Some(f) => free_texts(f)?,
        None => Vec::new(),
    };
    let mut options = options(
        objective,
        budget,
        seed,
        init,
        (mu, knee_margin, min_margin),
        basin_grid,
        basin_box,
        max_strides,
    )?;
    pdw::input::check_threads(threads, "threads").map_err(err)?;
    if let Some(o) = out.as_ref().filter(|o| o.exists() && !force) {
        return Err(err(format!(
            "out: '{}' exists; pass force=True to replace it",
            o.display()
        )));
    }
    let choice = crate::model_choice(model, slope, params)?;
    let base = pdw::build_model(&choice).map_err(err)?;
    crate::give_warnings(py)?;
    pdw::design::check_model(&base, "model").map_err(err)?;
    let space = pdw::design::space(&choice, &base, &free, "free").map_err(err)?;
    options.start = Some(pdw::design::start(&base, &space));
    let plan = DesignPlan {
        model: choice,
        space,
        options,
        starts,
    };
    let hist = interruptible(py, || -> PyResult<_> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(err)?;
        pdw::design::search(&plan, &base, Vec::new(), &pool, &mut |_: &DesignEval| {}).map_err(err)
    })?;
    if let Some(o) = &out {
        write_file(o, &plan, &base, &hist, threads)?;
    }
    let d = design_dict(py, &plan, &hist)?;
    crate::give_warnings(py)?;
    Ok(d)
}

use pdw::design::{measures, COLUMNS};

/// `out`: the design file of the search, as `pdw-sweep design` writes it
/// ([`pdw::design::write_file`]), its provenance naming the Python call.
fn write_file(
    out: &std::path::Path,
    plan: &DesignPlan,
    base: &pdw::BuiltModel,
    hist: &[DesignEval],
    threads: usize,
) -> PyResult<()> {
    let settings = pdw::design::settings(plan, base);
    let options = pdw::design::run_options(&settings, threads);
    let call = format!(
        "python: pdw_sweep.design(model='{}', free=[{}], budget={}, seed={}, init={}, starts={})",
        plan.model.model,
        plan.space.names.join(", "),
        plan.options.budget,
        plan.options.seed,
        plan.options.init,
        plan.starts
    );
    let mut prov = pdw::provenance(&call, &options);
    prov.model_spec = pdw::model::spec_toml(&plan.model.model).unwrap_or_default();
    pdw::design::write_file(out, (plan, base, &settings), hist, &prov, &[]).map_err(err)
}

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
    d.set_item("best", best_dict(py, plan, hist)?)?;
    Ok(d)
}

/// The best design (smallest cost; `None` without designs): its parameters by name, status,
/// reason, measures and whether it is feasible.
fn best_dict<'py>(
    py: Python<'py>,
    plan: &DesignPlan,
    hist: &[DesignEval],
) -> PyResult<Option<Bound<'py, PyDict>>> {
    let Some((b, why)) = pdw::design::closest(hist, plan.options.min_margin) else {
        return Ok(None);
    };
    let d = PyDict::new(py);
    let params = PyDict::new(py);
    for (n, v) in plan.space.names.iter().zip(&b.params) {
        params.set_item(n, v)?;
    }
    d.set_item("params", params)?;
    d.set_item("index", hist.iter().position(|e| std::ptr::eq(e, b)))?;
    d.set_item("status", status::NAMES[b.status as usize])?;
    d.set_item("feasible", b.feasible())?;
    d.set_item("reason", &b.reason)?;
    d.set_item("section", b.section.to_vec().into_pyarray(py))?;
    for (name, v) in COLUMNS.iter().zip(measures(b)) {
        d.set_item(*name, v)?;
    }
    d.set_item("binding", &b.binding)?;
    d.set_item("fates", &b.fates)?;
    d.set_item("closest_because", why)?;
    // A feasible best design on a face of the box: named in `on_bound` and warned about (an
    // infeasible one says nothing about an optimum beyond the bound).
    let on_bound = if b.feasible() {
        pdw::design::bound_warnings(&plan.space, &b.params)
    } else {
        Vec::new()
    };
    for w in &on_bound {
        crate::queue_warning(w);
    }
    d.set_item("on_bound", on_bound)?;
    Ok(Some(d))
}
