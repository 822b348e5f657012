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

/// The first gait of `fixedpoint --json` with `args` (the model's knee hardware tests).
pub fn first_gait(args: &[&str]) -> serde_json::Value {
    let mut a = vec!["fixedpoint", "--json"];
    a.extend_from_slice(args);
    json(&run(&a))["fixed_points"][0].clone()
}

/// The margin named `name` of a gait's validity.
pub fn margin<'a>(g: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    g["validity"]["margins"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == name)
        .unwrap_or_else(|| panic!("no margin {name}"))
}

/// The raw value of the margin named `name`.
pub fn raw(g: &serde_json::Value, name: &str) -> f64 {
    margin(g, name)["raw"].as_f64().unwrap()
}

/// The knee-lock torque margins a latch is judged by.
pub const LATCH_TORQUES: [&str; 2] = ["stance_knee_torque", "swing_knee_torque"];
/// The knee impulse margins a latch is judged by.
pub const LATCH_IMPULSES: [&str; 3] = [
    "knee_strike:stance_knee",
    "heel_strike:trailing_knee",
    "heel_strike:new_stance_knee",
];
