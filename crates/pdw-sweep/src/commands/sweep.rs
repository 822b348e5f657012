//! `pdw-sweep fixedpoint --sweep NAME=A:B:N`: continuation of the gaits in a parameter.

use crate::args::InputError;
use crate::cli::FixedpointArgs;
use std::process::ExitCode;

pub fn run(_a: &FixedpointArgs) -> anyhow::Result<ExitCode> {
    Err(InputError("--sweep is not available in this build".into()).into())
}
