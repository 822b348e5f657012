//! Exact first derivatives of forward dynamics, of the plastic impact maps and of the tip
//! position, by forward-mode dual numbers ([`crate::dual::Dual`]) through the kernel's own
//! per-link step functions ([`crate::spatial`]), not by finite differences.
//!
//! # Forward dynamics (seed §3.4 for the locked joints)
//! Let `ID(q, q̇, q̈)` be inverse dynamics (RNEA, seed eq. 2.57–2.62, no tip force). Forward
//! dynamics with the joints `l` locked as pseudo joints and the others `f` free is the solution of
//!
//! ```text
//! ID_f(q, q̇, q̈) = τ_f,    q̈_l = 0
//! ```
//! (`𝓜_ff q̈_f = τ_f − C_f`, the Schur-complement form of seed eq. 3.23). RNEA is linear in `q̈`,
//! so `∂ID/∂q̈ = 𝓜`; differentiating the identity along any input `x ∈ {q, q̇}` gives
//! (Carpentier & Mansard 2018, "Analytical derivatives of rigid body dynamics algorithms", RSS:
//! the derivatives of forward dynamics are `−𝓜⁻¹` times those of inverse dynamics evaluated at
//! the forward-dynamics solution)
//!
//! ```text
//! ∂q̈_f/∂x = −𝓜_ff⁻¹ ∂ID_f/∂x |_{q̈ = FD(q, q̇, τ)},    ∂q̈_l/∂x = 0.
//! ```
//! The value `q̈` is the kernel's articulated-body recursion ([`crate::aba()`],
//! [`crate::pseudo_joint_dynamics`]) run on the same step functions, so it equals theirs bit for
//! bit. Then **one** RNEA pass in duals of width `3n`, seeded on `(q, q̇, q̈)` at that `q̈`,
//! returns `∂ID/∂q`, `∂ID/∂q̇` and `𝓜 = ∂ID/∂q̈` at once; an `LDLᵀ` factorisation of `𝓜_ff`
//! (on the stack) gives the Jacobians.
//!
//! # Impacts
//! The plastic impact of [`crate::impact`] is `q̇⁺ = q̇⁻ − X Λ` with `X = 𝓜⁻¹Aᵀ`,
//! `S = A X`, `Λ = S⁻¹ A q̇⁻`; `A` holds the linear tip-Jacobian rows (heel strike) and/or
//! `e_kᵀ` for each locked joint `k`. The map is linear in `q̇⁻`, so
//! `∂q̇⁺/∂q̇⁻ = I − X S⁻¹ A`, and `∂q̇⁺/∂q` follows from running the whole computation in duals
//! of width `n` seeded on `q`: kinematics and the tip Jacobian by the generic kinematic steps,
//! `𝓜(q)` by the generic composite-rigid-body steps of [`crate::crba()`], the two solves by
//! `LDLᵀ` in duals.
//!
//! The value `q̇⁺` is computed apart, in `f64`, by the kernel's operations in the kernel's order
//! (the same kinematics and CRBA steps, faer's `LLᵀ` on stack storage): it equals
//! [`crate::tip_impact`] / [`crate::joint_lock_impact`] bit for bit, and a configuration is
//! rejected as singular exactly when the kernel rejects it. (Two backward-stable evaluations
//! of `q̇⁺` in a different order differ by `~ε κ`, up to `2e-13` relative on random 8-joint
//! chains; the value does not depend on the order chosen for the derivatives.)
//!
//! # Sizes, layout, memory
//! Chains of `1 ≤ n ≤` [`MAX_DOF`] joints; the dual width is chosen from `n` (`3n` for forward
//! dynamics, `n` otherwise), so a small chain pays for its own size only. Jacobians are written
//! row-major: entry `(i, j)` of an `r × c` Jacobian is `jac[i * c + j]`. Everything lives on the
//! stack; no call allocates (the error values of a failed call aside).

// The generic helpers mirror the kernel's index loops over several per-link arrays.
#![allow(clippy::needless_range_loop)]

