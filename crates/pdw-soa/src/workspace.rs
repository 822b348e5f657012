//! Scratch memory sized from a chain, and the shared first pass (kinematics + velocity biases).

use faer::dyn_stack::{MemBuffer, StackReq};
use faer::linalg::cholesky::llt;
use faer::{Mat, Par};

use crate::chain::Chain;
use crate::dual::Scalar;
use crate::error::{check_len, SoaError};
use crate::spatial::{self, Sym3};

/// Every intermediate of the scalar kernels, allocated once by [`Workspace::new`].
///
/// Per-link vectors have length `n` (one entry per joint/link, base to tip) and are filled by
/// the pass named in their comment. Kernels read the fields they need; accessors expose results.
pub struct Workspace {
    pub(crate) n: usize,
    // --- pass 1 (kinematics and velocity biases), base to tip ---
    /// absolute link angle θ_k (rad)
    pub(crate) theta: Vec<f64>,
    /// sin θ_k, cos θ_k
    pub(crate) s: Vec<f64>,
    pub(crate) c: Vec<f64>,
    /// absolute angular rate ω_k
    pub(crate) w: Vec<f64>,
    /// lever d_k = p_k − p_{k−1} (world)
    pub(crate) dy: Vec<f64>,
    pub(crate) dz: Vec<f64>,
    /// prismatic world axis h_k (zero for revolute joints)
    pub(crate) hy: Vec<f64>,
    pub(crate) hz: Vec<f64>,
    /// world COM offset c_k from p_k
    pub(crate) cy: Vec<f64>,
    pub(crate) cz: Vec<f64>,
    /// acceleration bias a_k (linear part; seed eq. 3.13)
    pub(crate) ay: Vec<f64>,
    pub(crate) az: Vec<f64>,
    /// force bias b_k (linear part; seed eq. 3.14)
    pub(crate) by: Vec<f64>,
    pub(crate) bz: Vec<f64>,
    /// tip lever p_tip − p_{n−1} (world)
    pub(crate) tip_d: [f64; 2],
    // --- articulated-body passes ---
    /// articulated inertia P_k before the joint-k innovation
    pub(crate) p: Vec<Sym3>,
    /// articulated bias force z_k before the joint-k innovation
    pub(crate) z: Vec<[f64; 3]>,
    /// gain G_k = P_k H_k / D_k
    pub(crate) g: Vec<[f64; 3]>,
    /// ν_k = ε_k / D_k
    pub(crate) nu: Vec<f64>,
    /// spatial acceleration A_k of link k at p_k (classical, gravity included as base accel.)
    pub(crate) acc: Vec<[f64; 3]>,
    /// spatial force F_k transmitted across joint k, from link k−1 (or the base) onto link k, at p_k
    pub(crate) force: Vec<[f64; 3]>,
    /// scratch joint vectors
    pub(crate) tmp: Vec<f64>,
    pub(crate) tmp2: Vec<f64>,
    // --- positions (kinematics::forward_kinematics) ---
    pub(crate) joint_pos: Vec<[f64; 2]>,
    pub(crate) com_pos: Vec<[f64; 2]>,
    pub(crate) tip_pos: [f64; 2],
    // --- dense (crba, constraints) ---
    /// mass matrix 𝓜 (n × n), filled by crba
    pub(crate) mass: Mat<f64>,
    /// Cholesky factor L of 𝓜 (n × n, lower triangle)
    pub(crate) chol: Mat<f64>,
    /// right-hand sides (n × n)
    pub(crate) rhs: Mat<f64>,
    /// tip Jacobian (3 × n)
    pub(crate) jac: Mat<f64>,
    /// small constraint operator (n × n) and its factor
    pub(crate) small: Mat<f64>,
    pub(crate) small_rhs: Mat<f64>,
    /// impulsive constraint rows A (n × n, first m rows used)
    pub(crate) arows: Mat<f64>,
    /// locked-joint mask (length n)
    pub(crate) mask: Vec<bool>,
    pub(crate) mem: MemBuffer,
}

impl Workspace {
    /// Allocate every buffer for `chain`.
    pub fn new(chain: &Chain) -> Self {
        let n = chain.dof();
        let v = || vec![0.0; n];
        let req = Self::faer_scratch(n);
        Workspace {
            n,
            theta: v(),
            s: v(),
            c: v(),
            w: v(),
            dy: v(),
            dz: v(),
            hy: v(),
            hz: v(),
            cy: v(),
            cz: v(),
            ay: v(),
            az: v(),
            by: v(),
            bz: v(),
            tip_d: [0.0; 2],
            p: vec![[0.0; 6]; n],
            z: vec![[0.0; 3]; n],
            g: vec![[0.0; 3]; n],
            nu: v(),
            acc: vec![[0.0; 3]; n],
            force: vec![[0.0; 3]; n],
            tmp: v(),
            tmp2: v(),
            joint_pos: vec![[0.0; 2]; n],
            com_pos: vec![[0.0; 2]; n],
            tip_pos: [0.0; 2],
            mass: Mat::zeros(n, n),
            chol: Mat::zeros(n, n),
            rhs: Mat::zeros(n, n),
            jac: Mat::zeros(3, n),
            small: Mat::zeros(n, n),
            small_rhs: Mat::zeros(n, n),
            arows: Mat::zeros(n, n),
            mask: vec![false; n],
            mem: MemBuffer::new(req),
        }
    }

