//! Scratch memory sized from a chain, and the shared first pass (kinematics + velocity biases).

use faer::dyn_stack::{MemBuffer, StackReq};
use faer::linalg::cholesky::llt;
use faer::{Mat, Par};

use crate::chain::Chain;
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
        let req = llt::factor::cholesky_in_place_scratch::<f64>(n, Par::Seq, Default::default())
            .or(llt::solve::solve_in_place_scratch::<f64>(n, n, Par::Seq))
            .or(StackReq::new::<f64>(4 * n + 16));
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
    let (mut thp, mut sp, mut cp, mut wp) = (0.0, 0.0, 1.0, 0.0);
    let (mut lyp, mut lzp) = (0.0, 0.0);
    for k in 0..n {
        let link = &chain.links[k];
        let qk = q[k];
        let qdk = match qd {
            Some(v) => v[k],
            None => 0.0,
        };
        let (w, ay, az);
        if chain.prismatic[k] {
            let u = chain.axis[k];
            let (dy, dz, hy, hz, cy, cz) =
                spatial::geom_pri(sp, cp, lyp, lzp, u[0], u[1], qk, link.com[0], link.com[1]);
            (w, ay, az) = spatial::vel_pri(wp, qdk, dy, dz, hy, hz);
            ws.theta[k] = thp;
            ws.s[k] = sp;
            ws.c[k] = cp;
            ws.dy[k] = dy;
            ws.dz[k] = dz;
            ws.hy[k] = hy;
            ws.hz[k] = hz;
            ws.cy[k] = cy;
            ws.cz[k] = cz;
        } else {
            let th = thp + qk;
            let (s, c) = spatial::sincos(th);
            let (dy, dz, cy, cz) =
                spatial::geom_rev(sp, cp, lyp, lzp, s, c, link.com[0], link.com[1]);
            (w, ay, az) = spatial::vel_rev(wp, qdk, dy, dz);
            ws.theta[k] = th;
            ws.s[k] = s;
            ws.c[k] = c;
            ws.dy[k] = dy;
            ws.dz[k] = dz;
            ws.hy[k] = 0.0;
            ws.hz[k] = 0.0;
            ws.cy[k] = cy;
            ws.cz[k] = cz;
        }
        let (by, bz) = spatial::force_bias(link.mass, w, ws.cy[k], ws.cz[k]);
        ws.w[k] = w;
        ws.ay[k] = ay;
        ws.az[k] = az;
        ws.by[k] = by;
        ws.bz[k] = bz;
        thp = ws.theta[k];
        sp = ws.s[k];
        cp = ws.c[k];
        wp = w;
        lyp = link.to_next[0];
        lzp = link.to_next[1];
    }
    // tip lever: R_{n−1} · to_next_{n−1}
    ws.tip_d = [cp * lyp - sp * lzp, sp * lyp + cp * lzp];
    Ok(())
}

impl std::fmt::Debug for Workspace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Workspace")
            .field("n", &self.n)
            .finish_non_exhaustive()
    }
}
