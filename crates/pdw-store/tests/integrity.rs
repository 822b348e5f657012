//! Nothing damaged is trusted, nothing running is clobbered: checksummed blocks verified on
//! resume, and the output lock that keeps a second writer off a file being written.

use crate::common;

use common::*;
use pdw_store::{read_basin, BasinWriter, StoreError};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::Path;

/// Writes every row of `h` into a new file at `p` and finishes it.
fn complete_file(p: &Path, h: &pdw_store::BasinHeader) {
    let mut w = BasinWriter::create(p, h, false).unwrap();
    write_block(&mut w, 0, h.ny());
    let (o, _, _) = block(h, 0, h.ny());
    w.finish(&fractions(h, &o), &attractors()).unwrap();
}

/// File offset and size of chunk `index` of dataset `name`.
fn chunk_at(p: &Path, name: &str, index: usize) -> (u64, u64) {
    let f = hdf5::File::open(p).unwrap();
    let ds = f.dataset(name).unwrap();
    let c = ds.chunk_info(index).expect("chunk is allocated");
    (c.addr, c.size)
}

/// Overwrites `n` bytes in the middle of `[at, at + len)` with their complement.
fn damage(p: &Path, at: u64, len: u64, n: u64) {
    let mut f = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(p)
        .unwrap();
    let start = at + len / 2 - n.min(len) / 2;
    let mut buf = vec![0u8; n.min(len) as usize];
    f.seek(SeekFrom::Start(start)).unwrap();
    f.read_exact(&mut buf).unwrap();
    for b in &mut buf {
        *b = !*b;
    }
    f.seek(SeekFrom::Start(start)).unwrap();
    f.write_all(&buf).unwrap();
}

#[test]
fn damaged_chunk_of_a_complete_file_is_detected_and_recomputed_on_resume() {
    let dir = scratch("damaged-complete");
    let p = dir.join("basin.h5");
    let h = header(23, 50); // blocks of rows 0..16, 16..32, 32..48, 48..50
    complete_file(&p, &h);
    let intact = read_basin(&p).unwrap();
    // Damage the second chunk of /basin/final (rows 16..32): the data can no longer be read.
    let (at, len) = chunk_at(&p, "basin/final", 1);
    damage(&p, at, len, 32);
    assert!(
        read_basin(&p).is_err(),
        "the checksum must catch the damage"
    );

    // Resume does not call it complete: it finds the block and schedules it again.
    let w = BasinWriter::resume(&p, &h).unwrap();
    assert_eq!(w.damaged_rows(), (16..32).collect::<Vec<_>>());
    assert_eq!(w.rows_todo(), (16..32).collect::<Vec<_>>());
    drop(w);
    // Interrupted before recomputing: still not complete, still found.
    let d = hdf5::File::open(&p).unwrap();
    assert!(!d.attr("complete").unwrap().read_scalar::<bool>().unwrap());
    drop(d);
    let mut w = BasinWriter::resume(&p, &h).unwrap();
    assert_eq!(w.rows_todo(), (16..32).collect::<Vec<_>>());
    write_block(&mut w, 16, 16);
    let (o, _, _) = block(&h, 0, h.ny());
    w.finish(&fractions(&h, &o), &attractors()).unwrap();

    let repaired = read_basin(&p).unwrap();
    assert!(repaired.complete);
    assert_eq!(repaired.outcome, intact.outcome);
    assert_eq!(repaired.strides, intact.strides);
    let bits = |a: &ndarray::Array3<f64>| a.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&repaired.final_state), bits(&intact.final_state));
    // Now intact: resuming it again is "already complete".
    assert!(matches!(
        BasinWriter::resume(&p, &h),
        Err(StoreError::AlreadyComplete { .. })
    ));
}

#[test]
fn damaged_outcome_chunk_of_a_partial_file_is_recomputed_not_trusted() {
    let dir = scratch("damaged-partial");
    let p = dir.join("basin.h5");
    let h = header(31, 40);
    let mut w = BasinWriter::create(&p, &h, false).unwrap();
    write_block(&mut w, 0, 32); // blocks 0 and 1 on disk, block 2 (rows 32..40) missing
    w.close().unwrap();
    let (at, len) = chunk_at(&p, "basin/outcome", 0);
    damage(&p, at, len, 8);
    let w = BasinWriter::resume(&p, &h).unwrap();
    assert_eq!(w.damaged_rows(), (0..16).collect::<Vec<_>>());
    let mut todo: Vec<usize> = (0..16).collect();
    todo.extend(32..40);
    assert_eq!(w.rows_todo(), todo);
}

