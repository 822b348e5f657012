//! Splitting a basin grid across processes and joining the pieces.
//!
//! # Split
//! Rows are dealt out in blocks of [`BLOCK_ROWS`](crate::BLOCK_ROWS) (the chunk height of the datasets),
//! round-robin: block `b = row / BLOCK_ROWS` goes to shard `b mod N`. Round-robin balances the
//! load (cells near the basin's thin band take many strides, cells far from it fall at once, so
//! contiguous halves of a grid can differ in cost by a large factor), and aligning to chunks means
//! each shard writes whole chunks only. Every shard file has the full grid shape; rows of other
//! shards stay at the fill value and take no space (HDF5 allocates chunks on first write).
//!
//! # Merge: a copy, not a virtual dataset
//! [`merge`] copies the shards' rows into one new file rather than building an HDF5 virtual
//! dataset over them: the result is a single self-contained file that can be moved, archived or
//! mailed without its shards; a virtual dataset resolves its source files by path at read time
//! (a moved or deleted shard silently reads as fill values) and is not understood by every
//! reader of HDF5 (netCDF-4 tools, older MATLAB), while a plain chunked dataset is; the copy
//! keeps chunking and compression, so the merged file is about the size of the shards together;
//! and the merged file gets whole-grid metrics, which no shard has. The cost is one pass over
//! the data, small next to computing it.

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use ndarray::ArrayView2;

use crate::basin::{
    block_of, block_range, read_attractors, Attractor, BasinHeader, BasinMetrics, BasinWriter,
    Layout,
};
use crate::h5util::{check_target, get_attr, open_file, At, Staged};
use crate::{Result, StoreError};

/// Shard `index` of `count` (0-based: `index` in `0..count`); written and parsed as `"I/N"`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ShardSpec {
    pub index: usize,
    pub count: usize,
}

impl ShardSpec {
    /// Checks `count ≥ 1` and `index < count`.
    pub fn validate(&self) -> Result<()> {
        if self.count == 0 || self.index >= self.count {
            return Err(StoreError::invalid(
                "shard",
                format!(
                    "{}/{}: need I/N with N ≥ 1 and 0 ≤ I < N (shards are numbered from 0)",
                    self.index, self.count
                ),
            ));
        }
        Ok(())
    }
}

impl fmt::Display for ShardSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for ShardSpec {
    type Err = StoreError;
    /// Parses `"I/N"`, e.g. `"0/4"`.
    fn from_str(s: &str) -> Result<Self> {
        let bad = || {
            StoreError::invalid(
                "shard",
                format!("{s:?}: expected I/N, e.g. 0/4 (shards are numbered from 0 to N-1)"),
            )
        };
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let spec = ShardSpec {
            index: i.trim().parse().map_err(|_| bad())?,
            count: n.trim().parse().map_err(|_| bad())?,
        };
        spec.validate()?;
        Ok(spec)
    }
}

/// Rows of a grid of `ny` rows that shard `index` of `count` computes, ascending: the rows of
/// blocks `b ≡ index (mod count)`, blocks being [`BLOCK_ROWS`](crate::BLOCK_ROWS) consecutive rows.
///
/// Over `index = 0..count` every row appears exactly once.
pub fn shard_rows(ny: usize, index: usize, count: usize) -> Result<Vec<usize>> {
    grid_shard_rows(ny, 1, index, count)
}

/// [`shard_rows`] of a 3-D grid of `nz` slices of `ny` rows, its rows being the (z, y) pairs
/// (row `k·ny + i`): blocks are dealt out round-robin in the order slice by slice, each slice
/// cut into blocks of [`BLOCK_ROWS`](crate::BLOCK_ROWS) rows ([`crate::basin::block_of`]); `nz = 1` is
/// [`shard_rows`].
pub fn grid_shard_rows(ny: usize, nz: usize, index: usize, count: usize) -> Result<Vec<usize>> {
    ShardSpec { index, count }.validate()?;
    Ok((0..nz * ny)
        .filter(|&r| block_of(r, ny) % count == index)
        .collect())
}

