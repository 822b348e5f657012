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
/// - `f_tip`: spatial force the tip exerts on the environment (see [`crate::rnea()`]), or `None`;
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

/// Forward dynamics of a passive chain with locked joints: `q̈ = 𝓜⁻¹ (−C)` with `τ = 0`, no tip
/// force and the joints in `locked` held at `q̈ = 0` (pseudo joints, seed §3.4, eq. 3.18–3.23).
///
/// The one-lane instance of [`crate::batch_aba_view`] with `tau = None`, `f_tip = None` and
/// the same mask (the same recursion over a [`Workspace`], hence the same bits per lane), for
/// callers that evaluate one state at a time and hold it as a slice, not a matrix. Unlike
/// [`crate::pseudo_joint_dynamics`] it computes no locking torques and takes the mask as `n`
/// booleans. No allocation.
///
/// - `q`, `qd`, `locked`, `qdd`: length `n`; `qdd` is exactly `0.0` at locked joints.
pub fn aba_masked(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd: &[f64],
    locked: &[bool],
    qdd: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    check_len("locked", n, locked.len())?;
    check_len("qdd", n, qdd.len())?;
    kin_pass(chain, ws, q, Some(qd))?;
    // the zero torques live in the workspace's scratch vector (taken out for the borrow)
    let mut zeros = std::mem::take(&mut ws.tmp);
    zeros.fill(0.0);
    aba_passes(chain, ws, &zeros, None, Some(locked), qdd);
    ws.tmp = zeros;
    Ok(())
}

/// Backward and forward articulated-body passes over a workspace filled by `kin_pass`.
/// `locked`: optional mask of locked joints (pseudo joints, seed §3.4), which get `q̈ = 0`.
/// The one-lane instance of [`aba_recursion`]; also keeps `P_k`, `z_k` and `A_k` in `ws`.
pub(crate) fn aba_passes(
    chain: &Chain,
    ws: &mut Workspace,
    tau: &[f64],
    f_tip: Option<[f64; 3]>,
    locked: Option<&[bool]>,
    qdd: &mut [f64],
) {
    let cz = match f_tip {
        Some(ft) => spatial::force_transport(&ft, ws.tip_d[0], ws.tip_d[1]),
        None => [0.0; 3],
    };
    let mut lane = OneLane {
        ws,
        tau,
        qdd,
        cp: [0.0; 6],
        cz,
        ap: chain.base_acc,
    };
    aba_recursion(chain, locked, &mut lane);
}

// ---------------------------------------------------------------------------------------------
// The articulated-body recursion, written once over where the lanes live.
// ---------------------------------------------------------------------------------------------

/// Joint kinds of one articulated-body step, as the const parameter of the lane loops (one
/// monomorphised copy per kind, no branch in the lane loop).
pub(crate) const REV: u8 = 0;
/// Prismatic joint (see [`REV`]).
pub(crate) const PRI: u8 = 1;
/// Locked joint, a pseudo joint of seed §3.4 (see [`REV`]).
pub(crate) const LOCKED: u8 = 2;

/// Where the lanes of one articulated-body recursion live (one lane of a [`Workspace`], a
/// block of lanes in the columns of a [`crate::BatchWorkspace`], stack arrays): each step
/// hands its link's quantities, as one slice per quantity over its lanes, to [`lanes_back`] or
/// [`lanes_fwd`]. The carries `(P⁺, z⁺)` and `A` start at their base values (`0`,
/// `Φ_{t,n}ᵀ F_t`; `a_b`) before [`aba_recursion`] runs.
pub(crate) trait AbaLanes {
    /// Backward step of link `k` (rotational inertia `j`, mass `m`) for every lane.
    fn back<const K: u8>(&mut self, k: usize, j: f64, m: f64);
    /// Forward step of link `k` for every lane, writing its `q̈_k`.
    fn fwd<const K: u8>(&mut self, k: usize);
}

/// The two articulated-body passes (module documentation; Rodriguez, Jain & Kreutz-Delgado
/// 1991): tip → base over [`AbaLanes::back`], base → tip over [`AbaLanes::fwd`], each link's
/// step chosen by its joint kind (locked joints from `locked`).
#[inline(always)]
pub(crate) fn aba_recursion<S: AbaLanes>(chain: &Chain, locked: Option<&[bool]>, s: &mut S) {
    let n = chain.dof();
    let kind = |k: usize| {
        if locked.is_some_and(|m| m[k]) {
            LOCKED
        } else if chain.prismatic[k] {
            PRI
        } else {
            REV
        }
    };
    for k in (0..n).rev() {
        let (j, m) = (chain.j_joint[k], chain.links[k].mass);
        match kind(k) {
            LOCKED => s.back::<LOCKED>(k, j, m),
            PRI => s.back::<PRI>(k, j, m),
            _ => s.back::<REV>(k, j, m),
        }
    }
    for k in 0..n {
        match kind(k) {
            LOCKED => s.fwd::<LOCKED>(k),
            PRI => s.fwd::<PRI>(k),
            _ => s.fwd::<REV>(k),
        }
    }
}

