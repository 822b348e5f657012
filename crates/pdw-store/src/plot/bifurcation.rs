//! Bifurcation diagrams of a parameter sweep: Floquet multipliers (moduli and real parts) and a
//! section coordinate against the parameter, with stability, bifurcations and physically
//! invalid points marked.

use std::path::Path;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    pad, pe, range_of, register_fonts, tick, tick_log, BIFURCATION_PNG_SIZE, FONT, SERIES_COLOURS,
};
use crate::h5util::Staged;
use crate::sweep::{Branch, SweepData};
use crate::{Result, StoreError};

/// Splits a branch into maximal runs of equal stability; consecutive runs share their boundary
/// point so the curve stays connected.
pub fn stability_runs(stable: &[bool]) -> Vec<(std::ops::Range<usize>, bool)> {
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
