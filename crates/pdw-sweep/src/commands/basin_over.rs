//! `pdw-sweep basin --over NAME=A:B:N`: basin stability over a model parameter (Menck, Heitzig,
//! Marwan & Kurths, "How basin stability complements the linear-stability paradigm", Nature
//! Physics 9, 89–92, 2013): at each of N evenly spaced values of the parameter, the fraction of
//! one fixed box of section states that reaches each attractor, falls, or neither.
//!
//! Every value is classified exactly as a plain `basin` run on the same box classifies it (the
//! same attractor discovery, [`super::basin::box_attractors`], the same engine and options), so
//! the fractions at a value equal that run's. The box is the same at every value: `--x`/`--y`,
//! else the default box of `basin` around the gait at A (stated in the output).

use super::basin::{box_attractors, check_memory, default_axis, split_sets};
use super::fixedpoint::search;
use super::output::{Format, Output};
use super::{build_with, BuiltModel};
use crate::args::{self, AxisRange, InputError};
use crate::cli::BasinArgs;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use pdw_limit::basin::{classify_cells, grid_cells, BasinOptions, Outcome};
use pdw_limit::{AttractorKind, AttractorSet};
use pdw_store::{StabilityAttractor, StabilityData};
use std::io::IsTerminal;
use std::process::ExitCode;
use std::time::Instant;

/// Default grid of `--over`: 41 × 41 cells per value.
pub const DEFAULT_OVER_GRID: &str = "41x41";

/// The column an outcome code counts in: an attractor's name (the gait, codes ≥ 10), `fall`
/// (every fall kind), `timeout`, or `other` (an orbit no attractor of the set explains, a
/// non-finite state, an integrator failure).
fn column_of(code: u8, set: &AttractorSet) -> (String, &'static str) {
    if let Some(a) = set.attractors.iter().find(|a| a.code == code) {
        return (a.name.clone(), "attractor");
    }
    match Outcome::from_code(code) {
        Some(o) if o.is_fall() => ("fall".into(), "fall"),
        Some(Outcome::Timeout) => ("timeout".into(), "timeout"),
        _ => ("other".into(), "other"),
    }
}

