//! A gait's physical validity as one JSON object — the `validity` of `fixedpoint --json`, of
//! Python's `fixed_point` and `continuation` dicts: the flags and extremes, the margins (raw
//! and relative to their natural scales), the binding criterion, the clearance under the
//! model's rule, the impacts and every violation with where it happens
//! ([`pdw_limit::validity`]). Written once: every front end serialises a validity through
//! [`validity_json`].

use pdw_limit::Validity;

/// A finite number as JSON, `null` otherwise (JSON has no NaN or infinity).
pub fn num(x: f64) -> serde_json::Value {
    if x.is_finite() {
        x.into()
    } else {
        serde_json::Value::Null
    }
}

/// One margin of [`Validity::margins`] as JSON.
pub fn margin_json(m: &pdw_limit::Margin) -> serde_json::Value {
    serde_json::json!({
        "name": m.name,
        "raw": num(m.raw),
        "scale": num(m.scale),
        "scale_name": m.scale_name,
        "relative": num(m.relative),
        "t": num(m.t),
    })
}

/// The name of a clearance rule in outputs.
pub fn clearance_rule_name(r: pdw_walkers::ClearanceRule) -> &'static str {
    match r {
        pdw_walkers::ClearanceRule::WholeSwing => "whole_swing",
        pdw_walkers::ClearanceRule::AfterMidStance => "after_mid_stance",
    }
}

/// The `validity` object of `fixedpoint --json`: the flags and extremes (the first seven keys,
/// now located on the dense solution), then the margins (raw and relative to their natural
/// scales), the binding criterion, the clearance under the model's rule, the impacts and every
/// violation with where it happens.
pub fn validity_json(v: &Validity) -> serde_json::Value {
    let binding = v.binding();
    let impacts: Vec<serde_json::Value> = v
        .impacts
        .iter()
        .map(|i| {
            serde_json::json!({
                "event": i.event,
                "t": num(i.t),
                "checked": i.report.is_some(),
                "friction_required": i.report.as_ref().map(|r| num(r.friction_required)),
                "energy_lost": i.report.as_ref().map(|r| num(r.energy_lost)),
                "min_margin": i.report.as_ref().and_then(|r| r.min_margin()).map(|(m, _)| num(m)),
                "entries": i.report.as_ref().map(|r| r.entries.iter().map(|e| serde_json::json!({
                    "name": e.name,
                    "kind": format!("{:?}", e.kind),
                    "unilateral": e.unilateral,
                    "active": e.active,
                    "impulse": num(e.impulse),
                    "rate_after": num(e.rate_after),
                    "margin": e.margin().map(num),
                })).collect::<Vec<_>>()),
            })
        })
        .collect();
    serde_json::json!({
        "valid": v.valid(),
        "min_normal_force": v.min_normal_force,
        "max_friction_required": v.max_friction_required,
        "min_knee_torque": v.min_knee_torque,
        "normal_force_negative": v.normal_force_negative,
        "knee_unlocks": v.knee_unlocks,
        "swing_foot_scuffs": v.swing_foot_scuffs,
        "impact_violation": v.impact_violation,
        "continuous": v.continuous,
        "fell": v.fell,
        "t_min_normal_force": num(v.t_min_normal_force),
        "t_max_friction_required": num(v.t_max_friction_required),
        "knee_torque": {"stance": v.knee_torque[0], "swing": v.knee_torque[1]},
        "clearance_rule": v.clearance_rule.map(clearance_rule_name),
        "min_clearance": v.min_clearance,
        "t_min_clearance": v.min_clearance.map(|_| num(v.t_min_clearance)),
        "scuff_depth": num(v.scuff_depth),
        "scuff_intervals": v.scuff_intervals.iter().map(|(a, b)| [num(*a), num(*b)]).collect::<Vec<_>>(),
        "t_mid_stance": v.t_mid_stance,
        "impact_friction_required": num(v.impact_friction_required),
        "impacts": impacts,
        "scales": v.scales.map(|s| serde_json::json!({"mass": s.mass, "length": s.length, "gravity": s.gravity})),
        "margins": v.margins.iter().map(margin_json).collect::<Vec<_>>(),
        "binding": binding.map(|m| m.name.clone()),
        "min_relative_margin": binding.map(|m| num(m.relative)),
        "violations": v.violations.iter().map(|x| serde_json::json!({
            "criterion": x.criterion,
            "t_start": num(x.t_start),
            "t_end": num(x.t_end),
            "worst": num(x.worst),
        })).collect::<Vec<_>>(),
    })
}
