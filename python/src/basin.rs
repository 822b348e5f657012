//! `basin`: every cell of a grid labelled by the attractor it reaches, as `pdw-sweep basin`
//! computes it ([`pdw::basin`]), held whole in memory (checked against the memory available
//! first).

use numpy::ndarray::Array2;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert::{attractor_dict, complex_array, coordinates_dict};
use crate::errors::err;
use crate::{build_kw, interruptible, Model, THREADS};
use pdw::basin::{BasinPlan, BasinRequest};
use pdw::limit::basin::{self as lbasin, BasinOptions, Outcome};
use pdw::limit::AttractorSet;

fn gib(b: u64) -> String {
    format!("{:.1} GiB", b as f64 / (1u64 << 30) as f64)
}

/// Refuses a basin grid held whole in memory (cells, results, the outcome array) that would
/// need more than 80 % of the memory available, naming the estimate.
pub(crate) fn check_basin_memory(grid: &[usize], d: usize) -> PyResult<()> {
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
pub(crate) fn basin<'py>(
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
pub(crate) type GivenAxis = Option<(String, f64, f64)>;

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
