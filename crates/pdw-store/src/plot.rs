//! Pictures: basin heatmaps, bifurcation diagrams, line charts (PNG) and gait animations (GIF).
//!
//! Drawn with `plotters`' pure-Rust bitmap backend. Text uses DejaVu Sans embedded in the
//! binary (`dejavu` crate) and registered with `plotters::style::register_font`, so nothing is
//! looked up on the system.

use std::path::Path;
use std::sync::Once;

use ndarray::ArrayView2;
use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;

use crate::basin::{Attractor, BasinHeader, NOT_COMPUTED};
use crate::h5util::Staged;
use crate::sweep::{Branch, SweepData};
use crate::{Result, StoreError};

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
pub(crate) fn tick(v: &f64) -> String {
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
fn tick_log(v: &f64) -> String {
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
pub(crate) fn nearest(grid: &[f64], v: f64) -> usize {
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

/// Writes a PNG ([`BASIN_PNG_SIZE`]) heatmap of the outcome codes `outcome` (ny × nx, row i =
/// `header.y[i]`), axes labelled with the header's coordinate names, a legend of the outcomes
/// present with their fractions, and `marker` (e.g. the fixed point) as a ringed cross.
pub fn plot_basin(
    path: impl AsRef<Path>,
    header: &BasinHeader,
    outcome: ArrayView2<u8>,
    marker: Option<(f64, f64)>,
    title: &str,
) -> Result<()> {
    let marks: Vec<Marks> = marker
        .map(|m| Marks {
            name: String::new(),
            label: "fixed point".into(),
            points: vec![m],
            colour: None,
            cloud: false,
            invalid: None,
        })
        .into_iter()
        .collect();
    plot_basin_marked(path, header, outcome, &marks, title)
}

/// Points marked on a basin picture.
struct Marks {
    /// The attractor's (outcome's) name, empty for a plain marker.
    name: String,
    label: String,
    points: Vec<(f64, f64)>,
    /// Fill of the ring (the attractor's basin colour), white if `None`.
    colour: Option<[u8; 3]>,
    /// A sample of a chaotic attractor: small dots, not ringed crosses.
    cloud: bool,
    /// What makes the orbit physically invalid: drawn hollow with a red ring, the reasons
    /// named under the legend.
    invalid: Option<Vec<String>>,
}

/// Ring colour of a physically invalid orbit's marks.
const INVALID_RING: RGBColor = RGBColor(200, 0, 0);

/// [`plot_basin`] with every attractor's points marked: the points of a periodic orbit as
/// ringed crosses filled with its basin's colour (the legend entry of the same name), a chaotic
/// attractor's sample as small black dots. Points are projected on the grid's two coordinates
/// (`header.state_names` must name `x_name` and `y_name`, optionally followed by a unit suffix
/// ` [unit]`; otherwise nothing is marked).
pub fn plot_basin_attractors(
    path: impl AsRef<Path>,
    header: &BasinHeader,
    outcome: ArrayView2<u8>,
    attractors: &[Attractor],
    title: &str,
) -> Result<()> {
    // Axis names may carry a unit suffix for the axis label ("theta [rad]").
    let bare = |n: &str| n.split(" [").next().unwrap_or(n).to_string();
    let ix = header
        .state_names
        .iter()
        .position(|n| *n == bare(&header.x_name));
    let iy = header
        .state_names
        .iter()
        .position(|n| *n == bare(&header.y_name));
    let colours = outcome_colours(&header.legend);
    let marks: Vec<Marks> = match (ix, iy) {
        (Some(ix), Some(iy)) => attractors
            .iter()
            .map(|a| {
                let code = header
                    .legend
                    .iter()
                    .find(|(_, n)| *n == a.name)
                    .map(|(c, _)| *c);
                let colour = code.and_then(|c| colours.iter().find(|(k, _)| *k == c).map(|x| x.1));
                let cloud = a.period_strides == 0;
                let invalid = a.validity.reasons().map(<[String]>::to_vec);
                Marks {
                    name: a.name.clone(),
                    label: match (cloud, &invalid) {
                        (true, _) => format!("{} (sample)", a.name),
                        (false, None) => format!("{} orbit", a.name),
                        (false, Some(_)) => format!("{} orbit (invalid)", a.name),
                    },
                    points: a
                        .section
                        .iter()
                        .filter(|p| p.len() > ix.max(iy))
                        .map(|p| (p[ix], p[iy]))
                        .collect(),
                    colour,
                    cloud,
                    invalid,
                }
            })
            .collect(),
        _ => Vec::new(),
    };
    plot_basin_marked(path, header, outcome, &marks, title)
}

fn plot_basin_marked(
    path: impl AsRef<Path>,
    header: &BasinHeader,
    outcome: ArrayView2<u8>,
    marks: &[Marks],
    title: &str,
) -> Result<()> {
    let path = path.as_ref();
    let (ny, nx) = outcome.dim();
    if ny != header.ny() || nx != header.nx() {
        return Err(StoreError::invalid(
            "basin plot",
            format!(
                "outcome is {ny} × {nx} but the grid is {} × {}",
                header.ny(),
                header.nx()
            ),
        ));
    }
    register_fonts();
    let pic = Staged::picture(path)?;
    let tmp = pic.path().to_path_buf();
    let root = BitMapBackend::new(&tmp, BASIN_PNG_SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|x| pe(path, x))?;
    let (left, right) = root.split_horizontally(BASIN_PNG_SIZE.0 - 220);
    let (x0, x1) = cell_extent(&header.x);
    let (y0, y1) = cell_extent(&header.y);
    let mut chart = ChartBuilder::on(&left)
        .caption(title, (FONT, 22))
        .margin(12)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|x| pe(path, x))?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .x_desc(header.x_name.as_str())
        .y_desc(header.y_name.as_str())
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 18))
        .draw()
        .map_err(|x| pe(path, x))?;

    let colours = outcome_colours(&header.legend);
    let mut lut = [[255u8, 255, 255]; 256];
    for (c, col) in &colours {
        lut[*c as usize] = *col;
    }
    // One pixel at a time: each pixel shows the cell whose centre is nearest (works for grids
    // coarser or finer than the picture).
    {
        let area = chart.plotting_area();
        let (pxr, pyr) = area.get_pixel_range();
        let (w, h) = ((pxr.end - pxr.start) as f64, (pyr.end - pyr.start) as f64);
        let pix = area.strip_coord_spec();
        let cols: Vec<usize> = (0..w as i32)
            .map(|i| nearest(&header.x, x0 + (i as f64 + 0.5) / w * (x1 - x0)))
            .collect();
        for j in 0..h as i32 {
            let row = nearest(&header.y, y1 - (j as f64 + 0.5) / h * (y1 - y0));
            for (i, &col) in cols.iter().enumerate() {
                let c = lut[outcome[[row, col]] as usize];
                pix.draw_pixel((i as i32, j), &rgb(c))
                    .map_err(|x| pe(path, x))?;
            }
        }
    }
    let inside = |&(x, y): &(f64, f64)| {
        x.is_finite() && y.is_finite() && (x0..=x1).contains(&x) && (y0..=y1).contains(&y)
    };
    for mk in marks {
        let pts: Vec<(f64, f64)> = mk.points.iter().copied().filter(inside).collect();
        if mk.cloud {
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 1, BLACK.filled())))
                .map_err(|x| pe(path, x))?;
            continue;
        }
        let (fill, ring) = mark_style(mk);
        for &(mx, my) in &pts {
            chart
                .draw_series([
                    EmptyElement::at((mx, my)) + Circle::new((0, 0), 9, fill.filled()),
                    EmptyElement::at((mx, my)) + Circle::new((0, 0), 9, WHITE.stroke_width(4)),
                    EmptyElement::at((mx, my)) + Circle::new((0, 0), 9, ring.stroke_width(2)),
                ])
                .map_err(|x| pe(path, x))?;
            chart
                .draw_series([Cross::new((mx, my), 6, BLACK.stroke_width(2))])
                .map_err(|x| pe(path, x))?;
        }
    }

    // Legend: outcomes present, with their fraction of computed cells.
    let total = outcome.len().max(1) as f64;
    let mut counts = [0usize; 256];
    outcome.iter().for_each(|&c| counts[c as usize] += 1);
    let mut entries: Vec<(String, [u8; 3])> = colours
        .iter()
        .filter(|(c, _)| counts[*c as usize] > 0)
        .map(|(c, col)| {
            let name = header.outcome_name(*c).unwrap_or("?");
            let invalid = marks.iter().any(|m| m.name == name && m.invalid.is_some());
            (
                format!(
                    "{name} {:.1}%{}",
                    100.0 * counts[*c as usize] as f64 / total,
                    if invalid { " (invalid)" } else { "" }
                ),
                *col,
            )
        })
        .collect();
    if counts[NOT_COMPUTED as usize] > 0 {
        entries.push((
            format!(
                "not computed {:.1}%",
                100.0 * counts[NOT_COMPUTED as usize] as f64 / total
            ),
            [255, 255, 255],
        ));
    }
    let legend_top = 60;
    for (k, (label, col)) in entries.iter().enumerate() {
        let y = legend_top + 30 * k as i32;
        right
            .draw(&Rectangle::new([(10, y), (32, y + 20)], rgb(*col).filled()))
            .map_err(|x| pe(path, x))?;
        right
            .draw(&Rectangle::new(
                [(10, y), (32, y + 20)],
                BLACK.stroke_width(1),
            ))
            .map_err(|x| pe(path, x))?;
        right
            .draw(&Text::new(
                label.clone(),
                (40, y + 2),
                (FONT, 16).into_font(),
            ))
            .map_err(|x| pe(path, x))?;
    }
    for (k, mk) in marks.iter().enumerate() {
        let y = legend_top + 30 * (entries.len() + k) as i32 + 10;
        if mk.cloud {
            for d in [-6, 0, 6] {
                right
                    .draw(&Circle::new((21 + d, y + 10 + d / 2), 2, BLACK.filled()))
                    .map_err(|x| pe(path, x))?;
            }
        } else {
            let (fill, ring) = mark_style(mk);
            right
                .draw(&Circle::new((21, y + 10), 8, fill.filled()))
                .map_err(|x| pe(path, x))?;
            right
                .draw(&Circle::new((21, y + 10), 8, ring.stroke_width(2)))
                .map_err(|x| pe(path, x))?;
            right
                .draw(&Cross::new((21, y + 10), 5, BLACK.stroke_width(2)))
                .map_err(|x| pe(path, x))?;
        }
        right
            .draw(&Text::new(
                mk.label.clone(),
                (40, y + 2),
                (FONT, 16).into_font(),
            ))
            .map_err(|x| pe(path, x))?;
    }
    let below = legend_top + 30 * (entries.len() + marks.len()) as i32 + 20;
    draw_invalid_reasons(&right, marks, below, path)?;
    root.present().map_err(|x| pe(path, x))?;
    pic.commit(path)
}

