//! One module per subcommand; shared model construction here.

mod animate;
mod basin;
mod basin_over;
mod design;
mod fixedpoint;
mod follow;
mod merge;
mod models;
mod output;
mod simulate;
mod sweep;

use crate::args::{self, InputError};
use crate::cli::{Cli, Command, IntegratorOpts, ModelOpts};
use pdw_hybrid::{Method, Options};
use pdw_walkers::{ModelInfo, Walker};
use std::process::ExitCode;

pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Models(a) => models::run(&a),
        Command::Fixedpoint(a) => fixedpoint::run(&a),
        Command::Animate(a) => animate::run(&a),
        Command::Basin(a) => basin::run(&a),
        Command::Merge(a) => merge::run(&a),
        Command::Simulate(a) => simulate::run(&a),
        Command::Design(a) => design::run(&a),
    }
}

/// A model built from the command line, with the resolved parameter values.
pub struct BuiltModel {
    pub info: ModelInfo,
    pub walker: Box<dyn Walker>,
    /// `(name, value)` in the model's parameter order.
    pub params: Vec<(String, f64)>,
}

impl BuiltModel {
    pub fn slope(&self) -> f64 {
        self.params
            .iter()
            .find(|(n, _)| *n == "slope")
            .map(|p| p.1)
            .unwrap_or(f64::NAN)
    }

    /// Parameters as a JSON object.
    pub fn params_json(&self) -> serde_json::Value {
        serde_json::Value::Object(
            self.params
                .iter()
                .map(|(n, v)| (n.to_string(), serde_json::json!(v)))
                .collect(),
        )
    }
}

/// Parses `--model`, `--slope`, `--set` into overrides (without building).
///
/// The slope given twice (`--slope` and `--set slope=…`) is refused: one of the two would be
/// silently ignored.
pub fn overrides(opts: &ModelOpts) -> Result<Vec<(String, f64)>, InputError> {
    let mut ov: Vec<(String, f64)> = Vec::new();
    for s in &opts.set {
        let (name, v) = args::parse_assignment(s)?;
        if let Some((_, prev)) = ov.iter().find(|(n, _)| *n == name) {
            return Err(InputError(format!(
                "--set {name}: given twice ({prev} and {v}); give each parameter once"
            )));
        }
        ov.push((name, v));
    }
    if let Some(s) = &opts.slope {
        if let Some(set) = opts
            .set
            .iter()
            .find(|a| a.split_once('=').is_some_and(|(n, _)| n.trim() == "slope"))
        {
            return Err(InputError(format!(
                "--slope {s} and --set {set} both set the slope; give it once (--slope accepts \
                 3deg as well)"
            )));
        }
        ov.push(("slope".to_string(), args::parse_slope(s)?));
    }
    Ok(ov)
}

/// Builds the model named on the command line with its overrides.
pub fn build_model(opts: &ModelOpts) -> Result<BuiltModel, InputError> {
    build_with(opts, &[])
}

/// Builds the model with the command-line overrides and then `extra` overrides on top.
pub fn build_with(opts: &ModelOpts, extra: &[(String, f64)]) -> Result<BuiltModel, InputError> {
    let info = pdw_walkers::model_info(&opts.model).map_err(|e| InputError(e.to_string()))?;
    let mut ov = overrides(opts)?;
    ov.extend_from_slice(extra);
    let refs: Vec<(&str, f64)> = ov.iter().map(|(n, v)| (n.as_str(), *v)).collect();
    let values = info.resolve(&refs).map_err(|e| InputError(e.to_string()))?;
    let walker = info
        .build_from(&values)
        .map_err(|e| InputError(e.to_string()))?;
    let info = info.with_walker(walker.as_ref());
    let params = info
        .params
        .iter()
        .map(|p| p.name.clone())
        .zip(values)
        .collect();
    Ok(BuiltModel {
        info,
        walker,
        params,
    })
}

/// The integrator of a command: `--integrator`, `--rtol`, `--atol`, `--rk4-step` on top of the
/// command's `default` (its method and tolerances fill what is not given). `--atol` defaults to
/// `--rtol` when only that is given. Tolerances with rk4, or a step with an adaptive method,
/// are refused (they would be ignored); so is rk4 without a step.
pub fn integrator(o: &IntegratorOpts, default: Options) -> Result<Options, InputError> {
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

/// `‖P(s) − s‖∞` of the stride map integrated by `integrator` at section state `s` (infinite
/// when the stride fails): how far `s` is from a fixed point of that map.
pub fn stride_residual(m: &BuiltModel, integrator: Options, s: &[f64]) -> anyhow::Result<f64> {
    let map = pdw_limit::StrideMap::new(m.walker.as_ref(), integrator)?;
    Ok(map
        .apply(s)
        .map(|p| {
            p.iter()
                .zip(s)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        })
        .unwrap_or(f64::INFINITY))
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

/// Units of the model's quantities (time, every state component, forces, energy): the
/// simplest walker's are dimensionless (time in √(l/g), lengths in l), the rimless wheel's and
/// the chain walkers' SI (see [`pdw_limit::trajectory::units`]).
pub fn model_units(m: &BuiltModel) -> pdw_limit::trajectory::TrajectoryUnits {
    let w = m.walker.as_ref();
    let e = pdw_limit::trajectory::model_energy(w).unwrap_or_default();
    pdw_limit::trajectory::units(w, &e)
}

/// The time unit of the model (`s`, or `sqrt(l/g)` for the simplest walker).
pub fn time_unit(m: &BuiltModel) -> String {
    model_units(m).time
}

/// The length unit of the model (`l`, the leg, for the simplest walker; `m` otherwise).
pub fn length_unit(m: &BuiltModel) -> String {
    m.walker.units().length.into()
}

/// The unit of each section coordinate, in section order (by the state component of the same
/// name).
pub fn section_units(m: &BuiltModel) -> Vec<String> {
    let u = model_units(m);
    m.info
        .section_names
        .iter()
        .map(|n| {
            m.info
                .state_names
                .iter()
                .position(|s| s == n)
                .map_or_else(|| "rad".to_string(), |j| u.state[j].clone())
        })
        .collect()
}

/// The command line as run.
pub fn command_line() -> String {
    std::env::args().collect::<Vec<_>>().join(" ")
}

/// This run's provenance: build (version, commit, profile), the SIMD path chosen at run time
/// and the numeric contract all paths keep, host, command line and `options` (every numerical
/// option of the run, a JSON object).
pub fn provenance(options: serde_json::Value) -> pdw_store::Provenance {
    let mut p = pdw_store::Provenance::new(&command_line(), pdw_simd::path().name(), &options);
    p.numerics = pdw_simd::NUMERICS.to_string();
    p
}

/// The unit of the model parameter `name` (`""` if unknown).
pub fn param_unit(m: &BuiltModel, name: &str) -> String {
    m.info
        .params
        .iter()
        .find(|p| p.name == name)
        .map(|p| p.unit.clone())
        .unwrap_or_default()
}

/// A JSON list of units, the form of a `units` attribute on a dataset whose last axis runs
/// over components of different units.
pub fn units_list(u: &[String]) -> String {
    serde_json::to_string(u).unwrap_or_default()
}
