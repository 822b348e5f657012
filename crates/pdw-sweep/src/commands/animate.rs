//! `pdw-sweep animate`: an animated GIF of `--steps` strides of the gait found
//! ([`pdw::animate`]: the first stable fixed point the model's guesses lead to, else an
//! unstable one; frames at equally spaced times in world coordinates, the slope descending to
//! the right at angle γ), or of a trajectory file written by `simulate` (`--from`,
//! [`pdw::animate_trajectory`]).

use super::fixedpoint::report_failure;
use super::{build_model, BuiltModel};
use crate::cli::AnimateArgs;
use pdw::animate::AnimOptions;
use pdw::limit::FixedPoint;
use std::path::Path;
use std::process::ExitCode;

pub fn run(a: &AnimateArgs) -> anyhow::Result<ExitCode> {
    let mut inputs: Vec<_> = super::output::model_input(&a.model.model)
        .into_iter()
        .collect();
    if let Some(f) = &a.from {
        inputs = vec![super::output::Input {
            flag: "--from",
            path: f,
        }];
    }
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
    let opts = AnimOptions {
        strides: a.strides,
        fps: a.fps.unwrap_or(pdw::animate::DEFAULT_FPS),
        size: a.size,
    };
    if let Some(f) = &a.from {
        return from_file(a, f, &opts);
    }
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
    let frames = pdw::animate::frames(&m, &fp, &opts)?;
    pdw::animate::write_gif(&a.out, &m, &fp, &frames, !flags.is_empty(), &opts)?;
    eprintln!(
        "wrote {} ({} frames, {} stride{}, {:.4} frames per second, {})",
        a.out.display(),
        frames.len(),
        opts.strides,
        if opts.strides == 1 { "" } else { "s" },
        opts.effective_fps(),
        pdw::animate::time_scale(&m)
    );
    Ok(ExitCode::SUCCESS)
}

/// `--from`: the trajectory file's walk, its model rebuilt from the file.
fn from_file(a: &AnimateArgs, from: &Path, opts: &AnimOptions) -> anyhow::Result<ExitCode> {
    let d = pdw::animate_trajectory::animate_file(from, &a.out, opts, "--from")?;
    if let Some(f) = &d.fall {
        eprintln!("note: the walk ends in a fall ({f}); the last frame shows it");
    }
    eprintln!(
        "wrote {} ({} frames of {}, {:.4} frames per second, {})",
        a.out.display(),
        d.frames,
        from.display(),
        opts.effective_fps(),
        pdw::animate::time_scale(&d.model)
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
