//! `pdw-sweep animate`: an animated GIF of two strides of the gait found ([`pdw::animate`]:
//! the first stable fixed point the model's guesses lead to, else an unstable one; frames at
//! equally spaced times in world coordinates, the slope descending to the right at angle γ).

use super::fixedpoint::report_failure;
use super::{build_model, BuiltModel};
use crate::cli::AnimateArgs;
use pdw_limit::FixedPoint;
use std::process::ExitCode;

pub fn run(a: &AnimateArgs) -> anyhow::Result<ExitCode> {
    let inputs: Vec<_> = super::output::model_input(&a.model.model)
        .into_iter()
        .collect();
    let _claim = super::output::claim(
        &[super::output::Output {
            flag: "--out",
            path: &a.out,
            format: super::output::Format::Gif,
            may_exist: false,
        }],
        &inputs,
        a.force,
    )?;
    let m = build_model(&a.model)?;
    pdw::animate::check_drawing(&m)?;
    let (gait, failed) = pdw::animate::gait(&m)?;
    let Some(fp) = gait else {
        eprintln!("no period-one gait found for model '{}'", m.info.name);
        for (label, g, e) in &failed {
            report_failure(label, g, e);
        }
        return Ok(ExitCode::from(2));
    };
    let flags = warnings(&m, &fp);
    let frames = pdw::animate::frames(&m, &fp)?;
    pdw::animate::write_gif(&a.out, &m, &fp, &frames, !flags.is_empty())?;
    eprintln!(
        "wrote {} ({} frames, {} strides)",
        a.out.display(),
        frames.len(),
        pdw::animate::STRIDES
    );
    Ok(ExitCode::SUCCESS)
}

/// Says so when the picture is not of a gait a real walker would show: an unstable gait (no
/// stable one was found) or one whose constraint forces are flagged. Returns the flags.
fn warnings(m: &BuiltModel, fp: &FixedPoint) -> Vec<&'static str> {
    if !fp.stable {
        eprintln!("warning: {}", pdw::animate::unstable_warning(m, fp));
    }
    let flags = pdw::animate::flags(m, fp);
    if !flags.is_empty() {
        eprintln!(
            "warning: the animated gait is FLAGGED as physically invalid: {}",
            flags.join("; ")
        );
    }
    flags
}
