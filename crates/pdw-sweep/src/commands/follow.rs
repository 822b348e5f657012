//! `pdw-sweep fixedpoint --follow pd|fold --sweep NAME=A:B:N --free NAME[=LO:HI]`: the curve of
//! period doublings or folds of the period-one gait in two parameters
//! ([`pdw_limit::codim2`]).
//!
//! 1. The period-one gait at `NAME = A` and the model's value of the free parameter (Newton from
//!    `--guess` or the model's presets there; failing that, the gait at the model's own values
//!    continued in the stepped parameter to A).
//! 2. One-parameter continuation of that gait in the free parameter (pseudo-arclength, within
//!    LO:HI, up first, then down) to its first bifurcation of the kind asked for, located there.
//! 3. The two-parameter curve through it over the N values A..B ([`follow_curve`]).
//! 4. `--png`: a region map of the plane under the curve ([`region_map`]).

use super::output::{Format, Output};
use super::{build_model, build_with, BuiltModel};
use crate::args::{self, InputError};
use crate::cli::FixedpointArgs;
use pdw_hybrid::Options;
use pdw_limit::{
    continue_branch, find_fixed_point, follow_curve, region_map, BifurcationKind, Codim2Kind,
    Codim2Options, ContinuationOptions, Curve, CurveEnd, CurveStart, NewtonOptions, Region,
    RegionOptions, StrideMap,
};
use pdw_store::{CurveData, RegionMap};
use std::process::ExitCode;

/// Default `--map-grid`.
const MAP_GRID: &str = "40x40";

/// The free parameter: its name and its domain (if given).
struct Free {
    name: String,
    range: Option<(f64, f64)>,
}

fn parse_free(s: &str) -> Result<Free, InputError> {
    let Some((name, range)) = s.split_once('=') else {
        let name = s.trim();
        if name.is_empty() {
            return Err(InputError("--free: empty parameter name".into()));
        }
        return Ok(Free {
            name: name.to_string(),
            range: None,
        });
    };
    let name = name.trim().to_string();
    let Some((lo, hi)) = range.split_once(':') else {
        return Err(InputError(format!(
            "--free: '{s}' is not of the form NAME or NAME=LO:HI (e.g. slope=2deg:8deg)"
        )));
    };
    let conv = |t: &str| {
        if name == "slope" {
            args::parse_slope_for(t, "--free slope")
        } else {
            args::parse_f64(t, &format!("--free {name}"))
        }
    };
    let (lo, hi) = (conv(lo)?, conv(hi)?);
    if lo >= hi {
        return Err(InputError(format!(
            "--free: range {lo}:{hi} is empty or inverted; LO must be below HI"
        )));
    }
    Ok(Free {
        name,
        range: Some((lo, hi)),
    })
}

fn value_of(m: &BuiltModel, name: &str) -> Option<f64> {
    m.params.iter().find(|(n, _)| n == name).map(|p| p.1)
}