/// Fill and ring of a periodic orbit's marks: its basin's colour (white without one) ringed in
/// black, or hollow (white) ringed in red when the orbit is physically invalid.
fn mark_style(mk: &Marks) -> (RGBColor, RGBColor) {
    match mk.invalid {
        Some(_) => (WHITE, INVALID_RING),
        None => (rgb(mk.colour.unwrap_or([255, 255, 255])), BLACK),
    }
}

/// Under the legend, in red: for each physically invalid orbit its name and what fails, one
/// reason per line.
fn draw_invalid_reasons(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    marks: &[Marks],
    top: i32,
    path: &Path,
) -> Result<()> {
    let style = (FONT, 14).into_font().color(&INVALID_RING);
    let mut y = top;
    for mk in marks {
        let Some(reasons) = &mk.invalid else {
            continue;
        };
        let lines = std::iter::once(format!("{}: physically invalid,", mk.name))
            .chain(reasons.iter().map(|r| format!("  {r}")));
        for line in lines {
            area.draw(&Text::new(line, (10, y), style.clone()))
                .map_err(|x| pe(path, x))?;
            y += 18;
        }
    }
    Ok(())
}

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

/// Splits a branch into maximal runs of equal stability; consecutive runs share their boundary
/// point so the curve stays connected.
fn stability_runs(stable: &[bool]) -> Vec<(std::ops::Range<usize>, bool)> {
    let mut out = Vec::new();
    let mut start = 0;
    for i in 1..=stable.len() {
        if i == stable.len() || stable[i] != stable[start] {
            out.push((start..(i + 1).min(stable.len()), stable[start]));
            start = i;
        }
    }
    out
}

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

