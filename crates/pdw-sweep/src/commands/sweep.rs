//! `pdw-sweep fixedpoint --sweep NAME=A:B:N`: continuation of the gait in a parameter
//! (pseudo-arclength, with period-doubling, fold and Neimark–Sacker detection and a switch onto
//! the period-2 branch at the first period doubling), plus a brute-force orbit diagram over the
//! N parameter values; written to HDF5 and drawn as a PNG bifurcation diagram.

use super::fixedpoint::{report_failure, search};
use super::{build_with, BuiltModel};
use crate::args::{self, InputError};
use crate::cli::FixedpointArgs;
use pdw_limit::{
    continue_branch, orbit_diagram, switch_period_doubling, BifurcationKind, Branch,
    ContinuationOptions, OrbitOptions, OrbitStart,
};
use pdw_store::{plot_bifurcation, write_sweep, Bifurcation, OrbitDiagram, SweepData};
use std::process::ExitCode;

fn kind_name(k: BifurcationKind) -> &'static str {
    match k {
        BifurcationKind::PeriodDoubling => "period_doubling",
        BifurcationKind::Fold => "fold",
        BifurcationKind::BranchPoint => "branch_point",
        BifurcationKind::NeimarkSacker => "neimark_sacker",
    }
}

fn store_branch(name: &str, b: &Branch) -> pdw_store::Branch {
    pdw_store::Branch {
        name: name.to_string(),
        period_strides: b.period_strides as u32,
        parameter: b.points.iter().map(|p| p.param).collect(),
        section: b.points.iter().map(|p| p.section.clone()).collect(),
        multipliers: b
            .points
            .iter()
            .map(|p| p.multipliers.iter().map(|l| (l.re, l.im)).collect())
            .collect(),
        stable: b.points.iter().map(|p| p.stable).collect(),
    }
}

