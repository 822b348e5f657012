//! Inverse dynamics on stack arrays of any [`Scalar`]: the kernel's Newton–Euler recursion.

use crate::chain::Chain;
use crate::dual::Scalar;
use crate::rnea::{one_lane_rnea_back, one_lane_rnea_fwd, rnea_recursion, RneaLanes};

use super::{Kin, Vec8, MAX_DOF};

/// RNEA acceleration and force passes (no tip force) over `kin`, with base acceleration `a0`:
/// `tau = ID(q, q̇, q̈)`; the stack instance of the kernel's [`rnea_recursion`].
pub(crate) fn rnea_passes<T: Scalar>(
    chain: &Chain,
    kin: &Kin<T>,
    a0: [T; 3],
    qdd: &[T],
    tau: &mut [T],
) {
    let zero = T::cst(0.0);
    let mut lane = StackRnea {
        kin,
        qdd,
        tau,
        acc: [[zero; 3]; MAX_DOF],
        ap: a0,
        cf: [zero; 3],
    };
    rnea_recursion(chain, &mut lane);
}

/// One lane of RNEA over the stack arrays of [`Kin`].
struct StackRnea<'a, T> {
    kin: &'a Kin<T>,
    qdd: &'a [T],
    tau: &'a mut [T],
    acc: Vec8<[T; 3]>,
    ap: [T; 3],
    cf: [T; 3],
}

impl<T: Scalar> RneaLanes for StackRnea<'_, T> {
    #[inline(always)]
    fn fwd<const PRI: bool>(&mut self, k: usize) {
        let kin = self.kin;
        let link = [
            &self.qdd[k],
            &kin.ay[k],
            &kin.az[k],
            &kin.hy[k],
            &kin.hz[k],
            &kin.dy[k],
            &kin.dz[k],
        ];
        one_lane_rnea_fwd::<T, PRI>(link, &mut self.ap);
        self.acc[k] = self.ap;
    }

    #[inline(always)]
    fn back<const PRI: bool>(&mut self, k: usize, j: f64, m: f64) {
        let kin = self.kin;
        let [a0, a1, a2] = &self.acc[k];
        let link = [
            a0, a1, a2, &kin.cy[k], &kin.cz[k], &kin.by[k], &kin.bz[k], &kin.dy[k], &kin.dz[k],
            &kin.hy[k], &kin.hz[k],
        ];
        (self.tau[k], _) = one_lane_rnea_back::<T, PRI>(j, m, link, &mut self.cf);
    }
}