/// A panel of [`plot_bifurcation`]: the swept parameter across, `Y` up.
type BifPanel<'a, 'b, Y> = ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, Y>>;

/// The three panels of [`plot_bifurcation`], top to bottom.
struct BifPanels<'a, 'b: 'a> {
    /// |λ| (log scale).
    top: BifPanel<'a, 'b, LogCoord<f64>>,
    /// Re λ.
    mid: BifPanel<'a, 'b, RangedCoordf64>,
    /// The section coordinate.
    bot: BifPanel<'a, 'b, RangedCoordf64>,
}

/// Writes a three-panel PNG ([`BIFURCATION_PNG_SIZE`]): top, the moduli of the Floquet
/// multipliers against the swept parameter (log scale) with the stability boundary |λ| = 1;
/// middle, their real parts (signed) with horizontal lines at λ = −1 (red: a real multiplier
/// crossing it is a period doubling) and λ = +1 (black: a fold or branch point), so the two are
/// told apart; bottom, section coordinate number `coordinate` against the parameter (every one
/// of the K points of a measured period-K branch), with the orbit diagram's samples as grey
/// dots if present. Stable stretches solid, unstable dashed; period doublings marked by red
/// triangles, other bifurcations by black diamonds; points whose orbit is physically invalid
/// (a stride where the ground, a knee lock or an impact must pull, or the swing foot scuffs:
/// [`invalid_reasons`]) ringed by hollow circles on the |λ| and section panels, with a legend
/// entry naming what fails.
pub fn plot_bifurcation(path: impl AsRef<Path>, data: &SweepData, coordinate: usize) -> Result<()> {
    let path = path.as_ref();
    data.validate()?;
    if coordinate >= data.section_names.len() {
        return Err(StoreError::invalid(
            "bifurcation plot",
            format!(
                "coordinate {coordinate} out of range: section has {:?}",
                data.section_names
            ),
        ));
    }
    register_fonts();
    let pic = Staged::picture(path)?;
    let tmp = pic.path().to_path_buf();
    let root = BitMapBackend::new(&tmp, BIFURCATION_PNG_SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|x| pe(path, x))?;
    let panels = root.split_evenly((3, 1));

    let orbit_params = data.orbit.iter().flat_map(|o| o.parameter.iter().copied());
    let pr = range_of(
        data.branches
            .iter()
            .flat_map(|b| b.parameter.iter().copied())
            .chain(orbit_params),
    )
    .unwrap_or((0.0, 1.0));
    let pr = pad(pr, 0.02);

    let top = bifurcation_moduli_panel(&panels[0], data, pr, path)?;
    let mid = bifurcation_real_panel(&panels[1], data, pr, path)?;
    let bot = bifurcation_section_panel(&panels[2], data, coordinate, pr, path)?;
    let mut charts = BifPanels { top, mid, bot };
    draw_bifurcation_branches(&mut charts, data, coordinate, path)?;
    draw_invalid_points(&mut charts, data, coordinate, path)?;
    draw_bifurcation_points(&mut charts, data, coordinate, path)?;
    draw_bifurcation_legends(&mut charts, path)?;
    root.present().map_err(|x| pe(path, x))?;
    pic.commit(path)
}

/// Top: |λ| (log scale, the range of the moduli widened to include 0.5 … 2) with the line
/// |λ| = 1.
fn bifurcation_moduli_panel<'a, 'b>(
    area: &'a DrawingArea<BitMapBackend<'b>, Shift>,
    data: &SweepData,
    pr: (f64, f64),
    path: &Path,
) -> Result<BifPanel<'a, 'b, LogCoord<f64>>> {
    // Top: |λ|.
    let mods = data.branches.iter().flat_map(|b| {
        b.multipliers
            .iter()
            .flat_map(|v| v.iter().map(|z| z.0.hypot(z.1)))
    });
    let (mlo, mhi) = range_of(mods.filter(|m| *m > 0.0)).unwrap_or((0.1, 10.0));
    let (mlo, mhi) = ((mlo.min(0.5) / 1.5).max(1e-8), (mhi.max(2.0) * 1.5));
    let mut top = ChartBuilder::on(area)
        .caption(format!("{}: Floquet multipliers", data.model), (FONT, 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(75)
        .build_cartesian_2d(pr.0..pr.1, (mlo..mhi).log_scale())
        .map_err(|x| pe(path, x))?;
    top.configure_mesh()
        .y_labels(12)
        .x_label_formatter(&tick)
        .y_label_formatter(&tick_log)
        .x_desc(data.parameter.as_str())
        .y_desc("|λ|")
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 17))
        .draw()
        .map_err(|x| pe(path, x))?;
    top.draw_series(LineSeries::new(
        [(pr.0, 1.0), (pr.1, 1.0)],
        BLACK.stroke_width(1),
    ))
    .map_err(|x| pe(path, x))?
    .label("|λ| = 1")
    .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK));
    Ok(top)
}

/// Middle: Re λ (the range of the real parts widened to include ±1.2), with the
/// period-doubling (−1) and fold (+1) lines.
fn bifurcation_real_panel<'a, 'b>(
    area: &'a DrawingArea<BitMapBackend<'b>, Shift>,
    data: &SweepData,
    pr: (f64, f64),
    path: &Path,
) -> Result<BifPanel<'a, 'b, RangedCoordf64>> {
    // Middle: Re λ, with the period-doubling (−1) and fold (+1) lines.
    let res = data
        .branches
        .iter()
        .flat_map(|b| b.multipliers.iter().flat_map(|v| v.iter().map(|z| z.0)));
    let (rlo, rhi) = range_of(res).unwrap_or((-1.0, 1.0));
    let rr = pad((rlo.min(-1.2), rhi.max(1.2)), 0.05);
    let mut mid = ChartBuilder::on(area)
        .caption(
            format!("{}: real parts of the multipliers", data.model),
            (FONT, 20),
        )
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(75)
        .build_cartesian_2d(pr.0..pr.1, rr.0..rr.1)
        .map_err(|x| pe(path, x))?;
    mid.configure_mesh()
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .x_desc(data.parameter.as_str())
        .y_desc("Re λ")
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 17))
        .draw()
        .map_err(|x| pe(path, x))?;
    mid.draw_series(DashedLineSeries::new(
        [(pr.0, -1.0), (pr.1, -1.0)],
        8,
        5,
        RED.stroke_width(2),
    ))
    .map_err(|x| pe(path, x))?
    .label("λ = −1: period doubling")
    .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], RED.stroke_width(2)));
    mid.draw_series(DashedLineSeries::new(
        [(pr.0, 1.0), (pr.1, 1.0)],
        8,
        5,
        BLACK.stroke_width(2),
    ))
    .map_err(|x| pe(path, x))?
    .label("λ = +1: fold / branch point")
    .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK.stroke_width(2)));
    Ok(mid)
}

