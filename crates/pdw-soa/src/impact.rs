//! Plastic impulsive constraints: heel strike (tip velocity to zero) and knee strike (a joint
//! rate to zero), or any set of linear velocity constraints `A q̇⁺ = 0`.
//!
//! Integrating `𝓜 q̈ = … − Aᵀ λ(t)` over an impact of vanishing duration with `A q̇⁺ = 0`
//! (perfectly plastic, no slip) gives
//!
//! ```text
//! Λ = (A 𝓜⁻¹ Aᵀ)⁻¹ A q̇⁻,    q̇⁺ = q̇⁻ − 𝓜⁻¹ Aᵀ Λ
//! ```
//! (for `A = J_lin`, the 2 × n linear tip Jacobian: `q̇⁺ = q̇⁻ − 𝓜⁻¹Jᵀ(J𝓜⁻¹Jᵀ)⁻¹Jq̇⁻`).
//! `Λ` is the impulse the constrained points exert on the environment (same sign convention
//! as the tip force of [`crate::rnea()`]); the environment's impulse on the tip is `−Λ`.
//! The kinetic energy changes by exactly `ΔT = −½ (A q̇⁻)ᵀ Λ ≤ 0`.
//!
//! Dense: 𝓜 by CRBA, Cholesky of 𝓜 and of `A 𝓜⁻¹ Aᵀ` (faer), all in workspace memory.

use faer::dyn_stack::MemStack;
use faer::linalg::cholesky::llt;
use faer::{Conj, MatRef, Par};

use crate::chain::Chain;
use crate::crba::{crba_from_kin, factor_mass, solve_mass_in_place};
use crate::error::{check_len, check_shape, SoaError};
use crate::kinematics::{fill_jacobian, positions_from_kin};
use crate::pseudo_joint::set_mask;
use crate::workspace::{kin_pass, Workspace};

/// Core: constraint rows are the first `m` rows of `ws.arows`.
#[allow(clippy::needless_range_loop)]
fn impulse_from_rows(
    ws: &mut Workspace,
    m: usize,
    qd_minus: &[f64],
    qd_plus: &mut [f64],
    impulse: &mut [f64],
) -> Result<(), SoaError> {
    let n = ws.n;
    factor_mass(ws)?;
    // X = 𝓜⁻¹ Aᵀ (n × m)
    for i in 0..m {
        for k in 0..n {
            ws.rhs[(k, i)] = ws.arows[(i, k)];
        }
    }
    solve_mass_in_place(ws, m);
    // S = A X (m × m), y = A q̇⁻
    for i in 0..m {
        for j in 0..m {
            let mut s = 0.0;
            for k in 0..n {
                s += ws.arows[(i, k)] * ws.rhs[(k, j)];
            }
            ws.small[(i, j)] = s;
        }
        let mut y = 0.0;
        for k in 0..n {
            y += ws.arows[(i, k)] * qd_minus[k];
        }
        ws.small_rhs[(i, 0)] = y;
    }
    let stack = MemStack::new(&mut ws.mem);
    llt::factor::cholesky_in_place(
        ws.small.as_mut().submatrix_mut(0, 0, m, m),
        Default::default(),
        Par::Seq,
        stack,
        Default::default(),
    )
    .map_err(|_| SoaError::SingularConstraint {
        what: "A 𝓜⁻¹ Aᵀ (impact)",
    })?;
    // reject numerically rank-deficient constraint sets: tiny pivot relative to the largest
    let (mut dmin, mut dmax) = (f64::INFINITY, 0.0f64);
    for i in 0..m {
        let d = ws.small[(i, i)].abs();
        dmin = dmin.min(d);
        dmax = dmax.max(d);
    }
    if dmin.is_nan() || dmin <= 1e-7 * dmax {
        return Err(SoaError::SingularConstraint {
            what: "A 𝓜⁻¹ Aᵀ (impact)",
        });
    }
    llt::solve::solve_in_place_with_conj(
        ws.small.as_ref().submatrix(0, 0, m, m),
        Conj::No,
        ws.small_rhs.as_mut().submatrix_mut(0, 0, m, 1),
        Par::Seq,
        stack,
    );
    for (i, l) in impulse.iter_mut().enumerate() {
        *l = ws.small_rhs[(i, 0)];
    }
    for k in 0..n {
        let mut s = 0.0;
        for (i, l) in impulse.iter().enumerate() {
            s += ws.rhs[(k, i)] * l;
        }
        qd_plus[k] = qd_minus[k] - s;
    }
    Ok(())
}

