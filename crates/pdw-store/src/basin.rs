//! The basin-of-attraction file: header, streaming writer with resume, reader.
//!
//! A basin grid assigns each cell `(x[j], y[i])` of two section coordinates an outcome code (see
//! the `legend`), the number of strides until it was classified and the last section state.
//! # Crash safety
//! Rows are produced in any order by the engine and handed to [`BasinWriter::write_rows`] in
//! any grouping. The writer buffers them until a whole chunk block ([`BLOCK_ROWS`] rows) is
//! present, then writes that block once, flushes, marks its rows in `/basin/rows_done` and
//! flushes again: a row is marked done only after its data is on disk. When the writer stops
//! early ([`BasinWriter::close`], or dropped after an error or an interrupt), the blocks still
//! incomplete are written the same way with the rows they have (the others keep the fill
//! values) and only those rows are marked, so every row handed over is in the file. Each
//! compressed chunk is written at most once per file (rewriting a partly filled deflated chunk
//! reallocates it, and a kill in between can leave the chunk index pointing at overwritten
//! bytes — observed in testing), and the file is created with HDF5's
//! file-space strategy `NONE` (no reuse of freed space), so nothing the last flushed state
//! refers to is overwritten before the next flush. A run killed at any moment (SIGKILL
//! included, tested) therefore leaves a file whose marked rows are valid; rows held in memory
//! at the kill are lost and recomputed. The chunks of a block interrupted before it was marked
//! can be unreadable (their index entry flushed before the file's end of allocation); readers
//! treat such a block as not computed, and an unreadable block with rows marked done as an
//! error. [`BasinWriter::resume`] checks every block with marked rows against its checksums and
//! digest, copies the whole good ones into a fresh file beside the old one and renames it over
//! the old (a killed file is never written in place: its last flush may have been cut between
//! the chunk index and the superblock, and HDF5 would then allocate over live metadata), takes
//! the marked rows of partly written blocks back into memory (written with the rest of their
//! block, or again when the resumed run stops; a SIGKILL before that loses them to
//! recomputation), and reports the rows still to compute; a kill during that copy leaves the
//! old file as it was. Since the engine's labels do not depend on batch size, thread count or
//! order, a resumed run yields the same datasets as an uninterrupted one.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use hdf5::{Dataset, File, Group};
use ndarray::{s, Array2, Array3, ArrayView3};

use crate::h5util::{
    create_file, ensure_space, get_attr, get_str, has_attr, lock_existing, open_file, open_locked,
    rename_into_place, set_attr, set_str, temp_sibling, At, OutputLock,
};
use crate::shard::{grid_shard_rows, ShardSpec};
use crate::{time, Result, StoreError};

/// Value of the root attribute `format` of a basin file.
pub const BASIN_FORMAT: &str = "pdw-sweep basin v1";
/// Rows per chunk of the 2-D/3-D datasets, and per shard block (see [`shard_rows`](crate::shard::shard_rows)).
/// Writing blocks aligned to it (`row0` a multiple, `BLOCK_ROWS` rows) writes whole chunks.
pub const BLOCK_ROWS: usize = 16;
/// Outcome code of a cell not (yet) computed: the fill value of `/basin/outcome`.
pub const NOT_COMPUTED: u8 = 255;
const DEFLATE_LEVEL: u8 = 4;
const KIND: &str = "pdw-sweep basin";

/// Everything that identifies a basin run: what `resume` and `merge` compare.
///
/// Floating-point fields are compared bit for bit; `params` and `tolerances` as JSON text, so
/// serialise them the same way each time (e.g. `serde_json::to_string` of the same value).
/// `command` is recorded but not compared (a resumed run's command line differs).
#[derive(Clone, Debug, PartialEq)]
pub struct BasinHeader {
    /// The command line that made the file.
    pub command: String,
    /// Model name, e.g. `"simplest"`.
    pub model: String,
    /// Slope γ in radians.
    pub slope: f64,
    /// Model parameters as a JSON object text.
    pub params: String,
    /// The fully resolved model, one `key = value` line per quantity (the walker's
    /// fingerprint): two files continue each other only if it is equal, so a spec whose
    /// expressions changed under the same parameter values is a different run. Empty in files
    /// written before it was stored.
    pub model_resolved: String,
    /// Integrator name, e.g. `"dopri5"`.
    pub integrator: String,
    /// Integrator tolerances as a JSON object text, e.g. `{"rtol":1e-10,"atol":1e-12}`.
    pub tolerances: String,
    /// Stride budget per cell.
    pub max_strides: u32,
    /// Section coordinate along x, e.g. `"theta"`.
    pub x_name: String,
    /// Grid abscissae (nx), finite.
    pub x: Vec<f64>,
    /// Section coordinate along y, e.g. `"thetadot"`.
    pub y_name: String,
    /// Grid ordinates (ny), finite.
    pub y: Vec<f64>,
    /// The third axis of a 3-D grid (`None`: a 2-D grid). Its cells are stored `[nz, ny, nx]`,
    /// and the writer's rows are the grid's (z, y) pairs, row `k·ny + i` for `(z[k], y[i])`.
    pub z: Option<ZAxis>,
    /// Names of the d section coordinates stored in `/basin/final`.
    pub state_names: Vec<String>,
    /// Outcome codes and names, e.g. `(0, "gait")`; codes unique and not [`NOT_COMPUTED`].
    pub legend: Vec<(u8, String)>,
    /// `Some` for a shard file holding only [`shard_rows`](crate::shard::shard_rows)`(ny, index, count)`.
    pub shard: Option<ShardSpec>,
}

impl BasinHeader {
    /// Number of grid columns.
    pub fn nx(&self) -> usize {
        self.x.len()
    }
    /// Number of grid rows.
    pub fn ny(&self) -> usize {
        self.y.len()
    }
    /// Number of z-slices: 1 for a 2-D grid.
    pub fn nz(&self) -> usize {
        self.z.as_ref().map_or(1, |z| z.values.len())
    }
    /// Rows of nx cells the writer handles: ny for a 2-D grid, nz·ny for a 3-D one (row
    /// `k·ny + i` is `(z[k], y[i])`).
    pub fn rows(&self) -> usize {
        self.nz() * self.ny()
    }
    /// Chunk blocks of the grid ([`block_count`]).
    pub fn blocks(&self) -> usize {
        block_count(self.ny(), self.nz())
    }
    /// Dimension of the stored section state.
    pub fn d(&self) -> usize {
        self.state_names.len()
    }
    /// Outcome name of `code`, if in the legend.
    pub fn outcome_name(&self, code: u8) -> Option<&str> {
        self.legend
            .iter()
            .find(|(c, _)| *c == code)
            .map(|(_, n)| n.as_str())
    }
    /// Rows this file is responsible for: all rows, or its shard's.
    pub fn own_rows(&self) -> Vec<usize> {
        match self.shard {
            None => (0..self.rows()).collect(),
            Some(s) => grid_shard_rows(self.ny(), self.nz(), s.index, s.count).unwrap_or_default(),
        }
    }

    /// Rejects empty or non-finite grids, empty names, a malformed legend, non-JSON params.
    pub fn validate(&self) -> Result<()> {
        for (axis, name, v) in [("x", &self.x_name, &self.x), ("y", &self.y_name, &self.y)] {
            if name.is_empty() {
                return Err(StoreError::invalid(
                    "grid",
                    format!("{axis} axis has no name"),
                ));
            }
            if v.is_empty() {
                return Err(StoreError::invalid(
                    "grid",
                    format!("{axis} axis ({name}) has no points"),
                ));
            }
            if let Some(bad) = v.iter().find(|a| !a.is_finite()) {
                return Err(StoreError::invalid(
                    "grid",
                    format!("{axis} axis ({name}) holds {bad}"),
                ));
            }
        }
        if let Some(z) = &self.z {
            z.validate(&self.x_name, &self.y_name)?;
        }
        if self.state_names.is_empty() || self.state_names.iter().any(|n| n.is_empty()) {
            return Err(StoreError::invalid(
                "state names",
                format!(
                    "need at least one non-empty name, got {:?}",
                    self.state_names
                ),
            ));
        }
        if self.legend.is_empty() {
            return Err(StoreError::invalid("legend", "empty"));
        }
        for (i, (c, n)) in self.legend.iter().enumerate() {
            if *c == NOT_COMPUTED {
                return Err(StoreError::invalid(
                    "legend",
                    format!("code {NOT_COMPUTED} is reserved for cells not computed ({n})"),
                ));
            }
            if n.is_empty() || n.contains('/') {
                return Err(StoreError::invalid(
                    "legend",
                    format!("bad outcome name {n:?}"),
                ));
            }
            if self.legend[..i].iter().any(|(c2, n2)| c2 == c || n2 == n) {
                return Err(StoreError::invalid(
                    "legend",
                    format!("duplicate code {c} or name {n:?}"),
                ));
            }
        }
        for (what, text) in [("params", &self.params), ("tolerances", &self.tolerances)] {
            match serde_json::from_str::<serde_json::Value>(text) {
                Ok(serde_json::Value::Object(_)) => {}
                _ => {
                    return Err(StoreError::invalid(
                        "header",
                        format!("{what} must be a JSON object, got {text:?}"),
                    ))
                }
            }
        }
        if !self.slope.is_finite() {
            return Err(StoreError::invalid(
                "header",
                format!("slope {}", self.slope),
            ));
        }
        if let Some(s) = self.shard {
            s.validate()?;
        }
        Ok(())
    }