/// Bottom: section coordinate number `coordinate` (its range over the branches, their
/// measured orbits and the orbit diagram), with the orbit diagram's samples as grey dots.
fn bifurcation_section_panel<'a, 'b>(
    area: &'a DrawingArea<BitMapBackend<'b>, Shift>,
    data: &SweepData,
    coordinate: usize,
    pr: (f64, f64),
    path: &Path,
) -> Result<BifPanel<'a, 'b, RangedCoordf64>> {
    // Bottom: section coordinate.
    let sec_vals = data
        .branches
        .iter()
        .flat_map(|b| b.section.iter().map(move |s| s[coordinate]))
        .chain(
            data.branches
                .iter()
                .flat_map(|b| b.orbit.iter().flatten().map(move |s| s[coordinate])),
        )
        .chain(
            data.orbit
                .iter()
                .flat_map(|o| o.points.iter().flatten().copied()),
        );
    let sr = pad(range_of(sec_vals).unwrap_or((0.0, 1.0)), 0.05);
    let mut bot = ChartBuilder::on(area)
        .caption(
            format!("{} on the section", data.section_names[coordinate]),
            (FONT, 20),
        )
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(75)
        .build_cartesian_2d(pr.0..pr.1, sr.0..sr.1)
        .map_err(|x| pe(path, x))?;
    bot.configure_mesh()
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .x_desc(data.parameter.as_str())
        .y_desc(data.section_names[coordinate].as_str())
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 17))
        .draw()
        .map_err(|x| pe(path, x))?;
    if let Some(o) = &data.orbit {
        let pts = o.parameter.iter().zip(&o.points).flat_map(|(&p, row)| {
            row.iter()
                .filter(|v| v.is_finite())
                .map(move |&v| Circle::new((p, v), 1, RGBColor(110, 110, 110).filled()))
        });
        bot.draw_series(pts)
            .map_err(|x| pe(path, x))?
            .label(format!("orbit diagram ({})", o.coordinate))
            .legend(|(x, y)| Circle::new((x + 10, y), 2, RGBColor(110, 110, 110).filled()));
    }
    Ok(bot)
}

/// Each branch in its colour on all three panels, run by run of equal stability (stable solid
/// and thicker, unstable dashed), with its legend entry on the bottom panel.
fn draw_bifurcation_branches(
    c: &mut BifPanels,
    data: &SweepData,
    coordinate: usize,
    path: &Path,
) -> Result<()> {
    let BifPanels { top, mid, bot } = c;
    for (bi, b) in data.branches.iter().enumerate() {
        let col = SERIES_COLOURS[bi % SERIES_COLOURS.len()];
        let m = b.multipliers.first().map_or(0, |v| v.len());
        for (run, stable) in stability_runs(&b.stable) {
            let style = col.stroke_width(if stable { 2 } else { 1 });
            for k in 0..m {
                let pts: Vec<(f64, f64)> = run
                    .clone()
                    .map(|i| {
                        (
                            b.parameter[i],
                            b.multipliers[i][k].0.hypot(b.multipliers[i][k].1),
                        )
                    })
                    .filter(|p| p.1 > 0.0 && p.1.is_finite())
                    .collect();
                if stable {
                    top.draw_series(LineSeries::new(pts, style))
                        .map_err(|x| pe(path, x))?;
                } else {
                    top.draw_series(DashedLineSeries::new(pts, 6, 4, style))
                        .map_err(|x| pe(path, x))?;
                }
                let re: Vec<(f64, f64)> = run
                    .clone()
                    .map(|i| (b.parameter[i], b.multipliers[i][k].0))
                    .filter(|p| p.1.is_finite())
                    .collect();
                if stable {
                    mid.draw_series(LineSeries::new(re, style))
                        .map_err(|x| pe(path, x))?;
                } else {
                    mid.draw_series(DashedLineSeries::new(re, 6, 4, style))
                        .map_err(|x| pe(path, x))?;
                }
            }
            // Every point of a measured period-K orbit, else the first.
            let kk = if b.measured() {
                b.period_strides as usize
            } else {
                1
            };
            for j in 0..kk {
                let pts: Vec<(f64, f64)> = run
                    .clone()
                    .map(|i| {
                        let s = b
                            .orbit
                            .get(i)
                            .and_then(|o| o.get(j))
                            .unwrap_or(&b.section[i]);
                        (b.parameter[i], s[coordinate])
                    })
                    .collect();
                if stable {
                    bot.draw_series(LineSeries::new(pts, style))
                        .map_err(|x| pe(path, x))?;
                } else {
                    bot.draw_series(DashedLineSeries::new(pts, 6, 4, style))
                        .map_err(|x| pe(path, x))?;
                }
            }
        }
        // Legend entries (empty series carry the label).
        let label = format!("{} (solid stable, dashed unstable)", b.name);
        bot.draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(|x| pe(path, x))?
            .label(label)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], col.stroke_width(2)));
    }
    Ok(())
}

/// What makes point `i` of branch `b` physically invalid, in words — the flags raised on any
/// of its strides (`"invalid"` for a stride marked invalid without a named flag) — or `None`
/// where every stride is valid, unchecked (a model without constraint forces) or not measured.
pub fn invalid_reasons(b: &Branch, i: usize) -> Option<Vec<&'static str>> {
    let mut reasons = Vec::new();
    for v in b.validity.get(i)?.iter().filter(|v| v.checked && !v.valid) {
        let named = [
            (v.normal_force_negative, "the ground must pull"),
            (v.knee_unlocks, "a knee lock must pull"),
            (v.impact_violation, "an impact must pull"),
            (v.swing_foot_scuffs, "the swing foot scuffs"),
        ];
        for (raised, what) in named {
            if raised && !reasons.contains(&what) {
                reasons.push(what);
            }
        }
        if !named.iter().any(|n| n.0) && !reasons.contains(&"invalid") {
            reasons.push("invalid");
        }
    }
    (!reasons.is_empty()).then_some(reasons)
}