    /// The bytes [`Workspace::new`] allocates for a chain of `n` joints, known before building
    /// it (in the manner of faer's `*_scratch` queries): 17 per-link vectors, 6 per-link
    /// spatial triples or pairs, the symmetric `P_k`, seven dense blocks (faer pads each column
    /// to a multiple of 8 rows) and faer's Cholesky scratch. Memory does not depend on the
    /// lane count or the call: every kernel call reuses it (tested against a byte-counting
    /// allocator).
    pub fn scratch_bytes(n: usize) -> usize {
        const F: usize = std::mem::size_of::<f64>();
        let padded = |rows: usize| rows.next_multiple_of(8);
        let vectors = 17 * n * F;
        let triples = 4 * n * 3 * F + 2 * n * 2 * F + n * 6 * F;
        let mask = n * std::mem::size_of::<bool>();
        let dense = if n == 0 {
            0
        } else {
            (6 * padded(n) * n + padded(3) * n) * F
        };
        vectors + triples + mask + dense + Self::faer_scratch(n).size_bytes()
    }

    /// faer's scratch for the Cholesky factorisation and solve of an `n × n` block.
    fn faer_scratch(n: usize) -> StackReq {
        llt::factor::cholesky_in_place_scratch::<f64>(n, Par::Seq, Default::default())
            .or(llt::solve::solve_in_place_scratch::<f64>(n, n, Par::Seq))
            .or(StackReq::new::<f64>(4 * n + 16))
    }

    /// Number of joints this workspace was sized for.
    pub fn dof(&self) -> usize {
        self.n
    }
    /// Spatial forces `F_k = [τ, f_y, f_z]` transmitted across each joint (from link k−1, or the
    /// ground for k = 0, onto link k; moment about the joint point), as left by the last call to
    /// [`crate::rnea::rnea`] (or a routine documented to fill them).
    pub fn joint_forces(&self) -> &[[f64; 3]] {
        &self.force
    }
    /// Spatial accelerations `A_k = [ω̇, a_y, a_z]` of each joint point (gravity included as the
    /// base acceleration, i.e. these are `a − g`), as left by the last rnea/aba call.
    pub fn link_accelerations(&self) -> &[[f64; 3]] {
        &self.acc
    }
    /// The mass matrix 𝓜 (n × n) left by the last [`crate::crba::crba`] call.
    pub fn mass_matrix(&self) -> &Mat<f64> {
        &self.mass
    }
}

