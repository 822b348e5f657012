//! The thesis design (its gait flagged: the knees would unlock) against the design an earlier
//! `pdw-sweep design` search found (`models/seed5_walking.toml`), whose stance knee buckles at
//! the knee strike under a hyper-extension stop: it is followed here with its knees latched
//! (`hold = "latch"`, holding both ways), the model that search used, so that its stride can be
//! compared at all. Knee torques and ground reaction over one stride of each gait. Writes
//! `experiments/results/seed5_design/` (charts, `stride.md`). The redesign under stop knees is
//! `seed5_redesign`.

use pdw_experiments::{results_dir, write_text, Table};
use pdw_hybrid::Options;
use pdw_limit::{find_fixed_point, simulate, NewtonOptions, StrideMap, TrajectoryOptions};
use pdw_walkers::{ChainWalker, Walker, WalkerSpec};

/// `models/seed5_walking.toml` with every knee latched (its stop model buckles at the knee
/// strike and has no gait).
fn walking_latched() -> anyhow::Result<ChainWalker> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/seed5_walking.toml");
    let mut spec = WalkerSpec::from_file(std::path::Path::new(path))?;
    for k in &mut spec.knees {
        k.hold = Some("latch".into());
    }
    Ok(ChainWalker::from_spec(spec)?)
}

/// One stride of the model's first gait, sampled every 5 ms: `(t/T, columns…)`.
fn stride(w: &dyn Walker) -> anyhow::Result<(Vec<f64>, pdw_limit::Trajectory, f64)> {
    let g = w.gait_guesses().into_iter().next().expect("a gait guess");
    let map = StrideMap::new(w, Options::dop853(1e-13))?;
    let fp = find_fixed_point(&map, &g.section, &NewtonOptions::default())?;
    let mut o = TrajectoryOptions::new(1);
    o.dt_out = Some(0.005);
    let tr = simulate(w, &fp.state, &o)?;
    let period = fp.metrics.period;
    Ok((tr.t.iter().map(|t| t / period).collect(), tr, period))
}

fn main() -> anyhow::Result<()> {
    let dir = results_dir("seed5_design")?;
    let thesis = pdw_walkers::build("seed5", &[])?;
    let new = walking_latched()?;
    let mut table = Table::new(&[
        "design",
        "period (s)",
        "min stance-knee torque (N m)",
        "min swing-knee torque, locked (N m)",
        "normal force (N)",
        "max friction needed",
    ]);
    let mut knee = Vec::new();
    let mut grf = Vec::new();
    for (name, w) in [
        ("thesis (both knees locked, γ = 0.05)", thesis.as_ref()),
        (
            "seed5_walking, knees latched (not valid: stops would pull at the impacts)",
            &new as &dyn Walker,
        ),
    ] {
        let (s, tr, period) = stride(w)?;
        let f = tr.forces.as_ref().expect("forces");
        let col = |k: usize| -> Vec<(f64, f64)> {
            s.iter()
                .zip(f.knee_torque.chunks(2))
                .filter(|(_, kt)| kt[k].is_finite())
                .map(|(t, kt)| (*t, kt[k]))
                .collect()
        };
        let (st, sw) = (col(0), col(1));
        let min = |v: &[(f64, f64)]| v.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        let nmin = f.normal.iter().copied().fold(f64::INFINITY, f64::min);
        let nmax = f.normal.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let fric = f.friction_required.iter().copied().fold(0.0, f64::max);
        table.row(vec![
            name.to_string(),
            format!("{period:.4}"),
            format!("{:.3}", min(&st)),
            format!("{:.3}", min(&sw)),
            format!("{nmin:.1} – {nmax:.1}"),
            format!("{fric:.3}"),
        ]);
        let short = if name.starts_with("thesis") {
            "thesis"
        } else {
            "walking"
        };
        knee.push((format!("{short}: stance knee"), st));
        knee.push((format!("{short}: swing knee (locked)"), sw));
        grf.push((
            format!("{short}: normal"),
            s.iter().zip(&f.normal).map(|(t, v)| (*t, *v)).collect(),
        ));
        grf.push((
            format!("{short}: tangential"),
            s.iter().zip(&f.tangential).map(|(t, v)| (*t, *v)).collect(),
        ));
    }
    pdw_store::plot_lines(
        dir.join("knee_torque.png"),
        "knee-lock torque over one stride (a passive stop needs > 0)",
        "t / T",
        "N m",
        &knee,
        false,
        false,
    )?;
    pdw_store::plot_lines(
        dir.join("ground_reaction.png"),
        "stance-foot ground reaction over one stride",
        "t / T",
        "N",
        &grf,
        false,
        false,
    )?;
    write_text(&dir, "stride.md", &table.markdown())?;
    print!("{}", table.markdown());
    Ok(())
}
