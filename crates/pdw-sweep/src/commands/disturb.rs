//! `pdw-sweep disturb`: one stride of another slope or height from the stable gait, then
//! nominal ground; or, with `--largest`, the largest such disturbance survived both ways. The
//! plan, the run and the report are [`pdw::disturb`]'s; this file turns the options into its
//! input and prints the report.

use crate::cli::DisturbArgs;
use pdw::disturb::DisturbInput;
use pdw::pipeline::{Silent, Spelling};
use std::process::ExitCode;

pub fn run(a: &DisturbArgs) -> anyhow::Result<ExitCode> {
    let input = DisturbInput {
        model: super::choice(&a.model),
        integrator: super::integrator_choice(&a.integrator),
        terrain: a.terrain.clone(),
        once: a.once.clone(),
        largest: a.largest,
        strides: a.strides,
        tol: a.tol,
    };
    let report = pdw::disturb::plan(&input, Spelling::Cli)?.run(&Silent)?;
    super::print_report(&report, a.json)?;
    Ok(ExitCode::SUCCESS)
}
