//! Errors of model construction: bad parameter values, unknown names.

/// Why a model could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum WalkerError {
    /// A parameter value outside its allowed range (or not finite).
    #[error("parameter `{name}` = {value} is invalid: must be {allowed}")]
    InvalidParam {
        name: &'static str,
        value: f64,
        allowed: &'static str,
    },
    /// A parameter name the model does not have.
    #[error("model `{model}` has no parameter `{name}`; valid parameters: {valid}")]
    UnknownParam {
        model: &'static str,
        name: String,
        valid: String,
    },
    /// A model name that is not registered.
    #[error("unknown model `{name}`; valid models: {valid}")]
    UnknownModel { name: String, valid: String },
}

/// Checks that `value` is finite and inside the open interval `(lo, hi)`.
pub(crate) fn check_open(
    name: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    allowed: &'static str,
) -> Result<f64, WalkerError> {
    if value.is_finite() && value > lo && value < hi {
        Ok(value)
    } else {
        Err(WalkerError::InvalidParam {
            name,
            value,
            allowed,
        })
    }
}
