//! `pdw-sweep mfpt --sd A:B:N`: the MFPT against the terrain's disturbance — one Monte Carlo
//! run per standard deviation (the same seed, so every walker meets the same standard normals
//! scaled by each σ: common random numbers make the curve smooth), with `--chain` the Markov
//! chain at each σ too; a table, an HDF5 file and a PNG on a logarithmic MFPT axis.

use super::basin::progress_bar;
use super::mfpt::{chain_plan, run_chain, ESTIMATOR};
use super::output::Claim;
use crate::cli::MfptArgs;
use pdw::limit::terrain::{MfptEstimate, SlopeTerrain, TerrainKind};
use pdw::mfpt::{self, MfptPlan};
use pdw::BuiltModel;
use std::process::ExitCode;
use std::time::Instant;

/// One standard deviation's results: the Monte Carlo estimate and the chain's MFPT at the
/// coarse and the fine mesh (NaN without the chain).
struct Row {
    sd: f64,
    est: MfptEstimate,
    chain: [f64; 2],
}

/// The curve over `sds` for the model `m` and the plan `plan` (its `sd` replaced by each).
pub(super) fn run(
    a: &MfptArgs,
    m: &BuiltModel,
    plan: &MfptPlan,
    sds: &[f64],
    claim: Option<Claim>,
) -> anyhow::Result<ExitCode> {
    let (x0, section) = mfpt::start(m)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads)
        .build()?;
    let chain = chain_plan(a, m)?;
    let pb = progress_bar(
        a.quiet,
        (a.walkers * sds.len()) as u64,
        "{elapsed_precise} [{wide_bar}] {pos}/{len} walkers  {per_sec}  ETA {eta}",
    );
    let t0 = Instant::now();
    let mut rows = Vec::with_capacity(sds.len());
    for (i, &sd) in sds.iter().enumerate() {
        let p = MfptPlan {
            terrain: SlopeTerrain {
                sd,
                ..plan.terrain.clone()
            },
            ..plan.clone()
        };
        let done = (i * a.walkers) as u64;
        let (_, est) = mfpt::run(m, &p, &x0, &pool, &|n| pb.set_position(done + n as u64))?;
        let chain = match &chain {
            Some(c) => {
                let numbers = pb.suspend(|| run_chain(m, &p, c, &x0, &pool, a.quiet))?;
                let get = |k: &str| numbers.iter().find(|e| e.0 == k).map_or(f64::NAN, |e| e.1);
                [get("mfpt_coarse"), get("mfpt_fine")]
            }
            None => [f64::NAN; 2],
        };
        rows.push(Row { sd, est, chain });
    }
    pb.finish_and_clear();
    table(m, plan, &section, &rows, t0.elapsed().as_secs_f64());
    if let (Some(out), Some(_claim)) = (&a.out, claim) {
        let mesh = chain.map_or([0, 0], |c| [c.mesh as u64, 2 * c.mesh as u64]);
        write(out, m, plan, &rows, mesh)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The curve as a table: σ, the MFPT with its standard error, falls and censored walkers, the
/// chain's two meshes.
fn table(m: &BuiltModel, plan: &MfptPlan, section: &[f64], rows: &[Row], secs: f64) {
    let t = &plan.terrain;
    let (mean, unit2, scale2) = match t.kind {
        TerrainKind::Slope => (
            format!(
                "terrain slope: mean {} rad ({:.4}°)",
                t.mean,
                t.mean.to_degrees()
            ),
            "sd (deg)".to_string(),
            1f64.to_degrees(),
        ),
        TerrainKind::StepDown => {
            let u = super::mfpt::terrain_unit(m, t.kind);
            (
                format!("terrain step-down: mean {} {u}", t.mean),
                format!("sd ({u})"),
                1.0,
            )
        }
    };
    crate::outln!(
        "model {}  {mean}, seed {}, draws {}; {} walkers per value, at most {} steps; start: \
         stable gait ({})",
        m.info.name,
        t.seed,
        mfpt::dist_words(&t.dist),
        plan.walkers,
        plan.max_strides,
        section
            .iter()
            .map(|v| format!("{v:.6}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    crate::outln!(
        "{:>10} {:>10} {:>22} {:>8} {:>9} {:>14} {:>14}",
        "sd (rad)",
        unit2,
        "MFPT ± stderr (steps)",
        "falls",
        "censored",
        "chain coarse",
        "chain fine"
    );
    for r in rows {
        let mfpt = if r.est.falls == 0 {
            format!("> {} (no fall)", (r.est.total_steps / 3).saturating_sub(1))
        } else {
            format!("{:.3} ± {:.3}", r.est.mfpt, r.est.stderr)
        };
        crate::outln!(
            "{:>10.6} {:>10.4} {:>22} {:>8} {:>9} {:>14.3} {:>14.3}",
            r.sd,
            r.sd * scale2,
            mfpt,
            r.est.falls,
            r.est.censored,
            r.chain[0],
            r.chain[1]
        );
    }
    crate::outln!("{secs:.1} s");
}

/// The HDF5 file ([`pdw::store::MfptCurveData`], with provenance) and its PNG: MFPT against σ
/// (degrees) on a logarithmic MFPT axis, the Monte Carlo and, where it ran, the chain.
fn write(
    out: &std::path::Path,
    m: &BuiltModel,
    plan: &MfptPlan,
    rows: &[Row],
    mesh: [u64; 2],
) -> anyhow::Result<()> {
    let unit = super::mfpt::terrain_unit(m, plan.terrain.kind);
    let col = |f: &dyn Fn(&Row) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    let cnt = |f: &dyn Fn(&Row) -> u64| rows.iter().map(f).collect::<Vec<u64>>();
    let data = pdw::store::MfptCurveData {
        command: super::command_line(),
        model: m.info.name.clone(),
        params: m.params_json().to_string(),
        terrain: plan.terrain.kind.name().into(),
        distribution: mfpt::dist_words(&plan.terrain.dist),
        terrain_unit: unit.clone(),
        mean: plan.terrain.mean,
        seed: plan.terrain.seed,
        walkers: plan.walkers as u64,
        max_steps: plan.max_strides as u64,
        estimator: ESTIMATOR.into(),
        chain_mesh: mesh,
        sd: col(&|r| r.sd),
        mfpt: col(&|r| r.est.mfpt),
        stderr: col(&|r| r.est.stderr),
        restricted_mean: col(&|r| r.est.restricted_mean),
        chain_mfpt_coarse: col(&|r| r.chain[0]),
        chain_mfpt_fine: col(&|r| r.chain[1]),
        falls: cnt(&|r| r.est.falls as u64),
        censored: cnt(&|r| r.est.censored as u64),
        total_steps: cnt(&|r| r.est.total_steps),
    };
    // the claim refused an existing file without --force; its placeholder is replaced
    pdw::store::write_mfpt_curve(out, true, &data)?;
    let prov = super::mfpt::provenance(m, plan);
    let coordinates = m.coordinates_json();
    pdw::store::annotate(
        out,
        &pdw::store::Annotations {
            provenance: Some(&prov),
            units: &|p: &str| match p {
                "curve/sd" => Some(unit.clone()),
                "curve/falls" | "curve/censored" => Some("walkers".into()),
                "curve/mfpt"
                | "curve/stderr"
                | "curve/restricted_mean"
                | "curve/total_steps"
                | "curve/chain_mfpt_coarse"
                | "curve/chain_mfpt_fine" => Some("steps".into()),
                _ => None,
            },
            slice: None,
            scales: &[],
            coordinates: Some(&coordinates),
        },
    )?;
    // slopes in degrees on the axis, heights as they are
    let axis = |sd: f64| match plan.terrain.kind {
        TerrainKind::Slope => sd.to_degrees(),
        TerrainKind::StepDown => sd,
    };
    let series = |name: String, ys: &[f64]| {
        let pts = rows.iter().zip(ys).map(|(r, y)| (axis(r.sd), *y)).collect();
        (name, pts)
    };
    let mut lines = vec![series("Monte Carlo".into(), &data.mfpt)];
    if mesh[0] > 0 {
        lines.push(series(
            format!("chain, mesh {}", mesh[0]),
            &data.chain_mfpt_coarse,
        ));
        lines.push(series(
            format!("chain, mesh {}", mesh[1]),
            &data.chain_mfpt_fine,
        ));
    }
    let (title, xlabel) = match plan.terrain.kind {
        TerrainKind::Slope => (
            format!(
                "{}: mean first-passage time on random slopes, mean {:.3}°",
                m.info.name,
                plan.terrain.mean.to_degrees()
            ),
            "slope standard deviation (deg)".to_string(),
        ),
        TerrainKind::StepDown => (
            format!(
                "{}: mean first-passage time on random step heights, mean {} {unit}",
                m.info.name, plan.terrain.mean
            ),
            format!("step-down standard deviation ({unit})"),
        ),
    };
    pdw::store::plot_lines(
        &pdw::mfpt::output_files(out, false)[1].path,
        &title,
        &xlabel,
        "MFPT (steps before a fall)",
        &lines,
        false,
        true,
    )?;
    Ok(())
}
