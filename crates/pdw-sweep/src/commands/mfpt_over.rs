//! `pdw-sweep mfpt --over PARAM=A:B:N`: the MFPT and the gait sensitivity norm over a model
//! parameter ([`pdw::mfpt_over`]): a table, an HDF5 file, a PNG of the MFPT against the
//! parameter (log axis) and a PNG of the MFPT against the GSN with their rank correlation.

use super::basin::progress_bar;
use super::mfpt::{chain_plan, run_chain, ESTIMATOR};
use super::output::Claim;
use crate::args::InputError;
use crate::cli::MfptArgs;
use pdw::limit::gsn::Indicator;
use pdw::mfpt::{MfptFlags, MfptPlan};
use pdw::mfpt_over::{self, OverRow};
use pdw::ModelChoice;
use std::process::ExitCode;
use std::time::Instant;

/// The run over the values of `over` (`NAME=A:B:N`), `plan` giving the walkers, steps, seed
/// and standard deviation.
pub(super) fn run(
    a: &MfptArgs,
    choice: &ModelChoice,
    plan: &MfptPlan,
    flags: &MfptFlags,
    claim: Option<Claim>,
) -> anyhow::Result<ExitCode> {
    let Some(over) = &a.over else {
        return Ok(ExitCode::SUCCESS);
    };
    if a.sd.contains(':') {
        return Err(
            InputError("--over with --sd A:B:N: give one standard deviation".into()).into(),
        );
    }
    let sw = pdw::input::parse_range_count(over, "--over")?;
    let ind = Indicator::DEFAULT;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads)
        .build()?;
    let values = mfpt_over::values(&sw);
    let pb = progress_bar(
        a.quiet,
        (a.walkers * values.len()) as u64,
        "{elapsed_precise} [{wide_bar}] {pos}/{len} walkers  {per_sec}  ETA {eta}",
    );
    let t0 = Instant::now();
    let mut rows = Vec::with_capacity(values.len());
    let mut first = None;
    for (i, &v) in values.iter().enumerate() {
        let m = mfpt_over::model_at_value(choice, &sw.name, v)?;
        let p = mfpt_over::plan_at(&m, plan, flags)?;
        let done = (i * a.walkers) as u64;
        let (mut row, x0) = mfpt_over::row(&m, v, &p, &ind, &pool, &|n| {
            pb.set_position(done + n as u64)
        })?;
        if let (Some(c), Some(x0)) = (chain_plan(a, &m)?, x0) {
            let numbers = pb.suspend(|| run_chain(&m, &p, &c, &x0, &pool, a.quiet))?;
            let get = |k: &str| numbers.iter().find(|e| e.0 == k).map_or(f64::NAN, |e| e.1);
            row.chain = [get("mfpt_coarse"), get("mfpt_fine")];
        }
        rows.push(row);
        first.get_or_insert(m);
    }
    pb.finish_and_clear();
    let gsn: Vec<f64> = rows.iter().map(|r| r.gsn).collect();
    let mf: Vec<f64> = rows.iter().map(mfpt_of).collect();
    let rho = mfpt_over::spearman(&gsn, &mf);
    table(&sw.name, plan, &rows, rho, t0.elapsed().as_secs_f64());
    if let (Some(out), Some(_claim), Some(m)) = (&a.out, claim, first) {
        let mesh = chain_plan(a, &m)?.map_or([0, 0], |c| [c.mesh as u64, 2 * c.mesh as u64]);
        write(out, &m, &sw.name, plan, &rows, mesh, rho)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The Monte Carlo MFPT of a row (NaN without a run).
fn mfpt_of(r: &OverRow) -> f64 {
    r.est.as_ref().map_or(f64::NAN, |e| e.mfpt)
}

/// The table: value, mean slope, MFPT ± stderr, falls, the chain, the GSN (or why none).
fn table(name: &str, plan: &MfptPlan, rows: &[OverRow], rho: f64, secs: f64) {
    let t = &plan.terrain;
    crate::outln!(
        "mfpt over {name}: terrain slope sd {} rad ({:.4}°), seed {}, draws {}; {} walkers per \
         value, at most {} steps; gait sensitivity norm of step time and step length per rad",
        t.sd,
        t.sd.to_degrees(),
        t.seed,
        pdw::mfpt::dist_words(&t.dist),
        plan.walkers,
        plan.max_strides
    );
    crate::outln!(
        "{:>12} {:>10} {:>24} {:>7} {:>9} {:>12} {:>12} {:>12}",
        name,
        "mean (rad)",
        "MFPT ± stderr (steps)",
        "falls",
        "censored",
        "chain",
        "chain fine",
        "GSN"
    );
    for r in rows {
        let Some(e) = &r.est else {
            crate::outln!(
                "{:>12.6} {:>10.6}   {}",
                r.value,
                r.mean,
                r.note.as_deref().unwrap_or("")
            );
            continue;
        };
        let mfpt = if e.falls == 0 {
            format!("> {} (no fall)", (e.total_steps / 3).saturating_sub(1))
        } else {
            format!("{:.4e} ± {:.2e}", e.mfpt, e.stderr)
        };
        crate::outln!(
            "{:>12.6} {:>10.6} {:>24} {:>7} {:>9} {:>12.4e} {:>12.4e} {:>12.5}{}",
            r.value,
            r.mean,
            mfpt,
            e.falls,
            e.censored,
            r.chain[0],
            r.chain[1],
            r.gsn,
            r.note
                .as_ref()
                .map(|n| format!("  ({n})"))
                .unwrap_or_default()
        );
    }
    crate::outln!(
        "Spearman rank correlation of GSN and MFPT: {rho:.4} (over the values with both)"
    );
    crate::outln!("{secs:.1} s");
}

/// The HDF5 file ([`pdw::store::MfptOverData`], with provenance) and its two PNGs.
fn write(
    out: &std::path::Path,
    m: &pdw::BuiltModel,
    name: &str,
    plan: &MfptPlan,
    rows: &[OverRow],
    mesh: [u64; 2],
    rho: f64,
) -> anyhow::Result<()> {
    let col = |f: &dyn Fn(&OverRow) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    let est = |f: &dyn Fn(&pdw::limit::terrain::MfptEstimate) -> u64| {
        rows.iter()
            .map(|r| r.est.as_ref().map_or(0, f))
            .collect::<Vec<u64>>()
    };
    let estf = |f: &dyn Fn(&pdw::limit::terrain::MfptEstimate) -> f64| {
        rows.iter()
            .map(|r| r.est.as_ref().map_or(f64::NAN, f))
            .collect::<Vec<f64>>()
    };
    let data = pdw::store::MfptOverData {
        command: super::command_line(),
        model: m.info.name.clone(),
        params: m.params_json().to_string(),
        param: name.to_string(),
        terrain: "slope".into(),
        distribution: pdw::mfpt::dist_words(&plan.terrain.dist),
        sd: plan.terrain.sd,
        seed: plan.terrain.seed,
        walkers: plan.walkers as u64,
        max_steps: plan.max_strides as u64,
        estimator: ESTIMATOR.into(),
        indicators: "step-time,step-length".into(),
        chain_mesh: mesh,
        spearman: rho,
        values: col(&|r| r.value),
        mean: col(&|r| r.mean),
        mfpt: estf(&|e| e.mfpt),
        stderr: estf(&|e| e.stderr),
        restricted_mean: estf(&|e| e.restricted_mean),
        chain_mfpt_coarse: col(&|r| r.chain[0]),
        chain_mfpt_fine: col(&|r| r.chain[1]),
        gsn: col(&|r| r.gsn),
        stable: rows.iter().map(|r| u64::from(r.gait.is_some())).collect(),
        falls: est(&|e| e.falls as u64),
        censored: est(&|e| e.censored as u64),
        total_steps: est(&|e| e.total_steps),
    };
    pdw::store::write_mfpt_over(out, true, &data)?;
    annotate(out, m, plan)?;
    plots(out, m, name, &data)
}

/// Provenance, units and coordinates of the file.
fn annotate(out: &std::path::Path, m: &pdw::BuiltModel, plan: &MfptPlan) -> anyhow::Result<()> {
    let prov = super::mfpt::provenance(m, plan);
    let coordinates = m.coordinates_json();
    pdw::store::annotate(
        out,
        &pdw::store::Annotations {
            provenance: Some(&prov),
            units: &|p: &str| match p {
                "over/mean" => Some("rad".into()),
                "over/falls" | "over/censored" => Some("walkers".into()),
                "over/mfpt"
                | "over/stderr"
                | "over/restricted_mean"
                | "over/total_steps"
                | "over/chain_mfpt_coarse"
                | "over/chain_mfpt_fine" => Some("steps".into()),
                "over/gsn" => Some("indicator units per rad".into()),
                _ => None,
            },
            slice: None,
            scales: &[],
            coordinates: Some(&coordinates),
        },
    )?;
    Ok(())
}

/// `OUT.png`: MFPT against the parameter (log MFPT axis); `OUT-gsn.png`: MFPT against GSN.
fn plots(
    out: &std::path::Path,
    m: &pdw::BuiltModel,
    name: &str,
    d: &pdw::store::MfptOverData,
) -> anyhow::Result<()> {
    let pts = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| (*a, *b)).collect::<Vec<_>>();
    let mut lines = vec![("Monte Carlo".to_string(), pts(&d.values, &d.mfpt))];
    if d.chain_mesh[0] > 0 {
        lines.push((
            format!("chain, mesh {}", d.chain_mesh[1]),
            pts(&d.values, &d.chain_mfpt_fine),
        ));
    }
    let title = format!(
        "{}: MFPT over {name}, slope sd {:.3}°",
        m.info.name,
        d.sd.to_degrees()
    );
    let files = pdw::mfpt::output_files(out, true);
    pdw::store::plot_lines(
        &files[1].path,
        &title,
        name,
        "MFPT (steps before a fall)",
        &lines,
        false,
        true,
    )?;
    let title = format!(
        "{}: MFPT against GSN over {name}, Spearman ρ = {:.3}",
        m.info.name, d.spearman
    );
    let marks = pdw::store::Markers {
        name: format!("one per {name} value"),
        points: pts(&d.gsn, &d.mfpt),
        colour: [31, 119, 180],
        shape: pdw::store::MarkerShape::Circle,
    };
    pdw::store::plot_lines_marked(
        &files[2].path,
        &title,
        "gait sensitivity norm (step time, step length per rad)",
        "MFPT (steps before a fall)",
        &[],
        &[marks],
        (false, true),
    )?;
    if !d.mfpt.iter().any(|v| v.is_finite()) {
        eprintln!(
            "note: no walker fell at any value of {name}, so no MFPT is finite (each is above \
             the steps walked, see the table): {} and {} show empty axes",
            files[1].path.display(),
            files[2].path.display()
        );
    }
    Ok(())
}
