//! 3-D basins (`basin --z NAME=LO:HI --grid NXxNYxNZ`) against independent references: every
//! z-slice equals the 2-D basin computed with that z value fixed by `--set` (a different path
//! through the front end: the coordinate held fixed off the axes, not swept), merged shards and
//! a resumed run equal a single run, the file's shape and axes, and bad input refused.

use crate::common::{h5_open, run, stderr};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const X: &str = "stance=0.2:0.34";
const Y: &str = "stance_rate=-1.37:-0.82";
const Z: &str = "hip_rate=0.4:1.0";

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A compass-walker basin over `X`, `Y` (and `--z`, `--set`… in `extra`) into `dir/name`.
fn compass_basin(dir: &Path, name: &str, grid: &str, extra: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let mut args = vec![
        "basin", "--model", "compass", "--x", X, "--y", Y, "--grid", grid, "--out",
    ];
    args.push(s(&out));
    args.extend(["--quiet", "--max-strides", "60"]);
    args.extend(extra);
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    out
}

fn read(p: &Path) -> pdw::store::BasinData {
    pdw::store::read_basin(p).expect("readable basin file")
}

/// The outcome names by code.
fn names(d: &pdw::store::BasinData) -> BTreeMap<u8, String> {
    d.header.legend.iter().cloned().collect()
}

/// Every cell's outcome (by name), strides and final state (bits) of the rows `rows`.
fn cells(d: &pdw::store::BasinData, rows: std::ops::Range<usize>) -> Vec<(String, u16, Vec<u64>)> {
    let n = names(d);
    rows.flat_map(|r| (0..d.header.nx()).map(move |j| (r, j)))
        .map(|(r, j)| {
            let f = d.final_state.slice(pdw::store::ndarray::s![r, j, ..]);
            (
                n[&d.outcome[[r, j]]].clone(),
                d.strides[[r, j]],
                f.iter().map(|v| v.to_bits()).collect(),
            )
        })
        .collect()
}

#[test]
fn every_z_slice_equals_the_2d_basin_with_z_fixed() {
    let dir = tempfile::tempdir().unwrap();
    let f3 = compass_basin(dir.path(), "c3.h5", "9x9x5", &["--z", Z]);
    let d3 = read(&f3);
    let h = &d3.header;
    let z = h.z.as_ref().expect("a 3-D file");
    assert_eq!((h.nx(), h.ny(), h.nz()), (9, 9, 5));
    assert_eq!(z.name, "hip_rate");
    // the z values: 5 evenly spaced over 0.4..1.0, both bounds included
    for (k, v) in z.values.iter().enumerate() {
        assert!((v - (0.4 + 0.15 * k as f64)).abs() < 1e-15, "{v}");
    }
    let mut fractions_2d: BTreeMap<String, f64> = BTreeMap::new();
    let mut entropy_2d = 0.0;
    for (k, v) in z.values.iter().enumerate() {
        let set = format!("hip_rate={v}");
        let f2 = compass_basin(dir.path(), &format!("c2_{k}.h5"), "9x9", &["--set", &set]);
        let d2 = read(&f2);
        assert!(d2.header.z.is_none());
        assert_eq!(d2.header.x, h.x);
        assert_eq!(d2.header.y, h.y);
        let (a2, a3) = (&d2.attractors, &d3.attractors);
        assert!(
            a2.len() == a3.len() && a2.iter().zip(a3).all(|(p, q)| p.name == q.name),
            "slice {k}: the attractors differ"
        );
        assert_eq!(
            cells(&d3, k * 9..(k + 1) * 9),
            cells(&d2, 0..9),
            "slice {k} (hip_rate = {v}) differs from the 2-D basin"
        );
        let m = d2.metrics.unwrap();
        for (n, f) in m.fractions {
            *fractions_2d.entry(n).or_default() += f / 5.0;
        }
        entropy_2d += m.basin_entropy / 5.0;
    }
    // the 3-D fractions are the slices' mean (equal slices), and so is the pooled entropy
    // (one 5×5 box per 9×9 slice)
    let m3 = d3.metrics.clone().unwrap();
    for (n, f) in &m3.fractions {
        assert!(
            (f - fractions_2d[n]).abs() < 1e-12,
            "{n}: {f} vs {}",
            fractions_2d[n]
        );
    }
    assert!((m3.basin_entropy - entropy_2d).abs() < 1e-12);
    // a nontrivial basin: the gait and a fall both occur
    let all = cells(&d3, 0..45);
    assert!(all.iter().any(|c| c.0 == "gait") && all.iter().any(|c| c.0.starts_with("fall")));
}