fn unknown(m: &BuiltModel, flag: &str, name: &str) -> InputError {
    InputError(format!(
        "{flag}: model '{}' has no parameter '{name}'; its parameters are {}",
        m.info.name,
        m.params
            .iter()
            .map(|(n, _)| n.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    ))
}

pub fn run(a: &FixedpointArgs) -> anyhow::Result<ExitCode> {
    let out = a.out_path();
    let kind =
        match a.follow.as_deref() {
            None => return Err(InputError(
                "--free and --map-grid belong to --follow pd|fold (the bifurcation to follow in \
                 two parameters); add --follow"
                    .into(),
            )
            .into()),
            Some("pd") => Codim2Kind::PeriodDoubling,
            Some("fold") => Codim2Kind::Fold,
            Some("ns") => {
                return Err(InputError(
                    "--follow ns: not supported: Neimark-Sacker curves (a complex pair of \
                 multipliers on the unit circle) are not implemented; --follow takes pd or fold"
                        .into(),
                )
                .into())
            }
            Some(other) => {
                return Err(InputError(format!(
                    "--follow: '{other}' is not one of pd (period doubling), fold"
                ))
                .into())
            }
        };
    if a.csv.is_some() {
        return Err(InputError(
            "--csv: a --follow curve is written to --out (HDF5) and printed by --json; --csv \
             belongs to a one-parameter --sweep"
                .into(),
        )
        .into());
    }
    let threads = a.threads.unwrap_or(2);
    let Some(sweep) = a.sweep.as_deref() else {
        return Err(InputError(
            "--follow needs --sweep NAME=A:B:N: the stepped parameter and the N points of the \
             curve (e.g. --sweep hip_mass=2:20:10)"
                .into(),
        )
        .into());
    };
    let Some(free_text) = a.free.as_deref() else {
        return Err(InputError(
            "--follow needs --free NAME: the parameter solved for along the curve (e.g. --free \
             slope)"
                .into(),
        )
        .into());
    };
    if a.period != 1 {
        return Err(InputError(format!(
            "--period {} with --follow: the curve follows a bifurcation of the period-one gait; \
             drop --period",
            a.period
        ))
        .into());
    }
    if !(super::fixedpoint::MIN_TOL..=super::fixedpoint::MAX_TOL).contains(&a.tol) {
        return Err(InputError(format!(
            "--tol: {} is outside [{:e}, {:e}]",
            a.tol,
            super::fixedpoint::MIN_TOL,
            super::fixedpoint::MAX_TOL
        ))
        .into());
    }
    if !matches!(a.gait.as_str(), "stable" | "unstable" | "all") {
        return Err(InputError(format!(
            "--gait: '{}' is not one of stable, unstable, all",
            a.gait
        ))
        .into());
    }
    let sw = args::parse_sweep(sweep)?;
    let free = parse_free(free_text)?;
    if free.name == sw.name {
        return Err(InputError(format!(
            "--free {} and --sweep {}: the same parameter; the curve needs two different \
             parameters (one stepped, one solved for)",
            free.name, sw.name
        ))
        .into());
    }
    if a.map_grid.is_some() && a.png.is_none() {
        return Err(InputError(
            "--map-grid: the region map is drawn only into --png; give --png FILE".into(),
        )
        .into());
    }
    let (nx, ny) = args::parse_grid_for("--map-grid", a.map_grid.as_deref().unwrap_or(MAP_GRID))?;
    if nx < 2 || ny < 2 || nx * ny > 250_000 {
        return Err(InputError(format!(
            "--map-grid: {nx}x{ny}: need at least 2 cells per side and at most 250000 cells \
             (each cell iterates the stride map a few hundred times)"
        ))
        .into());
    }
    let m_own = build_model(&a.model)?;
    let step_own =
        value_of(&m_own, &sw.name).ok_or_else(|| unknown(&m_own, "--sweep", &sw.name))?;
    let free0 =
        value_of(&m_own, &free.name).ok_or_else(|| unknown(&m_own, "--free", &free.name))?;
    let (lo, hi) = match free.range {
        Some(r) => r,
        None if free0 > 0.0 => {
            let hi = 4.0 * free0;
            let hi = if free.name == "slope" {
                hi.min(1.2)
            } else {
                hi
            };
            (0.25 * free0, hi)
        }
        None => {
            return Err(InputError(format!(
                "--free {}: the model's value {free0} is not positive, so there is no default \
                 range; give one: --free {}=LO:HI",
                free.name, free.name
            ))
            .into())
        }
    };
    if !(lo..=hi).contains(&free0) {
        return Err(InputError(format!(
            "--free {}={lo}:{hi}: the model's value {free0} (where the one-parameter search \
             starts) lies outside; set it inside with --set {}=VALUE{}",
            free.name,
            free.name,
            if free.name == "slope" {
                " or --slope"
            } else {
                ""
            }
        ))
        .into());
    }
    let outputs = [
        Some(Output {
            flag: "--out",
            path: &out,
            format: Format::Hdf5,
            may_exist: false,
        }),
        a.png.as_deref().map(|p| Output {
            flag: "--png",
            path: p,
            format: Format::Png,
            may_exist: false,
        }),
    ];
    let outputs: Vec<Output<'_>> = outputs.into_iter().flatten().collect();
    let inputs: Vec<_> = super::output::model_input(&a.model.model)
        .into_iter()
        .collect();
    let _claim = super::output::claim(&outputs, &inputs, a.force)?;
    let at = |ps: f64, pf: f64| -> Result<BuiltModel, InputError> {
        build_with(&a.model, &[(sw.name.clone(), ps), (free.name.clone(), pf)])
    };
    // Every corner of the region must be a valid model.
    for (ps, pf) in [(sw.lo, lo), (sw.lo, hi), (sw.hi, lo), (sw.hi, hi)] {
        at(ps, pf).map_err(|e| {
            InputError(format!(
                "{e} (at {} = {ps}, {} = {pf}: the corners of --sweep and --free must be valid \
                 parameter values)",
                sw.name, free.name
            ))
        })?;
    }
    let integrator = super::integrator(&a.integrator, Options::dop853(1e-13))?;
    let fam2 = |ps: f64, pf: f64| at(ps, pf).map(|m| m.walker);
    let t0 = std::time::Instant::now();

    // 1. The gait at (A, free0).
    let m_a = at(sw.lo, free0)?;
    let Some(gait) = start_gait(a, &m_a, &m_own, &sw.name, step_own, sw.lo, &integrator)? else {
        return Ok(ExitCode::from(2));
    };

    // 2. The bifurcation in the free parameter at A.
    let fam1 = |pf: f64| at(sw.lo, pf).map(|m| m.walker);
    let mut copts = ContinuationOptions::new(lo, hi);
    copts.integrator = integrator;
    copts.stop_at = Some(match kind {
        Codim2Kind::PeriodDoubling => BifurcationKind::PeriodDoubling,
        Codim2Kind::Fold => BifurcationKind::Fold,
    });
    copts.ds_max = (hi - lo) / 100.0;
    copts.ds_init = copts.ds_max / 10.0;
    copts.ds_min = (hi - lo) * 1e-9;
    copts.max_points = 5000;
    copts.locate_tol = 1e-10 * free0.abs().max(1.0);
    let mut ends = Vec::new();
    let mut bif = None;
    for dir in [1.0, -1.0] {
        copts.direction = dir;
        match continue_branch(&fam1, &gait, free0, 1, &copts) {
            Ok(br) => {
                if let Some(b) = br
                    .bifurcations
                    .iter()
                    .find(|b| Some(b.kind) == copts.stop_at)
                {
                    bif = Some(b.clone());
                    break;
                }
                ends.push(format!(
                    "{}: {:?}",
                    if dir > 0.0 { "up" } else { "down" },
                    br.end
                ));
            }
            Err(e) => ends.push(format!("{}: {e}", if dir > 0.0 { "up" } else { "down" })),
        }
    }
    let Some(bif) = bif else {
        eprintln!(
            "error: no {} of the period-one gait on {} in [{lo}, {hi}] at {} = {} (the branch \
             from {} = {free0} ended {})",
            kind_long(kind),
            free.name,
            sw.name,
            sw.lo,
            free.name,
            ends.join("; ")
        );
        eprintln!(
            "try: another --free range (NAME=LO:HI), another start of --sweep, or the other \
             gait (--gait)"
        );
        return Ok(ExitCode::from(2));
    };

    // 3. The curve.
    let steps = pdw_limit::basin::linspace(sw.lo, sw.hi, sw.n);
    let mut o2 = Codim2Options::new(lo, hi);
    o2.integrator = integrator;
    o2.newton_tol = a.tol.max(1e-11);
    let curve = follow_curve(
        &fam2,
        kind,
        &CurveStart::from_bifurcation(&bif),
        &steps,
        &o2,
    )?;

    // 4. The region map.
    let ropts = RegionOptions::default();
    let map = match (&a.png, curve.points.is_empty()) {
        (Some(_), false) => Some(compute_map(
            &fam2,
            &curve,
            (sw.lo, sw.hi),
            (nx, ny),
            free.range.unwrap_or_else(|| auto_range(&curve, lo, hi)),
            &ropts,
            (threads, a.quiet),
        )?),
        (Some(_), true) => {
            eprintln!("warning: no curve point, so no region map is drawn");
            None
        }
        _ => None,
    };
    let elapsed = t0.elapsed().as_secs_f64();

    // Outputs.
    let data = curve_data(&m_a, &sw.name, &free.name, &curve, map);
    // the claim refused an existing file without --force; its placeholder is replaced
    pdw_store::write_curve(&out, true, &data)?;
    annotate(&out, &m_a, &sw.name, &free.name, &copts, &o2, &ropts)?;
    if let Some(png) = &a.png {
        let label = |n: &str| format!("{n} [{}]", super::param_unit(&m_a, n));
        pdw_store::plot_curve(
            png,
            &data,
            &label(&sw.name),
            &label(&free.name),
            &format!(
                "{}: {} curve in ({}, {})",
                m_a.info.name,
                kind_long(kind),
                sw.name,
                free.name
            ),
        )?;
    }
    let (su, fu) = (
        super::param_unit(&m_a, &sw.name),
        super::param_unit(&m_a, &free.name),
    );
    if a.json {
        let out = serde_json::json!({
            "curve": {
                "kind": kind.name(),
                "params": [sw.name, free.name],
                "points": curve.points.iter().map(|p| [p.p_step, p.p_free]).collect::<Vec<_>>(),
            },
            "model": m_a.info.name,
            "units": {sw.name.clone(): su, free.name.clone(): fu},
            "complete": matches!(curve.end, CurveEnd::Complete),
            "end": end_json(&curve.end),
            "start": {
                "step": sw.lo,
                "free": bif.param,
                "bracket": bif.param_bracket,
                "method": "one-parameter pseudo-arclength continuation in the free parameter",
            },
            "section_names": m_a.info.section_names,
            "state_names": m_a.info.state_names,
            "gaits": curve.points.iter().map(|p| serde_json::json!({
                "section": p.section,
                "state": p.state,
                "critical_multiplier": p.critical,
                "multipliers": p.multipliers.iter().map(|l| serde_json::json!({"re": l.re, "im": l.im})).collect::<Vec<_>>(),
                "period": p.period,
                "residual": p.residual,
                "test_value": p.test_value,
                "newton_iterations": p.newton_iters,
            })).collect::<Vec<_>>(),
            "integrator": super::integrator_json(&integrator),
            "out": out.display().to_string(),
            "png": a.png.as_ref().map(|p| p.display().to_string()),
            "elapsed_s": elapsed,
        });
        crate::outln!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        crate::outln!(
            "model {}: {} curve in ({}, {}); start at {} = {} from the one-parameter \
             continuation: {} = {:.12} {fu}",
            m_a.info.name,
            kind_long(kind),
            sw.name,
            free.name,
            sw.name,
            sw.lo,
            free.name,
            bif.param
        );
        let deg = free.name == "slope";
        crate::outln!(
            "  {:>16} {:>22}{} {:>20} {:>10} {:>6}",
            format!("{} [{su}]", sw.name),
            format!("{} [{fu}]", free.name),
            if deg { "       (deg)" } else { "" },
            "critical multiplier",
            "residual",
            "Newton"
        );
        for p in &curve.points {
            crate::outln!(
                "  {:>16.10} {:>22.15}{} {:>20.12} {:>10.2e} {:>6}",
                p.p_step,
                p.p_free,
                if deg {
                    format!(" ({:>10.6})", p.p_free.to_degrees())
                } else {
                    String::new()
                },
                p.critical,
                p.residual,
                p.newton_iters
            );
        }
        crate::outln!(
            "  {} of {} points in {} corrector solves; wrote {}{} in {elapsed:.2} s",
            curve.points.len(),
            sw.n,
            curve.solves,
            out.display(),
            a.png
                .as_ref()
                .map(|p| format!(" and {}", p.display()))
                .unwrap_or_default()
        );
    }
    if let CurveEnd::Lost {
        last,
        tried,
        reason,
    } = &curve.end
    {
        eprintln!(
            "error: the {} curve was lost {} (the step to {} = {tried} failed even at 1/256 of \
             the spacing): {reason}; the {} points reached are written",
            kind_long(kind),
            match last {
                Some(l) => format!("after {} = {l}", sw.name),
                None => format!("at its start, {} = {}", sw.name, sw.lo),
            },
            sw.name,
            curve.points.len()
        );
        return Ok(ExitCode::from(2));
    }
    Ok(ExitCode::SUCCESS)
}

fn kind_long(k: Codim2Kind) -> &'static str {
    match k {
        Codim2Kind::PeriodDoubling => "period-doubling",
        Codim2Kind::Fold => "fold",
    }
}

