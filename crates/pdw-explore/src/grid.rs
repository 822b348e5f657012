//! A labelled grid as the page draws it — a file's basin or a refined window — and its JSON:
//! axes with names, units and values, outcome codes and strides (row-major, row = y index, the
//! rows of a 3-D grid its (z, y) pairs), the legend with pdw-store's palette
//! ([`pdw::store::outcome_colours`], the colours of the PNG), the attractors' orbit points, and
//! the model's parameters (the sliders).

use crate::source::{BasinSource, Rebuilt};
use serde_json::{json, Value};

/// One axis: its name, unit and values.
#[derive(Clone, Debug)]
pub struct GridAxis {
    pub name: String,
    pub units: String,
    pub values: Vec<f64>,
}

/// A labelled grid.
#[derive(Clone, Debug)]
pub struct Grid {
    pub x: GridAxis,
    pub y: GridAxis,
    pub z: Option<GridAxis>,
    /// (rows × nx) outcome codes.
    pub outcome: Vec<u8>,
    /// (rows × nx) strides until classified.
    pub strides: Vec<u16>,
    pub legend: Vec<(u8, String)>,
    /// Attractor name and its orbit points (section states).
    pub attractors: Vec<(String, Vec<Vec<f64>>)>,
    /// Section coordinate names (the attractors' points are in this order).
    pub section_names: Vec<String>,
    /// Whether every cell of the grid (or shard) is computed.
    pub complete: bool,
    /// `(index, count)` of a shard file.
    pub shard: Option<(usize, usize)>,
}

impl Grid {
    /// The basin of file `src`.
    pub fn of_file(src: &BasinSource) -> Grid {
        let (d, h) = (&src.data, &src.data.header);
        let unit = |i: usize| src.units.get(i).cloned().unwrap_or_default();
        Grid {
            x: GridAxis {
                name: h.x_name.clone(),
                units: unit(0),
                values: h.x.clone(),
            },
            y: GridAxis {
                name: h.y_name.clone(),
                units: unit(1),
                values: h.y.clone(),
            },
            z: h.z.as_ref().map(|z| GridAxis {
                name: z.name.clone(),
                units: unit(2),
                values: z.values.clone(),
            }),
            outcome: d.outcome.iter().copied().collect(),
            strides: d.strides.iter().copied().collect(),
            legend: h.legend.clone(),
            attractors: d
                .attractors
                .iter()
                .map(|a| (a.name.clone(), a.section.clone()))
                .collect(),
            section_names: h.state_names.clone(),
            complete: d.complete,
            shard: h.shard.map(|s| (s.index, s.count)),
        }
    }

    /// The x and y axes of file `src` (names and units; no values), as a window of it labels
    /// its axes.
    pub fn axes_of(src: &BasinSource) -> (GridAxis, GridAxis) {
        let h = &src.data.header;
        let unit = |i: usize| src.units.get(i).cloned().unwrap_or_default();
        let axis = |name: &str, i: usize| GridAxis {
            name: name.to_string(),
            units: unit(i),
            values: Vec::new(),
        };
        (axis(&h.x_name, 0), axis(&h.y_name, 1))
    }

    /// A refined window of `r` with the engine's `outcome` and `strides`; axis names and units
    /// from `like` ([`Grid::axes_of`] the file).
    pub fn of_window(
        r: &Rebuilt,
        outcome: Vec<u8>,
        strides: Vec<u16>,
        like: &(GridAxis, GridAxis),
    ) -> Grid {
        let p = &r.plan;
        Grid {
            x: GridAxis {
                values: p.xs.clone(),
                ..like.0.clone()
            },
            y: GridAxis {
                values: p.ys.clone(),
                ..like.1.clone()
            },
            z: None,
            outcome,
            strides,
            legend: r.set.legend(),
            attractors: r
                .set
                .attractors
                .iter()
                .map(|a| (a.name.clone(), a.points.clone()))
                .collect(),
            section_names: r.m.info.section_names.clone(),
            complete: true,
            shard: None,
        }
    }

    pub fn nx(&self) -> usize {
        self.x.values.len()
    }
    pub fn ny(&self) -> usize {
        self.y.values.len()
    }
    pub fn nz(&self) -> usize {
        self.z.as_ref().map_or(1, |z| z.values.len())
    }

    /// The legend with every code's colour, the `not_computed` fill included.
    fn legend_json(&self) -> Vec<Value> {
        let mut legend = self.legend.clone();
        legend.push((
            pdw::store::NOT_COMPUTED,
            pdw::store::basin::NOT_COMPUTED_NAME.to_string(),
        ));
        let colours = pdw::store::outcome_colours(&legend);
        legend
            .iter()
            .zip(colours)
            .map(|((c, n), (_, rgb))| {
                let rgb = if *c == pdw::store::NOT_COMPUTED {
                    [255, 255, 255]
                } else {
                    rgb
                };
                json!({"code": c, "name": n, "colour": format!("#{:02x}{:02x}{:02x}", rgb[0], rgb[1], rgb[2])})
            })
            .collect()
    }

    /// The page's JSON of this grid with the fields of `extra` beside it; `params` the
    /// model's parameters for the sliders. Serialised straight from the arrays (no JSON tree
    /// of the cells: a 4-million-cell grid is its ~20 MB of text, not gigabytes of values).
    pub fn to_json_bytes(
        &self,
        params: &[(String, f64)],
        extra: serde_json::Map<String, Value>,
    ) -> Result<Vec<u8>, crate::ApiError> {
        let axis = AxisOut::of;
        let out = GridOut {
            x: axis(&self.x),
            y: axis(&self.y),
            z: self.z.as_ref().map(axis),
            nx: self.nx(),
            ny: self.ny(),
            nz: self.nz(),
            outcome: &self.outcome,
            strides: &self.strides,
            legend: self.legend_json(),
            attractors: self
                .attractors
                .iter()
                .map(|(n, p)| json!({"name": n, "points": p}))
                .collect(),
            section_names: &self.section_names,
            complete: self.complete,
            shard: self.shard.map(|(i, n)| json!({"index": i, "count": n})),
            params: params
                .iter()
                .map(|(n, v)| json!({"name": n, "value": v}))
                .collect(),
            extra,
        };
        serde_json::to_vec(&out)
            .map_err(|e| crate::ApiError::internal(format!("the grid's JSON: {e}")))
    }
}

/// An axis as the page reads it.
#[derive(serde::Serialize)]
struct AxisOut<'a> {
    name: &'a str,
    units: &'a str,
    values: &'a [f64],
}

impl AxisOut<'_> {
    fn of(a: &GridAxis) -> AxisOut<'_> {
        AxisOut {
            name: &a.name,
            units: &a.units,
            values: &a.values,
        }
    }
}

/// A grid as the page reads it (see [`Grid::to_json_bytes`]).
#[derive(serde::Serialize)]
struct GridOut<'a> {
    x: AxisOut<'a>,
    y: AxisOut<'a>,
    z: Option<AxisOut<'a>>,
    nx: usize,
    ny: usize,
    nz: usize,
    outcome: &'a [u8],
    strides: &'a [u16],
    legend: Vec<Value>,
    attractors: Vec<Value>,
    section_names: &'a [String],
    complete: bool,
    shard: Option<Value>,
    params: Vec<Value>,
    #[serde(flatten)]
    extra: serde_json::Map<String, Value>,
}
