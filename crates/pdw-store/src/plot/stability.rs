//! Basin stability against a parameter: the fractions of the box stacked, and each attractor's
//! fraction on its own scale.

use std::path::Path;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    outcome_colours, pad, pe, range_of, register_fonts, rgb, tick, FONT, INVALID_RING,
    STABILITY_PNG_SIZE,
};
use crate::h5util::Staged;
use crate::stability::StabilityData;
use crate::Result;

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
    data: &StabilityData,
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
    // Stable colours by name: the basin picture's palette over the column names.
    let legend: Vec<(u8, String)> = data
        .columns
        .iter()
        .enumerate()
        .map(|(i, n)| (i as u8, n.clone()))
        .collect();
    let colours = outcome_colours(&legend);
    let labels = (title, x_label);
    draw_stacked_fractions(&panels[0], data, xr, labels, &colours, path)?;
    draw_attractor_fractions(&panels[1], data, xr, x_label, &colours, path)?;
    root.present().map_err(|x| pe(path, x))?;
    pic.commit(path)
}

/// Top panel of [`plot_basin_stability`]: the columns' fractions stacked as filled bands in
/// their colours (a physically invalid attractor's outlined, [`draw_invalid_band`]), the
/// parameter values as ticks on the top edge, the legend upper left. `(title, x_label)` label
/// the panel.
fn draw_stacked_fractions(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    data: &StabilityData,
    xr: (f64, f64),
    (title, x_label): (&str, &str),
    colours: &[(u8, [u8; 3])],
    path: &Path,
) -> Result<()> {
    let mut chart = ChartBuilder::on(area)
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
    Ok(())
}

/// Bottom panel of [`plot_basin_stability`]: each attractor's fraction alone, a line with a
/// marker per value, on a scale up to 1.15 times the largest (at most 1), the legend upper
/// right.
fn draw_attractor_fractions(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    data: &StabilityData,
    xr: (f64, f64),
    x_label: &str,
    colours: &[(u8, [u8; 3])],
    path: &Path,
) -> Result<()> {
    let n = data.values.len();
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
    let mut bot = ChartBuilder::on(area)
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
    Ok(())
}

/// The legend name of column `c`: suffixed ` (invalid)` for a physically invalid attractor.
fn stability_label(data: &StabilityData, c: usize) -> String {
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