/// Joins complete shard files into one new basin file at `out`.
///
/// Checks that every shard is complete, that all were made for the same run (model, slope,
/// params, grid, legend, … as [`BasinWriter::resume`] compares) with the same shard count and
/// the same attractors, and that their indices are `0..N` exactly once — so together they cover
/// every row exactly once. Then copies the rows into a temporary file beside `out`, computes the
/// whole grid's metrics with `metrics(header, outcome)` (outcome (rows × nx), [`BasinHeader::rows`]), finishes the file
/// (`complete = true`, `elapsed_s` = the shards' sum, attractors of the shards) and renames it
/// onto `out`. An existing `out` is refused unless `force`, and is replaced only by a finished
/// file; on any error `out` and the shards are untouched. `command` is recorded in the new file.
pub fn merge<P: AsRef<Path>>(
    shards: &[P],
    out: impl AsRef<Path>,
    force: bool,
    command: &str,
    metrics: impl FnOnce(&BasinHeader, ArrayView2<u8>) -> BasinMetrics,
) -> Result<BasinHeader> {
    let out = out.as_ref();
    check_target(out, force)?;
    if shards.is_empty() {
        return Err(StoreError::Coverage {
            detail: "no shard files given".into(),
        });
    }
    let out_canon = std::fs::canonicalize(out).ok();
    let mut list: Vec<Shard> = Vec::new();
    let mut attractors = None;
    for p in shards {
        let p = p.as_ref();
        if out_canon.is_some() && std::fs::canonicalize(p).ok() == out_canon {
            return Err(StoreError::invalid(
                "merge",
                format!("output {} is also one of the shards", out.display()),
            ));
        }
        let (f, header, spec, att) = open_complete_shard(p)?;
        if let Some(first) = list.first() {
            check_same_run(first, attractors.as_deref(), &header, spec, &att, p)?;
        } else {
            attractors = Some(att);
        }
        if list.iter().any(|s| s.header.shard == Some(spec)) {
            return Err(StoreError::Coverage {
                detail: format!("shard {spec} given twice ({})", p.display()),
            });
        }
        let elapsed: f64 = get_attr(p, "pdw-sweep basin", &f, "elapsed_s")?;
        list.push(Shard { header, elapsed });
    }
    let count = list[0].header.shard.map_or(0, |s| s.count);
    if list.len() != count {
        let have: Vec<String> = list
            .iter()
            .filter_map(|s| s.header.shard.map(|x| x.to_string()))
            .collect();
        return Err(StoreError::Coverage {
            detail: format!(
                "{count} shards needed, got {} ({})",
                list.len(),
                have.join(", ")
            ),
        });
    }
    // Count matching and uniqueness imply indices are exactly 0..count.

    let mut header = list[0].header.clone();
    header.shard = None;
    header.command = command.to_string();
    // The target was checked above, before the shards were read.
    let staged = Staged::beside(out);
    let tmp = staged.path();
    let result = (|| -> Result<BasinHeader> {
        let mut w = BasinWriter::create(tmp, &header, true)?;
        w.set_elapsed_before(list.iter().map(|s| s.elapsed).sum());
        for (s, p) in list.iter().zip(shards) {
            copy_shard(
                &mut w,
                &header,
                s.header.shard.expect("checked above"),
                p.as_ref(),
            )?;
        }
        let outcome = w.read_outcome()?;
        let m = metrics(&header, outcome.view());
        w.finish(&m, attractors.as_deref().unwrap_or(&[]))?;
        Ok(header.clone())
    })();
    let h = result?;
    staged.commit(out)?;
    Ok(h)
}

/// A shard accepted by [`merge`]: its header and its computing time.
struct Shard {
    header: BasinHeader,
    elapsed: f64,
}

/// Opens the shard file `p`: its header, shard spec and attractors, refused unless it is a
/// shard file with every one of its rows on disk and `complete` set.
fn open_complete_shard(p: &Path) -> Result<(hdf5::File, BasinHeader, ShardSpec, Vec<Attractor>)> {
    let f = open_file(p, false)?;
    let header = crate::basin::read_basin_header(p)?;
    let spec = header.shard.ok_or_else(|| StoreError::Coverage {
        detail: format!(
            "{} is not a shard file (no shard_index/shard_count)",
            p.display()
        ),
    })?;
    let done = f
        .dataset("basin/rows_done")
        .and_then(|d| d.read_raw::<u8>())
        .at(p, "reading /basin/rows_done")?;
    let own = grid_shard_rows(header.ny(), header.nz(), spec.index, spec.count)?;
    let n_done = own.iter().filter(|&&r| done[r] != 0).count();
    let complete: bool = get_attr(p, "pdw-sweep basin", &f, "complete")?;
    if n_done != own.len() || !complete {
        return Err(StoreError::Incomplete {
            path: p.to_path_buf(),
            done: n_done,
            expected: own.len(),
        });
    }
    let att = read_attractors(p, &f)?;
    Ok((f, header, spec, att))
}

