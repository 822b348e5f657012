//! `pdw-sweep mfpt`: the file holds exactly what the library computes, describes itself, and
//! the run's result does not depend on the thread count.

use pdw::limit::terrain::SlopeTerrain;
use pdw::mfpt::{self, MfptPlan};

use super::common::{h5_open, run, stderr};

/// The library's run of the same request.
fn library(walkers: usize, max_steps: usize) -> pdw::limit::terrain::MfptEstimate {
    let m = pdw::build("simplest", &[("slope".to_string(), 0.009)]).unwrap();
    let (x0, _) = mfpt::start(&m).unwrap();
    let plan = MfptPlan {
        terrain: SlopeTerrain {
            mean: 0.009,
            sd: 0.1f64.to_radians(),
            seed: 3,
            kind: pdw::limit::terrain::TerrainKind::Slope,
            dist: Default::default(),
        },
        walkers,
        max_strides: max_steps,
        integrator: mfpt::default_integrator(),
        stride_map: Default::default(),
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
            "--max-strides",
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
    let d = pdw::store::read_mfpt(&out).unwrap();
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
    let d1 = pdw::store::read_mfpt(&out1).unwrap();
    assert_eq!(
        (d1.mfpt.to_bits(), &d1.survival),
        (d.mfpt.to_bits(), &d.survival)
    );
}

/// Round feet walk on random step heights, not on random slopes (exit 2 naming `foot_radius`);
/// on step heights their chain at mid-stance lies at the legs together, and the file says so;
/// a negative `--sd` and an unknown terrain are refused.
#[test]
fn mfpt_takes_round_feet_on_both_terrains_and_refuses_a_negative_sd_clearly() {
    let o = run(&["mfpt", "--sd=-1deg", "--walkers", "2"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--sd"), "{}", stderr(&o));
    let o = run(&["mfpt", "--sd", "1deg", "--terrain", "height"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--terrain"), "{}", stderr(&o));
    let dir = tempfile::tempdir().unwrap();
    let text = pdw::walkers::registry::preset_text("compass").unwrap();
    let spec = dir.path().join("round.toml");
    std::fs::write(
        &spec,
        text.replacen("[parameters]", "foot_radius = 0.1\n\n[parameters]", 1),
    )
    .unwrap();
    let spec = spec.to_str().unwrap();
    // random slopes: the Monte Carlo walk on tilted landing lines; the chain refused, naming why
    let slopes = dir.path().join("slopes.h5");
    let o = run(&[
        "mfpt",
        "--model",
        spec,
        "--sd",
        "0.5deg",
        "--walkers",
        "100",
        "--seed",
        "1",
        "--quiet",
        "--out",
        slopes.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let d = pdw::store::read_mfpt(&slopes).unwrap();
    assert_eq!(d.terrain, "slope");
    assert!(d.falls > 50 && d.falls + d.censored == 100, "{}", d.falls);
    assert_eq!(d.mfpt, d.total_steps as f64 / d.falls as f64);
    let o = run(&[
        "mfpt",
        "--model",
        spec,
        "--sd",
        "0.2deg",
        "--walkers",
        "2",
        "--chain",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--chain") && stderr(&o).contains("foot_radius"),
        "{}",
        stderr(&o)
    );
    let out = dir.path().join("steps.h5");
    let o = run(&[
        "mfpt",
        "--model",
        spec,
        "--terrain",
        "step-down",
        "--sd",
        "0.004",
        "--walkers",
        "200",
        "--seed",
        "1",
        "--chain",
        "--chain-section",
        "mid-stance",
        "--mesh",
        "6",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let d = pdw::store::read_mfpt(&out).unwrap();
    assert_eq!(
        d.method,
        "monte carlo + markov chain on the mid-stance section at the legs together"
    );
    assert!(d.falls > 100, "{}", d.falls);
}

/// `mfpt --sd A:B:N` over the rimless wheel: each value of the curve is exactly the single run
/// at that standard deviation (same seed), the MFPT falls as the ground gets rougher (the
/// rimless wheel's closed-form step map loses more walkers per step to larger slope draws), and
/// the file and its PNG are written.
#[test]
fn an_mfpt_curve_is_the_single_runs_at_each_standard_deviation() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("curve.h5");
    let base = [
        "mfpt",
        "--model",
        "rimless",
        "--walkers",
        "200",
        "--max-strides",
        "5000",
        "--seed",
        "3",
        "--quiet",
    ];
    let mut args = base.to_vec();
    args.extend(["--sd", "0.4deg:0.6deg:3", "--out", out.to_str().unwrap()]);
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.with_extension("png").exists());
    let c = pdw::store::read_mfpt_curve(&out).unwrap();
    assert_eq!(c.sd.len(), 3);
    assert_eq!(c.sd[0], 0.4f64.to_radians());
    assert_eq!(c.sd[2], 0.6f64.to_radians());
    for (i, sd) in c.sd.iter().enumerate() {
        let single = dir.path().join(format!("s{i}.h5"));
        let sd_text = format!("{sd:?}");
        let mut args = base.to_vec();
        args.extend(["--sd", &sd_text, "--out", single.to_str().unwrap()]);
        let o = run(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let s = pdw::store::read_mfpt(&single).unwrap();
        assert_eq!(s.sd, *sd);
        assert_eq!(
            (s.total_steps, s.falls, s.censored),
            (c.total_steps[i], c.falls[i], c.censored[i])
        );
        assert_eq!(s.mfpt.to_bits(), c.mfpt[i].to_bits());
        assert!(c.chain_mfpt_coarse[i].is_nan(), "no chain was asked for");
    }
    assert!(
        c.mfpt[0] > c.mfpt[1] && c.mfpt[1] > c.mfpt[2],
        "MFPT must fall with the slope's spread: {:?}",
        c.mfpt
    );
    for (bad, says) in [
        ("1deg:0.5deg:3", "below the last"),
        ("0.5deg:1deg:1", "integer >= 2"),
        ("0.5deg:1deg", "neither"),
    ] {
        let mut args = base.to_vec();
        args.extend(["--sd", bad]);
        let o = run(&args);
        assert_eq!(o.status.code(), Some(2), "{bad}");
        assert!(stderr(&o).contains(says), "{bad}: {}", stderr(&o));
    }
}

/// `mfpt --terrain step-down`: the file says which terrain and in what unit, holds the
/// library's estimate at the model's `step_down` set by `--mean`, and a step beyond the rimless
/// wheel's reach is refused by name.
#[test]
fn a_step_down_mfpt_file_names_its_terrain_and_unit() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.h5");
    let o = run(&[
        "mfpt",
        "--model",
        "rimless",
        "--terrain",
        "step-down",
        "--mean",
        "0.001",
        "--sd",
        "0.01",
        "--walkers",
        "50",
        "--max-strides",
        "500",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let d = pdw::store::read_mfpt(&out).unwrap();
    assert_eq!(
        (d.terrain.as_str(), d.terrain_unit.as_str()),
        ("step-down", "m")
    );
    assert_eq!((d.mean, d.sd), (0.001, 0.01));
    let m = pdw::build("rimless", &[("step_down".to_string(), 0.001)]).unwrap();
    let (x0, _) = mfpt::start(&m).unwrap();
    let plan = MfptPlan {
        terrain: SlopeTerrain {
            mean: 0.001,
            sd: 0.01,
            seed: 0,
            kind: pdw::limit::terrain::TerrainKind::StepDown,
            dist: Default::default(),
        },
        walkers: 50,
        max_strides: 500,
        integrator: mfpt::default_integrator(),
        stride_map: Default::default(),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let e = mfpt::run(&m, &plan, &x0, &pool, &|_| {}).unwrap().1;
    assert_eq!(d.mfpt.to_bits(), e.mfpt.to_bits());
    assert!(d.params.contains("step_down"));
    let o = run(&[
        "mfpt",
        "--model",
        "rimless",
        "--terrain",
        "step-down",
        "--sd",
        "0.2",
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("reach"), "{}", stderr(&o));
    // The compass walks on step heights; a spread whose draws reach beyond its 1 m legs is
    // refused, naming the parameter.
    let o = run(&[
        "mfpt",
        "--model",
        "compass",
        "--terrain",
        "step-down",
        "--sd",
        "0.002",
        "--walkers",
        "20",
        "--max-strides",
        "30",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run(&[
        "mfpt",
        "--model",
        "compass",
        "--terrain",
        "step-down",
        "--sd",
        "0.2",
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("step_down"), "{}", stderr(&o));
}

/// `disturb`: the library's response printed, as text and as JSON, and the requests it refuses.
#[test]
fn disturb_prints_the_response_and_refuses_what_it_cannot_do() {
    let o = run(&[
        "disturb",
        "--model",
        "rimless",
        "--once",
        "-0.01",
        "--strides",
        "60",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    let m = pdw::build("rimless", &[]).unwrap();
    let r = pdw::disturb::respond(
        &m,
        pdw::limit::terrain::TerrainKind::StepDown,
        -0.01,
        60,
        mfpt::default_integrator(),
    )
    .unwrap();
    let k = r.returned_after.unwrap();
    assert!(
        text.contains(&format!("back within 1e-6 of the gait after {k} strides")),
        "{text}"
    );
    assert!(text.contains("walked all 60 strides"), "{text}");
    // --json: the same walk as one object (the old spelling --steps still counts strides)
    let o = run(&[
        "disturb", "--model", "rimless", "--once", "-0.01", "--steps", "60", "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["strides"], 60);
    assert_eq!(j["once"]["returned_after"], k);
    assert_eq!(j["once"]["fell"], false);
    let dev: Vec<f64> = serde_json::from_value(j["once"]["deviation"].clone()).unwrap();
    assert_eq!(dev, r.deviation);
    let o = run(&["disturb", "--model", "compass", "--once", "1.5"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("step_down"), "{}", stderr(&o));
    let o = run(&["disturb", "--model", "rimless"]);
    assert!(!o.status.success());
    // the strides walked are bounded (each is kept and integrated): 0, a million and one and the
    // largest count clap takes are refused with the bound named, before any model is built
    for strides in ["0", "1000001", "18446744073709551615"] {
        let o = run(&["disturb", "--once", "0", "--strides", strides]);
        assert_eq!(o.status.code(), Some(2), "{strides}");
        let e = stderr(&o);
        assert!(
            e.contains("--strides") && e.contains("outside 1..=1000000"),
            "{e}"
        );
    }
}

#[test]
fn a_uniform_mfpt_file_records_its_distribution_and_bad_names_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("u.h5");
    let o = run(&[
        "mfpt",
        "--model",
        "rimless",
        "--sd",
        "0.5deg",
        "--dist",
        "uniform",
        "--walkers",
        "40",
        "--max-strides",
        "200",
        "--seed",
        "2",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("draws uniform on [-sqrt 3, sqrt 3]"));
    let d = pdw::store::read_mfpt(&out).unwrap();
    assert!(d.distribution.starts_with("uniform"), "{}", d.distribution);
    // the library's walk on the same uniform draws
    let m = pdw::build("rimless", &[]).unwrap();
    let (x0, _) = pdw::mfpt::start(&m).unwrap();
    let plan = MfptPlan {
        terrain: SlopeTerrain {
            mean: d.mean,
            sd: 0.5f64.to_radians(),
            seed: 2,
            kind: pdw::limit::terrain::TerrainKind::Slope,
            dist: pdw::limit::terrain::TerrainDist::Uniform,
        },
        walkers: 40,
        max_strides: 200,
        integrator: pdw::mfpt::default_integrator(),
        stride_map: Default::default(),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let (_, e) = pdw::mfpt::run(&m, &plan, &x0, &pool, &|_| {}).unwrap();
    assert_eq!(d.survival, e.survival);
    let o = run(&["mfpt", "--sd", "1deg", "--dist", "cauchy"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--dist: 'cauchy' is not one of normal, uniform, file:PATH"),
        "{}",
        stderr(&o)
    );
}

/// `--chain --chain-section mid-stance`, on a grid and on a cloud (`--chain-mesh`): the file
/// names the section and the layout in its method and keeps the chain's numbers, which are the
/// library's mid-stance chain (the same box or cloud, the same meshes); a section that is not
/// one, a cloud on the other section, and a walker whose knee unlocks, are refused by flag.
#[test]
fn a_mid_stance_chain_file_names_its_section_and_holds_the_librarys_chain() {
    let m = pdw::build("rimless", &[]).unwrap();
    let (x0, _) = mfpt::start(&m).unwrap();
    let plan = MfptPlan {
        terrain: SlopeTerrain {
            mean: m.params.iter().find(|p| p.0 == "slope").unwrap().1,
            sd: 0.5f64.to_radians(),
            seed: 1,
            kind: pdw::limit::terrain::TerrainKind::Slope,
            dist: Default::default(),
        },
        walkers: 50,
        max_strides: 1000,
        integrator: mfpt::default_integrator(),
        stride_map: Default::default(),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    for (layout, method) in [
        (
            mfpt::ChainMesh::Grid,
            "monte carlo + markov chain on the mid-stance section",
        ),
        (
            mfpt::ChainMesh::Cloud,
            "monte carlo + markov chain on a cloud of the mid-stance section",
        ),
    ] {
        let out = dir.path().join(format!("{}.h5", layout.name()));
        let o = run(&[
            "mfpt",
            "--model",
            "rimless",
            "--sd",
            "0.5deg",
            "--walkers",
            "50",
            "--seed",
            "1",
            "--chain",
            "--chain-section",
            "mid-stance",
            "--chain-mesh",
            layout.name(),
            "--mesh",
            "50",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(text.contains("mid-stance section"), "{text}");
        let d = pdw::store::read_mfpt(&out).unwrap();
        assert_eq!(d.method, method);
        let get = |k: &str| d.chain.iter().find(|c| c.0 == k).map(|c| c.1);
        assert_eq!(get("mid_stance"), Some(1.0));
        let c = mfpt::ChainPlan {
            nodes: 11,
            mesh: 50,
            bounds: None,
            section: mfpt::ChainSection::MidStance,
            layout,
        };
        let pair = mfpt::chain_pair(&m, &plan, &c, &x0, &pool, &|_| {}).unwrap();
        assert_eq!(get("mfpt_coarse"), Some(pair.results[0].mfpt));
        assert_eq!(get("mfpt_fine"), Some(pair.results[1].mfpt));
        match &pair.clouds {
            Some([coarse, fine]) => {
                assert_eq!(get("cloud"), Some(1.0));
                assert_eq!(get("cloud_seeds_coarse"), Some(coarse.seeds as f64));
                assert_eq!(get("cloud_cell_fine"), Some(fine.cell));
                assert!(
                    text.contains(&format!("{} nodes after", fine.nodes)),
                    "{text}"
                );
            }
            None => assert_eq!(get("cloud"), None),
        }
    }
    let o = run(&["mfpt", "--sd", "1deg", "--chain", "--chain-mesh", "cloud"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--chain-mesh: a cloud is built on the mid-stance section only"),
        "{}",
        stderr(&o)
    );
    let o = run(&[
        "mfpt",
        "--sd",
        "1deg",
        "--chain",
        "--chain-section",
        "middle",
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--chain-section: 'middle' is not one of landing, mid-stance"),
        "{}",
        stderr(&o)
    );
    let o = run(&[
        "mfpt",
        "--model",
        "kneed",
        "--sd",
        "0.1deg",
        "--chain",
        "--chain-section",
        "mid-stance",
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("has 2 modes"), "{}", stderr(&o));
}

/// `--stride-map`: the rimless wheel walks in closed form by default and says so in the file's
/// provenance and its report; `integrated` walks the same walkers with the integrator (the same
/// fates here); a model without a closed form and an unknown name are refused.
#[test]
fn the_stride_map_is_chosen_recorded_and_refused_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let go = |map: &str, out: &std::path::Path| {
        let o = run(&[
            "mfpt",
            "--model",
            "rimless",
            "--sd",
            "2deg",
            "--set",
            "slope=8deg",
            "--walkers",
            "40",
            "--max-strides",
            "200",
            "--seed",
            "2",
            "--stride-map",
            map,
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{map}: {}", stderr(&o));
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        let f = h5_open(out).unwrap();
        let options = f
            .group("provenance")
            .unwrap()
            .attr("options")
            .unwrap()
            .read_scalar::<hdf5::types::VarLenUnicode>()
            .unwrap()
            .to_string();
        let v: serde_json::Value = serde_json::from_str(&options).unwrap();
        (
            text,
            v["stride_map"].clone(),
            pdw::store::read_mfpt(out).unwrap(),
        )
    };
    let (text, map, auto) = go("auto", &dir.path().join("a.h5"));
    assert!(text.contains("(closed form strides)"), "{text}");
    assert_eq!(map, "closed form");
    let (_, map, closed) = go("closed-form", &dir.path().join("c.h5"));
    assert_eq!(map, "closed form");
    assert_eq!(closed.survival, auto.survival);
    let (text, map, integrated) = go("integrated", &dir.path().join("i.h5"));
    assert!(text.contains("(integrated strides)"), "{text}");
    assert_eq!(map, "integrated");
    assert_eq!(integrated.survival, auto.survival);
    assert!(auto.falls > 0, "the test needs falls");

    for (args, says) in [
        (
            vec!["--model", "compass", "--stride-map", "closed-form"],
            "--stride-map: the model compass has no stride map in closed form",
        ),
        (
            vec!["--model", "rimless", "--stride-map", "exact"],
            "--stride-map: 'exact' is not one of auto, closed-form, integrated",
        ),
    ] {
        let mut a = vec!["mfpt", "--sd", "1deg", "--walkers", "2"];
        a.extend(args);
        let o = run(&a);
        assert_eq!(o.status.code(), Some(2), "{a:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(says), "{a:?}: {}", stderr(&o));
    }
}

/// On random step heights of mean 0 an odd `--nodes` puts a node at a step of exactly 0 (the
/// level-ground model): the CLI warns once, before the chain, on the grid and on the cloud,
/// and not for an even count.
#[test]
fn the_zero_height_node_warning_is_printed_once_and_only_for_an_odd_rule() {
    let chain = |nodes: &str, mesh: &str| {
        let o = run(&[
            "mfpt",
            "--model",
            "rimless",
            "--terrain",
            "step-down",
            "--sd",
            "0.005",
            "--walkers",
            "100",
            "--max-strides",
            "200",
            "--seed",
            "1",
            "--chain",
            "--chain-section",
            if mesh == "cloud" {
                "mid-stance"
            } else {
                "landing"
            },
            "--chain-mesh",
            mesh,
            "--nodes",
            nodes,
            "--quiet",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let out = String::from_utf8_lossy(&o.stdout).to_string();
        let warned = out.matches("at a step height of exactly 0").count();
        let before = out
            .find("at a step height of exactly 0")
            .zip(out.find("Markov chain"))
            .is_some_and(|(w, c)| w < c);
        (warned, before, out)
    };
    for mesh in ["grid", "cloud"] {
        let (warned, before, out) = chain("5", mesh);
        assert_eq!(warned, 1, "{mesh}: {out}");
        assert!(
            before,
            "{mesh}: the warning comes before the chain's lines: {out}"
        );
        let (warned, _, out) = chain("6", mesh);
        assert_eq!(warned, 0, "{mesh}: {out}");
    }
}

/// An MFPT estimate of 4000 walkers with mean `mean`, standard error `se` and `censored` walkers
/// censored.
fn est(mean: f64, se: f64, censored: usize) -> pdw::limit::terrain::MfptEstimate {
    pdw::limit::terrain::MfptEstimate {
        walkers: 4000,
        falls: 4000 - censored,
        censored,
        total_steps: 42_906,
        mfpt: mean,
        stderr: se,
        restricted_mean: mean,
        restricted_stderr: se,
        survival: Vec::new(),
        failures: Vec::new(),
    }
}

/// A chain's MFPTs on its two meshes as the `mfpt` file keeps them.
fn chain(coarse: f64, fine: f64) -> Vec<(String, f64)> {
    vec![
        ("mfpt_coarse".to_string(), coarse),
        ("mfpt_fine".to_string(), fine),
    ]
}

/// The warning `pdw-sweep mfpt` prints when its chain and its walkers disagree.
fn agreement_warning(
    chain: &[(String, f64)],
    est: &pdw::limit::terrain::MfptEstimate,
) -> Option<String> {
    mfpt::chain_agreement_warning(chain, est, "--nodes")
}

/// The simplest walker on step heights (docs/cli.md): 11.2061 / 11.2818 against
/// 10.7265 ± 0.1122 is 4.9 standard errors, the refinement 0.08 — warned; within 3 standard
/// errors plus the refinement, with censored walkers, or without a chain — silent.
#[test]
fn the_chain_is_flagged_where_it_and_the_walkers_disagree_beyond_its_refinement() {
    let w = agreement_warning(&chain(11.2061, 11.2818), &est(10.7265, 0.1122, 0)).unwrap();
    assert!(
        w.starts_with("WARNING") && w.contains("4.9 standard errors"),
        "{w}"
    );
    assert!(w.contains("--nodes"), "{w}");
    // within 3 standard errors
    assert!(agreement_warning(&chain(11.2, 11.05), &est(10.7265, 0.1122, 0)).is_none());
    // beyond them, but the refinement moved the chain as much
    assert!(agreement_warning(&chain(12.2, 11.28), &est(10.7265, 0.1122, 0)).is_none());
    // censored walkers: the restricted mean is not the MFPT
    assert!(agreement_warning(&chain(11.2, 11.28), &est(10.7265, 0.1122, 3)).is_none());
    assert!(agreement_warning(&[], &est(10.7265, 0.1122, 0)).is_none());
}

/// `--chain` on a grid reports its quadrature check and keeps it in the file; at the default 11
/// nodes the rimless wheel's chain (mesh 200) is not converged in its terrain quadrature and the
/// warning names the `--nodes` to try (the verdict is checked against a converged closed-form
/// chain in crates/pdw/tests/rimless_chain.rs); with `--nodes 40` (checked against 80) it passes
/// and nothing warns.
#[test]
fn the_chain_checks_its_quadrature_and_names_the_nodes_that_converge() {
    let dir = tempfile::tempdir().unwrap();
    for (nodes, warns) in [(None, true), (Some("40"), false)] {
        let out = dir.path().join(format!("q{}.h5", nodes.unwrap_or("11")));
        let mut args = vec![
            "mfpt",
            "--model",
            "rimless",
            "--sd",
            "0.5deg",
            "--walkers",
            "200",
            "--chain",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ];
        if let Some(n) = nodes {
            args.extend(["--nodes", n]);
        }
        let o = run(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = String::from_utf8_lossy(&o.stdout);
        let doubled = if warns { "22" } else { "80" };
        assert!(
            text.contains(&format!(
                "quadrature check: mesh 200 with --nodes {doubled}:"
            )),
            "{text}"
        );
        let warning = text
            .lines()
            .find(|l| l.contains("the terrain's quadrature is not converged"));
        assert_eq!(warning.is_some(), warns, "{text}");
        if let Some(w) = warning {
            assert!(w.contains("give --nodes 22 or more"), "{w}");
        }
        let f = h5_open(&out).unwrap();
        let g = f.group("mfpt").unwrap();
        let get = |k: &str| g.attr(k).unwrap().read_scalar::<f64>().unwrap();
        assert_eq!(
            get("chain_quadrature_nodes"),
            doubled.parse::<f64>().unwrap()
        );
        let change = get("chain_quadrature_change");
        assert_eq!(change > mfpt::QUADRATURE_MAX, warns, "{change}");
        assert!(get("chain_quadrature_mfpt").is_finite());
    }
}

/// The flags that count strides say so: `mfpt --max-strides` and `animate --strides`. Their old
/// spellings (`--max-steps`, `--steps`) still parse, as hidden aliases: the same run, the same
/// message naming the new flag, and `--help` shows only the new spelling.
#[test]
fn old_spellings_of_the_stride_flags_still_parse_and_are_hidden() {
    let go = |flag: &str, n: &str| {
        run(&[
            "mfpt",
            "--model",
            "simplest",
            "--slope",
            "0.009",
            "--sd",
            "0.1deg",
            "--walkers",
            "6",
            flag,
            n,
            "--seed",
            "1",
            "--quiet",
        ])
    };
    let (new, old) = (go("--max-strides", "20"), go("--max-steps", "20"));
    assert!(new.status.success(), "{}", stderr(&new));
    assert!(old.status.success(), "{}", stderr(&old));
    // the same run: every line but the one timing it
    let lines = |o: &std::process::Output| {
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .filter(|l| !l.contains("walkers/s"))
            .map(String::from)
            .collect::<Vec<_>>()
    };
    assert_eq!(lines(&new), lines(&old));
    for flag in ["--max-strides", "--max-steps"] {
        let o = go(flag, "0");
        assert_eq!(o.status.code(), Some(2), "{flag}");
        assert!(
            stderr(&o).contains("--max-strides: 0 must be an integer >= 1"),
            "{flag}: {}",
            stderr(&o)
        );
    }
    let help = String::from_utf8_lossy(&run(&["mfpt", "--help"]).stdout).into_owned();
    assert!(
        help.contains("--max-strides") && !help.contains("--max-steps"),
        "{help}"
    );
    let help = String::from_utf8_lossy(&run(&["animate", "--help"]).stdout).into_owned();
    assert!(
        help.contains("--strides") && !help.contains("--steps"),
        "{help}"
    );
}
