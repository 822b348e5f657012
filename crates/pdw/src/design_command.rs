//! The `design` command as plan → run → report ([`crate::pipeline`]), for `pdw-sweep design`
//! and Python's `design`: the inputs checked and the model built ([`plan`]); the file and its
//! picture claimed, a stored search with the same settings continued, every design written as
//! it comes, the picture drawn ([`DesignCommand::run`]); the designs by status and the best one
//! reported ([`DesignReport`]). The search itself is [`crate::design`]'s.

use crate::design::{
    check_basin_box, check_basin_grid, check_budget, check_knee_margin, check_max_strides,
    check_min_margin, check_model, check_mu, check_starts, closest, from_data, measures,
    parse_objective, DesignPlan, COLUMNS,
};
use crate::input::InputError;
use crate::model::{BuiltModel, ModelChoice};
use crate::output::{Claim, Format, Output};
use crate::pipeline::{CommandError, Report, Sink, Spelling};
use pdw_limit::basin::BasinOptions;
use pdw_limit::design::{status, DesignEval, DesignOptions};
use pdw_store::{MarkerShape, Markers};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// `design`'s inputs as the user gave them (counts as signed integers: a negative one is
/// refused with its option named).
#[derive(Clone, Debug, PartialEq)]
pub struct DesignInput {
    pub model: ModelChoice,
    /// Free parameters, `NAME=LO:HI`.
    pub free: Vec<String>,
    /// `basin` or `margin`.
    pub objective: String,
    pub budget: i64,
    pub seed: u64,
    pub init: usize,
    pub starts: i64,
    pub mu: f64,
    pub knee_margin: f64,
    pub min_margin: f64,
    pub basin_grid: i64,
    pub basin_box: Option<[f64; 2]>,
    pub max_strides: i64,
    /// The design file (a rerun on it continues its search); `None`: none (Python).
    pub out: Option<PathBuf>,
    /// The picture; `None`: beside `out`, with `.png`.
    pub png: Option<PathBuf>,
    pub threads: usize,
    /// Start over on an existing `out`.
    pub force: bool,
    /// The command as run, for the file's provenance.
    pub command: String,
}

/// A checked `design`: the search's plan, the model with its own values, the settings a
/// stored search must match, the files.
pub struct DesignCommand {
    pub plan: DesignPlan,
    pub base: BuiltModel,
    pub settings: String,
    out: Option<PathBuf>,
    png: Option<PathBuf>,
    threads: usize,
    force: bool,
    command: String,
    spelling: Spelling,
}

/// Checks every input of `input` (naming options as `sp` spells them) and builds the model.
pub fn plan(input: &DesignInput, sp: Spelling) -> Result<DesignCommand, CommandError> {
    let f = |n: &str| sp.flag(n);
    let basin_box = match input.basin_box {
        Some(b) => Some(check_basin_box(
            &b,
            &format!("{},{}", b[0], b[1]),
            &f("basin_box"),
        )?),
        None => None,
    };
    let mut options = DesignOptions {
        objective: parse_objective(&input.objective, &f("objective"))?,
        mu: check_mu(input.mu, &f("mu"))?,
        knee_margin: check_knee_margin(input.knee_margin, &f("knee_margin"))?,
        min_margin: check_min_margin(input.min_margin, &f("min_margin"))?,
        budget: check_budget(input.budget, &f("budget"))?,
        seed: input.seed,
        start: None,
        init: input.init,
        basin_grid: check_basin_grid(input.basin_grid, &f("basin_grid"))?,
        basin_box,
        basin: BasinOptions {
            max_strides: check_max_strides(input.max_strides, &f("max_strides"))?,
            ..BasinOptions::default()
        },
        newton_tol: 1e-10,
    };
    let starts = check_starts(input.starts, &f("starts"))?;
    crate::input::check_threads(input.threads, &f("threads"))?;
    let base = crate::build_model(&input.model)?;
    check_model(&base, &f("model"))?;
    let space = crate::design::space(&input.model, &base, &input.free, &f("free"))?;
    options.start = Some(crate::design::start(&base, &space));
    let plan = DesignPlan {
        model: input.model.clone(),
        space,
        options,
        starts,
    };
    let settings = crate::design::settings(&plan, &base);
    let png = input
        .png
        .clone()
        .or_else(|| input.out.as_ref().map(|o| o.with_extension("png")));
    Ok(DesignCommand {
        plan,
        base,
        settings,
        out: input.out.clone(),
        png,
        threads: input.threads,
        force: input.force,
        command: input.command.clone(),
        spelling: sp,
    })
}

