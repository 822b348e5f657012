//! The two-parameter bifurcation-curve file of `pdw-sweep fixedpoint --follow pd|fold` and its
//! picture.
//!
//! ```text
//! /                  attrs: format ("pdw-sweep curve v1"), version, command, created, model,
//!                           kind ("pd" | "fold"), step_parameter, free_parameter, params (JSON
//!                           object: the model's other parameters), section_names, state_names
//!                           (JSON lists), complete (u8: 1 if every requested point was
//!                           reached), end (text: how the curve ended)
//! /curve/p_step      f64 [n]     stepped parameter of each point
//! /curve/p_free      f64 [n]     free parameter solved for
//! /curve/section     f64 [n, d]  section state of the critical period-one gait
//! /curve/state       f64 [n, D]  its full post-heel-strike state
//! /curve/multipliers_re, multipliers_im   f64 [n, d]  Floquet multipliers (decreasing modulus)
//! /curve/critical    f64 [n]     the real multiplier at −1 (pd) or +1 (fold)
//! /curve/period      f64 [n]     stride duration
//! /curve/residual    f64 [n]     ‖P(x) − x‖∞ re-computed with a fresh stride
//! /map               optional region map: step f64 [nx], free f64 [ny], region u8 [ny, nx]
//!                    (row j = free[j], column i = step[i]); attr legend (JSON code → name)
//! ```
//! Units are added by the caller ([`crate::provenance::annotate`]). The file is written whole
//! to a temporary sibling and renamed into place (an existing file only with `force`).

use std::path::Path;

use hdf5::File;
use ndarray::Array2;
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::h5util::{
    get_str, matrix, open_file, put, set_attr, set_str, write_h5_atomically, At, Staged,
};
use crate::plot::{cell_extent, draw_swatches, paint_cells, pe, register_fonts, tick, FONT};
use crate::{time, Result, StoreError};

/// Value of the root attribute `format` of a curve file.
pub const CURVE_FORMAT: &str = "pdw-sweep curve v1";
const KIND: &str = "pdw-sweep curve";
/// Pixel size of [`plot_curve`]'s PNG.
pub const CURVE_PNG_SIZE: (u32, u32) = (1060, 720);

/// A coarse classification of the parameter plane.
#[derive(Clone, Debug, PartialEq)]
pub struct RegionMap {
    /// (nx) stepped-parameter values (columns).
    pub step: Vec<f64>,
    /// (ny) free-parameter values (rows).
    pub free: Vec<f64>,
    /// (ny × nx) region codes.
    pub region: Vec<Vec<u8>>,
    /// Code → name, in code order.
    pub legend: Vec<(u8, String)>,
}

/// Everything a curve file holds.
#[derive(Clone, Debug, PartialEq)]
pub struct CurveData {
    pub command: String,
    pub model: String,
    /// `"pd"` or `"fold"`.
    pub kind: String,
    pub step_parameter: String,
    pub free_parameter: String,
    /// The model's parameters as a JSON object text.
    pub params: String,
    pub section_names: Vec<String>,
    pub state_names: Vec<String>,
    pub p_step: Vec<f64>,
    pub p_free: Vec<f64>,
    pub section: Vec<Vec<f64>>,
    pub state: Vec<Vec<f64>>,
    /// `(re, im)` per point, d each.
    pub multipliers: Vec<Vec<(f64, f64)>>,
    pub critical: Vec<f64>,
    pub period: Vec<f64>,
    pub residual: Vec<f64>,
    pub complete: bool,
    pub end: String,
    pub map: Option<RegionMap>,
}

impl CurveData {
    /// Checks shapes.
    pub fn validate(&self) -> Result<()> {
        let n = self.p_step.len();
        let d = self.section_names.len();
        let big_d = self.state_names.len();
        let bad = |detail: String| Err(StoreError::invalid("curve", detail));
        if d == 0 || big_d == 0 {
            return bad("needs section and state names".into());
        }
        if serde_json::from_str::<serde_json::Map<String, serde_json::Value>>(&self.params).is_err()
        {
            return bad(format!("params is not a JSON object: {:?}", self.params));
        }
        let lens = [
            self.p_free.len(),
            self.section.len(),
            self.state.len(),
            self.multipliers.len(),
            self.critical.len(),
            self.period.len(),
            self.residual.len(),
        ];
        if lens.iter().any(|&l| l != n)
            || self.section.iter().any(|s| s.len() != d)
            || self.state.iter().any(|s| s.len() != big_d)
            || self.multipliers.iter().any(|s| s.len() != d)
        {
            return bad(format!(
                "need {n} points of every per-point array, {d} section values, {big_d} state \
                 values and {d} multipliers each"
            ));
        }
        if let Some(m) = &self.map {
            if m.region.len() != m.free.len() || m.region.iter().any(|r| r.len() != m.step.len()) {
                return bad("region map: need free.len() rows of step.len() codes".into());
            }
        }
        Ok(())
    }
}

