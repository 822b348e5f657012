//! A design search ([`pdw_limit::design`]): free parameters of a chain walker searched, within
//! their bounds, for the most robust (or most stable) passive gait that is physically valid
//! along the whole stride. Any parameter of the walker's spec (its `[parameters]` table:
//! segment lengths, masses, centres of mass along and normal to a segment, inertias, foot
//! radius, hip mass, slope, knee hardware limits) may be free; the search is the library's
//! multi-start ([`pdw_limit::design::search_multi`]) on the caller's pool. The plan ([`DesignPlan`]) holds the model, the free parameters and
//! the search's options; [`settings`] is what a stored search is continued by; [`search`]
//! runs it, every design built from the plan's model with the free values on top. The checks
//! of a front end's values ([`check_model`], [`space`], [`check_mu`] and the others) name the
//! front end's flag in their messages.

use crate::input::{AxisRange, InputError};
use crate::model::{build_with, BuiltModel, ModelChoice};
use pdw_limit::design::{
    evaluate_design, status, DesignEval, DesignOptions, DesignSpace, Objective,
};
use pdw_limit::LimitError;
use pdw_store::DesignData;

/// A checked design search.
pub struct DesignPlan {
    /// The model and its fixed overrides (no free parameter among them).
    pub model: ModelChoice,
    /// The free parameters and their bounds.
    pub space: DesignSpace,
    pub options: DesignOptions,
    /// Local runs of the multi-start ([`pdw_limit::design::search_multi`]; at least 1).
    pub starts: usize,
}

/// The search's settings as one JSON text: the model (name, fixed values, the resolved walker
/// of `base`), the free parameters with bounds and every option that changes which designs are
/// evaluated or how they score. A stored search continues only under the same text.
pub fn settings(plan: &DesignPlan, base: &BuiltModel) -> String {
    let (o, s) = (&plan.options, &plan.space);
    let free: Vec<serde_json::Value> = s
        .names
        .iter()
        .zip(&s.lo)
        .zip(&s.hi)
        .map(|((n, l), h)| serde_json::json!([n, l, h]))
        .collect();
    serde_json::json!({
        "model": plan.model.model,
        "fixed": base.params_json(),
        "free": free,
        "objective": o.objective.name(),
        "mu": o.mu,
        "knee_margin": o.knee_margin,
        "min_margin": o.min_margin,
        "seed": o.seed,
        "init": o.init,
        "starts": plan.starts,
        "basin_grid": o.basin_grid,
        "basin_box": o.basin_box,
        "max_strides": o.basin.max_strides,
        "newton_tol": o.newton_tol,
        "model_resolved": base.walker.fingerprint(),
    })
    .to_string()
}

/// The options a design file's provenance records: the search's `settings` and the worker
/// `threads`.
pub fn run_options(settings: &str, threads: usize) -> serde_json::Value {
    let mut options: serde_json::Value = serde_json::from_str(settings).unwrap_or_default();
    if let Some(o) = options.as_object_mut() {
        o.insert("threads".into(), serde_json::json!(threads));
    }
    options
}

/// Runs the search from `history` (designs already evaluated, replayed without evaluation)
/// on `pool`, the gaits of `base` (the model's own values) as the first guesses. `on_eval` sees
/// every newly evaluated design (one at a time; with several starts in the order the pool's
/// threads finish them); a design whose values make no model is recorded as such. Returns
/// every design, run by run, each run's in its evaluation order (the same on any number of
/// threads).
pub fn search(
    plan: &DesignPlan,
    base: &BuiltModel,
    history: Vec<DesignEval>,
    pool: &rayon::ThreadPool,
    on_eval: &mut (dyn FnMut(&DesignEval) + Send),
) -> Result<Vec<DesignEval>, LimitError> {
    let guesses = pdw_limit::gaits::model_guesses(base.walker.as_ref());
    let on_eval = std::sync::Mutex::new(on_eval);
    let eval = |run: u32, p: &[f64], g: &[(String, Vec<f64>)]| -> DesignEval {
        let mut ev = evaluate(plan, p, g, pool);
        ev.run = run;
        if let Ok(mut f) = on_eval.lock() {
            (*f)(&ev);
        }
        ev
    };
    pdw_limit::design::search_multi(
        &plan.space,
        &plan.options,
        plan.starts,
        &guesses,
        history,
        &eval,
        pool,
    )
}