/// A writer killed between writing a block and marking it done can leave that block's chunks
/// unreadable (seen once in CI: the chunk index on disk pointed at the end of the allocated
/// file). The file still reads: the block reads as not computed, the blocks marked done as
/// written, and a resume recomputes it.
#[test]
fn unreadable_block_not_marked_done_reads_as_not_computed() {
    let dir = scratch("unreadable-unmarked");
    let p = dir.join("basin.h5");
    let h = header(19, 40);
    let mut w = BasinWriter::create(&p, &h, false).unwrap();
    write_block(&mut w, 0, 32);
    w.close().unwrap();
    {
        let f = hdf5::File::open_rw(&p).unwrap();
        let d = f.dataset("basin/rows_done").unwrap();
        d.write_slice(&[0u8; 16], ndarray::s![16..32]).unwrap();
    }
    for name in ["basin/outcome", "basin/strides", "basin/final"] {
        let (at, len) = chunk_at(&p, name, 1);
        damage(&p, at, len, 8);
    }
    let d = read_basin(&p).unwrap();
    let (o, s, f) = block(&h, 0, 16);
    assert_eq!(
        d.outcome
            .slice(ndarray::s![0..16, ..])
            .iter()
            .copied()
            .collect::<Vec<_>>(),
        o
    );
    assert_eq!(
        d.strides
            .slice(ndarray::s![0..16, ..])
            .iter()
            .copied()
            .collect::<Vec<_>>(),
        s
    );
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let f0: Vec<f64> = d
        .final_state
        .slice(ndarray::s![0..16, .., ..])
        .iter()
        .copied()
        .collect();
    assert_eq!(bits(&f0), bits(&f));
    assert!(d
        .outcome
        .slice(ndarray::s![16..40, ..])
        .iter()
        .all(|&c| c == pdw_store::NOT_COMPUTED));
    assert!(d
        .strides
        .slice(ndarray::s![16..40, ..])
        .iter()
        .all(|&c| c == 0));
    assert!(d
        .final_state
        .slice(ndarray::s![16..40, .., ..])
        .iter()
        .all(|v| v.is_nan()));
    let (_, oc) = pdw_store::read_basin_outcome(&p).unwrap();
    assert_eq!(oc, d.outcome);
    let w = BasinWriter::resume(&p, &h).unwrap();
    assert_eq!(w.rows_todo(), (16..40).collect::<Vec<_>>());
}

#[test]
fn a_file_being_written_is_not_truncated_by_a_second_writer() {
    let dir = scratch("locked");
    let p = dir.join("basin.h5");
    let h = header(20, 32);
    let mut first = BasinWriter::create(&p, &h, false).unwrap();
    write_block(&mut first, 0, 16);
    let size_before = std::fs::metadata(&p).unwrap().len();
    // A second run with --force, and a second --resume, are refused while the first writes.
    let err = BasinWriter::create(&p, &h, true).unwrap_err();
    assert!(matches!(err, StoreError::Busy { .. }), "{err}");
    assert!(err.to_string().contains("another process"), "{err}");
    let err = BasinWriter::resume(&p, &h).unwrap_err();
    assert!(matches!(err, StoreError::Busy { .. }), "{err}");
    assert!(std::fs::metadata(&p).unwrap().len() >= size_before);
    // The first run is unharmed and finishes a readable file.
    write_block(&mut first, 16, 16);
    let (o, _, _) = block(&h, 0, 32);
    first.finish(&fractions(&h, &o), &attractors()).unwrap();
    let d = read_basin(&p).unwrap();
    assert!(d.complete);
    assert_eq!(d.outcome.as_slice().unwrap(), &o[..]);
    // Once it is done, --force may replace it.
    let w = BasinWriter::create(&p, &h, true).unwrap();
    drop(w);
}

/// HDF5 opens files without close-on-exec, so a child process started by another thread while
/// a file is open inherits its descriptor and, with it, the descriptor's `flock`. Every open of
/// this crate turns HDF5's own locking off, so such a left-over lock (held here by the test
/// itself) stops neither annotating, nor reading a file back.
#[test]
fn a_lock_left_on_a_finished_file_stops_neither_annotation_nor_reading() {
    let dir = scratch("inherited-lock");
    let p = dir.join("basin.h5");
    let h = header(20, 32);
    complete_file(&p, &h);
    let held = std::fs::File::open(&p).unwrap();
    held.lock().unwrap();
    let units = |ds: &str| (ds == "basin/outcome").then(|| "1".to_string());
    pdw_store::annotate(
        &p,
        &pdw_store::Annotations {
            provenance: None,
            units: &units,
            slice: None,
            scales: &[],
            coordinates: None,
        },
    )
    .unwrap();
    assert_eq!(
        pdw_store::provenance::read_units(&p, "basin/outcome").unwrap(),
        Some("1".to_string())
    );
    assert!(pdw_store::provenance::read_slice(&p).unwrap().is_none());
    assert!(pdw_store::provenance::read_slice_view(&p)
        .unwrap()
        .is_none());
    assert!(read_basin(&p).unwrap().complete);
    // HDF5's own locking, as the library opens by default, is what such a lock stops.
    let locked = hdf5::File::with_options()
        .with_fapl(|f| f.file_locking(true))
        .open_rw(&p);
    assert!(locked.is_err(), "the left-over lock is held");
    held.unlock().unwrap();
}

