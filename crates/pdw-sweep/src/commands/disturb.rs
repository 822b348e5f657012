//! `pdw-sweep disturb`: one step of another slope or height from the stable gait, then nominal
//! ground ([`pdw::disturb`]); or, with `--largest`, the largest such disturbance survived both
//! ways. This file parses and prints.

use super::build_model;
use crate::args::InputError;
use crate::cli::DisturbArgs;
use pdw::disturb::{self, Response, RETURN_TOL};
use pdw::limit::terrain::TerrainKind;
use pdw::output::number;
use pdw::BuiltModel;
use std::process::ExitCode;

/// The most steps `--steps` accepts.
const MAX_STEPS: usize = 1_000_000;

/// The names of `disturb`'s options in messages.
const FLAGS: pdw::mfpt::MfptFlags = pdw::mfpt::MfptFlags {
    terrain: "--terrain",
    sd: "--once",
    mean: "--mean",
    walkers: "--walkers",
    max_steps: "--steps",
    dist: "--dist",
};

pub fn run(a: &DisturbArgs) -> anyhow::Result<ExitCode> {
    // every step's deviation is kept (8 bytes a step) and each step is a stride to integrate:
    // a million bounds both (8 MB; minutes for the slowest walker)
    if !(1..=MAX_STEPS).contains(&a.steps) {
        return Err(InputError(format!(
            "--steps: {} is outside 1..={MAX_STEPS} (steps walked after the disturbance)",
            a.steps
        ))
        .into());
    }
    let kind = pdw::mfpt::check_terrain(&a.terrain, &FLAGS)?;
    let integrator = super::integrator(&a.integrator, pdw::mfpt::default_integrator())?;
    let m = build_model(&a.model)?;
    disturb::check(&m, kind)?;
    pdw::integrator::check_integrator(&m, &integrator)?;
    let unit = super::mfpt::terrain_unit(&m, kind);
    crate::outln!(
        "model {}  nominal {} {} {unit}; one disturbed step, then {} nominal steps at most",
        m.info.name,
        kind.param(),
        disturb::nominal(&m, kind),
        a.steps - 1
    );
    if let Some(once) = &a.once {
        let d = match kind {
            TerrainKind::Slope => pdw::input::parse_slope_for(once, "--once")?,
            TerrainKind::StepDown => pdw::mfpt::parse_height(once, "--once")?,
        };
        let r = disturb::respond(&m, kind, d, a.steps, integrator)?;
        report(&r, &unit);
        return Ok(ExitCode::SUCCESS);
    }
    if !(a.tol.is_finite() && a.tol > 0.0) {
        return Err(InputError(format!("--tol: {} must be > 0", a.tol)).into());
    }
    largest(a, &m, kind, integrator, &unit)?;
    Ok(ExitCode::SUCCESS)
}

/// One disturbance's outcome and the deviation's decay.
fn report(r: &Response, unit: &str) {
    match r.fall {
        Some(o) => crate::outln!(
            "disturbance {} {unit}: fell after {} heel strikes ({o})",
            number(r.disturbance),
            r.steps
        ),
        None => crate::outln!(
            "disturbance {} {unit}: walked all {} steps",
            number(r.disturbance),
            r.steps
        ),
    }
    match r.returned_after {
        Some(k) => crate::outln!("back within {RETURN_TOL:e} of the gait after {k} steps"),
        None => crate::outln!("not back within {RETURN_TOL:e} of the gait"),
    }
    let shown: Vec<String> = r
        .deviation
        .iter()
        .take(12)
        .map(|d| format!("{d:.2e}"))
        .collect();
    crate::outln!(
        "deviation from the gait after each step (section, inf-norm): {}{}",
        shown.join(" "),
        if r.deviation.len() > 12 { " …" } else { "" }
    );
}

/// `--largest`: both signs, bisected to `--tol`.
fn largest(
    a: &DisturbArgs,
    m: &BuiltModel,
    kind: TerrainKind,
    integrator: pdw::hybrid::Options,
    unit: &str,
) -> anyhow::Result<()> {
    let (names, limit) = match kind {
        TerrainKind::Slope => (["steeper", "shallower"], 1.5),
        TerrainKind::StepDown => (["step down", "step up"], 1e3),
    };
    for (name, sign) in names.iter().zip([1.0, -1.0]) {
        let (ok, fell) = disturb::largest(m, kind, sign, a.tol, limit, a.steps, integrator)?;
        crate::outln!(
            "largest {name} survived: {ok:.6e} {unit} (falls at {fell:.6e}; tolerance {:e}, \
             surviving = {} steps without a fall)",
            a.tol,
            a.steps
        );
        if (fell - ok).abs() > a.tol {
            crate::outln!(
                "note: the bisection stopped at the spacing of doubles: {ok:e} and {fell:e} are \
                 adjacent, {:e} {unit} apart, wider than --tol {:e}; no smaller tolerance can be \
                 met here",
                (fell - ok).abs(),
                a.tol
            );
        }
    }
    Ok(())
}
