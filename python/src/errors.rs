//! The errors Python sees: `ValueError` with the library's message (the one the CLI prints),
//! and the messages for a model without a gait to start from.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::Model;
use pdw::limit::gaits;

/// A `ValueError` carrying `msg`: every invalid input, with the library's own message.
pub(crate) fn err(msg: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(msg.to_string())
}

/// No gait of kind `which` from `n` guesses: the library's message, each failed guess named.
pub(crate) fn no_gait_error(m: &Model, which: &str, n: usize, failed: &[gaits::Failed]) -> PyErr {
    err(pdw::gaits::no_gait_message(m, which, n, failed))
}

/// No start gait for a sweep: the values tried (Newton from the guesses, then a section scan at
/// each), the failed guesses at the first, and what to pass instead.
pub(crate) fn no_start_error(
    m: &Model,
    plan: &pdw::sweep::SweepPlan,
    which: &str,
    none: &pdw::sweep::NoStart,
) -> PyErr {
    let values: Vec<String> = none.tried.iter().map(|v| v.to_string()).collect();
    let mut msg = format!(
        "no {which} period-one gait of model '{}' at {} = {} to start the continuation from (at \
         each: Newton from the guesses, then a scan of the section with {} starts); pass \
         start_at= a value of the range with a gait (gaits() lists the gaits at one value)",
        m.info.name,
        plan.grid.name,
        values.join(", "),
        pdw::sweep::START_SCAN_STARTS
    );
    for (label, g, e) in &none.failed {
        msg.push_str(&format!("\n  guess '{label}' {g:?}: {e}"));
    }
    err(msg)
}
