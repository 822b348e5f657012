//! The basin file: round trip, overwrite protection, resume, error paths.

use crate::common;

use common::*;
use pdw_store::{read_basin, BasinWriter, StoreError, NOT_COMPUTED};

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|a| a.to_bits()).collect()
}

#[test]
fn round_trip_preserves_values_attributes_and_legend() {
    let dir = scratch("roundtrip");
    let p = dir.join("basin.h5");
    let h = header(37, 41);
    let mut w = BasinWriter::create(&p, &h, false).unwrap();
    // Blocks that do not align with chunks, written out of order.
    for r0 in [35, 0, 7, 14, 21, 28] {
        let k = 7.min(41 - r0);
        write_block(&mut w, r0, k);
    }
    assert!(w.rows_todo().is_empty());
    let (o, _, _) = block(&h, 0, 41);
    let m = fractions(&h, &o);
    w.finish(&m, &attractors()).unwrap();

    let d = read_basin(&p).unwrap();
    assert_eq!(d.header, h);
    assert!(d.complete);
    assert_eq!(d.version, env!("CARGO_PKG_VERSION"));
    assert!(
        d.created.len() == 20 && d.created.ends_with('Z'),
        "{}",
        d.created
    );
    assert!(d.elapsed_s >= 0.0 && d.elapsed_s.is_finite());
    assert!(d.rows_done.iter().all(|b| *b));
    let (o, s, f) = block(&h, 0, 41);
    assert_eq!(d.outcome.as_slice().unwrap(), &o[..]);
    assert_eq!(d.strides.as_slice().unwrap(), &s[..]);
    assert_eq!(bits(d.final_state.as_slice().unwrap()), bits(&f));
    assert_eq!(d.metrics.as_ref(), Some(&m));
    assert_eq!(d.attractors, attractors());

    // The schema as another reader sees it: legend JSON, chunked + deflate, attribute types.
    let f = hdf5::File::open(&p).unwrap();
    let legend: hdf5::types::VarLenUnicode = f
        .dataset("basin/outcome")
        .unwrap()
        .attr("legend")
        .unwrap()
        .read_scalar()
        .unwrap();
    let legend: serde_json::Value = serde_json::from_str(legend.as_str()).unwrap();
    assert_eq!(legend["0"], "gait");
    assert_eq!(legend["2"], "fall_forward");
    for name in ["basin/outcome", "basin/strides", "basin/final"] {
        let ds = f.dataset(name).unwrap();
        assert!(ds.is_chunked(), "{name} not chunked");
        assert!(
            ds.filters()
                .iter()
                .any(|x| matches!(x, hdf5::filters::Filter::Deflate(_))),
            "{name} not deflate-compressed"
        );
    }
    let complete: bool = f.attr("complete").unwrap().read_scalar().unwrap();
    assert!(complete);
    let fmt: hdf5::types::VarLenUnicode = f.attr("format").unwrap().read_scalar().unwrap();
    assert_eq!(fmt.as_str(), "pdw-sweep basin v1");
    let gx = f.dataset("grid/x").unwrap();
    let name: hdf5::types::VarLenUnicode = gx.attr("name").unwrap().read_scalar().unwrap();
    assert_eq!(name.as_str(), "theta");
    assert_eq!(bits(&gx.read_raw::<f64>().unwrap()), bits(&h.x));
}

#[test]
fn unwritten_rows_read_as_not_computed_with_nan_state() {
    let dir = scratch("fill");
    let p = dir.join("b.h5");
    let h = header(5, 40);
    let mut w = BasinWriter::create(&p, &h, false).unwrap();
    write_block(&mut w, 16, 16);
    drop(w);
    let d = read_basin(&p).unwrap();
    assert!(!d.complete);
    for i in 0..40 {
        let written = (16..32).contains(&i);
        assert_eq!(d.rows_done[i], written);
        for j in 0..5 {
            assert_eq!(d.outcome[[i, j]] == NOT_COMPUTED, !written);
            assert_eq!(
                d.final_state[[i, j, 0]].is_nan(),
                !written || d.outcome[[i, j]] == 5
            );
        }
    }
    assert!(d.metrics.is_none());
}

