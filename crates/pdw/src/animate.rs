//! An animated GIF of strides of a gait, as both front ends draw it (the CLI's `animate`,
//! Python's `animate`).
//!
//! The gait is the first stable fixed point the model's guesses lead to (else an unstable one,
//! [`gait`]). Frames are the exact states at equally spaced times (the integrator stops at each
//! frame time and at every event), drawn in world coordinates: the slope descends to the right
//! at angle γ ([`frames`]); [`write_gif`] draws them with [`pdw_store::animate_gif`]. A
//! trajectory file of `simulate` is drawn the same way ([`crate::animate_trajectory`]).
//!
//! # Time
//! One second of the GIF is one unit of the model's time ([`crate::model::time_unit`]): real
//! time for models in seconds, `sqrt(l/g)` for the simplest walker, `T` for the kneed preset.
//! The GIF stores each frame's delay in whole centiseconds, so the delay is `round(100 / fps)`
//! cs (2 to 200: 0.5 to 50 frames per second) and frames are [`AnimOptions::frame_time`] =
//! delay / 100 model time units apart. A gait's stride (period `T`) gets
//! `n = max(2, round(T / frame_time))` frames spaced `T / n`, so that the animation loops on a
//! whole stride: playback is real time to within `1 / (2n)` of the speed, and the GIF has
//! `strides · n + 1` frames.

use crate::gaits::Failed;
use crate::input::InputError;
use crate::model::BuiltModel;
use pdw_hybrid::{GuardKind, Integrator, Options, StopReason};
use pdw_limit::{FixedPoint, LimitError, Validity};
use pdw_store::Frame;
use std::path::Path;

/// Strides shown by default.
pub const STRIDES: usize = 2;
/// Frames per second by default: a delay of 6 cs (60 ms) per frame.
pub const DEFAULT_FPS: f64 = 100.0 / 6.0;
/// Picture size (pixels) by default.
pub const SIZE: (u32, u32) = (640, 400);
/// Largest picture side (pixels).
pub const MAX_SIDE: u32 = 4096;
/// Most frames in one GIF.
pub const MAX_FRAMES: usize = 20_000;

/// How an animation is drawn: strides (of a gait), frame rate and picture size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnimOptions {
    /// Strides of the gait shown (1 to 1000; a trajectory is shown whole).
    pub strides: usize,
    /// Frames per second asked for (0.5 to 50); see [`AnimOptions::delay_cs`].
    pub fps: f64,
    /// Picture width and height (pixels).
    pub size: (u32, u32),
}

impl Default for AnimOptions {
    fn default() -> Self {
        Self {
            strides: STRIDES,
            fps: DEFAULT_FPS,
            size: SIZE,
        }
    }
}

impl AnimOptions {
    /// The GIF's delay per frame in centiseconds: `round(100 / fps)`, 2 to 200.
    pub fn delay_cs(&self) -> u32 {
        (100.0 / self.fps).round().clamp(2.0, 200.0) as u32
    }
    /// The frame rate the GIF plays at (`100 / delay_cs`).
    pub fn effective_fps(&self) -> f64 {
        100.0 / self.delay_cs() as f64
    }
    /// Model time between frames: the delay in seconds (one GIF second is one model time unit).
    pub fn frame_time(&self) -> f64 {
        self.delay_cs() as f64 / 100.0
    }
    /// Frames per stride of a gait of period `period`: `max(2, round(period / frame_time))`.
    pub fn frames_per_stride(&self, period: f64) -> usize {
        ((period / self.frame_time()).round() as usize).max(2)
    }
}

/// Strides shown: 1 to 1000.
pub fn check_strides(n: i64, flag: &str) -> Result<usize, InputError> {
    if (1..=1000).contains(&n) {
        Ok(n as usize)
    } else {
        Err(InputError(format!(
            "{flag}: {n} strides is outside 1..=1000"
        )))
    }
}

/// Frames per second: finite, 0.5 to 50 (a GIF's delay is 2 to 200 centiseconds here).
pub fn check_fps(f: f64, flag: &str) -> Result<f64, InputError> {
    if f.is_finite() && (0.5..=50.0).contains(&f) {
        Ok(f)
    } else {
        Err(InputError(format!(
            "{flag}: {f} frames per second is outside 0.5..=50 (a GIF frame lasts a whole \
             number of centiseconds, at least 2)"
        )))
    }
}

