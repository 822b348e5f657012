//! `follow`: the curve of period doublings or folds of the period-one gait in two parameters,
//! as `pdw-sweep fixedpoint --follow pd|fold --sweep NAME=A:B:N --free NAME[=LO:HI]` computes
//! it ([`pdw::follow`]: the gait at A, its bifurcation in the free parameter, the curve, and
//! with `map_grid` the region map under it).

use numpy::ndarray::Array2;
use numpy::{Complex64, IntoPyArray};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::rows_to_array;
use crate::errors::err;
use crate::{interruptible, THREADS};
use pdw::follow::{FollowFlags, FollowPlan, GaitChoice, StartSearch};
use pdw::limit::{Bifurcation, Curve, CurveEnd, Region, RegionOptions};

/// How Python names a curve's inputs in messages.
const FLAGS: FollowFlags = FollowFlags {
    kind: "kind",
    sweep: "sweep",
    free: "free",
    free_range_hint: |n| format!("free=\"{n}=LO:HI\""),
    set_hint: |n| format!("{n}=VALUE"),
};

/// What the run computed.
struct Followed {
    bif: Bifurcation,
    curve: Curve,
    map: Option<pdw::follow::RegionGrid>,
}

/// `follow(model="simplest", kind="pd", sweep=None, free=None, gait="all", guess=None,
/// tol=1e-12, map_grid=None, threads=2, slope=None, **params)`.
#[pyfunction]
#[pyo3(
    signature = (model="simplest", kind="pd", sweep=None, free=None, gait="all", guess=None, tol=1e-12, map_grid=None, threads=THREADS, slope=None, **params),
    text_signature = "(model='simplest', kind='pd', sweep=None, free=None, gait='all', guess=None, tol=1e-12, map_grid=None, threads=2, slope=None, **params)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn follow<'py>(
    py: Python<'py>,
    model: &str,
    kind: &str,
    sweep: Option<&str>,
    free: Option<&str>,
    gait: &str,
    guess: Option<Vec<f64>>,
    tol: f64,
    map_grid: Option<(usize, usize)>,
    threads: usize,
    slope: Option<&Bound<'py, PyAny>>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = pdw::follow::parse_kind(kind, "kind").map_err(err)?;
    let Some(sweep) = sweep else {
        return Err(err(
            "sweep: give the stepped parameter and the N points of the curve, \
                        sweep=\"NAME=A:B:N\" (e.g. \"hip_mass=2:20:10\")",
        ));
    };
    let Some(free) = free else {
        return Err(err(
            "free: give the parameter solved for along the curve, free=\"NAME\" or \
             \"NAME=LO:HI\" (e.g. \"slope\")",
        ));
    };
    let step = pdw::input::parse_sweep(sweep).map_err(err)?;
    let free = pdw::follow::parse_free(free, "free").map_err(err)?;
    crate::fixed_point::check_gait_and_tol(gait, tol)?;
    pdw::input::check_threads(threads, "threads").map_err(err)?;
    if let Some((nx, ny)) = map_grid {
        if nx < 2 || ny < 2 || nx * ny > 250_000 {
            return Err(err(format!(
                "map_grid: ({nx}, {ny}): need at least 2 cells per side and at most 250000 \
                 cells (each cell iterates the stride map a few hundred times)"
            )));
        }
    }
    let choice = crate::model_choice(model, slope, params)?;
    let gait = GaitChoice::from_name(gait).unwrap_or(GaitChoice::Any);
    let (mut plan, m_own) =
        pdw::follow::plan(choice, kind, step, &free, gait, tol, &FLAGS).map_err(err)?;
    let m_a = pdw::follow::start_model(&mut plan, guess, "guess").map_err(err)?;
    crate::give_warnings(py)?;
    let f = interruptible(py, || compute(&plan, &m_a, &m_own, map_grid, threads))?;
    if let Some(lost) = pdw::follow::lost_message(&plan, &f.curve) {
        crate::warn_all(
            py,
            &[format!(
                "{lost}; the {} points reached are returned (complete = False)",
                f.curve.points.len()
            )],
        )?;
    }
    follow_dict(py, &plan, &m_a, &f)
}

