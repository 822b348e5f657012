//! `pdw-sweep design`: search free design parameters of a walker for the most robust (or most
//! stable) passive gait that is physically valid along the whole stride
//! ([`pdw_limit::design`]); every evaluated design in an HDF5 file that a rerun continues.

use super::build_with;
use super::output::{Format, Output};
use crate::args::{self, InputError};
use crate::cli::DesignArgs;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use pdw_limit::basin::BasinOptions;
use pdw_limit::design::{
    evaluate_design, search, status, DesignEval, DesignOptions, DesignSpace, Objective,
};
use pdw_store::{read_design, read_design_commands, write_design_annotated, DesignData};
use std::io::IsTerminal;
use std::process::ExitCode;

/// Per-design measures stored as columns, in this order.
const COLUMNS: [&str; 9] = [
    "cost",
    "basin_fraction",
    "rho",
    "min_normal_force",
    "max_friction",
    "min_knee_torque",
    "period",
    "step_length",
    "min_relative_margin",
];

fn measures(e: &DesignEval) -> [f64; 9] {
    [
        e.cost,
        e.basin_fraction,
        e.rho,
        e.min_normal_force,
        e.max_friction,
        e.min_knee_torque,
        e.period,
        e.step_length,
        e.min_relative_margin,
    ]
}

fn to_data(settings: &str, names: &[String], h: &[DesignEval]) -> DesignData {
    DesignData {
        settings: settings.to_string(),
        free_names: names.to_vec(),
        status_names: status::NAMES.iter().map(|s| s.to_string()).collect(),
        params: h.iter().map(|e| e.params.clone()).collect(),
        status: h.iter().map(|e| e.status).collect(),
        reasons: h.iter().map(|e| e.reason.clone()).collect(),
        section: h.iter().map(|e| e.section).collect(),
        columns: COLUMNS
            .iter()
            .enumerate()
            .map(|(i, c)| (c.to_string(), h.iter().map(|e| measures(e)[i]).collect()))
            .collect(),
    }
}

fn from_data(d: &DesignData) -> Vec<DesignEval> {
    (0..d.params.len())
        .map(|i| {
            let c = |name: &str| d.column(name).map_or(f64::NAN, |v| v[i]);
            DesignEval {
                params: d.params[i].clone(),
                status: d.status[i],
                reason: d.reasons[i].clone(),
                cost: c("cost"),
                basin_fraction: c("basin_fraction"),
                rho: c("rho"),
                section: d.section[i],
                min_normal_force: c("min_normal_force"),
                max_friction: c("max_friction"),
                min_knee_torque: c("min_knee_torque"),
                period: c("period"),
                step_length: c("step_length"),
                min_relative_margin: c("min_relative_margin"),
            }
        })
        .collect()
}

