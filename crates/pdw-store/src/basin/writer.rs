//! The streaming writer of a basin file: creates it, takes rows in any order and grouping,
//! writes each chunk block once when it is complete (or when the writer stops), and finishes
//! the file with its metrics and attractors (see the crash-safety notes of [`super`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use hdf5::{Dataset, File};
use ndarray::{s, Array2};

use super::digest::{block_digest, header_digest, DIGEST_DESCRIPTION};
use super::header::{file_legend_json, legend_json};
use super::results::{write_attractors, write_metrics};
use super::{
    block_of, block_range, format_err, Attractor, BasinHeader, BasinMetrics, Layout, BASIN_FORMAT,
    DEFLATE_LEVEL, FINAL_DESCRIPTION, NOT_COMPUTED,
};
use crate::h5util::{create_file, ensure_space, set_attr, set_str, At, OutputLock};
use crate::{time, Result, StoreError};

/// Streams a basin grid into an HDF5 file, row block by row block.
///
/// Dropping the writer without [`finish`](Self::finish) writes the rows held in incomplete
/// blocks (as [`close`](Self::close) does) and leaves a valid, resumable file with
/// `complete = false`.
pub struct BasinWriter {
    pub(super) path: PathBuf,
    /// `None` once closed (or handed to [`Drop`]).
    pub(super) h: Option<Handles>,
    /// Held until the writer is dropped: no other process writes this file meanwhile.
    pub(super) _lock: OutputLock,
    /// Set by a failed HDF5 call: the handles are then leaked, not closed (HDF5's close after a
    /// failed write can crash; the file stays as of its last successful flush).
    pub(super) poisoned: bool,
    /// Blocks found damaged (checksum or content) by [`resume`](Self::resume), to recompute.
    pub(super) damaged: Vec<usize>,
    pub(super) header: BasinHeader,
    /// (ny) rows on disk.
    pub(super) rows_done: Vec<bool>,
    /// (ny) rows this file may hold (its shard's, or all).
    pub(super) own: Vec<bool>,
    /// Blocks with some rows received but not yet written, by block index.
    pub(super) pending: BTreeMap<usize, PendingBlock>,
    pub(super) elapsed_before: f64,
    pub(super) started: Instant,
}

/// The open HDF5 objects of a writer.
pub(super) struct Handles {
    pub(super) file: File,
    pub(super) outcome: Dataset,
    pub(super) strides: Dataset,
    pub(super) final_state: Dataset,
    pub(super) rows_done_ds: Dataset,
    /// `/basin/block_digest`: per block, [`block_digest`] of the values written.
    pub(super) digest_ds: Dataset,
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
    pub(super) fn init(
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
    /// [`BLOCK_ROWS`](super::BLOCK_ROWS)` − 1` rows per block) and are written when the writer
    /// is closed or dropped; a process killed outright (SIGKILL) loses them, and
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
pub(super) struct PendingBlock {
    /// (k × nx) outcome codes, k = rows in the block.
    pub(super) outcome: Vec<u8>,
    /// (k × nx) strides.
    pub(super) strides: Vec<u16>,
    /// (k × nx × d) final states.
    pub(super) final_state: Vec<f64>,
    /// (k) rows received.
    pub(super) have: Vec<bool>,
}

impl PendingBlock {
    /// A block of `k` rows of `nx` cells with no row received: every cell holds the fill value
    /// of its dataset (what reading a never-written row gives).
    pub(super) fn empty(k: usize, nx: usize, d: usize) -> Self {
        PendingBlock {
            outcome: vec![NOT_COMPUTED; k * nx],
            strides: vec![0; k * nx],
            final_state: vec![f64::NAN; k * nx * d],
            have: vec![false; k],
        }
    }
}

pub(super) fn own_mask(h: &BasinHeader) -> Vec<bool> {
    let mut own = vec![false; h.rows()];
    for r in h.own_rows() {
        own[r] = true;
    }
    own
}
