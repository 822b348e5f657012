//! Errors of the limit-cycle layer.

use crate::stride::StrideOutcome;

/// Why a stride-map computation or a fixed-point search failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LimitError {
    /// The hybrid layer rejected options or a configuration.
    #[error(transparent)]
    Hybrid(#[from] pdw_hybrid::HybridError),
    /// A section state had the wrong number of coordinates.
    #[error("section state has {got} coordinates, the model's section has {expected}")]
    SectionDim { expected: usize, got: usize },
    /// A stride did not end at the section (fall, timeout, non-finite state, ...).
    #[error(
        "the stride from section state {from:?} did not reach the next heel strike: {outcome}"
    )]
    StrideFailed {
        from: Vec<f64>,
        outcome: StrideOutcome,
    },
    /// The Newton iteration did not reach ‖P(x) − x‖∞ ≤ tol.
    #[error(
        "no fixed point found: {reason} after {iterations} iterations; last iterate {last:?}, \
         residual history ‖P(x)−x‖∞ = {history:?}"
    )]
    NoConvergence {
        reason: String,
        iterations: u64,
        last: Vec<f64>,
        history: Vec<f64>,
    },
    /// The Newton matrix DP − I is singular or the linear solve produced non-finite values.
    #[error("DP − I is singular at {at:?}")]
    Singular { at: Vec<f64> },
    /// The eigenvalue computation failed.
    #[error("eigenvalue computation of the stride-map Jacobian failed")]
    Eigen,
    /// A model family could not build the model at a parameter value.
    #[error("cannot build the model at parameter value {}: {message}", shown(*.param))]
    Model { param: f64, message: String },
    /// Invalid solver option.
    #[error("invalid option `{name}` = {value}: {allowed}")]
    InvalidOption {
        name: &'static str,
        value: f64,
        allowed: &'static str,
    },
}

/// A value in a message: as Rust prints it where that is short, with an exponent beyond
/// 10^±6 (so 1e308 is not printed as 309 digits).
fn shown(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() || (1e-6..1e6).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:.6e}")
    }
}

impl LimitError {
    /// The computation was stopped by [`pdw_hybrid::interrupt::request`] (Ctrl-C, SIGTERM,
    /// KeyboardInterrupt); its partial results mean nothing.
    pub fn is_interrupted(&self) -> bool {
        matches!(
            self,
            LimitError::Hybrid(pdw_hybrid::HybridError::Interrupted)
        )
    }

    /// The error to return once [`pdw_hybrid::interrupt::requested`] is seen.
    pub fn interrupted() -> Self {
        LimitError::Hybrid(pdw_hybrid::HybridError::Interrupted)
    }
}
