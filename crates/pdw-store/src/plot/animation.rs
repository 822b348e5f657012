//! Animated GIFs of a walking gait: links, joints, the slope and the swing foot's trace, frame
//! by frame on fixed axes, under a caption band.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{pad, pe, range_of, register_fonts, FONT};
use crate::h5util::Staged;
use crate::{Result, StoreError};

/// One picture of a walker, in world coordinates (metres or leg lengths; x along the ground's
/// horizontal, y up).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// Links as segments from one joint to the next.
    pub links: Vec<((f64, f64), (f64, f64))>,
    /// Joint and point-mass positions (drawn as dots).
    pub joints: Vec<(f64, f64)>,
    /// Two points on the slope line (drawn across the whole picture).
    pub slope: ((f64, f64), (f64, f64)),
    /// The swing foot's path so far.
    pub trace: Vec<(f64, f64)>,
    /// Caption of this frame, e.g. `"t = 1.23"`.
    pub label: String,
}

/// Clips the infinite line through `a`, `b` to the box `[x0, x1] × [y0, y1]` (Liang–Barsky on
/// the parametric line).
pub fn clip_line(
    a: (f64, f64),
    b: (f64, f64),
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
) -> Option<[(f64, f64); 2]> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for (p, q) in [
        (-dx, a.0 - x0),
        (dx, x1 - a.0),
        (-dy, a.1 - y0),
        (dy, y1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1 && t0.is_finite() && t1.is_finite()).then_some({
        [
            (a.0 + t0 * dx, a.1 + t0 * dy),
            (a.0 + t1 * dx, a.1 + t1 * dy),
        ]
    })
}

/// Height (pixels) of a GIF frame's caption band: the title on one line, the frame's label
/// below it.
pub const GIF_CAPTION_H: u32 = 46;

/// `text` at the largest font size from `max` down to 9 px whose width is at most `width`
/// pixels (measured with the font, as drawn); at 9 px still too wide, cut at the end with "…"
/// until it fits.
pub(crate) fn fit_text(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    text: &str,
    max: u32,
    width: u32,
) -> (String, u32) {
    register_fonts();
    let w = |t: &str, px: u32| {
        area.estimate_text_size(t, &TextStyle::from((FONT, px).into_font()))
            .map_or(u32::MAX, |s| s.0)
    };
    for px in (9..=max.max(9)).rev() {
        if w(text, px) <= width {
            return (text.to_string(), px);
        }
    }
    let mut chars: Vec<char> = text.chars().collect();
    while !chars.is_empty() {
        chars.pop();
        let t: String = chars.iter().collect::<String>() + "…";
        if w(&t, 9) <= width {
            return (t, 9);
        }
    }
    (String::new(), 9)
}

/// Draws a caption line `(text, font size)` centred at `y` pixels from the band's top.
fn draw_caption(
    band: &DrawingArea<BitMapBackend<'_>, Shift>,
    (text, px): &(String, u32),
    y: i32,
    path: &Path,
) -> Result<()> {
    if text.is_empty() {
        return Ok(());
    }
    let style = TextStyle::from((FONT, *px).into_font()).color(&BLACK).pos(
        plotters::style::text_anchor::Pos::new(
            plotters::style::text_anchor::HPos::Center,
            plotters::style::text_anchor::VPos::Top,
        ),
    );
    let x = band.dim_in_pixel().0 as i32 / 2;
    band.draw_text(text, &style, (x, y))
        .map_err(|x| pe(path, x))
}

/// Writes an animated GIF of `frames` at `size` pixels, `delay_ms` per frame, with the same
/// axes in every frame (the bounding box of all links, joints and traces, padded, with equal
/// scales on x and y): slope in brown, links black, joints as dots, swing-foot trace in blue.
/// The caption band on top holds `title` and, below it, the frame's label, each at the
/// largest font size (18 and 14 px at most) that fits the picture's width (`fit_text`).
pub fn animate_gif(
    path: impl AsRef<Path>,
    frames: &[Frame],
    size: (u32, u32),
    delay_ms: u32,
    title: &str,
) -> Result<()> {
    let path = path.as_ref();
    if frames.is_empty() || size.0 < 64 || size.1 < GIF_CAPTION_H + 64 {
        return Err(StoreError::invalid(
            "animation",
            format!(
                "need at least one frame and at least 64 × {} pixels (got {} frames, {} × {})",
                GIF_CAPTION_H + 64,
                frames.len(),
                size.0,
                size.1
            ),
        ));
    }
    let pts = || {
        frames.iter().flat_map(|f| {
            f.links
                .iter()
                .flat_map(|(a, b)| [*a, *b])
                .chain(f.joints.iter().copied())
                .chain(f.trace.iter().copied())
        })
    };
    let (xr, yr) = match (range_of(pts().map(|p| p.0)), range_of(pts().map(|p| p.1))) {
        (Some(x), Some(y)) => (pad(x, 0.1), pad(y, 0.15)),
        _ => {
            return Err(StoreError::invalid(
                "animation",
                "no finite coordinates in the frames",
            ))
        }
    };
    // Equal scales: widen the narrower extent to the picture's aspect ratio (the plotting area
    // is the picture minus the caption band).
    let (w, h) = (
        size.0 as f64 - 20.0,
        size.1 as f64 - GIF_CAPTION_H as f64 - 20.0,
    );
    let (sx, sy) = ((xr.1 - xr.0) / w, (yr.1 - yr.0) / h);
    let s = sx.max(sy);
    let (cx, cy) = ((xr.0 + xr.1) / 2.0, (yr.0 + yr.1) / 2.0);
    let (x0, x1) = (cx - s * w / 2.0, cx + s * w / 2.0);
    let (y0, y1) = (cy - s * h / 2.0, cy + s * h / 2.0);
    register_fonts();
    let pic = Staged::picture(path)?;
    let tmp = pic.path().to_path_buf();
    let root = BitMapBackend::gif(&tmp, size, delay_ms)
        .map_err(|x| pe(path, x))?
        .into_drawing_area();
    let (band, body) = root.split_vertically(GIF_CAPTION_H);
    let title_line = fit_text(&band, title, 18, size.0.saturating_sub(16));
    for f in frames {
        root.fill(&WHITE).map_err(|x| pe(path, x))?;
        draw_caption(&band, &title_line, 4, path)?;
        let label_line = fit_text(&band, &f.label, 14, size.0.saturating_sub(16));
        draw_caption(&band, &label_line, 26, path)?;
        let mut chart = ChartBuilder::on(&body)
            .margin(10)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|x| pe(path, x))?;
        if let Some(seg) = clip_line(f.slope.0, f.slope.1, x0, x1, y0, y1) {
            chart
                .draw_series(LineSeries::new(seg, RGBColor(140, 90, 40).stroke_width(3)))
                .map_err(|x| pe(path, x))?;
        }
        chart
            .draw_series(LineSeries::new(
                f.trace.iter().copied(),
                RGBColor(31, 119, 180).stroke_width(1),
            ))
            .map_err(|x| pe(path, x))?;
        chart
            .draw_series(
                f.links
                    .iter()
                    .map(|&(a, b)| PathElement::new([a, b], BLACK.stroke_width(3))),
            )
            .map_err(|x| pe(path, x))?;
        chart
            .draw_series(
                f.joints
                    .iter()
                    .map(|&p| Circle::new(p, 5, RGBColor(214, 39, 40).filled())),
            )
            .map_err(|x| pe(path, x))?;
        root.present().map_err(|x| pe(path, x))?;
    }
    // The GIF encoder writes its trailer when the backend is dropped.
    drop(root);
    pic.commit(path)
}