    /// The first field in which `found` (read from `path`) differs from `self`, as an error.
    pub(crate) fn check_matches(&self, found: &BasinHeader, path: &Path) -> Result<()> {
        let mism = |field: &str, f: String, e: String| StoreError::Mismatch {
            path: path.to_path_buf(),
            field: field.to_string(),
            found: f,
            expected: e,
        };
        let bits = |v: &[f64]| v.iter().map(|a| a.to_bits()).collect::<Vec<_>>();
        if found.model != self.model {
            return Err(mism("model", found.model.clone(), self.model.clone()));
        }
        if found.slope.to_bits() != self.slope.to_bits() {
            return Err(mism(
                "slope",
                found.slope.to_string(),
                self.slope.to_string(),
            ));
        }
        if found.params != self.params {
            return Err(mism("params", found.params.clone(), self.params.clone()));
        }
        if let Some((f, e)) =
            crate::first_line_difference(&found.model_resolved, &self.model_resolved)
        {
            let absent = |s: String| {
                if s.is_empty() {
                    "(absent)".to_string()
                } else {
                    s
                }
            };
            return Err(mism("resolved model", absent(f), absent(e)));
        }
        if found.integrator != self.integrator {
            return Err(mism(
                "integrator",
                found.integrator.clone(),
                self.integrator.clone(),
            ));
        }
        if found.tolerances != self.tolerances {
            return Err(mism(
                "tolerances",
                found.tolerances.clone(),
                self.tolerances.clone(),
            ));
        }
        if found.max_strides != self.max_strides {
            return Err(mism(
                "max_strides",
                found.max_strides.to_string(),
                self.max_strides.to_string(),
            ));
        }
        for (axis, fname, fv, ename, ev) in [
            ("x", &found.x_name, &found.x, &self.x_name, &self.x),
            ("y", &found.y_name, &found.y, &self.y_name, &self.y),
        ] {
            if fname != ename {
                return Err(mism(
                    &format!("{axis} coordinate"),
                    fname.clone(),
                    ename.clone(),
                ));
            }
            if bits(fv) != bits(ev) {
                let (field, f, e) = axis_difference(&format!("{axis} grid"), fv, ev);
                return Err(mism(&field, f, e));
            }
        }
        check_z_matches(&found.z, &self.z, path)?;
        if found.state_names != self.state_names {
            return Err(mism(
                "section coordinates",
                format!("{:?}", found.state_names),
                format!("{:?}", self.state_names),
            ));
        }
        if found.legend != self.legend {
            return Err(mism(
                "legend",
                legend_json(&found.legend),
                legend_json(&self.legend),
            ));
        }
        if found.shard != self.shard {
            let show = |s: Option<ShardSpec>| s.map_or("no shard".to_string(), |s| s.to_string());
            return Err(mism("shard", show(found.shard), show(self.shard)));
        }
        Ok(())
    }
}

/// The third axis of a 3-D basin grid: a section coordinate and its values.
#[derive(Clone, Debug, PartialEq)]
pub struct ZAxis {
    /// Section coordinate along z, e.g. `"hip_rate"`.
    pub name: String,
    /// The nz values of the grid's z-slices, finite.
    pub values: Vec<f64>,
}

impl ZAxis {
    /// Rejects an empty name or values, a non-finite value, and a coordinate already an axis.
    fn validate(&self, x: &str, y: &str) -> Result<()> {
        let bad = |d: String| Err(StoreError::invalid("grid", d));
        if self.name.is_empty() {
            return bad("z axis has no name".into());
        }
        if self.values.is_empty() {
            return bad(format!("z axis ({}) has no points", self.name));
        }
        if let Some(v) = self.values.iter().find(|a| !a.is_finite()) {
            return bad(format!("z axis ({}) holds {v}", self.name));
        }
        if self.name == x || self.name == y {
            return bad(format!("z axis ({}) is also the x or y axis", self.name));
        }
        Ok(())
    }
}

/// The first difference of the z axes `found` (read from `path`) and `expected`, as an error.
fn check_z_matches(found: &Option<ZAxis>, expected: &Option<ZAxis>, path: &Path) -> Result<()> {
    let show = |z: &Option<ZAxis>| match z {
        None => "no z axis (a 2-D grid)".to_string(),
        Some(z) => format!(
            "{}: {} points {}..{}",
            z.name,
            z.values.len(),
            z.values.first().copied().unwrap_or(f64::NAN),
            z.values.last().copied().unwrap_or(f64::NAN)
        ),
    };
    let bits = |z: &Option<ZAxis>| {
        z.as_ref().map(|z| {
            let v: Vec<u64> = z.values.iter().map(|a| a.to_bits()).collect();
            (z.name.clone(), v)
        })
    };
    if bits(found) == bits(expected) {
        return Ok(());
    }
    let (field, found, expected) = match (found, expected) {
        (Some(f), Some(e)) if f.name == e.name => axis_difference("z grid", &f.values, &e.values),
        _ => ("z grid".into(), show(found), show(expected)),
    };
    Err(StoreError::Mismatch {
        path: path.to_path_buf(),
        field,
        found,
        expected,
    })
}

/// How two axes that differ bit for bit differ, as `(field, found, expected)` of a
/// [`StoreError::Mismatch`]: their sizes and ends where those differ, else the first point that
/// differs, by index, with both values in full (the shortest text that reads back to each
/// double): "y grid is point 17 = -0.19980000000000003 in the file but point 17 = -0.1998 here
/// (of 40 points -0.25..-0.15)".
fn axis_difference(field: &str, found: &[f64], expected: &[f64]) -> (String, String, String) {
    let desc = |v: &[f64]| {
        format!(
            "{} points {}..{}",
            v.len(),
            v.first().copied().unwrap_or(f64::NAN),
            v.last().copied().unwrap_or(f64::NAN)
        )
    };
    let differs = |i: usize| found[i].to_bits() != expected[i].to_bits();
    match (0..found.len().min(expected.len())).find(|&i| differs(i)) {
        Some(i) if found.len() == expected.len() => (
            field.to_string(),
            format!("point {i} = {:?}", found[i]),
            format!("point {i} = {:?} (of {})", expected[i], desc(expected)),
        ),
        _ => (field.to_string(), desc(found), desc(expected)),
    }
}

/// Chunk blocks of a grid of `nz` slices of `ny` rows: each slice is cut into blocks of
/// [`BLOCK_ROWS`] rows (the last one shorter), so that no block spans two slices and each is
/// one chunk of the datasets.
pub fn block_count(ny: usize, nz: usize) -> usize {
    nz * ny.div_ceil(BLOCK_ROWS)
}

/// The chunk block holding row `r` (row `k·ny + i` is slice k, row i) of a grid of `ny` rows
/// per slice: `r / BLOCK_ROWS` for a 2-D grid.
pub fn block_of(r: usize, ny: usize) -> usize {
    (r / ny) * ny.div_ceil(BLOCK_ROWS) + (r % ny) / BLOCK_ROWS
}

/// Rows (as writer rows, `k·ny + i`) of chunk block `b` of a grid of `ny` rows per slice.
pub fn block_range(b: usize, ny: usize) -> std::ops::Range<usize> {
    let per_slice = ny.div_ceil(BLOCK_ROWS);
    let (k, j) = (b / per_slice, b % per_slice);
    k * ny + j * BLOCK_ROWS..k * ny + ((j + 1) * BLOCK_ROWS).min(ny)
}

/// Where a chunk block's cells are in the datasets: `[rows, nx(, d)]` for a 2-D grid,
/// `[1, rows, nx(, d)]` within its z-slice for a 3-D one.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Layout {
    ny: usize,
    three_d: bool,
}

impl Layout {
    pub(crate) fn of(h: &BasinHeader) -> Self {
        Layout {
            ny: h.ny(),
            three_d: h.z.is_some(),
        }
    }

    /// Block `b` of a dataset whose cells have the trailing dimensions `trailing` (`[nx]`,
    /// `[nx, d]`): its hyperslab and its shape.
    fn block(&self, b: usize, trailing: &[usize]) -> (hdf5::Selection, Vec<usize>) {
        use hdf5::SliceOrIndex;
        let r = block_range(b, self.ny);
        let mut sel: Vec<SliceOrIndex> = Vec::new();
        let mut shape = Vec::new();
        if self.three_d {
            let k = r.start / self.ny;
            sel.push((k..k + 1).into());
            sel.push((r.start - k * self.ny..r.end - k * self.ny).into());
            shape.push(1);
        } else {
            sel.push(r.clone().into());
        }
        shape.push(r.len());
        for &t in trailing {
            sel.push((..).into());
            shape.push(t);
        }
        (hdf5::Selection::new(hdf5::Hyperslab::from(sel)), shape)
    }

    /// The values of block `b` of `ds`, row-major.
    pub(crate) fn read<T: hdf5::H5Type + Copy>(
        &self,
        ds: &Dataset,
        b: usize,
        trailing: &[usize],
    ) -> hdf5::Result<Vec<T>> {
        let (sel, _) = self.block(b, trailing);
        let a = ds.read_slice::<T, _, ndarray::IxDyn>(sel)?;
        Ok(a.iter().copied().collect())
    }

    /// Writes block `b` of `ds` from its values, row-major.
    fn write<T: hdf5::H5Type>(
        &self,
        ds: &Dataset,
        b: usize,
        trailing: &[usize],
        v: &[T],
    ) -> hdf5::Result<()> {
        let (sel, shape) = self.block(b, trailing);
        let a = ndarray::ArrayViewD::from_shape(ndarray::IxDyn(&shape), v)
            .map_err(|e| hdf5::Error::from(e.to_string()))?;
        ds.write_slice(a, sel)
    }

    /// The shape of a whole dataset whose cells have the trailing dimensions `trailing`, and
    /// its chunk (one block).
    fn dataset(&self, nz: usize, trailing: &[usize]) -> (Vec<usize>, Vec<usize>) {
        let rb = BLOCK_ROWS.min(self.ny);
        let (mut shape, mut chunk) = if self.three_d {
            (vec![nz, self.ny], vec![1, rb])
        } else {
            (vec![self.ny], vec![rb])
        };
        shape.extend_from_slice(trailing);
        chunk.extend_from_slice(trailing);
        (shape, chunk)
    }
}

/// Basin metrics of a finished grid (computed by the caller).
#[derive(Clone, Debug, PartialEq)]
pub struct BasinMetrics {
    /// Fraction of the file's cells per outcome name.
    pub fractions: Vec<(String, f64)>,
    /// Basin entropy S_b (Daza et al. 2016, Sci. Rep. 6:31416, eq. 3): mean over ε-boxes of
    /// −Σ p log p of the outcome frequencies in the box.
    pub basin_entropy: f64,
    /// Basin-boundary entropy S_bb (Daza et al. 2016, eq. 4): the same sum averaged over the
    /// boxes holding more than one outcome only.
    pub boundary_entropy: f64,
    /// Side ε of the boxes, in cells.
    pub entropy_box: usize,
}

