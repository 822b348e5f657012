//! `pdw-sweep fixedpoint`: period-one gaits, their Floquet multipliers and gait metrics.

use super::{build_model, BuiltModel};
use crate::args::{self, InputError};
use crate::cli::FixedpointArgs;
use pdw_hybrid::Options;
use pdw_limit::{find_fixed_point, FixedPoint, LimitError, NewtonOptions, StrideMap};
use std::process::ExitCode;

/// Integration tolerance of the stride map used for fixed points: two orders below the default
/// residual tolerance 1e-12, so that the residual measures the Newton error, not the integrator's.
pub const FIXEDPOINT_INTEGRATOR_TOL: f64 = 1e-14;

/// One gait found, with the name of the guess it came from.
pub struct Found {
    pub label: String,
    pub fp: FixedPoint,
}

/// A guess that did not lead to a fixed point: its label, value and the error.
pub type Failed = (String, Vec<f64>, LimitError);

/// Runs Newton from every guess (the user's, or the model's presets), de-duplicates the fixed
/// points found, and returns them with the failures (guess label, error).
pub fn search(
    m: &BuiltModel,
    guesses: &[(String, Vec<f64>)],
    tol: f64,
) -> Result<(Vec<Found>, Vec<Failed>), LimitError> {
    let walker = m.walker.as_ref();
    let step = |x: &[f64]| walker.step_length(x);
    let map = StrideMap::new(
        walker,
        Options::dop853(FIXEDPOINT_INTEGRATOR_TOL.max(tol * 1e-2)),
    )?
    .with_step_length(&step);
    let opts = NewtonOptions {
        tol,
        ..NewtonOptions::default()
    };
    let mut found: Vec<Found> = Vec::new();
    let mut failed = Vec::new();
    for (label, g) in guesses {
        match find_fixed_point(&map, g, &opts) {
            Ok(fp) => {
                let dup = found.iter().any(|f| {
                    f.fp.section
                        .iter()
                        .zip(&fp.section)
                        .all(|(a, b)| (a - b).abs() <= 1e-8 * (1.0 + a.abs()))
                });
                if !dup {
                    found.push(Found {
                        label: label.clone(),
                        fp,
                    });
                }
            }
            Err(e) => failed.push((label.clone(), g.clone(), e)),
        }
    }
    Ok((found, failed))
}

/// Constraint forces and validity flags sampled along one stride of a gait (at every accepted
/// integrator step and event): the gait is flagged, not silently accepted, if the stance foot
/// would lift off, a locked knee would unlock, or the swing foot scuffs after mid-stance.
#[derive(Clone, Debug, Default)]
pub struct Validity {
    pub min_normal_force: f64,
    pub max_friction_required: f64,
    /// Smallest knee-lock torque (negative: the knee would unlock); `None` without knees.
    pub min_knee_torque: Option<f64>,
    pub normal_force_negative: bool,
    pub knee_unlocks: bool,
    pub swing_foot_scuffs: bool,
    pub samples: usize,
}

impl Validity {
    pub fn valid(&self) -> bool {
        !(self.normal_force_negative || self.knee_unlocks || self.swing_foot_scuffs)
    }

    pub fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "valid": self.valid(),
            "min_normal_force": self.min_normal_force,
            "max_friction_required": self.max_friction_required,
            "min_knee_torque": self.min_knee_torque,
            "normal_force_negative": self.normal_force_negative,
            "knee_unlocks": self.knee_unlocks,
            "swing_foot_scuffs": self.swing_foot_scuffs,
        })
    }
}

/// Samples [`Validity`] along one stride from the fixed point's post-impact state.
pub fn validity(m: &BuiltModel, fp: &FixedPoint) -> Option<Validity> {
    use pdw_hybrid::{GuardKind, Integrator, StopReason};
    let w = m.walker.as_ref();
    let mut v = Validity {
        min_normal_force: f64::INFINITY,
        ..Validity::default()
    };
    let mut integ = Integrator::new(w.dim(), Options::dop853(1e-10)).ok()?;
    let (mut t, mut x, mut mode) = (0.0, fp.state.clone(), w.section_mode());
    let mut buf = vec![0.0; x.len()];
    let t_end = 2.0 * fp.metrics.period;
    let mut supported = true;
    for _ in 0..64 {
        let m0 = mode;
        let stop = integ.integrate_observed(w, mode, &mut t, &mut x, t_end, &mut |_, xs| match (
            w.constraint_forces(m0, xs),
            w.step_flags(m0, xs),
        ) {
            (Some(cf), Some(fl)) => {
                v.samples += 1;
                v.min_normal_force = v.min_normal_force.min(cf.normal);
                v.max_friction_required = v.max_friction_required.max(cf.friction_required);
                for tq in cf.knee_torque.iter().flatten() {
                    v.min_knee_torque = Some(v.min_knee_torque.map_or(*tq, |k| k.min(*tq)));
                }
                v.normal_force_negative |= fl.normal_force_negative;
                v.knee_unlocks |= fl.knee_unlocks;
                v.swing_foot_scuffs |= fl.swing_foot_scuffs;
            }
            _ => supported = false,
        });
        match stop {
            StopReason::Guard { guard } if w.guards(mode)[guard].kind == GuardKind::Reset => {
                if (mode, guard) == w.section_guard() {
                    break;
                }
                mode = w.reset(integ.scratch(), mode, guard, &x, &mut buf);
                x.copy_from_slice(&buf);
            }
            _ => return None,
        }
    }
    (supported && v.samples > 0).then_some(v)
}

