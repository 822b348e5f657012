//! Typed errors of the kernel.

use thiserror::Error;

/// Everything that can go wrong when building a chain or calling a kernel with the wrong shapes.
///
/// Kernels never panic on bad input: a wrong slice length or matrix shape is reported here.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SoaError {
    /// A chain needs at least one joint.
    #[error("a chain needs at least one joint")]
    EmptyChain,
    /// Masses must be strictly positive (kg).
    #[error("link {link}: mass must be > 0, got {mass}")]
    NonPositiveMass { link: usize, mass: f64 },
    /// Rotational inertias about the COM must be non-negative (kg m²).
    #[error("link {link}: rotational inertia about the COM must be >= 0, got {inertia}")]
    NegativeInertia { link: usize, inertia: f64 },
    /// A revolute joint whose link has zero inertia about the joint axis (I_c + m|c|² = 0)
    /// would make the articulated inertia singular in some configurations.
    #[error("link {link}: revolute joint carries zero rotational inertia about its axis (inertia about COM is 0 and the COM sits on the joint)")]
    DegenerateRevoluteInertia { link: usize },
    /// Prismatic axes must be non-zero (they are normalised at construction).
    #[error("link {link}: prismatic axis must be non-zero, got [{ay}, {az}]")]
    ZeroPrismaticAxis { link: usize, ay: f64, az: f64 },
    /// A parameter is NaN or infinite.
    #[error("non-finite parameter `{what}`{}: {value}", match .link { Some(l) => format!(" of link {l}"), None => String::new() })]
    NonFinite {
        link: Option<usize>,
        what: &'static str,
        value: f64,
    },
    /// An argument has the wrong length or shape.
    #[error("dimension mismatch for `{what}`: expected {expected}, got {got}")]
    DimensionMismatch {
        what: &'static str,
        expected: String,
        got: String,
    },
    /// A joint index is out of range or repeated.
    #[error("invalid joint index {index} for a chain of {n} joints (out of range or repeated)")]
    InvalidJointIndex { index: usize, n: usize },
    /// A constraint operator (J 𝓜⁻¹ Jᵀ, A 𝓜⁻¹ Aᵀ or J Jᵀ) is singular: the constraint rows are
    /// linearly dependent in this configuration.
    #[error(
        "singular constraint in `{what}`: the constraint rows are dependent in this configuration"
    )]
    SingularConstraint { what: &'static str },
    /// The mass matrix Cholesky factorisation failed (not positive definite numerically).
    #[error("mass matrix is not numerically positive definite")]
    MassMatrixNotPositiveDefinite,
    /// Newton iteration for inverse kinematics did not converge.
    #[error(
        "inverse kinematics did not converge in {iterations} iterations (residual {residual:e})"
    )]
    IkNotConverged { iterations: usize, residual: f64 },
}

pub(crate) fn check_len(what: &'static str, expected: usize, got: usize) -> Result<(), SoaError> {
    if expected == got {
        Ok(())
    } else {
        Err(SoaError::DimensionMismatch {
            what,
            expected: expected.to_string(),
            got: got.to_string(),
        })
    }
}

pub(crate) fn check_shape(
    what: &'static str,
    expected: (usize, usize),
    got: (usize, usize),
) -> Result<(), SoaError> {
    if expected == got {
        Ok(())
    } else {
        Err(SoaError::DimensionMismatch {
            what,
            expected: format!("{} x {}", expected.0, expected.1),
            got: format!("{} x {}", got.0, got.1),
        })
    }
}