/// An attractor used to classify cells (the selected gait, a period-2 orbit, a chaotic
/// attractor…). Its legend entry is the one of the same name. A chaotic attractor has
/// `period_strides` 0, `period_time` NaN, no multipliers, and a sample of consecutive points on
/// it as `section`.
#[derive(Clone, Debug, PartialEq)]
pub struct Attractor {
    /// Name, e.g. `"gait"`; unique in a file, no `/`.
    pub name: String,
    /// Strides per period (1 for a fixed point of the stride map).
    pub period_strides: u32,
    /// Duration of one period (model time units).
    pub period_time: f64,
    /// The `period_strides` points of the orbit on the section (a sample of points for a chaotic
    /// attractor), each of length d.
    pub section: Vec<Vec<f64>>,
    /// Floquet multipliers `(re, im)`, by decreasing modulus.
    pub multipliers: Vec<(f64, f64)>,
    /// Physical validity of the orbit (attributes `validity`, `invalid_reasons` of its group;
    /// files without them read as unchecked).
    pub validity: OrbitCheck,
}

/// Physical validity of an attractor's orbit as a file records it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum OrbitCheck {
    /// The model reports no constraint forces, or the attractor is chaotic.
    #[default]
    Unchecked,
    /// Every stride of the orbit valid.
    Valid,
    /// What fails (e.g. "a knee lock must pull"), each named once.
    Invalid(Vec<String>),
}

impl OrbitCheck {
    /// The `validity` attribute's value: `valid`, `invalid` or `not checked`.
    pub fn word(&self) -> &'static str {
        match self {
            OrbitCheck::Unchecked => "not checked",
            OrbitCheck::Valid => "valid",
            OrbitCheck::Invalid(_) => "invalid",
        }
    }

    /// What fails, if the orbit is invalid.
    pub fn reasons(&self) -> Option<&[String]> {
        match self {
            OrbitCheck::Invalid(r) => Some(r),
            _ => None,
        }
    }
}

impl Attractor {
    /// Equal name and period, and every number equal bit for bit (so that a chaotic
    /// attractor's NaN `period_time` equals itself): what [`crate::merge`] requires of shards.
    pub fn same_as(&self, other: &Attractor) -> bool {
        let bits = |v: &[f64], w: &[f64]| {
            v.len() == w.len() && v.iter().zip(w).all(|(a, b)| a.to_bits() == b.to_bits())
        };
        self.name == other.name
            && self.period_strides == other.period_strides
            && self.period_time.to_bits() == other.period_time.to_bits()
            && self.section.len() == other.section.len()
            && self
                .section
                .iter()
                .zip(&other.section)
                .all(|(a, b)| bits(a, b))
            && self.multipliers.len() == other.multipliers.len()
            && self
                .multipliers
                .iter()
                .zip(&other.multipliers)
                .all(|(a, b)| bits(&[a.0, a.1], &[b.0, b.1]))
            && self.validity == other.validity
    }

    /// `name (period k, n points)`, for messages.
    pub fn summary(&self) -> String {
        format!(
            "{} (period {}, {} points)",
            self.name,
            self.period_strides,
            self.section.len()
        )
    }
}

/// A basin file read back whole.
#[derive(Clone, Debug)]
pub struct BasinData {
    pub header: BasinHeader,
    /// pdw-store version that wrote the file.
    pub version: String,
    /// RFC 3339 UTC creation time.
    pub created: String,
    /// Computing time over all sessions (s).
    pub elapsed_s: f64,
    /// Whether every row of the file (or shard) was written and `finish` was called.
    pub complete: bool,
    /// (rows × nx) outcome codes; [`NOT_COMPUTED`] where no row was written. The rows of a
    /// 3-D grid are its (z, y) pairs ([`BasinHeader::rows`]; [`BasinData::outcome_3d`]).
    pub outcome: Array2<u8>,
    /// (rows × nx) strides until classified.
    pub strides: Array2<u16>,
    /// (rows × nx × d) last section state.
    pub final_state: Array3<f64>,
    /// (rows) whether each row is on disk.
    pub rows_done: Vec<bool>,
    /// Present once finished.
    pub metrics: Option<BasinMetrics>,
    pub attractors: Vec<Attractor>,
}

impl BasinData {
    /// The outcome codes as (nz × ny × nx), the order of the file's dataset (nz = 1 for a 2-D
    /// grid).
    pub fn outcome_3d(&self) -> ArrayView3<'_, u8> {
        let h = &self.header;
        self.outcome
            .view()
            .into_shape_with_order((h.nz(), h.ny(), h.nx()))
            .expect("rows = nz·ny")
    }
}

pub(crate) fn legend_json(legend: &[(u8, String)]) -> String {
    let m: BTreeMap<String, serde_json::Value> = legend
        .iter()
        .map(|(c, n)| (c.to_string(), serde_json::Value::String(n.clone())))
        .collect();
    serde_json::to_string(&m).unwrap_or_default()
}

/// The `legend` attribute as written: the outcome codes and the fill value
/// [`NOT_COMPUTED`] = `"not_computed"` (a cell no run has written yet).
pub(crate) fn file_legend_json(legend: &[(u8, String)]) -> String {
    let mut all = legend.to_vec();
    all.push((NOT_COMPUTED, NOT_COMPUTED_NAME.to_string()));
    legend_json(&all)
}

/// The `description` attribute of `/basin/final`: what its states are, by outcome.
pub const FINAL_DESCRIPTION: &str = "section coordinates of the last state of each cell: for \
gait, every other attractor (codes 16 and up), other and timeout, and for a walk that came to a \
stand (fall, decided on the section), the section state after the last completed stride; for \
any other fall, nonfinite or integrator_failure the section coordinates of the state where the \
stride stopped (projected, not on the section); NaN where not computed";

/// Name of the fill value [`NOT_COMPUTED`] in the file's legend.
pub const NOT_COMPUTED_NAME: &str = "not_computed";

/// The legend read from a file: its outcome codes, without the fill value.
fn parse_legend(path: &Path, text: &str) -> Result<Vec<(u8, String)>> {
    let bad = |d: String| StoreError::Format {
        path: path.to_path_buf(),
        expected: KIND,
        detail: format!("legend {text:?}: {d}"),
    };
    let m: BTreeMap<String, String> = serde_json::from_str(text).map_err(|e| bad(e.to_string()))?;
    let mut v = m
        .into_iter()
        .map(|(k, n)| {
            k.parse::<u8>()
                .map(|c| (c, n))
                .map_err(|e| bad(e.to_string()))
        })
        .collect::<Result<Vec<_>>>()?;
    v.retain(|(c, _)| *c != NOT_COMPUTED);
    v.sort_by_key(|(c, _)| *c);
    Ok(v)
}

fn format_err(path: &Path, detail: impl Into<String>) -> StoreError {
    StoreError::Format {
        path: path.to_path_buf(),
        expected: KIND,
        detail: detail.into(),
    }
}

/// Reads and checks the header of an open basin file.
fn read_header(path: &Path, f: &File) -> Result<BasinHeader> {
    let fmt = get_str(path, KIND, f, "format")?;
    if fmt != BASIN_FORMAT {
        return Err(format_err(
            path,
            format!("format is {fmt:?}, expected {BASIN_FORMAT:?}"),
        ));
    }
    let g = |name: &str| -> Result<Group> {
        f.group(name)
            .map_err(|e| format_err(path, format!("group /{name}: {e}")))
    };
    let ds = |grp: &Group, name: &str| -> Result<Dataset> {
        grp.dataset(name)
            .map_err(|e| format_err(path, format!("dataset {}/{name}: {e}", grp.name())))
    };
    let grid = g("grid")?;
    let basin = g("basin")?;
    let xd = ds(&grid, "x")?;
    let yd = ds(&grid, "y")?;
    let x = xd.read_raw::<f64>().at(path, "reading /grid/x")?;
    let y = yd.read_raw::<f64>().at(path, "reading /grid/y")?;
    let z = read_z_axis(path, &grid)?;
    let outcome = ds(&basin, "outcome")?;
    let fin = ds(&basin, "final")?;
    let names_text = get_str(path, KIND, &fin, "names")?;
    let state_names: Vec<String> = serde_json::from_str(&names_text)
        .map_err(|e| format_err(path, format!("/basin/final names {names_text:?}: {e}")))?;
    let shard = if has_attr(f, "shard_count") {
        let s = ShardSpec {
            index: get_attr::<u64>(path, KIND, f, "shard_index")? as usize,
            count: get_attr::<u64>(path, KIND, f, "shard_count")? as usize,
        };
        s.validate().map_err(|e| format_err(path, e.to_string()))?;
        Some(s)
    } else {
        None
    };
    let h = BasinHeader {
        command: get_str(path, KIND, f, "command")?,
        model: get_str(path, KIND, f, "model")?,
        slope: get_attr(path, KIND, f, "slope")?,
        params: get_str(path, KIND, f, "params")?,
        model_resolved: if has_attr(f, "model_resolved") {
            get_str(path, KIND, f, "model_resolved")?
        } else {
            String::new()
        },
        integrator: get_str(path, KIND, f, "integrator")?,
        tolerances: get_str(path, KIND, f, "tolerances")?,
        max_strides: get_attr(path, KIND, f, "max_strides")?,
        x_name: get_str(path, KIND, &xd, "name")?,
        x,
        y_name: get_str(path, KIND, &yd, "name")?,
        y,
        z,
        state_names,
        legend: parse_legend(path, &get_str(path, KIND, &outcome, "legend")?)?,
        shard,
    };
    let (nx, d, lay) = (h.nx(), h.d(), Layout::of(&h));
    for (name, dset, want) in [
        ("outcome", &outcome, lay.dataset(h.nz(), &[nx]).0),
        (
            "strides",
            &ds(&basin, "strides")?,
            lay.dataset(h.nz(), &[nx]).0,
        ),
        ("final", &fin, lay.dataset(h.nz(), &[nx, d]).0),
        ("rows_done", &ds(&basin, "rows_done")?, vec![h.rows()]),
    ] {
        if dset.shape() != want {
            return Err(format_err(
                path,
                format!(
                    "/basin/{name} has shape {:?}, expected {want:?}",
                    dset.shape()
                ),
            ));
        }
    }
    // The header's own digest (files written before it have none; their header rests on the
    // checks above alone): a damaged axis value, legend name or run attribute that still parses
    // is refused here instead of being served or resumed as valid.
    if has_attr(f, "header_digest") {
        let written: u64 = get_attr(path, KIND, f, "header_digest")?;
        let read = header_digest(&h);
        if written != read {
            return Err(format_err(
                path,
                format!(
                    "the header is damaged: the grid axes, coordinate names, legend or run \
                     attributes read back with digest {read:#018x}, written as {written:#018x} \
                     (/header_digest); the file cannot be trusted or resumed"
                ),
            ));
        }
    }
    h.validate().map_err(|e| format_err(path, e.to_string()))?;
    Ok(h)
}

