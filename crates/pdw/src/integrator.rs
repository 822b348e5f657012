//! The integrator of a run from the front ends' choices (method, tolerances, rk4 step,
//! controller, cold restarts), and the integrator in a file's and a line's form.

use crate::input::InputError;
use crate::model::BuiltModel;
use pdw_hybrid::{Method, Options};

/// The integrator options as given (every field optional: the run's default fills the rest).
/// The CLI's `--integrator`, `--rtol`, `--atol`, `--rk4-step`, `--cold-restarts`,
/// `--controller`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IntegratorChoice {
    /// `dopri5`, `dop853` or `rk4`.
    pub integrator: Option<String>,
    pub rtol: Option<f64>,
    pub atol: Option<f64>,
    /// The fixed step of `rk4` (model time units).
    pub rk4_step: Option<f64>,
    /// Start every segment with the starting-step heuristic ([`Options::warm_restart`] off).
    pub cold_restarts: bool,
    /// DOPRI5's step-size controller: `pi` (default) or `elementary`.
    pub controller: Option<String>,
}

/// The integrator of a run: `--integrator`, `--rtol`, `--atol`, `--rk4-step` on top of the
/// command's `default` (its method and tolerances fill what is not given). `--atol` defaults to
/// `--rtol` when only that is given. Tolerances with rk4, or a step with an adaptive method,
/// are refused (they would be ignored); so is rk4 without a step.
pub fn integrator(o: &IntegratorChoice, default: Options) -> Result<Options, InputError> {
    let method = match o.integrator.as_deref() {
        None => None,
        Some("dopri5") => Some("dopri5"),
        Some("dop853") => Some("dop853"),
        Some("rk4") => Some("rk4"),
        Some(other) => {
            return Err(InputError(format!(
                "--integrator: '{other}' is not one of dopri5, dop853, rk4"
            )))
        }
    };
    let opts = match method {
        Some("rk4") => {
            if o.rtol.is_some() || o.atol.is_some() {
                return Err(InputError(
                    "--rtol/--atol: rk4 is a fixed-step method without tolerances; give its \
                     step with --rk4-step H, or use --integrator dopri5|dop853"
                        .into(),
                ));
            }
            let Some(h) = o.rk4_step else {
                return Err(InputError(
                    "--integrator rk4 needs --rk4-step H (the fixed step, model time units)".into(),
                ));
            };
            Options::rk4(h)
        }
        m => {
            if let Some(h) = o.rk4_step {
                return Err(InputError(format!(
                    "--rk4-step {h}: only --integrator rk4 takes a fixed step"
                )));
            }
            let base = match (m, default.method) {
                (Some("dopri5"), _) => Method::Dopri5,
                (Some(_), _) => Method::Dop853,
                (None, Method::Rk4 { .. }) => Method::Dop853,
                (None, d) => d,
            };
            let (d_rtol, d_atol) = match default.method {
                Method::Rk4 { .. } => (1e-10, 1e-10),
                _ => (default.rtol, default.atol),
            };
            let rtol = o.rtol.unwrap_or(d_rtol);
            let atol = o.atol.or(o.rtol).unwrap_or(d_atol);
            Options {
                method: base,
                rtol,
                atol,
                ..default
            }
        }
    };
    let controller = match o.controller.as_deref() {
        None | Some("pi") => pdw_hybrid::Controller::Pi,
        Some(_) if !matches!(opts.method, Method::Dopri5) => {
            return Err(InputError(
                "--controller: only --integrator dopri5 has a choice of step-size controller \
                 (dop853's is elementary, rk4 has none)"
                    .into(),
            ))
        }
        Some(_) => pdw_hybrid::Controller::Elementary,
    };
    let opts = Options {
        warm_restart: opts.warm_restart && !o.cold_restarts,
        controller,
        ..opts
    };
    opts.validate().map_err(|e| match e {
        pdw_hybrid::HybridError::InvalidOption {
            name,
            value,
            allowed,
        } => {
            let flag = match name {
                "rtol" => "--rtol",
                "atol" => "--atol",
                "h" => "--rk4-step",
                other => other,
            };
            InputError(format!("{flag}: {value:e} is invalid: {allowed}"))
        }
        other => InputError(other.to_string()),
    })?;
    Ok(opts)
}

/// The integrator as a JSON object for files and `--json` (method, tolerances or step).
/// `"warm_restart": true` when continued segments start from the controller's last proposal
/// ([`Options::warm_restart`], the basin's default), which changes results at the tolerance's
/// level; absent otherwise. `"controller": "elementary"` for DOPRI5 with
/// [`pdw_hybrid::Controller::Elementary`] (absent for the default PI controller).
pub fn integrator_json(o: &Options) -> serde_json::Value {
    let mut v = match o.method {
        Method::Rk4 { h } => return serde_json::json!({"method": "rk4", "h": h}),
        Method::Dopri5 => {
            serde_json::json!({"method": "dopri5", "rtol": o.rtol, "atol": o.atol})
        }
        Method::Dop853 => {
            serde_json::json!({"method": "dop853", "rtol": o.rtol, "atol": o.atol})
        }
    };
    if o.warm_restart {
        v["warm_restart"] = serde_json::Value::Bool(true);
    }
    if o.controller == pdw_hybrid::Controller::Elementary {
        v["controller"] = serde_json::Value::from("elementary");
    }
    v
}