fn end_json(e: &CurveEnd) -> serde_json::Value {
    match e {
        CurveEnd::Complete => serde_json::Value::Null,
        CurveEnd::Lost {
            last,
            tried,
            reason,
        } => serde_json::json!({"last": last, "tried": tried, "reason": reason.to_string()}),
    }
}

/// The period-one gait at `NAME = A` (`m_a`): Newton from `--guess` or the presets there, else
/// the gait at the model's own values continued in the stepped parameter from `step_own` to
/// `a_val`. `None` after reporting why not.
fn start_gait(
    a: &FixedpointArgs,
    m_a: &BuiltModel,
    m_own: &BuiltModel,
    step_name: &str,
    step_own: f64,
    a_val: f64,
    integrator: &Options,
) -> anyhow::Result<Option<Vec<f64>>> {
    let ds = m_a.info.section_names.len();
    let guesses = |m: &BuiltModel| -> Result<Vec<(String, Vec<f64>)>, InputError> {
        match &a.guess {
            Some(g) => {
                let v = args::parse_guess(g)?;
                if v.len() != ds {
                    return Err(InputError(format!(
                        "--guess: {} values given, model '{}' has {ds} section coordinates ({})",
                        v.len(),
                        m.info.name,
                        m.info.section_names.join(", ")
                    )));
                }
                Ok(vec![("guess".to_string(), v)])
            }
            None => Ok(pdw_limit::gaits::model_guesses(m.walker.as_ref())),
        }
    };
    let pick = |m: &BuiltModel| -> anyhow::Result<(Option<Vec<f64>>, String)> {
        let (found, failed) =
            super::fixedpoint::search_with(m, &guesses(m)?, a.tol.max(1e-12), integrator)?;
        let f = match a.gait.as_str() {
            "unstable" => found.iter().find(|f| !f.fp.stable),
            "stable" => found.iter().find(|f| f.fp.stable),
            _ => found.iter().find(|f| f.fp.stable).or_else(|| found.first()),
        };
        let why = failed
            .iter()
            .map(|(l, _, e)| format!("guess '{l}': {e}"))
            .collect::<Vec<_>>()
            .join("; ");
        Ok((f.map(|f| f.fp.section.clone()), why))
    };
    let (direct, why_a) = pick(m_a)?;
    if direct.is_some() {
        return Ok(direct);
    }
    // Continue the gait at the model's own values to A.
    let (own, why_own) = pick(m_own)?;
    let free_vals: Vec<(String, f64)> = m_a
        .params
        .iter()
        .filter(|(n, _)| n != step_name)
        .cloned()
        .collect();
    let transferred = own.and_then(|s0| {
        let fam = |ps: f64| {
            let mut ov = free_vals.clone();
            ov.push((step_name.to_string(), ps));
            build_with(&a.model, &ov).map(|m| m.walker)
        };
        let mut c = ContinuationOptions::new(step_own.min(a_val), step_own.max(a_val));
        c.integrator = *integrator;
        c.detect = false;
        c.direction = (a_val - step_own).signum();
        let span = (a_val - step_own).abs().max(1e-12);
        c.ds_max = span / 20.0;
        c.ds_init = span / 200.0;
        c.ds_min = span * 1e-9;
        let br = continue_branch(&fam, &s0, step_own, 1, &c).ok()?;
        let near = br
            .points
            .iter()
            .min_by(|p, q| (p.param - a_val).abs().total_cmp(&(q.param - a_val).abs()))?;
        let map = StrideMap::new(&*m_a.walker, *integrator).ok()?;
        let opts = NewtonOptions {
            tol: a.tol.max(1e-12),
            ..NewtonOptions::default()
        };
        find_fixed_point(&map, &near.section, &opts)
            .ok()
            .map(|fp| fp.section)
    });
    if transferred.is_none() {
        eprintln!(
            "error: no period-one gait of model '{}' at {step_name} = {a_val} to start from \
             (Newton there: {why_a}; at the model's own {step_name} = {step_own}: {})",
            m_a.info.name,
            if why_own.is_empty() {
                "a gait exists but its continuation to A failed".to_string()
            } else {
                why_own
            }
        );
        eprintln!("try: --guess (section coordinates), or another start of --sweep");
    }
    Ok(transferred)
}

