//! `mfpt_over`: the MFPT and the gait sensitivity norm over a model parameter, as
//! `pdw-sweep mfpt --over PARAM=A:B:N` (Monte Carlo; [`pdw::mfpt_over`]), as numpy arrays.

use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::err;
use crate::interruptible;
use pdw::limit::gsn::Indicator;
use pdw::mfpt_over::{self as over, OverRow};

/// `mfpt_over(over, model="simplest", slope=None, sd=..., walkers=1000, max_strides=1000,
/// seed=0, threads=2, dist="normal", **params)`: at each value of `over` ("hip_mass=4:16:7")
/// the stable gait's MFPT (the same walkers and seed at every value) and GSN; values without a
/// stable gait have `stable` False and NaN. `dist`: the standardised draws' distribution, as
/// `mfpt`'s (`normal`, `uniform`, `file:PATH`).
#[pyfunction]
#[pyo3(
    signature = (over, model="simplest", slope=None, sd=None, walkers=1000, max_strides=1000, seed=0, threads=2, dist="normal", max_steps=None, **params),
    text_signature = "(over, model='simplest', slope=None, sd=None, walkers=1000, max_strides=1000, seed=0, threads=2, dist='normal', max_steps=None, **params)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn mfpt_over<'py>(
    py: Python<'py>,
    over: &str,
    model: &str,
    slope: Option<&Bound<'py, PyAny>>,
    sd: Option<&Bound<'py, PyAny>>,
    walkers: usize,
    max_strides: usize,
    seed: u64,
    threads: usize,
    dist: &str,
    max_steps: Option<usize>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    pdw::input::check_threads(threads, "threads").map_err(err)?;
    let max_strides =
        crate::old_spelling(max_strides, 1000, max_steps, "max_strides", "max_steps")?;
    let dist = pdw::mfpt::parse_dist(dist, &crate::mfpt::MFPT_FLAGS).map_err(err)?;
    let sw = pdw::input::parse_range_count(over, "over").map_err(err)?;
    let sd = match sd {
        None => {
            return Err(err(
                "sd: give the slope's standard deviation (rad, or '1deg')",
            ))
        }
        Some(v) => match v.extract::<f64>() {
            Ok(x) => pdw::mfpt::parse_sd(&x.to_string(), &crate::mfpt::MFPT_FLAGS),
            Err(_) => pdw::mfpt::parse_sd(&v.extract::<String>()?, &crate::mfpt::MFPT_FLAGS),
        }
        .map_err(err)?,
    };
    let ov = crate::overrides(crate::slope_arg(slope)?, params)?;
    let plan = pdw::mfpt::MfptPlan {
        terrain: pdw::limit::terrain::SlopeTerrain {
            mean: 0.0,
            sd,
            seed,
            kind: pdw::limit::terrain::TerrainKind::Slope,
            dist,
        },
        walkers,
        max_strides,
        integrator: pdw::mfpt::default_integrator(),
        stride_map: Default::default(),
    };
    let rows = interruptible(py, || -> PyResult<Vec<OverRow>> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(err)?;
        let mut rows = Vec::new();
        for v in over::values(&sw) {
            let m = over::model_with(model, &ov, &sw.name, v).map_err(err)?;
            let p = over::plan_at(&m, &plan, &crate::mfpt::MFPT_FLAGS).map_err(err)?;
            let (r, _) = over::row(&m, v, &p, &Indicator::DEFAULT, &pool, &|_| {}).map_err(err)?;
            rows.push(r);
        }
        Ok(rows)
    })?;
    let d = PyDict::new(py);
    let col = |f: &dyn Fn(&OverRow) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    let est = |f: &dyn Fn(&pdw::limit::terrain::MfptEstimate) -> f64| {
        col(&|r| r.est.as_ref().map_or(f64::NAN, f))
    };
    d.set_item("param", &sw.name)?;
    d.set_item("values", col(&|r| r.value).into_pyarray(py))?;
    d.set_item("mean", col(&|r| r.mean).into_pyarray(py))?;
    d.set_item("mfpt", est(&|e| e.mfpt).into_pyarray(py))?;
    d.set_item("stderr", est(&|e| e.stderr).into_pyarray(py))?;
    d.set_item("falls", est(&|e| e.falls as f64).into_pyarray(py))?;
    d.set_item("gsn", col(&|r| r.gsn).into_pyarray(py))?;
    d.set_item(
        "stable",
        rows.iter()
            .map(|r| r.gait.is_some())
            .collect::<Vec<bool>>()
            .into_pyarray(py),
    )?;
    let (g, mf) = (col(&|r| r.gsn), est(&|e| e.mfpt));
    d.set_item("spearman", over::spearman(&g, &mf))?;
    d.set_item("sd", sd)?;
    d.set_item("dist", pdw::mfpt::dist_words(&plan.terrain.dist))?;
    Ok(d)
}