/// A search's result: every design in order (for a front end that returns them as arrays)
/// and the report.
pub struct DesignRun {
    pub designs: Vec<DesignEval>,
    pub report: DesignReport,
}

impl DesignCommand {
    /// Claims the files, continues a stored search of the same settings (else starts one),
    /// runs it on a pool of the plan's threads writing the whole file after every design, draws
    /// the picture and reports. Phases on `sink`: the designs of the budget.
    pub fn run(&self, sink: &dyn Sink) -> Result<DesignRun, CommandError> {
        let mut claim = self.claim()?;
        let stored = match (&self.out, &claim) {
            (Some(out), Some(c)) if c.existed(out) && !self.force => self.stored(out)?,
            _ => (Vec::new(), Vec::new()),
        };
        let n_stored = stored.0.len();
        let budget = self.plan.options.budget;
        sink.phase("designs", budget as u64, n_stored.min(budget) as u64);
        if let (Some(out), true) = (&self.out, n_stored > 0) {
            sink.say(&format!(
                "continuing {}: {n_stored} designs stored",
                out.display()
            ));
        }
        let designs = self.search(stored, claim.as_mut(), sink)?;
        sink.finish();
        if let Some(png) = &self.png {
            plot(png, &self.base, &self.plan, &designs).map_err(|e| InputError(e.to_string()))?;
        }
        let report = DesignReport::of(self, &designs, n_stored);
        Ok(DesignRun { designs, report })
    }

    /// The option named `name` as the front end spells it.
    fn flag(&self, name: &str) -> String {
        self.spelling.flag(name)
    }

    /// Claims `out` (an existing one continues its search unless `force`) and the picture
    /// (that search's, redrawn; a picture without its search is replaced only with `force`).
    fn claim(&self) -> Result<Option<Claim>, InputError> {
        let Some(out) = &self.out else {
            return Ok(None);
        };
        let continuing = out.is_file() && !self.force;
        let (out_flag, png_flag) = match self.spelling {
            Spelling::Cli => ("--out", "--png"),
            Spelling::Python => ("out", "png"),
        };
        let mut outputs = vec![Output {
            flag: out_flag,
            path: out,
            format: Format::Hdf5,
            may_exist: true,
        }];
        if let Some(png) = &self.png {
            outputs.push(Output {
                flag: png_flag,
                path: png,
                format: Format::Png,
                may_exist: continuing,
            });
        }
        let inputs: Vec<_> = crate::output::model_input(&self.plan.model.model)
            .into_iter()
            .collect();
        crate::output::claim(&outputs, &inputs, self.force).map(Some)
    }

    /// The designs of an existing `out` and the commands that made them, refused when its
    /// settings differ.
    fn stored(&self, out: &Path) -> Result<(Vec<DesignEval>, Vec<String>), InputError> {
        let io = |e: pdw_store::StoreError| InputError(e.to_string());
        let d = pdw_store::read_design(out, &COLUMNS).map_err(io)?;
        if d.settings != self.settings {
            return Err(InputError(settings_differ(
                &self.flag("out"),
                &self.flag("force"),
                out,
                &d.settings,
                &self.settings,
            )));
        }
        Ok((
            from_data(&d),
            pdw_store::read_design_commands(out).map_err(io)?,
        ))
    }

    /// Runs the search from the stored designs, writing the whole file (units, provenance,
    /// the earlier runs' commands) after every design and once more at the end (a run that
    /// replayed everything, e.g. a budget already met, still leaves a file).
    fn search(
        &self,
        (history, commands): (Vec<DesignEval>, Vec<String>),
        mut claim: Option<&mut Claim>,
        sink: &dyn Sink,
    ) -> Result<Vec<DesignEval>, CommandError> {
        let mut prov = crate::provenance(
            &self.command,
            &crate::design::run_options(&self.settings, self.threads),
        );
        prov.model_spec = crate::model::spec_toml(&self.plan.model.model).unwrap_or_default();
        let write = |out: &Path, hist: &[DesignEval]| {
            crate::design::write_file(
                out,
                (&self.plan, &self.base, &self.settings),
                hist,
                &prov,
                &commands,
            )
            .map_err(|e| InputError(e.to_string()))
        };
        let out_flag: &'static str = match self.spelling {
            Spelling::Cli => "--out",
            Spelling::Python => "out",
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(self.threads)
            .build()
            .map_err(|e| InputError(format!("{}: {e}", self.flag("threads"))))?;
        let mut all = history.clone();
        let mut best = all.iter().map(|e| e.cost).fold(f64::INFINITY, f64::min);
        let mut failed: Option<InputError> = None;
        let mut on_eval = |ev: &DesignEval| {
            all.push(ev.clone());
            if let (Some(out), Some(c), None) = (&self.out, claim.as_deref_mut(), &failed) {
                // each write replaces the file: the lock moves to the new one
                if let Err(e) = write(out, &all).and_then(|_| c.renew(out, out_flag)) {
                    failed = Some(e);
                }
            }
            best = best.min(ev.cost);
            sink.status(&format!("best cost {best:.4}"));
            sink.advance(1);
        };
        let hist = crate::design::search(&self.plan, &self.base, history, &pool, &mut on_eval)?;
        if let Some(e) = failed {
            return Err(e.into());
        }
        if let (Some(out), Some(c)) = (&self.out, claim) {
            write(out, &hist)?;
            c.renew(out, out_flag)?;
        }
        Ok(hist)
    }
}

