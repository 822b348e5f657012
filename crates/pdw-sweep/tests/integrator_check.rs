//! Every command that integrates warns, the same way, when its integrator cannot resolve a
//! stride: the gait found on the accurate stride map does not come back after one stride of
//! the run's integrator (`pdw::integrator::check_integrator`).

use crate::common::{run, stderr};

const WARNING: &str = "cannot resolve a stride";

#[test]
fn a_loose_integrator_draws_the_warning_in_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.h5");
    let out = out.to_str().unwrap();
    for args in [
        // the cases: an MFPT of 1 step and a fall on flat deterministic ground
        &["mfpt", "--sd", "0", "--rtol", "1", "--walkers", "4"][..],
        &[
            "mfpt",
            "--sd",
            "0",
            "--integrator",
            "rk4",
            "--rk4-step",
            "1.5",
            "--walkers",
            "4",
        ][..],
        &["disturb", "--once", "0", "--rtol", "1", "--steps", "5"][..],
        &["fixedpoint", "--rtol", "1"][..],
        &["simulate", "--rtol", "1", "--steps", "2", "--out", out],
    ] {
        let o = run(args);
        let e = stderr(&o);
        assert_eq!(e.matches(WARNING).count(), 1, "{args:?}: {e}");
        assert!(e.contains("warning: with "), "{args:?}: {e}");
    }
}

#[test]
fn the_default_integrators_do_not_warn() {
    for args in [
        &["mfpt", "--sd", "0", "--walkers", "4"][..],
        &["disturb", "--once", "0", "--steps", "5"][..],
        &["mfpt", "--sd", "0", "--rtol", "1e-10", "--walkers", "4"][..],
    ] {
        let o = run(args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains(WARNING), "{args:?}: {}", stderr(&o));
    }
}