/// The free-parameter range of the map when `--free` gives none: the curve's range, widened by
/// a quarter of its width or a fifth of its middle value (whichever is larger) on each side,
/// within the domain.
fn auto_range(c: &Curve, lo: f64, hi: f64) -> (f64, f64) {
    let (a, b) = c
        .points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(x, y), p| {
            (x.min(p.p_free), y.max(p.p_free))
        });
    let pad = (0.25 * (b - a)).max(0.2 * (0.5 * (a + b)).abs());
    ((a - pad).max(lo), (b + pad).min(hi))
}

/// The region map under the curve on `threads` workers (progress bar on stderr unless `quiet`).
fn compute_map<F, E>(
    fam2: &F,
    curve: &Curve,
    (s0, s1): (f64, f64),
    (nx, ny): (usize, usize),
    (f0, f1): (f64, f64),
    ropts: &RegionOptions,
    (threads, quiet): (usize, bool),
) -> anyhow::Result<RegionMap>
where
    E: std::fmt::Display,
    F: Fn(f64, f64) -> Result<Box<dyn pdw_walkers::Walker>, E> + Sync,
{
    let step = pdw_limit::basin::linspace(s0, s1, nx);
    let free = pdw_limit::basin::linspace(f0, f1, ny);
    // Each column starts from the curve's gait at the nearest curve point.
    let hints: Vec<(Vec<f64>, f64)> = step
        .iter()
        .map(|&ps| {
            let p = curve
                .points
                .iter()
                .min_by(|p, q| (p.p_step - ps).abs().total_cmp(&(q.p_step - ps).abs()))
                .expect("the curve has points");
            (p.section.clone(), p.p_free)
        })
        .collect();
    let bar = if quiet || !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(2 * nx as u64)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "region map {bar:40} {pos}/{len} columns x 2 passes [{elapsed_precise} < {eta}]",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    let grid = region_map(fam2, &step, &free, &hints, ropts, &pool, &|k| {
        bar.inc(k as u64)
    })?;
    bar.finish_and_clear();
    Ok(RegionMap {
        step,
        free,
        region: grid
            .iter()
            .map(|r| r.iter().map(|g| g.code()).collect())
            .collect(),
        legend: Region::ALL
            .iter()
            .map(|r| (r.code(), r.name().to_string()))
            .collect(),
    })
}

