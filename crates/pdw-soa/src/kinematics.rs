//! Kinematics: positions, the tip Jacobian `J = Φ_t Φ H` (seed eq. 2.24), tip velocity and
//! acceleration, `J̇ q̇` (seed eq. 3.27), and inverse kinematics by the pseudo-inverse
//! `J# = Jᵀ (J Jᵀ)⁻¹` (seed eq. 2.26).
//!
//! The tip twist is `V_t = [ω_n, v_tip,y, v_tip,z] = J q̇`; column `k` of `J` is
//! `Φ_{t,k} H_k`, i.e. `[1, −(t − p_k)_z, (t − p_k)_y]` for a revolute joint and
//! `[0, h_y, h_z]` for a prismatic one. Rows 1–2 (the *linear* Jacobian, 2 × n) give the tip
//! point velocity. The classical tip acceleration is `J q̈ + J̇ q̇`; `J̇ q̇` is the tip
//! acceleration with `q̈ = 0` and no gravity, from the acceleration recursion with the bias
//! terms `a_k` (seed eq. 3.27: `J̇q̇ = Φ_t Φ a + Φ̇_t Φ H q̇`).

use faer::MatRef;

use crate::chain::Chain;
use crate::error::{check_len, SoaError};
use crate::spatial;
use crate::workspace::{kin_pass, Workspace};

/// Compute joint, COM and tip positions (world frame, m) at `q`; read them with
/// [`Workspace::joint_positions`], [`Workspace::com_positions`], [`Workspace::tip_position`].
pub fn forward_kinematics(chain: &Chain, ws: &mut Workspace, q: &[f64]) -> Result<(), SoaError> {
    kin_pass(chain, ws, q, None)?;
    positions_from_kin(chain, ws);
    Ok(())
}

pub(crate) fn positions_from_kin(chain: &Chain, ws: &mut Workspace) {
    let n = chain.dof();
    let (mut y, mut z) = (0.0, 0.0);
    for k in 0..n {
        y += ws.dy[k];
        z += ws.dz[k];
        ws.joint_pos[k] = [y, z];
        ws.com_pos[k] = [y + ws.cy[k], z + ws.cz[k]];
    }
    ws.tip_pos = [y + ws.tip_d[0], z + ws.tip_d[1]];
}

impl Workspace {
    /// Joint points `p_k` from the last [`forward_kinematics`] (or a routine that calls it).
    pub fn joint_positions(&self) -> &[[f64; 2]] {
        &self.joint_pos
    }
    /// Link COM positions from the last [`forward_kinematics`].
    pub fn com_positions(&self) -> &[[f64; 2]] {
        &self.com_pos
    }
    /// Tip position from the last [`forward_kinematics`].
    pub fn tip_position(&self) -> [f64; 2] {
        self.tip_pos
    }
}

/// Tip position `[y, z]` at `q`.
pub fn tip_position(chain: &Chain, ws: &mut Workspace, q: &[f64]) -> Result<[f64; 2], SoaError> {
    forward_kinematics(chain, ws, q)?;
    Ok(ws.tip_pos)
}

/// The 3 × n tip Jacobian `J` (rows ω, v_y, v_z; seed eq. 2.24) at `q`. Rows 1..3
/// (`.subrows(1, 2)`) are the linear Jacobian of the tip point.
pub fn tip_jacobian<'a>(
    chain: &Chain,
    ws: &'a mut Workspace,
    q: &[f64],
) -> Result<MatRef<'a, f64>, SoaError> {
    forward_kinematics(chain, ws, q)?;
    fill_jacobian(chain, ws);
    Ok(ws.jac.as_ref())
}

/// The 2 × n linear tip Jacobian (tip point velocity = `J_lin q̇`).
pub fn tip_jacobian_linear<'a>(
    chain: &Chain,
    ws: &'a mut Workspace,
    q: &[f64],
) -> Result<MatRef<'a, f64>, SoaError> {
    Ok(tip_jacobian(chain, ws, q)?.subrows(1, 2))
}

pub(crate) fn fill_jacobian(chain: &Chain, ws: &mut Workspace) {
    let t = ws.tip_pos;
    for k in 0..chain.dof() {
        if chain.prismatic[k] {
            ws.jac[(0, k)] = 0.0;
            ws.jac[(1, k)] = ws.hy[k];
            ws.jac[(2, k)] = ws.hz[k];
        } else {
            let p = ws.joint_pos[k];
            ws.jac[(0, k)] = 1.0;
            ws.jac[(1, k)] = -(t[1] - p[1]);
            ws.jac[(2, k)] = t[0] - p[0];
        }
    }
}

/// Tip twist `V_t = J q̇ = [ω, v_y, v_z]` (seed eq. 2.25).
pub fn tip_velocity(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
) -> Result<[f64; 3], SoaError> {
    check_len("qd", chain.dof(), qd.len())?;
    tip_jacobian(chain, ws, q)?;
    let mut v = [0.0; 3];
    for (k, &r) in qd.iter().enumerate() {
        for (i, vi) in v.iter_mut().enumerate() {
            *vi += ws.jac[(i, k)] * r;
        }
    }
    Ok(v)
}

