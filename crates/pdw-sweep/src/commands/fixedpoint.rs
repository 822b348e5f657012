//! `pdw-sweep fixedpoint`: period-one gaits (or period-K orbits, `--period K`), their Floquet
//! multipliers and gait metrics.

use super::{build_model, BuiltModel};
use crate::args::{self, InputError};
use crate::cli::FixedpointArgs;
use pdw::limit::scan::Scan;
use pdw::limit::{FixedPoint, LimitError, PeriodicOrbit};
use std::process::ExitCode;

pub use pdw::limit::gaits::{Found, FoundOrbit};
use pdw::limit::gsn::{GsnError, Indicator};
use pdw::limit::Validity;

pub use pdw::gaits::search_with;

/// Constraint loads, swing-foot clearance and impacts along one step of a gait, located on
/// the dense solution ([`Validity::along_step`], module docs of [`pdw::limit::validity`]).
pub fn validity(m: &BuiltModel, fp: &FixedPoint) -> Option<Validity> {
    Validity::along_step(m.walker.as_ref(), &fp.state)
}

pub use pdw::validity::{clearance_rule_name, validity_json};

pub fn run(a: &FixedpointArgs) -> anyhow::Result<ExitCode> {
    if a.follow.is_some() || a.free.is_some() || a.map_grid.is_some() {
        return super::follow::run(a);
    }
    let integrator =
        super::integrator(&a.integrator, pdw::limit::gaits::default_integrator(a.tol))?;
    if a.sweep.is_some() {
        if a.period != 1 {
            return Err(InputError(format!(
                "--period {} with --sweep: a sweep follows the period-one branch and switches to \
                 period 2, 4, … at its period doublings by itself; drop --period",
                a.period
            ))
            .into());
        }
        return super::sweep::run(a);
    }
    // Not silently ignored: it draws a sweep or a curve only (--csv and --threads are refused
    // by clap without --sweep).
    if a.png.is_some() {
        return Err(InputError(
            "--png: only a --sweep NAME=A:B:N uses it (add --sweep, or drop --png)".into(),
        )
        .into());
    }
    let m = build_model(&a.model)?;
    pdw::integrator::check_integrator(&m, &integrator)?;
    if let Some(n) = a.search {
        return run_search(a, &m, n, &integrator);
    }
    let user = a.guess.as_deref().map(args::parse_guess).transpose()?;
    let guesses = pdw::gaits::guesses(&m, user, "--guess")?;
    if a.period > 1 {
        return run_period_k(a, &m, &guesses);
    }
    run_period_one(a, &m, &guesses, &integrator)
}

/// Period-one gaits: Newton from every guess, the ones `--gait` asks for printed (a table or
/// JSON); none found is exit 2 with every failed guess and advice.
fn run_period_one(
    a: &FixedpointArgs,
    m: &BuiltModel,
    guesses: &[(String, Vec<f64>)],
    integrator: &pdw::hybrid::Options,
) -> anyhow::Result<ExitCode> {
    let indicators = a
        .gsn
        .then(|| pdw::gsn::parse_indicators(&a.indicators, "--indicators"))
        .transpose()?;
    if a.gsn {
        pdw::mfpt::check_model(m)?;
    }
    let (found, failed) = search_with(m, guesses, a.tol, integrator)?;
    warn_inaccurate(a, m, &found, integrator)?;
    let selected: Vec<&Found> = found
        .iter()
        .filter(|f| wanted(&a.gait, f.fp.stable))
        .collect();
    if a.json {
        let mut j = gaits_json(m, &selected, integrator);
        if a.jacobian {
            for (k, f) in selected.iter().enumerate() {
                j["fixed_points"][k]["linear"] = linear_json(m, &f.fp.section)?;
            }
        }
        if let Some(ind) = &indicators {
            for (k, f) in selected.iter().enumerate() {
                let r = gsn_of(m, f, ind)?;
                j["fixed_points"][k]["gsn"] = pdw::gsn::json(ind, &r);
            }
        }
        crate::outln!("{}", serde_json::to_string_pretty(&j)?);
    } else {
        print_model_line(m, integrator);
        for f in &selected {
            print_fixed_point(m, &f.fp, &format!("from guess '{}'", f.label));
            if let Some(ind) = &indicators {
                print_gsn(ind, &gsn_of(m, f, ind)?);
            }
        }
    }
    if selected.is_empty() && a.guess.is_none() && m.walker.section_box().is_some() {
        eprintln!(
            "no {}period-one gait found for model '{}' from its {} guess(es); scanning the \
             section ({} starts, as --search does)",
            gait_adjective(&a.gait),
            m.info.name,
            guesses.len(),
            pdw::gaits::SCAN_STARTS
        );
        for (label, g, e) in &failed {
            report_failure(label, g, e);
        }
        return run_search(a, m, pdw::gaits::SCAN_STARTS, integrator);
    }
    if selected.is_empty() {
        eprintln!(
            "no {}period-one gait found for model '{}' from {} guess(es)",
            gait_adjective(&a.gait),
            m.info.name,
            guesses.len()
        );
        for (label, g, e) in &failed {
            report_failure(label, g, e);
        }
        eprintln!("try: {}", advice(m));
        return Ok(ExitCode::from(2));
    }
    Ok(ExitCode::SUCCESS)
}

