//! Period-one gaits (and period-K orbits, [`search_periodic`]) of a registered walker: Newton from each of several guesses, fixed points
//! de-duplicated, failures kept with their guess. The one search behind `pdw-sweep fixedpoint`,
//! `basin`, `animate` and the Python package.

use crate::continuation::real_eigenvector;
use crate::error::LimitError;
use crate::floquet::{is_stable, multipliers};
use crate::newton::{find_fixed_point, FixedPoint, NewtonOptions};
use crate::periodic::{
    canonical_start, find_periodic_orbit, iterate_map, same_orbit, PeriodKProblem, PeriodicOrbit,
};
use crate::stride::StrideMap;
use pdw_hybrid::Options;
use pdw_model::Walker;

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

/// The model's own guesses ([`Walker::gait_guesses`]) as `(label, section state)`.
pub fn model_guesses(w: &dyn Walker) -> Vec<(String, Vec<f64>)> {
    w.gait_guesses()
        .into_iter()
        .map(|g| (g.gait.to_string(), g.section))
        .collect()
}

/// Runs Newton (residual tolerance `tol`) from every guess, de-duplicates the fixed points found
/// (relative 1e-8 in every section coordinate), and returns them with the failures.
pub fn search(
    w: &dyn Walker,
    guesses: &[(String, Vec<f64>)],
    tol: f64,
) -> Result<(Vec<Found>, Vec<Failed>), LimitError> {
    search_with(w, guesses, tol, &default_integrator(tol))
}

/// The stride-map integrator of [`search`] for residual tolerance `tol`: DOP853 at
/// `max(FIXEDPOINT_INTEGRATOR_TOL, tol/100)`.
pub fn default_integrator(tol: f64) -> Options {
    Options::dop853(FIXEDPOINT_INTEGRATOR_TOL.max(tol * 1e-2))
}

/// [`search`] with the stride map integrated by `integrator` (validated here; an invalid option
/// is [`LimitError`]'s invalid-option error naming it).
pub fn search_with(
    w: &dyn Walker,
    guesses: &[(String, Vec<f64>)],
    tol: f64,
    integrator: &Options,
) -> Result<(Vec<Found>, Vec<Failed>), LimitError> {
    let step = |x: &[f64]| w.step_length(x);
    let map = StrideMap::new(w, *integrator)?.with_step_length(&step);
    let opts = NewtonOptions {
        tol,
        ..NewtonOptions::default()
    };
    let mut found: Vec<Found> = Vec::new();
    let mut failed = Vec::new();
    for (label, g) in guesses {
        if pdw_hybrid::interrupt::requested() {
            return Err(LimitError::interrupted());
        }
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
            Err(e) if e.is_interrupted() => return Err(e),
            Err(e) => failed.push((label.clone(), g.clone(), e)),
        }
    }
    Ok((found, failed))
}

/// Strides the map is iterated from each guess before Newton on `P^K` starts from where the
/// iterates went: long enough for a trajectory to settle on a stable period-K orbit of a
/// contracting map (a perturbation of 1e-1 shrinks below 1e-6 at |λ| ≤ 0.97 per stride).
pub const PERIOD_K_ITERATES: usize = 400;

/// Offsets ε of the period-doubling predictors `s₁ ± ε v`: the period-2 orbit's distance from
/// the period-one gait grows like √(μ − μ_PD), so one offset near the bifurcation and larger
/// ones further past it.
pub const PD_OFFSETS: [f64; 3] = [1e-3, 1e-2, 5e-2];

/// One period-K orbit found, with the name of the guess it came from.
pub struct FoundOrbit {
    pub label: String,
    pub orbit: PeriodicOrbit,
}