/// Picture size: width 64 to [`MAX_SIDE`], height [`pdw_store::plot::GIF_CAPTION_H`] + 64 to
/// [`MAX_SIDE`] pixels.
pub fn check_size((w, h): (u32, u32), flag: &str) -> Result<(u32, u32), InputError> {
    let min_h = pdw_store::plot::GIF_CAPTION_H + 64;
    if (64..=MAX_SIDE).contains(&w) && (min_h..=MAX_SIDE).contains(&h) {
        Ok((w, h))
    } else {
        Err(InputError(format!(
            "{flag}: {w}x{h} pixels is outside the sizes drawn (width 64 to {MAX_SIDE}, height \
             {min_h} to {MAX_SIDE})"
        )))
    }
}

/// Picture size from `WxH` text (e.g. `640x400`), checked by [`check_size`].
pub fn parse_size(s: &str, flag: &str) -> Result<(u32, u32), InputError> {
    let bad = || {
        InputError(format!(
            "{flag}: '{s}' is not a size WIDTHxHEIGHT in pixels (e.g. 640x400)"
        ))
    };
    let (w, h) = s.trim().split_once(['x', 'X', '×']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    check_size((w, h), flag)
}

/// The frame count `n` is refused above [`MAX_FRAMES`].
pub fn check_frames(n: usize) -> Result<(), AnimateError> {
    if n > MAX_FRAMES {
        return Err(AnimateError::Input(InputError(format!(
            "the animation would have {n} frames, more than {MAX_FRAMES}; show fewer strides \
             or lower the frame rate"
        ))));
    }
    Ok(())
}

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
    opts: &AnimOptions,
) -> Result<(), AnimateError> {
    write_titled(path, frames, opts, &title(m, fp, flagged))
}

/// Draws `frames` into the GIF `path` under `title`, at `opts`' size and frame delay.
pub fn write_titled(
    path: &Path,
    frames: &[Frame],
    opts: &AnimOptions,
    title: &str,
) -> Result<(), AnimateError> {
    pdw_store::animate_gif(path, frames, opts.size, opts.delay_cs() * 10, title)
        .map_err(AnimateError::Store)
}

/// What one second of the GIF shows, in words: one unit of the model's time.
pub fn time_scale(m: &BuiltModel) -> String {
    let u = crate::model::time_unit(m);
    if u == "s" {
        "real time".to_string()
    } else {
        format!("one second of the GIF is 1 {u} of model time")
    }
}

/// Maps a point in slope coordinates (stance foot advanced by `off` along the slope) to world
/// coordinates, the slope descending to the right at angle `gamma`.
pub(crate) fn world(gamma: f64, p: [f64; 2], off: f64) -> (f64, f64) {
    let (xs, ys) = (p[0] + off, p[1]);
    (
        xs * gamma.cos() + ys * gamma.sin(),
        -xs * gamma.sin() + ys * gamma.cos(),
    )
}

/// The walker at the frame `label`led, in world coordinates, the stance foot `offset` along
/// the slope; `trace` is the swing foot's path so far.
pub(crate) fn frame(
    m: &BuiltModel,
    x: &[f64],
    offset: f64,
    trace: &[(f64, f64)],
    label: String,
) -> Frame {
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

/// The walker of `fp` at [`AnimOptions::frames_per_stride`] equally spaced times per stride
/// over `opts.strides` strides (`strides · n + 1` frames), in world coordinates (the slope
/// descends to the right at angle γ; the stance foot advances by the swing foot's position at
/// each heel strike), with the swing foot's trace.
pub fn frames(
    m: &BuiltModel,
    fp: &FixedPoint,
    opts: &AnimOptions,
) -> Result<Vec<Frame>, AnimateError> {
    let w = m.walker.as_ref();
    let per_stride = opts.frames_per_stride(fp.metrics.period);
    check_frames(opts.strides * per_stride + 1)?;
    let dt = fp.metrics.period / per_stride as f64;
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
    for k in 0..=opts.strides * per_stride {
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
                        "the gait fell ({}) at t = {t:.4} while animating, after {strides_done} \
                             strides",
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
