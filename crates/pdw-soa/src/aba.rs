//! O(n) forward dynamics: the articulated-body recursion, i.e. the SOA innovations
//! factorisation of `𝓜⁻¹` (Rodriguez, Jain & Kreutz-Delgado 1991; seed ch. 2 references).
//!
//! With `P_k` the articulated inertia of links `k..n` at joint `k`, `D_k = H_kᵀ P_k H_k`,
//! the gain `G_k = P_k H_k / D_k` and the innovation `ε_k = τ_k − H_kᵀ (z_k + P_k a_k)`:
//!
//! ```text
//! tip → base:  P_k = M_k + Φ_{k+1,k}ᵀ P⁺_{k+1} Φ_{k+1,k},   z_k = b_k + Φ_{k+1,k}ᵀ z⁺_{k+1}
//!              P⁺_k = P_k − G_k D_k G_kᵀ,   z⁺_k = z_k + P_k a_k + G_k ε_k
//!              (P⁺_{n+1} = 0, z⁺_{n+1} = Φ_{t,n}ᵀ F_t)
//! base → tip:  Ā_k = Φ_{k,k−1} A_{k−1} (A_0 = a_b),   q̈_k = ε_k / D_k − G_kᵀ Ā_k,
//!              A_k = Ā_k + H_k q̈_k + a_k
//! ```
//! It solves `𝓜 q̈ = τ − C − Jᵀ F_t` (seed eq. 2.63) without forming 𝓜. Each `D_k ≥` the
//! link's own inertia about the joint (> 0 by construction of [`Chain`]), so no division fails.

use crate::chain::Chain;
use crate::error::{check_len, SoaError};
use crate::spatial;
use crate::workspace::{kin_pass, Workspace};

/// Forward dynamics `q̈ = 𝓜⁻¹ (τ − C − Jᵀ F_t)` in O(n).
///
/// - `q`, `qd`: joint positions and rates (length `n`);
/// - `tau`: applied joint torques/forces (length `n`);
/// - `f_tip`: spatial force the tip exerts on the environment (see [`crate::rnea`]), or `None`;
/// - `qdd`: output joint accelerations (length `n`).
pub fn aba(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
    f_tip: Option<[f64; 3]>,
    qdd: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    check_len("tau", n, tau.len())?;
    check_len("qdd", n, qdd.len())?;
    kin_pass(chain, ws, q, Some(qd))?;
    aba_passes(chain, ws, tau, f_tip, None, qdd);
    Ok(())
}

/// Backward and forward articulated-body passes over a workspace filled by `kin_pass`.
/// `locked`: optional mask of locked joints (pseudo joints, seed §3.4), which get `q̈ = 0`.
pub(crate) fn aba_passes(
    chain: &Chain,
    ws: &mut Workspace,
    tau: &[f64],
    f_tip: Option<[f64; 3]>,
    locked: Option<&[bool]>,
    qdd: &mut [f64],
) {
    let n = chain.dof();
    let mut cp = [0.0; 6];
    let mut cz = match f_tip {
        Some(ft) => spatial::force_transport(&ft, ws.tip_d[0], ws.tip_d[1]),
        None => [0.0; 3],
    };
    for k in (0..n).rev() {
        let link = &chain.links[k];
        let is_locked = match locked {
            Some(mask) => mask[k],
            None => false,
        };
        let back = if is_locked {
            spatial::aba_back_locked(
                &cp,
                &cz,
                chain.j_joint[k],
                link.mass,
                ws.cy[k],
                ws.cz[k],
                ws.by[k],
                ws.bz[k],
                ws.ay[k],
                ws.az[k],
                ws.dy[k],
                ws.dz[k],
            )
        } else if chain.prismatic[k] {
            spatial::aba_back_pri(
                &cp,
                &cz,
                chain.j_joint[k],
                link.mass,
                ws.cy[k],
                ws.cz[k],
                ws.by[k],
                ws.bz[k],
                ws.ay[k],
                ws.az[k],
                ws.hy[k],
                ws.hz[k],
                tau[k],
                ws.dy[k],
                ws.dz[k],
            )
        } else {
            spatial::aba_back_rev(
                &cp,
                &cz,
                chain.j_joint[k],
                link.mass,
                ws.cy[k],
                ws.cz[k],
                ws.by[k],
                ws.bz[k],
                ws.ay[k],
                ws.az[k],
                tau[k],
                ws.dy[k],
                ws.dz[k],
            )
        };
        ws.g[k] = back.g;
        ws.nu[k] = back.nu;
        ws.p[k] = back.p;
        ws.z[k] = back.z;
        cp = back.cp;
        cz = back.cz;
    }
    let mut ap = chain.base_acc;
    for k in 0..n {
        let is_locked = match locked {
            Some(mask) => mask[k],
            None => false,
        };
        let (qk, a) = if is_locked {
            let ab = spatial::motion_transport(&ap, ws.dy[k], ws.dz[k]);
            (0.0, [ab[0], ab[1] + ws.ay[k], ab[2] + ws.az[k]])
        } else if chain.prismatic[k] {
            spatial::aba_fwd_pri(
                &ap, &ws.g[k], ws.nu[k], ws.ay[k], ws.az[k], ws.hy[k], ws.hz[k], ws.dy[k], ws.dz[k],
            )
        } else {
            spatial::aba_fwd_rev(
                &ap, ws.g[k][1], ws.g[k][2], ws.nu[k], ws.ay[k], ws.az[k], ws.dy[k], ws.dz[k],
            )
        };
        qdd[k] = qk;
        ws.acc[k] = a;
        ap = a;
    }
}
