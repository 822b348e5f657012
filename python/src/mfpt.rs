//! `mfpt`: the mean first-passage time on random terrain by Monte Carlo, its curve over
//! standard deviations, and the Markov chain beside it, as `pdw-sweep mfpt` ([`pdw::mfpt`]).

use numpy::ndarray::Array2;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::err;
use crate::{build_kw, interruptible, Model};

/// The names of `mfpt`'s keyword arguments in its messages.
pub(crate) const MFPT_FLAGS: pdw::mfpt::MfptFlags = pdw::mfpt::MfptFlags {
    terrain: "terrain",
    sd: "sd",
    mean: "slope",
    walkers: "walkers",
    max_steps: "max_strides",
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
    (walkers, max_strides, seed, threads): (usize, usize, u64, usize),
    stride_map: pdw::mfpt::StrideMap,
) -> PyResult<Bound<'py, PyDict>> {
    pdw::input::check_threads(threads, "threads").map_err(err)?;
    pdw::mfpt::check_model_for(m, kind).map_err(err)?;
    let plan = |sd: f64| {
        mfpt_plan(
            m,
            (kind, dist),
            sd,
            (walkers, max_strides, seed),
            stride_map,
        )
    };
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
    (walkers, max_strides, seed): (usize, usize, u64),
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
        max_strides,
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

/// `mfpt(model="simplest", slope=None, sd=..., walkers=1000, max_strides=1000, seed=0,
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
    signature = (model="simplest", slope=None, sd=None, walkers=1000, max_strides=1000, seed=0, threads=2, terrain="slope", chain=false, mesh=None, nodes=None, dist="normal", chain_section="landing", chain_mesh="grid", stride_map="auto", max_steps=None, **params),
    text_signature = "(model='simplest', slope=None, sd=None, walkers=1000, max_strides=1000, seed=0, threads=2, terrain='slope', chain=False, mesh=None, nodes=None, dist='normal', chain_section='landing', chain_mesh='grid', stride_map='auto', max_steps=None, **params)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn mfpt<'py>(
    py: Python<'py>,
    model: &str,
    slope: Option<&Bound<'py, PyAny>>,
    sd: Option<&Bound<'py, PyAny>>,
    walkers: usize,
    max_strides: usize,
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
    max_steps: Option<usize>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    pdw::input::check_threads(threads, "threads").map_err(err)?;
    let max_strides =
        crate::old_spelling(max_strides, 1000, max_steps, "max_strides", "max_steps")?;
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
            (walkers, max_strides, seed, threads),
            stride_map,
        );
    }
    pdw::mfpt::check_model_for(&m, kind).map_err(err)?;
    let plan = mfpt_plan(
        &m,
        (kind, &dist),
        sds[0],
        (walkers, max_strides, seed),
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
/// `out_of_mesh`, `states`), `refinement_change`, `warning` (None when converged), on a grid the
/// coarse mesh's chain with twice the terrain's nodes (`quadrature_nodes`, `quadrature_mfpt`,
/// `quadrature_change`, `quadrature_warning`: None when the quadrature is converged; all None on
/// a cloud),
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
    // the coarse mesh with twice the terrain's nodes (on a grid; None on a cloud)
    let q = pair.quadrature.as_ref();
    d.set_item("quadrature_nodes", q.map(|q| q.nodes))?;
    d.set_item("quadrature_mfpt", q.map(|q| q.mfpt))?;
    d.set_item("quadrature_change", q.map(|q| q.change))?;
    d.set_item("quadrature_warning", q.and_then(|q| q.warning.clone()))?;
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
