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
use crate::dual::Scalar;
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

/// The acceleration and force passes of RNEA over a workspace filled by `kin_pass`: the
/// one-lane instance of [`rnea_recursion`]; also keeps `A_k` and `F_k` in `ws`.
pub(crate) fn rnea_passes(
    chain: &Chain,
    ws: &mut Workspace,
    qdd: &[f64],
    f_tip: Option<[f64; 3]>,
    tau: &mut [f64],
) {
    let cf = match f_tip {
        Some(ft) => spatial::force_transport(&ft, ws.tip_d[0], ws.tip_d[1]),
        None => [0.0; 3],
    };
    let mut lane = WsRnea {
        ws,
        qdd,
        tau,
        ap: chain.base_acc,
        cf,
    };
    rnea_recursion(chain, &mut lane);
}

// ---------------------------------------------------------------------------------------------
// The Newton–Euler recursion, written once over where the lanes live and over the scalar.
// ---------------------------------------------------------------------------------------------

/// Where the lanes of one RNEA live (one lane of a [`Workspace`], a block of lanes in the columns
/// of a [`crate::BatchWorkspace`], stack arrays of any [`Scalar`]): each step hands its link's
/// quantities, one slice per quantity over its lanes, to [`lanes_rnea_fwd`] or
/// [`lanes_rnea_back`]. The carries `A` and `Φᵀ F` start at `a_b` and `Φ_{t,n}ᵀ F_t` (or 0).
pub(crate) trait RneaLanes {
    /// Acceleration step of link `k` (prismatic joint if `PRI`) for every lane.
    fn fwd<const PRI: bool>(&mut self, k: usize);
    /// Force step of link `k` (rotational inertia `j`, mass `m`) for every lane, writing `τ_k`.
    fn back<const PRI: bool>(&mut self, k: usize, j: f64, m: f64);
}

/// The two passes of RNEA (module documentation; seed eq. 2.57–2.62): base → tip over
/// [`RneaLanes::fwd`], tip → base over [`RneaLanes::back`].
#[inline(always)]
pub(crate) fn rnea_recursion<S: RneaLanes>(chain: &Chain, s: &mut S) {
    let n = chain.dof();
    for k in 0..n {
        if chain.prismatic[k] {
            s.fwd::<true>(k);
        } else {
            s.fwd::<false>(k);
        }
    }
    for k in (0..n).rev() {
        let (j, m) = (chain.j_joint[k], chain.links[k].mass);
        if chain.prismatic[k] {
            s.back::<true>(k, j, m);
        } else {
            s.back::<false>(k, j, m);
        }
    }
}

/// Acceleration step over all lanes: `A_k = Φ A_{k−1} + H q̈ + a` with `A_{k−1}` read from and
/// `A_k` written to `(a0, a1, a2)`; link inputs `q̈, a_y, a_z, h_y, h_z, d_y, d_z`.
#[inline(always)]
pub(crate) fn lanes_rnea_fwd<T: Scalar, const PRI: bool>(
    [qdd, ay, az, hy, hz, dy, dz]: [&[T]; 7],
    a0: &mut [T],
    a1: &mut [T],
    a2: &mut [T],
) {
    let bl = a0.len();
    let (qdd, ay, az) = (&qdd[..bl], &ay[..bl], &az[..bl]);
    let (hy, hz, dy, dz) = (&hy[..bl], &hz[..bl], &dy[..bl], &dz[..bl]);
    let (a1, a2) = (&mut a1[..bl], &mut a2[..bl]);
    for l in 0..bl {
        let ap = [a0[l], a1[l], a2[l]];
        let a = if PRI {
            spatial::rnea_fwd_pri(&ap, qdd[l], ay[l], az[l], hy[l], hz[l], dy[l], dz[l])
        } else {
            spatial::rnea_fwd_rev(&ap, qdd[l], ay[l], az[l], dy[l], dz[l])
        };
        [a0[l], a1[l], a2[l]] = a;
    }
}