/// Pass 1: link angles, levers, world COM offsets, prismatic axes, angular rates and the
/// velocity-dependent bias terms, base to tip. `qd = None` means zero joint rates.
/// The one-lane instance of [`kin_recursion`].
pub(crate) fn kin_pass(
    chain: &Chain,
    ws: &mut Workspace,
    q: &[f64],
    qd: Option<&[f64]>,
) -> Result<(), SoaError> {
    let n = chain.dof();
    check_len("workspace dof", n, ws.n)?;
    check_len("q", n, q.len())?;
    if let Some(qd) = qd {
        check_len("qd", n, qd.len())?;
    }
    kin_recursion(chain, &mut WsKin { ws, q, qd });
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// The kinematic pass, written once over where the lanes live and over the scalar.
// ---------------------------------------------------------------------------------------------

/// The constants of link `k` in pass 1: mass `m`, the previous link's lever to this joint `lp`
/// (`0` for the first), the local COM offset and the prismatic axis (parent frame).
#[derive(Clone, Copy)]
pub(crate) struct KinLink {
    pub(crate) m: f64,
    pub(crate) lp: [f64; 2],
    pub(crate) com: [f64; 2],
    pub(crate) u: [f64; 2],
}

/// Where the lanes of one kinematic pass live (one lane of a [`Workspace`], a block of lanes in
/// the columns of a [`crate::BatchWorkspace`], stack arrays of any [`Scalar`]): each link's step
/// hands its quantities, one slice per quantity over its lanes, to [`lanes_angles`] and
/// [`lanes_kin`], the tip's to [`lanes_tip`].
pub(crate) trait KinLanes {
    /// Step of link `k` (prismatic joint if `PRI`) for every lane.
    fn link<const PRI: bool>(&mut self, k: usize, c: &KinLink);
    /// The tip lever `R_{n−1} l` of the last link's `l = to_next_{n−1}` for every lane.
    fn tip(&mut self, lp: [f64; 2]);
}

/// The kinematic pass (seed §3.3: Φ, H and the bias terms of eq. 3.13–3.14), base to tip over
/// [`KinLanes::link`], then the tip lever.
#[inline(always)]
pub(crate) fn kin_recursion<S: KinLanes>(chain: &Chain, s: &mut S) {
    let n = chain.dof();
    let mut lp = [0.0, 0.0];
    for k in 0..n {
        let link = &chain.links[k];
        let c = KinLink {
            m: link.mass,
            lp,
            com: link.com,
            u: chain.axis[k],
        };
        if chain.prismatic[k] {
            s.link::<true>(k, &c);
        } else {
            s.link::<false>(k, &c);
        }
        lp = link.to_next;
    }
    s.tip(lp);
}

/// Angles of link `k` over all lanes: `θ = θ_p + q` then `(sin θ, cos θ)` for a revolute
/// joint; a prismatic joint keeps `θ_p` and its sine and cosine. Inputs `θ_p, sin θ_p, cos θ_p,
/// q`.
#[inline(always)]
pub(crate) fn lanes_angles<T: Scalar, const PRI: bool>(
    [thp, sp, cp, qk]: [&[T]; 4],
    th: &mut [T],
    s: &mut [T],
    c: &mut [T],
) {
    let bl = th.len();
    let (s, c) = (&mut s[..bl], &mut c[..bl]);
    if PRI {
        th.copy_from_slice(&thp[..bl]);
        s.copy_from_slice(&sp[..bl]);
        c.copy_from_slice(&cp[..bl]);
    } else {
        let (thp, qk) = (&thp[..bl], &qk[..bl]);
        for l in 0..bl {
            th[l] = thp[l] + qk[l];
        }
        T::sin_cos_lanes(th, s, c);
    }
}

// The lane loops take every output stream as its own slice parameter (distinct `noalias`
// parameters: no runtime overlap checks in the vectorised loop; see aba.rs).

/// Geometry, rate and biases of link `k` over all lanes (joint kind `PRI`): from the previous
/// link's `sin, cos, ω` (`sp, cp, wp`), this link's `sin, cos` (`s, c`), `q` and `q̇`, writes
/// the lever `d`, the axis `h` (`0` for a revolute joint), the COM offset `c`, `ω` and the
/// biases `a`, `b` (seed eq. 3.13–3.14).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn lanes_kin<T: Scalar, const PRI: bool>(
    kl: &KinLink,
    [sp, cp, s, c, wp, qk, qdk]: [&[T]; 7],
    dy: &mut [T],
    dz: &mut [T],
    hy: &mut [T],
    hz: &mut [T],
    cy: &mut [T],
    cz: &mut [T],
    w: &mut [T],
    ay: &mut [T],
    az: &mut [T],
    by: &mut [T],
    bz: &mut [T],
) {
    let bl = dy.len();
    let (sp, cp, wp, qdk) = (&sp[..bl], &cp[..bl], &wp[..bl], &qdk[..bl]);
    let (dz, hy, hz) = (&mut dz[..bl], &mut hy[..bl], &mut hz[..bl]);
    let (cy, cz, w) = (&mut cy[..bl], &mut cz[..bl], &mut w[..bl]);
    let (ay, az, by, bz) = (&mut ay[..bl], &mut az[..bl], &mut by[..bl], &mut bz[..bl]);
    let m = T::cst(kl.m);
    let (lyp, lzp) = (T::cst(kl.lp[0]), T::cst(kl.lp[1]));
    let (comy, comz) = (T::cst(kl.com[0]), T::cst(kl.com[1]));
    if PRI {
        let qk = &qk[..bl];
        let (uy, uz) = (T::cst(kl.u[0]), T::cst(kl.u[1]));
        for l in 0..bl {
            let (dyl, dzl, hyl, hzl, cyl, czl) =
                spatial::geom_pri(sp[l], cp[l], lyp, lzp, uy, uz, qk[l], comy, comz);
            let (wl, ayl, azl) = spatial::vel_pri(wp[l], qdk[l], dyl, dzl, hyl, hzl);
            let (byl, bzl) = spatial::force_bias(m, wl, cyl, czl);
            (dy[l], dz[l], hy[l], hz[l], cy[l], cz[l]) = (dyl, dzl, hyl, hzl, cyl, czl);
            (w[l], ay[l], az[l], by[l], bz[l]) = (wl, ayl, azl, byl, bzl);
        }
    } else {
        let (s, c) = (&s[..bl], &c[..bl]);
        let zero = T::cst(0.0);
        for l in 0..bl {
            let (dyl, dzl, cyl, czl) =
                spatial::geom_rev(sp[l], cp[l], lyp, lzp, s[l], c[l], comy, comz);
            let (wl, ayl, azl) = spatial::vel_rev(wp[l], qdk[l], dyl, dzl);
            let (byl, bzl) = spatial::force_bias(m, wl, cyl, czl);
            (dy[l], dz[l], hy[l], hz[l], cy[l], cz[l]) = (dyl, dzl, zero, zero, cyl, czl);
            (w[l], ay[l], az[l], by[l], bz[l]) = (wl, ayl, azl, byl, bzl);
        }
    }
}

