//! Period-one gaits of a built model from the user's guess or the model's own: the one gait
//! search behind every command and Python function that needs a gait
//! ([`pdw_limit::gaits::search`] underneath).

use crate::input::{AxisRange, InputError};
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

/// Starts of a scan when the front end gives no number ([`scan`]).
pub const SCAN_STARTS: usize = 256;

/// The box a scan samples: the model's own ([`pdw_walkers::Walker::section_box`]) with the
/// coordinates named in `given` replaced by their ranges (each a section coordinate, its range
/// finite and increasing; messages name `flag`, e.g. `--search-box`). A model without a box of
/// its own needs every coordinate given.
pub fn scan_box(
    m: &BuiltModel,
    given: &[AxisRange],
    flag: &str,
) -> Result<pdw_limit::scan::ScanBox, InputError> {
    let names = &m.info.section_names;
    let (mut lo, mut hi) = match m.walker.section_box() {
        Some(b) => b,
        None => (vec![f64::NAN; names.len()], vec![f64::NAN; names.len()]),
    };
    let mut seen = vec![false; names.len()];
    for r in given {
        let Some(i) = names.iter().position(|n| *n == r.name) else {
            return Err(InputError(format!(
                "{flag}: model '{}' has no section coordinate '{}'; its coordinates are {}",
                m.info.name,
                r.name,
                names.join(", ")
            )));
        };
        if seen[i] {
            return Err(InputError(format!("{flag}: '{}' is given twice", r.name)));
        }
        if !(r.lo.is_finite() && r.hi.is_finite() && r.lo < r.hi) {
            return Err(InputError(format!(
                "{flag}: range {}:{} of '{}' is empty or inverted; the first bound must be below \
                 the second",
                r.lo, r.hi, r.name
            )));
        }
        seen[i] = true;
        (lo[i], hi[i]) = (r.lo, r.hi);
    }
    if let Some(i) = lo.iter().position(|v| v.is_nan()) {
        return Err(InputError(format!(
            "{flag}: model '{}' has no default box to scan; give the range of '{}' (and of every \
             section coordinate: {}) as {flag} NAME=LO:HI",
            m.info.name,
            names[i],
            names.join(", ")
        )));
    }
    Ok(pdw_limit::scan::ScanBox { lo, hi })
}

/// Scans `b` for every gait ([`pdw_limit::scan::scan`]) with `starts` starts on `pool`,
/// Newton to `tol` on the stride map integrated by `integrator`.
pub fn scan(
    m: &BuiltModel,
    b: &pdw_limit::scan::ScanBox,
    starts: usize,
    tol: f64,
    integrator: &Options,
    pool: &rayon::ThreadPool,
) -> Result<pdw_limit::scan::Scan, LimitError> {
    let opts = pdw_limit::scan::ScanOptions {
        integrator: *integrator,
        ..pdw_limit::scan::ScanOptions::new(starts, tol)
    };
    pdw_limit::scan::scan(m.walker.as_ref(), b, &opts, pool)
}