/// Rings every physically invalid point ([`invalid_reasons`]) with a hollow circle in its
/// branch's colour — on the |λ| panel at the leading multiplier, on the section panel at each of
/// its orbit's points — and adds one legend entry naming every reason found.
fn draw_invalid_points(
    c: &mut BifPanels,
    data: &SweepData,
    coordinate: usize,
    path: &Path,
) -> Result<()> {
    let BifPanels { top, bot, .. } = c;
    let mut all: Vec<&'static str> = Vec::new();
    for (bi, b) in data.branches.iter().enumerate() {
        let col = SERIES_COLOURS[bi % SERIES_COLOURS.len()];
        let ring = |p: (f64, f64)| Circle::new(p, 6, col.stroke_width(2));
        for i in 0..b.parameter.len() {
            let Some(reasons) = invalid_reasons(b, i) else {
                continue;
            };
            for r in reasons {
                if !all.contains(&r) {
                    all.push(r);
                }
            }
            let x = b.parameter[i];
            if let Some(z) = b.multipliers.get(i).and_then(|m| m.first()) {
                let m = z.0.hypot(z.1);
                if m > 0.0 && m.is_finite() {
                    top.draw_series([ring((x, m))]).map_err(|e| pe(path, e))?;
                }
            }
            let points = b.orbit.get(i).map_or(&b.section[i..=i], |o| &o[..]);
            for s in points {
                bot.draw_series([ring((x, s[coordinate]))])
                    .map_err(|e| pe(path, e))?;
            }
        }
    }
    if !all.is_empty() {
        bot.draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(|e| pe(path, e))?
            .label(format!("physically invalid: {}", all.join(", ")))
            .legend(|(x, y)| Circle::new((x + 10, y), 5, BLACK.stroke_width(2)));
    }
    Ok(())
}

/// The bifurcations: period doublings as red triangles, others as black diamonds; on the
/// |λ| = 1 line above, on λ = −1 (period doublings) or +1 (folds, branch points) in the middle,
/// on the branch below; with their legend entries on the bottom panel.
fn draw_bifurcation_points(
    c: &mut BifPanels,
    data: &SweepData,
    coordinate: usize,
    path: &Path,
) -> Result<()> {
    let BifPanels { top, mid, bot } = c;
    let is_pd = |k: &str| k.to_ascii_lowercase().contains("period");
    // Bifurcations: on the |λ| = 1 line above, on the branch below.
    for z in &data.bifurcations {
        let x = z.parameter;
        let y = z.section[coordinate];
        if is_pd(&z.kind) {
            top.draw_series([TriangleMarker::new((x, 1.0), 8, RED.filled())])
                .map_err(|x| pe(path, x))?;
            mid.draw_series([TriangleMarker::new((x, -1.0), 8, RED.filled())])
                .map_err(|x| pe(path, x))?;
            bot.draw_series([TriangleMarker::new((x, y), 8, RED.filled())])
                .map_err(|x| pe(path, x))?;
        } else {
            let diamond = || Polygon::new(vec![(0, -7), (7, 0), (0, 7), (-7, 0)], BLACK.filled());
            top.draw_series([EmptyElement::at((x, 1.0)) + diamond()])
                .map_err(|x| pe(path, x))?;
            let k = z.kind.to_ascii_lowercase();
            if k.contains("fold") || k.contains("branch") {
                mid.draw_series([EmptyElement::at((x, 1.0)) + diamond()])
                    .map_err(|x| pe(path, x))?;
            }
            bot.draw_series([EmptyElement::at((x, y)) + diamond()])
                .map_err(|x| pe(path, x))?;
        }
    }
    if data.bifurcations.iter().any(|z| is_pd(&z.kind)) {
        bot.draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(|x| pe(path, x))?
            .label("period doubling")
            .legend(|(x, y)| TriangleMarker::new((x + 10, y), 7, RED.filled()));
    }
    if data.bifurcations.iter().any(|z| !is_pd(&z.kind)) {
        bot.draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(|x| pe(path, x))?
            .label("fold / Neimark–Sacker")
            .legend(|(x, y)| {
                EmptyElement::at((x + 10, y))
                    + Polygon::new(vec![(0, -6), (6, 0), (0, 6), (-6, 0)], BLACK.filled())
            });
    }
    Ok(())
}

/// The three panels' legends: upper left, lower left (middle), upper left.
fn draw_bifurcation_legends(c: &mut BifPanels, path: &Path) -> Result<()> {
    c.top
        .configure_series_labels()
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(|x| pe(path, x))?;
    c.mid
        .configure_series_labels()
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerLeft)
        .draw()
        .map_err(|x| pe(path, x))?;
    c.bot
        .configure_series_labels()
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(|x| pe(path, x))?;
    Ok(())
}