/// Checks that shard `p` (`header`, `spec`, attractors `att`) belongs to the run of the first
/// shard accepted (`first`, whose attractors are `attractors`): the same shard count, every
/// header field as [`BasinHeader::check_matches`] compares it, and the same attractors bit for
/// bit ([`Attractor::same_as`]).
fn check_same_run(
    first: &Shard,
    attractors: Option<&[Attractor]>,
    header: &BasinHeader,
    spec: ShardSpec,
    att: &[Attractor],
    p: &Path,
) -> Result<()> {
    let first_count = first.header.shard.map_or(0, |s| s.count);
    if spec.count != first_count {
        return Err(StoreError::Mismatch {
            path: p.to_path_buf(),
            field: "shard".into(),
            found: spec.to_string(),
            expected: format!("a shard of {first_count}"),
        });
    }
    let mut want = first.header.clone();
    want.shard = header.shard;
    want.check_matches(header, p)?;
    let same = attractors.is_some_and(|a: &[Attractor]| {
        a.len() == att.len() && a.iter().zip(att).all(|(x, y)| x.same_as(y))
    });
    if !same {
        let list = |v: &[Attractor]| {
            format!(
                "[{}] (or different values)",
                v.iter()
                    .map(Attractor::summary)
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        };
        return Err(StoreError::Mismatch {
            path: p.to_path_buf(),
            field: "attractors".into(),
            found: list(att),
            expected: list(attractors.unwrap_or_default()),
        });
    }
    Ok(())
}

/// Copies the blocks of shard `spec` (file `p`, complete and checked) into the merged file's
/// writer `w`, each checked against its digest.
fn copy_shard(w: &mut BasinWriter, header: &BasinHeader, spec: ShardSpec, p: &Path) -> Result<()> {
    let (nx, d, lay) = (header.nx(), header.d(), Layout::of(header));
    let f = open_file(p, false)?;
    let ds = |n: &str| f.dataset(n).at(p, "opening the basin datasets");
    let (o, st, fs) = (
        ds("basin/outcome")?,
        ds("basin/strides")?,
        ds("basin/final")?,
    );
    let damaged = |r: std::ops::Range<usize>| StoreError::Format {
        path: p.to_path_buf(),
        expected: "pdw-sweep basin",
        detail: format!(
            "rows {}..{} do not read back as written (damaged); run that shard again with \
             --resume, which recomputes damaged blocks",
            r.start, r.end
        ),
    };
    let blocks: Vec<usize> = (0..header.blocks())
        .filter(|b| b % spec.count == spec.index)
        .collect();
    let own = grid_shard_rows(header.ny(), header.nz(), spec.index, spec.count)?;
    let all = own.first().map_or(0..0, |&r0| r0..own[own.len() - 1] + 1);
    let digests = crate::basin::read_digests(&f, header.blocks()).ok_or_else(|| damaged(all))?;
    for b in blocks {
        let r = block_range(b, header.ny());
        let ov: Vec<u8> = lay.read(&o, b, &[nx]).at(p, "reading rows")?;
        let sv: Vec<u16> = lay.read(&st, b, &[nx]).at(p, "reading rows")?;
        let fv: Vec<f64> = lay.read(&fs, b, &[nx, d]).at(p, "reading rows")?;
        if let Some(dg) = &digests {
            if dg.get(b) != Some(&crate::basin::block_digest(&ov, &sv, &fv)) {
                return Err(damaged(r));
            }
        }
        if ov.len() != r.len() * nx || fv.len() != r.len() * nx * d {
            return Err(StoreError::Format {
                path: p.to_path_buf(),
                expected: "pdw-sweep basin",
                detail: "row block of unexpected size".into(),
            });
        }
        w.write_rows(r.start, &ov, &sv, &fv)?;
    }
    Ok(())
}
