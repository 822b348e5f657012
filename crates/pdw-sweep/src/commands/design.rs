//! `pdw-sweep design`: search free design parameters of a walker for the most robust (or most
//! stable) passive gait that is physically valid along the whole stride
//! ([`pdw::limit::design`]); every evaluated design in an HDF5 file that a rerun continues.
//!
//! [`run`] reads as the command does: the free parameters checked against the model
//! ([`parse`]; the other values are checked by clap), the outputs claimed, the plan made
//! ([`plan`]), a stored search with the same settings read back ([`stored`]), the search run
//! with every design written as it comes ([`search`], the library's [`pdw::design`]), the
//! picture drawn ([`plot`]) and the best design printed ([`report`]).

use super::output::{Claim, Format, Output};
use super::{build_with, BuiltModel};
use crate::args::InputError;
use crate::cli::DesignArgs;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use pdw::design::DesignPlan;
use pdw::limit::basin::BasinOptions;
use pdw::limit::design::{status, DesignEval, DesignOptions, DesignSpace};
use pdw::store::{read_design, read_design_commands, MarkerShape, Markers};
use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;

use pdw::design::{from_data, COLUMNS};

/// A stored search continued: its designs and the command lines that made them.
struct Stored {
    history: Vec<DesignEval>,
    commands: Vec<String>,
}

pub fn run(a: &DesignArgs) -> anyhow::Result<ExitCode> {
    let (base, space) = parse(a)?;
    let png = a.png.clone().unwrap_or_else(|| a.out.with_extension("png"));
    let mut claim = claim(a, &png)?;
    let plan = plan(a, &base, space)?;
    let settings = pdw::design::settings(&plan, &base);
    let stored = stored(a, &claim, &settings)?;
    let hist = search(a, &plan, &base, &settings, stored, &mut claim)?;
    plot(&png, &base, &plan, &hist)?;
    report(a, &png, &plan, &hist.designs, hist.stored)
}

/// The model (a chain walker) and the free parameters ([`pdw::design::space`]): each a
/// parameter of the model, given once, not also set, both bounds making a model.
fn parse(a: &DesignArgs) -> anyhow::Result<(BuiltModel, DesignSpace)> {
    let base = build_with(&a.model, &[])?;
    pdw::design::check_model(&base, "--model")?;
    let space = pdw::design::space(&super::choice(&a.model), &base, &a.free, "--free")?;
    Ok((base, space))
}

/// Claims `--out` (an existing one continues its search unless `--force`) and the picture
/// beside it (that search's, redrawn; a picture without its search is replaced only with
/// `--force`).
fn claim(a: &DesignArgs, png: &Path) -> Result<Claim, InputError> {
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
            path: png,
            format: Format::Png,
            may_exist: continuing,
        },
    ];
    let inputs: Vec<_> = super::output::model_input(&a.model.model)
        .into_iter()
        .collect();
    super::output::claim(&outputs, &inputs, a.force)
}

/// The plan: the model, the free parameters (starting from the model's own values) and the
/// search's options from the flags.
fn plan(a: &DesignArgs, base: &BuiltModel, space: DesignSpace) -> anyhow::Result<DesignPlan> {
    let start = pdw::design::start(base, &space);
    let options = DesignOptions {
        objective: a.objective,
        mu: a.mu,
        knee_margin: a.knee_margin,
        min_margin: a.min_margin,
        budget: a.budget,
        seed: a.seed,
        start: Some(start),
        init: a.init,
        basin_grid: a.basin_grid,
        basin_box: a.basin_box,
        basin: BasinOptions {
            max_strides: a.max_strides,
            ..BasinOptions::default()
        },
        newton_tol: 1e-10,
    };
    Ok(DesignPlan {
        model: super::choice(&a.model),
        space,
        options,
        starts: a.starts,
    })
}

/// The designs of an existing `--out` (unless `--force`), refused when its settings differ.
fn stored(a: &DesignArgs, claim: &Claim, settings: &str) -> anyhow::Result<Stored> {
    if !claim.existed(&a.out) || a.force {
        return Ok(Stored {
            history: Vec::new(),
            commands: Vec::new(),
        });
    }
    let d = read_design(&a.out, &COLUMNS)?;
    if d.settings != settings {
        return Err(InputError(settings_differ(&a.out, &d.settings, settings)).into());
    }
    Ok(Stored {
        history: from_data(&d),
        commands: read_design_commands(&a.out)?,
    })
}

