//! `pdw-sweep mfpt`: the mean first-passage time on random terrain (steps before a fall) by
//! Monte Carlo. The request's checks, the model at any slope, the start and the run are
//! [`pdw::mfpt`]'s; this file parses, shows progress, prints and writes.

use super::basin::progress_bar;
use super::build_model;
use crate::args::InputError;
use crate::cli::MfptArgs;
use indicatif::ProgressBar;
use pdw::limit::terrain::{MfptEstimate, SlopeTerrain, TerrainKind};
use pdw::mfpt::{self, MfptFlags, MfptPlan, StrideMap};
use pdw::BuiltModel;
use std::process::ExitCode;
use std::time::Instant;

/// The names of `mfpt`'s options in messages.
const FLAGS: MfptFlags = MfptFlags {
    terrain: "--terrain",
    sd: "--sd",
    mean: "--mean",
    walkers: "--walkers",
    max_steps: "--max-strides",
    dist: "--dist",
};

pub fn run(a: &MfptArgs) -> anyhow::Result<ExitCode> {
    let kind = mfpt::check_terrain(&a.terrain, &FLAGS)?;
    let sds = mfpt::parse_sd_values_for(&a.sd, kind, &FLAGS)?;
    let sd = sds[sds.len() - 1];
    let dist = mfpt::parse_dist(&a.dist, &FLAGS)?;
    let integrator = super::integrator(&a.integrator, mfpt::default_integrator())?;
    let choice = model_choice(a, kind)?;
    let m = build_model(&choice)?;
    mfpt::check_model_for(&m, kind)?;
    pdw::integrator::check_integrator(&m, &integrator)?;
    let stride_map = StrideMap::parse(&a.stride_map, "--stride-map")?;
    stride_map.closed_form(&m, "--stride-map")?;
    let plan = MfptPlan {
        terrain: SlopeTerrain {
            mean: terrain_mean(&m, kind),
            sd,
            seed: a.seed,
            kind,
            dist,
        },
        walkers: a.walkers,
        max_strides: a.max_strides,
        integrator,
        stride_map,
    };
    // the largest standard deviation is checked (the range's last value)
    mfpt::check_plan(&plan, &FLAGS)?;
    mfpt::check_heights(&m, &plan, &FLAGS)?;
    // the chain's request is checked before any walker walks
    let chain = chain_plan(a, &m)?;
    mfpt::check_memory(&m, &plan, chain.as_ref(), &FLAGS, "--mesh")?;
    let claim = claim_out(a)?;
    if a.over.is_some() {
        if kind != pdw::limit::terrain::TerrainKind::Slope {
            return Err(InputError(
                "--over: runs on random slopes only (its gait sensitivity norm is against the \
                 landing line's slope); use --terrain slope"
                    .into(),
            )
            .into());
        }
        return super::mfpt_over::run(a, &super::choice(&choice), &plan, &FLAGS, claim);
    }
    if sds.len() > 1 {
        return super::mfpt_curve::run(a, &m, &plan, &sds, claim);
    }
    let (x0, section) = mfpt::start(&m)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads)
        .build()
        .map_err(|e| InputError(format!("--threads: cannot start the pool: {e}")))?;
    let pb = progress_bar(
        a.quiet,
        a.walkers as u64,
        "{elapsed_precise} [{wide_bar}] {pos}/{len} walkers  {per_sec}  ETA {eta}",
    );
    let t0 = Instant::now();
    let (_, est) = mfpt::run(&m, &plan, &x0, &pool, &|n| pb.set_position(n as u64))?;
    let secs = t0.elapsed().as_secs_f64();
    pb.finish_and_clear();
    summary(&m, &plan, &section, &est, secs);
    let (chain, method) = match chain {
        Some(c) => (
            run_chain(&m, &plan, &c, &x0, &pool, a.quiet)?,
            method_of(Some((c.section, c.layout)), legs_together(&m, &plan)),
        ),
        None => (Vec::new(), method_of(None, false)),
    };
    if let Some(w) = mfpt::chain_agreement_warning(&chain, &est, "--nodes") {
        crate::outln!("{w}");
    }
    if let (Some(out), Some(_claim)) = (&a.out, claim) {
        write(out, &m, &plan, &section, &est, secs, (chain, method))?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The model options with `--mean` applied: the model's slope on random slopes (not together
/// with `--slope`), its `step_down` on random step heights.
pub(super) fn model_choice(
    a: &MfptArgs,
    kind: TerrainKind,
) -> Result<crate::cli::ModelOpts, InputError> {
    let mut choice = a.model.clone();
    let Some(mean) = &a.mean else {
        return Ok(choice);
    };
    match kind {
        TerrainKind::Slope if a.model.slope.is_some() => {
            return Err(InputError(
                "--mean: the mean slope is the model's slope; give --mean or --slope, not both"
                    .into(),
            ))
        }
        TerrainKind::Slope => {
            choice.slope = Some(pdw::input::parse_slope_for(mean, "--mean")?.to_string())
        }
        TerrainKind::StepDown => {
            let h = mfpt::parse_height(mean, "--mean")?;
            choice.set.push(format!("step_down={h:?}"));
        }
    }
    Ok(choice)
}

/// The terrain's mean: the model's slope, or its step down.
pub(super) fn terrain_mean(m: &BuiltModel, kind: TerrainKind) -> f64 {
    let p = kind.param();
    m.params.iter().find(|q| q.0 == p).map_or(0.0, |q| q.1)
}

/// The terrain's mean and standard deviation in words: radians and degrees for slopes, the
/// model's length unit for step heights.
pub(super) fn terrain_words(m: &BuiltModel, t: &SlopeTerrain) -> String {
    match t.kind {
        TerrainKind::Slope => format!(
            "terrain slope: mean {} rad ({:.4}°), sd {} rad ({:.4}°)",
            t.mean,
            t.mean.to_degrees(),
            t.sd,
            t.sd.to_degrees()
        ),
        TerrainKind::StepDown => {
            let u = terrain_unit(m, t.kind);
            format!(
                "terrain step-down (foothold below the stance foot, a step down positive): \
                 mean {} {u}, sd {} {u}",
                t.mean, t.sd
            )
        }
    }
}

/// The unit of the terrain's mean and standard deviation.
pub(super) fn terrain_unit(m: &BuiltModel, kind: TerrainKind) -> String {
    match kind {
        TerrainKind::Slope => "rad".into(),
        TerrainKind::StepDown => m.walker.units().length.to_string(),
    }
}

/// Claims every file `--out` makes ([`mfpt::output_files`]: the HDF5 file, its picture and,
/// with `--over`, the GSN picture), against the spec file and the `--dist` file as inputs.
pub(super) fn claim_out(a: &MfptArgs) -> Result<Option<super::output::Claim>, InputError> {
    let Some(out) = &a.out else {
        return Ok(None);
    };
    let files = mfpt::output_files(out, a.over.is_some());
    let mut inputs: Vec<_> = super::output::model_input(&a.model.model)
        .into_iter()
        .collect();
    if let Some(path) = mfpt::dist_input(&a.dist) {
        inputs.push(super::output::Input {
            flag: "--dist",
            path,
        });
    }
    let outputs: Vec<_> = files.iter().map(|f| f.output()).collect();
    super::output::claim(&outputs, &inputs, a.force).map(Some)
}

/// The run's lines: model, terrain and start; the MFPT by both estimators; falls by kind; speed.
fn summary(m: &BuiltModel, plan: &MfptPlan, section: &[f64], est: &MfptEstimate, secs: f64) {
    let t = &plan.terrain;
    crate::outln!(
        "model {}  {}, seed {}; draws {}",
        m.info.name,
        terrain_words(m, t),
        t.seed,
        mfpt::dist_words(&t.dist)
    );
    crate::outln!("start: stable gait {section:?} (just after a heel strike)");
    crate::outln!(
        "{} walkers, at most {} steps: {} fell, {} still walking (censored); {} steps in all",
        est.walkers,
        plan.max_strides,
        est.falls,
        est.censored,
        est.total_steps
    );
    if est.falls == 0 {
        // no fall in S strides: p < 3/S at 95 % confidence (the rule of three), MFPT > S/3 − 1
        crate::outln!(
            "MFPT: no fall in {} steps; more than about {} steps at 95 % confidence (rule of \
             three)",
            est.total_steps,
            (est.total_steps / 3).saturating_sub(1)
        );
    } else {
        crate::outln!(
            "MFPT {:.4} ± {:.4} steps (maximum likelihood, constant fall probability per step: \
             steps / falls)",
            est.mfpt,
            est.stderr
        );
    }
    crate::outln!(
        "mean of min(T, {}) {:.4} ± {:.4} steps (survival-based, restricted to the step limit)",
        plan.max_strides,
        est.restricted_mean,
        est.restricted_stderr
    );
    for (kind, n) in &est.failures {
        crate::outln!("  {n} {kind}");
    }
    let strides = est.total_steps + est.falls as u64;
    crate::outln!(
        "{:.1} s: {:.0} walkers/s, {:.0} strides/s ({} strides)",
        secs,
        est.walkers as f64 / secs,
        strides as f64 / secs,
        plan.stride_map.describe(m)
    );
}

/// The estimator's description stored with the result.
pub(super) const ESTIMATOR: &str =
    "mfpt = total steps / falls: the maximum-likelihood estimate for a \
                         constant fall probability per step (censored geometric first-passage \
                         time); stderr = sqrt(S (S + F)) / F^1.5 from the Fisher information";

/// The file's `method`: the Monte Carlo, and the chain on its section where it ran; `legs`:
/// the mid-stance section is the legs together (step heights on a model with legs,
/// `pdw::limit::mid_stance::plane`).
fn method_of(chain: Option<(mfpt::ChainSection, mfpt::ChainMesh)>, legs: bool) -> &'static str {
    use mfpt::{ChainMesh, ChainSection};
    match (chain, legs) {
        (None, _) => "monte carlo",
        (Some((ChainSection::Landing, _)), _) => "monte carlo + markov chain",
        (Some((ChainSection::MidStance, ChainMesh::Grid)), false) => {
            "monte carlo + markov chain on the mid-stance section"
        }
        (Some((ChainSection::MidStance, ChainMesh::Cloud)), false) => {
            "monte carlo + markov chain on a cloud of the mid-stance section"
        }
        (Some((ChainSection::MidStance, ChainMesh::Grid)), true) => {
            "monte carlo + markov chain on the mid-stance section at the legs together"
        }
        (Some((ChainSection::MidStance, ChainMesh::Cloud)), true) => {
            "monte carlo + markov chain on a cloud of the mid-stance section at the legs together"
        }
    }
}

