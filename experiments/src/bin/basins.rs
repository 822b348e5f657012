//! Basins of attraction of the stable period-one gait: the simplest walker (Garcia et al. 1998)
//! at several slopes, the compass gait (Goswami et al. 1998) at 3° and the kneed walker (Hsu Chen
//! 2007 preset), each on a grid around its stable fixed point.
//!
//! Window: each axis spans the fixed-point coordinate ± 25 % of its value (at least ± 0.05), as
//! `pdw-sweep basin` does by default; the third section coordinate (compass and kneed: the hip
//! rate) is held at its fixed-point value. Each cell is iterated by the stride map (DOP853 at
//! 1e-9, the engine's default) until it is classified: `gait` (within 1e-6 of s* on two
//! consecutive strides), a fall, another periodic attractor, or `timeout`.
//!
//! Basin entropy S_b and boundary basin entropy S_bb follow Daza et al. (2016, Sci. Rep. 6,
//! 31416, eq. 3–4), on boxes of 5 × 5 cells, natural log. Because the window is scaled with the
//! fixed point, the fractions compare basins in each slope's own natural units.

use pdw_experiments::{command, fmt_multipliers, results_dir, time_once, write_text, Table};
use pdw_hybrid::Options;
use pdw_limit::basin::DEFAULT_ENTROPY_BOX;
use pdw_limit::{
    basin_metrics, classify_cells, find_fixed_point, grid_cells, legend, linspace, BasinOptions,
    BasinProblem, FixedPoint, NewtonOptions, Outcome, StrideMap,
};
use pdw_walkers::Walker;
use std::fmt::Write as _;

const NAME: &str = "basins";
/// Slopes with a PNG each (rad).
const PNG_SLOPES: [f64; 5] = [0.004, 0.007, 0.009, 0.012, 0.015];
/// Slopes of the fraction / entropy chart (rad).
const CHART_SLOPES: [f64; 14] = [
    0.002, 0.003, 0.004, 0.005, 0.006, 0.007, 0.008, 0.009, 0.010, 0.011, 0.012, 0.013, 0.014,
    0.015,
];

/// The stable period-one gait among the model's guesses (Newton to 1e-12, DOP853 at 1e-14).
fn stable_gait(w: &dyn Walker) -> anyhow::Result<Option<FixedPoint>> {
    let map = StrideMap::new(w, Options::dop853(1e-14))?;
    let no = NewtonOptions {
        tol: 1e-12,
        ..NewtonOptions::default()
    };
    for g in w.gait_guesses() {
        if let Ok(fp) = find_fixed_point(&map, &g.section, &no) {
            if fp.stable {
                return Ok(Some(fp));
            }
        }
    }
    Ok(None)
}

/// `centre ± max(0.25 |centre|, 0.05)` (the `pdw-sweep basin` default window).
fn window(centre: f64, n: usize) -> Vec<f64> {
    let half = (0.25 * centre.abs()).max(0.05);
    linspace(centre - half, centre + half, n)
}

/// One basin computation and its numbers.
struct Run {
    max_strides: u16,
    label: String,
    slope: f64,
    fp: FixedPoint,
    n: usize,
    labels: Vec<u8>,
    xs: Vec<f64>,
    ys: Vec<f64>,
    secs: f64,
    gait: f64,
    fractions: String,
    s_b: f64,
    s_bb: f64,
}