/// Evaluates design `p` (values of the free parameters) of `plan` from guesses `g`
/// ([`evaluate_design`]). A design without a gait whose knees are held by stops is graded by
/// its latched twin ([`crate::model::build_latched_twin`]: the same walker with ideal latches):
/// where the twin walks, the design costs what the twin's gait costs, whose shortfall counts
/// what the latches pull — exactly what the stops cannot do — so the search climbs towards
/// designs whose stops need to pull less, and reaches the stop-only gait where the pull falls
/// to zero (there the stops hold and the two walkers walk alike). The design keeps its status
/// (`no gait`), and its reason says what the twin found.
pub fn evaluate(
    plan: &DesignPlan,
    p: &[f64],
    g: &[(String, Vec<f64>)],
    pool: &rayon::ThreadPool,
) -> DesignEval {
    let set: Vec<(String, f64)> = plan
        .space
        .names
        .iter()
        .cloned()
        .zip(p.iter().copied())
        .collect();
    let mut ev = match build_with(&plan.model, &set) {
        Ok(m) => evaluate_design(p, m.walker.as_ref(), g, &plan.options, pool),
        Err(e) => return DesignEval::bad_model(p, e.0),
    };
    if ev.status != status::NO_GAIT {
        return ev;
    }
    if let Ok(Some(twin)) = crate::model::build_latched_twin(&plan.model, &set) {
        // the twin's section has no `swing_knee_rate` (a latched trailing knee is never
        // released): the guesses' first coordinates (the rate is 0 where a stop held)
        let dim = twin.walker.section_dim();
        let g_twin: Vec<(String, Vec<f64>)> = g
            .iter()
            .map(|(n, s)| (n.clone(), s[..s.len().min(dim)].to_vec()))
            .collect();
        let tw = evaluate_design(p, twin.walker.as_ref(), &g_twin, &plan.options, pool);
        if matches!(
            tw.status,
            status::FEASIBLE | status::INVALID | status::UNSTABLE
        ) {
            // a feasible twin (its latches never pull) costs as a gait at the margin
            let cost = if tw.status == status::FEASIBLE {
                pdw_limit::design::graded_cost(pdw_limit::design::Grade::Gait {
                    rho: tw.rho,
                    d: 0.0,
                })
            } else {
                tw.cost
            };
            ev.cost = cost;
            ev.reason = format!(
                "{}; with ideal latches for its stops: {} (max |λ| = {:.4}{})",
                ev.reason,
                status::NAMES[tw.status as usize].replace('_', " "),
                tw.rho,
                if tw.reason.is_empty() {
                    String::new()
                } else {
                    format!("; {}", tw.reason)
                }
            );
        }
    }
    ev
}

/// The number of local runs: 1 to 10000.
pub fn check_starts(n: i64, flag: &str) -> Result<usize, InputError> {
    check_count(n, flag, " starts", (1, 10_000)).map(|n| n as usize)
}

/// The closest design of `hist` (the smallest cost) and, when nothing is feasible, what keeps
/// it from being feasible in words: its binding criterion with its relative margin, or without
/// a gait how its guesses ended.
pub fn closest(hist: &[DesignEval], min_margin: f64) -> Option<(&DesignEval, Option<String>)> {
    let b = hist.iter().min_by(|x, y| x.cost.total_cmp(&y.cost))?;
    if b.feasible() {
        return Some((b, None));
    }
    let why = if !b.binding.is_empty() && b.min_relative_margin.is_finite() {
        format!(
            "binding criterion {} at relative margin {:.4} (required {min_margin}); shortfall {:.4}",
            b.binding, b.min_relative_margin, b.shortfall
        )
    } else if !b.fates.is_empty() {
        let twin = b
            .reason
            .find("with ideal latches")
            .map_or(String::new(), |i| format!("; {}", &b.reason[i..]));
        format!(
            "no gait; the best guess walked {} of {} strides (smallest stride-to-stride change \
             {:.3e}); {}{twin}",
            b.strides_survived,
            pdw_limit::design::PROBE_STRIDES,
            b.probe_residual,
            b.fates
        )
    } else {
        b.reason.clone()
    };
    Some((b, Some(why)))
}

