//! One module per subcommand. Model building, overrides, units and the integrator choice are
//! the library's ([`pdw`]); the functions here only turn the command line's option groups into
//! its types.

mod animate;
mod basin;
mod basin_over;
mod design;
mod disturb;
mod explore;
mod fixedpoint;
mod follow;
mod merge;
mod mfpt;
mod mfpt_curve;
mod mfpt_over;
mod models;
mod output;
mod simulate;
mod sink;
mod sweep;

use crate::args::InputError;
use crate::cli::{Cli, Command, IntegratorOpts, ModelOpts};
use pdw::hybrid::Options;
use std::process::ExitCode;

pub use pdw::model::{
    length_unit, model_units, param_unit, section_units, stride_residual, time_unit, units_list,
};
pub use pdw::{integrator_json, integrator_text, BuiltModel};

pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Models(a) => models::run(&a),
        Command::Fixedpoint(a) => fixedpoint::run(&a),
        Command::Animate(a) => animate::run(&a),
        Command::Basin(a) => basin::run(&a),
        Command::Merge(a) => merge::run(&a),
        Command::Simulate(a) => simulate::run(&a),
        Command::Mfpt(a) => mfpt::run(&a),
        Command::Design(a) => design::run(&a),
        Command::Explore(a) => explore::run(&a),
        Command::Disturb(a) => disturb::run(&a),
    }
}

/// `--model`, `--slope`, `--set` as the library's [`pdw::ModelChoice`].
fn choice(opts: &ModelOpts) -> pdw::ModelChoice {
    pdw::ModelChoice {
        model: opts.model.clone(),
        slope: opts.slope.clone(),
        set: opts.set.clone(),
    }
}

/// Parses `--model`, `--slope`, `--set` into overrides (without building); see
/// [`pdw::model::overrides`].
pub fn overrides(opts: &ModelOpts) -> Result<Vec<(String, f64)>, InputError> {
    pdw::model::overrides(&choice(opts))
}

/// Builds the model named on the command line with its overrides.
pub fn build_model(opts: &ModelOpts) -> Result<BuiltModel, InputError> {
    pdw::build_model(&choice(opts))
}

/// The integrator of a command from `--integrator`, `--rtol`, `--atol`, `--rk4-step`,
/// `--controller`, `--cold-restarts` on top of the command's `default`; see
/// [`pdw::integrator()`].
pub fn integrator(o: &IntegratorOpts, default: Options) -> Result<Options, InputError> {
    pdw::integrator(&integrator_choice(o), default)
}

/// `--integrator`, `--rtol`, `--atol`, `--rk4-step`, `--controller`, `--cold-restarts` as the
/// library's [`pdw::IntegratorChoice`].
fn integrator_choice(o: &IntegratorOpts) -> pdw::IntegratorChoice {
    pdw::IntegratorChoice {
        integrator: o.integrator.clone(),
        rtol: o.rtol,
        atol: o.atol,
        rk4_step: o.rk4_step,
        cold_restarts: o.cold_restarts,
        controller: o.controller.clone(),
    }
}

/// Prints a command's report: its text, or with `--json` its JSON object on one line.
fn print_report<R: pdw::pipeline::Report>(r: &R, json: bool) -> anyhow::Result<()> {
    if json {
        crate::outln!("{}", serde_json::to_string(&r.json())?);
    } else {
        crate::out(&r.text());
    }
    Ok(())
}

/// The command line as run.
pub fn command_line() -> String {
    std::env::args().collect::<Vec<_>>().join(" ")
}

/// This run's provenance: build (version, commit, profile), the SIMD path chosen at run time
/// and the numeric contract all paths keep, host, command line and `options` (every numerical
/// option of the run, a JSON object).
pub fn provenance(options: serde_json::Value) -> pdw::store::Provenance {
    let mut p = pdw::provenance(&command_line(), &options);
    // the resolved spec of a chain walker's `--model`, so that its files rebuild it anywhere
    p.model_spec = model_arg()
        .and_then(|m| pdw::model::spec_toml(&m))
        .unwrap_or_default();
    p
}

/// The value of this run's `--model` (`--model X` or `--model=X`), if given.
fn model_arg() -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .enumerate()
        .find_map(|(i, a)| match a.strip_prefix("--model") {
            Some("") => args.get(i + 1).cloned(),
            Some(rest) => rest.strip_prefix('=').map(str::to_string),
            None => None,
        })
}
