//! Sharding the grid and merging the shards back.

use crate::common;

use std::path::PathBuf;

use common::*;
use pdw_store::{merge, read_basin, shard_rows, BasinWriter, ShardSpec, StoreError, BLOCK_ROWS};

#[test]
fn shard_rows_cover_each_row_exactly_once() {
    for ny in [1, 15, 16, 17, 100, 401, 1000] {
        for n in 1..=7 {
            let mut seen = vec![0u32; ny];
            for i in 0..n {
                let rows = shard_rows(ny, i, n).unwrap();
                assert!(rows.windows(2).all(|w| w[0] < w[1]), "not ascending");
                // Whole chunk blocks only, so shards never share a chunk.
                for r in &rows {
                    assert_eq!((r / BLOCK_ROWS) % n, i);
                    seen[*r] += 1;
                }
            }
            assert!(seen.iter().all(|&c| c == 1), "ny = {ny}, n = {n}: {seen:?}");
        }
    }
    assert!(shard_rows(10, 3, 3).is_err());
    assert!(shard_rows(10, 0, 0).is_err());
}

#[test]
fn shard_spec_parses_i_over_n_from_zero() {
    assert_eq!(
        "2/4".parse::<ShardSpec>().unwrap(),
        ShardSpec { index: 2, count: 4 }
    );
    assert_eq!(ShardSpec { index: 0, count: 1 }.to_string(), "0/1");
    for bad in ["4/4", "1", "a/b", "-1/3", "1/0", ""] {
        let err = bad.parse::<ShardSpec>().unwrap_err();
        assert!(matches!(err, StoreError::Invalid { .. }), "{bad}: {err}");
    }
}

/// Writes shard `i` of `n` (all its rows, in the given order of blocks) and finishes it.
fn write_shard(dir: &std::path::Path, nx: usize, ny: usize, i: usize, n: usize) -> PathBuf {
    let p = dir.join(format!("shard{i}.h5"));
    let h = shard_header(nx, ny, i, n);
    let mut w = BasinWriter::create(&p, &h, false).unwrap();
    let rows = w.rows_todo();
    // Odd groupings: 5 rows at a time, last first.
    for chunk in rows.rchunks(5) {
        for &r in chunk {
            write_block(&mut w, r, 1);
        }
    }
    let own: Vec<u8> = rows.iter().flat_map(|&r| block(&h, r, 1).0).collect();
    w.finish(&fractions(&h, &own), &attractors()).unwrap();
    p
}

#[test]
fn merge_of_shards_equals_the_single_file() {
    let dir = scratch("merge");
    let (nx, ny) = (29, 83);
    let h = header(nx, ny);
    let single = dir.join("single.h5");
    let mut w = BasinWriter::create(&single, &h, false).unwrap();
    write_block(&mut w, 0, ny);
    let (o, _, _) = block(&h, 0, ny);
    w.finish(&fractions(&h, &o), &attractors()).unwrap();

    for n in [1, 2, 3, 7] {
        let sdir = dir.join(format!("n{n}"));
        std::fs::create_dir_all(&sdir).unwrap();
        let shards: Vec<PathBuf> = (0..n)
            .rev()
            .map(|i| write_shard(&sdir, nx, ny, i, n))
            .collect();
        let out = sdir.join("merged.h5");
        let mh = merge(&shards, &out, false, "pdw-sweep merge", |hh, oc| {
            fractions(hh, oc.as_slice().unwrap())
        })
        .unwrap();
        assert_eq!(mh.shard, None);
        let (a, b) = (read_basin(&single).unwrap(), read_basin(&out).unwrap());
        assert_eq!(a.outcome, b.outcome, "n = {n}");
        assert_eq!(a.strides, b.strides);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(
            bits(a.final_state.as_slice().unwrap()),
            bits(b.final_state.as_slice().unwrap())
        );
        assert!(b.complete && b.rows_done.iter().all(|d| *d));
        assert_eq!(a.metrics, b.metrics, "metrics of the merged grid");
        assert_eq!(a.attractors, b.attractors);
        let mut expect = h.clone();
        expect.command = "pdw-sweep merge".into();
        assert_eq!(b.header, expect);

        // The merged file is not overwritten by a second merge without force.
        let before = bytes(&out);
        let err = merge(&shards, &out, false, "again", |hh, oc| {
            fractions(hh, oc.as_slice().unwrap())
        })
        .unwrap_err();
        assert!(matches!(err, StoreError::Exists { .. }), "{err}");
        assert_eq!(bytes(&out), before);
        merge(&shards, &out, true, "again", |hh, oc| {
            fractions(hh, oc.as_slice().unwrap())
        })
        .unwrap();
        assert_eq!(read_basin(&out).unwrap().header.command, "again");
        // No temporary files left beside the output.
        let leftovers: Vec<_> = std::fs::read_dir(&sdir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().contains("partial"))
            .collect();
        assert!(leftovers.is_empty());
    }
}