type GsnResult = Result<(pdw::limit::gsn::Linearisation, pdw::limit::gsn::Gsn), GsnError>;

/// `--gsn`: the gait sensitivity norm of a gait ([`pdw::gsn`]); an unstable gait's is the
/// unstable-gait error (reported, not a failure of the run), any other failure is an error.
fn gsn_of(m: &BuiltModel, f: &Found, ind: &[Indicator]) -> anyhow::Result<GsnResult> {
    let r = pdw::gsn::gait_sensitivity(m, &f.fp.section, ind, pdw::gsn::default_integrator());
    match r {
        Err(GsnError::Limit(e)) => Err(e.into()),
        r => Ok(r),
    }
}

/// The gait sensitivity norm block of the text report.
fn print_gsn(ind: &[Indicator], r: &GsnResult) {
    match r {
        Ok((lin, g)) => {
            crate::outln!(
                "  gait sensitivity norm {:>16.10}  (per rad of landing-line slope; \
                 differences accurate to {:.1e})",
                g.norm,
                lin.fd_error
            );
            for (i, h) in ind.iter().zip(&g.per_indicator) {
                crate::outln!("    {:<12} {h:>22.10}", i.name());
            }
        }
        Err(e) => crate::outln!("  gait sensitivity norm: infinite ({e})"),
    }
}

/// `--search [N]` (and the fallback when the model's guesses find nothing): every gait in the
/// section's box from N starts ([`pdw::gaits::scan`]), each with the starts that reached it.
fn run_search(
    a: &FixedpointArgs,
    m: &BuiltModel,
    starts: usize,
    integrator: &pdw::hybrid::Options,
) -> anyhow::Result<ExitCode> {
    let b = pdw::gaits::scan_box(m, &a.search_box, "--search-box")?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads.unwrap_or(2))
        .build()?;
    let sc = pdw::gaits::scan(m, &b, starts, a.tol, integrator, &pool)?;
    let gaits: Vec<_> = sc
        .gaits
        .iter()
        .filter(|g| wanted(&a.gait, g.fp.stable))
        .collect();
    let orbits: Vec<_> = sc
        .orbits
        .iter()
        .filter(|o| wanted(&a.gait, o.orbit.stable))
        .collect();
    if a.json {
        let j = scan_json(m, &sc, &gaits, &orbits, integrator);
        crate::outln!("{}", serde_json::to_string_pretty(&j)?);
    } else {
        print_scan_header(m, &sc, integrator);
        for g in &gaits {
            let source = format!(
                "Newton converged to it from {} of the {} starts; {} settled on it{}",
                g.newton_starts,
                sc.starts,
                g.attracted_starts,
                near_text(g.near_gaits)
            );
            print_fixed_point(m, &g.fp, &source);
        }
        for o in &orbits {
            let source = format!(
                "{} of the {} starts settled on it{}",
                o.attracted_starts,
                sc.starts,
                near_text(o.near_gaits)
            );
            print_orbit(m, &o.orbit, &source);
        }
    }
    if gaits.is_empty() && orbits.is_empty() {
        eprintln!(
            "no {}gait found for model '{}' at slope {} by a scan ({}); try more starts \
             (--search N), a smaller --search-box, or: {}",
            gait_adjective(&a.gait),
            m.info.name,
            m.slope(),
            pdw::limit::scan::fates_text(sc.starts, &sc.fates()),
            advice(m)
        );
        return Ok(ExitCode::from(2));
    }
    Ok(ExitCode::SUCCESS)
}

