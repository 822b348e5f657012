//! Period-one gaits of a registered walker: Newton from each of several guesses, fixed points
//! de-duplicated, failures kept with their guess. The one search behind `pdw-sweep fixedpoint`,
//! `basin`, `animate` and the Python package.

use crate::error::LimitError;
use crate::newton::{find_fixed_point, FixedPoint, NewtonOptions};
use crate::stride::StrideMap;
use pdw_hybrid::Options;
use pdw_walkers::Walker;

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