/// Whether the chain's mid-stance section is the legs together for `m` on `plan`'s terrain.
fn legs_together(m: &BuiltModel, plan: &mfpt::MfptPlan) -> bool {
    pdw::limit::mid_stance::legs_together_on(m.walker.as_ref(), plan.terrain.kind).is_some()
}

/// Writes the HDF5 file (with provenance and units) and the survival curve's PNG next to it.
fn write(
    out: &std::path::Path,
    m: &BuiltModel,
    plan: &MfptPlan,
    section: &[f64],
    est: &MfptEstimate,
    secs: f64,
    (chain, method): (Vec<(String, f64)>, &str),
) -> anyhow::Result<()> {
    let t = &plan.terrain;
    let data = pdw::store::MfptData {
        command: super::command_line(),
        model: m.info.name.clone(),
        params: m.params_json().to_string(),
        method: method.into(),
        terrain: t.kind.name().into(),
        distribution: mfpt::dist_words(&t.dist),
        terrain_unit: terrain_unit(m, t.kind),
        mean: t.mean,
        sd: t.sd,
        seed: t.seed,
        walkers: est.walkers as u64,
        max_steps: plan.max_strides as u64,
        falls: est.falls as u64,
        censored: est.censored as u64,
        total_steps: est.total_steps,
        mfpt: est.mfpt,
        stderr: est.stderr,
        restricted_mean: est.restricted_mean,
        restricted_stderr: est.restricted_stderr,
        estimator: ESTIMATOR.into(),
        survival: est.survival.clone(),
        failures: est
            .failures
            .iter()
            .map(|(k, n)| (k.clone(), *n as u64))
            .collect(),
        start: section.to_vec(),
        start_names: m.info.section_names.clone(),
        elapsed_s: secs,
        chain,
    };
    // the claim refused an existing file without --force; its placeholder is replaced
    pdw::store::write_mfpt(out, true, &data)?;
    let prov = provenance(m, plan);
    let units = pdw::model::unit_context(m);
    let coordinates = m.coordinates_json();
    pdw::store::annotate(
        out,
        &pdw::store::Annotations {
            provenance: Some(&prov),
            units: &pdw::store::format::MFPT.units(&units),
            slice: None,
            scales: &[],
            coordinates: Some(&coordinates),
        },
    )?;
    let curve: Vec<(f64, f64)> = est
        .survival
        .iter()
        .enumerate()
        .map(|(k, s)| (k as f64, *s))
        .collect();
    let title = match t.kind {
        TerrainKind::Slope => format!(
            "{}: survival on random slopes, mean {:.3}°, sd {:.3}°",
            m.info.name,
            t.mean.to_degrees(),
            t.sd.to_degrees()
        ),
        TerrainKind::StepDown => format!(
            "{}: survival on random step heights, mean {}, sd {} {}",
            m.info.name,
            t.mean,
            t.sd,
            terrain_unit(m, t.kind)
        ),
    };
    pdw::store::plot_lines(
        &pdw::mfpt::output_files(out, false)[1].path,
        &title,
        "steps k",
        "fraction still walking after k steps",
        &[("Monte Carlo".to_string(), curve)],
        false,
        // a constant fall probability per step is a straight line on a log axis
        true,
    )?;
    Ok(())
}

