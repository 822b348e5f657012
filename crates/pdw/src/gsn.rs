//! The gait sensitivity norm of a model's gait (Hobbelen & Wisse, IEEE T-RO 23(6), 2007), written
//! once for `pdw-sweep fixedpoint --gsn` and Python's `gait_sensitivity`: the indicators by
//! name, the model on random slopes ([`crate::mfpt::model_at`]) and the norm of
//! [`pdw_limit::gsn`] (which documents the linear system, the derivatives and the Lyapunov
//! equation).

use crate::input::InputError;
use crate::mfpt::{check_model, model_at};
use crate::model::BuiltModel;
use pdw_hybrid::Options;
use pdw_limit::gsn::{self, Gsn, GsnError, Indicator, Linearisation};
use pdw_limit::terrain::SlopeWalk;

/// The integrator of the strides: the fixed-point search's (DOP853 at 1e-14), so that the
/// differences of [`pdw_limit::gsn`] resolve their `O(h⁴)` accuracy.
pub fn default_integrator() -> Options {
    pdw_limit::gaits::default_integrator(crate::mfpt::GAIT_TOL)
}

/// A comma-separated list of indicator names (`step-time,step-length`), each once, at least one.
pub fn parse_indicators(s: &str, flag: &str) -> Result<Vec<Indicator>, InputError> {
    let mut out: Vec<Indicator> = Vec::new();
    for part in s.split(',') {
        let i = Indicator::parse(part).ok_or_else(|| {
            let names: Vec<&str> = Indicator::ALL.iter().map(Indicator::name).collect();
            InputError(format!(
                "{flag}: '{}' is not one of {}",
                part.trim(),
                names.join(", ")
            ))
        })?;
        if out.contains(&i) {
            return Err(InputError(format!("{flag}: '{}' is named twice", i.name())));
        }
        out.push(i);
    }
    Ok(out)
}

/// The names of `ind`, in order.
pub fn names(ind: &[Indicator]) -> Vec<&'static str> {
    ind.iter().map(Indicator::name).collect()
}

/// The linearised terrain stride of `m` (built at its mean slope) at its gait `s` (section
/// coordinates), for `indicators`; a model that cannot walk on random slopes is refused.
pub fn linearise(
    m: &BuiltModel,
    s: &[f64],
    indicators: &[Indicator],
    integrator: Options,
) -> Result<Linearisation, GsnError> {
    check_model(m).map_err(|e| GsnError::Limit(model_error(m, e)))?;
    let at = model_at(m);
    let walk = SlopeWalk::new(&at, m.slope(), integrator)?;
    Ok(gsn::linearise(&walk, s, indicators, gsn::SLOPE_STEP)?)
}

fn model_error(m: &BuiltModel, e: InputError) -> pdw_limit::LimitError {
    pdw_limit::LimitError::Model {
        param: m.slope(),
        message: e.0,
    }
}

/// The gait sensitivity norm of `m`'s gait `s` and its linearisation.
pub fn gait_sensitivity(
    m: &BuiltModel,
    s: &[f64],
    indicators: &[Indicator],
    integrator: Options,
) -> Result<(Linearisation, Gsn), GsnError> {
    let lin = linearise(m, s, indicators, integrator)?;
    let g = gsn::gait_sensitivity(&lin)?;
    Ok((lin, g))
}

/// The `gsn` object of a JSON report: `norm`, `indicators` (name and norm each), `unstable`
/// and `message` when there is no finite norm, `spectral_radius`, `fd_error`.
pub fn json(
    indicators: &[Indicator],
    result: &Result<(Linearisation, Gsn), GsnError>,
) -> serde_json::Value {
    match result {
        Ok((lin, g)) => serde_json::json!({
            "norm": g.norm,
            "indicators": indicators.iter().zip(&g.per_indicator)
                .map(|(i, h)| serde_json::json!({"name": i.name(), "norm": h}))
                .collect::<Vec<_>>(),
            "spectral_radius": g.radius,
            "fd_error": lin.fd_error,
            "disturbance": "landing-line slope deviation (rad)",
        }),
        Err(e) => serde_json::json!({
            "norm": serde_json::Value::Null,
            "indicators": names(indicators),
            "unstable": matches!(e, GsnError::Unstable { .. }),
            "message": e.to_string(),
        }),
    }
}