/// Tip acceleration `J q̈ + J̇ q̇ = [ω̇, a_y, a_z]` (classical, gravity **not** included).
/// With `qdd = None` this is `J̇ q̇` (seed eq. 3.27).
pub fn tip_acceleration(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
    qdd: Option<&[f64]>,
) -> Result<[f64; 3], SoaError> {
    let n = chain.dof();
    if let Some(a) = qdd {
        check_len("qdd", n, a.len())?;
    }
    kin_pass(chain, ws, q, Some(qd))?;
    Ok(tip_acc_from_kin(chain, ws, qdd))
}

pub(crate) fn tip_acc_from_kin(chain: &Chain, ws: &Workspace, qdd: Option<&[f64]>) -> [f64; 3] {
    let n = chain.dof();
    let mut ap = [0.0; 3];
    for k in 0..n {
        let qk = qdd.map_or(0.0, |a| a[k]);
        ap = if chain.prismatic[k] {
            spatial::rnea_fwd_pri(
                &ap, qk, ws.ay[k], ws.az[k], ws.hy[k], ws.hz[k], ws.dy[k], ws.dz[k],
            )
        } else {
            spatial::rnea_fwd_rev(&ap, qk, ws.ay[k], ws.az[k], ws.dy[k], ws.dz[k])
        };
    }
    let w = ws.w[n - 1];
    let w2 = w * w;
    let at = spatial::motion_transport(&ap, ws.tip_d[0], ws.tip_d[1]);
    [at[0], at[1] - w2 * ws.tip_d[0], at[2] - w2 * ws.tip_d[1]]
}

/// `J# v = Jᵀ (J Jᵀ)⁻¹ v` for the 2 × n linear Jacobian currently in the workspace.
fn pinv_linear_apply(
    ws: &Workspace,
    n: usize,
    v: [f64; 2],
    out: &mut [f64],
) -> Result<(), SoaError> {
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for k in 0..n {
        let (j1, j2) = (ws.jac[(1, k)], ws.jac[(2, k)]);
        a += j1 * j1;
        b += j1 * j2;
        c += j2 * j2;
    }
    let det = a * c - b * b;
    if det.is_nan() || det <= 1e-14 * (a * c).max(f64::MIN_POSITIVE) {
        return Err(SoaError::SingularConstraint {
            what: "J Jᵀ (pseudo-inverse)",
        });
    }
    let y0 = (c * v[0] - b * v[1]) / det;
    let y1 = (a * v[1] - b * v[0]) / det;
    for (k, o) in out.iter_mut().enumerate() {
        *o = ws.jac[(1, k)] * y0 + ws.jac[(2, k)] * y1;
    }
    Ok(())
}

/// Resolved-rate inverse kinematics (seed eq. 2.26): the minimum-norm joint rates
/// `q̇ = J# v` that give the tip point the velocity `v = [v_y, v_z]`.
pub fn pseudo_inverse_rates(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    v: [f64; 2],
    qd: &mut [f64],
) -> Result<(), SoaError> {
    check_len("qd", chain.dof(), qd.len())?;
    tip_jacobian(chain, ws, q)?;
    pinv_linear_apply(ws, chain.dof(), v, qd)
}

/// Position-level inverse kinematics: Newton iterations `q ← q + J# (target − tip(q))` until
/// `|target − tip(q)| ≤ tol` (m). `q` is the initial guess on entry and the solution on exit.
/// Returns the number of iterations.
pub fn inverse_kinematics(
    chain: &Chain,
    ws: &mut Workspace,
    q: &mut [f64],
    target: [f64; 2],
    tol: f64,
    max_iter: usize,
) -> Result<usize, SoaError> {
    let n = chain.dof();
    check_len("q", n, q.len())?;
    let mut step = std::mem::take(&mut ws.tmp);
    let mut res = f64::INFINITY;
    let mut out = Err(SoaError::IkNotConverged {
        iterations: max_iter,
        residual: res,
    });
    for it in 0..=max_iter {
        if let Err(e) = tip_jacobian(chain, ws, q) {
            out = Err(e);
            break;
        }
        let t = ws.tip_pos;
        let e = [target[0] - t[0], target[1] - t[1]];
        res = (e[0] * e[0] + e[1] * e[1]).sqrt();
        if res <= tol {
            out = Ok(it);
            break;
        }
        if it == max_iter {
            out = Err(SoaError::IkNotConverged {
                iterations: max_iter,
                residual: res,
            });
            break;
        }
        if let Err(err) = pinv_linear_apply(ws, n, e, &mut step) {
            out = Err(err);
            break;
        }
        for (qk, s) in q.iter_mut().zip(&step) {
            *qk += s;
        }
    }
    ws.tmp = step;
    out
}