/// Why a stored design search cannot be continued: the resolved model's first differing line
/// (a spec edited under the same parameter values), else both settings without the model.
fn settings_differ(out_flag: &str, force: &str, out: &Path, stored: &str, now: &str) -> String {
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
            "{out_flag}: '{}' holds a design search of a different model (stored: {}; now: \
             {}); pass {force} to start over or give another {out_flag}",
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
        "{out_flag}: '{}' holds a design search with other settings (stored: {s}; now: {n}); \
         pass {force} to start over or give another {out_flag}",
        out.display()
    )
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
/// by its status (a legend entry per status present).
fn plot(
    png: &Path,
    base: &BuiltModel,
    plan: &DesignPlan,
    hist: &[DesignEval],
) -> Result<(), pdw_store::StoreError> {
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
    pdw_store::plot_lines_marked(
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
    )
}

/// The designs of each status.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StatusCounts {
    pub feasible: usize,
    pub invalid: usize,
    pub unstable: usize,
    pub no_gait: usize,
    pub not_a_model: usize,
}

/// The best design (the smallest cost), or when nothing is feasible the closest one.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BestDesign {
    /// The free parameters' values by name.
    pub params: serde_json::Map<String, serde_json::Value>,
    /// Its place among the designs.
    pub index: usize,
    /// Its status by name (`feasible`, `invalid`, …) and whether it is feasible.
    pub status: &'static str,
    pub feasible: bool,
    pub reason: String,
    /// Its gait's section state (NaN without a gait).
    pub section: [f64; 3],
    /// Every measure of [`COLUMNS`] by name (null where not defined: no knees, no gait).
    #[serde(flatten)]
    pub measures: serde_json::Map<String, serde_json::Value>,
    /// The criterion with the smallest relative margin, and the gait search's fates.
    pub binding: String,
    pub fates: String,
    /// When nothing is feasible: what keeps the closest design from being feasible.
    pub closest_because: Option<String>,
    /// A feasible best design on a face of the box: the warnings naming the bound.
    pub on_bound: Vec<String>,
    /// The command line that finds its gait.
    pub reproduce: String,
    /// The free parameters' values, in order (for the text: `params` holds them by name).
    #[serde(skip)]
    values: Vec<f64>,
}

/// `design`'s report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DesignReport {
    pub model: String,
    pub objective: &'static str,
    pub free_names: Vec<String>,
    /// Designs in all, and how many of them this run evaluated.
    pub designs: usize,
    pub new: usize,
    pub starts: usize,
    pub counts: StatusCounts,
    /// The margin every criterion needs (relative).
    pub min_margin: f64,
    pub best: Option<BestDesign>,
    pub out: Option<PathBuf>,
    pub png: Option<PathBuf>,
}