/// `, and N of the starts near the unstable period-one gaits` when N > 0.
fn near_text(n: usize) -> String {
    if n == 0 {
        String::new()
    } else {
        format!(", and {n} of the starts near the unstable period-one gaits")
    }
}

/// The first line of a gait report: model, slope (rad and degrees), integrator.
fn print_model_line(m: &BuiltModel, integrator: &pdw::hybrid::Options) {
    crate::outln!(
        "model {}  slope {} rad ({:.4} deg)  integrator {}",
        m.info.name,
        m.slope(),
        m.slope().to_degrees(),
        super::integrator_text(integrator)
    );
}

/// The scan's first lines: the model, the box and what became of the starts.
fn print_scan_header(m: &BuiltModel, sc: &Scan, integrator: &pdw::hybrid::Options) {
    print_model_line(m, integrator);
    let b = &sc.scan_box;
    let ranges: Vec<String> = m
        .info
        .section_names
        .iter()
        .zip(b.lo.iter().zip(&b.hi))
        .map(|(n, (lo, hi))| format!("{n} in [{lo}, {hi}]"))
        .collect();
    crate::outln!(
        "scan of the section: {} starts (Halton) over {}",
        sc.starts,
        ranges.join(", ")
    );
    crate::outln!(
        "  {} period-one gait(s), {} period-K orbit(s); {} starts fell, {} neither fell nor \
         settled on an orbit of period ≤ {}; {} more starts near the unstable period-one gaits",
        sc.gaits.len(),
        sc.orbits.len(),
        sc.fell,
        sc.unsettled,
        pdw::limit::scan::MAX_PERIOD,
        sc.near_gait_starts
    );
    crate::outln!(
        "  by fate: {}",
        pdw::limit::scan::fates_text(sc.starts, &sc.fates())
    );
}

/// `--search --json`: the `--json` of the gaits and of the orbits found, each with its starts,
/// and the scan's box and counts.
fn scan_json(
    m: &BuiltModel,
    sc: &Scan,
    gaits: &[&pdw::limit::scan::ScanGait],
    orbits: &[&pdw::limit::scan::ScanOrbit],
    integrator: &pdw::hybrid::Options,
) -> serde_json::Value {
    let found: Vec<Found> = gaits
        .iter()
        .map(|g| Found {
            label: "scan".into(),
            fp: g.fp.clone(),
        })
        .collect();
    let refs: Vec<&Found> = found.iter().collect();
    let mut j = gaits_json(m, &refs, integrator);
    if let Some(fps) = j["fixed_points"].as_array_mut() {
        for (e, g) in fps.iter_mut().zip(gaits) {
            e["starts_newton"] = g.newton_starts.into();
            e["starts_settled"] = g.attracted_starts.into();
            e["starts_near_gaits"] = g.near_gaits.into();
        }
    }
    let orbits: Vec<serde_json::Value> = orbits
        .iter()
        .map(|o| {
            let fo = FoundOrbit {
                label: "scan".into(),
                orbit: o.orbit.clone(),
            };
            let mut one = orbits_json(m, o.orbit.period_k, &[&fo]);
            let mut e = one["fixed_points"][0].take();
            e["starts_settled"] = o.attracted_starts.into();
            e["starts_near_gaits"] = o.near_gaits.into();
            e
        })
        .collect();
    j["orbits"] = orbits.into();
    j["scan"] = serde_json::json!({
        "starts": sc.starts,
        "sample": "halton",
        "box": m.info.section_names.iter().zip(sc.scan_box.lo.iter().zip(&sc.scan_box.hi))
            .map(|(n, (lo, hi))| serde_json::json!({"name": n, "lo": lo, "hi": hi}))
            .collect::<Vec<_>>(),
        "fell": sc.fell,
        "unsettled": sc.unsettled,
        "fates": sc.fates().iter().map(|(f, n)| serde_json::json!({"fate": f, "starts": n}))
            .collect::<Vec<_>>(),
        "near_gait_starts": sc.near_gait_starts,
        "near_gait_offset": pdw::limit::scan::NEAR_GAIT_OFFSET,
    });
    j
}