pub fn run(a: &DesignArgs) -> anyhow::Result<ExitCode> {
    // ---- arguments, checked before anything is computed
    let objective = match a.objective.as_str() {
        "basin" => Objective::Basin,
        "margin" => Objective::Margin,
        o => {
            return Err(
                InputError(format!("--objective: '{o}' is not one of basin, margin")).into(),
            )
        }
    };
    if !(a.mu.is_finite() && a.mu > 0.0) {
        return Err(InputError(format!(
            "--mu: {} is not a friction coefficient; give a finite value > 0 (e.g. 0.6)",
            a.mu
        ))
        .into());
    }
    if !(a.knee_margin.is_finite() && a.knee_margin >= 0.0) {
        return Err(InputError(format!(
            "--knee-margin: {} N m is not allowed; give a finite torque >= 0",
            a.knee_margin
        ))
        .into());
    }
    if !(a.min_margin.is_finite() && a.min_margin >= 0.0) {
        return Err(InputError(format!(
            "--min-margin: {} is not allowed; give a finite relative margin >= 0 (e.g. 0.05)",
            a.min_margin
        ))
        .into());
    }
    if !(1..=100_000).contains(&a.budget) {
        return Err(InputError(format!(
            "--budget: {} designs is outside 1..=100000",
            a.budget
        ))
        .into());
    }
    if !(1..=200).contains(&a.basin_grid) {
        return Err(InputError(format!(
            "--basin-grid: {} cells per side is outside 1..=200",
            a.basin_grid
        ))
        .into());
    }
    let bx = args::parse_guess(&a.basin_box)?;
    if bx.len() != 2 || bx.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        return Err(InputError(format!(
            "--basin-box: '{}' must be two positive half widths DSTANCE,DSTANCE_RATE (e.g. \
             0.05,0.2)",
            a.basin_box
        ))
        .into());
    }
    if a.max_strides == 0 || a.max_strides > 10_000 {
        return Err(InputError(format!(
            "--max-strides: {} is outside 1..=10000",
            a.max_strides
        ))
        .into());
    }
    let base = build_with(&a.model, &[])?;
    if base.info.spec().is_none() {
        return Err(InputError(format!(
            "--model: '{}' is not a chain walker (section of {} coordinates); design searches \
             run on walker specs (compass, kneed, seed5 or a .toml file)",
            base.info.name,
            base.info.section_names.len()
        ))
        .into());
    }
    let mut names = Vec::new();
    let (mut lo, mut hi) = (Vec::new(), Vec::new());
    let set_names: Vec<String> = super::overrides(&a.model)?
        .into_iter()
        .map(|p| p.0)
        .collect();
    for f in &a.free {
        let r = args::parse_axis(f, "--free")?;
        if !base.params.iter().any(|p| p.0 == r.name) {
            return Err(InputError(format!(
                "--free: '{}' is not a parameter of model '{}' (parameters: {})",
                r.name,
                base.info.name,
                base.params
                    .iter()
                    .map(|p| p.0.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
            .into());
        }
        if names.contains(&r.name) {
            return Err(InputError(format!("--free: '{}' is given twice", r.name)).into());
        }
        if set_names.contains(&r.name) {
            return Err(InputError(format!(
                "--free: '{}' is also fixed by --set/--slope; a parameter is either free or set",
                r.name
            ))
            .into());
        }
        // both bounds must make a model (checked once, here)
        for v in [r.lo, r.hi] {
            build_with(&a.model, &[(r.name.clone(), v)]).map_err(|e| {
                InputError(format!(
                    "--free {}: the bound {v} does not make a model: {e}",
                    f
                ))
            })?;
        }
        names.push(r.name);
        lo.push(r.lo);
        hi.push(r.hi);
    }
    if names.is_empty() {
        return Err(InputError("--free: give at least one NAME=LO:HI".into()).into());
    }
    let png = a.png.clone().unwrap_or_else(|| a.out.with_extension("png"));
    // An existing --out continues its search (unless --force); the picture beside it is that
    // search's and is redrawn. A picture without its search is replaced only with --force.
    let continuing = a.out.is_file() && !a.force;
    let outputs = [
        Output {
            flag: "--out",
            path: &a.out,
            format: Format::Hdf5,
            may_exist: true,
        },
        Output {
            flag: "--png",
            path: &png,
            format: Format::Png,
            may_exist: continuing,
        },
    ];
    let inputs: Vec<_> = super::output::model_input(&a.model.model)
        .into_iter()
        .collect();
    let mut claim = super::output::claim(&outputs, &inputs, a.force)?;
    let basin = BasinOptions {
        max_strides: a.max_strides,
        ..BasinOptions::default()
    };
    let opts = DesignOptions {
        objective,
        mu: a.mu,
        knee_margin: a.knee_margin,
        min_margin: a.min_margin,
        budget: a.budget,
        seed: a.seed,
        start: Some(
            names
                .iter()
                .map(|n| {
                    base.params
                        .iter()
                        .find(|p| p.0 == *n)
                        .map_or(f64::NAN, |p| p.1)
                })
                .collect(),
        ),
        init: a.init,
        basin_grid: a.basin_grid,
        basin_box: [bx[0], bx[1]],
        basin,
        newton_tol: 1e-10,
    };
    let settings = serde_json::json!({
        "model": a.model.model,
        "fixed": base.params_json(),
        "free": names.iter().zip(&lo).zip(&hi).map(|((n, l), h)| serde_json::json!([n, l, h])).collect::<Vec<_>>(),
        "objective": objective.name(),
        "mu": a.mu,
        "knee_margin": a.knee_margin,
        "min_margin": a.min_margin,
        "seed": a.seed,
        "init": a.init,
        "basin_grid": a.basin_grid,
        "basin_box": bx,
        "max_strides": a.max_strides,
        "newton_tol": opts.newton_tol,
        "model_resolved": base.walker.fingerprint(),
    })
    .to_string();

    // ---- what the file says besides the designs: units of every dataset, provenance
    let mut options: serde_json::Value = serde_json::from_str(&settings)?;
    options["threads"] = serde_json::json!(a.threads);
    let prov = super::provenance(options);
    let param_units = super::units_list(
        &names
            .iter()
            .map(|n| super::param_unit(&base, n))
            .collect::<Vec<_>>(),
    );
    let section_units = super::units_list(&super::section_units(&base));
    let mu = super::model_units(&base);
    let (tu, lu) = (super::time_unit(&base), super::length_unit(&base));
    let units = move |ds: &str| -> Option<String> {
        Some(match ds {
            "params" => param_units.clone(),
            "section" => section_units.clone(),
            "min_normal_force" => mu.force.clone(),
            "min_knee_torque" => mu.torque.clone(),
            "period" => tu.clone(),
            "step_length" => lu.clone(),
            // codes, fractions, multiplier moduli, friction coefficients, costs, the reasons' text
            _ => "1".into(),
        })
    };
    let ann = pdw_store::Annotations {
        provenance: Some(&prov),
        units: &units,
        slice: None,
        scales: &[],
    };
    let mut earlier_commands = Vec::new();

    // ---- a stored run with the same settings continues
    let mut history = Vec::new();
    if claim.existed(&a.out) && !a.force {
        let d = read_design(&a.out, &COLUMNS)?;
        if d.settings != settings {
            return Err(InputError(settings_differ(&a.out, &d.settings, &settings)).into());
        }
        history = from_data(&d);
        earlier_commands = read_design_commands(&a.out)?;
    }
    let write_design = |path: &std::path::Path, d: &DesignData| {
        write_design_annotated(path, d, Some(&ann), &earlier_commands)
    };
    let stored = history.len();
    let space = DesignSpace {
        names: names.clone(),
        lo,
        hi,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads)
        .build()?;
    let guesses = pdw_limit::gaits::model_guesses(base.walker.as_ref());
    let pb = if a.quiet || !std::io::stderr().is_terminal() {
        ProgressBar::with_draw_target(Some(a.budget as u64), ProgressDrawTarget::hidden())
    } else {
        ProgressBar::new(a.budget as u64)
    };
    pb.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} designs  {msg}  eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    pb.set_position(stored.min(a.budget) as u64);
    if stored > 0 {
        pb.println(format!(
            "continuing {}: {stored} designs stored",
            a.out.display()
        ));
    }
    let mut all = history.clone();
    let mut best = all.iter().map(|e| e.cost).fold(f64::INFINITY, f64::min);
    let mut write_err: Option<anyhow::Error> = None;
    let mut eval = |p: &[f64], g: &[(String, Vec<f64>)]| -> DesignEval {
        let set: Vec<(String, f64)> = names.iter().cloned().zip(p.iter().copied()).collect();
        let ev = match build_with(&a.model, &set) {
            Ok(m) => evaluate_design(p, m.walker.as_ref(), g, &opts, &pool),
            Err(e) => DesignEval::bad_model(p, e.0),
        };
        all.push(ev.clone());
        if write_err.is_none() {
            // each write replaces the file: the lock moves to the new one
            if let Err(e) = write_design(&a.out, &to_data(&settings, &names, &all)) {
                write_err = Some(e.into());
            } else if let Err(e) = claim.renew(&a.out, "--out") {
                write_err = Some(e.into());
            }
        }
        best = best.min(ev.cost);
        pb.set_message(format!("best cost {best:.4}"));
        pb.inc(1);
        ev
    };
    let hist = search(&space, &opts, &guesses, history, &mut eval)?;
    pb.finish_and_clear();
    if let Some(e) = write_err {
        return Err(e);
    }
    // a run that replayed everything still leaves a file (e.g. a budget already met)
    write_design(&a.out, &to_data(&settings, &names, &hist))?;
    claim.renew(&a.out, "--out")?;

    // ---- the search's picture: the cost of every design and the best so far
    let mut run_best = f64::INFINITY;
    let each: Vec<(f64, f64)> = hist
        .iter()
        .enumerate()
        .map(|(i, e)| ((i + 1) as f64, e.cost))
        .collect();
    let best_line: Vec<(f64, f64)> = hist
        .iter()
        .enumerate()
        .map(|(i, e)| {
            run_best = run_best.min(e.cost);
            ((i + 1) as f64, run_best)
        })
        .collect();
    pdw_store::plot_lines(
        &png,
        &format!(
            "design search, {} ({}): cost < 1 feasible; 1-5 invalid; 5-9 unstable; 10 no gait",
            base.info.name,
            objective.name()
        ),
        "design evaluated",
        "cost",
        &[
            ("each design".to_string(), each),
            ("best so far".to_string(), best_line),
        ],
        false,
        false,
    )?;

    // ---- report
    let count = |s: u8| hist.iter().filter(|e| e.status == s).count();
    crate::outln!(
        "{} designs ({} new): {} feasible, {} invalid, {} unstable, {} without a gait, {} not a model",
        hist.len(),
        hist.len() - stored.min(hist.len()),
        count(status::FEASIBLE),
        count(status::INVALID),
        count(status::UNSTABLE),
        count(status::NO_GAIT),
        count(status::BAD_MODEL)
    );
    let Some(b) = hist.iter().min_by(|x, y| x.cost.total_cmp(&y.cost)) else {
        return Ok(ExitCode::SUCCESS);
    };
    let sets: Vec<String> = names
        .iter()
        .zip(&b.params)
        .map(|(n, v)| format!("--set {n}={v}"))
        .collect();
    crate::outln!(
        "best: {} (cost {:.6}{}{}) {}",
        status::NAMES[b.status as usize],
        b.cost,
        if b.basin_fraction.is_finite() {
            format!(", basin fraction {:.4}", b.basin_fraction)
        } else {
            String::new()
        },
        if b.rho.is_finite() {
            format!(", max |λ| {:.4}", b.rho)
        } else {
            String::new()
        },
        b.reason
    );
    crate::outln!(
        "  gait {:?}, min knee torque {:.4} N m, min normal force {:.3} N, friction needed {:.4}",
        b.section,
        b.min_knee_torque,
        b.min_normal_force,
        b.max_friction
    );
    if b.min_relative_margin.is_finite() {
        crate::outln!(
            "  smallest relative margin {:.4} (required {})",
            b.min_relative_margin,
            a.min_margin
        );
    }
    crate::outln!(
        "  reproduce: pdw-sweep fixedpoint --model {} {}",
        a.model.model,
        sets.join(" ")
    );
    crate::outln!("  written: {}, {}", a.out.display(), png.display());
    Ok(if b.feasible() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// Why a stored design search cannot be continued: the resolved model's first differing line
/// (a spec edited under the same parameter values), else both settings without the model.
fn settings_differ(out: &std::path::Path, stored: &str, now: &str) -> String {
    let parse = |t: &str| serde_json::from_str::<serde_json::Value>(t).unwrap_or_default();
    let (mut s, mut n) = (parse(stored), parse(now));
    let model = |v: &serde_json::Value| {
        v.get("model_resolved")
            .and_then(|m| m.as_str())
            .unwrap_or("")
            .to_string()
    };
    if let Some((f, e)) = pdw_store::first_line_difference(&model(&s), &model(&n)) {
        let shown = |t: String| {
            if t.is_empty() {
                "(absent)".to_string()
            } else {
                t
            }
        };
        return format!(
            "--out: '{}' holds a design search of a different model (stored: {}; now: {}); \
             pass --force to start over or give another --out",
            out.display(),
            shown(f),
            shown(e)
        );
    }
    for v in [&mut s, &mut n] {
        if let Some(o) = v.as_object_mut() {
            o.remove("model_resolved");
        }
    }
    format!(
        "--out: '{}' holds a design search with other settings (stored: {s}; now: {n}); pass \
         --force to start over or give another --out",
        out.display()
    )
}