/// The run's options as every MFPT file's provenance records them.
pub(super) fn provenance(m: &BuiltModel, plan: &MfptPlan) -> pdw::store::Provenance {
    super::provenance(serde_json::json!({
        "stride_map": plan.stride_map.describe(m),
        "integrator": super::integrator_json(&plan.integrator),
        "walkers": plan.walkers,
        "max_steps": plan.max_strides,
        "gait_newton_tol": mfpt::GAIT_TOL,
    }))
}

/// The chain's plan from `--chain`, `--mesh`, `--nodes` (checked), or `None` without `--chain`.
pub(super) fn chain_plan(
    a: &MfptArgs,
    m: &BuiltModel,
) -> Result<Option<mfpt::ChainPlan>, InputError> {
    if !a.chain {
        return Ok(None);
    }
    let flags = mfpt::ChainFlags {
        chain: "--chain",
        mesh: "--mesh",
        nodes: "--nodes",
        section: "--chain-section",
    };
    let section = mfpt::ChainSection::parse(&a.chain_section, flags.section)?;
    mfpt::check_chain_terrain(m, mfpt::check_terrain(&a.terrain, &FLAGS)?, flags.chain)?;
    let c = mfpt::check_chain(m, a.mesh, Some(a.nodes), section, &flags)?;
    mfpt::check_layout(c, &a.chain_mesh, "--chain-mesh").map(Some)
}