/// Whether `--gait` (stable, unstable or all) reports a gait of this stability.
fn wanted(which: &str, stable: bool) -> bool {
    match which {
        "stable" => stable,
        "unstable" => !stable,
        _ => true,
    }
}

/// `--gait` as it qualifies "gait" in a message: empty for all, else the word and a space.
fn gait_adjective(which: &str) -> String {
    if which == "all" {
        String::new()
    } else {
        format!("{which} ")
    }
}

/// A gait found on a loose integrator is checked on the accurate stride map, as `basin`
/// checks its cells' integrator: the Newton tolerance means nothing beyond the integrator's.
fn warn_inaccurate(
    a: &FixedpointArgs,
    m: &BuiltModel,
    found: &[Found],
    integrator: &pdw::hybrid::Options,
) -> anyhow::Result<()> {
    let o = &a.integrator;
    if !(o.integrator.is_some() || o.rtol.is_some() || o.atol.is_some() || o.rk4_step.is_some()) {
        return Ok(());
    }
    let accurate = pdw::limit::gaits::default_integrator(a.tol);
    for f in found {
        let s = &f.fp.section;
        let scale = s.iter().fold(0.0, |n: f64, x| n.max(x.abs())).min(1.0);
        let r = super::stride_residual(m, accurate, s)?;
        if r.is_nan() || r > a.tol * scale {
            eprintln!(
                "warning: with {} the {} gait (from {}) is a fixed point of the accurate stride \
                 map ({}) only to {r:.2e}, more than --tol {:e} allows: its multipliers and \
                 validity are those of the integrator's error, not of the walker; use a tighter \
                 --rtol/--atol or a smaller --rk4-step",
                super::integrator_text(integrator),
                if f.fp.stable { "stable" } else { "unstable" },
                f.label,
                super::integrator_text(&accurate),
                a.tol * scale
            );
        }
    }
    Ok(())
}

/// `--json`: the model, its units and integrator, and every gait reported with its metrics,
/// multipliers and validity.
fn gaits_json(
    m: &BuiltModel,
    selected: &[&Found],
    integrator: &pdw::hybrid::Options,
) -> serde_json::Value {
    let fps: Vec<serde_json::Value> = selected
        .iter()
        .map(|f| {
            let fp = &f.fp;
            serde_json::json!({
                "gait": if fp.stable { "stable" } else { "unstable" },
                "guess": f.label,
                "section": fp.section,
                "state_names": m.info.state_names,
                "state": fp.state,
                "period": fp.metrics.period,
                "step_length": fp.metrics.step_length,
                "speed": fp.metrics.speed,
                "multipliers": fp.multipliers.iter().map(|l| serde_json::json!({"re": l.re, "im": l.im})).collect::<Vec<_>>(),
                "stable": fp.stable,
                "residual": fp.residual,
                "iterations": fp.iterations,
                "validity": validity(m, fp).map(|v| validity_json(&v)),
                "period_k": 1,
                "orbit": [&fp.section],
            })
        })
        .collect();
    serde_json::json!({
        "model": m.info.name,
        "slope": m.slope(),
        "params": m.params_json(),
        "section_names": m.info.section_names,
        "section_units": super::section_units(m),
        "time_unit": super::time_unit(m),
        "integrator": super::integrator_json(integrator),
        "fixed_points": fps,
    })
}

/// `--jacobian`: the linear stability data of the gait at section state `s`
/// ([`pdw::linear`]): `jacobian` (rows), `eigenvalues` ({re, im}), `eigenvectors` (one per
/// eigenvalue, unit norm, {re, im} entries), `impacts` (event, t, modes, pre-impact state,
/// `saltation` rows) and `lyapunov` over `lyapunov_strides` strides.
fn linear_json(m: &BuiltModel, s: &[f64]) -> anyhow::Result<serde_json::Value> {
    const STRIDES: usize = 100;
    let n = s.len();
    let (dp, _) = pdw::linear::jacobian(m, s)?;
    let pairs = pdw::linear::eigenpairs(&dp, n)?;
    let impacts = pdw::linear::impacts(m, s)?;
    let c = |z: &(f64, f64)| serde_json::json!({"re": z.0, "im": z.1});
    let rows = |v: &[f64], k: usize| v.chunks(k).map(<[f64]>::to_vec).collect::<Vec<_>>();
    Ok(serde_json::json!({
        "jacobian": rows(&dp, n),
        "eigenvalues": pairs.iter().map(|p| c(&p.value)).collect::<Vec<_>>(),
        "eigenvectors": pairs.iter().map(|p| p.vector.iter().map(c).collect::<Vec<_>>()).collect::<Vec<_>>(),
        "impacts": impacts.iter().map(|i| serde_json::json!({
            "event": i.event,
            "t": i.t,
            "mode_before": i.mode_before,
            "mode_after": i.mode_after,
            "pre": i.pre,
            "saltation": rows(&i.saltation, i.pre.len()),
        })).collect::<Vec<_>>(),
        "lyapunov": pdw::linear::lyapunov(m, s, STRIDES)?,
        "lyapunov_strides": STRIDES,
    }))
}

