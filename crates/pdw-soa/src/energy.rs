//! Energies and momenta (for conservation checks of walkers and integrators).
//!
//! Link velocities at the joint points follow seed eq. 2.13, `V_k = Φ_{k,k−1} V_{k−1} + H_k q̇_k`;
//! the kinetic energy is `T = ½ Σ V_kᵀ M_k V_k = ½ q̇ᵀ 𝓜 q̇` (seed Table 2.1) and the potential
//! energy `U = Σ m_k a_b · r_com,k` (zero at the base point; `a_b = −g`, seed eq. 3.12).

use crate::chain::Chain;
use crate::error::{check_len, SoaError};
use crate::kinematics::positions_from_kin;
use crate::workspace::{kin_pass, Workspace};

/// Visit each link with `(k, ω_k, v_k at p_k)` after a kinematic pass with rates.
#[allow(clippy::needless_range_loop)]
fn for_each_link_velocity(
    chain: &Chain,
    ws: &Workspace,
    qd: &[f64],
    mut f: impl FnMut(usize, f64, [f64; 2]),
) {
    let (mut wp, mut v) = (0.0, [0.0, 0.0]);
    for k in 0..chain.dof() {
        // v_k = v_{k−1} + ω_{k−1} × d_k (+ h q̇ for a prismatic joint)
        v = [v[0] - wp * ws.dz[k], v[1] + wp * ws.dy[k]];
        if chain.prismatic[k] {
            v = [v[0] + ws.hy[k] * qd[k], v[1] + ws.hz[k] * qd[k]];
        }
        let w = ws.w[k];
        f(k, w, v);
        wp = w;
    }
}

/// Kinetic energy `T = ½ q̇ᵀ 𝓜(q) q̇` (J), in O(n).
pub fn kinetic_energy(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
) -> Result<f64, SoaError> {
    kin_pass(chain, ws, q, Some(qd))?;
    let mut t = 0.0;
    for_each_link_velocity(chain, ws, qd, |k, w, v| {
        let m = chain.links[k].mass;
        let (cy, cz) = (ws.cy[k], ws.cz[k]);
        t += 0.5 * (chain.j_joint[k] * w * w + m * (v[0] * v[0] + v[1] * v[1]))
            + w * m * (cy * v[1] - cz * v[0]);
    });
    Ok(t)
}

/// Gravitational potential energy `U = Σ m_k a_b · r_com,k` (J), zero at the base point.
pub fn potential_energy(chain: &Chain, ws: &mut Workspace, q: &[f64]) -> Result<f64, SoaError> {
    kin_pass(chain, ws, q, None)?;
    positions_from_kin(chain, ws);
    let ab = chain.base_acc;
    Ok((0..chain.dof())
        .map(|k| chain.links[k].mass * (ab[1] * ws.com_pos[k][0] + ab[2] * ws.com_pos[k][1]))
        .sum())
}

/// Total mechanical energy `T + U` (J).
pub fn total_energy(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
) -> Result<f64, SoaError> {
    Ok(kinetic_energy(chain, ws, q, qd)? + potential_energy(chain, ws, q)?)
}

/// Angular momentum of the whole chain about the fixed world point `point` (kg m²/s):
/// `Σ I_c,k ω_k + m_k (r_com,k − point) × v_com,k`.
pub fn angular_momentum_about(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
    point: [f64; 2],
) -> Result<f64, SoaError> {
    check_len("qd", chain.dof(), qd.len())?;
    kin_pass(chain, ws, q, Some(qd))?;
    positions_from_kin(chain, ws);
    let mut l = 0.0;
    for_each_link_velocity(chain, ws, qd, |k, w, v| {
        let link = &chain.links[k];
        let (cy, cz) = (ws.cy[k], ws.cz[k]);
        let vc = [v[0] - w * cz, v[1] + w * cy];
        let r = [ws.com_pos[k][0] - point[0], ws.com_pos[k][1] - point[1]];
        l += link.inertia * w + link.mass * (r[0] * vc[1] - r[1] * vc[0]);
    });
    Ok(l)
}

/// Linear momentum `Σ m_k v_com,k` (kg m/s).
pub fn linear_momentum(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
) -> Result<[f64; 2], SoaError> {
    check_len("qd", chain.dof(), qd.len())?;
    kin_pass(chain, ws, q, Some(qd))?;
    let mut p = [0.0; 2];
    for_each_link_velocity(chain, ws, qd, |k, w, v| {
        let m = chain.links[k].mass;
        p[0] += m * (v[0] - w * ws.cz[k]);
        p[1] += m * (v[1] + w * ws.cy[k]);
    });
    Ok(p)
}