#[test]
fn existing_file_is_not_overwritten_without_force() {
    let dir = scratch("noclobber");
    let p = dir.join("precious.h5");
    std::fs::write(&p, b"results of a week of computing").unwrap();
    let err = BasinWriter::create(&p, &header(4, 4), false).unwrap_err();
    assert!(matches!(err, StoreError::Exists { .. }), "{err}");
    assert!(err.to_string().contains("precious.h5"), "{err}");
    assert_eq!(bytes(&p), b"results of a week of computing");

    let w = BasinWriter::create(&p, &header(4, 4), true).unwrap();
    drop(w);
    assert!(read_basin(&p).is_ok());
}

#[test]
fn resume_after_drop_matches_uninterrupted_write() {
    let dir = scratch("resume");
    let (nx, ny) = (23, 70);
    let h = header(nx, ny);
    // Uninterrupted: aligned blocks in order.
    let a = dir.join("a.h5");
    let mut w = BasinWriter::create(&a, &h, false).unwrap();
    for r0 in (0..ny).step_by(16) {
        write_block(&mut w, r0, 16.min(ny - r0));
    }
    let (o, _, _) = block(&h, 0, ny);
    w.finish(&fractions(&h, &o), &attractors()).unwrap();

    // Interrupted twice: some rows, dropped without finish (the process stops), resumed.
    // Rows of a block not complete when the writer stops are written as they are and marked
    // done; the resumed writer holds them until their block is complete.
    let b = dir.join("b.h5");
    let mut w = BasinWriter::create(&b, &h, false).unwrap();
    write_block(&mut w, 48, 16);
    write_block(&mut w, 3, 5);
    assert_eq!(w.rows_todo().len(), ny - 21, "held rows are not to do");
    drop(w);
    let part = read_basin(&b).unwrap();
    let marked: Vec<usize> = (0..ny).filter(|&r| part.rows_done[r]).collect();
    assert_eq!(marked, (3..8).chain(48..64).collect::<Vec<_>>());
    let (o3, _, _) = block(&h, 3, 5);
    assert_eq!(
        part.outcome
            .slice(ndarray::s![3..8, ..])
            .iter()
            .copied()
            .collect::<Vec<_>>(),
        o3
    );
    assert!(part
        .outcome
        .row(2)
        .iter()
        .all(|&c| c == pdw_store::NOT_COMPUTED));
    let mut w = BasinWriter::resume(&b, &h).unwrap();
    let todo = w.rows_todo();
    assert_eq!(todo.len(), ny - 21);
    assert!(!todo.contains(&50) && !todo.contains(&3) && !todo.contains(&7));
    assert!(todo.contains(&2) && todo.contains(&8) && todo.contains(&47) && todo.contains(&64));
    write_block(&mut w, 0, 3);
    write_block(&mut w, 64, 6);
    drop(w);
    let marked: Vec<usize> = {
        let d = read_basin(&b).unwrap();
        (0..ny).filter(|&r| d.rows_done[r]).collect()
    };
    assert_eq!(marked, (0..8).chain(48..70).collect::<Vec<_>>());
    let mut w = BasinWriter::resume(&b, &h).unwrap();
    // Rewrite whatever is left, one row at a time in reverse order.
    for r in w.rows_todo().into_iter().rev() {
        write_block(&mut w, r, 1);
    }
    w.finish(&fractions(&h, &o), &attractors()).unwrap();

    let (da, db) = (read_basin(&a).unwrap(), read_basin(&b).unwrap());
    assert_eq!(da.outcome, db.outcome);
    assert_eq!(da.strides, db.strides);
    assert_eq!(
        bits(da.final_state.as_slice().unwrap()),
        bits(db.final_state.as_slice().unwrap())
    );
    assert_eq!(da.rows_done, db.rows_done);
    assert_eq!(da.header, db.header);
    assert_eq!(da.metrics, db.metrics);
    assert_eq!(da.attractors, db.attractors);
    assert!(da.complete && db.complete);
}

