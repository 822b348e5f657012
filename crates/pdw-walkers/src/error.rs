//! Errors of model construction: bad parameter values, unknown names.

/// A value as a message prints it: the shortest round-trip decimal, with an exponent beyond
/// 10^±6 (`1e308`, not 309 digits).
fn short(v: &f64) -> String {
    if v.is_finite() && *v != 0.0 && !(1e-6..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Why a model could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum WalkerError {
    /// A parameter value outside its allowed range (or not finite).
    #[error("parameter `{name}` = {} is invalid: must be {allowed}", short(.value))]
    InvalidParam {
        name: &'static str,
        value: f64,
        allowed: &'static str,
    },
    /// A parameter name the model does not have.
    #[error("model `{model}` has no parameter `{name}`; valid parameters: {valid}")]
    UnknownParam {
        model: String,
        name: String,
        valid: String,
    },
    /// A model name that is not registered (and not a spec file).
    #[error("unknown model `{name}`; valid models: {valid}, or a walker spec file (.toml)")]
    UnknownModel { name: String, valid: String },
    /// A walker spec field with a value that breaks a rule, e.g. a negative mass.
    #[error("{source_name}: `{field}` = {value} is invalid: {rule}")]
    InvalidSpec {
        /// The spec's file (or preset) name.
        source_name: String,
        /// Path of the field, e.g. `segments[1].mass`.
        field: String,
        /// The offending value as written or evaluated.
        value: String,
        /// The rule it breaks.
        rule: String,
    },
    /// A walker spec that cannot be read or parsed (syntax, unknown keys, wrong types).
    #[error("{source_name}: {message}")]
    SpecSyntax {
        source_name: String,
        message: String,
    },
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
