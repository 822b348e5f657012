//! Basin heatmaps: each pixel the outcome of the nearest grid cell, a legend of the outcomes
//! with their fractions, and the attractors' points marked.

use std::path::Path;

use ndarray::ArrayView2;
use plotters::coord::Shift;
use plotters::prelude::*;

use plotters::coord::types::RangedCoordf64;

use super::{
    cell_extent, draw_swatches, outcome_colours, paint_cells, pe, register_fonts, rgb, tick,
    BASIN_PNG_SIZE, FONT, INVALID_RING,
};
use crate::basin::{Attractor, BasinHeader, NOT_COMPUTED};
use crate::h5util::Staged;
use crate::{Result, StoreError};

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
    paint_cells(
        chart.plotting_area(),
        (&header.x, &header.y),
        ((x0, x1), (y0, y1)),
        |row, col| lut[outcome[[row, col]] as usize],
        path,
    )?;
    draw_marks(&mut chart, marks, ((x0, x1), (y0, y1)), path)?;

    let entries = outcome_entries(header, outcome, &colours, marks);
    let legend_top = 60;
    draw_swatches(&right, &entries, legend_top, 16, path)?;
    draw_mark_legend(
        &right,
        marks,
        legend_top + 30 * entries.len() as i32 + 10,
        path,
    )?;
    let below = legend_top + 30 * (entries.len() + marks.len()) as i32 + 20;
    draw_invalid_reasons(&right, marks, below, path)?;
    root.present().map_err(|x| pe(path, x))?;
    pic.commit(path)
}

/// The marks inside the box `((x0, x1), (y0, y1))` on the heatmap: a chaotic sample as small
/// black dots, a periodic orbit's points as ringed crosses ([`mark_style`]).
fn draw_marks<'a, 'b: 'a>(
    chart: &mut ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    marks: &[Marks],
    ((x0, x1), (y0, y1)): ((f64, f64), (f64, f64)),
    path: &Path,
) -> Result<()> {
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
    Ok(())
}

/// The legend's outcome entries: each outcome present with its percentage of the cells
/// (` (invalid)` for the basin of a physically invalid orbit), then the cells not computed, if
/// any, in white.
fn outcome_entries(
    header: &BasinHeader,
    outcome: ArrayView2<u8>,
    colours: &[(u8, [u8; 3])],
    marks: &[Marks],
) -> Vec<(String, [u8; 3])> {
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
    entries
}

/// One legend entry per mark, from `top` down (30 px apart): three dots for a chaotic sample,
/// a ringed cross ([`mark_style`]) for an orbit, then its label.
fn draw_mark_legend(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    marks: &[Marks],
    top: i32,
    path: &Path,
) -> Result<()> {
    for (k, mk) in marks.iter().enumerate() {
        let y = top + 30 * k as i32;
        if mk.cloud {
            for d in [-6, 0, 6] {
                area.draw(&Circle::new((21 + d, y + 10 + d / 2), 2, BLACK.filled()))
                    .map_err(|x| pe(path, x))?;
            }
        } else {
            let (fill, ring) = mark_style(mk);
            area.draw(&Circle::new((21, y + 10), 8, fill.filled()))
                .map_err(|x| pe(path, x))?;
            area.draw(&Circle::new((21, y + 10), 8, ring.stroke_width(2)))
                .map_err(|x| pe(path, x))?;
            area.draw(&Cross::new((21, y + 10), 5, BLACK.stroke_width(2)))
                .map_err(|x| pe(path, x))?;
        }
        area.draw(&Text::new(
            mk.label.clone(),
            (40, y + 2),
            (FONT, 16).into_font(),
        ))
        .map_err(|x| pe(path, x))?;
    }
    Ok(())
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