/// Every design of a search and how many of them were stored before this run.
struct Searched {
    designs: Vec<DesignEval>,
    stored: usize,
}

/// Runs the search ([`pdw::design::search`]) with a progress bar, writing the whole file
/// (units, provenance, the earlier runs' commands) after every design, and once more at the
/// end (a run that replayed everything, e.g. a budget already met, still leaves a file).
fn search(
    a: &DesignArgs,
    plan: &DesignPlan,
    base: &BuiltModel,
    settings: &str,
    stored: Stored,
    claim: &mut Claim,
) -> anyhow::Result<Searched> {
    let prov = super::provenance(pdw::design::run_options(settings, a.threads));
    let write_design = |hist: &[DesignEval]| {
        pdw::design::write_file(
            &a.out,
            (plan, base, settings),
            hist,
            &prov,
            &stored.commands,
        )
    };
    let n_stored = stored.history.len();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads)
        .build()?;
    let pb = progress_bar(a, n_stored);
    let mut all = stored.history.clone();
    let mut best = all.iter().map(|e| e.cost).fold(f64::INFINITY, f64::min);
    let mut write_err: Option<anyhow::Error> = None;
    let mut on_eval = |ev: &DesignEval| {
        all.push(ev.clone());
        if write_err.is_none() {
            // each write replaces the file: the lock moves to the new one
            if let Err(e) = write_design(&all) {
                write_err = Some(e.into());
            } else if let Err(e) = claim.renew(&a.out, "--out") {
                write_err = Some(e.into());
            }
        }
        best = best.min(ev.cost);
        pb.set_message(format!("best cost {best:.4}"));
        pb.inc(1);
    };
    let hist = pdw::design::search(plan, base, stored.history.clone(), &pool, &mut on_eval)?;
    pb.finish_and_clear();
    if let Some(e) = write_err {
        return Err(e);
    }
    write_design(&hist)?;
    claim.renew(&a.out, "--out")?;
    Ok(Searched {
        designs: hist,
        stored: n_stored,
    })
}

/// The search's progress bar (hidden with `--quiet` or when stderr is not a terminal), at the
/// stored designs; a continued search says so.
fn progress_bar(a: &DesignArgs, stored: usize) -> ProgressBar {
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
    pb
}

/// Marker colour and shape of each design status on the search's picture, by status code.
const STATUS_MARKERS: [([u8; 3], MarkerShape); 5] = [
    ([44, 160, 44], MarkerShape::Circle),    // feasible: green
    ([255, 127, 14], MarkerShape::Triangle), // invalid: orange
    ([148, 103, 189], MarkerShape::Square),  // unstable: purple
    ([127, 127, 127], MarkerShape::Cross),   // no gait: grey
    ([0, 0, 0], MarkerShape::Cross),         // not a model: black
];

/// The search's picture: the best cost so far (a line) and every design's cost as a marker
/// by its status (legend entry per status present).
fn plot(png: &Path, base: &BuiltModel, plan: &DesignPlan, s: &Searched) -> anyhow::Result<()> {
    let hist = &s.designs;
    let mut run_best = f64::INFINITY;
    let best_line: Vec<(f64, f64)> = hist
        .iter()
        .enumerate()
        .map(|(i, e)| {
            run_best = run_best.min(e.cost);
            ((i + 1) as f64, run_best)
        })
        .collect();
    let markers: Vec<Markers> = STATUS_MARKERS
        .iter()
        .enumerate()
        .map(|(code, &(colour, shape))| Markers {
            name: status::NAMES[code].replace('_', " "),
            points: hist
                .iter()
                .enumerate()
                .filter(|(_, e)| e.status as usize == code)
                .map(|(i, e)| ((i + 1) as f64, e.cost))
                .collect(),
            colour,
            shape,
        })
        .filter(|m| !m.points.is_empty())
        .collect();
    pdw::store::plot_lines_marked(
        png,
        &format!(
            "design search, {} ({}): cost < 1 feasible; 1-4.5 invalid; 5-9 unstable; 9-10 no gait",
            base.info.name,
            plan.options.objective.name()
        ),
        "design evaluated",
        "cost",
        &[("best so far".to_string(), best_line)],
        &markers,
        (false, false),
    )?;
    Ok(())
}

