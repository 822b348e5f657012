//! A design search ([`pdw_limit::design`]): free parameters of a chain walker searched, within
//! their bounds, for the most robust (or most stable) passive gait that is physically valid
//! along the whole stride. The plan ([`DesignPlan`]) holds the model, the free parameters and
//! the search's options; [`settings`] is what a stored search is continued by; [`search`]
//! runs it, every design built from the plan's model with the free values on top.

use crate::model::{build_with, BuiltModel, ModelChoice};
use pdw_limit::design::{evaluate_design, DesignEval, DesignOptions, DesignSpace};
use pdw_limit::LimitError;

/// A checked design search.
pub struct DesignPlan {
    /// The model and its fixed overrides (no free parameter among them).
    pub model: ModelChoice,
    /// The free parameters and their bounds.
    pub space: DesignSpace,
    pub options: DesignOptions,
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
        "basin_grid": o.basin_grid,
        "basin_box": o.basin_box,
        "max_strides": o.basin.max_strides,
        "newton_tol": o.newton_tol,
        "model_resolved": base.walker.fingerprint(),
    })
    .to_string()
}

/// Runs the search from `history` (designs already evaluated, replayed without evaluation)
/// on `pool`, the gaits of `base` (the model's own values) as the first guesses. `on_eval` sees
/// every newly evaluated design in order; a design whose values make no model is recorded as
/// such. Returns every design, the history's first.
pub fn search(
    plan: &DesignPlan,
    base: &BuiltModel,
    history: Vec<DesignEval>,
    pool: &rayon::ThreadPool,
    on_eval: &mut dyn FnMut(&DesignEval),
) -> Result<Vec<DesignEval>, LimitError> {
    let guesses = pdw_limit::gaits::model_guesses(base.walker.as_ref());
    let names = &plan.space.names;
    let mut eval = |p: &[f64], g: &[(String, Vec<f64>)]| -> DesignEval {
        let set: Vec<(String, f64)> = names.iter().cloned().zip(p.iter().copied()).collect();
        let ev = match build_with(&plan.model, &set) {
            Ok(m) => evaluate_design(p, m.walker.as_ref(), g, &plan.options, pool),
            Err(e) => DesignEval::bad_model(p, e.0),
        };
        on_eval(&ev);
        ev
    };
    pdw_limit::design::search(&plan.space, &plan.options, &guesses, history, &mut eval)
}