#[test]
fn non_regular_outputs_are_refused() {
    let dir = scratch("fifo");
    let fifo = dir.join("fifo.h5");
    // mkfifo(3) directly: spawning a process here would fork this multi-threaded test binary
    // and let the child briefly hold other tests' file locks.
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(fifo.as_os_str().as_bytes()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
    let h = header(8, 8);
    let err = BasinWriter::create(&fifo, &h, true).unwrap_err();
    assert!(err.to_string().contains("not a regular file"), "{err}");
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
}

/// Every byte of a complete file flipped in turn (a fixed stride through the whole file: the
/// superblock, object headers, chunk indexes, attributes, data): a resume either refuses, or
/// rebuilds the damaged blocks and finishes with the intact data, or says "already complete"
/// only when the file reads back equal to the intact one. Never "complete" with damage.
#[test]
fn a_byte_flipped_anywhere_is_refused_repaired_or_harmless() {
    let dir = scratch("flip-anywhere");
    let clean = dir.join("clean.h5");
    let p = dir.join("basin.h5");
    let h = header(23, 50);
    complete_file(&clean, &h);
    let intact = read_basin(&clean).unwrap();
    let bits = |a: &ndarray::Array3<f64>| a.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    let same = |d: &pdw_store::BasinData| {
        d.complete
            && d.outcome == intact.outcome
            && d.strides == intact.strides
            && bits(&d.final_state) == bits(&intact.final_state)
    };
    let len = std::fs::metadata(&clean).unwrap().len();
    let (mut refused, mut repaired, mut harmless) = (0, 0, 0);
    let stride = (len / 700).max(1);
    for at in (0..len).step_by(stride as usize) {
        std::fs::copy(&clean, &p).unwrap();
        damage(&p, at, 1, 1);
        match BasinWriter::resume(&p, &h) {
            Err(StoreError::AlreadyComplete { .. }) => {
                let d = read_basin(&p);
                assert!(
                    d.as_ref().is_ok_and(same),
                    "byte {at} of {len}: resume says complete but the file reads {}",
                    match &d {
                        Ok(d) => format!(
                            "different data (complete {}, outcome {}, strides {}, final {})",
                            d.complete,
                            d.outcome == intact.outcome,
                            d.strides == intact.strides,
                            bits(&d.final_state) == bits(&intact.final_state)
                        ),
                        Err(e) => e.to_string(),
                    }
                );
                harmless += 1;
            }
            Err(_) => refused += 1,
            Ok(mut w) => {
                let todo = w.rows_todo();
                for b in 0..h.ny().div_ceil(16) {
                    if todo.contains(&(16 * b)) {
                        write_block(&mut w, 16 * b, 16.min(h.ny() - 16 * b));
                    }
                }
                let (o, _, _) = block(&h, 0, h.ny());
                w.finish(&fractions(&h, &o), &attractors()).unwrap();
                let d = read_basin(&p);
                assert!(
                    d.as_ref().is_ok_and(same),
                    "byte {at} of {len}: the repaired file differs from the intact one"
                );
                repaired += 1;
            }
        }
    }
    eprintln!("{len} bytes, every {stride}th flipped: {refused} refused, {repaired} repaired, {harmless} harmless");
    assert!(refused + repaired > 0, "no flip was noticed at all");
}

/// What the explorer reads (`read_basin`: the header — axes, coordinate names, legend, run
/// attributes — and the cells) is either refused or equal to the intact file, for a byte flipped
/// anywhere (a fixed stride through the whole file). Before the header's digest, a flipped axis
/// value or legend letter that still parsed was served as valid.
#[test]
fn a_byte_flipped_anywhere_is_never_read_as_a_different_header() {
    let dir = scratch("flip-header");
    let clean = dir.join("clean.h5");
    let p = dir.join("basin.h5");
    let h = header(23, 50);
    complete_file(&clean, &h);
    let intact = read_basin(&clean).unwrap();
    assert_eq!(intact.header, h, "the intact file reads its own header");
    let len = std::fs::metadata(&clean).unwrap().len();
    let (mut refused, mut same) = (0, 0);
    let stride = (len / 900).max(1);
    for at in (0..len).step_by(stride as usize) {
        std::fs::copy(&clean, &p).unwrap();
        damage(&p, at, 1, 1);
        match read_basin(&p) {
            Err(_) => refused += 1,
            Ok(d) => {
                assert!(
                    d.header == intact.header,
                    "byte {at} of {len}: served a different header: {:?} against {:?}",
                    d.header,
                    intact.header
                );
                assert!(
                    d.outcome == intact.outcome,
                    "byte {at} of {len}: served different outcome codes"
                );
                same += 1;
            }
        }
    }
    eprintln!(
        "{len} bytes, every {stride}th flipped: {refused} refused, {same} read as the intact file"
    );
    assert!(refused > 0, "no flip was noticed at all");
}

/// The header's digest is what refuses a damaged axis value that still parses: the same value
/// changed through HDF5 itself (no checksum can see that) is refused, naming the digest.
#[test]
fn an_axis_value_changed_after_writing_is_refused_by_the_header_digest() {
    let dir = scratch("axis-changed");
    let p = dir.join("basin.h5");
    let h = header(23, 50);
    complete_file(&p, &h);
    {
        let f = hdf5::File::open_rw(&p).unwrap();
        let x = f.dataset("grid/x").unwrap();
        let mut v = x.read_raw::<f64>().unwrap();
        v[7] += 1e-3;
        x.write_raw(&v).unwrap();
    }
    let e = read_basin(&p).unwrap_err().to_string();
    assert!(
        e.contains("header is damaged") && e.contains("header_digest"),
        "{e}"
    );
}

/// A file of another resolved model (same name and parameter values, a different spec line) is
/// refused, naming the line that differs.
#[test]
fn resume_refuses_a_file_of_a_different_resolved_model() {
    let dir = scratch("model-resolved");
    let p = dir.join("basin.h5");
    let mut h = header(7, 20);
    h.model_resolved = "model = my\nsegments[0] = length 1.0, com 0.5\n".into();
    let mut w = BasinWriter::create(&p, &h, false).unwrap();
    write_block(&mut w, 0, 16);
    w.close().unwrap();
    let mut other = h.clone();
    other.model_resolved = "model = my\nsegments[0] = length 1.0, com 0.505\n".into();
    match BasinWriter::resume(&p, &other) {
        Err(StoreError::Mismatch {
            field,
            found,
            expected,
            ..
        }) => {
            assert_eq!(field, "resolved model");
            assert_eq!(found, "segments[0] = length 1.0, com 0.5");
            assert_eq!(expected, "segments[0] = length 1.0, com 0.505");
        }
        Err(e) => panic!("expected a mismatch, got {e}"),
        Ok(_) => panic!("a different model was resumed"),
    }
    // the same model continues
    let w = BasinWriter::resume(&p, &h).unwrap();
    assert_eq!(w.rows_todo(), (16..20).collect::<Vec<_>>());
}

/// A global heap collection (where every string attribute lives) whose free-space object a
/// damaged byte left with size 0 would make the HDF5 library loop forever on the first string
/// it reads: the file is refused as damaged before the library sees it, by resume and by every
/// reader.
#[test]
fn a_global_heap_the_library_would_loop_on_is_refused() {
    let dir = scratch("gcol");
    let p = dir.join("basin.h5");
    let h = header(9, 20);
    complete_file(&p, &h);
    let mut bytes = std::fs::read(&p).unwrap();
    let start = bytes
        .windows(4)
        .position(|w| w == b"GCOL")
        .expect("a global heap");
    let size = u64::from_le_bytes(bytes[start + 8..start + 16].try_into().unwrap()) as usize;
    // Walk the collection's objects to its free space (index 0) and zero its size.
    let mut at = start + 16;
    loop {
        let idx = u16::from_le_bytes([bytes[at], bytes[at + 1]]);
        let len = u64::from_le_bytes(bytes[at + 8..at + 16].try_into().unwrap()) as usize;
        if idx == 0 {
            bytes[at + 8..at + 16].fill(0);
            break;
        }
        at += 16 + len.div_ceil(8) * 8;
        assert!(at + 16 <= start + size, "no free space in the collection");
    }
    std::fs::write(&p, &bytes).unwrap();
    let Err(resumed) = BasinWriter::resume(&p, &h) else {
        panic!("a file with a damaged global heap was resumed");
    };
    for e in [resumed, read_basin(&p).unwrap_err()] {
        let text = e.to_string();
        assert!(
            text.contains(&format!("damaged global heap at byte {at}")),
            "{text}"
        );
    }
}