#[test]
fn mismatched_resume_is_refused_and_leaves_file_unchanged() {
    let dir = scratch("mismatch");
    let p = dir.join("b.h5");
    let h = header(10, 20);
    let mut w = BasinWriter::create(&p, &h, false).unwrap();
    write_block(&mut w, 0, 16);
    drop(w);
    let before = bytes(&p);

    let mut cases = Vec::new();
    let mut m = h.clone();
    m.slope = f64::from_bits(h.slope.to_bits() + 1); // one ulp
    cases.push((m, "slope"));
    let mut m = h.clone();
    m.x[3] += 1e-12;
    cases.push((m, "x grid"));
    let mut m = h.clone();
    m.y = linspace(-0.25, -0.15, 21);
    cases.push((m, "y grid"));
    let mut m = h.clone();
    m.params = r#"{"gamma":0.0091}"#.into();
    cases.push((m, "params"));
    let mut m = h.clone();
    m.model = "compass".into();
    cases.push((m, "model"));
    let mut m = h.clone();
    m.legend[1].1 = "period2".into();
    cases.push((m, "legend"));
    let mut m = h.clone();
    m.max_strides = 200;
    cases.push((m, "max_strides"));
    let mut m = h.clone();
    m.x_name = "phi".into();
    cases.push((m, "x coordinate"));
    cases.push((shard_header(10, 20, 0, 2), "shard"));
    for (m, field) in cases {
        let err = BasinWriter::resume(&p, &m).unwrap_err();
        match &err {
            StoreError::Mismatch { field: f, .. } => assert_eq!(f, field, "{err}"),
            _ => panic!("expected a mismatch on {field}, got {err}"),
        }
        assert!(err.to_string().contains("b.h5"));
        assert_eq!(
            bytes(&p),
            before,
            "file changed by a refused resume ({field})"
        );
    }
    // The command line is not part of the identity.
    let mut same = h.clone();
    same.command = "pdw-sweep basin --resume".into();
    let w = BasinWriter::resume(&p, &same).unwrap();
    assert_eq!(w.rows_todo(), (16..20).collect::<Vec<_>>());
}

#[test]
fn resume_of_complete_file_is_refused() {
    let dir = scratch("complete");
    let p = dir.join("b.h5");
    let h = header(3, 3);
    let mut w = BasinWriter::create(&p, &h, false).unwrap();
    write_block(&mut w, 0, 3);
    let (o, _, _) = block(&h, 0, 3);
    w.finish(&fractions(&h, &o), &[]).unwrap();
    let before = bytes(&p);
    let err = BasinWriter::resume(&p, &h).unwrap_err();
    assert!(matches!(err, StoreError::AlreadyComplete { .. }), "{err}");
    assert_eq!(bytes(&p), before);
}

#[test]
fn corrupt_or_foreign_files_give_typed_errors_naming_the_path() {
    let dir = scratch("corrupt");
    let h = header(4, 4);
    // Not HDF5 at all.
    let junk = dir.join("junk.h5");
    std::fs::write(&junk, vec![0x42u8; 4096]).unwrap();
    let err = BasinWriter::resume(&junk, &h).unwrap_err();
    assert!(matches!(err, StoreError::Hdf5 { .. }), "{err}");
    assert!(err.to_string().contains("junk.h5"), "{err}");
    assert_eq!(bytes(&junk), vec![0x42u8; 4096]);
    assert!(read_basin(&junk).is_err());

    // HDF5, but not a basin file.
    let other = dir.join("other.h5");
    hdf5::File::create(&other)
        .unwrap()
        .new_dataset::<f64>()
        .shape([3])
        .create("data")
        .unwrap();
    let before = bytes(&other);
    let err = BasinWriter::resume(&other, &h).unwrap_err();
    assert!(matches!(err, StoreError::Format { .. }), "{err}");
    assert!(err.to_string().contains("other.h5"), "{err}");
    assert_eq!(bytes(&other), before);

    // A basin file truncated half-way (a disk filled up, a copy interrupted).
    let good = dir.join("good.h5");
    let mut w = BasinWriter::create(&good, &h, false).unwrap();
    write_block(&mut w, 0, 2);
    drop(w);
    let cut = dir.join("cut.h5");
    let b = bytes(&good);
    std::fs::write(&cut, &b[..b.len() / 2]).unwrap();
    let err = BasinWriter::resume(&cut, &h).unwrap_err();
    assert!(err.to_string().contains("cut.h5"), "{err}");
    assert_eq!(bytes(&cut), &b[..b.len() / 2]);

    // Missing file.
    let err = BasinWriter::resume(dir.join("missing.h5"), &h).unwrap_err();
    assert!(matches!(err, StoreError::Io { .. }) && err.to_string().contains("missing.h5"));
}