/// A counter of the chain's strides on stderr, with the stage in its message (hidden with
/// --quiet or off a terminal): the chain's total is not known before its box and, on a cloud,
/// its closure are.
fn chain_progress(quiet: bool) -> ProgressBar {
    let pb = progress_bar(
        quiet,
        0,
        "{elapsed_precise} {spinner} {human_pos} strides of the chain  {per_sec}  {msg}",
    );
    pb.enable_steady_tick(std::time::Duration::from_millis(250));
    pb
}

/// The chain at `--mesh` and twice as fine over the box the walkers visit; prints both and
/// returns the numbers the file keeps. A counter of its strides on stderr unless `quiet`.
pub(super) fn run_chain(
    m: &BuiltModel,
    plan: &MfptPlan,
    c: &mfpt::ChainPlan,
    x0: &[f64],
    pool: &rayon::ThreadPool,
    quiet: bool,
) -> anyhow::Result<Vec<(String, f64)>> {
    if let Some(w) = mfpt::zero_height_node_warning(plan, c.nodes, "--nodes") {
        crate::outln!("{w}");
    }
    if c.layout == mfpt::ChainMesh::Cloud {
        return run_cloud(m, plan, c, x0, pool, quiet);
    }
    let pb = chain_progress(quiet);
    let tell = |n: usize| pb.inc(n as u64);
    pb.set_message("the box the walkers visit");
    let cb = mfpt::chain_box(m, plan, c, x0, pool, &tell)?;
    let how = if cb.passes == 0 {
        "the walkers' box, padded".to_string()
    } else {
        format!(
            "the walkers' box widened in {} pass{} to hold its nodes' landings: on the walkers' \
             box {:.1} % of the absorption was landings outside it",
            cb.passes,
            if cb.passes == 1 { "" } else { "es" },
            100.0 * cb.out_share
        )
    };
    pb.suspend(|| {
        crate::outln!(
            "Markov chain: {} {} nodes of the terrain, {} section, mesh over {} ({how})",
            c.nodes,
            mfpt::quadrature_name(&plan.terrain.dist),
            c.section.name(),
            mesh_box_text(&cb)
        )
    });
    let mut out = vec![
        ("nodes".to_string(), c.nodes as f64),
        ("box_widening_passes".to_string(), cb.passes as f64),
        (
            "mid_stance".to_string(),
            f64::from(u8::from(c.section == mfpt::ChainSection::MidStance)),
        ),
    ];
    let mut results = Vec::with_capacity(2);
    for (label, n) in [("coarse", c.mesh), ("fine", 2 * c.mesh)] {
        let t0 = Instant::now();
        let fine = mfpt::ChainPlan {
            mesh: n,
            ..c.clone()
        };
        pb.set_message(format!("mesh {n}"));
        let r = mfpt::chain_in(m, plan, &fine, &cb.frame, &cb.bounds, x0, pool, &tell)?;
        let secs = t0.elapsed().as_secs_f64();
        pb.suspend(|| report_mesh(&r, (n, secs), label, &format!("{secs:.1} s"), &mut out));
        results.push(r);
    }
    pb.set_message(format!("mesh {}, --nodes {}", c.mesh, 2 * c.nodes));
    let t0 = Instant::now();
    let q = mfpt::quadrature_check(m, plan, c, &cb, &results[0], x0, pool, &tell, "--nodes")?;
    pb.finish_and_clear();
    crate::outln!(
        "  quadrature check: mesh {} with --nodes {}: MFPT {:.4} steps, {:.2} % from --nodes {}; \
         {:.1} s",
        q.mesh,
        q.nodes,
        q.mfpt,
        100.0 * q.change,
        c.nodes,
        t0.elapsed().as_secs_f64()
    );
    let change = mfpt::refinement_change(&results[0], &results[1]);
    out.push(("refinement_change".to_string(), change));
    out.push(("quadrature_nodes".to_string(), q.nodes as f64));
    out.push(("quadrature_mfpt".to_string(), q.mfpt));
    out.push(("quadrature_change".to_string(), q.change));
    if let Some(w) = mfpt::refinement_warning(&results[0], &results[1], c.mesh) {
        crate::outln!("  {w}");
    }
    if let Some(w) = &q.warning {
        crate::outln!("  {w}");
    }
    Ok(out)
}