impl DesignReport {
    fn of(c: &DesignCommand, hist: &[DesignEval], stored: usize) -> Self {
        let count = |s: u8| hist.iter().filter(|e| e.status == s).count();
        let plan = &c.plan;
        let best = closest(hist, plan.options.min_margin).map(|(b, why)| {
            let names = &plan.space.names;
            let sets: Vec<String> = names
                .iter()
                .zip(&b.params)
                .map(|(n, v)| format!("--set {n}={v}"))
                .collect();
            BestDesign {
                params: names
                    .iter()
                    .zip(&b.params)
                    .map(|(n, v)| (n.clone(), serde_json::json!(v)))
                    .collect(),
                index: hist.iter().position(|e| std::ptr::eq(e, b)).unwrap_or(0),
                status: status::NAMES[b.status as usize],
                feasible: b.feasible(),
                reason: b.reason.clone(),
                section: b.section,
                measures: COLUMNS
                    .iter()
                    .zip(measures(b))
                    .map(|(n, v)| (n.to_string(), serde_json::json!(v)))
                    .collect(),
                binding: b.binding.clone(),
                fates: b.fates.clone(),
                closest_because: why,
                on_bound: if b.feasible() {
                    crate::design::bound_warnings(&plan.space, &b.params)
                } else {
                    Vec::new()
                },
                reproduce: format!(
                    "pdw-sweep fixedpoint --model {} {}",
                    plan.model.model,
                    sets.join(" ")
                ),
                values: b.params.clone(),
            }
        });
        DesignReport {
            model: c.base.info.name.to_string(),
            objective: plan.options.objective.name(),
            free_names: plan.space.names.clone(),
            designs: hist.len(),
            new: hist.len() - stored.min(hist.len()),
            starts: plan.starts,
            counts: StatusCounts {
                feasible: count(status::FEASIBLE),
                invalid: count(status::INVALID),
                unstable: count(status::UNSTABLE),
                no_gait: count(status::NO_GAIT),
                not_a_model: count(status::BAD_MODEL),
            },
            min_margin: plan.options.min_margin,
            best,
            out: c.out.clone(),
            png: c.png.clone(),
        }
    }

    /// The best design is feasible (the CLI exits 1 when it is not).
    pub fn feasible(&self) -> bool {
        self.best.as_ref().is_none_or(|b| b.feasible)
    }
}

impl Report for DesignReport {
    fn text(&self) -> String {
        let c = &self.counts;
        let mut t = format!(
            "{} designs ({} new) from {} start{}: {} feasible, {} invalid, {} unstable, {} \
             without a gait, {} not a model\n",
            self.designs,
            self.new,
            self.starts,
            if self.starts == 1 { "" } else { "s" },
            c.feasible,
            c.invalid,
            c.unstable,
            c.no_gait,
            c.not_a_model
        );
        if let Some(b) = &self.best {
            best_text(&mut t, b, self.min_margin);
        }
        let files: Vec<String> = self
            .out
            .iter()
            .chain(&self.png)
            .map(|p| p.display().to_string())
            .collect();
        if self.best.is_some() && !files.is_empty() {
            t += &format!("  written: {}\n", files.join(", "));
        }
        t
    }
}

/// A finite measure of the best design by name.
fn measure(b: &BestDesign, name: &str) -> f64 {
    b.measures
        .get(name)
        .and_then(|v| v.as_f64())
        .unwrap_or(f64::NAN)
}

/// The best design's lines: status and cost, why it is the closest, its gait, its binding
/// margin, its parameters and the command that reproduces its gait.
fn best_text(t: &mut String, b: &BestDesign, min_margin: f64) {
    let (fraction, rho) = (measure(b, "basin_fraction"), measure(b, "rho"));
    *t += &format!(
        "{}: {} (cost {:.6}{}{}) {}\n",
        if b.feasible {
            "best"
        } else {
            "no feasible design; closest"
        },
        b.status,
        measure(b, "cost"),
        if fraction.is_finite() {
            format!(", basin fraction {fraction:.4}")
        } else {
            String::new()
        },
        if rho.is_finite() {
            format!(", max |λ| {rho:.4}")
        } else {
            String::new()
        },
        b.reason
    );
    if let Some(why) = &b.closest_because {
        *t += &format!("  closest because: {why}\n");
    }
    if b.section.iter().all(|v| v.is_finite()) {
        let gait: Vec<String> = b.section.iter().map(|v| format!("{v:.6}")).collect();
        // a model without knees has no knee torque (NaN): the clause is left out
        let knee = measure(b, "min_knee_torque");
        let knee = if knee.is_finite() {
            format!(", min knee torque {knee:.4} N m")
        } else {
            String::new()
        };
        *t += &format!(
            "  gait ({}){knee}, min normal force {:.3} N, friction needed {:.4}\n",
            gait.join(", "),
            measure(b, "min_normal_force"),
            measure(b, "max_friction")
        );
    } else {
        *t += "  no gait\n";
    }
    let margin = measure(b, "min_relative_margin");
    if margin.is_finite() {
        *t += &format!(
            "  smallest relative margin {margin:.4} ({}; required {min_margin})\n",
            b.binding
        );
    }
    let values: Vec<String> = b
        .params
        .keys()
        .zip(&b.values)
        .map(|(n, v)| format!("{n} = {v}"))
        .collect();
    *t += &format!("  parameters: {}\n", values.join(", "));
    *t += &format!("  reproduce: {}\n", b.reproduce);
}