/// What to try when no gait is found, by model: the rimless wheel rolls only on a slope steep
/// enough to make up the energy its spoke impacts lose (McGeer 1990: its fixed point exists for
/// γ above a threshold that grows as the spoke angle does), so it needs a *steeper* slope; the
/// legged walkers lose their gaits by period doubling and falls on steep slopes and stop on
/// shallow ones, so the advice names both directions; an uphill slope is named as such.
pub fn advice(m: &BuiltModel) -> String {
    let coords = m.info.section_names.join(", ");
    if m.info.name == "rimless" {
        let n = m
            .params
            .iter()
            .find(|(p, _)| p == "n_spokes")
            .map_or(8.0, |p| p.1);
        let g_min = rimless_min_slope(n);
        if m.slope() > g_min {
            return format!(
                "another --guess ({coords}; the slope {:.4} rad is above the {g_min:.4} rad the \
                 rolling gait needs, and the model's own guess is its closed-form fixed point)",
                m.slope()
            );
        }
        format!(
            "a steeper --slope: the rimless wheel keeps rolling only where the slope makes up the \
             energy each spoke impact loses; with {n} spokes its rolling gait needs slope > \
             {g_min:.4} rad ({:.2} deg), this run has {:.4} rad",
            g_min.to_degrees(),
            m.slope()
        )
    } else if m.slope() < 0.0 {
        format!(
            "a downhill --slope (positive: a passive walker walks down the slope; this run has \
             {:.4} rad, uphill), or another --guess (section coordinates {coords})",
            m.slope()
        )
    } else {
        format!(
            "another --guess (section coordinates {coords}), another --slope (too steep and the \
             gait falls or period-doubles, too shallow and the walker stops: level ground has no \
             passive gait), or continuation from a slope where a gait exists \
             (--sweep slope=A:B:N)"
        )
    }
}

