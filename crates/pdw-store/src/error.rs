//! Typed errors. Every variant that concerns a file names it, so the CLI can print the message
//! as is.

use std::path::PathBuf;

/// Errors of pdw-store.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// The output exists and overwriting was not allowed.
    #[error("{}: file exists; refusing to overwrite it (use --force to replace it{})", path.display(), if *resumable { ", or --resume to continue it" } else { "" })]
    Exists {
        path: PathBuf,
        /// Whether the command can continue the file (`basin --resume`).
        resumable: bool,
    },

    /// Another process holds the output file's lock (it is being written).
    #[error("{}: another process is writing this file (it is locked); wait for it to finish, or choose another output path", path.display())]
    Busy { path: PathBuf },

    /// Creating, opening, renaming or removing a file failed at the operating-system level.
    #[error("{}: cannot {action}: {source}", path.display())]
    Io {
        path: PathBuf,
        action: &'static str,
        source: std::io::Error,
    },

    /// An HDF5 call failed (corrupt file, unsupported type, disk full…).
    #[error("{}: HDF5 error while {action}: {source}", path.display())]
    Hdf5 {
        path: PathBuf,
        action: String,
        source: hdf5::Error,
    },

    /// The file opens but is not what was expected (wrong `format`, missing or malformed
    /// dataset or attribute).
    #[error("{}: not a valid {expected} file: {detail}", path.display())]
    Format {
        path: PathBuf,
        expected: &'static str,
        detail: String,
    },

    /// `resume` or `merge` found a file made for a different run.
    #[error("{}: made for a different run: {field} is {found} in the file but {expected} here", path.display())]
    Mismatch {
        path: PathBuf,
        field: String,
        found: String,
        expected: String,
    },

    /// `resume` on a file whose grid is already complete.
    #[error("{}: already complete; nothing to resume", path.display())]
    AlreadyComplete { path: PathBuf },

    /// `finish` or `merge` on a file with rows still missing.
    #[error("{}: incomplete: {done} of {expected} rows written", path.display())]
    Incomplete {
        path: PathBuf,
        done: usize,
        expected: usize,
    },

    /// The shards given to `merge` do not cover the grid exactly once.
    #[error("shards do not cover the grid exactly once: {detail}")]
    Coverage { detail: String },

    /// A value passed to this crate is out of range or inconsistent.
    #[error("invalid {what}: {detail}")]
    Invalid { what: &'static str, detail: String },

    /// Drawing or encoding a picture failed.
    #[error("{}: cannot draw: {detail}", path.display())]
    Plot { path: PathBuf, detail: String },
}

impl StoreError {
    pub(crate) fn invalid(what: &'static str, detail: impl Into<String>) -> Self {
        StoreError::Invalid {
            what,
            detail: detail.into(),
        }
    }
}
