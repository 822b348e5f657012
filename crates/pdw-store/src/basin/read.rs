//! Reading basin files: the header (checked against its digest), the outcome codes alone, or
//! the whole file ([`BasinData`]).

use std::path::Path;

use hdf5::{Dataset, File, Group};
use ndarray::{Array2, Array3, ArrayView3};

use super::digest::header_digest;
use super::header::parse_legend;
use super::resume::damaged_blocks;
use super::writer::own_mask;
use super::{
    block_range, format_err, read_attractors, results::read_metrics, Attractor, BasinHeader,
    BasinMetrics, Layout, ZAxis, BASIN_FORMAT, KIND, NOT_COMPUTED,
};
use crate::h5util::{get_attr, get_str, has_attr, open_file, At};
use crate::shard::ShardSpec;
use crate::Result;

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

/// Reads and checks the header of an open basin file.
pub(super) fn read_header(path: &Path, f: &File) -> Result<BasinHeader> {
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

pub(super) fn read_rows_done(path: &Path, f: &File) -> Result<Vec<bool>> {
    let v = f
        .dataset("basin/rows_done")
        .and_then(|d| d.read_raw::<u8>())
        .at(path, "reading /basin/rows_done")?;
    Ok(v.into_iter().map(|b| b != 0).collect())
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

/// Reads a dataset of `h`'s grid block by block (chunk blocks of
/// [`BLOCK_ROWS`](super::BLOCK_ROWS) rows), as rows × nx (× d for `final`) values, row-major.
/// A block with no row marked in `rows_done`
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
