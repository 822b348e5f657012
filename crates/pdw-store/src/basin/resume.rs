//! Continuing a basin file after a stop or a kill: every block marked done checked against its
//! checksums and digest, the good ones copied into a fresh file that replaces the old one, the
//! rows of partly written blocks taken back into memory.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use hdf5::File;
use ndarray::s;

use super::digest::{block_digest, read_digests};
use super::read::{read_header, read_rows_done};
use super::results::{read_attractors, read_metrics};
use super::writer::{own_mask, Handles, PendingBlock};
use super::{block_range, BasinHeader, BasinWriter, Layout, DEFLATE_LEVEL, KIND};
use crate::h5util::{
    create_file, get_attr, get_str, lock_existing, open_locked, rename_into_place, set_attr,
    set_str, temp_sibling, At,
};
use crate::{Result, StoreError};

impl BasinWriter {
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
}

/// Blocks with rows marked done in `rows_done` that do not read back intact: a chunk fails its
/// checksum or cannot be read, the block's digest differs, or an outcome code of a marked row is
/// outside the legend (e.g. the fill value of a chunk never written).
pub(super) fn damaged_blocks(f: &File, h: &BasinHeader, rows_done: &[bool]) -> Vec<usize> {
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
