//! Locked joints by the pseudo-joint technique (seed §3.4, eq. 3.18–3.23).
//!
//! The seed partitions the joints into real (`r`) and pseudo/locked (`p`) ones with a
//! permutation `S`, writes `q̈ = D τ̄ + E` with `D = 𝓜⁻¹`, and eliminates the locked torques
//! so that `q̈_p = 0`: `q̈_r = D_r τ̄_r + E_r` with `D_r = d₁ − d₂ d₄⁻¹ d₃` (eq. 3.23). By the
//! Schur-complement identity `D_r = (𝓜_rr)⁻¹`, so the real-joint accelerations solve
//! `𝓜_rr q̈_r = τ_r − C_r` and the locking torques are `τ_lock,p = 𝓜_pr q̈_r + C_p − τ_p`.
//!
//! Here this is computed in O(n) by the articulated-body recursion with the locked joints
//! treated as welds: a locked joint makes no innovation (`P⁺ = P`, `z⁺ = z + P a`) and gets
//! `q̈ = 0`. The force across every joint then follows from the articulated relation
//! `F_k = P_k A_k + z_k`, and the locking torque is `H_kᵀ F_k − τ_k`.

use crate::aba::aba_passes;
use crate::chain::Chain;
use crate::error::{check_len, SoaError};
use crate::workspace::{kin_pass, Workspace};

/// Fill `ws.mask` from a list of joint indices (range- and duplicate-checked).
pub(crate) fn set_mask(ws: &mut Workspace, n: usize, locked: &[usize]) -> Result<(), SoaError> {
    ws.mask.iter_mut().for_each(|m| *m = false);
    for &k in locked {
        if k >= n || ws.mask[k] {
            return Err(SoaError::InvalidJointIndex { index: k, n });
        }
        ws.mask[k] = true;
    }
    Ok(())
}

/// Forward dynamics with the joints in `locked` held at `q̈ = 0` (pseudo joints).
///
/// - `tau`: applied joint torques (length `n`; entries of locked joints are applied too);
/// - `f_tip`: tip force on the environment (see [`crate::rnea()`]) or `None`;
/// - `qdd`: output accelerations, exactly `0.0` at locked joints;
/// - `lock_torque`: output torque each lock must add (`0.0` at free joints), so that
///   `τ + τ_lock = 𝓜 q̈ + C + Jᵀ F_t`.
///
/// Also fills [`Workspace::joint_forces`] with the force across every joint.
#[allow(clippy::too_many_arguments)]
pub fn pseudo_joint_dynamics(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
    locked: &[usize],
    f_tip: Option<[f64; 3]>,
    qdd: &mut [f64],
    lock_torque: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    check_len("tau", n, tau.len())?;
    check_len("qdd", n, qdd.len())?;
    check_len("lock_torque", n, lock_torque.len())?;
    kin_pass(chain, ws, q, Some(qd))?;
    set_mask(ws, n, locked)?;
    let mask = std::mem::take(&mut ws.mask);
    aba_passes(chain, ws, tau, f_tip, Some(&mask), qdd);
    for k in 0..n {
        let p = &ws.p[k];
        let a = &ws.acc[k];
        let z = &ws.z[k];
        let f = [
            p[0] * a[0] + p[1] * a[1] + p[2] * a[2] + z[0],
            p[1] * a[0] + p[3] * a[1] + p[4] * a[2] + z[1],
            p[2] * a[0] + p[4] * a[1] + p[5] * a[2] + z[2],
        ];
        ws.force[k] = f;
        lock_torque[k] = if mask[k] {
            let hf = if chain.prismatic[k] {
                ws.hy[k] * f[1] + ws.hz[k] * f[2]
            } else {
                f[0]
            };
            hf - tau[k]
        } else {
            0.0
        };
    }
    ws.mask = mask;
    Ok(())
}
