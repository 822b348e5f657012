//! Basin stability over a model parameter (Menck, Heitzig, Marwan & Kurths, "How basin
//! stability complements the linear-stability paradigm", Nature Physics 9, 89–92, 2013), as
//! both front ends run it (the CLI's `basin --over NAME=A:B:N`, Python's `basin_over`): at
//! each of N evenly spaced values of the parameter, the fraction of one fixed box of section
//! states that reaches each attractor, falls, or neither.
//!
//! Every value is classified exactly as a plain basin on the same box is ([`crate::basin`]: the
//! gait search, the attractor discovery, the engine and its options), so the fractions at a
//! value equal that basin's. The box is the same at every value: the axes given, else the
//! default box of a basin around the gait at A. The steps are [`check_over`], [`plan`] (a model
//! per value and the box), [`at_value`] for every value, then [`columns`] and
//! [`fraction_table`] over the results.

use crate::basin::{AxisFlags, BasinBox, BasinPlan, BasinRequest, SlowAttractor};
use crate::input::{InputError, Sweep};
use crate::model::BuiltModel;
use pdw_limit::basin::{classify_cells, CellResult, Outcome};
use pdw_limit::{Attractor, AttractorSet, LimitError};
use pdw_walkers::ModelInfo;

/// Why a plan could not be made: a bad input, or the gait search at A failed.
#[derive(Debug)]
pub enum OverError {
    Input(InputError),
    Limit(LimitError),
}

