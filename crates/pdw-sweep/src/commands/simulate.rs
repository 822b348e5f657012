//! `pdw-sweep simulate`: the time series of a walk of N strides (states, mode, events, ground
//! reaction, knee-lock torque, energy, with units) to HDF5 or CSV. The plan, the walk, the file
//! and the report are [`pdw::simulate`]'s; this file turns the options into its input and
//! prints the report.

use crate::args;
use crate::cli::SimulateArgs;
use pdw::pipeline::{Silent, Spelling};
use pdw::simulate::{DtOut, SimulateInput};
use std::process::ExitCode;

pub fn run(a: &SimulateArgs) -> anyhow::Result<ExitCode> {
    let state = match &a.state {
        Some(s) => Some(
            s.split(',')
                .map(|t| args::parse_f64(t, "--state"))
                .collect::<Result<Vec<f64>, _>>()?,
        ),
        None => None,
    };
    let input = SimulateInput {
        model: super::choice(&a.model),
        integrator: super::integrator_choice(&a.integrator),
        strides: a.strides,
        dt_out: a.dt_out.unwrap_or(DtOut::Default),
        state,
        gait: a.gait.clone(),
        out: Some(a.out.clone()),
        force: a.force,
        command: super::command_line(),
    };
    let run = pdw::simulate::plan(&input, Spelling::Cli)?.run(&Silent)?;
    super::print_report(&run.report, a.json)?;
    // A fall is an outcome of the walk (in the file's `outcome`), not an error.
    Ok(ExitCode::SUCCESS)
}