/// Writes `data` to `path` (refused if it exists, unless `force`).
pub fn write_curve(path: impl AsRef<Path>, force: bool, data: &CurveData) -> Result<()> {
    let path = path.as_ref();
    data.validate()?;
    write_h5_atomically(path, force, |tmp, f| fill(tmp, f, data))
}

fn fill(p: &Path, f: &File, data: &CurveData) -> Result<()> {
    let json = |v: &[String]| serde_json::to_string(v).unwrap_or_default();
    for (k, v) in [
        ("format", CURVE_FORMAT),
        ("version", env!("CARGO_PKG_VERSION")),
        ("command", &data.command),
        ("created", &time::now_rfc3339()),
        ("model", &data.model),
        ("kind", &data.kind),
        ("step_parameter", &data.step_parameter),
        ("free_parameter", &data.free_parameter),
        ("params", &data.params),
        ("section_names", &json(&data.section_names)),
        ("state_names", &json(&data.state_names)),
        ("end", &data.end),
    ] {
        set_str(p, f, k, v)?;
    }
    set_attr(p, f, "complete", &u8::from(data.complete))?;
    let d = data.section_names.len();
    let g = f.create_group("curve").at(p, "creating /curve")?;
    put(p, &g, "p_step", &data.p_step)?;
    put(p, &g, "p_free", &data.p_free)?;
    put(p, &g, "section", &matrix(&data.section, d))?;
    put(p, &g, "state", &matrix(&data.state, data.state_names.len()))?;
    let part = |k: usize| -> Vec<Vec<f64>> {
        data.multipliers
            .iter()
            .map(|v| v.iter().map(|z| if k == 0 { z.0 } else { z.1 }).collect())
            .collect()
    };
    put(p, &g, "multipliers_re", &matrix(&part(0), d))?;
    put(p, &g, "multipliers_im", &matrix(&part(1), d))?;
    put(p, &g, "critical", &data.critical)?;
    put(p, &g, "period", &data.period)?;
    put(p, &g, "residual", &data.residual)?;
    if let Some(m) = &data.map {
        let g = f.create_group("map").at(p, "creating /map")?;
        put(p, &g, "step", &m.step)?;
        put(p, &g, "free", &m.free)?;
        let flat: Vec<u8> = m.region.iter().flatten().copied().collect();
        let a = Array2::from_shape_vec((m.free.len(), m.step.len()), flat).expect("validated");
        put(p, &g, "region", &a)?;
        let legend: serde_json::Map<String, serde_json::Value> = m
            .legend
            .iter()
            .map(|(c, n)| (c.to_string(), serde_json::Value::String(n.clone())))
            .collect();
        let ds = g.dataset("region").at(p, "opening /map/region")?;
        set_str(
            p,
            &ds,
            "legend",
            &serde_json::Value::Object(legend).to_string(),
        )?;
    }
    Ok(())
}

/// Reads the curve of a curve file: `(kind, step_parameter, free_parameter, p_step, p_free,
/// complete)`.
#[allow(clippy::type_complexity)]
pub fn read_curve_points(
    path: impl AsRef<Path>,
) -> Result<(String, String, String, Vec<f64>, Vec<f64>, bool)> {
    let p = path.as_ref();
    let f = open_file(p, false)?;
    let fmt = get_str(p, KIND, &f, "format")?;
    if fmt != CURVE_FORMAT {
        return Err(StoreError::Format {
            path: p.to_path_buf(),
            expected: KIND,
            detail: format!("format is {fmt:?}, expected {CURVE_FORMAT:?}"),
        });
    }
    let r1 = |n: &str| {
        f.dataset(n)
            .and_then(|d| d.read_raw::<f64>())
            .at(p, &format!("reading {n}"))
    };
    let complete: u8 = f
        .attr("complete")
        .and_then(|a| a.read_scalar())
        .at(p, "reading complete")?;
    Ok((
        get_str(p, KIND, &f, "kind")?,
        get_str(p, KIND, &f, "step_parameter")?,
        get_str(p, KIND, &f, "free_parameter")?,
        r1("curve/p_step")?,
        r1("curve/p_free")?,
        complete != 0,
    ))
}

/// Colour of a region code in [`plot_curve`] (by the legend name).
fn region_colour(name: &str) -> [u8; 3] {
    let n = name.to_ascii_lowercase();
    if n.starts_with("stable period-1") {
        [44, 160, 44]
    } else if n.starts_with("period-2") {
        [31, 119, 180]
    } else if n.starts_with("period-4") {
        [148, 103, 189]
    } else if n.starts_with("no period") {
        [255, 200, 90]
    } else if n.contains("fall") {
        [214, 39, 40]
    } else {
        [190, 190, 190]
    }
}