/// Writes a two-panel PNG ([`STABILITY_PNG_SIZE`]) of basin stability against the parameter.
/// Top: the fractions of `data` stacked (bottom to top in column order, each a filled band
/// between the cumulative sums, linear between the parameter values, which are marked by ticks
/// on the top edge), coloured as the basin picture colours the same names
/// ([`outcome_colours`]: the gait green, falls red, timeout grey, `other` blue, other
/// attractors in their own colours); columns that are zero at every value are left out of the
/// legend. An attractor found physically invalid at some value is named `NAME (invalid)` and
/// its band outlined in red. Bottom: each attractor's fraction alone (lines with a marker per
/// value, its own scale), since basins are often a few per cent of the box.
pub fn plot_basin_stability(
    path: impl AsRef<Path>,
    data: &crate::stability::StabilityData,
    x_label: &str,
    title: &str,
) -> Result<()> {
    let path = path.as_ref();
    data.validate()?;
    register_fonts();
    let pic = Staged::picture(path)?;
    let tmp = pic.path().to_path_buf();
    let root = BitMapBackend::new(&tmp, STABILITY_PNG_SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|x| pe(path, x))?;
    let panels = root.split_evenly((2, 1));
    let xr = pad(
        range_of(data.values.iter().copied()).unwrap_or((0.0, 1.0)),
        0.0,
    );
    let mut chart = ChartBuilder::on(&panels[0])
        .caption(title, (FONT, 20))
        .margin(14)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(xr.0..xr.1, 0.0..1.0)
        .map_err(|x| pe(path, x))?;
    chart
        .configure_mesh()
        .x_labels(10)
        .y_labels(11)
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .x_desc(x_label)
        .y_desc("fraction of the box")
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 17))
        .draw()
        .map_err(|x| pe(path, x))?;
    // Stable colours by name: the basin picture's palette over the column names.
    let legend: Vec<(u8, String)> = data
        .columns
        .iter()
        .enumerate()
        .map(|(i, n)| (i as u8, n.clone()))
        .collect();
    let colours = outcome_colours(&legend);
    let n = data.values.len();
    let mut lower = vec![0.0; n];
    for (c, name) in data.columns.iter().enumerate() {
        let upper: Vec<f64> = (0..n).map(|i| lower[i] + data.fractions[i][c]).collect();
        let col = rgb(colours[c].1);
        if data.fractions.iter().any(|r| r[c] > 0.0) {
            let mut poly: Vec<(f64, f64)> = (0..n).map(|i| (data.values[i], upper[i])).collect();
            poly.extend((0..n).rev().map(|i| (data.values[i], lower[i])));
            if data.invalid_column(name) {
                draw_invalid_band(&mut chart, poly, col, name, path)?;
            } else {
                chart
                    .draw_series(std::iter::once(Polygon::new(poly, col.filled())))
                    .map_err(|x| pe(path, x))?
                    .label(name.as_str())
                    .legend(move |(x, y)| {
                        Rectangle::new([(x, y - 5), (x + 16, y + 5)], col.filled())
                    });
            }
        }
        lower = upper;
    }
    // The parameter values computed.
    chart
        .draw_series(
            data.values
                .iter()
                .map(|&v| PathElement::new([(v, 1.0), (v, 0.97)], BLACK.stroke_width(2))),
        )
        .map_err(|x| pe(path, x))?;
    chart
        .configure_series_labels()
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(|x| pe(path, x))?;
    // Bottom: the attractors' fractions on their own scale.
    let att: Vec<usize> = (0..data.columns.len())
        .filter(|&c| data.kinds[c] == "attractor")
        .collect();
    let top = att
        .iter()
        .flat_map(|&c| data.fractions.iter().map(move |r| r[c]))
        .fold(0.0f64, f64::max);
    let top = if top > 0.0 {
        (top * 1.15).min(1.0)
    } else {
        1.0
    };
    let mut bot = ChartBuilder::on(&panels[1])
        .caption("basin stability of each attractor", (FONT, 18))
        .margin(14)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(xr.0..xr.1, 0.0..top)
        .map_err(|x| pe(path, x))?;
    bot.configure_mesh()
        .x_labels(10)
        .y_labels(10)
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .x_desc(x_label)
        .y_desc("fraction of the box")
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 17))
        .draw()
        .map_err(|x| pe(path, x))?;
    for &c in &att {
        let col = rgb(colours[c].1);
        let pts: Vec<(f64, f64)> = (0..n)
            .map(|i| (data.values[i], data.fractions[i][c]))
            .collect();
        bot.draw_series(LineSeries::new(pts.iter().copied(), col.stroke_width(2)))
            .map_err(|x| pe(path, x))?
            .label(stability_label(data, c))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], col.stroke_width(2)));
        bot.draw_series(pts.iter().map(|&p| Circle::new(p, 4, col.filled())))
            .map_err(|x| pe(path, x))?;
    }
    if !att.is_empty() {
        bot.configure_series_labels()
            .label_font((FONT, 14))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|x| pe(path, x))?;
    }
    root.present().map_err(|x| pe(path, x))?;
    pic.commit(path)
}

/// The legend name of column `c`: suffixed ` (invalid)` for a physically invalid attractor.
fn stability_label(data: &crate::stability::StabilityData, c: usize) -> String {
    let name = &data.columns[c];
    if data.invalid_column(name) {
        format!("{name} (invalid)")
    } else {
        name.clone()
    }
}

/// The band `poly` of a physically invalid attractor: filled in its colour, outlined in
/// [`INVALID_RING`] red, named `NAME (invalid)` with a red-bordered legend swatch.
fn draw_invalid_band<'a, 'b: 'a>(
    chart: &mut ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    poly: Vec<(f64, f64)>,
    col: RGBColor,
    name: &str,
    path: &Path,
) -> Result<()> {
    let mut ring = poly.clone();
    ring.push(poly[0]);
    chart
        .draw_series(std::iter::once(Polygon::new(poly, col.filled())))
        .map_err(|x| pe(path, x))?
        .label(format!("{name} (invalid)"))
        .legend(move |(x, y)| {
            EmptyElement::at((x, y))
                + Rectangle::new([(0, -5), (16, 5)], col.filled())
                + Rectangle::new([(0, -5), (16, 5)], INVALID_RING.stroke_width(2))
        });
    chart
        .draw_series(std::iter::once(PathElement::new(
            ring,
            INVALID_RING.stroke_width(2),
        )))
        .map_err(|x| pe(path, x))?;
    Ok(())
}

/// Title and axis labels of a chart.
struct Labels<'a> {
    title: &'a str,
    x: &'a str,
    y: &'a str,
    log_x: bool,
    log_y: bool,
}

/// The corner of the plot area for the legend of [`plot_lines`]: the one whose quarter of the
/// area (the 45 % × 45 % box at that corner, in axis coordinates: logarithmic on a log axis)
/// holds the fewest points, ties in the order upper right, upper left, lower right, lower left.
fn legend_corner(
    series: &[(String, Vec<(f64, f64)>)],
    (xr, yr): ((f64, f64), (f64, f64)),
    (log_x, log_y): (bool, bool),
) -> SeriesLabelPosition {
    let unit = |v: f64, (lo, hi): (f64, f64), log: bool| {
        if log {
            (v.ln() - lo.ln()) / (hi.ln() - lo.ln())
        } else {
            (v - lo) / (hi - lo)
        }
    };
    let corners = [
        (SeriesLabelPosition::UpperRight, true, true),
        (SeriesLabelPosition::UpperLeft, false, true),
        (SeriesLabelPosition::LowerRight, true, false),
        (SeriesLabelPosition::LowerLeft, false, false),
    ];
    let count = |right: bool, upper: bool| {
        series
            .iter()
            .flat_map(|(_, v)| v.iter())
            .filter(|p| {
                let (u, w) = (unit(p.0, xr, log_x), unit(p.1, yr, log_y));
                (if right { u >= 0.55 } else { u <= 0.45 })
                    && (if upper { w >= 0.55 } else { w <= 0.45 })
            })
            .count()
    };
    let mut best = (usize::MAX, SeriesLabelPosition::UpperRight);
    for (pos, right, upper) in corners {
        let n = count(right, upper);
        if n < best.0 {
            best = (n, pos);
        }
    }
    best.1
}