#[test]
fn unwritable_path_is_an_io_error_naming_it() {
    let dir = scratch("unwritable");
    let p = dir.join("no/such/dir/basin.h5");
    let err = BasinWriter::create(&p, &header(3, 3), false).unwrap_err();
    assert!(matches!(err, StoreError::Io { .. }), "{err}");
    assert!(err.to_string().contains("no/such/dir/basin.h5"), "{err}");
    let err = BasinWriter::create(&dir, &header(3, 3), true).unwrap_err();
    assert!(matches!(err, StoreError::Io { .. }), "{err}");
}

#[test]
fn bad_row_blocks_are_rejected_without_marking_rows() {
    let dir = scratch("badrows");
    let p = dir.join("b.h5");
    let h = header(4, 40);
    let mut w = BasinWriter::create(&p, &h, false).unwrap();
    let (o, s, f) = block(&h, 0, 2);
    assert!(w.write_rows(0, &o[..7], &s[..7], &f[..14]).is_err()); // not whole rows
    assert!(w.write_rows(0, &o, &s[..4], &f).is_err()); // strides short
    assert!(w.write_rows(0, &o, &s, &f[..8]).is_err()); // final short
    assert!(w.write_rows(39, &o, &s, &f).is_err()); // past the end
    let mut bad = o.clone();
    bad[1] = 9; // not in the legend
    assert!(w.write_rows(0, &bad, &s, &f).is_err());
    assert_eq!(w.rows_todo().len(), 40);
    drop(w);

    // A shard accepts only its own rows.
    let sp = dir.join("s.h5");
    let mut w = BasinWriter::create(&sp, &shard_header(4, 40, 1, 2), false).unwrap();
    assert_eq!(w.rows_todo(), (16..32).collect::<Vec<_>>());
    let err = w.write_rows(0, &o, &s, &f).unwrap_err();
    assert!(err.to_string().contains("row 0"), "{err}");
    write_block(&mut w, 16, 14);
    // An unfinished grid cannot be finished (14 rows wait for the block's last 2).
    let err = w.finish(&fractions(&h, &o), &[]).unwrap_err();
    assert!(
        matches!(
            err,
            StoreError::Incomplete {
                done: 0,
                expected: 16,
                ..
            }
        ),
        "{err}"
    );

    // Rows already on disk are not taken again.
    let p2 = dir.join("b2.h5");
    let mut w = BasinWriter::create(&p2, &h, false).unwrap();
    write_block(&mut w, 0, 16);
    let (o1, s1, f1) = block(&h, 5, 1);
    let err = w.write_rows(5, &o1, &s1, &f1).unwrap_err();
    assert!(
        err.to_string().contains("row 5 is already on disk"),
        "{err}"
    );
}

#[test]
fn headers_with_bad_grids_or_legends_are_rejected_at_creation() {
    let dir = scratch("badheader");
    let p = dir.join("b.h5");
    let mut cases = Vec::new();
    let mut h = header(3, 3);
    h.x.clear();
    cases.push(h);
    let mut h = header(3, 3);
    h.y[1] = f64::NAN;
    cases.push(h);
    let mut h = header(3, 3);
    h.legend.push((NOT_COMPUTED, "unset".into()));
    cases.push(h);
    let mut h = header(3, 3);
    h.legend.push((0, "again".into()));
    cases.push(h);
    let mut h = header(3, 3);
    h.params = "gamma=0.009".into();
    cases.push(h);
    let mut h = header(3, 3);
    h.state_names.clear();
    cases.push(h);
    cases.push(shard_header(3, 3, 2, 2));
    for h in cases {
        let err = BasinWriter::create(&p, &h, false).unwrap_err();
        assert!(matches!(err, StoreError::Invalid { .. }), "{err}");
        assert!(!p.exists(), "a rejected header left a file behind");
    }
}

