//! Errors of the hybrid-simulation layer. A fallen walker or a non-finite state is an outcome
//! ([`StopReason`](crate::StopReason)), not an error; errors are bad parameters and misuse.

/// Errors returned by constructors and batch runners.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HybridError {
    /// An integrator option is out of its allowed range.
    #[error("invalid integrator option `{name}` = {value}: {allowed}")]
    InvalidOption {
        name: &'static str,
        value: f64,
        allowed: &'static str,
    },
    /// The state dimension must be at least 1.
    #[error("state dimension must be at least 1 (got {dim})")]
    ZeroDimension { dim: usize },
    /// The integrator was built for another dimension than the system's.
    #[error("integrator built for state dimension {expected}, but the system has dimension {got}")]
    DimensionMismatch { expected: usize, got: usize },
    /// A batch needs at least one lane.
    #[error("a batch needs at least one lane (got {lanes})")]
    NoLanes { lanes: usize },
    /// A parallel batch needs a chunk size of at least one item.
    #[error("chunk size must be at least 1 item (got {chunk})")]
    ZeroChunk { chunk: usize },
    /// A driver asked for a mode the system does not have.
    #[error("mode {mode} out of range: the system has {n_modes} modes")]
    ModeOutOfRange { mode: usize, n_modes: usize },
    /// A stop was requested ([`crate::interrupt::request`]: Ctrl-C, SIGTERM, KeyboardInterrupt).
    #[error("interrupted")]
    Interrupted,
}