/// The smallest slope on which the rimless wheel with `n` spokes has a rolling gait. Its return
/// map `ω' = cos 2α · √(ω² + 4 (g/l) sin α sin γ)` (α = π/n; Coleman; Tedrake ch. 4) has the
/// fixed point `ω*² = 4 (g/l) cos² 2α sin α sin γ / sin² 2α`; the wheel vaults over the next
/// spoke only if `½ ω*² > (g/l) (1 − cos(α − γ))` (the hub must pass the top, θ = −γ). The
/// threshold is the root of the difference in (0, α), found by bisection (independent of g/l).
pub fn rimless_min_slope(n: f64) -> f64 {
    let a = std::f64::consts::PI / n;
    let (c2, s2) = ((2.0 * a).cos(), (2.0 * a).sin());
    let f = |g: f64| 2.0 * c2 * c2 * a.sin() * g.sin() / (s2 * s2) - (1.0 - (a - g).cos());
    let (mut lo, mut hi) = (0.0, a);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

fn print_fixed_point(m: &BuiltModel, fp: &FixedPoint, source: &str) {
    crate::outln!();
    crate::outln!(
        "{} gait ({source})",
        if fp.stable { "stable" } else { "unstable" },
    );
    let (tu, lu) = (super::time_unit(m), super::length_unit(m));
    for ((n, v), u) in m
        .info
        .section_names
        .iter()
        .zip(&fp.section)
        .zip(super::section_units(m))
    {
        crate::outln!("  {n:<12} {v:>22.15}  {u}");
    }
    crate::outln!("  period       {:>22.15}  {tu}", fp.metrics.period);
    if let Some(l) = fp.metrics.step_length {
        crate::outln!("  step length  {l:>22.15}  {lu}");
    }
    if let Some(v) = fp.metrics.speed {
        crate::outln!("  speed        {v:>22.15}  {lu}/{tu}");
    }
    crate::outln!("  multipliers (|λ|):");
    for l in &fp.multipliers {
        crate::outln!(
            "    {:>+20.15} {:>+20.15}i   ({:.6})",
            l.re,
            l.im,
            l.modulus()
        );
    }
    if let Some(v) = validity(m, fp) {
        print_validity(m, &v);
    }
    crate::outln!(
        "  residual ‖P(x) − x‖∞ = {:.3e} after {} Newton iterations",
        fp.residual,
        fp.iterations
    );
}

/// The validity block of a gait: flags, violations, the binding criterion, the clearance.
fn print_validity(m: &BuiltModel, v: &Validity) {
    let units = super::model_units(m);
    crate::outln!(
        "  validity     {}: normal force ≥ {:.4} {}, friction needed ≤ {:.4}{}",
        if v.valid() { "ok" } else { "FLAGGED" },
        v.min_normal_force,
        units.force,
        v.max_friction_required,
        v.min_knee_torque
            .map(|k| format!(", knee-lock torque ≥ {k:.4} {}", units.torque))
            .unwrap_or_default()
    );
    for what in v.flag_descriptions() {
        crate::outln!("    flag: {what}");
    }
    for x in &v.violations {
        crate::outln!(
            "    violated: {} < 0 from t = {:.4} to {:.4} {} (worst {:.6})",
            x.criterion,
            x.t_start,
            x.t_end,
            units.time,
            x.worst
        );
    }
    if let Some(b) = v.binding() {
        crate::outln!(
            "  binding      {} (relative margin {:.4} of {}; raw {:.6})",
            b.name,
            b.relative,
            b.scale_name,
            b.raw
        );
    }
    if let Some(rule) = v.clearance_rule {
        let lu = super::length_unit(m);
        let mut line = format!("  clearance    rule {}", clearance_rule_name(rule));
        if let Some(c) = v.min_clearance {
            line += &format!(", min {c:.6} {lu}");
        }
        if v.scuff_depth > 0.0 {
            let name = match rule {
                pdw::walkers::ClearanceRule::AfterMidStance => {
                    "mid-stance scuff (ignored by the convention, Garcia et al. 1998)"
                }
                pdw::walkers::ClearanceRule::WholeSwing => "below the slope",
            };
            line += &format!(", {name}: depth {:.6} {lu}", v.scuff_depth);
        }
        crate::outln!("{line}");
    }
}

/// Prints why a Newton run failed (the error carries its residual history and last iterate).
pub fn report_failure(label: &str, guess: &[f64], e: &LimitError) {
    eprintln!("  guess '{label}' {guess:?}: {e}");
}

/// `fixedpoint --period K` with K > 1: period-K orbits ([`pdw::limit::gaits::search_periodic`]).
/// `section`, `state` refer to the orbit's first point (its smallest, see
/// [`pdw::limit::periodic::canonical_start`]), `period` to the K strides together, `multipliers`
/// to the K-step map; `orbit` lists the K section points in stride order.
fn run_period_k(
    a: &FixedpointArgs,
    m: &BuiltModel,
    guesses: &[(String, Vec<f64>)],
) -> anyhow::Result<ExitCode> {
    let k = a.period;
    let (found, failed) = pdw::limit::gaits::search_periodic(m.walker.as_ref(), guesses, k, a.tol)?;
    let selected: Vec<&FoundOrbit> = found
        .iter()
        .filter(|f| wanted(&a.gait, f.orbit.stable))
        .collect();
    if a.json {
        let j = orbits_json(m, k, &selected);
        crate::outln!("{}", serde_json::to_string_pretty(&j)?);
    } else {
        crate::outln!(
            "model {}  slope {} rad ({:.4} deg)  period-{k} orbits",
            m.info.name,
            m.slope(),
            m.slope().to_degrees()
        );
        for f in &selected {
            print_orbit(m, &f.orbit, &format!("from '{}'", f.label));
        }
    }
    if selected.is_empty() {
        eprintln!(
            "no {}period-{k} orbit found for model '{}' from {} guess(es), their iterates and \
             the period-doubling predictors",
            gait_adjective(&a.gait),
            m.info.name,
            guesses.len()
        );
        for (label, g, e) in &failed {
            report_failure(label, g, e);
        }
        eprintln!(
            "try: another --guess (section coordinates {}), another --period (the orbit diagram \
             of a sweep shows which periods exist), or another --slope",
            m.info.section_names.join(", ")
        );
        return Ok(ExitCode::from(2));
    }
    Ok(ExitCode::SUCCESS)
}

/// `--json` of `--period K`: every orbit reported with all K points, per-stride times, step
/// lengths and validity, and the multipliers of the K-stride map.
fn orbits_json(m: &BuiltModel, k: usize, selected: &[&FoundOrbit]) -> serde_json::Value {
    let fps: Vec<serde_json::Value> = selected
        .iter()
        .map(|f| {
            let o = &f.orbit;
            let valid: Vec<Option<Validity>> = o
                .states
                .iter()
                .map(|x| Validity::along_step(m.walker.as_ref(), x))
                .collect();
            serde_json::json!({
                "gait": if o.stable { "stable" } else { "unstable" },
                "guess": f.label,
                "period_k": k,
                "section": o.orbit[0],
                "orbit": o.orbit,
                "state_names": m.info.state_names,
                "state": o.states[0],
                "period": o.period,
                "stride_periods": o.strides.iter().map(|s| s.period).collect::<Vec<_>>(),
                "step_length": o.total_step_length().map(|l| l / k as f64),
                "step_lengths": o.strides.iter().map(|s| s.step_length).collect::<Vec<_>>(),
                "speed": o.speed(),
                "multipliers": o.multipliers.iter().map(|l| serde_json::json!({"re": l.re, "im": l.im})).collect::<Vec<_>>(),
                "stable": o.stable,
                "residual": o.residual,
                "iterations": o.iterations,
                "validity": valid[0].as_ref().map(validity_json),
                "validity_per_stride": valid.iter().map(|v| v.as_ref().map(validity_json)).collect::<Vec<_>>(),
            })
        })
        .collect();
    serde_json::json!({
        "model": m.info.name,
        "slope": m.slope(),
        "params": m.params_json(),
        "section_names": m.info.section_names,
        "period_k": k,
        "fixed_points": fps,
    })
}

fn print_orbit(m: &BuiltModel, o: &PeriodicOrbit, source: &str) {
    let k = o.period_k;
    crate::outln!();
    crate::outln!(
        "{} period-{k} orbit ({source})",
        if o.stable { "stable" } else { "unstable" },
    );
    let names = &m.info.section_names;
    crate::outln!(
        "  {:<6}{}{:>22}{:>22}",
        "point",
        names.iter().map(|n| format!("{n:>22}")).collect::<String>(),
        "stride time",
        "step length"
    );
    for (j, (p, st)) in o.orbit.iter().zip(&o.strides).enumerate() {
        crate::outln!(
            "  {:<6}{}{:>22.15}{}",
            j + 1,
            p.iter().map(|v| format!("{v:>22.15}")).collect::<String>(),
            st.period,
            st.step_length
                .map(|l| format!("{l:>22.15}"))
                .unwrap_or_default()
        );
    }
    crate::outln!("  period ({k} strides) {:>22.15}", o.period);
    if let Some(v) = o.speed() {
        crate::outln!("  speed        {v:>22.15}");
    }
    crate::outln!("  multipliers of the {k}-stride map (|λ|):");
    for l in &o.multipliers {
        crate::outln!(
            "    {:>+20.15} {:>+20.15}i   ({:.6})",
            l.re,
            l.im,
            l.modulus()
        );
    }
    let flagged: Vec<usize> = o
        .states
        .iter()
        .enumerate()
        .filter(|(_, x)| Validity::along_step(m.walker.as_ref(), x).is_some_and(|v| !v.valid()))
        .map(|(j, _)| j + 1)
        .collect();
    if !flagged.is_empty() {
        crate::outln!("  validity     FLAGGED at the strides from points {flagged:?}");
    }
    crate::outln!(
        "  residual ‖P^{k}(x) − x‖∞ = {:.3e} after {} Newton iterations",
        o.residual,
        o.iterations
    );
}