pub fn run(a: &FixedpointArgs) -> anyhow::Result<ExitCode> {
    let sw = args::parse_sweep(a.sweep.as_deref().unwrap_or_default())?;
    let png = a.png.clone().unwrap_or_else(|| a.out.with_extension("png"));
    args::check_outputs(
        &[
            args::Output {
                flag: "--out",
                path: &a.out,
                may_exist: false,
            },
            args::Output {
                flag: "--png",
                path: &png,
                may_exist: false,
            },
        ],
        &[],
        a.force,
    )?;
    let at = |mu: f64| -> Result<BuiltModel, InputError> {
        build_with(&a.model, &[(sw.name.clone(), mu)])
    };
    let m0 = at(sw.lo)?;
    at(sw.hi)?; // both ends must be valid parameter values
    let family = |mu: f64| at(mu).map(|m| m.walker);

    // the gait to continue, at the start of the range
    let guesses: Vec<(String, Vec<f64>)> = match &a.guess {
        Some(g) => vec![("guess".into(), args::parse_guess(g)?)],
        None => m0
            .walker
            .gait_guesses()
            .into_iter()
            .map(|g| (g.gait.to_string(), g.section))
            .collect(),
    };
    // --integrator/--rtol/--atol, when given, integrate every stride of the sweep (the gait
    // search, the continuation and the orbit diagram); otherwise each keeps its default.
    let user_integrator = (a.integrator.integrator.is_some()
        || a.integrator.rtol.is_some()
        || a.integrator.atol.is_some()
        || a.integrator.rk4_step.is_some())
    .then(|| super::integrator(&a.integrator, pdw_limit::gaits::default_integrator(a.tol)))
    .transpose()?;
    let (found, failed) = match &user_integrator {
        Some(i) => super::fixedpoint::search_with(&m0, &guesses, a.tol.max(1e-12), i)?,
        None => search(&m0, &guesses, a.tol.max(1e-12))?,
    };
    let start = match a.gait.as_str() {
        "unstable" => found.iter().find(|f| !f.fp.stable),
        _ => found.iter().find(|f| f.fp.stable).or_else(|| found.first()),
    };
    let Some(start) = start else {
        eprintln!(
            "no period-one gait of model '{}' at {} = {} to start the continuation from",
            m0.info.name, sw.name, sw.lo
        );
        for (label, g, e) in &failed {
            report_failure(label, g, e);
        }
        eprintln!("try: another start of the range, or --guess");
        return Ok(ExitCode::from(2));
    };
    let span = sw.hi - sw.lo;
    let step = span.abs() / (sw.n - 1) as f64;
    let mut opts = ContinuationOptions::new(sw.lo.min(sw.hi), sw.lo.max(sw.hi));
    opts.direction = span.signum();
    opts.ds_max = step;
    opts.ds_init = step;
    opts.ds_min = (step * 1e-6).min(opts.ds_min.max(1e-12));
    opts.max_points = 20 * sw.n;
    if let Some(i) = user_integrator {
        opts.integrator = i;
    }
    let t0 = std::time::Instant::now();
    let main = continue_branch(&family, &start.fp.section, sw.lo, 1, &opts)?;
    let mut branches = vec![store_branch("period-1", &main)];
    let mut bifs: Vec<Bifurcation> = Vec::new();
    let mut printed = Vec::new();
    for b in &main.bifurcations {
        bifs.push(Bifurcation {
            kind: kind_name(b.kind).into(),
            parameter: b.param,
            branch: 0,
            section: b.section.clone(),
        });
        printed.push((1, b.kind, b.param));
    }
    // period-2 branch from the first period doubling
    if let Some(pd) = main
        .bifurcations
        .iter()
        .find(|b| b.kind == BifurcationKind::PeriodDoubling)
    {
        match switch_period_doubling(&family, pd, &opts) {
            Ok(b2) => {
                for b in &b2.bifurcations {
                    bifs.push(Bifurcation {
                        kind: kind_name(b.kind).into(),
                        parameter: b.param,
                        branch: 1,
                        section: b.section.clone(),
                    });
                    printed.push((2, b.kind, b.param));
                }
                branches.push(store_branch("period-2", &b2));
            }
            Err(e) => eprintln!("warning: switching onto the period-2 branch failed: {e}"),
        }
    }
    // brute-force orbit diagram over the N values
    let params = pdw_limit::basin::linspace(sw.lo, sw.hi, sw.n);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    let mut oo = OrbitOptions {
        transient: 300,
        record: 64,
        ..OrbitOptions::default()
    };
    if let Some(i) = user_integrator {
        oo.integrator = i;
    }
    // Each value starts from the continued period-1 gait at the nearest parameter, nudged by
    // 1e-6 so that an unstable gait is left for whatever attracts beyond it.
    let starts: Vec<Vec<f64>> = params
        .iter()
        .map(|&mu| {
            let near = main
                .points
                .iter()
                .min_by(|p, q| (p.param - mu).abs().total_cmp(&(q.param - mu).abs()))
                .map(|p| p.section.clone())
                .unwrap_or_else(|| start.fp.section.clone());
            let mut v = near;
            v[0] += 1e-6;
            v
        })
        .collect();
    let cols = orbit_diagram(&family, &params, &OrbitStart::PerParam(starts), &oo, &pool)?;
    let orbit = OrbitDiagram {
        coordinate: m0.info.section_names[0].to_string(),
        parameter: params.clone(),
        points: cols
            .iter()
            .map(|c| {
                let mut v: Vec<f64> = c.points.iter().map(|p| p[0]).collect();
                v.resize(oo.record, f64::NAN);
                v
            })
            .collect(),
    };
    let data = SweepData {
        command: std::env::args().collect::<Vec<_>>().join(" "),
        model: m0.info.name.to_string(),
        parameter: sw.name.clone(),
        params: m0.params_json().to_string(),
        section_names: m0
            .info
            .section_names
            .iter()
            .map(|s| s.to_string())
            .collect(),
        branches,
        bifurcations: bifs,
        orbit: Some(orbit),
    };
    write_sweep(&a.out, a.force, &data)?;
    let fp_integrator =
        user_integrator.unwrap_or_else(|| pdw_limit::gaits::default_integrator(a.tol.max(1e-12)));
    annotate_sweep(&a.out, &m0, &sw.name, &opts, &oo, a.tol, &fp_integrator)?;
    // Units on the picture's axes (the file keeps the bare names, with units attributes).
    let mut shown = data.clone();
    shown.parameter = format!("{} [{}]", sw.name, super::param_unit(&m0, &sw.name));
    for (n, u) in shown
        .section_names
        .iter_mut()
        .zip(super::section_units(&m0))
    {
        *n = format!("{n} [{u}]");
    }
    plot_bifurcation(&png, &shown, 0)?;
    let elapsed = t0.elapsed().as_secs_f64();
    crate::outln!(
        "model {}: {} continued from {} to {} ({} points on the period-1 branch, end: {:?})",
        m0.info.name,
        sw.name,
        sw.lo,
        sw.hi,
        main.points.len(),
        main.end
    );
    for (period, kind, mu) in printed {
        crate::outln!(
            "  {:<16} on the period-{period} branch at {} = {mu:.12} {}",
            kind_name(kind),
            sw.name,
            super::param_unit(&m0, &sw.name)
        );
    }
    let falls = cols.iter().filter(|c| c.fall.is_some()).count();
    crate::outln!(
        "  orbit diagram: {} values, {} with a fall; wrote {} and {} in {:.2} s",
        params.len(),
        falls,
        a.out.display(),
        png.display(),
        elapsed
    );
    Ok(ExitCode::SUCCESS)
}

