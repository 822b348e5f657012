//! Forward dynamics with locked joints and its exact Jacobians (module docs of
//! [`crate::derivatives`]).

use crate::aba::{aba_recursion, one_lane_back, one_lane_fwd, AbaLanes};
use crate::chain::Chain;
use crate::dual::Dual;
use crate::error::{check_len, SoaError};

use super::{by_dof, check_dof, kin, ldl, ldl_solve, rnea_passes, Kin, Vec8, MAX_DOF};

/// The kernel's articulated-body recursion ([`crate::aba::aba_recursion`], no tip force) on
/// `f64` stack arrays: the same loops and step functions, hence the same bits.
pub(crate) fn aba_value(
    chain: &Chain,
    kin: &Kin<f64>,
    tau: &[f64],
    locked: &[bool],
    qdd: &mut [f64],
) {
    let mut lane = StackLane {
        kin,
        tau,
        qdd,
        g: [[0.0; 3]; MAX_DOF],
        nu: [0.0; MAX_DOF],
        cp: [0.0; 6],
        cz: [0.0; 3],
        ap: chain.base_acc,
    };
    aba_recursion(chain, Some(locked), &mut lane);
}

/// One lane of the articulated-body recursion over the stack arrays of [`Kin`].
struct StackLane<'a> {
    kin: &'a Kin<f64>,
    tau: &'a [f64],
    qdd: &'a mut [f64],
    g: Vec8<[f64; 3]>,
    nu: Vec8<f64>,
    cp: [f64; 6],
    cz: [f64; 3],
    ap: [f64; 3],
}

impl AbaLanes for StackLane<'_> {
    #[inline(always)]
    fn back<const K: u8>(&mut self, k: usize, j: f64, m: f64) {
        let kin = self.kin;
        let link = [
            &kin.cy, &kin.cz, &kin.by, &kin.bz, &kin.ay, &kin.az, &kin.hy, &kin.hz, &kin.dy,
            &kin.dz,
        ]
        .map(|v| &v[k]);
        let gain = (&mut self.g[k], &mut self.nu[k]);
        one_lane_back::<K>(
            j,
            m,
            self.tau[k],
            link,
            gain,
            (&mut self.cp, &mut self.cz),
            |_| {},
        );
    }

    #[inline(always)]
    fn fwd<const K: u8>(&mut self, k: usize) {
        let kin = self.kin;
        let link = [&kin.ay, &kin.az, &kin.hy, &kin.hz, &kin.dy, &kin.dz].map(|v| &v[k]);
        self.qdd[k] = one_lane_fwd::<K>(&self.g[k], self.nu[k], link, &mut self.ap);
    }
}

/// Forward dynamics with the joints where `locked[k]` is true held as pseudo joints (`q̈_k = 0`,
/// seed §3.4), and its exact Jacobians (see the module docs for the method).
///
/// - `q`, `qd`: joint positions (rad or m) and rates, length `n`;
/// - `tau`: applied joint torques/forces (N m or N), length `n`;
/// - `locked`: mask of locked joints, length `n` (all `false`: plain [`crate::aba()`]);
/// - `qdd`: output accelerations, length `n`; bit-identical to [`crate::aba()`] (no joint locked)
///   or [`crate::pseudo_joint_dynamics`] (the same joints locked, no tip force), `0.0` at locked
///   joints;
/// - `dqdd_dq`, `dqdd_dqd`: output `∂q̈/∂q`, `∂q̈/∂q̇`, `n × n` row-major (entry `(i, j)` at
///   `i·n + j`); rows of locked joints are zero.
///
/// # Errors
/// [`SoaError::DimensionMismatch`] for wrong lengths or `n > MAX_DOF`;
/// [`SoaError::MassMatrixNotPositiveDefinite`] if `𝓜_ff` is not numerically positive definite.
#[allow(clippy::too_many_arguments)]
pub fn aba_derivatives(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
    locked: &[bool],
    qdd: &mut [f64],
    dqdd_dq: &mut [f64],
    dqdd_dqd: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    check_dof(n)?;
    check_len("q", n, q.len())?;
    check_len("qd", n, qd.len())?;
    check_len("tau", n, tau.len())?;
    check_len("locked", n, locked.len())?;
    check_len("qdd", n, qdd.len())?;
    check_len("dqdd_dq (n x n)", n * n, dqdd_dq.len())?;
    check_len("dqdd_dqd (n x n)", n * n, dqdd_dqd.len())?;
    by_dof!(
        n,
        3,
        aba_derivatives_w(chain, q, qd, tau, locked, qdd, dqdd_dq, dqdd_dqd)
    )
}

/// [`aba_derivatives`] with duals of width `W = 3n`: directions `0..n` are `q`, `n..2n` are `q̇`,
/// `2n..3n` are `q̈`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn aba_derivatives_w<const W: usize>(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
    locked: &[bool],
    qdd: &mut [f64],
    dqdd_dq: &mut [f64],
    dqdd_dqd: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    debug_assert_eq!(W, 3 * n);
    // value: the kernel's articulated-body recursion
    let k64 = kin::<f64>(chain, q, Some(qd));
    aba_value(chain, &k64, tau, locked, qdd);

    // one dual RNEA pass seeded on (q, q̇, q̈) at the solution q̈
    let zero = Dual::<W>::constant(0.0);
    let (mut qx, mut qdx, mut qddx) = ([zero; MAX_DOF], [zero; MAX_DOF], [zero; MAX_DOF]);
    for k in 0..n {
        qx[k] = Dual::variable(q[k], k);
        qdx[k] = Dual::variable(qd[k], n + k);
        qddx[k] = Dual::variable(qdd[k], 2 * n + k);
    }
    let kd = kin(chain, &qx[..n], Some(&qdx[..n]));
    let a0 = chain.base_acc.map(Dual::constant);
    let mut id = [zero; MAX_DOF];
    rnea_passes(chain, &kd, a0, &qddx[..n], &mut id[..n]);

    // free joints f, 𝓜_ff = ∂ID_f/∂q̈_f
    let mut free = [0usize; MAX_DOF];
    let mut nf = 0;
    for k in 0..n {
        if !locked[k] {
            free[nf] = k;
            nf += 1;
        }
    }
    let mut mff = [[0.0; MAX_DOF]; MAX_DOF];
    for a in 0..nf {
        for b in 0..=a {
            mff[a][b] = id[free[a]].d[2 * n + free[b]];
        }
    }
    ldl(&mut mff, nf).ok_or(SoaError::MassMatrixNotPositiveDefinite)?;

    dqdd_dq.fill(0.0);
    dqdd_dqd.fill(0.0);
    let mut rhs = [0.0; MAX_DOF];
    for x in 0..2 * n {
        // ∂q̈_f/∂x = −𝓜_ff⁻¹ ∂ID_f/∂x
        for a in 0..nf {
            rhs[a] = -id[free[a]].d[x];
        }
        ldl_solve(&mff, nf, &mut rhs[..nf]);
        let (out, col) = if x < n {
            (&mut *dqdd_dq, x)
        } else {
            (&mut *dqdd_dqd, x - n)
        };
        for a in 0..nf {
            out[free[a] * n + col] = rhs[a];
        }
    }
    Ok(())
}