// The lane loops take every stream as its own slice parameter so that each is a distinct
// `noalias` parameter (kept as alias scopes when inlined): the loop vectoriser then needs no
// runtime overlap checks between the ~25 streams. They are inlined into the per-instruction-set
// copies made by `pdw_simd::dispatch` for the batched instance.

/// Backward step of joint kind `K` over all lanes: reads the link quantities and the carries
/// `(p0..p5, z0..z2)`, writes the gain `g`, `ν`, the new carries, and hands each lane's full
/// step to `keep` (lane index, step). A locked joint writes `g = 0`, `ν = 0`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn lanes_back<const K: u8>(
    j: f64,
    m: f64,
    tk: &[f64],
    [cy, cz, by, bz, ay, az, hy, hz, dy, dz]: [&[f64]; 10],
    g0: &mut [f64],
    g1: &mut [f64],
    g2: &mut [f64],
    nu: &mut [f64],
    p0: &mut [f64],
    p1: &mut [f64],
    p2: &mut [f64],
    p3: &mut [f64],
    p4: &mut [f64],
    p5: &mut [f64],
    z0: &mut [f64],
    z1: &mut [f64],
    z2: &mut [f64],
    mut keep: impl FnMut(usize, &spatial::AbaBack),
) {
    let bl = tk.len();
    let (cy, cz, by, bz, ay, az) = (
        &cy[..bl],
        &cz[..bl],
        &by[..bl],
        &bz[..bl],
        &ay[..bl],
        &az[..bl],
    );
    let (hy, hz, dy, dz) = (&hy[..bl], &hz[..bl], &dy[..bl], &dz[..bl]);
    let (g0, g1, g2, nu) = (&mut g0[..bl], &mut g1[..bl], &mut g2[..bl], &mut nu[..bl]);
    let (p0, p1, p2) = (&mut p0[..bl], &mut p1[..bl], &mut p2[..bl]);
    let (p3, p4, p5) = (&mut p3[..bl], &mut p4[..bl], &mut p5[..bl]);
    let (z0, z1, z2) = (&mut z0[..bl], &mut z1[..bl], &mut z2[..bl]);
    for l in 0..bl {
        let cp = [p0[l], p1[l], p2[l], p3[l], p4[l], p5[l]];
        let czc = [z0[l], z1[l], z2[l]];
        let (cy, cz, by, bz, ay, az) = (cy[l], cz[l], by[l], bz[l], ay[l], az[l]);
        let r = match K {
            REV => {
                spatial::aba_back_rev(&cp, &czc, j, m, cy, cz, by, bz, ay, az, tk[l], dy[l], dz[l])
            }
            PRI => spatial::aba_back_pri(
                &cp, &czc, j, m, cy, cz, by, bz, ay, az, hy[l], hz[l], tk[l], dy[l], dz[l],
            ),
            _ => spatial::aba_back_locked(&cp, &czc, j, m, cy, cz, by, bz, ay, az, dy[l], dz[l]),
        };
        g0[l] = r.g[0];
        g1[l] = r.g[1];
        g2[l] = r.g[2];
        nu[l] = r.nu;
        [p0[l], p1[l], p2[l], p3[l], p4[l], p5[l]] = r.cp;
        [z0[l], z1[l], z2[l]] = r.cz;
        keep(l, &r);
    }
}

/// Forward step of joint kind `K` over all lanes: from the carried `A` (`a0..a2`), the gain,
/// `ν` and the link quantities, writes `q̈_k` to `out` and the new `A`; a locked joint gives
/// `q̈ = 0` and `A = Φ A_p + a`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn lanes_fwd<const K: u8>(
    [g0, g1, g2, nu]: [&[f64]; 4],
    [ay, az, hy, hz, dy, dz]: [&[f64]; 6],
    out: &mut [f64],
    a0: &mut [f64],
    a1: &mut [f64],
    a2: &mut [f64],
) {
    let bl = out.len();
    let (g0, g1, g2, nu) = (&g0[..bl], &g1[..bl], &g2[..bl], &nu[..bl]);
    let (ay, az, hy, hz, dy, dz) = (
        &ay[..bl],
        &az[..bl],
        &hy[..bl],
        &hz[..bl],
        &dy[..bl],
        &dz[..bl],
    );
    let (a0, a1, a2) = (&mut a0[..bl], &mut a1[..bl], &mut a2[..bl]);
    for l in 0..bl {
        let ap = [a0[l], a1[l], a2[l]];
        let (qk, a) = match K {
            REV => spatial::aba_fwd_rev(&ap, g1[l], g2[l], nu[l], ay[l], az[l], dy[l], dz[l]),
            PRI => spatial::aba_fwd_pri(
                &ap,
                &[g0[l], g1[l], g2[l]],
                nu[l],
                ay[l],
                az[l],
                hy[l],
                hz[l],
                dy[l],
                dz[l],
            ),
            _ => {
                let ab = spatial::motion_transport(&ap, dy[l], dz[l]);
                (0.0, [ab[0], ab[1] + ay[l], ab[2] + az[l]])
            }
        };
        out[l] = qk;
        [a0[l], a1[l], a2[l]] = a;
    }
}

