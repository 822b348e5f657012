//! Two-parameter maps of the validity region around the shipped seed5 design
//! (`models/seed5_walking.toml`): on a grid of two design parameters, the period-one gait is
//! followed from the design's own gait (each cell starts Newton from its already computed
//! neighbours' gaits, then from the model's guesses) and classified by the same evaluation the
//! design search uses (`pdw_limit::design::evaluate_design`, knee margin 0.1 N m, μ = 0.6):
//!
//! - `gait`: stable and valid along the whole stride;
//! - `knee unlocks`: a locked knee would need a negative (pulling) stop torque — the knee-unlock
//!   boundary;
//! - `invalid (other)`: normal force, friction, scuffing or no knee strike;
//! - `unstable: period doubling`: the largest multiplier is real and < −1 (the PD boundary);
//! - `unstable: fold / Neimark–Sacker`: a real multiplier > 1 or a complex pair outside the unit
//!   circle;
//! - `no gait (fall)`: Newton finds no period-one gait from any start (beyond a fold, or no
//!   convergence — the map cannot tell them apart; the message of each cell is in the CSV).
//!
//! The boundaries between the regions are the maps' content: a grid of fixed points, not a
//! two-parameter continuation of the bifurcation curves.

use std::fmt::Write as _;

use anyhow::Context;
use ndarray::Array2;
use pdw_experiments::{command, results_dir, write_text};
use pdw_limit::design::{evaluate_design, status, DesignOptions, Objective};
use pdw_limit::BasinOptions;
use pdw_walkers::registry::model_info;

const MODEL: &str = "models/seed5_walking.toml";

