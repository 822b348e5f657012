//! Helpers shared by the CLI test modules.

use std::path::Path;

/// Opens a file for reading without HDF5's file lock: HDF5 opens files without close-on-exec,
/// so a pdw-sweep started meanwhile by a parallel test would inherit the lock and hold it.
#[allow(dead_code)]
pub fn h5_open(path: impl AsRef<Path>) -> hdf5::Result<hdf5::File> {
    hdf5::File::with_options()
        .with_fapl(|p| p.file_locking(false))
        .open(path)
}

/// [`h5_open`] read-write.
#[allow(dead_code)]
pub fn h5_open_rw(path: impl AsRef<Path>) -> hdf5::Result<hdf5::File> {
    hdf5::File::with_options()
        .with_fapl(|p| p.file_locking(false))
        .open_rw(path)
}