/// The root attribute `header_digest`: 64-bit FNV-1a (as [`block_digest`]) over every field of
/// the header a reader trusts — the run attributes (command, model, slope, params, resolved
/// model, integrator, tolerances, stride budget), the grid axes' names and values (f64 bits),
/// the state names, the legend (in code order) and the shard — each length-prefixed so that no two headers
/// frame to the same bytes. Written when the file is created, checked by every read of the
/// header (the explorer, `--resume`, `merge`).
pub(crate) fn header_digest(h: &BasinHeader) -> u64 {
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    let mut d: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in (bytes.len() as u64).to_le_bytes().iter().chain(bytes) {
            d ^= b as u64;
            d = d.wrapping_mul(PRIME);
        }
    };
    for text in [
        &h.command,
        &h.model,
        &h.params,
        &h.model_resolved,
        &h.integrator,
        &h.tolerances,
        &h.x_name,
        &h.y_name,
    ] {
        eat(text.as_bytes());
    }
    eat(&h.slope.to_bits().to_le_bytes());
    eat(&h.max_strides.to_le_bytes());
    let bits =
        |v: &[f64]| -> Vec<u8> { v.iter().flat_map(|x| x.to_bits().to_le_bytes()).collect() };
    eat(&bits(&h.x));
    eat(&bits(&h.y));
    if let Some(z) = &h.z {
        eat(z.name.as_bytes());
        eat(&bits(&z.values));
    }
    for n in &h.state_names {
        eat(n.as_bytes());
    }
    // in code order: the file keeps the legend as a JSON object, which does not keep the order
    let mut legend = h.legend.clone();
    legend.sort();
    for (code, name) in &legend {
        eat(&[*code]);
        eat(name.as_bytes());
    }
    if let Some(sh) = h.shard {
        eat(&(sh.index as u64).to_le_bytes());
        eat(&(sh.count as u64).to_le_bytes());
    }
    d
}

/// `/grid/z` of a 3-D file (`None` for a 2-D one).
fn read_z_axis(path: &Path, grid: &Group) -> Result<Option<ZAxis>> {
    if !grid.link_exists("z") {
        return Ok(None);
    }
    let zd = grid
        .dataset("z")
        .map_err(|e| format_err(path, format!("dataset /grid/z: {e}")))?;
    Ok(Some(ZAxis {
        name: get_str(path, KIND, &zd, "name")?,
        values: zd.read_raw::<f64>().at(path, "reading /grid/z")?,
    }))
}

fn read_rows_done(path: &Path, f: &File) -> Result<Vec<bool>> {
    let v = f
        .dataset("basin/rows_done")
        .and_then(|d| d.read_raw::<u8>())
        .at(path, "reading /basin/rows_done")?;
    Ok(v.into_iter().map(|b| b != 0).collect())
}

/// Streams a basin grid into an HDF5 file, row block by row block.
///
/// Dropping the writer without [`finish`](Self::finish) writes the rows held in incomplete
/// blocks (as [`close`](Self::close) does) and leaves a valid, resumable file with
/// `complete = false`.
pub struct BasinWriter {
    path: PathBuf,
    /// `None` once closed (or handed to [`Drop`]).
    h: Option<Handles>,
    /// Held until the writer is dropped: no other process writes this file meanwhile.
    _lock: OutputLock,
    /// Set by a failed HDF5 call: the handles are then leaked, not closed (HDF5's close after a
    /// failed write can crash; the file stays as of its last successful flush).
    poisoned: bool,
    /// Blocks found damaged (checksum or content) by [`resume`](Self::resume), to recompute.
    damaged: Vec<usize>,
    header: BasinHeader,
    /// (ny) rows on disk.
    rows_done: Vec<bool>,
    /// (ny) rows this file may hold (its shard's, or all).
    own: Vec<bool>,
    /// Blocks with some rows received but not yet written, by block index.
    pending: BTreeMap<usize, PendingBlock>,
    elapsed_before: f64,
    started: Instant,
}

/// The open HDF5 objects of a writer.
struct Handles {
    file: File,
    outcome: Dataset,
    strides: Dataset,
    final_state: Dataset,
    rows_done_ds: Dataset,
    /// `/basin/block_digest`: per block, [`block_digest`] of the values written.
    digest_ds: Dataset,
}

impl Handles {
    /// Closes the datasets, then the file.
    fn close(self, path: &Path) -> Result<()> {
        let Handles {
            file,
            outcome,
            strides,
            final_state,
            rows_done_ds,
            digest_ds,
        } = self;
        drop((outcome, strides, final_state, rows_done_ds, digest_ds));
        file.close().at(path, "closing")
    }
}

impl Drop for BasinWriter {
    fn drop(&mut self) {
        if self.h.is_some() && !self.poisoned {
            // As `close`, without a way to report a failure (which poisons the writer).
            let _ = self.write_held_rows();
        }
        if let Some(h) = self.h.take() {
            if self.poisoned {
                std::mem::forget(h);
            } else {
                let _ = h.close(&self.path);
            }
        }
    }
}

impl std::fmt::Debug for BasinWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BasinWriter")
            .field("path", &self.path)
            .field("rows_done", &self.rows_done.iter().filter(|b| **b).count())
            .finish()
    }
}

impl BasinWriter {
    /// Creates a new basin file at `path` with `complete = false` and no rows.
    ///
    /// An existing file is an error ([`StoreError::Exists`], file untouched) unless `force`,
    /// which replaces it.
    pub fn create(path: impl AsRef<Path>, header: &BasinHeader, force: bool) -> Result<Self> {
        let path = path.as_ref();
        header.validate()?;
        let reserve =
            64 * 1024 + 8 * (header.nx() + header.ny() + header.nz()) as u64 + header.rows() as u64;
        let (file, lock) = create_file(path, force, true, reserve)?;
        let mut made = Vec::new();
        match Self::init(path, &file, header, &mut made) {
            Ok(h) => Ok(BasinWriter {
                path: path.to_path_buf(),
                h: Some(h),
                _lock: lock,
                poisoned: false,
                damaged: Vec::new(),
                header: header.clone(),
                rows_done: vec![false; header.rows()],
                own: own_mask(header),
                pending: BTreeMap::new(),
                elapsed_before: 0.0,
                started: Instant::now(),
            }),
            Err(e) => {
                // A half-initialised file is useless: do not leave it behind. Its HDF5 objects
                // are leaked, not closed (closing after a failed write can crash HDF5).
                std::mem::forget(made);
                std::mem::forget(file);
                let _ = std::fs::remove_file(path);
                Err(e)
            }
        }
    }

    /// Writes the header and creates the datasets; every object created is pushed onto `made`
    /// so that the caller decides whether to close or leak them.
    fn init(
        path: &Path,
        file: &File,
        h: &BasinHeader,
        made: &mut Vec<hdf5::Location>,
    ) -> Result<Handles> {
        let file = file.clone();
        let (nx, d, nz, lay) = (h.nx(), h.d(), h.nz(), Layout::of(h));
        let (rows, blocks) = (h.rows(), h.blocks());
        for (k, v) in [
            ("format", BASIN_FORMAT),
            ("version", env!("CARGO_PKG_VERSION")),
            ("command", &h.command),
            ("created", &time::now_rfc3339()),
            ("model", &h.model),
            ("params", &h.params),
            ("model_resolved", &h.model_resolved),
            ("integrator", &h.integrator),
            ("tolerances", &h.tolerances),
        ] {
            set_str(path, &file, k, v)?;
        }
        set_attr(path, &file, "slope", &h.slope)?;
        set_attr(path, &file, "max_strides", &h.max_strides)?;
        set_attr(path, &file, "elapsed_s", &0.0f64)?;
        set_attr(path, &file, "complete", &false)?;
        if let Some(s) = h.shard {
            set_attr(path, &file, "shard_index", &(s.index as u64))?;
            set_attr(path, &file, "shard_count", &(s.count as u64))?;
        }
        write_grid(path, &file, h, made)?;
        set_attr(path, &file, "header_digest", &header_digest(h))?;
        let basin = file.create_group("basin").at(path, "creating /basin")?;
        made.push((*basin).clone());
        let (cells, cells_chunk) = lay.dataset(nz, &[nx]);
        let (states, states_chunk) = lay.dataset(nz, &[nx, d]);
        let outcome = basin
            .new_dataset::<u8>()
            .shape(cells.clone())
            .chunk(cells_chunk.clone())
            .deflate(DEFLATE_LEVEL)
            .fletcher32()
            .fill_value(NOT_COMPUTED)
            .create("outcome")
            .at(path, "creating /basin/outcome")?;
        made.push((**outcome).clone());
        set_str(path, &outcome, "legend", &file_legend_json(&h.legend))?;
        let strides = basin
            .new_dataset::<u16>()
            .shape(cells)
            .chunk(cells_chunk)
            .shuffle()
            .deflate(DEFLATE_LEVEL)
            .fletcher32()
            .create("strides")
            .at(path, "creating /basin/strides")?;
        made.push((**strides).clone());
        let final_state = basin
            .new_dataset::<f64>()
            .shape(states)
            .chunk(states_chunk)
            .shuffle()
            .deflate(DEFLATE_LEVEL)
            .fletcher32()
            .fill_value(f64::NAN)
            .create("final")
            .at(path, "creating /basin/final")?;
        made.push((**final_state).clone());
        let names = serde_json::to_string(&h.state_names).unwrap_or_default();
        set_str(path, &final_state, "names", &names)?;
        set_str(path, &final_state, "description", FINAL_DESCRIPTION)?;
        let rows_done_ds = basin
            .new_dataset::<u8>()
            .shape([rows])
            .create("rows_done")
            .at(path, "creating /basin/rows_done")?;
        made.push((**rows_done_ds).clone());
        rows_done_ds
            .write_raw(&vec![0u8; rows])
            .at(path, "writing /basin/rows_done")?;
        let digest_ds = basin
            .new_dataset::<u64>()
            .shape([blocks])
            .create("block_digest")
            .at(path, "creating /basin/block_digest")?;
        made.push((**digest_ds).clone());
        digest_ds
            .write_raw(&vec![0u64; blocks])
            .at(path, "writing /basin/block_digest")?;
        set_str(path, &digest_ds, "description", DIGEST_DESCRIPTION)?;
        file.flush().at(path, "flushing")?;
        Ok(Handles {
            file,
            outcome,
            strides,
            final_state,
            rows_done_ds,
            digest_ds,
        })
    }