fn draw_lines<XR, YR>(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    path: &Path,
    labels: &Labels<'_>,
    (series, markers): (&[NamedLine], &[Markers]),
    legend_at: SeriesLabelPosition,
    xr: XR,
    yr: YR,
) -> Result<()>
where
    XR: AsRangedCoord<Value = f64>,
    YR: AsRangedCoord<Value = f64>,
    XR::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
    YR::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(area)
        .caption(labels.title, (FONT, 22))
        .margin(14)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(xr, yr)
        .map_err(|x| pe(path, x))?;
    chart
        .configure_mesh()
        .x_labels(10)
        .y_labels(10)
        .x_label_formatter(if labels.log_x { &tick_log } else { &tick })
        .y_label_formatter(if labels.log_y { &tick_log } else { &tick })
        .x_desc(labels.x)
        .y_desc(labels.y)
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 17))
        .draw()
        .map_err(|x| pe(path, x))?;
    for (k, (name, pts)) in series.iter().enumerate() {
        let col = SERIES_COLOURS[k % SERIES_COLOURS.len()];
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), col.stroke_width(2)))
            .map_err(|x| pe(path, x))?
            .label(name.as_str())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], col.stroke_width(2)));
        if k < SERIES_COLOURS.len() {
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 3, col.filled())))
                .map_err(|x| pe(path, x))?;
        } else {
            chart
                .draw_series(pts.iter().map(|&p| {
                    EmptyElement::at(p) + Rectangle::new([(-3, -3), (3, 3)], col.filled())
                }))
                .map_err(|x| pe(path, x))?;
        }
    }
    for m in markers {
        draw_markers(&mut chart, m, path)?;
    }
    chart
        .configure_series_labels()
        .position(legend_at)
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|x| pe(path, x))?;
    Ok(())
}

/// A named polyline of [`plot_lines`].
type NamedLine = (String, Vec<(f64, f64)>);

/// Shape of a markers-only series ([`Markers`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MarkerShape {
    Circle,
    Square,
    Triangle,
    Cross,
}

/// A markers-only series of [`plot_lines_marked`]: points drawn as `shape` in `colour`, no
/// line, with a legend entry `name`.
#[derive(Clone, Debug, PartialEq)]
pub struct Markers {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub colour: [u8; 3],
    pub shape: MarkerShape,
}

/// Draws `m`'s points (5 px markers) with its legend entry.
fn draw_markers<'a, 'b: 'a, X, Y>(
    chart: &mut ChartContext<'a, BitMapBackend<'b>, Cartesian2d<X, Y>>,
    m: &Markers,
    path: &Path,
) -> Result<()>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let col = rgb(m.colour);
    let pts = m.points.iter().copied();
    let name = m.name.as_str();
    match m.shape {
        MarkerShape::Circle => {
            chart
                .draw_series(pts.map(|p| Circle::new(p, 5, col.filled())))
                .map_err(|x| pe(path, x))?
                .label(name)
                .legend(move |(x, y)| Circle::new((x + 8, y), 5, col.filled()));
        }
        MarkerShape::Square => {
            chart
                .draw_series(pts.map(|p| {
                    EmptyElement::at(p) + Rectangle::new([(-4, -4), (4, 4)], col.filled())
                }))
                .map_err(|x| pe(path, x))?
                .label(name)
                .legend(move |(x, y)| {
                    Rectangle::new([(x + 4, y - 4), (x + 12, y + 4)], col.filled())
                });
        }
        MarkerShape::Triangle => {
            chart
                .draw_series(pts.map(|p| TriangleMarker::new(p, 6, col.filled())))
                .map_err(|x| pe(path, x))?
                .label(name)
                .legend(move |(x, y)| TriangleMarker::new((x + 8, y), 6, col.filled()));
        }
        MarkerShape::Cross => {
            chart
                .draw_series(pts.map(|p| Cross::new(p, 5, col.stroke_width(2))))
                .map_err(|x| pe(path, x))?
                .label(name)
                .legend(move |(x, y)| Cross::new((x + 8, y), 5, col.stroke_width(2)));
        }
    }
    Ok(())
}

/// Writes a PNG ([`LINES_PNG_SIZE`]) of named polylines with point markers, optionally on
/// logarithmic axes (work-precision charts: error vs time). With a log axis, points with a
/// non-positive coordinate on it are dropped; non-finite points are always dropped. With no
/// point left the axes are drawn alone and the title ends in "(no finite values to draw)".
pub fn plot_lines(
    path: impl AsRef<Path>,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[(String, Vec<(f64, f64)>)],
    log_x: bool,
    log_y: bool,
) -> Result<()> {
    plot_lines_marked(path, title, x_label, y_label, series, &[], (log_x, log_y))
}