/// General plastic impact with constraint rows `A` (`m × n`, `m ≤ n`): returns `q̇⁺` with
/// `A q̇⁺ = 0` and the impulse `Λ` (length `m`) (see the module docs).
pub fn impulsive_constraint(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd_minus: &[f64],
    a: MatRef<'_, f64>,
    qd_plus: &mut [f64],
    impulse: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    let m = a.nrows();
    check_len("qd_minus", n, qd_minus.len())?;
    check_len("qd_plus", n, qd_plus.len())?;
    check_len("impulse", m, impulse.len())?;
    if m == 0 || m > n {
        return Err(SoaError::DimensionMismatch {
            what: "constraint rows A (1 ≤ rows ≤ n)",
            expected: format!("1..={n} x {n}"),
            got: format!("{} x {}", a.nrows(), a.ncols()),
        });
    }
    check_shape("A", (m, n), (a.nrows(), a.ncols()))?;
    kin_pass(chain, ws, q, None)?;
    crba_from_kin(chain, ws);
    ws.arows.as_mut().submatrix_mut(0, 0, m, n).copy_from(a);
    impulse_from_rows(ws, m, qd_minus, qd_plus, impulse)
}

/// Heel strike / tip impact: the tip point's velocity becomes zero (rows = the 2 × n linear tip
/// Jacobian), optionally with the joints in `locked` also stopped (knee strike in the same
/// instant). Returns `q̇⁺` and the impulse: its first two entries are the tip impulse
/// `[Λ_y, Λ_z]` on the environment, followed by one locking impulse per entry of `locked`.
pub fn tip_impact(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd_minus: &[f64],
    locked: &[usize],
    qd_plus: &mut [f64],
    impulse: &mut [f64],
) -> Result<(), SoaError> {
    constraint_impact(chain, ws, q, qd_minus, true, locked, qd_plus, impulse)
}

/// Knee strike: the rates of the joints in `locked` become zero (rows `e_kᵀ`); the impulse
/// entries are the locking angular impulses, in the order of `locked`.
pub fn joint_lock_impact(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd_minus: &[f64],
    locked: &[usize],
    qd_plus: &mut [f64],
    impulse: &mut [f64],
) -> Result<(), SoaError> {
    constraint_impact(chain, ws, q, qd_minus, false, locked, qd_plus, impulse)
}

#[allow(clippy::too_many_arguments)]
fn constraint_impact(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd_minus: &[f64],
    tip: bool,
    locked: &[usize],
    qd_plus: &mut [f64],
    impulse: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    let m = locked.len() + if tip { 2 } else { 0 };
    check_len("qd_minus", n, qd_minus.len())?;
    check_len("qd_plus", n, qd_plus.len())?;
    check_len("impulse", m, impulse.len())?;
    if m == 0 || m > n {
        return Err(SoaError::DimensionMismatch {
            what: "number of impulsive constraints (1 ≤ rows ≤ n)",
            expected: format!("1..={n}"),
            got: m.to_string(),
        });
    }
    kin_pass(chain, ws, q, None)?;
    set_mask(ws, n, locked)?;
    positions_from_kin(chain, ws);
    fill_jacobian(chain, ws);
    crba_from_kin(chain, ws);
    ws.arows.fill(0.0);
    let mut row = 0;
    if tip {
        for k in 0..n {
            ws.arows[(0, k)] = ws.jac[(1, k)];
            ws.arows[(1, k)] = ws.jac[(2, k)];
        }
        row = 2;
    }
    for (i, &k) in locked.iter().enumerate() {
        ws.arows[(row + i, k)] = 1.0;
    }
    impulse_from_rows(ws, m, qd_minus, qd_plus, impulse)
}