/// One mesh's result (mesh `n`, built and solved in `secs`) printed (`how`: what else to say
/// of it) and its numbers added to `out` with the suffix `label`.
fn report_mesh(
    r: &pdw::limit::markov::ChainResult,
    (n, secs): (usize, f64),
    label: &str,
    how: &str,
    out: &mut Vec<(String, f64)>,
) {
    crate::outln!(
        "  mesh {n}: MFPT {:.4} steps from the start; lambda {:.10}, 1/(1-lambda)-1 = {:.4} \
         (quasi-stationary by the solve: {:.4}); {} states; per step {:.2e} falls, {:.2e} out \
         of the mesh; {how}",
        r.mfpt,
        r.lambda,
        r.mfpt_lambda,
        r.mfpt_quasi_stationary,
        r.states,
        r.fall_per_step,
        r.out_of_mesh,
    );
    if let Some(w) = box_warning(r) {
        crate::outln!("  {w}");
    }
    for (k, v) in [
        ("mesh", n as f64),
        ("mfpt", r.mfpt),
        ("lambda", r.lambda),
        ("mfpt_lambda", r.mfpt_lambda),
        ("out_of_mesh", r.out_of_mesh),
        ("fall_per_step", r.fall_per_step),
        ("secs", secs),
    ] {
        out.push((format!("{k}_{label}"), v));
    }
}

