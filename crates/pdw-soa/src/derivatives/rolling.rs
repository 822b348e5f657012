//! Round feet: a base rolling without slip, its dynamics and exact Jacobians.

use crate::chain::Chain;
use crate::dual::Dual;
use crate::error::{check_len, SoaError};

use super::{by_dof, check_dof, kin, ldl, ldl_solve, mass_matrix, rnea_passes, Vec8, MAX_DOF};

/// Checks a floating chain (joint 0 prismatic along the base `y`, joint 1 along `z`, then `n ≥ 1`
/// joints) for the rolling routines; returns `n`.
pub(crate) fn check_floating(chain: &Chain) -> Result<usize, SoaError> {
    let nf = chain.dof();
    check_dof(nf)?;
    let ok = nf >= 3
        && chain.prismatic[0]
        && chain.prismatic[1]
        && chain.axis[0] == [1.0, 0.0]
        && chain.axis[1] == [0.0, 1.0]
        && chain.links[0].to_next == [0.0, 0.0]
        && chain.links[1].to_next == [0.0, 0.0];
    if ok {
        Ok(nf - 2)
    } else {
        Err(SoaError::DimensionMismatch {
            what: "floating chain for a rolling base",
            expected: "prismatic [1, 0], prismatic [0, 1] (zero-length base links), then ≥ 1 joint"
                .into(),
            got: format!("{} joints", nf),
        })
    }
}

/// Forward dynamics of a chain whose base point rolls without slip on the slope: the base point
/// is the centre of a circular arc of radius `radius` rigidly fixed to the first link, touching
/// the slope at the point straight below it (McGeer 1990, "Passive dynamic walking", IJRR 9(2):
/// the arc-foot walker). With `θ₀ = q₀` the first link's absolute angle, the arc centre moves
/// along the slope by `y = −r q₀` (rolling, no slip) at constant height: a holonomic constraint
/// with a **constant** Jacobian on the floating chain `q_F = (y, z, q) = J q`,
/// `J = [−r e₀ᵀ; 0; I]`, so that `J̇ = 0` and the reduced equations are
///
/// ```text
/// Jᵀ ID_F(J q, J q̇, J q̈) = τ        (Jᵀ𝓜_F J q̈ = τ − Jᵀ C_F)
/// ```
/// with the joints where `locked[k]` is true held (`q̈_k = 0`, seed §3.4) and the others passive
/// (`τ = 0`). `chain` is the floating chain (see `check_floating`: prismatic `y`, prismatic
/// `z`, then the `n` joints of the walker rooted at the arc centre); `radius = 0` is a pinned
/// base (the values agree with [`crate::pseudo_joint_dynamics`] to roundoff).
///
/// - `q`, `qd`: the `n` joint positions and rates;
/// - `qdd`: output accelerations (length `n`, `0.0` at locked joints);
/// - `tau_f`: output `ID_F(J q, J q̇, J q̈)` (length `n + 2`): the ground's force on the foot
///   `[f_y, f_z]` (entries 0, 1), the torque `r f_y` the rolling contact applies about the arc
///   centre (entry 2, as `q₀`'s generalized force) and the locking torques (entries `2 + k`).
///
/// # Errors
/// [`SoaError::DimensionMismatch`] for a chain of the wrong shape or wrong lengths;
/// [`SoaError::MassMatrixNotPositiveDefinite`] if `(Jᵀ𝓜_F J)_ff` is not positive definite.
#[allow(clippy::too_many_arguments)]
pub fn rolling_base_dynamics(
    chain: &Chain,
    radius: f64,
    q: &[f64],
    qd: &[f64],
    locked: &[bool],
    qdd: &mut [f64],
    tau_f: &mut [f64],
) -> Result<(), SoaError> {
    let n = check_floating(chain)?;
    check_len("q", n, q.len())?;
    check_len("qd", n, qd.len())?;
    check_len("locked", n, locked.len())?;
    check_len("qdd", n, qdd.len())?;
    check_len("tau_f", n + 2, tau_f.len())?;
    rolling_value(chain, n, radius, q, qd, locked, qdd, tau_f)
}

/// [`rolling_base_dynamics`] and its exact Jacobians `∂q̈/∂q`, `∂q̈/∂q̇` (`n × n` row-major,
/// rows of locked joints zero): one RNEA pass in duals of width `3n` seeded on `(q, q̇, q̈)`
/// through `J`, `∂q̈_f/∂x = −(Jᵀ𝓜_F J)_ff⁻¹ ∂(Jᵀ ID_F)_f/∂x` (Carpentier & Mansard 2018, as
/// [`crate::aba_derivatives`]). Errors as [`rolling_base_dynamics`].
#[allow(clippy::too_many_arguments)]
pub fn rolling_base_derivatives(
    chain: &Chain,
    radius: f64,
    q: &[f64],
    qd: &[f64],
    locked: &[bool],
    qdd: &mut [f64],
    dqdd_dq: &mut [f64],
    dqdd_dqd: &mut [f64],
) -> Result<(), SoaError> {
    let n = check_floating(chain)?;
    check_len("q", n, q.len())?;
    check_len("qd", n, qd.len())?;
    check_len("locked", n, locked.len())?;
    check_len("qdd", n, qdd.len())?;
    check_len("dqdd_dq (n x n)", n * n, dqdd_dq.len())?;
    check_len("dqdd_dqd (n x n)", n * n, dqdd_dqd.len())?;
    by_dof!(
        n,
        3,
        rolling_derivatives_w(chain, radius, q, qd, locked, qdd, dqdd_dq, dqdd_dqd)
    )
}