    /// Reopens a file made for the same run as `expected` (same model, slope, params,
    /// integrator, tolerances, stride budget, grid, coordinates, legend, shard) to continue it.
    ///
    /// Every block marked done is read back and checked before it is trusted: its chunks'
    /// Fletcher-32 checksums (files written by this version) and its outcome codes (all in the
    /// legend). A block that fails either check is recomputed ([`damaged_rows`](Self::damaged_rows)
    /// lists it) and the file is marked incomplete until it is. A complete file whose every
    /// block, metric and attractor reads back intact gives [`StoreError::AlreadyComplete`].
    ///
    /// A file that does not match gives [`StoreError::Mismatch`], a corrupt header
    /// [`StoreError::Format`] or [`StoreError::Hdf5`], a file another process is writing
    /// [`StoreError::Busy`]; in these cases the file is not modified. Rows still to do:
    /// [`rows_todo`](Self::rows_todo).
    pub fn resume(path: impl AsRef<Path>, expected: &BasinHeader) -> Result<Self> {
        let path = path.as_ref();
        expected.validate()?;
        let old_lock = lock_existing(path)?;
        let old = open_locked(path, false)?;
        let found = read_header(path, &old)?;
        expected.check_matches(&found, path)?;
        let complete = get_attr::<bool>(path, KIND, &old, "complete")?;
        let mut rows_done = read_rows_done(path, &old)?;
        // A partly marked block is one a stopped run wrote with the rows it had; it is checked
        // against its digest like a whole one. Files without digests were written by versions
        // that wrote whole blocks only: a partly marked block there is redone whole.
        if !matches!(read_digests(&old, found.blocks()), Some(Some(_))) {
            for b in 0..found.blocks() {
                let r = block_range(b, found.ny());
                if !rows_done[r.clone()].iter().all(|d| *d) {
                    rows_done[r].iter_mut().for_each(|d| *d = false);
                }
            }
        }
        let damaged = damaged_blocks(&old, &found, &rows_done);
        // Everything `read_basin` reads besides the blocks must read back too: a damaged
        // `created` string would otherwise make a file "complete" that no reader opens.
        let run_ok = get_str(path, KIND, &old, "version").is_ok()
            && get_str(path, KIND, &old, "created").is_ok()
            && get_attr::<f64>(path, KIND, &old, "elapsed_s").is_ok();
        let extras_ok = !complete
            || (run_ok
                && read_metrics(path, &old, &found.legend).is_ok_and(|m| m.is_some())
                && read_attractors(path, &old).is_ok()
                && (!old.link_exists("provenance")
                    || crate::provenance::read_provenance(path, &old).is_ok_and(|p| p.is_some())));
        if complete && damaged.is_empty() && extras_ok {
            return Err(StoreError::AlreadyComplete {
                path: path.to_path_buf(),
            });
        }
        for &b in &damaged {
            let r = block_range(b, found.ny());
            rows_done[r].iter_mut().for_each(|d| *d = false);
        }
        // The rows of partly marked blocks go back into memory, to be written with the rest of
        // their block (or again when this run stops): completing the chunk in place would
        // write it a second time (see the module's notes on crash safety).
        let mut pending = BTreeMap::new();
        for b in 0..found.blocks() {
            let r = block_range(b, found.ny());
            let marked = rows_done[r.clone()].to_vec();
            if marked.iter().any(|d| *d) && !marked.iter().all(|d| *d) {
                pending.insert(b, read_partial_block(path, &old, &found, b, &marked)?);
                rows_done[r].iter_mut().for_each(|d| *d = false);
            }
        }
        let elapsed_before = get_attr::<f64>(path, KIND, &old, "elapsed_s")?;
        let created = get_str(path, KIND, &old, "created").ok();
        // The verified blocks go into a fresh file beside the old one, which then replaces it
        // (one rename). Writing into a killed file in place is not safe: its last flush may
        // have been cut between the chunk index and the superblock's end-of-allocation, and
        // HDF5 then allocates new space over live metadata ("addr overflow" on the next flush;
        // observed under repeated SIGKILL). Until the rename the old file is untouched, so a
        // kill during the rebuild loses nothing.
        let tmp = temp_sibling(path);
        let reserve = 64 * 1024
            + 8 * (found.nx() + found.ny() + found.nz()) as u64
            + found.rows() as u64
            + std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
        let (file, lock) = create_file(&tmp, true, true, reserve)?;
        let mut made = Vec::new();
        let rebuilt = Self::init(&tmp, &file, &found, &mut made).and_then(|h| {
            copy_done_blocks(path, &old, &tmp, &h, &found, &rows_done)?;
            crate::provenance::carry_history(path, &old, &tmp, &h.file)?;
            set_attr(&tmp, &h.file, "elapsed_s", &elapsed_before)?;
            if let Some(c) = &created {
                set_str(&tmp, &h.file, "created", c)?;
            }
            let marks: Vec<u8> = rows_done.iter().map(|&d| d as u8).collect();
            h.rows_done_ds
                .write_raw(&marks)
                .at(&tmp, "writing /basin/rows_done")?;
            h.file.flush().at(&tmp, "flushing")?;
            Ok(h)
        });
        let h = match rebuilt {
            Ok(h) => h,
            Err(e) => {
                // As in `create`: leak the half-made objects, remove the partial file.
                std::mem::forget(made);
                std::mem::forget(file);
                let _ = std::fs::remove_file(&tmp);
                return Err(e);
            }
        };
        drop(made);
        drop(file);
        rename_into_place(&tmp, path)?;
        drop(old);
        drop(old_lock);
        let own = own_mask(&found);
        Ok(BasinWriter {
            path: path.to_path_buf(),
            h: Some(h),
            _lock: lock,
            poisoned: false,
            damaged,
            header: found,
            rows_done,
            own,
            pending,
            elapsed_before,
            started: Instant::now(),
        })
    }

    /// Rows of blocks that [`resume`](Self::resume) found marked done but damaged (failed
    /// checksum, unreadable, or outcome codes outside the legend); they are among
    /// [`rows_todo`](Self::rows_todo).
    pub fn damaged_rows(&self) -> Vec<usize> {
        self.damaged
            .iter()
            .flat_map(|&b| block_range(b, self.header.ny()))
            .collect()
    }

    /// What the CLI's `--resume` / `--force` mean: with `resume`, continue `path` if it exists
    /// ([`resume`](Self::resume); `force` is ignored, a mismatched file is an error, never
    /// replaced) or create it if it does not; without `resume`, [`create`](Self::create) with
    /// `force`.
    pub fn start(
        path: impl AsRef<Path>,
        header: &BasinHeader,
        resume: bool,
        force: bool,
    ) -> Result<Self> {
        let path = path.as_ref();
        if resume && path.exists() {
            Self::resume(path, header)
        } else {
            Self::create(path, header, force)
        }
    }

    /// Writes the rows of incomplete blocks (marked done, so that every row handed over is on
    /// disk), flushes and closes the file without finishing it (`complete` stays false).
    /// Dropping the writer does the same but cannot report errors.
    pub fn close(mut self) -> Result<()> {
        let p = self.path.clone();
        let r = (|| {
            self.write_held_rows()?;
            set_attr(&p, &self.h().file, "elapsed_s", &self.elapsed())?;
            self.h().file.flush().at(&p, "flushing")
        })();
        self.close_after(r)
    }

    /// Closes the handles after `r` succeeded; after a failure marks the writer poisoned so
    /// that [`Drop`] leaks them instead.
    fn close_after(&mut self, r: Result<()>) -> Result<()> {
        match r {
            Ok(()) => {
                let h = self.h.take().expect("writer is open");
                h.close(&self.path)
            }
            Err(e) => {
                self.poisoned = true;
                Err(e)
            }
        }
    }

    fn h(&self) -> &Handles {
        self.h.as_ref().expect("writer is open")
    }

    /// The file's header.
    pub fn header(&self) -> &BasinHeader {
        &self.header
    }

    /// The file path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// (ny) whether each row is on disk.
    pub fn rows_done(&self) -> &[bool] {
        &self.rows_done
    }

    /// Rows of this file (its shard's, or all) still to compute, ascending: neither on disk nor
    /// held in memory in an incomplete block (handed to [`write_rows`](Self::write_rows), or
    /// taken back by [`resume`](Self::resume) from a block written before it was complete).
    pub fn rows_todo(&self) -> Vec<usize> {
        (0..self.header.rows())
            .filter(|&i| self.own[i] && !self.rows_done[i] && !self.held(i))
            .collect()
    }

    /// Whether row `r` is held in memory in an incomplete block.
    fn held(&self, r: usize) -> bool {
        let ny = self.header.ny();
        let b = block_of(r, ny);
        self.pending
            .get(&b)
            .is_some_and(|pb| pb.have[r - block_range(b, ny).start])
    }

