//! The basin-of-attraction file: header, streaming writer with resume, reader.
//!
//! A basin grid assigns each cell `(x[j], y[i])` of two section coordinates an outcome code (see
//! the `legend`), the number of strides until it was classified and the last section state.
//!
//! The file's parts, one submodule each: the run's [`BasinHeader`] and its checks (`header`),
//! the chunk-block layout of the datasets (`layout`), the metrics and attractors a finished
//! file holds (`results`), the checksums of header and blocks (`digest`), the streaming
//! [`BasinWriter`] (`writer`), [`BasinWriter::resume`] (`resume`) and the readers (`read`).
//!
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

use std::path::Path;

use crate::StoreError;

mod digest;
mod header;
mod layout;
mod read;
mod results;
mod resume;
mod writer;

pub(crate) use digest::{block_digest, read_digests};
pub use header::{BasinHeader, ZAxis};
pub(crate) use layout::Layout;
pub use layout::{block_count, block_of, block_range};
pub use read::{read_basin, read_basin_header, read_basin_outcome, BasinData};
pub(crate) use results::read_attractors;
pub use results::{Attractor, BasinMetrics, OrbitCheck};
pub use writer::BasinWriter;

/// Value of the root attribute `format` of a basin file.
pub const BASIN_FORMAT: &str = "pdw-sweep basin v1";
/// Rows per chunk of the 2-D/3-D datasets, and per shard block (see [`shard_rows`](crate::shard::shard_rows)).
/// Writing blocks aligned to it (`row0` a multiple, `BLOCK_ROWS` rows) writes whole chunks.
pub const BLOCK_ROWS: usize = 16;
/// Outcome code of a cell not (yet) computed: the fill value of `/basin/outcome`.
pub const NOT_COMPUTED: u8 = 255;
const DEFLATE_LEVEL: u8 = 4;
const KIND: &str = "pdw-sweep basin";

/// The `description` attribute of `/basin/final`: what its states are, by outcome.
pub const FINAL_DESCRIPTION: &str = "section coordinates of the last state of each cell: for \
gait, every other attractor (codes 16 and up), other and timeout, and for a walk that came to a \
stand (fall, decided on the section), the section state after the last completed stride; for \
any other fall, nonfinite or integrator_failure the section coordinates of the state where the \
stride stopped (projected, not on the section); NaN where not computed";

/// Name of the fill value [`NOT_COMPUTED`] in the file's legend.
pub const NOT_COMPUTED_NAME: &str = "not_computed";

/// A [`StoreError::Format`] of the basin file at `path`.
fn format_err(path: &Path, detail: impl Into<String>) -> StoreError {
    StoreError::Format {
        path: path.to_path_buf(),
        expected: KIND,
        detail: detail.into(),
    }
}