/// The backward step of joint kind `K` for one lane ([`lanes_back`] over slices of length 1):
/// `link` holds the link's `c_y, c_z, b_y, b_z, a_y, a_z, h_y, h_z, d_y, d_z`, `gain` receives
/// `(G_k, ν_k)`, `carry` is `(P⁺, z⁺)`; `keep` sees the full step.
#[inline(always)]
pub(crate) fn one_lane_back<const K: u8>(
    j: f64,
    m: f64,
    tau_k: f64,
    link: [&f64; 10],
    (g, nu): (&mut [f64; 3], &mut f64),
    (cp, cz): (&mut spatial::Sym3, &mut [f64; 3]),
    mut keep: impl FnMut(&spatial::AbaBack),
) {
    let [g0, g1, g2] = g;
    let [p0, p1, p2, p3, p4, p5] = cp;
    let [z0, z1, z2] = cz;
    let m1 = std::slice::from_mut;
    lanes_back::<K>(
        j,
        m,
        std::slice::from_ref(&tau_k),
        link.map(std::slice::from_ref),
        m1(g0),
        m1(g1),
        m1(g2),
        m1(nu),
        m1(p0),
        m1(p1),
        m1(p2),
        m1(p3),
        m1(p4),
        m1(p5),
        m1(z0),
        m1(z1),
        m1(z2),
        |_, r| keep(r),
    );
}

/// The forward step of joint kind `K` for one lane ([`lanes_fwd`] over slices of length 1):
/// `link` holds `a_y, a_z, h_y, h_z, d_y, d_z`, `ap` the carried `A`; returns `q̈_k`.
#[inline(always)]
pub(crate) fn one_lane_fwd<const K: u8>(
    g: &[f64; 3],
    nu: f64,
    link: [&f64; 6],
    ap: &mut [f64; 3],
) -> f64 {
    let [g0, g1, g2] = g;
    let gain = [g0, g1, g2, &nu].map(std::slice::from_ref);
    let [a0, a1, a2] = ap;
    let m1 = std::slice::from_mut;
    let mut qk = 0.0;
    lanes_fwd::<K>(
        gain,
        link.map(std::slice::from_ref),
        m1(&mut qk),
        m1(a0),
        m1(a1),
        m1(a2),
    );
    qk
}

/// One lane in a [`Workspace`]: the carries are locals, `P_k`, `z_k`, the gains and `A_k` are
/// kept in the workspace for the callers that read them (pseudo joints, closed chains).
struct OneLane<'a> {
    ws: &'a mut Workspace,
    tau: &'a [f64],
    qdd: &'a mut [f64],
    cp: spatial::Sym3,
    cz: [f64; 3],
    ap: [f64; 3],
}

impl AbaLanes for OneLane<'_> {
    #[inline(always)]
    fn back<const K: u8>(&mut self, k: usize, j: f64, m: f64) {
        let ws = &mut *self.ws;
        let link = [
            &ws.cy, &ws.cz, &ws.by, &ws.bz, &ws.ay, &ws.az, &ws.hy, &ws.hz, &ws.dy, &ws.dz,
        ]
        .map(|v| &v[k]);
        let (pk, zk) = (&mut ws.p[k], &mut ws.z[k]);
        let carry = (&mut self.cp, &mut self.cz);
        let gain = (&mut ws.g[k], &mut ws.nu[k]);
        one_lane_back::<K>(j, m, self.tau[k], link, gain, carry, |r| {
            *pk = r.p;
            *zk = r.z;
        });
    }

    #[inline(always)]
    fn fwd<const K: u8>(&mut self, k: usize) {
        let ws = &mut *self.ws;
        let link = [&ws.ay, &ws.az, &ws.hy, &ws.hz, &ws.dy, &ws.dz].map(|v| &v[k]);
        self.qdd[k] = one_lane_fwd::<K>(&ws.g[k], ws.nu[k], link, &mut self.ap);
        ws.acc[k] = self.ap;
    }
}
