//! Inverse dynamics by the recursive Newton–Euler algorithm in spatial operator form
//! (seed eq. 2.50, 2.57–2.62):
//!
//! ```text
//! A_0 = a_b (gravity, seed eq. 3.12)
//! A_k = Φ_{k,k−1} A_{k−1} + H_k q̈_k + a_k                        base → tip
//! F_k = Φ_{k+1,k}ᵀ F_{k+1} + M_k A_k + b_k,   F_{n+1} := Φ_{t,n}ᵀ F_t   tip → base
//! τ_k = H_kᵀ F_k
//! ```
//! so that `τ = 𝓜 q̈ + C + Jᵀ F_t` (seed eq. 2.62).
//!
//! **Tip-force convention.** `F_t = [τ_t, f_y, f_z]` is the spatial force the tip **exerts on
//! the environment** (moment about the tip point), as in seed eq. 2.62: the environment pushes
//! on the tip with `−F_t`. A foot standing on the ground with ground reaction `R` has
//! `F_t = −R`.
//!
//! After the call, [`Workspace::joint_forces`] holds `F_k`; `F_0` is the force the base (the
//! ground, for a stance foot at joint 0) exerts on link 0 at the base point: its linear part is
//! the base reaction force `[f_y (tangential, downhill), f_z (normal)]`.

use crate::chain::Chain;
use crate::error::{check_len, SoaError};
use crate::spatial;
use crate::workspace::{kin_pass, Workspace};

/// Inverse dynamics: `tau = 𝓜(q) q̈ + C(q, q̇) + Jᵀ F_t` (seed eq. 2.62).
///
/// - `q`, `qd`, `qdd`: joint positions (rad or m), rates, accelerations, each of length `n`;
/// - `f_tip`: spatial force the tip exerts on the environment (see the module docs), or `None`;
/// - `tau`: output generalised forces (N m or N), length `n`.
///
/// Fills [`Workspace::joint_forces`] and [`Workspace::link_accelerations`].
pub fn rnea(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    f_tip: Option<[f64; 3]>,
    tau: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    check_len("qdd", n, qdd.len())?;
    check_len("tau", n, tau.len())?;
    kin_pass(chain, ws, q, Some(qd))?;
    rnea_passes(chain, ws, qdd, f_tip, tau);
    Ok(())
}

/// The acceleration and force passes of RNEA over a workspace filled by `kin_pass`.
#[allow(clippy::needless_range_loop)]
pub(crate) fn rnea_passes(
    chain: &Chain,
    ws: &mut Workspace,
    qdd: &[f64],
    f_tip: Option<[f64; 3]>,
    tau: &mut [f64],
) {
    let n = chain.dof();
    let mut ap = chain.base_acc;
    for k in 0..n {
        let a = if chain.prismatic[k] {
            spatial::rnea_fwd_pri(
                &ap, qdd[k], ws.ay[k], ws.az[k], ws.hy[k], ws.hz[k], ws.dy[k], ws.dz[k],
            )
        } else {
            spatial::rnea_fwd_rev(&ap, qdd[k], ws.ay[k], ws.az[k], ws.dy[k], ws.dz[k])
        };
        ws.acc[k] = a;
        ap = a;
    }
    let mut cf = match f_tip {
        Some(ft) => spatial::force_transport(&ft, ws.tip_d[0], ws.tip_d[1]),
        None => [0.0; 3],
    };
    for k in (0..n).rev() {
        let link = &chain.links[k];
        let f = spatial::rnea_back(
            &cf,
            &ws.acc[k],
            chain.j_joint[k],
            link.mass,
            ws.cy[k],
            ws.cz[k],
            ws.by[k],
            ws.bz[k],
        );
        ws.force[k] = f;
        tau[k] = if chain.prismatic[k] {
            ws.hy[k] * f[1] + ws.hz[k] * f[2]
        } else {
            f[0]
        };
        cf = spatial::force_transport(&f, ws.dy[k], ws.dz[k]);
    }
}

/// Generalised bias forces `C(q, q̇)` (Coriolis, centrifugal and gravity; seed eq. 2.62 with the
/// base acceleration folded in as in eq. 2.65): RNEA with `q̈ = 0` and no tip force.
pub fn bias_forces(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
    c_out: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    check_len("C", n, c_out.len())?;
    kin_pass(chain, ws, q, Some(qd))?;
    let zeros = std::mem::take(&mut ws.tmp);
    let mut z = zeros;
    z.iter_mut().for_each(|x| *x = 0.0);
    rnea_passes(chain, ws, &z, None, c_out);
    ws.tmp = z;
    Ok(())
}

/// Base reaction: the spatial force `[τ, f_y, f_z]` the base (ground) exerts on link 0 at the
/// base point, for the motion `(q, q̇, q̈)` with tip force `f_tip` (see the module docs). It is
/// `F_0` of the outward RNEA force recursion: the sum of the links' rates of momentum change
/// minus their weights, plus the tip force. `f_z` is the normal and `f_y` the tangential
/// (downhill) ground reaction of a stance foot at joint 0; `τ` equals the joint-0 torque.
pub fn base_reaction(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    f_tip: Option<[f64; 3]>,
) -> Result<[f64; 3], SoaError> {
    let mut tau = std::mem::take(&mut ws.tmp2);
    let r = rnea(chain, ws, q, qd, qdd, f_tip, &mut tau);
    ws.tmp2 = tau;
    r?;
    Ok(ws.force[0])
}
