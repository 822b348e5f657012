//! Kinematics on stack arrays of any [`Scalar`] (the kernel's kinematic pass, its positions)
//! and the tip position's exact Jacobian.

use crate::chain::Chain;
use crate::dual::{Dual, Scalar};
use crate::error::{check_len, SoaError};
use crate::workspace::{kin_recursion, lanes_tip, one_lane_kin, KinLanes, KinLink};

use super::{by_dof, check_dof, Vec8, MAX_DOF};

/// Pass-1 quantities of every link (fields as in [`crate::Workspace`]).
#[derive(Clone, Copy)]
pub(crate) struct Kin<T> {
    pub(crate) w: Vec8<T>,
    pub(crate) dy: Vec8<T>,
    pub(crate) dz: Vec8<T>,
    pub(crate) hy: Vec8<T>,
    pub(crate) hz: Vec8<T>,
    pub(crate) cy: Vec8<T>,
    pub(crate) cz: Vec8<T>,
    pub(crate) ay: Vec8<T>,
    pub(crate) az: Vec8<T>,
    pub(crate) by: Vec8<T>,
    pub(crate) bz: Vec8<T>,
    pub(crate) tip_d: [T; 2],
}

/// Link angles, levers, world COM offsets, prismatic axes, rates and bias terms, base to tip:
/// the stack instance of the kernel's kinematic pass ([`kin_recursion`]) on any [`Scalar`].
/// `qd = None` means zero joint rates. `q` (and `qd`) have length `chain.dof() ≤ MAX_DOF`.
pub(crate) fn kin<T: Scalar>(chain: &Chain, q: &[T], qd: Option<&[T]>) -> Kin<T> {
    let zero = T::cst(0.0);
    let mut lanes = StackKin {
        out: Kin {
            w: [zero; MAX_DOF],
            dy: [zero; MAX_DOF],
            dz: [zero; MAX_DOF],
            hy: [zero; MAX_DOF],
            hz: [zero; MAX_DOF],
            cy: [zero; MAX_DOF],
            cz: [zero; MAX_DOF],
            ay: [zero; MAX_DOF],
            az: [zero; MAX_DOF],
            by: [zero; MAX_DOF],
            bz: [zero; MAX_DOF],
            tip_d: [zero; 2],
        },
        q,
        qd,
        prev: [zero, zero, T::cst(1.0), zero],
    };
    kin_recursion(chain, &mut lanes);
    lanes.out
}

/// One lane of the kinematic pass into the stack arrays of [`Kin`], the previous link's
/// `θ, sin, cos, ω` carried in `prev`.
struct StackKin<'a, T> {
    out: Kin<T>,
    q: &'a [T],
    qd: Option<&'a [T]>,
    prev: [T; 4],
}

impl<T: Scalar> KinLanes for StackKin<'_, T> {
    #[inline(always)]
    fn link<const PRI: bool>(&mut self, k: usize, c: &KinLink) {
        let o = &mut self.out;
        let qdk = self.qd.map_or(T::cst(0.0), |v| v[k]);
        let out = [
            &mut o.dy[k],
            &mut o.dz[k],
            &mut o.hy[k],
            &mut o.hz[k],
            &mut o.cy[k],
            &mut o.cz[k],
            &mut o.w[k],
            &mut o.ay[k],
            &mut o.az[k],
            &mut o.by[k],
            &mut o.bz[k],
        ];
        self.prev = one_lane_kin::<T, PRI>(c, self.prev, (self.q[k], qdk), out);
    }

    #[inline(always)]
    fn tip(&mut self, lp: [f64; 2]) {
        let [_, sp, cp, _] = self.prev;
        let [ty, tz] = &mut self.out.tip_d;
        let (one, m1) = (std::slice::from_ref, std::slice::from_mut);
        lanes_tip(lp, one(&sp), one(&cp), m1(ty), m1(tz));
    }
}

/// Joint points and the tip point (world) from the levers, as the kernel's positions pass.
pub(crate) fn positions<T: Scalar>(n: usize, kin: &Kin<T>) -> (Vec8<[T; 2]>, [T; 2]) {
    let (mut y, mut z) = (T::cst(0.0), T::cst(0.0));
    let mut p = [[T::cst(0.0); 2]; MAX_DOF];
    for k in 0..n {
        y = y + kin.dy[k];
        z = z + kin.dz[k];
        p[k] = [y, z];
    }
    (p, [y + kin.tip_d[0], z + kin.tip_d[1]])
}

// ---------------------------------------------------------------------------------------------
// Tip position.
// ---------------------------------------------------------------------------------------------

/// Tip position `[y, z]` (m, bit-identical to [`crate::tip_position`]) and its exact
/// Jacobian `∂tip/∂q` (`2 × n` row-major, entry `(i, j)` at `i·n + j`), for guard gradients.
///
/// # Errors
/// [`SoaError::DimensionMismatch`] for wrong lengths or `n > MAX_DOF`.
pub fn tip_position_derivatives(
    chain: &Chain,
    q: &[f64],
    pos: &mut [f64; 2],
    jac: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    check_dof(n)?;
    check_len("q", n, q.len())?;
    check_len("jac (2 x n)", 2 * n, jac.len())?;
    by_dof!(n, 1, tip_position_w(chain, q, pos, jac));
    Ok(())
}

pub(crate) fn tip_position_w<const W: usize>(
    chain: &Chain,
    q: &[f64],
    pos: &mut [f64; 2],
    jac: &mut [f64],
) {
    let n = chain.dof();
    let mut qx = [Dual::<W>::constant(0.0); MAX_DOF];
    for k in 0..n {
        qx[k] = Dual::variable(q[k], k);
    }
    let kd = kin(chain, &qx[..n], None);
    let (_, t) = positions(n, &kd);
    *pos = [t[0].v, t[1].v];
    jac[..n].copy_from_slice(&t[0].d[..n]);
    jac[n..2 * n].copy_from_slice(&t[1].d[..n]);
}