fn curve_data(
    m: &BuiltModel,
    step: &str,
    free: &str,
    c: &Curve,
    map: Option<RegionMap>,
) -> CurveData {
    let end = match &c.end {
        CurveEnd::Complete => "complete".to_string(),
        CurveEnd::Lost {
            last,
            tried,
            reason,
        } => format!("lost after {step} = {last:?} (step to {tried} failed): {reason}"),
    };
    CurveData {
        command: super::command_line(),
        model: m.info.name.to_string(),
        kind: c.kind.name().into(),
        step_parameter: step.into(),
        free_parameter: free.into(),
        params: m.params_json().to_string(),
        section_names: m.info.section_names.iter().map(|s| s.to_string()).collect(),
        state_names: m.info.state_names.iter().map(|s| s.to_string()).collect(),
        p_step: c.points.iter().map(|p| p.p_step).collect(),
        p_free: c.points.iter().map(|p| p.p_free).collect(),
        section: c.points.iter().map(|p| p.section.clone()).collect(),
        state: c.points.iter().map(|p| p.state.clone()).collect(),
        multipliers: c
            .points
            .iter()
            .map(|p| p.multipliers.iter().map(|l| (l.re, l.im)).collect())
            .collect(),
        critical: c.points.iter().map(|p| p.critical).collect(),
        period: c.points.iter().map(|p| p.period).collect(),
        residual: c.points.iter().map(|p| p.residual).collect(),
        complete: matches!(c.end, CurveEnd::Complete),
        end,
        map,
    }
}

