//! Closed-chain dynamics: the tip point held fixed (seed §3.5, eq. 3.24–3.28).
//!
//! The constraint is on the tip point's linear motion (a point contact: the tip may rotate):
//! `J_lin q̇ = 0`, `J_lin q̈ + J̇_lin q̇ = 0` (eq. 3.24). The tip pushes on the environment with
//! `F_t = [0, f_c]` (eq. 3.25, 3.28), and `𝓜 q̈ = τ − C − J_linᵀ f_c`, hence (eq. 3.26)
//!
//! ```text
//! f_c = (J 𝓜⁻¹ Jᵀ)⁻¹ (J 𝓜⁻¹ (τ − C) + J̇ q̇)
//! ```
//!
//! Computed in O(n) without forming 𝓜: one articulated-body solve gives the unconstrained
//! `q̈₀ = 𝓜⁻¹(τ − C)`, and two force-only sweeps over the same factorisation give
//! `𝓜⁻¹ Jᵀ e_y` and `𝓜⁻¹ Jᵀ e_z`; the 2 × 2 operational-space inverse inertia
//! `Λ⁻¹ = J 𝓜⁻¹ Jᵀ` follows, then `f_c = Λ (J q̈₀ + J̇ q̇)` and `q̈ = q̈₀ − 𝓜⁻¹ Jᵀ f_c`.
//!
//! **Base reaction.** With `q̈` and `F_t` known, the outward RNEA force recursion gives the
//! spatial force `F_0` transmitted across joint 0 from the base (the stance foot's ground) onto
//! link 0: `[τ_0, f_y, f_z]` with `f_z` the normal and `f_y` the tangential (downhill) ground
//! reaction. The ground reaction on the constrained tip (the other foot) is `−f_c`.

use crate::aba::aba_passes;
use crate::chain::Chain;
use crate::error::{check_len, SoaError};
use crate::kinematics::{fill_jacobian, positions_from_kin, tip_acc_from_kin};
use crate::rnea::rnea_passes;
use crate::spatial;
use crate::workspace::{kin_pass, Workspace};

/// Result of [`closed_chain_dynamics`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosedChainForces {
    /// `f_c = [f_y, f_z]`: force the tip exerts on the environment (N). The environment's
    /// reaction on the tip is `−f_c` (normal component `−f_z`).
    pub tip_force: [f64; 2],
    /// `F_0 = [τ, f_y, f_z]`: spatial force from the base (ground) onto link 0 at the base point.
    pub base_reaction: [f64; 3],
}

/// Joint accelerations with the tip point held fixed, the constraint force and the base
/// reaction (seed eq. 3.26). `qdd` (length `n`) receives the accelerations.
///
/// # Errors
/// [`SoaError::SingularConstraint`] when `J 𝓜⁻¹ Jᵀ` is singular (tip Jacobian rank < 2,
/// e.g. a single link or a fully stretched chain).
pub fn closed_chain_dynamics(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
    qdd: &mut [f64],
) -> Result<ClosedChainForces, SoaError> {
    let n = chain.dof();
    check_len("tau", n, tau.len())?;
    check_len("qdd", n, qdd.len())?;
    kin_pass(chain, ws, q, Some(qd))?;
    positions_from_kin(chain, ws);
    fill_jacobian(chain, ws);
    aba_passes(chain, ws, tau, None, None, qdd);
    let a0 = tip_acc_from_kin(chain, ws, Some(qdd));
    // responses r_y = −𝓜⁻¹ Jᵀ e_y, r_z = −𝓜⁻¹ Jᵀ e_z into tmp, tmp2
    let mut ry = std::mem::take(&mut ws.tmp);
    let mut rz = std::mem::take(&mut ws.tmp2);
    force_response(chain, ws, [0.0, 1.0, 0.0], &mut ry);
    force_response(chain, ws, [0.0, 0.0, 1.0], &mut rz);
    // Λ⁻¹ = J 𝓜⁻¹ Jᵀ (2 × 2): column e = −J r_e
    let (mut l00, mut l01, mut l10, mut l11) = (0.0, 0.0, 0.0, 0.0);
    for k in 0..n {
        let (j1, j2) = (ws.jac[(1, k)], ws.jac[(2, k)]);
        l00 -= j1 * ry[k];
        l10 -= j2 * ry[k];
        l01 -= j1 * rz[k];
        l11 -= j2 * rz[k];
    }
    let det = l00 * l11 - l01 * l10;
    let scale = (l00 * l11).abs().max((l01 * l10).abs());
    if !det.is_finite() || det.abs() <= 1e-13 * scale {
        ws.tmp = ry;
        ws.tmp2 = rz;
        return Err(SoaError::SingularConstraint {
            what: "J 𝓜⁻¹ Jᵀ (closed chain)",
        });
    }
    // f_c = Λ a0 (tip acceleration a0 − Λ⁻¹ f_c = 0)
    let fy = (l11 * a0[1] - l01 * a0[2]) / det;
    let fz = (l00 * a0[2] - l10 * a0[1]) / det;
    for k in 0..n {
        qdd[k] += ry[k] * fy + rz[k] * fz;
    }
    let ft = [0.0, fy, fz];
    let mut tq = ry;
    rnea_passes(chain, ws, qdd, Some(ft), &mut tq);
    let base = ws.force[0];
    ws.tmp = tq;
    ws.tmp2 = rz;
    Ok(ClosedChainForces {
        tip_force: [fy, fz],
        base_reaction: base,
    })
}

/// `out = −𝓜⁻¹ Jᵀ F` for a tip force `F`, reusing the articulated inertias `P_k` and gains
/// `G_k` of the last articulated-body pass (no torques, biases or gravity: linear response).
#[allow(clippy::needless_range_loop)]
pub(crate) fn force_response(chain: &Chain, ws: &Workspace, f: [f64; 3], out: &mut [f64]) {
    let n = chain.dof();
    let mut cz = spatial::force_transport(&f, ws.tip_d[0], ws.tip_d[1]);
    // ν_k stored in out temporarily
    for k in (0..n).rev() {
        let p = &ws.p[k];
        let g = &ws.g[k];
        let (eps, d) = if chain.prismatic[k] {
            let (hy, hz) = (ws.hy[k], ws.hz[k]);
            let ph1 = p[3] * hy + p[4] * hz;
            let ph2 = p[4] * hy + p[5] * hz;
            (-(hy * cz[1] + hz * cz[2]), hy * ph1 + hz * ph2)
        } else {
            (-cz[0], p[0])
        };
        out[k] = eps / d;
        let zp = [cz[0] + g[0] * eps, cz[1] + g[1] * eps, cz[2] + g[2] * eps];
        cz = spatial::force_transport(&zp, ws.dy[k], ws.dz[k]);
    }
    let mut ap = [0.0; 3];
    for k in 0..n {
        let g = &ws.g[k];
        let ab = spatial::motion_transport(&ap, ws.dy[k], ws.dz[k]);
        let qk = out[k] - (g[0] * ab[0] + g[1] * ab[1] + g[2] * ab[2]);
        out[k] = qk;
        ap = if chain.prismatic[k] {
            [ab[0], ab[1] + ws.hy[k] * qk, ab[2] + ws.hz[k] * qk]
        } else {
            [ab[0] + qk, ab[1], ab[2]]
        };
    }
}
