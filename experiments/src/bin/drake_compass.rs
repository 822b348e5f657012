//! The compass gait against Drake: reads `results/drake_compass/drake.json` (written by
//! `experiments/drake_compass.py`, which runs `pydrake.examples.CompassGait` with its default
//! parameters at several simulator accuracies), computes the same gait with pdw-sweep at Drake's
//! slope, and puts fixed point, period, multipliers and time per stride side by side.
//!
//! Coordinates: pdw-sweep's section `(q₁, q̇₁, q̇₂)`; the Python script converts Drake's
//! `(stance, swing, stancedot, swingdot)` (absolute angles from the vertical) with
//! `q₁ = γ − stance`, `q̇₁ = −stancedot`, `q̇₂ = stancedot − swingdot`.

use anyhow::Context;
use pdw_experiments::{
    command, fmt_multipliers, max_abs_diff, multiplier_error, results_dir, sci, time_mean,
    write_text, Table,
};
use pdw_hybrid::{Integrator, Options};
use pdw_limit::{find_fixed_point, Multiplier, NewtonOptions, StrideMap};
use std::fmt::Write as _;

fn main() -> anyhow::Result<()> {
    faer::set_global_parallelism(faer::Par::Seq);
    let dir = results_dir("drake_compass")?;
    let text = std::fs::read_to_string(dir.join("drake.json"))
        .context("run `python3 experiments/drake_compass.py` first")?;
    let json: serde_json::Value = serde_json::from_str(&text)?;
    let runs = json["runs"].as_array().context("runs")?;
    let p = &runs[0]["params"];
    let f = |k: &str| p[k].as_f64().context(k.to_string());
    let slope = f("slope")?;
    let (mh, m, l, com, g) = (
        f("mass_hip")?,
        f("mass_leg")?,
        f("length_leg")?,
        f("center_of_mass_leg")?,
        f("gravity")?,
    );
    // Drake's center_of_mass_leg is measured from the hip: b = com, a = l − com.
    let w = pdw_walkers::build(
        "compass",
        &[
            ("slope", slope),
            ("hip_mass", mh),
            ("leg_mass", m),
            ("a", l - com),
            ("b", com),
            ("gravity", g),
        ],
    )?;
    let guess = w.gait_guesses()[0].section.clone();
    let map = StrideMap::new(w.as_ref(), Options::dop853(1e-14))?;
    let fp = find_fixed_point(
        &map,
        &guess,
        &NewtonOptions {
            tol: 1e-13,
            ..NewtonOptions::default()
        },
    )?;
    eprintln!(
        "ours: s* = {:?}, period {}, λ = {}",
        fp.section,
        fp.metrics.period,
        fmt_multipliers(&fp.multipliers, 12)
    );
    // Our time per stride at several tolerances (one stride from the fixed point).
    let mut ours_t = Vec::new();
    for tol in [1e-6, 1e-8, 1e-10, 1e-12, 1e-14] {
        let m = StrideMap::new(w.as_ref(), Options::dop853(tol))?;
        let mut integ = Integrator::new(4, Options::dop853(tol))?;
        let (st, t) = time_mean(0.3, || m.stride_with(&mut integ, &fp.section));
        let st = st?;
        ours_t.push((tol, t, max_abs_diff(&st.next, &fp.section)));
    }
    // One fixed-point solve as the CLI does it (DOP853 1e-14, variational multipliers).
    let (_, t_fp) = time_mean(0.5, || {
        find_fixed_point(&map, &guess, &NewtonOptions::default())
    });

    let mut md = String::new();
    let _ = writeln!(md, "# Compass gait: pdw-sweep against Drake\n");
    let _ = writeln!(
        md,
        "Reproduce: `python3 experiments/drake_compass.py && {}`.\n",
        command("drake_compass")
    );
    let _ = writeln!(
        md,
        "Drake: `pydrake.examples.CompassGait` with its default parameters (m_H = {mh}, m = {m}, \
         l = {l}, leg COM {com} from the hip, g = {g}, slope {slope} rad = {:.4}° — Drake's \
         default slope is 0.0525 rad, not exactly 3°), simulated by its `Simulator` with the \
         error-controlled RK5 integrator; steady state by 60 simulated strides, then Newton on \
         Drake's own stride map (central differences); multipliers = eigenvalues of a \
         central-difference Jacobian of Drake's stride map. pdw-sweep: DOP853 1e-14, Newton to \
         1e-13, variational multipliers.\n",
        slope.to_degrees()
    );
    let _ = writeln!(
        md,
        "pdw-sweep: s* = ({:.13}, {:.13}, {:.13}), period {:.13} s, multipliers {}; one \
         fixed-point solve (Newton + verification + variational DP) {:.2} ms.\n",
        fp.section[0],
        fp.section[1],
        fp.section[2],
        fp.metrics.period,
        fmt_multipliers(&fp.multipliers, 10),
        t_fp * 1e3
    );
    let mut t = Table::new(&[
        "Drake accuracy",
        "Drake s*",
        "Drake period (s)",
        "|Δs*|∞",
        "|Δperiod|",
        "Drake Newton residual",
        "Drake ms/stride (plain simulation)",
        "Drake ms/stride (stride map, Python monitor)",
    ]);
    let mut tm = Table::new(&["Drake accuracy", "FD step", "Drake multipliers", "max |Δλ|"]);
    let mut series_fp = Vec::new();
    let mut series_lam = Vec::new();
    for r in runs {
        let acc = r["accuracy"].as_f64().context("accuracy")?;
        let s: Vec<f64> = r["fixed_point"]
            .as_array()
            .context("fixed_point")?
            .iter()
            .filter_map(|v| v.as_f64())
            .collect();
        let period = r["period"].as_f64().context("period")?;
        let spp = r["seconds_per_stride_plain_simulation"]
            .as_f64()
            .context("seconds_per_stride_plain_simulation")?;
        let spm = r["seconds_per_stride_stride_map"]
            .as_f64()
            .context("seconds_per_stride_stride_map")?;
        let res = r["newton_residuals"]
            .as_array()
            .and_then(|a| a.last())
            .and_then(|v| v.as_f64())
            .unwrap_or(f64::NAN);
        let dfp = max_abs_diff(&s, &fp.section);
        let dper = (period - fp.metrics.period).abs();
        t.row(vec![
            format!("{acc:.0e}"),
            format!("({:.11}, {:.11}, {:.11})", s[0], s[1], s[2]),
            format!("{period:.12}"),
            sci(dfp),
            sci(dper),
            sci(res),
            format!("{:.3}", spp * 1e3),
            format!("{:.2}", spm * 1e3),
        ]);
        series_fp.push((acc, dfp.max(dper)));
        let mut best = f64::INFINITY;
        for (h, lam) in r["multipliers_fd"].as_object().context("mults")? {
            let ml: Vec<Multiplier> = lam
                .as_array()
                .context("lam")?
                .iter()
                .map(|z| Multiplier {
                    re: z[0].as_f64().unwrap_or(f64::NAN),
                    im: z[1].as_f64().unwrap_or(f64::NAN),
                })
                .collect();
            let e = multiplier_error(&ml, &fp.multipliers);
            best = best.min(e);
            tm.row(vec![
                format!("{acc:.0e}"),
                h.clone(),
                fmt_multipliers(&ml, 8),
                sci(e),
            ]);
        }
        series_lam.push((acc, best));
    }
    let _ = writeln!(md, "## Fixed point and period\n\n{}", t.markdown());
    let _ = writeln!(
        md,
        "## Multipliers (Drake: finite differences of its stride map)\n\n{}",
        tm.markdown()
    );
    let mut to = Table::new(&["pdw-sweep DOP853 tol", "µs per stride", "|P(s*) − s*|∞"]);
    for (tol, tt, e) in &ours_t {
        to.row(vec![
            format!("{tol:.0e}"),
            format!("{:.1}", tt * 1e6),
            sci(*e),
        ]);
    }
    let _ = writeln!(
        md,
        "## pdw-sweep time per stride (scalar, one thread)\n\n{}",
        to.markdown()
    );
    pdw_store::plot_lines(
        dir.join("agreement.png"),
        "Compass gait, Drake vs pdw-sweep: difference against Drake's accuracy setting",
        "Drake simulator accuracy",
        "difference",
        &[
            ("fixed point and period (max)".to_string(), series_fp),
            ("multipliers (best FD step)".to_string(), series_lam),
        ],
        true,
        true,
    )?;
    let _ = writeln!(md, "![agreement](agreement.png)\n");
    write_text(&dir, "table.md", &md)?;
    Ok(())
}