struct Map {
    file: &'static str,
    x: (&'static str, f64, f64),
    y: (&'static str, f64, f64),
}

const NAMES: [&str; 6] = [
    "gait",
    "knee unlocks",
    "invalid (other)",
    "unstable: period doubling",
    "unstable: fold / Neimark-Sacker",
    "no gait (fall)",
];

fn main() -> anyhow::Result<()> {
    let dir = results_dir("seed5_design")?;
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let model = root.join(MODEL);
    let model = model.to_str().context("model path")?.to_string();
    let info = model_info(&model)?;
    let base = info.build(&[])?;
    let n = 21;
    let maps = [
        Map {
            file: "map_slope_hip_mass",
            x: ("slope", 0.02, 0.07),
            y: ("hip_mass", 2.0, 12.0),
        },
        Map {
            file: "map_thigh_cn_shank_cn",
            x: ("thigh_cn", -0.02, 0.08),
            y: ("shank_cn", -0.16, 0.0),
        },
    ];
    let opts = DesignOptions {
        objective: Objective::Margin,
        mu: 0.6,
        knee_margin: 0.1,
        budget: 1,
        seed: 0,
        start: None,
        init: 0,
        basin_grid: 3,
        basin_box: [0.02, 0.08],
        basin: BasinOptions::default(),
        newton_tol: 1e-10,
    };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    let model_guesses = pdw_limit::gaits::model_guesses(base.as_ref());
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Validity maps around the shipped design\n\nReproduce: `{}` (grids of {n}×{n} \
         fixed points; a few minutes on 2 cores). Centre: `{MODEL}` (marked ⊗).\n",
        command("seed5_design_map")
    );
    for m in &maps {
        let xs = pdw_limit::linspace(m.x.1, m.x.2, n);
        let ys = pdw_limit::linspace(m.y.1, m.y.2, n);
        let mut code = Array2::<u8>::zeros((n, n));
        let mut gaits: Vec<Vec<Option<[f64; 3]>>> = vec![vec![None; n]; n];
        let mut csv = format!("{},{},region,rho,min_knee_torque,reason\n", m.x.0, m.y.0);
        // Row by row from the row nearest the design, each row outwards from its centre, so that
        // every cell has a computed neighbour to start from.
        let centre = |v: &[f64], c: f64| {
            (0..v.len())
                .min_by(|&a, &b| (v[a] - c).abs().total_cmp(&(v[b] - c).abs()))
                .unwrap_or(0)
        };
        let value = |name: &str| {
            base.param_values()
                .iter()
                .find(|p| p.0 == name)
                .map_or(f64::NAN, |p| p.1)
        };
        let (cx, cy) = (centre(&xs, value(m.x.0)), centre(&ys, value(m.y.0)));
        let order = |c: usize| {
            let mut o = vec![c];
            for d in 1..n {
                if c + d < n {
                    o.push(c + d);
                }
                if d <= c {
                    o.push(c - d);
                }
            }
            o
        };
        for &iy in &order(cy) {
            for &ix in &order(cx) {
                let mut guesses: Vec<(String, Vec<f64>)> = Vec::new();
                for (dx, dy) in [(0i32, 1i32), (0, -1), (1, 0), (-1, 0)] {
                    let (jx, jy) = (ix as i32 + dx, iy as i32 + dy);
                    if jx >= 0 && jy >= 0 && (jx as usize) < n && (jy as usize) < n {
                        if let Some(s) = gaits[jy as usize][jx as usize] {
                            guesses.push(("neighbour".into(), s.to_vec()));
                        }
                    }
                }
                guesses.extend(model_guesses.iter().cloned());
                let set = [(m.x.0, xs[ix]), (m.y.0, ys[iy])];
                let (c, ev_rho, torque, reason) = match info.build(&set) {
                    Err(e) => (5u8, f64::NAN, f64::NAN, format!("not a model: {e}")),
                    Ok(w) => {
                        let ev =
                            evaluate_design(&[xs[ix], ys[iy]], w.as_ref(), &guesses, &opts, &pool);
                        if ev.section.iter().all(|v| v.is_finite()) {
                            gaits[iy][ix] = Some(ev.section);
                        }
                        let c = match ev.status {
                            status::FEASIBLE => 0,
                            status::INVALID
                                if ev.reason.contains("knee") && ev.reason.contains("torque") =>
                            {
                                1
                            }
                            status::INVALID => 2,
                            status::UNSTABLE => {
                                // The kind of instability from the gait's multipliers.
                                let map = pdw_limit::StrideMap::new(
                                    w.as_ref(),
                                    pdw_limit::gaits::default_integrator(1e-10),
                                )?;
                                let pd = pdw_limit::find_fixed_point(
                                    &map,
                                    &ev.section,
                                    &pdw_limit::NewtonOptions::default(),
                                )
                                .ok()
                                .and_then(|fp| fp.multipliers.first().copied())
                                .is_some_and(|l| l.im == 0.0 && l.re < -1.0);
                                if pd {
                                    3
                                } else {
                                    4
                                }
                            }
                            _ => 5,
                        };
                        (c, ev.rho, ev.min_knee_torque, ev.reason)
                    }
                };
                code[[iy, ix]] = c;
                let _ = writeln!(
                    csv,
                    "{},{},{},{},{},\"{}\"",
                    xs[ix],
                    ys[iy],
                    NAMES[c as usize],
                    ev_rho,
                    torque,
                    reason.replace('"', "'")
                );
            }
            eprintln!("{}: row {iy} done", m.file);
        }
        write_text(&dir, &format!("{}.csv", m.file), &csv)?;
        let header = pdw_store::BasinHeader {
            command: command("seed5_design_map"),
            model: "seed5_walking".into(),
            slope: value("slope"),
            params: String::new(),
            integrator: String::new(),
            tolerances: String::new(),
            max_strides: 1,
            x_name: m.x.0.into(),
            x: xs.clone(),
            y_name: m.y.0.into(),
            y: ys.clone(),
            state_names: vec![m.x.0.into(), m.y.0.into()],
            legend: NAMES
                .iter()
                .enumerate()
                .map(|(c, s)| (c as u8, s.to_string()))
                .collect(),
            shard: None,
        };
        pdw_store::plot_basin(
            dir.join(format!("{}.png", m.file)),
            &header,
            code.view(),
            Some((value(m.x.0), value(m.y.0))),
            &format!("seed5_walking: regions in ({}, {})", m.x.0, m.y.0),
        )?;
        let counts: Vec<String> = (0..NAMES.len())
            .map(|c| {
                format!(
                    "{}: {}",
                    NAMES[c],
                    code.iter().filter(|&&v| v as usize == c).count()
                )
            })
            .collect();
        let _ = writeln!(
            md,
            "## {x} × {y}\n\n![{f}]({f}.png)\n\nCells ({n}×{n}): {c}. Per cell (region, largest \
             |λ|, smallest knee-lock torque, reason): [{f}.csv]({f}.csv).\n",
            x = m.x.0,
            y = m.y.0,
            f = m.file,
            c = counts.join(", ")
        );
    }
    write_text(&dir, "maps.md", &md)?;
    print!("{md}");
    Ok(())
}