impl std::fmt::Display for OverError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OverError::Input(e) => e.fmt(f),
            OverError::Limit(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for OverError {}

impl From<InputError> for OverError {
    fn from(e: InputError) -> Self {
        OverError::Input(e)
    }
}

impl From<LimitError> for OverError {
    fn from(e: LimitError) -> Self {
        OverError::Limit(e)
    }
}

/// The parameter varied, checked: one of the model's, and not also among `params` (it would be
/// set twice). `flag` names it in the message (`--over`, `over`).
pub fn check_over(
    info: &ModelInfo,
    params: &[(String, f64)],
    over: &Sweep,
    flag: &str,
) -> Result<(), InputError> {
    if let Some((_, v)) = params.iter().find(|(n, _)| *n == over.name) {
        return Err(InputError(format!(
            "{flag} {}: the parameter is also set to {v} (--slope or --set); give it once",
            over.name
        )));
    }
    if !info.params.iter().any(|p| p.name == over.name) {
        return Err(InputError(format!(
            "{flag}: model '{}' has no parameter '{}'; its parameters are {}",
            info.name,
            over.name,
            info.params
                .iter()
                .map(|p| p.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    Ok(())
}

/// The models and the box every value is classified on.
pub struct OverPlan {
    pub values: Vec<f64>,
    /// The model at each value.
    pub models: Vec<BuiltModel>,
    pub req: BasinRequest,
    pub bx: BasinBox,
    /// The box's centre (the gait at A): the state off the axes at a value without a gait.
    pub centre_a: Vec<f64>,
    /// Where the box comes from, in words.
    pub box_source: String,
}

/// The model at every value of `over` (`model` with `params` and the value on top; a bad value
/// is refused before anything is computed) and the box: the axes of `req`, else the default box
/// of a basin around the gait at A, for every value. `flags` name the axes, `flag` the range.
pub fn plan(
    model: &str,
    params: &[(String, f64)],
    over: &Sweep,
    req: BasinRequest,
    flags: AxisFlags,
    flag: &str,
) -> Result<OverPlan, OverError> {
    let values = pdw_limit::basin::linspace(over.lo, over.hi, over.n);
    let models: Vec<BuiltModel> = values
        .iter()
        .map(|&mu| {
            let mut sets = params.to_vec();
            sets.push((over.name.clone(), mu));
            crate::build(model, &sets)
        })
        .collect::<Result<_, _>>()?;
    let info = &models[0].info;
    let gaits_a = crate::basin::find_gaits(&models[0])?;
    let Some(centre_a) = crate::basin::grid_centre(&models[0], &gaits_a, req.axes_given()) else {
        return Err(InputError(format!(
            "{flag}: no period-one gait of model '{}' at {} = {} to centre the default \
             box on; give both {} and {}",
            info.name, over.name, over.lo, flags.x, flags.y
        ))
        .into());
    };
    let box_source = if req.axes_given() {
        format!("{} and {}", flags.x, flags.y)
    } else {
        format!(
            "the default basin box around the period-one gait at {} = {} (fixed for every \
             value)",
            over.name, over.lo
        )
    };
    let bx = crate::basin::choose_box(&req, &info.section_names, &centre_a, flags, "box")?;
    Ok(OverPlan {
        values,
        models,
        req,
        bx,
        centre_a,
        box_source,
    })
}

/// One parameter value's result.
pub struct AtValue {
    /// `(column, kind, fraction)` in the order met; kind is `attractor`, `fall`, `timeout` or
    /// `other`.
    pub fractions: Vec<(String, &'static str, f64)>,
    /// Fractions of the fixed outcome codes ([`Outcome::CELL_ENDS`], before attractors are told
    /// apart).
    pub outcomes: Vec<f64>,
    /// The attractors found at this value.
    pub attractors: Vec<Attractor>,
}

/// The box classified at value `i` of the plan: the coordinates off the box's axes at this
/// value's gait, as a basin takes them, and its own attractors. `slow` is told of every
/// attractor converging too slowly for the stride budget ([`crate::basin::slow_attractors`]),
/// `progress` of the cells done so far at this value.
pub fn at_value(
    plan: &OverPlan,
    i: usize,
    pool: &rayon::ThreadPool,
    slow: &mut dyn FnMut(&SlowAttractor<'_>),
    progress: &(dyn Fn(usize) + Sync),
) -> Result<AtValue, LimitError> {
    let m = &plan.models[i];
    let gaits = crate::basin::find_gaits(m)?;
    let centre = gaits
        .centre()
        .map_or_else(|| plan.centre_a.clone(), <[f64]>::to_vec);
    let vp = BasinPlan::new(&plan.req, plan.bx.clone(), gaits, centre);
    let (set, _) = vp.attractors(m, pool)?;
    for s in crate::basin::slow_attractors(&set, plan.req.max_strides) {
        slow(&s);
    }
    let fall = Outcome::of_fall;
    let problem = set.problem(m.walker.as_ref(), &fall);
    let res = classify_cells(&problem, &vp.cells(&vp.ys), &vp.opts, pool, progress)?;
    Ok(tally(res, &set))
}

/// The column an outcome code counts in: an attractor's name (the gait, codes ≥ 10), `fall`
/// (every fall kind), `timeout`, or `other` (an orbit no attractor of the set explains, a
/// non-finite state, an integrator failure).
fn column_of(code: u8, set: &AttractorSet) -> (String, &'static str) {
    if let Some(a) = set.attractors.iter().find(|a| a.code == code) {
        return (a.name.clone(), "attractor");
    }
    match Outcome::from_code(code) {
        Some(o) if o.is_fall() => ("fall".into(), "fall"),
        Some(Outcome::Timeout) => ("timeout".into(), "timeout"),
        _ => ("other".into(), "other"),
    }
}

/// The fractions of the cells `res` by outcome code, then by column (count / n, as a basin's
/// metrics compute them), and the attractors of `set`.
fn tally(mut res: Vec<CellResult>, set: &AttractorSet) -> AtValue {
    let n = res.len() as f64;
    let counts = |res: &[CellResult]| {
        let mut counts = [0usize; 256];
        for c in res {
            counts[c.outcome as usize] += 1;
        }
        counts
    };
    let by_code = counts(&res);
    let outcomes: Vec<f64> = Outcome::CELL_ENDS
        .iter()
        .map(|o| by_code[o.code() as usize] as f64 / n)
        .collect();
    set.relabel(&mut res);
    let mut fractions: Vec<(String, &'static str, usize)> = set
        .attractors
        .iter()
        .map(|at| (at.name.clone(), "attractor", 0))
        .collect();
    for (code, &k) in counts(&res).iter().enumerate().filter(|(_, k)| **k > 0) {
        let (name, kind) = column_of(code as u8, set);
        match fractions.iter_mut().find(|(n, _, _)| *n == name) {
            Some(e) => e.2 += k,
            None => fractions.push((name, kind, k)),
        }
    }
    AtValue {
        fractions: fractions
            .into_iter()
            .map(|(name, kind, k)| (name, kind, k as f64 / n))
            .collect(),
        outcomes,
        attractors: set.attractors.clone(),
    }
}

/// The columns of the table: every attractor met (in order met), then fall, timeout, other.
pub fn columns(results: &[AtValue]) -> Vec<(String, &'static str)> {
    let mut columns: Vec<(String, &'static str)> = Vec::new();
    for r in results {
        for (name, kind, _) in r.fractions.iter().filter(|c| c.1 == "attractor") {
            if !columns.iter().any(|(n, _)| n == name) {
                columns.push((name.clone(), kind));
            }
        }
    }
    for (n, k) in [("fall", "fall"), ("timeout", "timeout"), ("other", "other")] {
        columns.push((n.into(), k));
    }
    columns
}

/// Every value's fraction in every column (0 where a column was not met).
pub fn fraction_table(results: &[AtValue], columns: &[(String, &'static str)]) -> Vec<Vec<f64>> {
    results
        .iter()
        .map(|r| {
            columns
                .iter()
                .map(|(c, _)| {
                    r.fractions
                        .iter()
                        .find(|(n, _, _)| n == c)
                        .map_or(0.0, |f| f.2)
                })
                .collect()
        })
        .collect()
}