/// The integrator in one line of text, e.g. `dop853 rtol=1e-14 atol=1e-14` (plus
/// ` warm-restart` when [`Options::warm_restart`] is set, ` elementary` for DOPRI5 with the
/// elementary controller).
pub fn integrator_text(o: &Options) -> String {
    let elementary = o.controller == pdw_hybrid::Controller::Elementary;
    let warm = match (o.warm_restart, elementary) {
        (false, false) => "",
        (true, false) => " warm-restart",
        (false, true) => " elementary",
        (true, true) => " elementary warm-restart",
    };
    match o.method {
        Method::Rk4 { h } => format!("rk4 h={h:e}"),
        Method::Dopri5 => format!("dopri5 rtol={:e} atol={:e}{warm}", o.rtol, o.atol),
        Method::Dop853 => format!("dop853 rtol={:e} atol={:e}{warm}", o.rtol, o.atol),
    }
}

/// The gait tolerance the integrator check measures a stride against: the basin's cells'
/// ([`pdw_limit::BasinOptions`]'s `tol_gait`), the loosest the engine uses to call two states
/// the same gait.
pub const CHECK_GAIT_TOL: f64 = 1e-6;

/// Integrators at least this accurate need no check: every command's default is (the basin's,
/// the loosest, is DOP853 at 1e-9), and the tests show each resolves every preset's gait.
const SOUND_TOL: f64 = 1e-9;
/// The largest RK4 step not checked (see [`integrator_warning`]).
const SOUND_RK4_STEP: f64 = 1e-4;

/// How far one stride of `integrator` carries the gait at `section` (a fixed point of the
/// accurate stride map), when more than a tenth of `gait_tol`: the run's integrator cannot
/// resolve a stride, so what it reports (a basin's labels, an MFPT, a fall) is the integrator's
/// error, not the walker's. A stride that does not come back (a fall, a failed integration)
/// counts as infinitely far. `None`: the integrator is accurate enough.
pub fn gait_drift(
    m: &BuiltModel,
    integrator: Options,
    section: &[f64],
    gait_tol: f64,
) -> Result<Option<f64>, pdw_limit::LimitError> {
    let r = crate::model::stride_residual(m, integrator, section)?;
    Ok((r.is_nan() || r > 0.1 * gait_tol).then_some(r))
}

/// The warning every front end gives for a [`gait_drift`] of `r`.
pub fn drift_warning(integrator: &Options, r: f64, gait_tol: f64) -> String {
    let how_far = if r.is_finite() {
        format!("is a fixed point only to {r:.2e}")
    } else {
        "does not come back after one stride (it falls or the integration fails)".to_string()
    };
    format!(
        "with {} the gait {how_far} (the gait tolerance is {gait_tol:e}): this integrator \
         cannot resolve a stride, and what the run reports (falls, strides, labels) is its \
         error, not the walker's; use a tighter --rtol/--atol or a smaller --rk4-step",
        integrator_text(integrator)
    )
}

/// The integrator check of a run that has no gait at hand: the model's stable gait (else its
/// first) found on the accurate stride map from the model's own guesses, then [`gait_drift`]
/// at [`CHECK_GAIT_TOL`] with the warning. Integrators at least as accurate as every
/// command's default (adaptive at rtol, atol ≤ 1e-9, or RK4 at a step ≤ 1e-4) are not checked
/// (no gait search); a model without a gait at its values
/// is not checked either (there is nothing to measure the stride against).
pub fn integrator_warning(
    m: &BuiltModel,
    integrator: &Options,
) -> Result<Option<String>, pdw_limit::LimitError> {
    // RK4 at a step of at most SOUND_RK4_STEP is too fine to be the coarse integrator this
    // check is for (its error, ~h⁴ a unit time, is below what the drift resolves), and checking
    // it would cost 1/h steps a stride (`--rk4-step 1e-12`: the check would never end).
    let sound = match integrator.method {
        Method::Rk4 { h } => h <= SOUND_RK4_STEP,
        _ => integrator.rtol <= SOUND_TOL && integrator.atol <= SOUND_TOL,
    };
    if sound {
        return Ok(None);
    }
    let guesses = crate::gaits::model_guesses(m.walker.as_ref());
    let Ok((found, _)) = crate::gaits::search(m, &guesses, crate::mfpt::GAIT_TOL) else {
        return Ok(None);
    };
    let Some(gait) = crate::gaits::selected(&found) else {
        return Ok(None);
    };
    Ok(
        gait_drift(m, *integrator, &gait.fp.section, CHECK_GAIT_TOL)?
            .map(|r| drift_warning(integrator, r, CHECK_GAIT_TOL)),
    )
}

/// Gives the [`integrator_warning`] of a run through the library's warnings (the CLI's stderr
/// as `warning: …`, Python's `warnings.warn`), once per run. Every command that integrates
/// calls it after building its model and integrator.
pub fn check_integrator(m: &BuiltModel, integrator: &Options) -> Result<(), pdw_limit::LimitError> {
    if let Some(msg) = integrator_warning(m, integrator)? {
        crate::model::warn_integrator(&msg);
    }
    Ok(())
}