/// The design's model must be a chain walker (the search varies a walker spec's parameters);
/// `flag` names the model in the message.
pub fn check_model(base: &BuiltModel, flag: &str) -> Result<(), InputError> {
    if base.info.spec().is_none() {
        return Err(InputError(format!(
            "{flag}: '{}' is not a chain walker (section of {} coordinates); design searches \
             run on walker specs (compass, kneed, seed5 or a .toml file)",
            base.info.name,
            base.info.section_names.len()
        )));
    }
    Ok(())
}

/// The free parameters `free` (`NAME=LO:HI` each, `flag` naming them): each a parameter of the
/// model `base` (built from `model`), given once, not also set by `model`'s overrides, both
/// bounds making a model; at least one.
pub fn space(
    model: &ModelChoice,
    base: &BuiltModel,
    free: &[String],
    flag: &str,
) -> Result<DesignSpace, InputError> {
    let set_names: Vec<String> = crate::model::overrides(model)?
        .into_iter()
        .map(|p| p.0)
        .collect();
    let mut space = DesignSpace {
        names: Vec::new(),
        lo: Vec::new(),
        hi: Vec::new(),
    };
    for f in free {
        let r = free_parameter(model, base, (&space.names[..], &set_names[..]), f, flag)?;
        space.names.push(r.name);
        space.lo.push(r.lo);
        space.hi.push(r.hi);
    }
    if space.names.is_empty() {
        return Err(InputError(format!("{flag}: give at least one NAME=LO:HI")));
    }
    Ok(space)
}