/// Period-`k` orbits: Newton on `P^k − id` ([`find_periodic_orbit`]) from
/// - every guess itself,
/// - the point the map reaches after [`PERIOD_K_ITERATES`] strides from every guess (where a
///   stable period-k orbit attracts it),
/// - for every period-one gait found from the guesses, the predictors of the period-doubled
///   branch `s₁ ± ε v` (v the eigenvector of the multiplier nearest −1, ε in [`PD_OFFSETS`]; the
///   period-2 orbit leaves the period-one one along v, see [`crate::continuation`]), and that
///   gait perturbed by 10⁻³ and iterated [`PERIOD_K_ITERATES`] strides;
///
/// de-duplicated as cycles ([`same_orbit`]) and rotated to start at their smallest point
/// ([`canonical_start`]), failures kept with their guess. `k = 1` is [`search`].
pub fn search_periodic(
    w: &dyn Walker,
    guesses: &[(String, Vec<f64>)],
    k: usize,
    tol: f64,
) -> Result<(Vec<FoundOrbit>, Vec<Failed>), LimitError> {
    let step = |x: &[f64]| w.step_length(x);
    let map = StrideMap::new(
        w,
        Options::dop853(FIXEDPOINT_INTEGRATOR_TOL.max(tol * 1e-2)),
    )?
    .with_step_length(&step);
    let opts = NewtonOptions {
        tol,
        ..NewtonOptions::default()
    };
    let mut starts: Vec<(String, Vec<f64>)> = Vec::new();
    for (label, g) in guesses {
        starts.push((label.clone(), g.clone()));
        if let Some(x) = iterate_map(&map, g, PERIOD_K_ITERATES) {
            starts.push((format!("{label}, iterated {PERIOD_K_ITERATES} strides"), x));
        }
    }
    if k > 1 {
        let (ones, _) = search(w, guesses, tol)?;
        let eps = 1e-3;
        for f in &ones {
            let s1 = &f.fp.section;
            let n = s1.len();
            // The real multiplier nearest −1 and its eigenvector.
            if let Some(l) =
                f.fp.multipliers
                    .iter()
                    .filter(|m| m.im == 0.0)
                    .min_by(|a, b| (a.re + 1.0).abs().total_cmp(&(b.re + 1.0).abs()))
            {
                if let Some(v) = real_eigenvector(&f.fp.dp, n, l.re) {
                    for e in PD_OFFSETS {
                        for sign in [1.0, -1.0] {
                            let g: Vec<f64> =
                                s1.iter().zip(&v).map(|(a, b)| a + sign * e * b).collect();
                            let pm = if sign > 0.0 { '+' } else { '−' };
                            starts.push((
                                format!("{} gait {pm} {e:e}·v(λ = {:.4})", f.label, l.re),
                                g,
                            ));
                        }
                    }
                }
            }
            let mut p = s1.clone();
            p[0] += eps;
            if let Some(x) = iterate_map(&map, &p, PERIOD_K_ITERATES) {
                starts.push((
                    format!("{} gait + ε, iterated {PERIOD_K_ITERATES} strides", f.label),
                    x,
                ));
            }
        }
    }
    let mut found: Vec<FoundOrbit> = Vec::new();
    let mut failed = Vec::new();
    for (label, g) in starts {
        if pdw_hybrid::interrupt::requested() {
            return Err(LimitError::interrupted());
        }
        match find_periodic_orbit(&map, &g, k, &opts) {
            Ok(mut orbit) => {
                if !found
                    .iter()
                    .any(|f| same_orbit(&f.orbit.orbit, &orbit.orbit))
                {
                    rotate_to_canonical(&map, &mut orbit, &opts)?;
                    found.push(FoundOrbit { label, orbit });
                }
            }
            Err(e) if e.is_interrupted() => return Err(e),
            Err(e) => failed.push((label, g, e)),
        }
    }
    Ok((found, failed))
}

/// Re-expresses `orbit` from its canonical first point ([`canonical_start`]): points, states
/// and stride metrics rotated, `DP^K` re-computed there (same multipliers up to round-off).
pub(crate) fn rotate_to_canonical(
    map: &StrideMap<'_>,
    orbit: &mut PeriodicOrbit,
    opts: &NewtonOptions,
) -> Result<(), LimitError> {
    let c = canonical_start(&orbit.orbit);
    let Some(shift) = orbit.orbit.iter().position(|p| *p == c[0]) else {
        return Ok(());
    };
    if shift == 0 {
        return Ok(());
    }
    orbit.orbit.rotate_left(shift);
    orbit.states.rotate_left(shift);
    orbit.strides.rotate_left(shift);
    let prob = PeriodKProblem::new(map, orbit.period_k, opts.dp_report);
    orbit.dp = prob.dp_k(&orbit.orbit[0])?;
    orbit.multipliers = multipliers(&orbit.dp, orbit.orbit[0].len())?;
    orbit.stable = is_stable(&orbit.multipliers);
    Ok(())
}
