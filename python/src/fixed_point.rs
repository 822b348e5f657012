//! `fixed_point` and `gaits`: the gaits of `pdw-sweep fixedpoint` (period one, with or without
//! a guess, and period K) and of `fixedpoint --search`, as dicts ([`pdw::gaits`]).

use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert::{complex_array, rows_to_array, validity_dict};
use crate::errors::{err, no_gait_error};
use crate::linear;
use crate::{build_kw, interruptible, Model, THREADS};
use pdw::limit::gaits::{self, Found};
use pdw::limit::trajectory::Validity;

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

/// `fixed_point(model, slope=None, period=1, gait="all", tol=1e-12, guess=None,
/// jacobian=False, **params)`; with `jacobian=True` (period one) each gait also carries its
/// linear stability data ([`linear::set_linear`]).
#[pyfunction]
#[pyo3(
    signature = (model="simplest", slope=None, period=1, gait="all", tol=1e-12, guess=None, jacobian=false, **params),
    text_signature = "(model='simplest', slope=None, period=1, gait='all', tol=1e-12, guess=None, jacobian=False, **params)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn fixed_point<'py>(
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
pub(crate) fn check_gait_and_tol(gait: &str, tol: f64) -> PyResult<()> {
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
pub(crate) fn scan_gaits<'py>(
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