#[test]
fn a_3d_file_has_its_axes_and_the_drawn_slice() {
    let dir = tempfile::tempdir().unwrap();
    let f = compass_basin(
        dir.path(),
        "c.h5",
        "7x5x4",
        &["--z", Z, "--slice", "hip_rate=0.78"],
    );
    let h5 = h5_open(&f).unwrap();
    let shape = |n: &str| h5.dataset(n).unwrap().shape();
    assert_eq!(shape("basin/outcome"), vec![4, 5, 7]);
    assert_eq!(shape("basin/strides"), vec![4, 5, 7]);
    assert_eq!(shape("basin/final"), vec![4, 5, 7, 3]);
    assert_eq!(shape("basin/rows_done"), vec![20]);
    assert_eq!(shape("basin/block_digest"), vec![4]);
    let zd = h5.dataset("grid/z").unwrap();
    let zs = zd.read_raw::<f64>().unwrap();
    assert_eq!(zs.len(), 4);
    let name: hdf5::types::VarLenUnicode = zd.attr("name").unwrap().read_scalar().unwrap();
    assert_eq!(name.as_str(), "hip_rate");
    // --slice hip_rate=0.78: the nearest of 0.4, 0.6, 0.8, 1.0 is slice 2
    let g = h5.group("slice").unwrap();
    let k: u64 = g.attr("z_index").unwrap().read_scalar().unwrap();
    let v: f64 = g.attr("z_value").unwrap().read_scalar().unwrap();
    assert_eq!((k, v.to_bits()), (2, zs[2].to_bits()));
    let view = g.dataset("outcome").unwrap().read_2d::<u8>().unwrap();
    let all = h5
        .dataset("basin/outcome")
        .unwrap()
        .read_raw::<u8>()
        .unwrap();
    assert_eq!(
        view.iter().copied().collect::<Vec<_>>(),
        all[2 * 35..3 * 35]
    );
    // the PNG exists and is a PNG
    let png = std::fs::read(dir.path().join("c.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
}

#[test]
fn shards_of_a_3d_grid_merged_and_a_resumed_run_equal_a_single_run() {
    let dir = tempfile::tempdir().unwrap();
    // 20 rows per slice: two chunk blocks per slice, the second of 4 rows
    let grid = "5x20x3";
    let single = compass_basin(dir.path(), "single.h5", grid, &["--z", Z]);
    let mut shards = Vec::new();
    for i in 0..2 {
        let spec = format!("{i}/2");
        let name = format!("s{i}.h5");
        shards.push(compass_basin(
            dir.path(),
            &name,
            grid,
            &["--z", Z, "--shard", &spec],
        ));
    }
    let merged = dir.path().join("merged.h5");
    let o = run(&["merge", s(&shards[0]), s(&shards[1]), "--out", s(&merged)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (a, b) = (read(&single), read(&merged));
    assert_eq!(b.header.z, a.header.z);
    assert_eq!(cells(&a, 0..60), cells(&b, 0..60));
    let (ma, mb) = (a.metrics.clone().unwrap(), b.metrics.unwrap());
    assert_eq!(ma.fractions, mb.fractions);
    assert_eq!(ma.basin_entropy.to_bits(), mb.basin_entropy.to_bits());
    // an interrupted run (killed by SIGTERM after its 23rd row: mid-block of slice 1) resumed
    let out = dir.path().join("resumed.h5");
    let args = [
        "basin",
        "--model",
        "compass",
        "--x",
        X,
        "--y",
        Y,
        "--z",
        Z,
        "--grid",
        grid,
        "--max-strides",
        "60",
        "--quiet",
        "--out",
        s(&out),
    ];
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_pdw-sweep"))
        .args(args)
        .env("PDW_SWEEP_SIGNAL_AFTER_ROWS", "23")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    let partial = read(&out);
    assert!(!partial.complete);
    assert_eq!(partial.rows_done.iter().filter(|d| **d).count(), 23);
    let mut resumed: Vec<&str> = args.to_vec();
    resumed.push("--resume");
    let o = run(&resumed);
    assert!(o.status.success(), "{}", stderr(&o));
    let r = read(&out);
    assert!(r.complete);
    assert_eq!(cells(&a, 0..60), cells(&r, 0..60));
}

#[test]
fn bad_3d_requests_are_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bad.h5");
    let base = ["basin", "--model", "compass", "--quiet", "--out", s(&out)];
    let cases: [(&[&str], &str); 7] = [
        (
            &["--x", X, "--z", "stance=0.1:0.2", "--grid", "5x5x3"],
            "already the --x axis",
        ),
        (&["--z", Z, "--grid", "9x9"], "--z needs a 3-D grid"),
        (&["--grid", "9x9x5"], "no --z axis"),
        (&["--z", Z, "--grid", "9x9x5x2"], "NXxNY or NXxNYxNZ"),
        // 10⁹ rows of one cell: their bookkeeping alone exceeds any memory here
        (&["--z", Z, "--grid", "1x100000x10000"], "GiB of memory"),
        (
            &["--z", Z, "--grid", "5x5x3", "--slice", "z=2.5"],
            "outside the --z range",
        ),
        (
            &["--z", Z, "--grid", "5x5x3", "--slice", "stance=0.5"],
            "--z coordinate 'hip_rate'",
        ),
    ];
    for (extra, want) in cases {
        let mut args = base.to_vec();
        args.extend(extra);
        let o = run(&args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {e}");
        assert!(e.contains(want), "{extra:?}: {e}");
        assert!(!e.contains("panicked") && !e.contains("Some("), "{e}");
        assert!(!out.exists(), "{extra:?} wrote {}", out.display());
    }
}
