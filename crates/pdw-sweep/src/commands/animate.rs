//! `pdw-sweep animate`: an animated GIF of two strides of the gait found.
//!
//! The gait is the first stable fixed point the model's guesses lead to (else an unstable one).
//! Frames are the exact states at equally spaced times (the integrator stops at each frame time
//! and at every event), drawn in world coordinates: the slope descends to the right at angle γ.

use super::fixedpoint::{report_failure, search};
use super::{build_model, BuiltModel};
use crate::args::InputError;
use crate::cli::AnimateArgs;
use pdw_hybrid::{GuardKind, Integrator, Options, StopReason};
use pdw_limit::FixedPoint;
use pdw_store::{animate_gif, Frame};
use std::process::ExitCode;

/// Frames per stride of the animation.
const FRAMES_PER_STRIDE: usize = 40;
/// Strides shown.
const STRIDES: usize = 2;

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
    let w = m.walker.as_ref();
    if w.pose(&vec![0.0; w.dim()]).is_none() {
        return Err(InputError(format!("model '{}' has no drawing", m.info.name)).into());
    }
    let guesses = pdw::gaits::model_guesses(w);
    let (found, failed) = search(&m, &guesses, 1e-10)?;
    let Some(gait) = pdw::gaits::selected(&found) else {
        eprintln!("no period-one gait found for model '{}'", m.info.name);
        for (label, g, e) in &failed {
            report_failure(label, g, e);
        }
        return Ok(ExitCode::from(2));
    };
    let fp = &gait.fp;
    let flags = warnings(&m, fp);
    let frames = frames(&m, fp)?;
    let title = format!(
        "{} walker, slope {:.4} rad: {} gait{}, period {:.4}",
        m.info.name,
        m.slope(),
        if fp.stable { "stable" } else { "UNSTABLE" },
        if flags.is_empty() { "" } else { " (FLAGGED)" },
        fp.metrics.period
    );
    animate_gif(&a.out, &frames, (640, 400), 60, &title)?;
    eprintln!(
        "wrote {} ({} frames, {} strides)",
        a.out.display(),
        frames.len(),
        STRIDES
    );
    Ok(ExitCode::SUCCESS)
}

/// Says so when the picture is not of a gait a real walker would show: an unstable gait (no
/// stable one was found) or one whose constraint forces are flagged. Returns the flags.
fn warnings(m: &BuiltModel, fp: &FixedPoint) -> Vec<&'static str> {
    if !fp.stable {
        eprintln!(
            "warning: model '{}' has no stable period-one gait from its guesses at slope {}; \
             animating the UNSTABLE gait (largest |λ| = {:.4}): a walker started near it leaves it",
            m.info.name,
            m.slope(),
            fp.multipliers.first().map_or(f64::NAN, |l| l.modulus())
        );
    }
    let validity = super::fixedpoint::validity(m, fp);
    let flags = validity.as_ref().map(flag_list).unwrap_or_default();
    if !flags.is_empty() {
        eprintln!(
            "warning: the animated gait is FLAGGED as physically invalid: {}",
            flags.join("; ")
        );
    }
    flags
}

/// The walker of `fp` at [`FRAMES_PER_STRIDE`] equally spaced times over [`STRIDES`] strides,
/// in world coordinates (the slope descends to the right at angle γ; the stance foot advances
/// by the swing foot's position at each heel strike), with the swing foot's trace.
fn frames(m: &BuiltModel, fp: &FixedPoint) -> anyhow::Result<Vec<Frame>> {
    let w = m.walker.as_ref();
    let gamma = m.slope();
    let dt = fp.metrics.period / FRAMES_PER_STRIDE as f64;
    let mut integ = Integrator::new(w.dim(), Options::dop853(1e-10))?;
    let mut x = fp.state.clone();
    let mut buf = vec![0.0; x.len()];
    let mut mode = w.section_mode();
    let mut t = 0.0;
    let mut offset = 0.0; // stance-foot position along the slope
    let mut trace: Vec<(f64, f64)> = Vec::new();
    let mut frames = Vec::new();
    let section = w.section_guard();
    let world = |p: [f64; 2], off: f64| -> (f64, f64) {
        let (xs, ys) = (p[0] + off, p[1]);
        (
            xs * gamma.cos() + ys * gamma.sin(),
            -xs * gamma.sin() + ys * gamma.cos(),
        )
    };
    let mut strides_done = 0;
    for k in 0..=STRIDES * FRAMES_PER_STRIDE {
        let t_frame = k as f64 * dt;
        // Advance to the frame time, handling every event on the way.
        loop {
            match integ.integrate(w, mode, &mut t, &mut x, t_frame) {
                StopReason::EndTime => break,
                StopReason::Guard { guard } => match w.guards(mode)[guard].kind {
                    GuardKind::Reset => {
                        if (mode, guard) == section {
                            if let Some(foot) = w.pose(&x).and_then(|p| p.swing_foot) {
                                offset += foot[0];
                            }
                            strides_done += 1;
                        }
                        mode = w.reset(integ.scratch(), mode, guard, &x, &mut buf);
                        x.copy_from_slice(&buf);
                    }
                    GuardKind::Terminal(kind) => {
                        return Err(anyhow::anyhow!(
                            "the gait fell ({}) at t = {t:.4} while animating (state {x:?}, strides {strides_done})",
                            kind.name()
                        ))
                    }
                },
                other => {
                    return Err(anyhow::anyhow!(
                        "integration stopped at t = {t:.4}: {other}"
                    ))
                }
            }
        }
        let pose = w.pose(&x).expect("model has a drawing (checked above)");
        if let Some(f) = pose.swing_foot {
            trace.push(world(f, offset));
        }
        let x0 = -1.5;
        let x1 = offset + 3.0;
        frames.push(Frame {
            links: pose
                .links
                .iter()
                .map(|[p, q]| (world(*p, offset), world(*q, offset)))
                .collect(),
            joints: pose.joints.iter().map(|p| world(*p, offset)).collect(),
            slope: (world([x0, 0.0], 0.0), world([x1, 0.0], 0.0)),
            trace: trace.clone(),
            label: format!("t = {t:.3}   stride {}", strides_done + 1),
        });
    }
    Ok(frames)
}

/// The validity flags raised along a gait's step, in words (empty for a valid gait).
pub fn flag_list(v: &pdw_limit::Validity) -> Vec<&'static str> {
    [
        (
            v.normal_force_negative,
            "the stance foot would lift off (normal force < 0)",
        ),
        (
            v.knee_unlocks,
            "a locked knee would unlock (lock torque < 0)",
        ),
        (
            v.swing_foot_scuffs,
            "the swing foot goes below the slope where its clearance rule checks it",
        ),
        (
            v.impact_violation,
            "an impact needs a pulling contact or stop",
        ),
    ]
    .into_iter()
    .filter(|(f, _)| *f)
    .map(|(_, w)| w)
    .collect()
}