fn merge_err(shards: &[PathBuf], out: &std::path::Path) -> StoreError {
    let e = merge(shards, out, false, "m", |hh, oc| {
        fractions(hh, oc.as_slice().unwrap())
    })
    .unwrap_err();
    assert!(!out.exists(), "a failed merge left {}", out.display());
    e
}

#[test]
fn merge_rejects_incomplete_inconsistent_missing_or_duplicate_shards() {
    let dir = scratch("mergebad");
    let (nx, ny) = (8, 50);
    let s0 = write_shard(&dir, nx, ny, 0, 2);
    let s1 = write_shard(&dir, nx, ny, 1, 2);
    let out = dir.join("out.h5");

    // Missing shard.
    let e = merge_err(std::slice::from_ref(&s0), &out);
    assert!(matches!(e, StoreError::Coverage { .. }), "{e}");
    // Duplicate shard.
    let e = merge_err(&[s0.clone(), s0.clone()], &out);
    assert!(matches!(e, StoreError::Coverage { .. }), "{e}");

    // Incomplete shard (the writer stopped early).
    let inc = dir.join("incomplete.h5");
    let mut w = BasinWriter::create(&inc, &shard_header(nx, ny, 1, 2), false).unwrap();
    write_block(&mut w, 16, 16);
    drop(w);
    let e = merge_err(&[s0.clone(), inc.clone()], &out);
    assert!(matches!(e, StoreError::Incomplete { .. }), "{e}");
    assert!(e.to_string().contains("incomplete.h5"));

    // A shard of a different run (another slope).
    let other = dir.join("other");
    std::fs::create_dir_all(&other).unwrap();
    let mut h = shard_header(nx, ny, 1, 2);
    h.slope = 0.01;
    let p = other.join("s1.h5");
    let mut w = BasinWriter::create(&p, &h, false).unwrap();
    for r in w.rows_todo() {
        write_block(&mut w, r, 1);
    }
    w.finish(&fractions(&h, &[0]), &attractors()).unwrap();
    let e = merge_err(&[s0.clone(), p.clone()], &out);
    assert!(
        matches!(e, StoreError::Mismatch { ref field, .. } if field == "slope"),
        "{e}"
    );

    // Shards of different splits (0/2 with 1/3).
    let q = write_shard(&other, nx, ny, 1, 3);
    let e = merge_err(&[s0.clone(), q], &out);
    assert!(
        matches!(e, StoreError::Mismatch { ref field, .. } if field == "shard"),
        "{e}"
    );

    // A whole-grid file is not a shard.
    let single = dir.join("single.h5");
    let mut w = BasinWriter::create(&single, &header(nx, ny), false).unwrap();
    write_block(&mut w, 0, ny);
    drop(w);
    let e = merge_err(&[single, s1.clone()], &out);
    assert!(matches!(e, StoreError::Coverage { .. }), "{e}");

    // The output may not be one of the inputs.
    let e = merge(&[s0.clone(), s1.clone()], &s1, true, "m", |hh, oc| {
        fractions(hh, oc.as_slice().unwrap())
    })
    .unwrap_err();
    assert!(matches!(e, StoreError::Invalid { .. }), "{e}");

    // And with all that, the good pair still merges.
    merge(&[s1, s0], &out, false, "m", |hh, oc| {
        fractions(hh, oc.as_slice().unwrap())
    })
    .unwrap();
    assert!(read_basin(&out).unwrap().complete);
}

/// A shard whose block reads back without error but not as written (here: values rewritten
/// behind the writer's back, as a damaged chunk index or object header can make them read) is
/// refused by merge, naming the rows, instead of being merged.
#[test]
fn merge_refuses_a_shard_whose_block_reads_back_different() {
    let dir = scratch("merge-damaged");
    let (nx, ny) = (6, 40);
    let shards: Vec<PathBuf> = (0..2).map(|i| write_shard(&dir, nx, ny, i, 2)).collect();
    let own = pdw_store::shard_rows(ny, 1, 2).unwrap();
    {
        let f = hdf5::File::open_rw(&shards[1]).unwrap();
        let ds = f.dataset("basin/final").unwrap();
        let r0 = own[0];
        let v = ndarray::Array3::<f64>::from_elem((1, nx, 2), 0.25);
        ds.write_slice(&v, ndarray::s![r0..r0 + 1, .., ..]).unwrap();
    }
    match merge_err(&shards, &dir.join("merged.h5")) {
        StoreError::Format { path, detail, .. } => {
            assert_eq!(path, shards[1]);
            assert!(detail.contains("do not read back as written"), "{detail}");
            assert!(detail.contains(&format!("rows {}..", own[0])), "{detail}");
        }
        e => panic!("expected a damaged-shard error, got {e}"),
    }
}
