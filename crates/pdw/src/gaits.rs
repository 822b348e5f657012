//! Period-one gaits of a built model from the user's guess or the model's own: the one gait
//! search behind every command and Python function that needs a gait
//! ([`pdw_limit::gaits::search`] underneath).

use crate::input::InputError;
use crate::model::BuiltModel;
use pdw_hybrid::Options;
use pdw_limit::LimitError;

pub use pdw_limit::gaits::{model_guesses, Failed, Found, FoundOrbit};

/// The guesses to start Newton from: the user's section state (named `"guess"`, its length
/// checked against the model's section; messages name `what`, e.g. `--guess`) or, without
/// one, the model's own ([`pdw_walkers::Walker::gait_guesses`]).
pub fn guesses(
    m: &BuiltModel,
    user: Option<Vec<f64>>,
    what: &str,
) -> Result<Vec<(String, Vec<f64>)>, InputError> {
    let Some(g) = user else {
        return Ok(model_guesses(m.walker.as_ref()));
    };
    let ds = m.walker.section_dim();
    if g.len() != ds {
        return Err(InputError(format!(
            "{what}: {} values given, model '{}' has {} section coordinates ({})",
            g.len(),
            m.info.name,
            ds,
            m.info.section_names.join(", ")
        )));
    }
    Ok(vec![("guess".to_string(), g)])
}

/// Newton (residual tolerance `tol`) from every guess; see [`pdw_limit::gaits::search`].
pub fn search(
    m: &BuiltModel,
    guesses: &[(String, Vec<f64>)],
    tol: f64,
) -> Result<(Vec<Found>, Vec<Failed>), LimitError> {
    pdw_limit::gaits::search(m.walker.as_ref(), guesses, tol)
}

/// [`search`] with the stride map integrated by `integrator`.
pub fn search_with(
    m: &BuiltModel,
    guesses: &[(String, Vec<f64>)],
    tol: f64,
    integrator: &Options,
) -> Result<(Vec<Found>, Vec<Failed>), LimitError> {
    pdw_limit::gaits::search_with(m.walker.as_ref(), guesses, tol, integrator)
}

/// The gait a run centres on or animates: the first stable one found, else the first found.
pub fn selected(found: &[Found]) -> Option<&Found> {
    found.iter().find(|f| f.fp.stable).or_else(|| found.first())
}

/// Why no gait came out: the model, its slope, how many guesses were tried, and each failed
/// guess with its error, one per line. `which` is `"all"` or the gait asked for (`"stable"`,
/// `"unstable"`).
pub fn no_gait_message(m: &BuiltModel, which: &str, tried: usize, failed: &[Failed]) -> String {
    let mut msg = format!(
        "no {}period-one gait found for model '{}' at slope {} from {} guess(es)",
        if which == "all" {
            String::new()
        } else {
            format!("{which} ")
        },
        m.info.name,
        m.slope(),
        tried
    );
    for (label, g, e) in failed {
        msg.push_str(&format!("\n  guess '{label}' {g:?}: {e}"));
    }
    msg
}