pub fn run(a: &FixedpointArgs) -> anyhow::Result<ExitCode> {
    if !(a.tol.is_finite() && a.tol > 0.0) {
        return Err(InputError(format!("--tol: {} must be a positive number", a.tol)).into());
    }
    let which = a.gait.as_str();
    if !matches!(which, "stable" | "unstable" | "all") {
        return Err(InputError(format!(
            "--gait: '{which}' is not one of stable, unstable, all"
        ))
        .into());
    }
    if a.sweep.is_some() {
        return super::sweep::run(a);
    }
    let m = build_model(&a.model)?;
    let ds = m.info.section_names.len();
    let guesses: Vec<(String, Vec<f64>)> = match &a.guess {
        Some(g) => {
            let v = args::parse_guess(g)?;
            if v.len() != ds {
                return Err(InputError(format!(
                    "--guess: {} values given, model '{}' has {} section coordinates ({})",
                    v.len(),
                    m.info.name,
                    ds,
                    m.info.section_names.join(", ")
                ))
                .into());
            }
            vec![("guess".to_string(), v)]
        }
        None => m
            .walker
            .gait_guesses()
            .into_iter()
            .map(|g| (g.gait.to_string(), g.section))
            .collect(),
    };
    let (found, failed) = search(&m, &guesses, a.tol)?;
    let selected: Vec<&Found> = found
        .iter()
        .filter(|f| match which {
            "stable" => f.fp.stable,
            "unstable" => !f.fp.stable,
            _ => true,
        })
        .collect();

    if a.json {
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
                    "validity": validity(&m, fp).map(|v| v.json()),
                })
            })
            .collect();
        let out = serde_json::json!({
            "model": m.info.name,
            "slope": m.slope(),
            "params": m.params_json(),
            "section_names": m.info.section_names,
            "fixed_points": fps,
        });
        crate::outln!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        crate::outln!(
            "model {}  slope {} rad ({:.4} deg)",
            m.info.name,
            m.slope(),
            m.slope().to_degrees()
        );
        for f in &selected {
            print_fixed_point(&m, f);
        }
    }
    if selected.is_empty() {
        eprintln!(
            "no {} period-one gait found for model '{}' from {} guess(es)",
            if which == "all" { "" } else { which },
            m.info.name,
            guesses.len()
        );
        for (label, g, e) in &failed {
            report_failure(label, g, e);
        }
        eprintln!(
            "try: another --guess (section coordinates {}), a smaller --slope, or continuation \
             from a slope where a gait exists (--sweep slope=A:B:N)",
            m.info.section_names.join(", ")
        );
        return Ok(ExitCode::from(2));
    }
    Ok(ExitCode::SUCCESS)
}

fn print_fixed_point(m: &BuiltModel, f: &Found) {
    let fp = &f.fp;
    crate::outln!();
    crate::outln!(
        "{} gait (from guess '{}')",
        if fp.stable { "stable" } else { "unstable" },
        f.label
    );
    for (n, v) in m.info.section_names.iter().zip(&fp.section) {
        crate::outln!("  {n:<12} {v:>22.15}");
    }
    crate::outln!("  period       {:>22.15}", fp.metrics.period);
    if let Some(l) = fp.metrics.step_length {
        crate::outln!("  step length  {l:>22.15}");
    }
    if let Some(v) = fp.metrics.speed {
        crate::outln!("  speed        {v:>22.15}");
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
        crate::outln!(
            "  validity     {}: normal force ≥ {:.4}, friction needed ≤ {:.4}{}",
            if v.valid() { "ok" } else { "FLAGGED" },
            v.min_normal_force,
            v.max_friction_required,
            v.min_knee_torque
                .map(|k| format!(", knee-lock torque ≥ {k:.4}"))
                .unwrap_or_default()
        );
        for (flag, what) in [
            (
                v.normal_force_negative,
                "the stance foot would lift off (normal force < 0)",
            ),
            (
                v.knee_unlocks,
                "a locked knee would unlock (lock torque < 0)",
            ),
            (
                v.swing_foot_scuffs,
                "the swing foot scuffs after mid-stance",
            ),
        ] {
            if flag {
                crate::outln!("    flag: {what}");
            }
        }
    }
    crate::outln!(
        "  residual ‖P(x) − x‖∞ = {:.3e} after {} Newton iterations",
        fp.residual,
        fp.iterations
    );
}

/// Prints why a Newton run failed (the error carries its residual history and last iterate).
pub fn report_failure(label: &str, guess: &[f64], e: &LimitError) {
    eprintln!("  guess '{label}' {guess:?}: {e}");
}
