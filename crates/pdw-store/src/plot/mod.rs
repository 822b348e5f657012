//! Pictures: basin heatmaps, bifurcation diagrams, line charts (PNG) and gait animations (GIF).
//!
//! Drawn with `plotters`' pure-Rust bitmap backend. Text uses DejaVu Sans embedded in the
//! binary (`dejavu` crate) and registered with `plotters::style::register_font`, so nothing is
//! looked up on the system.
//!
//! One submodule per kind of picture: basin heatmaps (`basin`), bifurcation diagrams
//! (`bifurcation`), basin stability over a parameter (`stability`), line charts (`lines`) and
//! gait animations (`animation`); the fonts, colours, tick labels and grid helpers they share
//! are here.

use std::path::Path;
use std::sync::Once;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;

use crate::{Result, StoreError};

mod animation;
mod basin;
mod bifurcation;
mod lines;
mod stability;

#[doc(hidden)] // pub for the crate's tests (tests/internals.rs), not part of the API
pub use animation::clip_line;
pub use animation::{animate_gif, Frame, GIF_CAPTION_H};
pub use basin::{plot_basin, plot_basin_attractors};
#[doc(hidden)] // pub for the crate's tests (tests/internals.rs), not part of the API
pub use bifurcation::stability_runs;
pub use bifurcation::{invalid_reasons, plot_bifurcation};
#[doc(hidden)] // pub for the crate's tests (tests/internals.rs), not part of the API
pub use lines::legend_corner;
pub use lines::{plot_lines, plot_lines_marked, MarkerShape, Markers};
pub use stability::plot_basin_stability;

/// Pixel size of [`plot_basin`]'s PNG.
pub const BASIN_PNG_SIZE: (u32, u32) = (960, 720);
/// Pixel size of [`plot_bifurcation`]'s PNG.
pub const BIFURCATION_PNG_SIZE: (u32, u32) = (900, 1380);
/// Pixel size of [`plot_basin_stability`]'s PNG.
pub const STABILITY_PNG_SIZE: (u32, u32) = (900, 960);
/// Pixel size of [`plot_lines`]' PNG.
pub const LINES_PNG_SIZE: (u32, u32) = (900, 640);

pub(crate) const FONT: &str = "sans-serif";

pub(crate) fn register_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The embedded fonts are valid TrueType files; failure would only disable text.
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
        let _ = plotters::style::register_font(FONT, FontStyle::Bold, dejavu::sans::bold());
    });
}

/// A drawing error, told in words: plotters' backend errors embed the image encoder's Debug
/// text (`ImageError(IoError(Custom { .. }))`); an operating-system error inside is reported
/// by its own message instead.
pub(crate) fn pe<E: std::fmt::Display>(path: &Path, e: E) -> StoreError {
    let text = e.to_string();
    let os = text.find("(os error ").and_then(|i| {
        let digits: String = text[i + 10..]
            .chars()
            .take_while(|c| c.is_ascii_digit())
            .collect();
        digits.parse::<i32>().ok()
    });
    let detail = match os {
        Some(code) => std::io::Error::from_raw_os_error(code).to_string(),
        None if text.contains("ImageError") || text.contains("Custom {") => {
            "the image encoder failed to write the file".to_string()
        }
        None => text,
    };
    StoreError::Plot {
        path: path.to_path_buf(),
        detail,
    }
}

/// Compact tick label: plain decimals for 1e-3 ≤ |v| < 1e4 (up to 4 decimals, trailing zeros
/// dropped), otherwise `1.5e-7` style.
#[doc(hidden)] // pub for the crate's tests (tests/internals.rs), not part of the API
pub fn tick(v: &f64) -> String {
    let a = v.abs();
    if *v == 0.0 {
        "0".into()
    } else if (1e-3..1e4).contains(&a) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" || s.is_empty() {
            "0".into()
        } else {
            s.to_string()
        }
    } else {
        let s = format!("{v:.1e}");
        s.replace(".0e", "e")
    }
}

/// Tick label on a log axis: only 1, 2 and 5 times a power of ten are labelled (plotters puts
/// a tick at every integer multiple, which crowds the labels).
#[doc(hidden)] // pub for the crate's tests (tests/internals.rs), not part of the API
pub fn tick_log(v: &f64) -> String {
    if *v <= 0.0 {
        return String::new();
    }
    let m = v / 10f64.powf(v.log10().floor());
    if [1.0, 2.0, 5.0, 10.0]
        .iter()
        .any(|k| (m - k).abs() < 1e-6 * k)
    {
        tick(v)
    } else {
        String::new()
    }
}

pub(crate) fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

