//! Helpers shared by the CLI test modules.

use std::path::Path;
use std::process::{Command, Output};

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

/// Runs the pdw-sweep binary with `args` and waits for it.
pub fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pdw-sweep"))
        .args(args)
        .output()
        .expect("the binary runs")
}

/// A run's stderr as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A successful run's stdout as JSON.
pub fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_slice(&o.stdout).expect("stdout is JSON")
}
