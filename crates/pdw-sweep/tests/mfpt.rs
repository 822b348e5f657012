//! `pdw-sweep mfpt`: the file holds exactly what the library computes, describes itself, and
//! the run's result does not depend on the thread count.

use pdw::mfpt::{self, MfptPlan};
use pdw_limit::terrain::SlopeTerrain;

use super::common::{h5_open, run, stderr};

/// The library's run of the same request.
fn library(walkers: usize, max_steps: usize) -> pdw_limit::terrain::MfptEstimate {
    let m = pdw::build("simplest", &[("slope".to_string(), 0.009)]).unwrap();
    let (x0, _) = mfpt::start(&m).unwrap();
    let plan = MfptPlan {
        terrain: SlopeTerrain {
            mean: 0.009,
            sd: 0.1f64.to_radians(),
            seed: 3,
        },
        walkers,
        max_steps,
        integrator: mfpt::default_integrator(),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    mfpt::run(&m, &plan, &x0, &pool, &|_| {}).unwrap().1
}

#[test]
fn the_mfpt_file_holds_the_library_estimate_with_units_and_provenance() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.h5");
    let args = |threads: &str, out: &str| {
        run(&[
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
            "30",
            "--max-steps",
            "50",
            "--seed",
            "3",
            "--threads",
            threads,
            "--quiet",
            "--out",
            out,
        ])
    };
    let o = args("2", out.to_str().unwrap());
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(text.contains("MFPT") || text.contains("no fall"), "{text}");
    let d = pdw_store::read_mfpt(&out).unwrap();
    let e = library(30, 50);
    assert_eq!(d.mfpt.to_bits(), e.mfpt.to_bits());
    assert_eq!(d.survival, e.survival);
    assert_eq!((d.falls, d.censored), (e.falls as u64, e.censored as u64));
    assert_eq!(d.walkers, 30);
    assert_eq!((d.mean, d.sd, d.seed), (0.009, 0.1f64.to_radians(), 3));
    assert_eq!(d.method, "monte carlo");
    assert!(out.with_extension("png").is_file());
    let f = h5_open(&out).unwrap();
    for ds in ["mfpt/survival", "mfpt/failures", "mfpt/start"] {
        let units = f.dataset(ds).unwrap().attr("units");
        assert!(units.is_ok(), "{ds} has no units");
    }
    let prov = f.group("provenance").unwrap();
    assert!(prov.attr("options").is_ok() && prov.attr("commands").is_ok());
    // one thread: the same file contents (the walk is a pure function of seed, walker, step)
    let out1 = dir.path().join("m1.h5");
    let o = args("1", out1.to_str().unwrap());
    assert!(o.status.success(), "{}", stderr(&o));
    let d1 = pdw_store::read_mfpt(&out1).unwrap();
    assert_eq!(
        (d1.mfpt.to_bits(), &d1.survival),
        (d.mfpt.to_bits(), &d.survival)
    );
}

#[test]
fn mfpt_refuses_round_feet_and_a_negative_sd_clearly() {
    let o = run(&["mfpt", "--sd=-1deg", "--walkers", "2"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--sd"), "{}", stderr(&o));
    let o = run(&["mfpt", "--sd", "1deg", "--terrain", "height"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--terrain"), "{}", stderr(&o));
}
