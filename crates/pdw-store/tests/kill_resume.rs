//! A writer process killed with SIGKILL at arbitrary moments leaves a file that resumes to the
//! same datasets as an uninterrupted run.

use crate::common;

use std::process::Command;
use std::time::Duration;

use common::*;
use pdw_store::{read_basin, BasinWriter, BLOCK_ROWS};

const NX: usize = 300;
const NY: usize = 3200;

/// Child process body: resume the file named by `PDW_STORE_CHILD` and write its remaining rows
/// one at a time (run by `killed_writer_resumes_to_uninterrupted_result`, not on its own).
#[test]
#[ignore = "child process of killed_writer_resumes_to_uninterrupted_result"]
fn child_writer_process() {
    let path = std::env::var("PDW_STORE_CHILD").expect("run by the parent test");
    let h = header(NX, NY);
    let mut w = BasinWriter::resume(&path, &h).unwrap();
    for r in w.rows_todo() {
        write_block(&mut w, r, 1);
    }
}

#[test]
fn killed_writer_resumes_to_uninterrupted_result() {
    let dir = scratch("kill");
    let h = header(NX, NY);
    let reference = dir.join("reference.h5");
    let mut w = BasinWriter::create(&reference, &h, false).unwrap();
    for r0 in (0..NY).step_by(16) {
        write_block(&mut w, r0, 16.min(NY - r0));
    }
    let (o, _, _) = block(&h, 0, NY);
    w.finish(&fractions(&h, &o), &attractors()).unwrap();

    let p = dir.join("killed.h5");
    BasinWriter::create(&p, &h, false).unwrap();
    let exe = std::env::current_exe().unwrap();
    // The child's test name as the harness lists it: its module path without the crate name.
    let child_test = match module_path!().split_once("::") {
        Some((_, m)) => format!("{m}::child_writer_process"),
        None => "child_writer_process".to_string(),
    };
    let mut kills = 0;
    // `PDW_KILL_TRIALS=N` runs N kills at spread delays instead (a stress run).
    let mut delays = vec![40u64, 75, 20, 110, 55, 90, 30, 140, 65, 25, 85, 45];
    if let Some(n) = std::env::var("PDW_KILL_TRIALS")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
    {
        delays = (0..n).map(|i| 15 + (i * 37) % 130).collect();
    }
    for delay_ms in delays {
        let mut child = Command::new(&exe)
            .args([
                "--exact",
                &child_test,
                "--ignored",
                "--nocapture",
                "--test-threads=1",
            ])
            .env("PDW_STORE_CHILD", &p)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(delay_ms));
        let killed = child.try_wait().unwrap().is_none();
        if killed {
            child.kill().unwrap(); // SIGKILL: no destructor, no flush
            kills += 1;
        }
        let status = child.wait().unwrap();
        assert!(
            killed || status.success(),
            "a writer that was not killed failed: {status}"
        );
        // Whatever the moment, the file must reopen and read (a block the kill interrupted may
        // have its chunk index past the end of the file: it reads as not computed), and every
        // row marked done must be right.
        let d = read_basin(&p).unwrap();
        let (o, s, _) = block(&h, 0, NY);
        for i in (0..NY).filter(|&i| d.rows_done[i]) {
            assert_eq!(
                d.outcome.row(i).to_vec(),
                o[i * NX..(i + 1) * NX].to_vec(),
                "row {i}"
            );
            assert_eq!(
                d.strides.row(i).to_vec(),
                s[i * NX..(i + 1) * NX].to_vec(),
                "row {i}"
            );
        }
        // And every killed file takes writes again: resume it and write one whole block here
        // (its data and marks are flushed; the next child resumes after it).
        let mut w = BasinWriter::resume(&p, &h).unwrap();
        for r in w.rows_todo().into_iter().take(BLOCK_ROWS) {
            write_block(&mut w, r, 1);
        }
        w.close().unwrap();
    }
    assert!(
        kills >= 4,
        "the writer always finished before being killed: grid too small"
    );
    let mut w = BasinWriter::resume(&p, &h).unwrap();
    for r in w.rows_todo() {
        write_block(&mut w, r, 1);
    }
    w.finish(&fractions(&h, &o), &attractors()).unwrap();
    let (a, b) = (read_basin(&reference).unwrap(), read_basin(&p).unwrap());
    assert_eq!(a.outcome, b.outcome);
    assert_eq!(a.strides, b.strides);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(
        bits(a.final_state.as_slice().unwrap()),
        bits(b.final_state.as_slice().unwrap())
    );
    assert_eq!(a.metrics, b.metrics);
    eprintln!(
        "killed {kills} times; file size {} bytes",
        std::fs::metadata(&p).unwrap().len()
    );
}
