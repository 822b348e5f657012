//! A second run on a file that a running job is writing (a mistaken `--force`, a duplicated
//! array task) is refused, and the running job keeps its file. In a test binary of its own:
//! child processes forked by tests on other threads would briefly inherit this test's lock.

use std::path::Path;
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pdw-sweep"))
}

fn err(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn basin(out: &Path, extra: &[&str]) -> Output {
    let mut a = vec![
        "basin",
        "--grid",
        "48x40",
        "--max-strides",
        "40",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ];
    a.extend_from_slice(extra);
    bin().args(&a).output().expect("the binary runs")
}

fn refused(o: &Output) -> String {
    assert_eq!(o.status.code(), Some(2), "{}", err(o));
    err(o)
}

fn same_cells(a: &Path, b: &Path) {
    let (a, b) = (
        pdw::store::read_basin(a).unwrap(),
        pdw::store::read_basin(b).unwrap(),
    );
    assert_eq!(a.outcome, b.outcome);
    assert_eq!(a.strides, b.strides);
    let bits = |d: &pdw::store::BasinData| {
        d.final_state
            .iter()
            .map(|v| v.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&a), bits(&b));
}

#[test]
fn a_second_run_on_a_file_being_written_is_refused_and_the_first_keeps_its_file() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full.h5");
    assert!(basin(&full, &[]).status.success());
    let h = pdw::store::read_basin_header(&full).unwrap();
    // A writer of this process holds busy.h5 (as a running basin job would).
    let busy = dir.path().join("busy.h5");
    let mut w = pdw::store::BasinWriter::create(&busy, &h, false).unwrap();
    let data = pdw::store::read_basin(&full).unwrap();
    let (nx, d) = (h.nx(), h.d());
    let rows = |r0: usize, r1: usize| {
        (
            data.outcome.as_slice().unwrap()[r0 * nx..r1 * nx].to_vec(),
            data.strides.as_slice().unwrap()[r0 * nx..r1 * nx].to_vec(),
            data.final_state.as_slice().unwrap()[r0 * nx * d..r1 * nx * d].to_vec(),
        )
    };
    let (o0, s0, f0) = rows(0, 16);
    w.write_rows(0, &o0, &s0, &f0).unwrap();
    for extra in [&["--force"][..], &["--resume"][..]] {
        let o = basin(&busy, extra);
        assert!(refused(&o).contains("another process"), "{}", err(&o));
    }
    // The first writer finishes a valid file.
    let (o1, s1, f1) = rows(16, 40);
    w.write_rows(16, &o1, &s1, &f1).unwrap();
    w.finish(data.metrics.as_ref().unwrap(), &data.attractors)
        .unwrap();
    same_cells(&busy, &full);
}