mod aba;
mod impact;
mod kinematics;
mod rnea;
mod rolling;

pub use aba::aba_derivatives;
pub use impact::{contact_impact, joint_lock_impact_derivatives, tip_impact_derivatives};
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub use impact::FAER_SCRATCH;
pub(crate) use impact::{impact_in_duals, mass_matrix};
pub use kinematics::tip_position_derivatives;
pub(crate) use kinematics::{kin, positions, Kin};
pub(crate) use rnea::rnea_passes;
pub(crate) use rolling::check_floating;
pub use rolling::{rolling_base_derivatives, rolling_base_dynamics};

use crate::dual::Scalar;
use crate::error::SoaError;

/// Largest number of joints the derivative routines accept.
pub const MAX_DOF: usize = 8;

pub(crate) type Vec8<T> = [T; MAX_DOF];
pub(crate) type Mat8<T> = [[T; MAX_DOF]; MAX_DOF];

// ---------------------------------------------------------------------------------------------
// Small dense LDLᵀ on the stack, on any Scalar.
// ---------------------------------------------------------------------------------------------

/// In-place `A = L D Lᵀ` of the leading `n × n` block of the symmetric `a` (lower triangle
/// read): strictly lower part ← `L`, diagonal ← `D`. Returns `(min Dᵢ, max Dᵢ)` of the values;
/// `None` if a pivot is not positive (or NaN).
pub(crate) fn ldl<T: Scalar>(a: &mut Mat8<T>, n: usize) -> Option<(f64, f64)> {
    let (mut dmin, mut dmax) = (f64::INFINITY, 0.0f64);
    for j in 0..n {
        let mut d = a[j][j];
        for k in 0..j {
            d = d - a[j][k] * a[j][k] * a[k][k];
        }
        if d.re().is_nan() || d.re() <= 0.0 {
            return None;
        }
        a[j][j] = d;
        dmin = dmin.min(d.re());
        dmax = dmax.max(d.re());
        for i in j + 1..n {
            let mut s = a[i][j];
            for k in 0..j {
                s = s - a[i][k] * a[j][k] * a[k][k];
            }
            a[i][j] = s / d;
        }
    }
    Some((dmin, dmax))
}

/// Solve `L D Lᵀ x = b` in place (`b` of length `n`) with a factor from [`ldl`].
pub(crate) fn ldl_solve<T: Scalar>(f: &Mat8<T>, n: usize, b: &mut [T]) {
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s = s - f[i][k] * b[k];
        }
        b[i] = s;
    }
    for i in 0..n {
        b[i] = b[i] / f[i][i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s = s - f[k][i] * b[k];
        }
        b[i] = s;
    }
}

// ---------------------------------------------------------------------------------------------
// Argument checks and dispatch on the chain size.
// ---------------------------------------------------------------------------------------------

pub(crate) fn check_dof(n: usize) -> Result<(), SoaError> {
    if n <= MAX_DOF {
        Ok(())
    } else {
        Err(SoaError::DimensionMismatch {
            what: "joints of a chain for derivatives",
            expected: format!("at most {MAX_DOF}"),
            got: n.to_string(),
        })
    }
}

/// Call `$f::<W>(args)` with the dual width `W = $mult · n` for `n = 1..=MAX_DOF`.
macro_rules! by_dof {
    ($n:expr, $mult:literal, $f:ident ( $($arg:expr),* $(,)? )) => {
        match $n {
            1 => $f::<{ $mult }>($($arg),*),
            2 => $f::<{ 2 * $mult }>($($arg),*),
            3 => $f::<{ 3 * $mult }>($($arg),*),
            4 => $f::<{ 4 * $mult }>($($arg),*),
            5 => $f::<{ 5 * $mult }>($($arg),*),
            6 => $f::<{ 6 * $mult }>($($arg),*),
            7 => $f::<{ 7 * $mult }>($($arg),*),
            _ => $f::<{ 8 * $mult }>($($arg),*),
        }
    };
}
pub(crate) use by_dof;