/// The tip lever `R_{n−1} l = [c l_y − s l_z, s l_y + c l_z]` over all lanes from the last
/// link's `sin, cos`.
#[inline(always)]
pub(crate) fn lanes_tip<T: Scalar>(lp: [f64; 2], sp: &[T], cp: &[T], ty: &mut [T], tz: &mut [T]) {
    let bl = ty.len();
    let (sp, cp, tz) = (&sp[..bl], &cp[..bl], &mut tz[..bl]);
    let (lyp, lzp) = (T::cst(lp[0]), T::cst(lp[1]));
    for l in 0..bl {
        ty[l] = cp[l] * lyp - sp[l] * lzp;
        tz[l] = sp[l] * lyp + cp[l] * lzp;
    }
}

/// One lane of the kinematic pass for any [`Scalar`], with the previous link's
/// `θ, sin, cos, ω` carried in `prev`: writes link `k`'s angles to `ang` and the rest through
/// [`lanes_kin`] into `out` (`d_y, d_z, h_y, h_z, c_y, c_z, ω, a_y, a_z, b_y, b_z`); returns the
/// new carry.
#[inline(always)]
pub(crate) fn one_lane_kin<T: Scalar, const PRI: bool>(
    kl: &KinLink,
    prev: [T; 4],
    (qk, qdk): (T, T),
    out: [&mut T; 11],
) -> [T; 4] {
    let [thp, sp, cp, wp] = prev;
    let (mut th, mut s, mut c) = (thp, sp, cp);
    let one = std::slice::from_ref;
    let m1 = std::slice::from_mut;
    lanes_angles::<T, PRI>(
        [one(&thp), one(&sp), one(&cp), one(&qk)],
        m1(&mut th),
        m1(&mut s),
        m1(&mut c),
    );
    let [dy, dz, hy, hz, cy, cz, w, ay, az, by, bz] = out;
    lanes_kin::<T, PRI>(
        kl,
        [
            one(&sp),
            one(&cp),
            one(&s),
            one(&c),
            one(&wp),
            one(&qk),
            one(&qdk),
        ],
        m1(dy),
        m1(dz),
        m1(hy),
        m1(hz),
        m1(cy),
        m1(cz),
        m1(&mut *w),
        m1(ay),
        m1(az),
        m1(by),
        m1(bz),
    );
    [th, s, c, *w]
}

/// One lane in a [`Workspace`] (every quantity kept per link).
struct WsKin<'a> {
    ws: &'a mut Workspace,
    q: &'a [f64],
    qd: Option<&'a [f64]>,
}

impl KinLanes for WsKin<'_> {
    #[inline(always)]
    fn link<const PRI: bool>(&mut self, k: usize, c: &KinLink) {
        let ws = &mut *self.ws;
        let prev = match k {
            0 => [0.0, 0.0, 1.0, 0.0],
            _ => [ws.theta[k - 1], ws.s[k - 1], ws.c[k - 1], ws.w[k - 1]],
        };
        let qdk = self.qd.map_or(0.0, |v| v[k]);
        let out = [
            &mut ws.dy[k],
            &mut ws.dz[k],
            &mut ws.hy[k],
            &mut ws.hz[k],
            &mut ws.cy[k],
            &mut ws.cz[k],
            &mut ws.w[k],
            &mut ws.ay[k],
            &mut ws.az[k],
            &mut ws.by[k],
            &mut ws.bz[k],
        ];
        let [th, s, c, _] = one_lane_kin::<f64, PRI>(c, prev, (self.q[k], qdk), out);
        (ws.theta[k], ws.s[k], ws.c[k]) = (th, s, c);
    }

    #[inline(always)]
    fn tip(&mut self, lp: [f64; 2]) {
        let ws = &mut *self.ws;
        let (sp, cp) = match ws.n {
            0 => (0.0, 1.0),
            n => (ws.s[n - 1], ws.c[n - 1]),
        };
        let [ty, tz] = &mut ws.tip_d;
        let (one, m1) = (std::slice::from_ref, std::slice::from_mut);
        lanes_tip(lp, one(&sp), one(&cp), m1(ty), m1(tz));
    }
}

impl std::fmt::Debug for Workspace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Workspace")
            .field("n", &self.n)
            .finish_non_exhaustive()
    }
}