/// Provenance (every numerical option: the gait search, the continuation, the orbit diagram)
/// and units on every dataset of the sweep file.
fn annotate_sweep(
    out: &std::path::Path,
    m: &BuiltModel,
    parameter: &str,
    c: &ContinuationOptions,
    o: &OrbitOptions,
    tol: f64,
    fp_integrator: &pdw_hybrid::Options,
) -> anyhow::Result<()> {
    let options = serde_json::json!({
        "fixed_point": {
            "newton_tol": tol.max(1e-12),
            "integrator": super::integrator_json(fp_integrator),
        },
        "continuation": {
            "method": format!("{:?}", c.method),
            "integrator": super::integrator_json(&c.integrator),
            "direction": c.direction,
            "ds_init": c.ds_init, "ds_min": c.ds_min, "ds_max": c.ds_max,
            "max_points": c.max_points,
            "mu_min": c.mu_min, "mu_max": c.mu_max,
            "newton_tol": c.newton_tol, "max_newton": c.max_newton,
            "dmu": c.dmu, "max_turn": c.max_turn,
            "locate_tol": c.locate_tol, "switch_eps": c.switch_eps,
        },
        "orbit_diagram": {
            "integrator": super::integrator_json(&o.integrator),
            "transient": o.transient,
            "record": o.record,
            "max_period": o.max_period,
            "tol_period": o.tol_period,
        },
    });
    let prov = super::provenance(options);
    let pu = super::param_unit(m, parameter);
    let su = super::section_units(m);
    let list = super::units_list(&su);
    let first = su.first().cloned().unwrap_or_default();
    let units = move |p: &str| -> Option<String> {
        let leaf = p.rsplit('/').next().unwrap_or(p);
        match leaf {
            "parameter" => Some(pu.clone()),
            "section" => Some(list.clone()),
            "multipliers_re" | "multipliers_im" | "stable" => Some("1".into()),
            "points" if p.starts_with("orbit") => Some(first.clone()),
            _ => None,
        }
    };
    pdw_store::annotate(
        out,
        &pdw_store::Annotations {
            provenance: Some(&prov),
            units: &units,
            slice: None,
            scales: &[],
        },
    )?;
    Ok(())
}
