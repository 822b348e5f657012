//! Each file the CLI writes holds exactly what its declared format
//! ([`pdw::store::format`]) lists: every group, dataset and attribute in the file is declared,
//! every item declared as always present is there, and every dataset carries its `units`.

use crate::common::run;
use pdw::store::format::{
    inventory, Format, Unit, BASIN, CURVE, DESIGN, MFPT, MFPT_CURVE, STABILITY, SWEEP, TRAJECTORY,
};
use std::path::Path;

fn ok(args: &[&str]) {
    let o = run(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// The file at `p` against `f`: nothing undeclared, nothing declared missing, a `units`
/// attribute on every dataset whose item has a unit.
fn holds_exactly(p: &Path, f: &Format) -> Vec<String> {
    let present = inventory(p).unwrap();
    let m = f.check(&present);
    assert!(m.is_empty(), "{} ({}): {m:?}", p.display(), f.name);
    for item in present.iter().filter(|i| !i.contains('@')) {
        let declared = f.find(item).unwrap();
        if declared.unit != Unit::None {
            assert!(
                present.contains(&format!("{item}@units")),
                "{}: {item} has no units",
                p.display()
            );
        }
    }
    present
}

#[test]
fn basin_files_2d_and_3d_hold_exactly_the_declared_basin_items() {
    let dir = tempfile::tempdir().unwrap();
    let two = dir.path().join("b2.h5");
    let three = dir.path().join("b3.h5");
    ok(&[
        "basin",
        "--model",
        "compass",
        "--grid",
        "16x16",
        "--quiet",
        "--out",
        two.to_str().unwrap(),
    ]);
    ok(&[
        "basin",
        "--model",
        "kneed",
        "--grid",
        "8x8x3",
        "--z",
        "hip_rate=-0.5:0.5",
        "--quiet",
        "--out",
        three.to_str().unwrap(),
    ]);
    holds_exactly(&two, &BASIN);
    let items = holds_exactly(&three, &BASIN);
    for only_3d in ["grid/z", "slice/outcome", "slice@z_index"] {
        assert!(
            items.iter().any(|i| i == only_3d),
            "{only_3d} in the 3-D file"
        );
    }
}

#[test]
fn mfpt_and_design_files_hold_exactly_their_declared_items() {
    let dir = tempfile::tempdir().unwrap();
    let mfpt = dir.path().join("mfpt.h5");
    ok(&[
        "mfpt",
        "--model",
        "simplest",
        "--slope",
        "0.009",
        "--terrain",
        "slope",
        "--sd",
        "0.1deg",
        "--walkers",
        "20",
        "--max-steps",
        "20",
        "--out",
        mfpt.to_str().unwrap(),
    ]);
    holds_exactly(&mfpt, &MFPT);
    let design = dir.path().join("design.h5");
    let o = run(&[
        "design",
        "--model",
        "compass",
        "--free",
        "hip_mass=8:12",
        "--objective",
        "margin",
        "--budget",
        "3",
        "--quiet",
        "--out",
        design.to_str().unwrap(),
    ]);
    assert!(
        matches!(o.status.code(), Some(0 | 1)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    holds_exactly(&design, &DESIGN);
}

#[test]
fn sweep_files_hold_exactly_the_declared_sweep_items() {
    let dir = tempfile::tempdir().unwrap();
    let bif = dir.path().join("bif.h5");
    ok(&[
        "fixedpoint",
        "--sweep",
        "slope=0.005:0.012:4",
        "--out",
        bif.to_str().unwrap(),
    ]);
    let items = holds_exactly(&bif, &SWEEP);
    assert!(items.iter().any(|i| i == "orbit/points@units"));
}

#[test]
fn trajectory_files_hold_exactly_the_declared_trajectory_items() {
    let dir = tempfile::tempdir().unwrap();
    let traj = dir.path().join("traj.h5");
    ok(&[
        "simulate",
        "--model",
        "compass",
        "--steps",
        "2",
        "--out",
        traj.to_str().unwrap(),
    ]);
    let items = holds_exactly(&traj, &TRAJECTORY);
    assert!(items.iter().any(|i| i == "events/pre@units"));
}

#[test]
fn curve_and_basin_stability_files_hold_exactly_their_declared_items() {
    let dir = tempfile::tempdir().unwrap();
    let curve = dir.path().join("pd.h5");
    ok(&[
        "fixedpoint",
        "--model",
        "compass",
        "--follow",
        "pd",
        "--sweep",
        "hip_mass=8:12:3",
        "--free",
        "slope",
        "--map-grid",
        "3x3",
        "--png",
        dir.path().join("pd.png").to_str().unwrap(),
        "--quiet",
        "--out",
        curve.to_str().unwrap(),
    ]);
    let items = holds_exactly(&curve, &CURVE);
    assert!(items.iter().any(|i| i == "map/region@legend"));
    let over = dir.path().join("over.h5");
    ok(&[
        "basin",
        "--over",
        "slope=0.009:0.011:2",
        "--grid",
        "8x8",
        "--quiet",
        "--out",
        over.to_str().unwrap(),
    ]);
    let items = holds_exactly(&over, &STABILITY);
    assert!(items.iter().any(|i| i == "values/001@attractors"));
}

#[test]
fn mfpt_curve_files_hold_exactly_the_declared_items() {
    let dir = tempfile::tempdir().unwrap();
    let curve = dir.path().join("curve.h5");
    ok(&[
        "mfpt",
        "--model",
        "simplest",
        "--slope",
        "0.009",
        "--sd",
        "0.05deg:0.1deg:2",
        "--walkers",
        "20",
        "--max-strides",
        "20",
        "--out",
        curve.to_str().unwrap(),
    ]);
    holds_exactly(&curve, &MFPT_CURVE);
}