/// One free parameter `f` (`NAME=LO:HI`), checked against the model, the free parameters
/// before it and the parameters set.
fn free_parameter(
    model: &ModelChoice,
    base: &BuiltModel,
    (names, set_names): (&[String], &[String]),
    f: &str,
    flag: &str,
) -> Result<AxisRange, InputError> {
    let r = crate::input::parse_axis(f, flag)?;
    if !base.params.iter().any(|p| p.0 == r.name) {
        return Err(InputError(format!(
            "{flag}: '{}' is not a parameter of model '{}' (parameters: {})",
            r.name,
            base.info.name,
            base.params
                .iter()
                .map(|p| p.0.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    if names.contains(&r.name) {
        return Err(InputError(format!("{flag}: '{}' is given twice", r.name)));
    }
    if set_names.contains(&r.name) {
        return Err(InputError(format!(
            "{flag}: '{}' is also fixed by --set/--slope; a parameter is either free or set",
            r.name
        )));
    }
    // both bounds must make a model (checked once, here)
    for v in [r.lo, r.hi] {
        build_with(model, &[(r.name.clone(), v)]).map_err(|e| {
            InputError(format!(
                "{flag} {f}: the bound {v} does not make a model: {e}"
            ))
        })?;
    }
    Ok(r)
}

/// The model's own values of the free parameters: where the search starts.
pub fn start(base: &BuiltModel, space: &DesignSpace) -> Vec<f64> {
    space
        .names
        .iter()
        .map(|n| {
            base.params
                .iter()
                .find(|p| p.0 == *n)
                .map_or(f64::NAN, |p| p.1)
        })
        .collect()
}

/// The search's objective by name: `basin` or `margin`.
pub fn parse_objective(s: &str, flag: &str) -> Result<Objective, InputError> {
    match s {
        "basin" => Ok(Objective::Basin),
        "margin" => Ok(Objective::Margin),
        o => Err(InputError(format!(
            "{flag}: '{o}' is not one of basin, margin"
        ))),
    }
}

/// The largest friction coefficient: finite and > 0.
pub fn check_mu(mu: f64, flag: &str) -> Result<f64, InputError> {
    if mu.is_finite() && mu > 0.0 {
        Ok(mu)
    } else {
        Err(InputError(format!(
            "{flag}: {mu} is not a friction coefficient; give a finite value > 0 (e.g. 0.6)"
        )))
    }
}

/// The smallest knee-lock torque: finite and ≥ 0.
pub fn check_knee_margin(k: f64, flag: &str) -> Result<f64, InputError> {
    if k.is_finite() && k >= 0.0 {
        Ok(k)
    } else {
        Err(InputError(format!(
            "{flag}: {k} N m is not allowed; give a finite torque >= 0"
        )))
    }
}

/// The smallest relative margin: finite and ≥ 0.
pub fn check_min_margin(m: f64, flag: &str) -> Result<f64, InputError> {
    if m.is_finite() && m >= 0.0 {
        Ok(m)
    } else {
        Err(InputError(format!(
            "{flag}: {m} is not allowed; give a finite relative margin >= 0 (e.g. 0.05)"
        )))
    }
}

/// An integer count in `lo..=hi`; `what` follows the value in the message (e.g. ` designs`).
pub fn check_count(
    n: i64,
    flag: &str,
    what: &str,
    (lo, hi): (i64, i64),
) -> Result<i64, InputError> {
    if (lo..=hi).contains(&n) {
        Ok(n)
    } else {
        Err(InputError(format!(
            "{flag}: {n}{what} is outside {lo}..={hi}"
        )))
    }
}

/// Designs evaluated in all: 1 to 100000.
pub fn check_budget(n: i64, flag: &str) -> Result<usize, InputError> {
    check_count(n, flag, " designs", (1, 100_000)).map(|n| n as usize)
}

/// Basin cells per side: 1 to 200.
pub fn check_basin_grid(n: i64, flag: &str) -> Result<usize, InputError> {
    check_count(n, flag, " cells per side", (1, 200)).map(|n| n as usize)
}

/// Strides per basin cell of a design: 1 to 10000.
pub fn check_max_strides(n: i64, flag: &str) -> Result<u16, InputError> {
    check_count(n, flag, "", (1, 10_000)).map(|n| n as u16)
}

/// The basin box's half widths `DSTANCE,DSTANCE_RATE`: two positive values (`given` as typed).
/// Without them the box scales with each design's gait ([`pdw_limit::design::basin_box`]).
pub fn check_basin_box(v: &[f64], given: &str, flag: &str) -> Result<[f64; 2], InputError> {
    match v[..] {
        [a, b] if [a, b].iter().all(|x| x.is_finite() && *x > 0.0) => Ok([a, b]),
        _ => Err(InputError(format!(
            "{flag}: '{given}' must be two positive half widths DSTANCE,DSTANCE_RATE (e.g. \
             0.05,0.2)"
        ))),
    }
}

/// Share of a free parameter's range within which a best design counts as on its bound.
pub const ON_BOUND: f64 = 0.01;

/// Warnings for a best design `best` (values in `space`'s order) that sits on a bound of its
/// search box — within [`ON_BOUND`] of the range from it: the optimum may lie beyond, and the
/// range should be widened there (a bounded search reports the best *inside* the box, which is
/// not a stationary point of the objective when it is on a face of it).
pub fn bound_warnings(space: &DesignSpace, best: &[f64]) -> Vec<String> {
    let mut out = Vec::new();
    for (i, name) in space.names.iter().enumerate() {
        let (lo, hi, v) = (space.lo[i], space.hi[i], best[i]);
        let tol = ON_BOUND * (hi - lo).abs();
        let side = if (v - lo).abs() <= tol {
            Some(("lower", lo))
        } else if (hi - v).abs() <= tol {
            Some(("upper", hi))
        } else {
            None
        };
        if let Some((which, b)) = side {
            out.push(format!(
                "the best design has {name} = {v} at the {which} bound {b} of its range \
                 {lo}:{hi}; the optimum may lie beyond it — widen the range there"
            ));
        }
    }
    out
}

/// Per-design measures as the design file stores them (columns, in this order) and Python
/// returns them; `basin_box_*` are the half widths of the box each basin fraction was measured
/// in ([`pdw_limit::design::basin_box`]).
pub const COLUMNS: [&str; 15] = [
    "cost",
    "basin_fraction",
    "rho",
    "min_normal_force",
    "max_friction",
    "min_knee_torque",
    "period",
    "step_length",
    "min_relative_margin",
    "basin_box_stance",
    "basin_box_stance_rate",
    "shortfall",
    "strides_survived",
    "probe_residual",
    "run",
];

/// The measures of `e` in [`COLUMNS`]' order.
pub fn measures(e: &DesignEval) -> [f64; 15] {
    [
        e.cost,
        e.basin_fraction,
        e.rho,
        e.min_normal_force,
        e.max_friction,
        e.min_knee_torque,
        e.period,
        e.step_length,
        e.min_relative_margin,
        e.basin_box[0],
        e.basin_box[1],
        e.shortfall,
        e.strides_survived,
        e.probe_residual,
        f64::from(e.run),
    ]
}

/// The design file's contents: the search's `settings`, the free parameters' `names` and every
/// design of `hist`.
pub fn to_data(settings: &str, names: &[String], hist: &[DesignEval]) -> DesignData {
    DesignData {
        settings: settings.to_string(),
        free_names: names.to_vec(),
        status_names: status::NAMES.iter().map(|s| s.to_string()).collect(),
        params: hist.iter().map(|e| e.params.clone()).collect(),
        status: hist.iter().map(|e| e.status).collect(),
        reasons: hist.iter().map(|e| e.reason.clone()).collect(),
        bindings: hist.iter().map(|e| e.binding.clone()).collect(),
        fates: hist.iter().map(|e| e.fates.clone()).collect(),
        section: hist.iter().map(|e| e.section).collect(),
        columns: COLUMNS
            .iter()
            .enumerate()
            .map(|(i, c)| (c.to_string(), hist.iter().map(|e| measures(e)[i]).collect()))
            .collect(),
    }
}

/// The designs of a design file (a column the file lacks reads NaN).
pub fn from_data(d: &DesignData) -> Vec<DesignEval> {
    (0..d.params.len())
        .map(|i| {
            let c = |name: &str| d.column(name).map_or(f64::NAN, |v| v[i]);
            DesignEval {
                params: d.params[i].clone(),
                status: d.status[i],
                reason: d.reasons[i].clone(),
                cost: c("cost"),
                basin_fraction: c("basin_fraction"),
                rho: c("rho"),
                section: d.section[i],
                min_normal_force: c("min_normal_force"),
                max_friction: c("max_friction"),
                min_knee_torque: c("min_knee_torque"),
                period: c("period"),
                step_length: c("step_length"),
                min_relative_margin: c("min_relative_margin"),
                basin_box: [c("basin_box_stance"), c("basin_box_stance_rate")],
                binding: d.bindings.get(i).cloned().unwrap_or_default(),
                shortfall: c("shortfall"),
                strides_survived: c("strides_survived"),
                probe_residual: c("probe_residual"),
                fates: d.fates.get(i).cloned().unwrap_or_default(),
                run: {
                    let r = c("run");
                    if r.is_finite() && r >= 0.0 {
                        r as u32
                    } else {
                        0
                    }
                },
            }
        })
        .collect()
}

/// The units of the design file's datasets ([`pdw_store::format::DESIGN`]'s rules) for the
/// model `base` and the free parameters `names`.
pub fn units(base: &BuiltModel, names: &[String]) -> pdw_store::format::UnitContext {
    pdw_store::format::UnitContext {
        free_parameters: names
            .iter()
            .map(|n| crate::model::param_unit(base, n))
            .collect(),
        ..crate::model::unit_context(base)
    }
}

/// Writes the design file `path` (replacing it): every design of `hist` under the search's
/// `settings` ([`settings`]), with units and the provenance `prov`; `earlier` are the command
/// lines of the runs that wrote the search before.
pub fn write_file(
    path: &std::path::Path,
    (plan, base, settings): (&DesignPlan, &BuiltModel, &str),
    hist: &[DesignEval],
    prov: &pdw_store::Provenance,
    earlier: &[String],
) -> Result<(), pdw_store::StoreError> {
    let units = units(base, &plan.space.names);
    let coordinates = base.coordinates_json();
    let ann = pdw_store::Annotations {
        provenance: Some(prov),
        units: &pdw_store::format::DESIGN.units(&units),
        slice: None,
        scales: &[],
        coordinates: Some(&coordinates),
    };
    let d = to_data(settings, &plan.space.names, hist);
    pdw_store::write_design_annotated(path, &d, Some(&ann), earlier)
}