#[test]
fn start_resumes_existing_files_and_creates_missing_ones() {
    fn assert_send<T: Send>() {}
    assert_send::<BasinWriter>(); // the CLI may hand the writer to a writer thread

    let dir = scratch("start");
    let p = dir.join("b.h5");
    let h = header(6, 40);
    // --resume on a missing file starts it.
    let mut w = BasinWriter::start(&p, &h, true, false).unwrap();
    write_block(&mut w, 16, 16);
    w.close().unwrap();
    // --resume continues it, even with --force (which never replaces a file being resumed).
    let w = BasinWriter::start(&p, &h, true, true).unwrap();
    assert_eq!(w.rows_todo().len(), 24);
    drop(w);
    let mut other = h.clone();
    other.slope = 0.01;
    assert!(matches!(
        BasinWriter::start(&p, &other, true, true),
        Err(StoreError::Mismatch { .. })
    ));
    // Without --resume an existing file needs --force.
    assert!(matches!(
        BasinWriter::start(&p, &h, false, false),
        Err(StoreError::Exists { .. })
    ));
    let w = BasinWriter::start(&p, &h, false, true).unwrap();
    assert_eq!(w.rows_todo().len(), 40);
}

/// Attractor validity: written as the `validity` / `invalid_reasons` attributes another reader
/// sees, read back; a file without them (written before validity was recorded) reads as
/// unchecked; an unknown word is a format error naming the words allowed.
#[test]
fn attractor_validity_is_recorded_and_old_files_read_as_unchecked() {
    use pdw_store::OrbitCheck;
    let dir = scratch("orbitcheck");
    let p = dir.join("basin.h5");
    let h = header(5, 4);
    let mut w = BasinWriter::create(&p, &h, false).unwrap();
    write_block(&mut w, 0, 4);
    let (o, _, _) = block(&h, 0, 4);
    w.finish(&fractions(&h, &o), &attractors()).unwrap();
    {
        let f = hdf5::File::open(&p).unwrap();
        let word = |g: &str, a: &str| -> String {
            let v: hdf5::types::VarLenUnicode = f
                .group(&format!("attractors/{g}"))
                .unwrap()
                .attr(a)
                .unwrap()
                .read_scalar()
                .unwrap();
            v.as_str().to_string()
        };
        assert_eq!(word("gait", "validity"), "valid");
        assert_eq!(word("period2", "validity"), "invalid");
        assert_eq!(
            word("period2", "invalid_reasons"),
            "a knee lock must pull; the swing foot scuffs"
        );
    }
    let d = read_basin(&p).unwrap();
    assert_eq!(d.attractors[0].validity, OrbitCheck::Valid);
    assert_eq!(
        d.attractors[1].validity.reasons().unwrap(),
        ["a knee lock must pull", "the swing foot scuffs"]
    );
    {
        let f = hdf5::File::open_rw(&p).unwrap();
        let g = f.group("attractors/period2").unwrap();
        g.delete_attr("validity").unwrap();
        g.delete_attr("invalid_reasons").unwrap();
    }
    assert_eq!(
        read_basin(&p).unwrap().attractors[1].validity,
        OrbitCheck::Unchecked
    );
    {
        let f = hdf5::File::open_rw(&p).unwrap();
        let g = f.group("attractors/gait").unwrap();
        g.delete_attr("validity").unwrap();
        let bad: hdf5::types::VarLenUnicode = "maybe".parse().unwrap();
        g.new_attr::<hdf5::types::VarLenUnicode>()
            .create("validity")
            .unwrap()
            .write_scalar(&bad)
            .unwrap();
    }
    let e = read_basin(&p).unwrap_err().to_string();
    assert!(
        e.contains("\"maybe\"") && e.contains("valid, invalid or not checked"),
        "{e}"
    );
}