/// Provenance (every numerical option) and units on every dataset of the curve file.
fn annotate(
    out: &std::path::Path,
    m: &BuiltModel,
    step: &str,
    free: &str,
    c: &ContinuationOptions,
    o: &Codim2Options,
    r: &RegionOptions,
) -> anyhow::Result<()> {
    let options = serde_json::json!({
        "one_parameter_start": {
            "method": format!("{:?}", c.method),
            "integrator": super::integrator_json(&c.integrator),
            "ds_init": c.ds_init, "ds_min": c.ds_min, "ds_max": c.ds_max,
            "mu_min": c.mu_min, "mu_max": c.mu_max,
            "newton_tol": c.newton_tol, "dmu": c.dmu, "locate_tol": c.locate_tol,
        },
        "curve": {
            "system": "minimally augmented: P(x) - x = 0, g = 0 from the bordered [[DP -+ I, b], [c^T, 0]]",
            "integrator": super::integrator_json(&o.integrator),
            "newton_tol": o.newton_tol, "max_newton": o.max_newton,
            "max_backtracks": o.max_backtracks,
            "dtest_rel": o.dtest_rel,
            "free_min": o.free_min, "free_max": o.free_max,
            "min_step_fraction": o.min_step_fraction,
            "critical_tol": o.critical_tol,
        },
        "region_map": {
            "newton_tol": r.newton.tol,
            "newton_integrator": super::integrator_json(&r.integrator),
            "orbit_integrator": super::integrator_json(&r.orbit.integrator),
            "transient": r.orbit.transient, "record": r.orbit.record,
            "max_period": r.orbit.max_period, "tol_period": r.orbit.tol_period,
            "nudge": r.nudge,
        },
    });
    let prov = super::provenance(options);
    let (su, fu) = (super::param_unit(m, step), super::param_unit(m, free));
    let sec = super::units_list(&super::section_units(m));
    let state = super::units_list(&super::model_units(m).state);
    let tu = super::time_unit(m);
    let units = move |p: &str| -> Option<String> {
        Some(match p {
            "curve/p_step" | "map/step" => su.clone(),
            "curve/p_free" | "map/free" => fu.clone(),
            "curve/section" => sec.clone(),
            "curve/residual" => format!("max over /curve/section's coordinates {sec}"),
            "curve/state" => state.clone(),
            "curve/period" => tu.clone(),
            "curve/multipliers_re" | "curve/multipliers_im" | "curve/critical" | "map/region" => {
                "1".into()
            }
            _ => return None,
        })
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