/// [`plot_lines`] with markers-only series drawn over the lines (each with its shape, colour
/// and legend entry after the lines'); the axes cover the markers' points too.
pub fn plot_lines_marked(
    path: impl AsRef<Path>,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[(String, Vec<(f64, f64)>)],
    markers: &[Markers],
    (log_x, log_y): (bool, bool),
) -> Result<()> {
    let path = path.as_ref();
    let keep = |p: &(f64, f64)| {
        p.0.is_finite() && p.1.is_finite() && (!log_x || p.0 > 0.0) && (!log_y || p.1 > 0.0)
    };
    let given_x = || {
        series
            .iter()
            .flat_map(|(_, v)| v.iter())
            .chain(markers.iter().flat_map(|m| m.points.iter()))
            .map(|p| p.0)
            .filter(|x| !log_x || *x > 0.0)
            .collect::<Vec<f64>>()
    };
    let series: Vec<(String, Vec<(f64, f64)>)> = series
        .iter()
        .map(|(n, v)| (n.clone(), v.iter().copied().filter(keep).collect()))
        .collect();
    let markers: Vec<Markers> = markers
        .iter()
        .map(|m| Markers {
            points: m.points.iter().copied().filter(keep).collect(),
            ..m.clone()
        })
        .collect();
    // the legend's corner and the axes see the markers as points of unnamed series
    let mut placed = series.clone();
    placed.extend(markers.iter().map(|m| (String::new(), m.points.clone())));
    let all = || placed.iter().flat_map(|(_, v)| v.iter().copied());
    let unit = |log: bool| if log { (1.0, 10.0) } else { (0.0, 1.0) };
    let (xr, yr, title) = match (range_of(all().map(|p| p.0)), range_of(all().map(|p| p.1))) {
        (Some(x), Some(y)) => (x, y, title.to_string()),
        // Nothing finite to draw (an MFPT where no walker fell is infinite at every value):
        // the axes alone, over the x values given, and the title says so; the caller says why.
        _ => (
            range_of(given_x().into_iter()).unwrap_or(unit(log_x)),
            unit(log_y),
            format!("{title} (no finite values to draw)"),
        ),
    };
    let title = title.as_str();
    let widen = |(lo, hi): (f64, f64), log: bool| {
        if log {
            (lo / 1.3, hi * 1.3)
        } else {
            pad((lo, hi), 0.04)
        }
    };
    let (xr, yr) = (widen(xr, log_x), widen(yr, log_y));
    register_fonts();
    let pic = Staged::picture(path)?;
    let tmp = pic.path().to_path_buf();
    let root = BitMapBackend::new(&tmp, LINES_PNG_SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|x| pe(path, x))?;
    let labels = Labels {
        title,
        x: x_label,
        y: y_label,
        log_x,
        log_y,
    };
    let (xa, xb, ya, yb) = (xr.0, xr.1, yr.0, yr.1);
    let lin = |a: f64, b: f64| a..b;
    let at = legend_corner(&placed, (xr, yr), (log_x, log_y));
    let series = (&series[..], &markers[..]);
    match (log_x, log_y) {
        (false, false) => draw_lines(&root, path, &labels, series, at, lin(xa, xb), lin(ya, yb)),
        (true, false) => draw_lines(
            &root,
            path,
            &labels,
            series,
            at,
            lin(xa, xb).log_scale(),
            lin(ya, yb),
        ),
        (false, true) => draw_lines(
            &root,
            path,
            &labels,
            series,
            at,
            lin(xa, xb),
            lin(ya, yb).log_scale(),
        ),
        (true, true) => draw_lines(
            &root,
            path,
            &labels,
            series,
            at,
            lin(xa, xb).log_scale(),
            lin(ya, yb).log_scale(),
        ),
    }?;
    root.present().map_err(|x| pe(path, x))?;
    pic.commit(path)
}

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
fn clip_line(
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_legend_goes_to_the_emptiest_corner() {
        let s = |pts: &[(f64, f64)]| vec![("a".to_string(), pts.to_vec())];
        let lin = ((0.0, 1.0), (0.0, 1.0));
        // Points in every corner but the lower left.
        let three = s(&[(0.9, 0.9), (0.1, 0.9), (0.9, 0.1), (0.5, 0.5)]);
        assert!(matches!(
            legend_corner(&three, lin, (false, false)),
            SeriesLabelPosition::LowerLeft
        ));
        // An empty chart area keeps the first choice, the upper right.
        assert!(matches!(
            legend_corner(&s(&[(0.5, 0.5)]), lin, (false, false)),
            SeriesLabelPosition::UpperRight
        ));
        // Log axes over x ∈ [1, 100], y ∈ [10⁻⁸, 1]: 10 is the middle of x, 10⁻⁵ in the lower
        // half of y; the upper left is empty there. On linear axes all four points have
        // x ≤ 30 (the left 30 %), so the first choice, the upper right, is empty.
        let logs = s(&[(3.0, 1e-5), (30.0, 1e-5), (10.0, 0.5), (30.0, 0.5)]);
        let r = ((1.0, 100.0), (1e-8, 1.0));
        assert!(matches!(
            legend_corner(&logs, r, (true, true)),
            SeriesLabelPosition::UpperLeft
        ));
        assert!(matches!(
            legend_corner(&logs, r, (false, false)),
            SeriesLabelPosition::UpperRight
        ));
    }

    #[test]
    fn tick_labels_are_compact() {
        assert_eq!(tick(&0.001), "0.001");
        assert_eq!(tick(&0.25), "0.25");
        assert_eq!(tick(&-0.15), "-0.15");
        assert_eq!(tick(&0.0100000001), "0.01");
        assert_eq!(tick(&9.999999999e-5), "1e-4");
        assert_eq!(tick(&1.5e-7), "1.5e-7");
        assert_eq!(tick(&0.0), "0");
        assert_eq!(tick_log(&0.005), "0.005");
        assert_eq!(tick_log(&0.007), "");
        assert_eq!(tick_log(&2e-9), "2e-9");
    }

    #[test]
    fn nearest_picks_closest_grid_point_in_either_order() {
        let g = [0.0, 1.0, 2.0, 3.0];
        assert_eq!(nearest(&g, -5.0), 0);
        assert_eq!(nearest(&g, 1.4), 1);
        assert_eq!(nearest(&g, 1.6), 2);
        assert_eq!(nearest(&g, 9.0), 3);
        let r = [3.0, 2.0, 1.0, 0.0];
        assert_eq!(nearest(&r, 1.4), 2);
        assert_eq!(nearest(&r, 2.9), 0);
    }

    #[test]
    fn stability_runs_share_boundary_points_and_cover_branch() {
        let runs = stability_runs(&[true, true, false, false, true]);
        assert_eq!(runs, vec![(0..3, true), (2..5, false), (4..5, true)]);
    }

    #[test]
    fn clipped_slope_line_ends_on_box_edges() {
        // Line y = −0.1 x through the box [−1, 1] × [−1, 1]: enters at x = −1, leaves at x = 1.
        let s = clip_line((0.0, 0.0), (1.0, -0.1), -1.0, 1.0, -1.0, 1.0).unwrap();
        assert!((s[0].0 + 1.0).abs() < 1e-15 && (s[0].1 - 0.1).abs() < 1e-15);
        assert!((s[1].0 - 1.0).abs() < 1e-15 && (s[1].1 + 0.1).abs() < 1e-15);
        assert!(clip_line((0.0, 5.0), (1.0, 5.0), -1.0, 1.0, -1.0, 1.0).is_none());
    }
}