/// The steps of [`pdw::follow`], or why there is no curve to follow.
fn compute(
    plan: &FollowPlan,
    m_a: &pdw::BuiltModel,
    m_own: &pdw::BuiltModel,
    map_grid: Option<(usize, usize)>,
    threads: usize,
) -> PyResult<Followed> {
    let gait = match pdw::follow::start_gait(plan, m_a, m_own).map_err(err)? {
        Ok(g) => g,
        Err(why) => return Err(err(pdw::follow::no_gait_message(plan, m_a, &why))),
    };
    let StartSearch { found, .. } = pdw::follow::locate_start(plan, &gait);
    let bif = found.map_err(|ends| err(pdw::follow::no_bifurcation_message(plan, &ends)))?;
    let (_, curve) = pdw::follow::curve(plan, &bif).map_err(err)?;
    let map = match map_grid {
        Some(grid) if !curve.points.is_empty() => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .map_err(err)?;
            let ropts = RegionOptions::default();
            let g = pdw::follow::region_map(plan, &curve, grid, &ropts, &pool, &|_| {});
            Some(g.map_err(err)?)
        }
        _ => None,
    };
    Ok(Followed { bif, curve, map })
}

/// The dict `follow` returns (the keys of `fixedpoint --follow --json`, as arrays).
fn follow_dict<'py>(
    py: Python<'py>,
    plan: &FollowPlan,
    m: &pdw::BuiltModel,
    f: &Followed,
) -> PyResult<Bound<'py, PyDict>> {
    let pts = &f.curve.points;
    let n = pts.len();
    let col = |g: &dyn Fn(&pdw::limit::CurvePoint) -> f64| {
        pts.iter().map(g).collect::<Vec<_>>().into_pyarray(py)
    };
    let d = PyDict::new(py);
    d.set_item("kind", plan.kind.name())?;
    d.set_item("params", [plan.step.name.clone(), plan.free.clone()])?;
    d.set_item("p_step", col(&|p| p.p_step))?;
    d.set_item("p_free", col(&|p| p.p_free))?;
    d.set_item("section_names", m.info.section_names.to_vec())?;
    d.set_item("state_names", m.info.state_names.to_vec())?;
    let ds = m.info.section_names.len();
    let section = pts.iter().flat_map(|p| p.section.clone()).collect();
    d.set_item("section", rows_to_array(py, section, ds)?)?;
    let state = pts.iter().flat_map(|p| p.state.clone()).collect();
    d.set_item("state", rows_to_array(py, state, m.info.state_names.len())?)?;
    d.set_item("critical_multiplier", col(&|p| p.critical))?;
    let nm = pts.first().map_or(0, |p| p.multipliers.len());
    let mult: Vec<Complex64> = pts
        .iter()
        .flat_map(|p| p.multipliers.iter().map(|l| Complex64::new(l.re, l.im)))
        .collect();
    let mult = Array2::from_shape_vec((n, nm), mult).map_err(err)?;
    d.set_item("multipliers", mult.into_pyarray(py))?;
    d.set_item("period", col(&|p| p.period))?;
    d.set_item("residual", col(&|p| p.residual))?;
    d.set_item("test_value", col(&|p| p.test_value))?;
    let iters: Vec<i64> = pts.iter().map(|p| p.newton_iters as i64).collect();
    d.set_item("newton_iterations", iters.into_pyarray(py))?;
    d.set_item("complete", matches!(f.curve.end, CurveEnd::Complete))?;
    let start = PyDict::new(py);
    start.set_item("step", plan.step.lo)?;
    start.set_item("free", f.bif.param)?;
    start.set_item("bracket", f.bif.param_bracket)?;
    d.set_item("start", start)?;
    d.set_item(
        "region_map",
        f.map.as_ref().map(|g| map_dict(py, g)).transpose()?,
    )?;
    Ok(d)
}

/// The region map: `step` (nx,), `free` (ny,), `region` (nx, ny) codes, `legend`.
fn map_dict<'py>(py: Python<'py>, g: &pdw::follow::RegionGrid) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("step", g.step.clone().into_pyarray(py))?;
    d.set_item("free", g.free.clone().into_pyarray(py))?;
    let codes: Vec<u8> = g.region.iter().flatten().map(|r| r.code()).collect();
    let a = Array2::from_shape_vec((g.step.len(), g.free.len()), codes).map_err(err)?;
    d.set_item("region", a.into_pyarray(py))?;
    let legend = PyDict::new(py);
    for r in Region::ALL {
        legend.set_item(r.code(), r.name())?;
    }
    d.set_item("legend", legend)?;
    Ok(d)
}