/// Force step over all lanes: `F_k = Φᵀ F_{k+1} + M_k A_k + b_k`, `τ_k = H_kᵀ F_k`, with the
/// carry `Φᵀ F_{k+1}` read from and `Φ_{k,k−1}ᵀ F_k` written to `(f0, f1, f2)`; link inputs
/// `A_k` (three), `c_y, c_z, b_y, b_z, d_y, d_z, h_y, h_z`. `keep` sees each lane's `F_k`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn lanes_rnea_back<T: Scalar, const PRI: bool>(
    j: f64,
    m: f64,
    [a0, a1, a2, cy, cz, by, bz, dy, dz, hy, hz]: [&[T]; 11],
    tau: &mut [T],
    f0: &mut [T],
    f1: &mut [T],
    f2: &mut [T],
    mut keep: impl FnMut(usize, &[T; 3]),
) {
    let bl = tau.len();
    let (a0, a1, a2) = (&a0[..bl], &a1[..bl], &a2[..bl]);
    let (cy, cz, by, bz) = (&cy[..bl], &cz[..bl], &by[..bl], &bz[..bl]);
    let (dy, dz, hy, hz) = (&dy[..bl], &dz[..bl], &hy[..bl], &hz[..bl]);
    let (f0, f1, f2) = (&mut f0[..bl], &mut f1[..bl], &mut f2[..bl]);
    let (j, m) = (T::cst(j), T::cst(m));
    for l in 0..bl {
        let f = spatial::rnea_back(
            &[f0[l], f1[l], f2[l]],
            &[a0[l], a1[l], a2[l]],
            j,
            m,
            cy[l],
            cz[l],
            by[l],
            bz[l],
        );
        tau[l] = if PRI {
            hy[l] * f[1] + hz[l] * f[2]
        } else {
            f[0]
        };
        [f0[l], f1[l], f2[l]] = spatial::force_transport(&f, dy[l], dz[l]);
        keep(l, &f);
    }
}

/// The acceleration step for one lane ([`lanes_rnea_fwd`] over slices of length 1): `link` holds
/// `q̈, a_y, a_z, h_y, h_z, d_y, d_z`, `ap` the carried `A`, which becomes `A_k`.
#[inline(always)]
pub(crate) fn one_lane_rnea_fwd<T: Scalar, const PRI: bool>(link: [&T; 7], ap: &mut [T; 3]) {
    let [a0, a1, a2] = ap;
    let m1 = std::slice::from_mut;
    lanes_rnea_fwd::<T, PRI>(link.map(std::slice::from_ref), m1(a0), m1(a1), m1(a2));
}

/// The force step for one lane ([`lanes_rnea_back`] over slices of length 1): `link` holds
/// `A_k` (three), `c_y, c_z, b_y, b_z, d_y, d_z, h_y, h_z`, `cf` the carried `Φᵀ F`; returns
/// `(τ_k, F_k)`.
#[inline(always)]
pub(crate) fn one_lane_rnea_back<T: Scalar, const PRI: bool>(
    j: f64,
    m: f64,
    link: [&T; 11],
    cf: &mut [T; 3],
) -> (T, [T; 3]) {
    let [f0, f1, f2] = cf;
    let m1 = std::slice::from_mut;
    let mut tk = T::cst(0.0);
    let mut fk = [T::cst(0.0); 3];
    lanes_rnea_back::<T, PRI>(
        j,
        m,
        link.map(std::slice::from_ref),
        m1(&mut tk),
        m1(f0),
        m1(f1),
        m1(f2),
        |_, f| fk = *f,
    );
    (tk, fk)
}

/// One lane in a [`Workspace`]: `A_k` and `F_k` kept per link.
struct WsRnea<'a> {
    ws: &'a mut Workspace,
    qdd: &'a [f64],
    tau: &'a mut [f64],
    ap: [f64; 3],
    cf: [f64; 3],
}

impl RneaLanes for WsRnea<'_> {
    #[inline(always)]
    fn fwd<const PRI: bool>(&mut self, k: usize) {
        let ws = &mut *self.ws;
        let link = [self.qdd, &ws.ay[..], &ws.az, &ws.hy, &ws.hz, &ws.dy, &ws.dz].map(|v| &v[k]);
        one_lane_rnea_fwd::<f64, PRI>(link, &mut self.ap);
        ws.acc[k] = self.ap;
    }

    #[inline(always)]
    fn back<const PRI: bool>(&mut self, k: usize, j: f64, m: f64) {
        let ws = &mut *self.ws;
        let [a0, a1, a2] = &ws.acc[k];
        let link = [
            a0, a1, a2, &ws.cy[k], &ws.cz[k], &ws.by[k], &ws.bz[k], &ws.dy[k], &ws.dz[k],
            &ws.hy[k], &ws.hz[k],
        ];
        let (tk, f) = one_lane_rnea_back::<f64, PRI>(j, m, link, &mut self.cf);
        self.tau[k] = tk;
        ws.force[k] = f;
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
