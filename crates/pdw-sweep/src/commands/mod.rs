//! One module per subcommand; shared model construction here.

mod animate;
mod basin;
mod design;
mod fixedpoint;
mod merge;
mod models;
mod simulate;
mod sweep;

use crate::args::{self, InputError};
use crate::cli::{Cli, Command, ModelOpts};
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
pub fn overrides(opts: &ModelOpts) -> Result<Vec<(String, f64)>, InputError> {
    let mut ov = Vec::new();
    for s in &opts.set {
        ov.push(args::parse_assignment(s)?);
    }
    if let Some(s) = &opts.slope {
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