    /// Hands over rows `row0 .. row0 + k`; every chunk block they complete is written and
    /// flushed, then marked done and flushed again. Returns the number of rows that reached the
    /// disk in this call.
    ///
    /// `outcome` and `strides` are (k × nx) row-major, `final_state` (k × nx × d) row-major.
    /// Every row must belong to this file (its shard) and not be on disk already; outcome codes
    /// must be in the legend. Rows of incomplete blocks wait in memory (at most
    /// [`BLOCK_ROWS`]` − 1` rows per block) and are written when the writer is closed or
    /// dropped; a process killed outright (SIGKILL) loses them, and
    /// [`rows_todo`](Self::rows_todo) lists them again after [`resume`](Self::resume).
    pub fn write_rows(
        &mut self,
        row0: usize,
        outcome: &[u8],
        strides: &[u16],
        final_state: &[f64],
    ) -> Result<usize> {
        let (nx, ny, d) = (self.header.nx(), self.header.ny(), self.header.d());
        let rows = self.header.rows();
        if outcome.is_empty() || (outcome.len() / nx) * nx != outcome.len() {
            return Err(StoreError::invalid(
                "row block",
                format!(
                    "outcome has {} values, not a positive multiple of nx = {nx}",
                    outcome.len()
                ),
            ));
        }
        let k = outcome.len() / nx;
        if strides.len() != k * nx || final_state.len() != k * nx * d {
            return Err(StoreError::invalid(
                "row block",
                format!(
                    "{k} rows of {nx} cells need {} strides and {} final values (d = {d}), got {} and {}",
                    k * nx,
                    k * nx * d,
                    strides.len(),
                    final_state.len()
                ),
            ));
        }
        if row0 + k > rows {
            return Err(StoreError::invalid(
                "row block",
                format!("rows {row0}..{} outside the grid's {rows} rows", row0 + k),
            ));
        }
        if let Some(r) = (row0..row0 + k).find(|&r| !self.own[r]) {
            return Err(StoreError::invalid(
                "row block",
                format!("row {r} does not belong to this shard"),
            ));
        }
        if let Some(r) = (row0..row0 + k).find(|&r| self.rows_done[r]) {
            return Err(StoreError::invalid(
                "row block",
                format!("row {r} is already on disk"),
            ));
        }
        if let Some(c) = outcome
            .iter()
            .find(|c| !self.header.legend.iter().any(|(l, _)| l == *c))
        {
            return Err(StoreError::invalid(
                "row block",
                format!(
                    "outcome code {c} is not in the legend {}",
                    legend_json(&self.header.legend)
                ),
            ));
        }
        let mut complete = Vec::new();
        for r in row0..row0 + k {
            let b = block_of(r, ny);
            let range = block_range(b, ny);
            let kb = range.len();
            let pb = self
                .pending
                .entry(b)
                .or_insert_with(|| PendingBlock::empty(kb, nx, d));
            let (i, src) = (r - range.start, r - row0);
            pb.outcome[i * nx..(i + 1) * nx].copy_from_slice(&outcome[src * nx..(src + 1) * nx]);
            pb.strides[i * nx..(i + 1) * nx].copy_from_slice(&strides[src * nx..(src + 1) * nx]);
            pb.final_state[i * nx * d..(i + 1) * nx * d]
                .copy_from_slice(&final_state[src * nx * d..(src + 1) * nx * d]);
            pb.have[i] = true;
            if pb.have.iter().all(|h| *h) && complete.last() != Some(&b) {
                complete.push(b);
            }
        }
        let mut written = 0;
        for b in complete {
            written += self.write_pending(b)?;
        }
        Ok(written)
    }

    /// Writes the held block `b` ([`write_block`](Self::write_block)) and drops it from the
    /// held rows; a failed write poisons the writer. Returns the rows written.
    fn write_pending(&mut self, b: usize) -> Result<usize> {
        let pb = &self.pending[&b];
        // Uncompressed size: compression only shrinks it.
        ensure_space(
            &self.path,
            (pb.outcome.len() * (3 + 8 * self.header.d())) as u64,
        )?;
        let pb = self.pending.remove(&b).expect("block is held");
        self.write_block(b, &pb)
            .inspect_err(|_| self.poisoned = true)
    }

    /// Writes every block with rows held in memory, each as it is (the rows not received keep
    /// the fill values), and marks the rows received: what `close` and `Drop` do so that every
    /// finished row of a stopped run is on disk. Each such chunk is still written once in this
    /// file; [`resume`](Self::resume) takes the rows back into memory instead of completing the
    /// chunk in place.
    fn write_held_rows(&mut self) -> Result<()> {
        let blocks: Vec<usize> = self.pending.keys().copied().collect();
        for b in blocks {
            self.write_pending(b)?;
        }
        Ok(())
    }

    /// Writes one chunk block, flushes, marks its received rows done (`pb.have`; all of them for
    /// a complete block), flushes. Returns the rows marked.
    fn write_block(&mut self, b: usize, pb: &PendingBlock) -> Result<usize> {
        let (nx, d, lay) = (self.header.nx(), self.header.d(), Layout::of(&self.header));
        let range = block_range(b, self.header.ny());
        let (r0, r1) = (range.start, range.end);
        let p = &self.path;
        let h = self.h.as_ref().expect("writer is open");
        lay.write(&h.outcome, b, &[nx], &pb.outcome)
            .at(p, "writing /basin/outcome")?;
        lay.write(&h.strides, b, &[nx], &pb.strides)
            .at(p, "writing /basin/strides")?;
        lay.write(&h.final_state, b, &[nx, d], &pb.final_state)
            .at(p, "writing /basin/final")?;
        set_attr(p, &h.file, "elapsed_s", &self.elapsed())?;
        h.file.flush().at(p, "flushing")?;
        let marks: Vec<u8> = pb.have.iter().map(|&h| u8::from(h)).collect();
        h.digest_ds
            .write_slice(
                &[block_digest(&pb.outcome, &pb.strides, &pb.final_state)],
                s![b..b + 1],
            )
            .at(p, "writing /basin/block_digest")?;
        h.rows_done_ds
            .write_slice(&marks, s![r0..r1])
            .at(p, "writing /basin/rows_done")?;
        h.file.flush().at(p, "flushing")?;
        for (done, &have) in self.rows_done[r0..r1].iter_mut().zip(&pb.have) {
            *done |= have;
        }
        Ok(pb.have.iter().filter(|&&h| h).count())
    }

    /// Reads back the (rows × nx) outcome codes written so far ([`NOT_COMPUTED`] elsewhere),
    /// e.g. to compute metrics before [`finish`](Self::finish); a 3-D grid's rows are its
    /// (z, y) pairs ([`BasinHeader::rows`]).
    pub fn read_outcome(&self) -> Result<Array2<u8>> {
        let v = self
            .h()
            .outcome
            .read_raw::<u8>()
            .at(&self.path, "reading /basin/outcome")?;
        Array2::from_shape_vec((self.header.rows(), self.header.nx()), v)
            .map_err(|e| format_err(&self.path, format!("/basin/outcome: {e}")))
    }

    pub(crate) fn set_elapsed_before(&mut self, s: f64) {
        self.elapsed_before = s;
    }

    fn elapsed(&self) -> f64 {
        self.elapsed_before + self.started.elapsed().as_secs_f64()
    }

    /// Writes provenance, units, the slice and dimension scales into the open file
    /// ([`crate::provenance::annotate_file`]) and flushes.
    pub fn annotate(&mut self, a: &crate::provenance::Annotations<'_>) -> Result<()> {
        let p = self.path.clone();
        ensure_space(&p, 0)?;
        let r = (|| {
            let f = &self.h().file;
            crate::provenance::annotate_file(&p, f, a)?;
            f.flush().at(&p, "flushing")
        })();
        if r.is_err() {
            self.poisoned = true;
        }
        r
    }

    /// Writes `/metrics` and `/attractors`, sets `complete = true` and closes the file.
    ///
    /// Every row of the file (or shard) must be on disk ([`StoreError::Incomplete`] otherwise).
    pub fn finish(mut self, metrics: &BasinMetrics, attractors: &[Attractor]) -> Result<()> {
        let expected = self.own.iter().filter(|b| **b).count();
        let done = (0..self.header.rows())
            .filter(|&i| self.own[i] && self.rows_done[i])
            .count();
        if done < expected {
            return Err(StoreError::Incomplete {
                path: self.path.clone(),
                done,
                expected,
            });
        }
        let p = self.path.clone();
        ensure_space(&p, 0)?;
        let r = (|| {
            let f = &self.h().file;
            write_metrics(&p, f, metrics)?;
            write_attractors(&p, f, attractors, self.header.d())?;
            set_attr(&p, f, "elapsed_s", &self.elapsed())?;
            f.flush().at(&p, "flushing")?;
            // `complete` only once everything else is on disk.
            set_attr(&p, f, "complete", &true)?;
            f.flush().at(&p, "flushing")
        })();
        self.close_after(r)
    }
}

/// `/grid`: the axes' values, each with its coordinate's `name` (`z` only for a 3-D grid).
fn write_grid(
    path: &Path,
    file: &File,
    h: &BasinHeader,
    made: &mut Vec<hdf5::Location>,
) -> Result<()> {
    let grid = file.create_group("grid").at(path, "creating /grid")?;
    made.push((*grid).clone());
    let mut axes = vec![("x", &h.x_name, &h.x), ("y", &h.y_name, &h.y)];
    if let Some(z) = &h.z {
        axes.push(("z", &z.name, &z.values));
    }
    for (name, coord, v) in axes {
        let ds = grid
            .new_dataset::<f64>()
            .shape([v.len()])
            .create(name)
            .at(path, "creating the grid")?;
        made.push((**ds).clone());
        ds.write_raw(v.as_slice()).at(path, "writing the grid")?;
        set_str(path, &ds, "name", coord)?;
    }
    Ok(())
}

/// Rows of one chunk block received so far (or, after [`BasinWriter::resume`], found on disk in
/// a block written before it was complete).
struct PendingBlock {
    /// (k × nx) outcome codes, k = rows in the block.
    outcome: Vec<u8>,
    /// (k × nx) strides.
    strides: Vec<u16>,
    /// (k × nx × d) final states.
    final_state: Vec<f64>,
    /// (k) rows received.
    have: Vec<bool>,
}