/// The chain on two clouds of the mid-stance section ([`mfpt::cloud_pair`]); prints both and
/// returns the numbers the file keeps (those of the grid, and each cloud's closure).
fn run_cloud(
    m: &BuiltModel,
    plan: &MfptPlan,
    c: &mfpt::ChainPlan,
    x0: &[f64],
    pool: &rayon::ThreadPool,
    quiet: bool,
) -> anyhow::Result<Vec<(String, f64)>> {
    crate::outln!(
        "Markov chain: {} {} nodes of the terrain, mid-stance section{}, on a cloud: the states \
         the first {} walkers visit (at most {} transitions each) thinned to the spacing of \
         mesh {} and {}, closed under their landings (at most {} passes)",
        c.nodes,
        mfpt::quadrature_name(&plan.terrain.dist),
        if legs_together(m, plan) {
            " at the legs together (step heights: the next height matters from there)"
        } else {
            ""
        },
        mfpt::CLOUD_WALKERS,
        mfpt::CLOUD_STEPS,
        c.mesh,
        2 * c.mesh,
        mfpt::CLOUD_PASSES
    );
    let t0 = Instant::now();
    let pb = chain_progress(quiet);
    pb.set_message(format!(
        "the visited states, the clouds of mesh {} and {}",
        c.mesh,
        2 * c.mesh
    ));
    let pair = mfpt::cloud_pair(m, plan, c, x0, pool, &|n| pb.inc(n as u64))?;
    pb.finish_and_clear();
    let mut out = vec![
        ("nodes".to_string(), c.nodes as f64),
        ("box_widening_passes".to_string(), 0.0),
        ("mid_stance".to_string(), 1.0),
        ("cloud".to_string(), 1.0),
    ];
    let clouds = pair.clouds.as_ref().map(|c| c.to_vec()).unwrap_or_default();
    for ((r, label), s) in pair.results.iter().zip(["coarse", "fine"]).zip(&clouds) {
        let how = format!(
            "{} visited states thinned at a spacing of {:.3} standard deviations, {} nodes after \
             {} closure pass{}; {:.1} s",
            s.seeds,
            s.cell,
            s.nodes,
            s.passes,
            if s.passes == 1 { "" } else { "es" },
            s.secs
        );
        report_mesh(r, (s.mesh, s.secs), label, &how, &mut out);
        for (k, v) in [
            ("cloud_cell", s.cell),
            ("cloud_seeds", s.seeds as f64),
            ("cloud_passes", s.passes as f64),
            ("cloud_nodes", s.nodes as f64),
        ] {
            out.push((format!("{k}_{label}"), v));
        }
    }
    crate::outln!(
        "  the chain in all (the visited states and both clouds): {:.1} s",
        t0.elapsed().as_secs_f64()
    );
    out.push(("refinement_change".to_string(), pair.change));
    if let Some(w) = &pair.warning {
        crate::outln!("  {w}");
    }
    Ok(out)
}

/// The chain's mesh box for the report: `lo .. hi` in section coordinates, or, along the
/// walkers' principal axes, the parallelogram's corner and edges.
fn mesh_box_text(cb: &mfpt::ChainBox) -> String {
    if cb.frame.is_identity() {
        return format!("{:?} .. {:?}", cb.bounds.0, cb.bounds.1);
    }
    let (corner, edges) = cb.frame.edges(&cb.bounds);
    let edges: Vec<String> = edges.iter().map(|e| format!("{e:?}")).collect();
    format!(
        "the walkers' principal axes: the parallelogram from {corner:?} along {}",
        edges.join(" and ")
    )
}

/// A warning when the chain's absorption is more than 1 % landings outside the mesh rather
/// than falls: its MFPT is then the time to leave the box, an underestimate of the time to fall.
pub(super) fn box_warning(r: &pdw::limit::markov::ChainResult) -> Option<String> {
    let absorbed = r.out_of_mesh + r.fall_per_step;
    (absorbed > 0.0 && r.out_of_mesh > 0.01 * absorbed).then(|| {
        format!(
            "WARNING: {:.1} % of the chain's absorption is landings outside the mesh ({:.2e} per \
             step against {:.2e} falls): its MFPT is the time to leave the box and \
             underestimates the time to fall",
            100.0 * r.out_of_mesh / absorbed,
            r.out_of_mesh,
            r.fall_per_step
        )
    })
}