/// The designs by status and the best one, with the command line that reproduces its gait;
/// when nothing is feasible, the closest design and what keeps it from being feasible (its
/// binding criterion, or how its gait search's guesses ended). Bound warnings only for a
/// feasible best (an infeasible one on a bound says nothing about an optimum beyond it).
/// Exit 1 when the best design is not feasible.
fn report(
    a: &DesignArgs,
    png: &Path,
    plan: &DesignPlan,
    hist: &[DesignEval],
    stored: usize,
) -> anyhow::Result<ExitCode> {
    let count = |s: u8| hist.iter().filter(|e| e.status == s).count();
    crate::outln!(
        "{} designs ({} new) from {} start{}: {} feasible, {} invalid, {} unstable, {} without a gait, {} not a model",
        hist.len(),
        hist.len() - stored.min(hist.len()),
        plan.starts,
        if plan.starts == 1 { "" } else { "s" },
        count(status::FEASIBLE),
        count(status::INVALID),
        count(status::UNSTABLE),
        count(status::NO_GAIT),
        count(status::BAD_MODEL)
    );
    let Some((b, why)) = pdw::design::closest(hist, a.min_margin) else {
        return Ok(ExitCode::SUCCESS);
    };
    let sets: Vec<String> = plan
        .space
        .names
        .iter()
        .zip(&b.params)
        .map(|(n, v)| format!("--set {n}={v}"))
        .collect();
    crate::outln!(
        "{}: {} (cost {:.6}{}{}) {}",
        if b.feasible() {
            "best"
        } else {
            "no feasible design; closest"
        },
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
    if let Some(why) = &why {
        crate::outln!("  closest because: {why}");
    }
    if b.section.iter().all(|v| v.is_finite()) {
        let gait: Vec<String> = b.section.iter().map(|v| format!("{v:.6}")).collect();
        // a model without knees has no knee torque (NaN): the clause is left out
        let knee = if b.min_knee_torque.is_finite() {
            format!(", min knee torque {:.4} N m", b.min_knee_torque)
        } else {
            String::new()
        };
        crate::outln!(
            "  gait ({}){knee}, min normal force {:.3} N, friction needed {:.4}",
            gait.join(", "),
            b.min_normal_force,
            b.max_friction
        );
    } else {
        crate::outln!("  no gait");
    }
    if b.min_relative_margin.is_finite() {
        crate::outln!(
            "  smallest relative margin {:.4} ({}; required {})",
            b.min_relative_margin,
            b.binding,
            a.min_margin
        );
    }
    let values: Vec<String> = plan
        .space
        .names
        .iter()
        .zip(&b.params)
        .map(|(n, v)| format!("{n} = {v}"))
        .collect();
    crate::outln!("  parameters: {}", values.join(", "));
    crate::outln!(
        "  reproduce: pdw-sweep fixedpoint --model {} {}",
        a.model.model,
        sets.join(" ")
    );
    if b.feasible() {
        for w in pdw::design::bound_warnings(&plan.space, &b.params) {
            eprintln!("warning: {w}");
        }
    }
    crate::outln!("  written: {}, {}", a.out.display(), png.display());
    Ok(if b.feasible() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// Why a stored design search cannot be continued: the resolved model's first differing line
/// (a spec edited under the same parameter values), else both settings without the model.
fn settings_differ(out: &Path, stored: &str, now: &str) -> String {
    let parse = |t: &str| serde_json::from_str::<serde_json::Value>(t).unwrap_or_default();
    let (mut s, mut n) = (parse(stored), parse(now));
    let model = |v: &serde_json::Value| {
        v.get("model_resolved")
            .and_then(|m| m.as_str())
            .unwrap_or("")
            .to_string()
    };
    if let Some((f, e)) = pdw::store::first_line_difference(&model(&s), &model(&n)) {
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