fn run(
    model: &str,
    label: &str,
    slope: f64,
    n: usize,
    max_strides: u16,
    pool: &rayon::ThreadPool,
) -> anyhow::Result<Option<Run>> {
    let w = pdw_walkers::build(model, &[("slope", slope)])?;
    let Some(fp) = stable_gait(w.as_ref())? else {
        eprintln!("{label}: no stable period-one gait");
        return Ok(None);
    };
    // A stride budget that lets a 0.1 perturbation shrink to 1e-6 twice over at the gait's
    // slowest rate |λ|max (needed near the period doubling, where λ → −1).
    let lmax = fp
        .multipliers
        .iter()
        .map(|m| m.modulus())
        .fold(0.0, f64::max);
    let needed = 2.0 * (1e-5f64).ln() / lmax.ln();
    let max_strides = if needed.is_finite() {
        max_strides.max(needed.ceil().min(2000.0) as u16)
    } else {
        max_strides
    };
    let s = &fp.section;
    let xs = window(s[0], n);
    let ys = window(s[1], n);
    let fall = Outcome::of_fall;
    let problem = BasinProblem::new(w.as_ref(), s.clone(), &fall);
    let cells = grid_cells(s, 0, &xs, 1, &ys);
    let bo = BasinOptions {
        max_strides,
        ..BasinOptions::default()
    };
    let (res, secs) = time_once(|| classify_cells(&problem, &cells, &bo, pool, &|_| {}));
    let labels: Vec<u8> = res?.iter().map(|c| c.outcome).collect();
    let m = basin_metrics(&labels, n, n, DEFAULT_ENTROPY_BOX)?;
    let gait = m
        .fractions
        .iter()
        .find(|f| f.0 == Outcome::Gait.code())
        .map_or(0.0, |f| f.2);
    let fractions = m
        .fractions
        .iter()
        .filter(|f| f.2 > 0.0)
        .map(|f| format!("{} {:.4}", f.1, f.2))
        .collect::<Vec<_>>()
        .join(", ");
    eprintln!(
        "{label}: {n}×{n} in {secs:.2} s, gait {gait:.4}, S_b {:.4}, S_bb {:.4}",
        m.basin_entropy, m.boundary_entropy
    );
    Ok(Some(Run {
        max_strides,
        label: label.to_string(),
        slope,
        fp,
        n,
        labels,
        xs,
        ys,
        secs,
        gait,
        fractions,
        s_b: m.basin_entropy,
        s_bb: m.boundary_entropy,
    }))
}

fn png(
    dir: &std::path::Path,
    file: &str,
    model: &str,
    names: [&str; 2],
    state_names: &[&str],
    r: &Run,
) -> anyhow::Result<()> {
    let s = &r.fp.section;
    let max_strides = r.max_strides;
    let header = pdw_store::BasinHeader {
        command: command(NAME),
        model: model.into(),
        slope: r.slope,
        params: "{}".into(),
        model_resolved: String::new(),
        integrator: "dop853".into(),
        tolerances: "{\"rtol\":1e-9,\"atol\":1e-9}".into(),
        max_strides: u32::from(max_strides),
        x_name: names[0].into(),
        x: r.xs.clone(),
        y_name: names[1].into(),
        y: r.ys.clone(),
        z: None,
        state_names: state_names.iter().map(|s| s.to_string()).collect(),
        legend: legend()
            .into_iter()
            .map(|(c, nm)| (c, nm.to_string()))
            .collect(),
        shard: None,
    };
    let arr = ndarray::Array2::from_shape_vec((r.n, r.n), r.labels.clone())?;
    let extra = if s.len() > 2 {
        format!(", hip_rate = {:.4}", s[2])
    } else {
        String::new()
    };
    pdw_store::plot_basin(
        dir.join(file),
        &header,
        arr.view(),
        Some((s[0], s[1])),
        &format!(
            "{}, slope {:.4} rad, {} strides{extra}",
            r.label, r.slope, max_strides
        ),
    )?;
    Ok(())
}