impl PendingBlock {
    /// A block of `k` rows of `nx` cells with no row received: every cell holds the fill value
    /// of its dataset (what reading a never-written row gives).
    fn empty(k: usize, nx: usize, d: usize) -> Self {
        PendingBlock {
            outcome: vec![NOT_COMPUTED; k * nx],
            strides: vec![0; k * nx],
            final_state: vec![f64::NAN; k * nx * d],
            have: vec![false; k],
        }
    }
}

/// Blocks with rows marked done in `rows_done` that do not read back intact: a chunk fails its
/// checksum or cannot be read, the block's digest differs, or an outcome code of a marked row is
/// outside the legend (e.g. the fill value of a chunk never written).
fn damaged_blocks(f: &File, h: &BasinHeader, rows_done: &[bool]) -> Vec<usize> {
    let Ok(basin) = f.group("basin") else {
        return (0..h.blocks()).collect();
    };
    let (o, st, fs) = (
        basin.dataset("outcome"),
        basin.dataset("strides"),
        basin.dataset("final"),
    );
    let (Ok(o), Ok(st), Ok(fs)) = (o, st, fs) else {
        return (0..h.blocks()).collect();
    };
    // Type and filter pipeline as written (a damaged datatype or filter message reads back
    // different values without any error): otherwise every block is suspect. Files from
    // before the checksums have the same pipeline without Fletcher-32.
    let as_written = |ds: &hdf5::Dataset, t: hdf5::Result<hdf5::Datatype>, shuffle: bool| {
        use hdf5::filters::Filter;
        let mut want: Vec<Filter> = Vec::new();
        if shuffle {
            want.push(Filter::Shuffle);
        }
        want.push(Filter::Deflate(DEFLATE_LEVEL));
        let f = ds.filters();
        let filters_ok = f == want
            || (f.len() == want.len() + 1
                && f[..want.len()] == want[..]
                && f[want.len()] == Filter::Fletcher32);
        filters_ok && t.is_ok_and(|t| ds.dtype().is_ok_and(|d| d == t))
    };
    if !(as_written(&o, hdf5::Datatype::from_type::<u8>(), false)
        && as_written(&st, hdf5::Datatype::from_type::<u16>(), true)
        && as_written(&fs, hdf5::Datatype::from_type::<f64>(), true))
    {
        return (0..h.blocks()).collect();
    }
    // The digest of each block as written (files from before it have none: the checks below
    // then rest on the checksums and the outcome codes).
    let Some(digests) = read_digests(f, h.blocks()) else {
        return (0..h.blocks()).collect();
    };
    let mut bad = Vec::new();
    let (lay, nx, d) = (Layout::of(h), h.nx(), h.d());
    for b in 0..h.blocks() {
        let r = block_range(b, h.ny());
        let marked = &rows_done[r.clone()];
        if !marked.iter().any(|d| *d) {
            continue;
        }
        let read = (
            lay.read::<u8>(&o, b, &[nx]),
            lay.read::<u16>(&st, b, &[nx]),
            lay.read::<f64>(&fs, b, &[nx, d]),
        );
        let ok = match read {
            (Ok(ov), Ok(sv), Ok(fv)) => {
                ov.chunks(h.nx())
                    .zip(marked)
                    .filter(|(_, m)| **m)
                    .all(|(row, _)| row.iter().all(|c| h.legend.iter().any(|(l, _)| l == c)))
                    && digests
                        .as_ref()
                        .is_none_or(|d| d[b] == block_digest(&ov, &sv, &fv))
            }
            _ => false,
        };
        if !ok {
            bad.push(b);
        }
    }
    bad
}

/// The marked rows (`marked`, one flag per row of the block) of block `b` of the open file
/// `old`, as a block held in memory; the other rows hold the fill values.
fn read_partial_block(
    path: &Path,
    old: &File,
    h: &BasinHeader,
    b: usize,
    marked: &[bool],
) -> Result<PendingBlock> {
    let (nx, d, lay) = (h.nx(), h.d(), Layout::of(h));
    let r = block_range(b, h.ny());
    let basin = old.group("basin").at(path, "opening /basin")?;
    let open = |n: &str| basin.dataset(n).at(path, "opening the basin datasets");
    let ov: Vec<u8> = lay
        .read(&open("outcome")?, b, &[nx])
        .at(path, "reading /basin/outcome")?;
    let sv: Vec<u16> = lay
        .read(&open("strides")?, b, &[nx])
        .at(path, "reading /basin/strides")?;
    let fv: Vec<f64> = lay
        .read(&open("final")?, b, &[nx, d])
        .at(path, "reading /basin/final")?;
    let mut pb = PendingBlock::empty(r.len(), nx, d);
    for i in (0..r.len()).filter(|&i| marked[i]) {
        let (c, f) = (i * nx..(i + 1) * nx, i * nx * d..(i + 1) * nx * d);
        pb.outcome[c.clone()].copy_from_slice(&ov[c.clone()]);
        pb.strides[c.clone()].copy_from_slice(&sv[c]);
        pb.final_state[f.clone()].copy_from_slice(&fv[f]);
        pb.have[i] = true;
    }
    Ok(pb)
}

/// Copies every block whose rows are all marked in `rows_done` from the open file `old` into
/// the new file's datasets `h` (whole chunk blocks, each written once; [`resume`]).
///
/// [`resume`]: BasinWriter::resume
fn copy_done_blocks(
    old_path: &Path,
    old: &File,
    new_path: &Path,
    h: &Handles,
    header: &BasinHeader,
    rows_done: &[bool],
) -> Result<()> {
    let basin = old.group("basin").at(old_path, "opening /basin")?;
    let open = |n: &str| basin.dataset(n).at(old_path, "opening the basin datasets");
    let (o, st, fs) = (open("outcome")?, open("strides")?, open("final")?);
    let (lay, nx, d) = (Layout::of(header), header.nx(), header.d());
    for b in 0..header.blocks() {
        let r = block_range(b, header.ny());
        if !rows_done[r.clone()].iter().all(|d| *d) {
            continue;
        }
        let ov: Vec<u8> = lay
            .read(&o, b, &[nx])
            .at(old_path, "reading /basin/outcome")?;
        let sv: Vec<u16> = lay
            .read(&st, b, &[nx])
            .at(old_path, "reading /basin/strides")?;
        let fv: Vec<f64> = lay
            .read(&fs, b, &[nx, d])
            .at(old_path, "reading /basin/final")?;
        lay.write(&h.outcome, b, &[nx], &ov)
            .at(new_path, "writing /basin/outcome")?;
        lay.write(&h.strides, b, &[nx], &sv)
            .at(new_path, "writing /basin/strides")?;
        lay.write(&h.final_state, b, &[nx, d], &fv)
            .at(new_path, "writing /basin/final")?;
        h.digest_ds
            .write_slice(&[block_digest(&ov, &sv, &fv)], s![b..b + 1])
            .at(new_path, "writing /basin/block_digest")?;
    }
    Ok(())
}

/// What `/basin/block_digest` holds.
const DIGEST_DESCRIPTION: &str = "per block of BLOCK_ROWS rows: 64-bit FNV-1a of the block's \
     outcome bytes, strides (u16 little-endian) and final states (f64 bits little-endian), in \
     row-major order; 0 for a block not written. Checked on resume and merge: a block whose \
     values read back different from what was written is recomputed or refused";

/// 64-bit FNV-1a (Fowler–Noll–Vo) over a block's outcome codes, stride counts and final states
/// (little-endian bytes, row-major): end-to-end evidence that a block reads back as written,
/// whatever part of the file (data, chunk index, object headers) was damaged.
pub(crate) fn block_digest(outcome: &[u8], strides: &[u16], final_state: &[f64]) -> u64 {
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h ^= b as u64;
            h = h.wrapping_mul(PRIME);
        }
    };
    eat(outcome);
    for v in strides {
        eat(&v.to_le_bytes());
    }
    for v in final_state {
        eat(&v.to_bits().to_le_bytes());
    }
    h
}

/// `/basin/block_digest` of an open file of `blocks` chunk blocks ([`BasinHeader::blocks`]):
/// `Some(None)` for files written before it existed, `None` if it is there but cannot be read
/// whole (damage).
pub(crate) fn read_digests(f: &File, blocks: usize) -> Option<Option<Vec<u64>>> {
    let Ok(basin) = f.group("basin") else {
        return None;
    };
    if !basin.link_exists("block_digest") {
        return Some(None);
    }
    let v = basin
        .dataset("block_digest")
        .and_then(|d| d.read_raw::<u64>())
        .ok()?;
    (v.len() == blocks).then_some(Some(v))
}

fn own_mask(h: &BasinHeader) -> Vec<bool> {
    let mut own = vec![false; h.rows()];
    for r in h.own_rows() {
        own[r] = true;
    }
    own
}

pub(crate) fn write_metrics(path: &Path, file: &File, m: &BasinMetrics) -> Result<()> {
    if file.link_exists("metrics") {
        file.unlink("metrics").at(path, "replacing /metrics")?;
    }
    let g = file.create_group("metrics").at(path, "creating /metrics")?;
    set_attr(path, &g, "basin_entropy", &m.basin_entropy)?;
    set_attr(path, &g, "boundary_entropy", &m.boundary_entropy)?;
    set_attr(path, &g, "entropy_box", &(m.entropy_box as u64))?;
    let mut obj = serde_json::Map::new();
    for (name, f) in &m.fractions {
        if name.is_empty() || name.contains('/') {
            return Err(StoreError::invalid(
                "metrics",
                format!("bad outcome name {name:?}"),
            ));
        }
        obj.insert(name.clone(), serde_json::json!(f));
        set_attr(path, &g, &format!("fraction_{name}"), f)?;
    }
    set_str(
        path,
        &g,
        "fractions",
        &serde_json::Value::Object(obj).to_string(),
    )
}

