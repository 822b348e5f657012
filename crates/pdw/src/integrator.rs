//! The integrator of a run from the front ends' choices (method, tolerances, rk4 step,
//! controller, cold restarts), and the integrator in a file's and a line's form.

use crate::input::InputError;
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