fn main() -> anyhow::Result<()> {
    faer::set_global_parallelism(faer::Par::Seq);
    let dir = results_dir(NAME)?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    let n = 150;
    let strides = 100;
    let mut runs: Vec<(Run, Option<String>)> = Vec::new();

    // ---- simplest walker against the slope ----
    let mut chart = vec![
        ("gait fraction".to_string(), Vec::new()),
        ("basin entropy S_b".to_string(), Vec::new()),
        ("boundary entropy S_bb".to_string(), Vec::new()),
    ];
    for &g in &CHART_SLOPES {
        let Some(r) = run("simplest", "simplest walker", g, n, strides, &pool)? else {
            continue;
        };
        chart[0].1.push((g, r.gait));
        chart[1].1.push((g, r.s_b));
        chart[2].1.push((g, r.s_bb));
        let file = if PNG_SLOPES.iter().any(|p| (p - g).abs() < 1e-12) {
            let f = format!("simplest_{:03}.png", (g * 1000.0).round() as i64);
            png(
                &dir,
                &f,
                "simplest",
                ["theta", "thetadot"],
                &["theta", "thetadot"],
                &r,
            )?;
            Some(f)
        } else {
            None
        };
        runs.push((r, file));
    }
    pdw_store::plot_lines(
        dir.join("simplest_vs_slope.png"),
        "Simplest walker: basin fraction and basin entropy vs slope (150×150, ±25 % window)",
        "slope γ (rad)",
        "fraction  |  entropy (nats)",
        &chart,
        false,
        false,
    )?;

    // ---- compass gait at 3° and the kneed walker (Hsu Chen preset) ----
    let three = [
        ("compass", "compass gait", 3f64.to_radians(), "compass.png"),
        ("kneed", "kneed walker (Hsu Chen)", 0.0504, "kneed.png"),
    ];
    for (model, label, g, file) in three {
        if let Some(r) = run(model, label, g, n, strides, &pool)? {
            png(
                &dir,
                file,
                model,
                ["stance", "stance_rate"],
                &["stance", "stance_rate", "hip_rate"],
                &r,
            )?;
            runs.push((r, Some(file.to_string())));
        }
    }

    // ---- table ----
    let mut t = Table::new(&[
        "model",
        "slope (rad)",
        "s*",
        "multipliers",
        "grid",
        "max strides",
        "gait fraction",
        "gait area (rad²/s)",
        "all outcomes",
        "S_b",
        "S_bb",
        "time (s)",
        "cells/s",
    ]);
    let mut total = 0.0;
    for (r, _) in &runs {
        total += r.secs;
        t.row(vec![
            r.label.clone(),
            format!("{:.4}", r.slope),
            format!(
                "({})",
                r.fp.section
                    .iter()
                    .map(|x| format!("{x:.5}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            fmt_multipliers(&r.fp.multipliers, 3),
            format!("{}×{}", r.n, r.n),
            r.max_strides.to_string(),
            format!("{:.4}", r.gait),
            format!(
                "{:.2e}",
                r.gait * (r.xs[r.n - 1] - r.xs[0]).abs() * (r.ys[r.n - 1] - r.ys[0]).abs()
            ),
            r.fractions.clone(),
            format!("{:.4}", r.s_b),
            format!("{:.4}", r.s_bb),
            format!("{:.2}", r.secs),
            format!("{:.0}", (r.n * r.n) as f64 / r.secs),
        ]);
    }
    write_text(&dir, "basins.csv", &t.csv().replace(", ", ";"))?;
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Basins of attraction\n\nReproduce: `{}`. 2 threads, DOP853 1e-9, at least {strides} strides per \
         cell (more where |λ|max is close to 1: 2 ln(1e-5)/ln|λ|max), window s* ± 25 % per axis, entropy boxes {DEFAULT_ENTROPY_BOX}×{DEFAULT_ENTROPY_BOX}. \
         Classification time total {total:.1} s.\n",
        command(NAME)
    );
    let _ = writeln!(md, "{}", t.markdown());
    for (r, f) in &runs {
        if let Some(f) = f {
            let _ = writeln!(md, "![{} γ = {:.4}]({f})", r.label, r.slope);
        }
    }
    let _ = writeln!(md, "\n![vs slope](simplest_vs_slope.png)");
    write_text(&dir, "table.md", &md)?;
    Ok(())
}
