//! Line charts: named polylines with point markers and markers-only series, on linear or
//! logarithmic axes (work-precision charts), the legend in the emptiest corner.

use std::path::Path;

use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    pad, pe, range_of, register_fonts, rgb, tick, tick_log, FONT, LINES_PNG_SIZE, SERIES_COLOURS,
};
use crate::h5util::Staged;
use crate::Result;

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
pub fn legend_corner(
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
