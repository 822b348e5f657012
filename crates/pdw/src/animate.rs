//! An animated GIF of two strides of a gait, as both front ends draw it (the CLI's `animate`,
//! Python's `animate`).
//!
//! The gait is the first stable fixed point the model's guesses lead to (else an unstable one,
//! [`gait`]). Frames are the exact states at equally spaced times (the integrator stops at each
//! frame time and at every event), drawn in world coordinates: the slope descends to the right
//! at angle γ ([`frames`]); [`write_gif`] draws them with [`pdw_store::animate_gif`].

use crate::gaits::Failed;
use crate::input::InputError;
use crate::model::BuiltModel;
use pdw_hybrid::{GuardKind, Integrator, Options, StopReason};
use pdw_limit::{FixedPoint, LimitError, Validity};
use pdw_store::Frame;
use std::path::Path;

/// Frames per stride of the animation.
pub const FRAMES_PER_STRIDE: usize = 40;
/// Strides shown.
pub const STRIDES: usize = 2;
/// Size of the picture (pixels) and delay between frames (ms).
const SIZE: (u32, u32) = (640, 400);
const DELAY_MS: u32 = 60;

/// Why an animation was not drawn.
#[derive(Debug)]
pub enum AnimateError {
    /// The model has no drawing.
    Input(InputError),
    Limit(LimitError),
    /// The gait fell or the integration stopped while animating.
    Walk(String),
    Store(pdw_store::StoreError),
}

impl std::fmt::Display for AnimateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AnimateError::Input(e) => e.fmt(f),
            AnimateError::Limit(e) => e.fmt(f),
            AnimateError::Walk(e) => f.write_str(e),
            AnimateError::Store(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for AnimateError {}

/// The model can be drawn (its walker has a pose).
pub fn check_drawing(m: &BuiltModel) -> Result<(), InputError> {
    let w = m.walker.as_ref();
    if w.pose(&vec![0.0; w.dim()]).is_none() {
        return Err(InputError(format!(
            "model '{}' has no drawing",
            m.info.name
        )));
    }
    Ok(())
}

/// The gait animated: Newton (to 1e-10) from the model's guesses, the first stable gait found
/// (else the first), with the failed guesses.
pub fn gait(m: &BuiltModel) -> Result<(Option<FixedPoint>, Vec<Failed>), LimitError> {
    let guesses = crate::gaits::model_guesses(m.walker.as_ref());
    let (found, failed) = crate::gaits::search(m, &guesses, 1e-10)?;
    Ok((crate::gaits::selected(&found).map(|f| f.fp.clone()), failed))
}

/// The validity flags raised along a gait's step, in words (empty for a valid gait):
/// [`Validity::flag_descriptions`].
pub fn flag_list(v: &Validity) -> Vec<&'static str> {
    v.flag_descriptions()
}

/// The flags of `fp`'s step ([`flag_list`] of [`Validity::along_step`]).
pub fn flags(m: &BuiltModel, fp: &FixedPoint) -> Vec<&'static str> {
    Validity::along_step(m.walker.as_ref(), &fp.state)
        .as_ref()
        .map(flag_list)
        .unwrap_or_default()
}

/// The picture's title: model, slope, whether the gait is stable and flagged, its period.
pub fn title(m: &BuiltModel, fp: &FixedPoint, flagged: bool) -> String {
    format!(
        "{} walker, slope {:.4} rad: {} gait{}, period {:.4}",
        m.info.name,
        m.slope(),
        if fp.stable { "stable" } else { "UNSTABLE" },
        if flagged { " (FLAGGED)" } else { "" },
        fp.metrics.period
    )
}

/// Draws `frames` of `fp` into the GIF `path` under [`title`].
pub fn write_gif(
    path: &Path,
    m: &BuiltModel,
    fp: &FixedPoint,
    frames: &[Frame],
    flagged: bool,
) -> Result<(), AnimateError> {
    pdw_store::animate_gif(path, frames, SIZE, DELAY_MS, &title(m, fp, flagged))
        .map_err(AnimateError::Store)
}

/// Maps a point in slope coordinates (stance foot advanced by `off` along the slope) to world
/// coordinates, the slope descending to the right at angle `gamma`.
fn world(gamma: f64, p: [f64; 2], off: f64) -> (f64, f64) {
    let (xs, ys) = (p[0] + off, p[1]);
    (
        xs * gamma.cos() + ys * gamma.sin(),
        -xs * gamma.sin() + ys * gamma.cos(),
    )
}

/// The walker at the frame `label`led, in world coordinates, the stance foot `offset` along
/// the slope; `trace` is the swing foot's path so far.
fn frame(m: &BuiltModel, x: &[f64], offset: f64, trace: &[(f64, f64)], label: String) -> Frame {
    let gamma = m.slope();
    let pose = m
        .walker
        .pose(x)
        .expect("model has a drawing (check_drawing)");
    let (x0, x1) = (-1.5, offset + 3.0);
    Frame {
        links: pose
            .links
            .iter()
            .map(|[p, q]| (world(gamma, *p, offset), world(gamma, *q, offset)))
            .collect(),
        joints: pose
            .joints
            .iter()
            .map(|p| world(gamma, *p, offset))
            .collect(),
        slope: (world(gamma, [x0, 0.0], 0.0), world(gamma, [x1, 0.0], 0.0)),
        trace: trace.to_vec(),
        label,
    }
}

/// The walker of `fp` at [`FRAMES_PER_STRIDE`] equally spaced times over [`STRIDES`] strides,
/// in world coordinates (the slope descends to the right at angle γ; the stance foot advances
/// by the swing foot's position at each heel strike), with the swing foot's trace.
pub fn frames(m: &BuiltModel, fp: &FixedPoint) -> Result<Vec<Frame>, AnimateError> {
    let w = m.walker.as_ref();
    let dt = fp.metrics.period / FRAMES_PER_STRIDE as f64;
    let mut integ = Integrator::new(w.dim(), Options::dop853(1e-10))
        .map_err(|e| AnimateError::Walk(e.to_string()))?;
    let mut x = fp.state.clone();
    let mut buf = vec![0.0; x.len()];
    let mut mode = w.section_mode();
    let mut t = 0.0;
    let mut offset = 0.0; // stance-foot position along the slope
    let mut trace: Vec<(f64, f64)> = Vec::new();
    let mut frames = Vec::new();
    let section = w.section_guard();
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
                        return Err(AnimateError::Walk(format!(
                            "the gait fell ({}) at t = {t:.4} while animating (state {x:?}, strides {strides_done})",
                            kind.name()
                        )))
                    }
                },
                other => {
                    return Err(AnimateError::Walk(format!(
                        "integration stopped at t = {t:.4}: {other}"
                    )))
                }
            }
        }
        if let Some(f) = w.pose(&x).and_then(|p| p.swing_foot) {
            trace.push(world(m.slope(), f, offset));
        }
        let label = format!("t = {t:.3}   stride {}", strides_done + 1);
        frames.push(frame(m, &x, offset, &trace, label));
    }
    Ok(frames)
}

/// The warning for an animated unstable gait (no stable one was found).
pub fn unstable_warning(m: &BuiltModel, fp: &FixedPoint) -> String {
    format!(
        "model '{}' has no stable period-one gait from its guesses at slope {}; animating the \
         UNSTABLE gait (largest |λ| = {:.4}): a walker started near it leaves it",
        m.info.name,
        m.slope(),
        fp.multipliers.first().map_or(f64::NAN, |l| l.modulus())
    )
}