/// Indices of the free joints.
pub(crate) fn free_joints(locked: &[bool]) -> (Vec8<usize>, usize) {
    let mut free = [0usize; MAX_DOF];
    let mut nf = 0;
    for (k, l) in locked.iter().enumerate() {
        if !l {
            free[nf] = k;
            nf += 1;
        }
    }
    (free, nf)
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn rolling_value(
    chain: &Chain,
    n: usize,
    r: f64,
    q: &[f64],
    qd: &[f64],
    locked: &[bool],
    qdd: &mut [f64],
    tau_f: &mut [f64],
) -> Result<(), SoaError> {
    let nf = n + 2;
    let (mut qf, mut qdf, mut qddf) = ([0.0; MAX_DOF], [0.0; MAX_DOF], [0.0; MAX_DOF]);
    qf[0] = -r * q[0];
    qdf[0] = -r * qd[0];
    qf[2..nf].copy_from_slice(q);
    qdf[2..nf].copy_from_slice(qd);
    let k64 = kin::<f64>(chain, &qf[..nf], Some(&qdf[..nf]));
    // C_F = ID_F(q_F, q̇_F, 0), 𝓜_F
    let mut c = [0.0; MAX_DOF];
    rnea_passes(chain, &k64, chain.base_acc, &qddf[..nf], &mut c[..nf]);
    let mut mf = [[0.0; MAX_DOF]; MAX_DOF];
    mass_matrix(chain, &k64, &mut mf);
    // Jᵀ𝓜_F J and Jᵀ C_F: column a of J is e_{a+2} − r δ_{a0} e_0
    let red = |a: usize, b: usize| {
        let mut v = mf[a + 2][b + 2];
        if a == 0 {
            v -= r * mf[0][b + 2];
        }
        if b == 0 {
            v -= r * mf[a + 2][0];
        }
        if a == 0 && b == 0 {
            v += r * r * mf[0][0];
        }
        v
    };
    let (free, nfree) = free_joints(locked);
    let mut mff = [[0.0; MAX_DOF]; MAX_DOF];
    let mut rhs = [0.0; MAX_DOF];
    for a in 0..nfree {
        for b in 0..=a {
            mff[a][b] = red(free[a], free[b]);
        }
        let k = free[a];
        rhs[a] = -(c[k + 2] - if k == 0 { r * c[0] } else { 0.0 });
    }
    ldl(&mut mff, nfree).ok_or(SoaError::MassMatrixNotPositiveDefinite)?;
    ldl_solve(&mff, nfree, &mut rhs[..nfree]);
    qdd.fill(0.0);
    for a in 0..nfree {
        qdd[free[a]] = rhs[a];
    }
    qddf[0] = -r * qdd[0];
    qddf[2..nf].copy_from_slice(qdd);
    rnea_passes(chain, &k64, chain.base_acc, &qddf[..nf], tau_f);
    Ok(())
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn rolling_derivatives_w<const W: usize>(
    chain: &Chain,
    r: f64,
    q: &[f64],
    qd: &[f64],
    locked: &[bool],
    qdd: &mut [f64],
    dqdd_dq: &mut [f64],
    dqdd_dqd: &mut [f64],
) -> Result<(), SoaError> {
    let nf = chain.dof();
    let n = nf - 2;
    debug_assert_eq!(W, 3 * n);
    let mut tau_f = [0.0; MAX_DOF];
    rolling_value(chain, n, r, q, qd, locked, qdd, &mut tau_f[..nf])?;

    let zero = Dual::<W>::constant(0.0);
    let mr = Dual::<W>::constant(-r);
    let (mut qx, mut qdx, mut qddx) = ([zero; MAX_DOF], [zero; MAX_DOF], [zero; MAX_DOF]);
    for k in 0..n {
        qx[k + 2] = Dual::variable(q[k], k);
        qdx[k + 2] = Dual::variable(qd[k], n + k);
        qddx[k + 2] = Dual::variable(qdd[k], 2 * n + k);
    }
    qx[0] = mr * qx[2];
    qdx[0] = mr * qdx[2];
    qddx[0] = mr * qddx[2];
    let kd = kin(chain, &qx[..nf], Some(&qdx[..nf]));
    let a0 = chain.base_acc.map(Dual::constant);
    let mut id = [zero; MAX_DOF];
    rnea_passes(chain, &kd, a0, &qddx[..nf], &mut id[..nf]);
    // Jᵀ ID_F
    let mut idr = [zero; MAX_DOF];
    idr[..n].copy_from_slice(&id[2..n + 2]);
    idr[0] = idr[0] + mr * id[0];

    let (free, nfree) = free_joints(locked);
    let mut mff = [[0.0; MAX_DOF]; MAX_DOF];
    for a in 0..nfree {
        for b in 0..=a {
            mff[a][b] = idr[free[a]].d[2 * n + free[b]];
        }
    }
    ldl(&mut mff, nfree).ok_or(SoaError::MassMatrixNotPositiveDefinite)?;
    dqdd_dq.fill(0.0);
    dqdd_dqd.fill(0.0);
    let mut rhs = [0.0; MAX_DOF];
    for x in 0..2 * n {
        for a in 0..nfree {
            rhs[a] = -idr[free[a]].d[x];
        }
        ldl_solve(&mff, nfree, &mut rhs[..nfree]);
        let (out, col) = if x < n {
            (&mut *dqdd_dq, x)
        } else {
            (&mut *dqdd_dqd, x - n)
        };
        for a in 0..nfree {
            out[free[a] * n + col] = rhs[a];
        }
    }
    Ok(())
}