pub(crate) fn write_attractors(
    path: &Path,
    file: &File,
    list: &[Attractor],
    d: usize,
) -> Result<()> {
    for (i, a) in list.iter().enumerate() {
        if a.name.is_empty() || a.name.contains('/') || a.name == "." || a.name == ".." {
            return Err(StoreError::invalid(
                "attractor",
                format!("bad name {:?}", a.name),
            ));
        }
        if list[..i].iter().any(|b| b.name == a.name) {
            return Err(StoreError::invalid(
                "attractor",
                format!("duplicate name {:?}", a.name),
            ));
        }
        if a.section.is_empty() || a.section.iter().any(|p| p.len() != d) {
            return Err(StoreError::invalid(
                "attractor",
                format!("{}: section points must each have d = {d} values", a.name),
            ));
        }
    }
    if file.link_exists("attractors") {
        file.unlink("attractors")
            .at(path, "replacing /attractors")?;
    }
    let g = file
        .create_group("attractors")
        .at(path, "creating /attractors")?;
    for a in list {
        let ga = g.create_group(&a.name).at(path, "creating an attractor")?;
        set_attr(path, &ga, "period_strides", &a.period_strides)?;
        // The same number under the name of `fixedpoint --period K` (0: chaotic).
        set_attr(path, &ga, "period_k", &a.period_strides)?;
        set_attr(path, &ga, "period_time", &a.period_time)?;
        let k = a.section.len();
        let flat: Vec<f64> = a.section.iter().flatten().copied().collect();
        let sec = Array2::from_shape_vec((k, d), flat).expect("lengths checked");
        ga.new_dataset_builder()
            .with_data(&sec)
            .create("section")
            .at(path, "writing an attractor")?;
        let re: Vec<f64> = a.multipliers.iter().map(|m| m.0).collect();
        let im: Vec<f64> = a.multipliers.iter().map(|m| m.1).collect();
        for (n, v) in [("multipliers_re", re), ("multipliers_im", im)] {
            ga.new_dataset_builder()
                .with_data(&v)
                .create(n)
                .at(path, "writing an attractor")?;
        }
        set_str(path, &ga, "validity", a.validity.word())?;
        if let Some(r) = a.validity.reasons() {
            set_str(path, &ga, "invalid_reasons", &r.join("; "))?;
        }
    }
    Ok(())
}

/// An attractor group's `validity` and `invalid_reasons` (unchecked where absent: files written
/// before validity was recorded).
fn read_orbit_check(path: &Path, ga: &Group) -> Result<OrbitCheck> {
    if !has_attr(ga, "validity") {
        return Ok(OrbitCheck::Unchecked);
    }
    Ok(match get_str(path, KIND, ga, "validity")?.as_str() {
        "valid" => OrbitCheck::Valid,
        "invalid" => OrbitCheck::Invalid(
            get_str(path, KIND, ga, "invalid_reasons")?
                .split("; ")
                .map(str::to_string)
                .collect(),
        ),
        "not checked" => OrbitCheck::Unchecked,
        other => {
            return Err(format_err(
                path,
                format!("attractor validity {other:?} is not valid, invalid or not checked"),
            ))
        }
    })
}

fn read_metrics(path: &Path, f: &File, legend: &[(u8, String)]) -> Result<Option<BasinMetrics>> {
    if !f.link_exists("metrics") {
        return Ok(None);
    }
    let g = f.group("metrics").at(path, "opening /metrics")?;
    let text = get_str(path, KIND, &g, "fractions")?;
    let obj: serde_json::Map<String, serde_json::Value> = serde_json::from_str(&text)
        .map_err(|e| format_err(path, format!("/metrics fractions: {e}")))?;
    // Names from the JSON object, exact values from the f64 attributes, in legend order.
    let rank = |n: &str| {
        legend
            .iter()
            .position(|(_, l)| l == n)
            .unwrap_or(usize::MAX)
    };
    let mut names: Vec<String> = obj.keys().cloned().collect();
    names.sort_by_key(|n| rank(n));
    let fractions = names
        .into_iter()
        .map(|n| {
            let v = get_attr::<f64>(path, KIND, &g, &format!("fraction_{n}"))?;
            Ok((n, v))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Some(BasinMetrics {
        fractions,
        basin_entropy: get_attr(path, KIND, &g, "basin_entropy")?,
        boundary_entropy: get_attr(path, KIND, &g, "boundary_entropy")?,
        entropy_box: get_attr::<u64>(path, KIND, &g, "entropy_box")? as usize,
    }))
}

pub(crate) fn read_attractors(path: &Path, f: &File) -> Result<Vec<Attractor>> {
    if !f.link_exists("attractors") {
        return Ok(Vec::new());
    }
    let g = f.group("attractors").at(path, "opening /attractors")?;
    let mut out = Vec::new();
    for ga in g.groups().at(path, "listing /attractors")? {
        let name = ga.name().rsplit('/').next().unwrap_or_default().to_string();
        let sec = ga
            .dataset("section")
            .and_then(|d| d.read_2d::<f64>())
            .at(path, "reading an attractor")?;
        let rd = |n: &str| {
            ga.dataset(n)
                .and_then(|d| d.read_raw::<f64>())
                .at(path, "reading an attractor")
        };
        let (re, im) = (rd("multipliers_re")?, rd("multipliers_im")?);
        out.push(Attractor {
            name,
            period_strides: get_attr(path, KIND, &ga, "period_strides")?,
            period_time: get_attr(path, KIND, &ga, "period_time")?,
            section: sec.rows().into_iter().map(|r| r.to_vec()).collect(),
            multipliers: re.into_iter().zip(im).collect(),
            validity: read_orbit_check(path, &ga)?,
        });
    }
    Ok(out)
}

/// Reads only the header of a basin file (cheap; for checks and plots).
pub fn read_basin_header(path: impl AsRef<Path>) -> Result<BasinHeader> {
    let path = path.as_ref();
    let f = open_file(path, false)?;
    read_header(path, &f)
}

/// Reads the header and the (rows × nx) outcome codes only (for plotting large files without
/// loading `/basin/final`); a 3-D grid's rows are its (z, y) pairs ([`BasinHeader::rows`]).
pub fn read_basin_outcome(path: impl AsRef<Path>) -> Result<(BasinHeader, Array2<u8>)> {
    let path = path.as_ref();
    let f = open_file(path, false)?;
    let h = read_header(path, &f)?;
    let rows_done = read_rows_done(path, &f)?;
    let ds = f
        .dataset("basin/outcome")
        .at(path, "opening /basin/outcome")?;
    let o = read_blocks(path, &ds, "outcome", &h, &rows_done, NOT_COMPUTED)?;
    let o = Array2::from_shape_vec((h.rows(), h.nx()), o).expect("rows × nx cells");
    Ok((h, o))
}

/// Reads a dataset of `h`'s grid block by block (chunk blocks of [`BLOCK_ROWS`] rows), as
/// rows × nx (× d for `final`) values, row-major. A block with no row marked in `rows_done`
/// that cannot be read (a writer killed mid-block can leave its chunk index pointing past the
/// end of the file) reads as `fill`, the value of cells not computed; a block with rows marked
/// done that cannot be read is an error.
fn read_blocks<T: hdf5::H5Type + Copy>(
    path: &Path,
    ds: &Dataset,
    name: &str,
    h: &BasinHeader,
    rows_done: &[bool],
    fill: T,
) -> Result<Vec<T>> {
    let lay = Layout::of(h);
    let (nx, d) = (h.nx(), h.d());
    let trailing: &[usize] = if name == "final" { &[nx, d] } else { &[nx] };
    let per_row: usize = trailing.iter().product();
    let mut out = vec![fill; h.rows() * per_row];
    for b in 0..h.blocks() {
        let r = block_range(b, h.ny());
        match lay.read::<T>(ds, b, trailing) {
            Ok(v) => out[r.start * per_row..r.end * per_row].copy_from_slice(&v),
            Err(e) if rows_done[r.clone()].iter().any(|d| *d) => {
                return Err(e).at(path, &format!("reading /basin/{name}"))
            }
            Err(_) => {}
        }
    }
    Ok(out)
}

/// Reads a whole basin file.
pub fn read_basin(path: impl AsRef<Path>) -> Result<BasinData> {
    let path = path.as_ref();
    let f = open_file(path, false)?;
    let header = read_header(path, &f)?;
    let basin = f.group("basin").at(path, "opening /basin")?;
    let rows_done = read_rows_done(path, &f)?;
    let open = |n: &str| basin.dataset(n).at(path, &format!("opening /basin/{n}"));
    let (rows, nx, d) = (header.rows(), header.nx(), header.d());
    let h = &header;
    let outcome = read_blocks(
        path,
        &open("outcome")?,
        "outcome",
        h,
        &rows_done,
        NOT_COMPUTED,
    )?;
    let strides = read_blocks(path, &open("strides")?, "strides", h, &rows_done, 0u16)?;
    let final_state = read_blocks(path, &open("final")?, "final", h, &rows_done, f64::NAN)?;
    let outcome = Array2::from_shape_vec((rows, nx), outcome).expect("rows × nx cells");
    let strides = Array2::from_shape_vec((rows, nx), strides).expect("rows × nx cells");
    let final_state =
        Array3::from_shape_vec((rows, nx, d), final_state).expect("rows × nx × d values");
    // What a reader is served is what was written: every block with finished rows against its
    // checksums and digest (as `--resume` checks them), and a complete file with all its own
    // rows marked (a damaged `rows_done` would serve finished rows as not computed).
    let complete: bool = get_attr(path, KIND, &f, "complete")?;
    let own = own_mask(h);
    if complete && own.iter().zip(&rows_done).any(|(o, d)| *o && !*d) {
        return Err(format_err(
            path,
            "the file says it is complete but /basin/rows_done misses some of its rows: damaged",
        ));
    }
    let bad = damaged_blocks(&f, h, &rows_done);
    if let Some(&b) = bad.first() {
        let r = block_range(b, h.ny());
        return Err(format_err(
            path,
            format!(
                "{} block(s) of rows read back different from what was written (checksum or \
                 digest), the first rows {}..{}; `basin --resume` recomputes them",
                bad.len(),
                r.start,
                r.end
            ),
        ));
    }
    Ok(BasinData {
        version: get_str(path, KIND, &f, "version")?,
        created: get_str(path, KIND, &f, "created")?,
        elapsed_s: get_attr(path, KIND, &f, "elapsed_s")?,
        complete,
        rows_done,
        metrics: read_metrics(path, &f, &header.legend)?,
        attractors: read_attractors(path, &f)?,
        header,
        outcome,
        strides,
        final_state,
    })
}