/// Colours for the outcomes of a legend: `gait` green, `other` blue, names containing
/// `fall` reds and oranges (in legend order), `timeout` grey, `nonfinite` black, anything else
/// purple/teal/pink. Returned in legend order as `(code, [r, g, b])`.
pub fn outcome_colours(legend: &[(u8, String)]) -> Vec<(u8, [u8; 3])> {
    // one per fall class of the basin's fixed outcomes (eight), so that none shares a colour
    const FALLS: [[u8; 3]; 8] = [
        [214, 39, 40],
        [255, 127, 14],
        [166, 54, 3],
        [250, 170, 100],
        [140, 20, 40],
        [240, 90, 70],
        [200, 30, 120],
        [230, 190, 40],
    ];
    const OTHERS: [[u8; 3]; 4] = [
        [148, 103, 189],
        [23, 190, 207],
        [227, 119, 194],
        [188, 189, 34],
    ];
    let (mut nf, mut no) = (0, 0);
    legend
        .iter()
        .map(|(c, name)| {
            let n = name.to_ascii_lowercase();
            let col = if n == "gait" {
                [44, 160, 44]
            } else if n == "other" {
                [31, 119, 180]
            } else if n.contains("fall") {
                nf += 1;
                FALLS[(nf - 1) % FALLS.len()]
            } else if n == "timeout" {
                [150, 150, 150]
            } else if n == "nonfinite" {
                [0, 0, 0]
            } else {
                no += 1;
                OTHERS[(no - 1) % OTHERS.len()]
            };
            (*c, col)
        })
        .collect()
}

/// Index of the grid point nearest to `v` (grid monotone, ascending or descending).
#[doc(hidden)] // pub for the crate's tests (tests/internals.rs), not part of the API
pub fn nearest(grid: &[f64], v: f64) -> usize {
    let asc = grid.len() < 2 || grid[0] <= grid[grid.len() - 1];
    let k = if asc {
        grid.partition_point(|&g| g < v)
    } else {
        grid.partition_point(|&g| g > v)
    };
    match k {
        0 => 0,
        k if k >= grid.len() => grid.len() - 1,
        k => {
            if (grid[k] - v).abs() < (v - grid[k - 1]).abs() {
                k
            } else {
                k - 1
            }
        }
    }
}

/// Extent of a grid of cell centres: from half a spacing before the first to half after the last.
pub(crate) fn cell_extent(g: &[f64]) -> (f64, f64) {
    let (lo, hi) = g
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let half = if g.len() > 1 {
        (hi - lo) / (g.len() - 1) as f64 / 2.0
    } else {
        0.5
    };
    let half = if half > 0.0 { half } else { 0.5 };
    (lo - half, hi + half)
}
/// Paints the plotting area of a heatmap pixel by pixel: each pixel shows the grid cell whose
/// centre is nearest (grids `xs` across, `ys` up, over the extent `((x0, x1), (y0, y1))`), in
/// `colour(row, col)`; works for grids coarser or finer than the picture.
pub(crate) fn paint_cells(
    area: &DrawingArea<BitMapBackend<'_>, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    (xs, ys): (&[f64], &[f64]),
    ((x0, x1), (y0, y1)): ((f64, f64), (f64, f64)),
    colour: impl Fn(usize, usize) -> [u8; 3],
    path: &Path,
) -> Result<()> {
    let (pxr, pyr) = area.get_pixel_range();
    let (w, h) = ((pxr.end - pxr.start) as f64, (pyr.end - pyr.start) as f64);
    let pix = area.strip_coord_spec();
    let cols: Vec<usize> = (0..w as i32)
        .map(|i| nearest(xs, x0 + (i as f64 + 0.5) / w * (x1 - x0)))
        .collect();
    for j in 0..h as i32 {
        let row = nearest(ys, y1 - (j as f64 + 0.5) / h * (y1 - y0));
        for (i, &col) in cols.iter().enumerate() {
            let c = colour(row, col);
            pix.draw_pixel((i as i32, j), &rgb(c))
                .map_err(|x| pe(path, x))?;
        }
    }
    Ok(())
}

/// A heatmap's legend of colour swatches: from `top` down, 30 px apart, a filled square with a
/// black border and its label at `font_px`.
pub(crate) fn draw_swatches(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    entries: &[(String, [u8; 3])],
    top: i32,
    font_px: u32,
    path: &Path,
) -> Result<()> {
    for (k, (label, col)) in entries.iter().enumerate() {
        let y = top + 30 * k as i32;
        area.draw(&Rectangle::new([(10, y), (32, y + 20)], rgb(*col).filled()))
            .map_err(|x| pe(path, x))?;
        area.draw(&Rectangle::new(
            [(10, y), (32, y + 20)],
            BLACK.stroke_width(1),
        ))
        .map_err(|x| pe(path, x))?;
        area.draw(&Text::new(
            label.clone(),
            (40, y + 2),
            (FONT, font_px).into_font(),
        ))
        .map_err(|x| pe(path, x))?;
    }
    Ok(())
}

/// Ring colour of a physically invalid orbit's marks.
const INVALID_RING: RGBColor = RGBColor(200, 0, 0);
/// Colours of the branches of a bifurcation diagram and of the polylines of [`plot_lines`]
/// (ten, so that a work-precision chart's series each get their own; there an eleventh series
/// starts over with square markers).
const SERIES_COLOURS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
];
fn range_of(vals: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = vals
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if lo.is_finite() {
        Some(if hi > lo {
            (lo, hi)
        } else {
            (lo - 0.5 * lo.abs().max(1e-3), hi + 0.5 * hi.abs().max(1e-3))
        })
    } else {
        None
    }
}

fn pad((lo, hi): (f64, f64), f: f64) -> (f64, f64) {
    let d = (hi - lo) * f;
    (lo - d, hi + d)
}
