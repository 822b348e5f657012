//! A writer process killed without a flush (abort, like SIGKILL) after a chosen number of rows
//! and a chosen delay — inside a write or between two — leaves a file that resumes to the same
//! datasets as an uninterrupted run. Every child is killed (it never exits by itself), and the
//! test asserts that it was.

use crate::common;

use std::process::Command;
use std::time::Duration;

use common::*;
use pdw_store::{read_basin, BasinWriter, BLOCK_ROWS};

const NX: usize = 300;
const NY: usize = 3200;

/// Child process body (run by `killed_writer_resumes_to_uninterrupted_result`, not on its own):
/// resume the file named by `PDW_STORE_CHILD`, write `PDW_STORE_CHILD_ROWS` of its remaining rows
/// one at a time, then start a thread that aborts the process (`abort`: no destructor, no flush,
/// like SIGKILL) after `PDW_STORE_CHILD_ABORT_US` microseconds while this thread goes on
/// writing rows, so the abort lands inside a write as often as between two. The process never
/// ends by itself: every child is killed, at a row and moment the parent chose.
#[test]
#[ignore = "child process of killed_writer_resumes_to_uninterrupted_result"]
fn child_writer_process() {
    let var = |name: &str| std::env::var(name).expect("run by the parent test");
    let path = var("PDW_STORE_CHILD");
    let rows: usize = var("PDW_STORE_CHILD_ROWS").parse().unwrap();
    let abort_us: u64 = var("PDW_STORE_CHILD_ABORT_US").parse().unwrap();
    let h = header(NX, NY);
    let mut w = BasinWriter::resume(&path, &h).unwrap();
    let todo = w.rows_todo();
    let (before, after) = todo.split_at(rows.min(todo.len()));
    for &r in before {
        write_block(&mut w, r, 1);
    }
    std::thread::spawn(move || {
        std::thread::sleep(Duration::from_micros(abort_us));
        std::process::abort();
    });
    for &r in after {
        write_block(&mut w, r, 1);
    }
    loop {
        std::thread::park();
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
    // (rows written before the abort thread starts, its delay in µs) per kill; a row write takes
    // tens of µs to a few ms, so the delays land the abort inside and between writes.
    // `PDW_KILL_TRIALS=N` runs N kills instead (a stress run).
    let mut trials: Vec<(usize, u64)> = vec![
        (0, 0),
        (1, 40),
        (5, 900),
        (0, 2500),
        (12, 150),
        (3, 7000),
        (30, 60),
        (2, 400),
    ];
    if let Some(n) = std::env::var("PDW_KILL_TRIALS")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
    {
        trials = (0..n)
            .map(|i| ((i * 7 % 40) as usize, (i * 997) % 9000))
            .collect();
    }
    for &(rows, abort_us) in &trials {
        let status = Command::new(&exe)
            .args([
                "--exact",
                &child_test,
                "--ignored",
                "--nocapture",
                "--test-threads=1",
            ])
            .env("PDW_STORE_CHILD", &p)
            .env("PDW_STORE_CHILD_ROWS", rows.to_string())
            .env("PDW_STORE_CHILD_ABORT_US", abort_us.to_string())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status()
            .unwrap();
        assert!(
            !status.success(),
            "the writer ({rows} rows, abort at {abort_us} µs) was not killed: {status}"
        );
        #[cfg(unix)]
        {
            use std::os::unix::process::ExitStatusExt;
            assert_eq!(status.signal(), Some(6), "ended by SIGABRT: {status}");
        }
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
        "killed {} times; file size {} bytes",
        trials.len(),
        std::fs::metadata(&p).unwrap().len()
    );
}