/// One parameter value's result.
struct AtValue {
    /// `(column, kind, fraction)` in the order met.
    fractions: Vec<(String, &'static str, f64)>,
    /// Fractions of the fixed outcome codes (before attractors are told apart).
    outcomes: Vec<f64>,
    attractors: Vec<StabilityAttractor>,
}

pub fn run(a: &BasinArgs) -> anyhow::Result<ExitCode> {
    let t0 = Instant::now();
    let over = args::parse_range_count(a.over.as_deref().unwrap_or_default(), "--over")?;
    for (given, flag) in [(a.resume, "--resume"), (a.shard.is_some(), "--shard")] {
        if given {
            return Err(InputError(format!(
                "{flag}: `basin --over` writes one small file whole; it has no shards or \
                 resumable blocks (drop {flag})"
            ))
            .into());
        }
    }
    let (nx, ny) = args::parse_grid(a.grid.as_deref().unwrap_or(DEFAULT_OVER_GRID))?;
    if a.max_strides == 0 || a.max_strides > u32::from(u16::MAX) {
        return Err(InputError(format!(
            "--max-strides: {} must be between 1 and {}",
            a.max_strides,
            u16::MAX
        ))
        .into());
    }
    let integrator = super::integrator(&a.integrator, BasinOptions::default_integrator())?;
    let info = pdw_walkers::model_info(&a.model.model).map_err(|e| InputError(e.to_string()))?;
    let names_owned = info.section_names.clone();
    let names: Vec<&str> = names_owned.iter().map(|s| s.as_str()).collect();
    let names = &names[..];
    if names.len() < 2 {
        return Err(InputError(format!(
            "model '{}' has one section coordinate ({}); a basin box needs two",
            info.name,
            names.join(", ")
        ))
        .into());
    }
    check_memory(nx, ny, names.len(), info.state_names.len())?;
    let (param_sets, fixed) = split_sets(a, names)?;
    if let Some((_, v)) = param_sets.iter().find(|(n, _)| *n == over.name) {
        return Err(InputError(format!(
            "--over {}: the parameter is also set to {v} (--slope or --set); give it once",
            over.name
        ))
        .into());
    }
    if !info.params.iter().any(|p| p.name == over.name) {
        return Err(InputError(format!(
            "--over: model '{}' has no parameter '{}'; its parameters are {}",
            info.name,
            over.name,
            info.params
                .iter()
                .map(|p| p.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ))
        .into());
    }
    let out = a.out_path();
    let png = a.png.clone().unwrap_or_else(|| out.with_extension("png"));
    let inputs: Vec<_> = super::output::model_input(&a.model.model)
        .into_iter()
        .collect();
    let _claim = super::output::claim(
        &[
            Output {
                flag: "--out",
                path: &out,
                format: Format::Hdf5,
                may_exist: false,
            },
            Output {
                flag: "--png",
                path: &png,
                format: Format::Png,
                may_exist: false,
            },
        ],
        &inputs,
        a.force,
    )?;
    let values = pdw_limit::basin::linspace(over.lo, over.hi, over.n);
    let plain = crate::cli::ModelOpts {
        model: a.model.model.clone(),
        slope: None,
        set: Vec::new(),
    };
    // Every value must build (a bad value is refused before anything is computed).
    let models: Vec<BuiltModel> = values
        .iter()
        .map(|&mu| {
            let mut sets = param_sets.clone();
            sets.push((over.name.clone(), mu));
            build_with(&plain, &sets)
        })
        .collect::<Result<_, _>>()?;
    let axis =
        |opt: &Option<String>, flag: &str| -> Result<Option<(usize, AxisRange)>, InputError> {
            let Some(s) = opt else { return Ok(None) };
            let r = args::parse_axis(s, flag)?;
            let i = names.iter().position(|n| *n == r.name).ok_or_else(|| {
                InputError(format!(
                    "{flag}: model '{}' has no section coordinate '{}'; its coordinates are {}",
                    info.name,
                    r.name,
                    names.join(", ")
                ))
            })?;
            Ok(Some((i, r)))
        };
    let xa = axis(&a.x, "--x")?;
    let ya = axis(&a.y, "--y")?;
    let guesses = |m: &BuiltModel| pdw::gaits::model_guesses(m.walker.as_ref());
    // ---- the box: --x/--y, else basin's default box around the gait at A, for every value
    let (found_a, _) = search(&models[0], &guesses(&models[0]), 1e-12)?;
    let centre_a: Option<Vec<f64>> = pdw::gaits::selected(&found_a).map(|f| f.fp.section.clone());
    let box_source = match (&xa, &ya) {
        (Some(_), Some(_)) => "--x and --y".to_string(),
        _ => match &centre_a {
            Some(_) => format!(
                "the default basin box around the period-one gait at {} = {} (fixed for every \
                 value)",
                over.name, over.lo
            ),
            None => {
                return Err(InputError(format!(
                    "--over: no period-one gait of model '{}' at {} = {} to centre the default \
                     box on; give both --x and --y",
                    info.name, over.name, over.lo
                ))
                .into())
            }
        },
    };
    let centre_a = centre_a.unwrap_or_else(|| {
        guesses(&models[0])
            .first()
            .map(|g| g.1.clone())
            .unwrap_or_else(|| vec![0.0; names.len()])
    });
    let (ix, xr) = xa.unwrap_or_else(|| (0, default_axis(names[0], centre_a[0])));
    let (iy, yr) = ya.unwrap_or_else(|| (1, default_axis(names[1], centre_a[1])));
    if ix == iy {
        return Err(InputError(format!(
            "--x and --y both name '{}'; choose two different coordinates",
            names[ix]
        ))
        .into());
    }
    for (i, _) in &fixed {
        if *i == ix || *i == iy {
            return Err(InputError(format!(
                "--set {}: that coordinate is an axis of the box",
                names[*i]
            ))
            .into());
        }
    }
    let xs = pdw_limit::basin::linspace(xr.lo, xr.hi, nx);
    let ys = pdw_limit::basin::linspace(yr.lo, yr.hi, ny);
    let opts = BasinOptions {
        max_strides: a.max_strides as u16,
        integrator,
        ..BasinOptions::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads)
        .build()?;
    let total = (values.len() * nx * ny) as u64;
    let pb = if a.quiet || !std::io::stderr().is_terminal() {
        ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden())
    } else {
        ProgressBar::new(total)
    };
    pb.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{wide_bar}] {pos}/{len} cells  {msg}  ETA {eta}",
        )
        .expect("valid template"),
    );
    let fall = Outcome::of_fall;
    let mut results: Vec<AtValue> = Vec::with_capacity(values.len());
    for (mu, m) in values.iter().zip(&models) {
        pb.set_message(format!("{} = {mu}", over.name));
        let walker = m.walker.as_ref();
        let (found, _) = search(m, &guesses(m), 1e-12)?;
        let gait = found.iter().find(|f| f.fp.stable).map(|f| &f.fp);
        // The coordinates off the box's axes: at this value's gait, as `basin` takes them.
        let mut base = gait
            .map(|fp| fp.section.clone())
            .or_else(|| found.first().map(|f| f.fp.section.clone()))
            .unwrap_or_else(|| centre_a.clone());
        for (i, v) in &fixed {
            base[*i] = *v;
        }
        let (set, _) = box_attractors(
            walker,
            &found,
            gait,
            &fixed,
            &base,
            (ix, &xr),
            (iy, &yr),
            &opts,
            &pool,
        )?;
        // As `basin` warns: cells near a slowly attracting orbit need more strides than given.
        for at in set
            .attractors
            .iter()
            .filter(|at| at.kind == AttractorKind::Periodic)
        {
            if let Some(lmax) = at.multipliers.first().map(|l| l.modulus()) {
                let needed = (at.period_k as f64 * (1e-4f64).ln() / lmax.ln()).ceil();
                if lmax < 1.0 && needed > f64::from(a.max_strides) {
                    pb.suspend(|| {
                        eprintln!(
                            "warning: {} = {mu}: attractor `{}` has |λ| = {lmax:.4} per {} \
                             stride(s); cells converge in about {needed} strides, more than \
                             --max-strides {}: expect `timeout` there",
                            over.name, at.name, at.period_k, a.max_strides
                        )
                    });
                }
            }
        }
        let problem = set.problem(walker, &fall);
        let cells = grid_cells(&base, ix, &xs, iy, &ys);
        let done = pb.position();
        let mut res = classify_cells(&problem, &cells, &opts, &pool, &|k| {
            pb.set_position(done + k as u64)
        })?;
        let n = res.len() as f64;
        // Counts, then fractions (count / n, as `basin`'s metrics compute them).
        let mut counts = [0usize; 256];
        for c in &res {
            counts[c.outcome as usize] += 1;
        }
        let outcomes: Vec<f64> = Outcome::ALL
            .iter()
            .map(|o| counts[o.code() as usize] as f64 / n)
            .collect();
        set.relabel(&mut res);
        let mut counts = [0usize; 256];
        for c in &res {
            counts[c.outcome as usize] += 1;
        }
        let mut fractions: Vec<(String, &'static str, usize)> = set
            .attractors
            .iter()
            .map(|at| (at.name.clone(), "attractor", 0))
            .collect();
        for (code, &k) in counts.iter().enumerate().filter(|(_, k)| **k > 0) {
            let (name, kind) = column_of(code as u8, &set);
            match fractions.iter_mut().find(|(n, _, _)| *n == name) {
                Some(e) => e.2 += k,
                None => fractions.push((name, kind, k)),
            }
        }
        results.push(AtValue {
            fractions: fractions
                .into_iter()
                .map(|(name, kind, k)| (name, kind, k as f64 / n))
                .collect(),
            outcomes,
            attractors: set
                .attractors
                .iter()
                .map(|at| StabilityAttractor {
                    name: at.name.clone(),
                    period_strides: if at.kind == AttractorKind::Chaotic {
                        0
                    } else {
                        at.period_k as u32
                    },
                    period_time: at.period_time.is_finite().then_some(at.period_time),
                    points: at.points.clone(),
                    multipliers: at.multipliers.iter().map(|l| [l.re, l.im]).collect(),
                })
                .collect(),
        });
    }
    pb.finish_and_clear();

    // ---- columns: every attractor met (in order met), then fall, timeout, other
    let mut columns: Vec<(String, &'static str)> = Vec::new();
    for r in &results {
        for (name, kind, _) in r.fractions.iter().filter(|c| c.1 == "attractor") {
            if !columns.iter().any(|(n, _)| n == name) {
                columns.push((name.clone(), kind));
            }
        }
    }
    for (n, k) in [("fall", "fall"), ("timeout", "timeout"), ("other", "other")] {
        columns.push((n.into(), k));
    }
    let fractions: Vec<Vec<f64>> = results
        .iter()
        .map(|r| {
            columns
                .iter()
                .map(|(c, _)| {
                    r.fractions
                        .iter()
                        .find(|(n, _, _)| n == c)
                        .map_or(0.0, |f| f.2)
                })
                .collect()
        })
        .collect();
    let unit = super::param_unit(&models[0], &over.name);
    let sec_units = super::section_units(&models[0]);
    let box_json = serde_json::json!({
        "x": {"name": names[ix], "lo": xr.lo, "hi": xr.hi, "n": nx, "unit": sec_units[ix]},
        "y": {"name": names[iy], "lo": yr.lo, "hi": yr.hi, "n": ny, "unit": sec_units[iy]},
        "fixed": fixed.iter().map(|(i, v)| (names[*i].to_string(), *v)).collect::<std::collections::BTreeMap<_, _>>(),
        "off_axis": "other section coordinates at each value's period-one gait (else --set)",
        "source": box_source,
    });
    let options = serde_json::json!({
        "integrator": super::integrator_json(&opts.integrator),
        "max_strides": opts.max_strides,
        "tol_gait": opts.tol_gait,
        "confirm": opts.confirm,
        "tol_recur": opts.tol_recur,
        "max_period": opts.max_period,
        "grid": [nx, ny],
        "over": {"name": over.name, "from": over.lo, "to": over.hi, "n": over.n, "unit": unit},
        "threads": a.threads,
    });
    let mut params = models[0].params_json();
    if let Some(o) = params.as_object_mut() {
        o.remove(&over.name);
    }
    let elapsed = t0.elapsed().as_secs_f64();
    let data = StabilityData {
        command: super::command_line(),
        model: info.name.to_string(),
        parameter: over.name.clone(),
        params: params.to_string(),
        box_json: box_json.to_string(),
        max_strides: a.max_strides,
        values: values.clone(),
        columns: columns.iter().map(|c| c.0.clone()).collect(),
        kinds: columns.iter().map(|c| c.1.to_string()).collect(),
        fractions,
        outcome_columns: Outcome::ALL.iter().map(|o| o.name().to_string()).collect(),
        outcome_fractions: results.iter().map(|r| r.outcomes.clone()).collect(),
        attractors: results.iter().map(|r| r.attractors.clone()).collect(),
        settings: vec![("options".into(), options.to_string())],
        elapsed_s: elapsed,
    };
    // the claim refused an existing file without --force; its placeholder is replaced
    pdw_store::write_stability(&out, true, &data)?;
    let prov = super::provenance(options);
    let pu = unit.clone();
    let units = move |p: &str| -> Option<String> {
        match p {
            "parameter" => Some(pu.clone()),
            "fractions" | "outcome_fractions" => Some("1".into()),
            _ => None,
        }
    };
    pdw_store::annotate(
        &out,
        &pdw_store::Annotations {
            provenance: Some(&prov),
            units: &units,
            slice: None,
            scales: &[],
        },
    )?;
    let title = format!(
        "{} walker: basin stability, {nx}x{ny} box {} x {}",
        info.name, names[ix], names[iy]
    );
    pdw_store::plot_basin_stability(&png, &data, &format!("{} [{unit}]", over.name), &title)?;
    if a.json {
        let j = serde_json::json!({
            "model": data.model,
            "parameter": data.parameter,
            "parameter_unit": unit,
            "params": params,
            "box": box_json,
            "max_strides": a.max_strides,
            "columns": data.columns,
            "kinds": data.kinds,
            "values": values.iter().zip(&data.fractions).zip(&data.attractors).map(|((mu, f), ats)| serde_json::json!({
                "param": mu,
                "fractions": data.columns.iter().cloned().zip(f.iter().map(|x| serde_json::json!(x))).collect::<serde_json::Map<String, serde_json::Value>>(),
                "attractors": ats,
            })).collect::<Vec<_>>(),
            "outcome_columns": data.outcome_columns,
            "outcome_fractions": data.outcome_fractions,
            "elapsed_s": elapsed,
            "files": {"hdf5": out.display().to_string(), "png": png.display().to_string()},
        });
        crate::outln!("{}", serde_json::to_string_pretty(&j)?);
        return Ok(ExitCode::SUCCESS);
    }
    crate::outln!(
        "basin stability of the {} walker over {} = {} .. {} {unit} ({} values), box {} = \
         {}..{} x {} = {}..{} ({nx}x{ny} cells; {box_source}), up to {} strides:",
        info.name,
        over.name,
        over.lo,
        over.hi,
        over.n,
        names[ix],
        xr.lo,
        xr.hi,
        names[iy],
        yr.lo,
        yr.hi,
        a.max_strides
    );
    crate::outln!(
        "  {:>14}{}",
        over.name,
        data.columns
            .iter()
            .map(|c| format!("{c:>12}"))
            .collect::<String>()
    );
    for (mu, f) in values.iter().zip(&data.fractions) {
        crate::outln!(
            "  {mu:>14.6}{}",
            f.iter().map(|x| format!("{x:>12.4}")).collect::<String>()
        );
    }
    crate::outln!(
        "  wrote {} and {} in {:.2} s ({} thread(s))",
        out.display(),
        png.display(),
        elapsed,
        a.threads
    );
    Ok(ExitCode::SUCCESS)
}