/// Writes the two-parameter bifurcation diagram ([`CURVE_PNG_SIZE`]): the region map (if any) as
/// a heatmap with a legend of the regions and their fractions, and the curve on top (black line
/// and dots). `step_label`, `free_label` name the axes (with units).
pub fn plot_curve(
    path: impl AsRef<Path>,
    data: &CurveData,
    step_label: &str,
    free_label: &str,
    title: &str,
) -> Result<()> {
    let path = path.as_ref();
    data.validate()?;
    register_fonts();
    let pic = Staged::picture(path)?;
    let tmp = pic.path().to_path_buf();
    let root = BitMapBackend::new(&tmp, CURVE_PNG_SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|x| pe(path, x))?;
    let (left, right) = root.split_horizontally(CURVE_PNG_SIZE.0 - 300);
    let ((x0, x1), (y0, y1)) = curve_extent(data);
    let mut chart = ChartBuilder::on(&left)
        .caption(title, (FONT, 20))
        .margin(12)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|x| pe(path, x))?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .x_desc(step_label)
        .y_desc(free_label)
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 18))
        .draw()
        .map_err(|x| pe(path, x))?;
    let mut entries: Vec<(String, [u8; 3])> = Vec::new();
    if let Some(m) = &data.map {
        let mut lut = [[255u8, 255, 255]; 256];
        for (c, name) in &m.legend {
            lut[*c as usize] = region_colour(name);
        }
        paint_cells(
            chart.plotting_area(),
            (&m.step, &m.free),
            ((x0, x1), (y0, y1)),
            |row, col| lut[m.region[row][col] as usize],
            path,
        )?;
        entries = region_entries(m);
    }
    let pts: Vec<(f64, f64)> = data
        .p_step
        .iter()
        .zip(&data.p_free)
        .map(|(&a, &b)| (a, b))
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .collect();
    chart
        .draw_series(LineSeries::new(pts.iter().copied(), BLACK.stroke_width(3)))
        .map_err(|x| pe(path, x))?;
    chart
        .draw_series(pts.iter().map(|&p| Circle::new(p, 4, BLACK.filled())))
        .map_err(|x| pe(path, x))?;
    let legend_top = 60;
    draw_swatches(&right, &entries, legend_top, 14, path)?;
    draw_curve_entry(
        &right,
        &data.kind,
        legend_top + 30 * entries.len() as i32 + 10,
        path,
    )?;
    root.present().map_err(|x| pe(path, x))?;
    drop(chart);
    drop(root);
    pic.commit(path)
}

/// The axes of [`plot_curve`]: the region map's cells, or else the curve's finite points (a
/// degenerate range widened by 5 % of its value, at least 10⁻³ of it), with 10 % of the free
/// parameter's range added above and below.
fn curve_extent(data: &CurveData) -> ((f64, f64), (f64, f64)) {
    let finite = |v: &[f64]| -> Option<(f64, f64)> {
        let (lo, hi) = v
            .iter()
            .filter(|x| x.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        lo.is_finite().then_some((lo, hi))
    };
    let widen = |(lo, hi): (f64, f64)| {
        if hi > lo {
            (lo, hi)
        } else {
            let d = 0.05 * lo.abs().max(1e-3);
            (lo - d, hi + d)
        }
    };
    match &data.map {
        Some(m) => (cell_extent(&m.step), cell_extent(&m.free)),
        None => {
            let xs = widen(finite(&data.p_step).unwrap_or((0.0, 1.0)));
            let ys = widen(finite(&data.p_free).unwrap_or((0.0, 1.0)));
            let pad = 0.1 * (ys.1 - ys.0);
            (xs, (ys.0 - pad, ys.1 + pad))
        }
    }
}

/// The legend entries of a region map: each region present with its percentage of the map, in
/// its colour ([`region_colour`]).
fn region_entries(m: &RegionMap) -> Vec<(String, [u8; 3])> {
    let mut entries = Vec::new();
    let total = (m.step.len() * m.free.len()).max(1) as f64;
    for (c, name) in &m.legend {
        let k = m.region.iter().flatten().filter(|&&v| v == *c).count();
        if k > 0 {
            entries.push((
                format!("{name} {:.1}%", 100.0 * k as f64 / total),
                region_colour(name),
            ));
        }
    }
    entries
}

/// The curve's legend entry at `y`: a thick black line and the curve's kind in words.
fn draw_curve_entry(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    kind: &str,
    y: i32,
    path: &Path,
) -> Result<()> {
    area.draw(&PathElement::new(
        vec![(10, y + 10), (32, y + 10)],
        BLACK.stroke_width(3),
    ))
    .map_err(|x| pe(path, x))?;
    let curve_name = match kind {
        "pd" => "period-doubling curve",
        "fold" => "fold curve",
        _ => "curve",
    };
    area.draw(&Text::new(
        curve_name.to_string(),
        (40, y + 2),
        (FONT, 14).into_font(),
    ))
    .map_err(|x| pe(path, x))?;
    Ok(())
}
