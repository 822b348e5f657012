//! The seed's literal dense operator form — the deliberately O(n³) baseline.
//!
//! With the stacked `3n × 3n` block lower-triangular propagation operator
//! `Φ = [Φ_{i,j}]_{i ≥ j}` (seed eq. 2.19, 2.52), the `3n × n` joint map `H`, the block-diagonal
//! spatial inertia `M`, the stacked biases `a`, `b` (gravity folded into `a_1` as `Φ_{1,0} a_b`,
//! seed eq. 2.64) and `Φ_t = [0 … Φ_{t,n}]`:
//!
//! ```text
//! 𝓜 = Hᵀ Φᵀ M Φ H,   C = Hᵀ Φᵀ (M Φ a + b),   J = Φ_t Φ H          (seed eq. 2.62, 2.65)
//! q̈ = 𝓜⁻¹ (τ − C − Jᵀ F_t)                                        (seed eq. 2.63)
//! ```
//! formed with dense matrix products and solved by LU with partial pivoting.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::lu::partial_pivoting::{factor as lu_factor, solve as lu_solve};
use faer::linalg::matmul::matmul;
use faer::{Accum, Conj, Mat, Par};

use crate::chain::Chain;
use crate::error::{check_len, SoaError};
use crate::workspace::{kin_pass, Workspace};

/// Dense buffers of the naive baseline, allocated once.
pub struct NaiveWorkspace {
    n: usize,
    /// Φ (3n × 3n)
    phi: Mat<f64>,
    /// H (3n × n)
    h: Mat<f64>,
    /// M (3n × 3n)
    m: Mat<f64>,
    /// Φ H (3n × n)
    phih: Mat<f64>,
    /// M Φ H (3n × n)
    mphih: Mat<f64>,
    /// 𝓜 (n × n), overwritten by its LU factors
    mass: Mat<f64>,
    /// stacked a, Φ a, M Φ a + b (3n × 1 each)
    a: Mat<f64>,
    phia: Mat<f64>,
    v: Mat<f64>,
    /// Φ_t (3 × 3n) and J (3 × n)
    phit: Mat<f64>,
    jac: Mat<f64>,
    /// right-hand side / solution (n × 1)
    rhs: Mat<f64>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    mem: MemBuffer,
}

impl NaiveWorkspace {
    /// Allocate the dense operators for `chain`.
    pub fn new(chain: &Chain) -> Self {
        let n = chain.dof();
        let m3 = 3 * n;
        let req = lu_factor::lu_in_place_scratch::<usize, f64>(n, n, Par::Seq, Default::default())
            .or(lu_solve::solve_in_place_scratch::<usize, f64>(
                n,
                1,
                Par::Seq,
            ))
            .or(StackReq::EMPTY);
        NaiveWorkspace {
            n,
            phi: Mat::zeros(m3, m3),
            h: Mat::zeros(m3, n),
            m: Mat::zeros(m3, m3),
            phih: Mat::zeros(m3, n),
            mphih: Mat::zeros(m3, n),
            mass: Mat::zeros(n, n),
            a: Mat::zeros(m3, 1),
            phia: Mat::zeros(m3, 1),
            v: Mat::zeros(m3, 1),
            phit: Mat::zeros(3, m3),
            jac: Mat::zeros(3, n),
            rhs: Mat::zeros(n, 1),
            perm: vec![0; n],
            perm_inv: vec![0; n],
            mem: MemBuffer::new(req),
        }
    }

    /// 𝓜 as formed by the last [`naive_mass_matrix`] call (before factorisation).
    pub fn mass_matrix(&self) -> &Mat<f64> {
        &self.mass
    }
}

/// Build the dense operators Φ, H, M, a, b, Φ_t at `(q, q̇)` and form `X = Φ H`, `M X`,
/// `𝓜 = Xᵀ M X`, `C = Xᵀ (M Φ a + b)` (into `nws.v` → returned through `c`), `J = Φ_t X`.
fn build(
    chain: &Chain,
    ws: &mut Workspace,
    nws: &mut NaiveWorkspace,
    q: &[f64],
    qd: &[f64],
    c: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    check_len("naive workspace dof", n, nws.n)?;
    kin_pass(chain, ws, q, Some(qd))?;
    fill_operators(chain, ws, nws);
    form_products(nws, c);
    Ok(())
}

/// The dense operators at the state of the kinematic pass in `ws`: Φ (seed eq. 2.16, 2.19), H,
/// the block-diagonal M, the stacked biases a (gravity folded into a_1, seed eq. 2.64) and b
/// (in `nws.v`), and Φ_t.
fn fill_operators(chain: &Chain, ws: &Workspace, nws: &mut NaiveWorkspace) {
    let n = chain.dof();
    nws.phi.fill(0.0);
    nws.h.fill(0.0);
    nws.m.fill(0.0);
    nws.phit.fill(0.0);
    // Φ_{i,j} = Φ(p_i − p_j), p_i − p_j = Σ_{k=j+1..i} d_k   (seed eq. 2.16)
    for j in 0..n {
        let (mut ly, mut lz) = (0.0, 0.0);
        for i in j..n {
            if i > j {
                ly += ws.dy[i];
                lz += ws.dz[i];
            }
            let (r, cc) = (3 * i, 3 * j);
            nws.phi[(r, cc)] = 1.0;
            nws.phi[(r + 1, cc + 1)] = 1.0;
            nws.phi[(r + 2, cc + 2)] = 1.0;
            nws.phi[(r + 1, cc)] = -lz;
            nws.phi[(r + 2, cc)] = ly;
        }
    }
    for k in 0..n {
        let r = 3 * k;
        if chain.prismatic[k] {
            nws.h[(r + 1, k)] = ws.hy[k];
            nws.h[(r + 2, k)] = ws.hz[k];
        } else {
            nws.h[(r, k)] = 1.0;
        }
        let link = &chain.links[k];
        let (m, cy, cz) = (link.mass, ws.cy[k], ws.cz[k]);
        let blk = [
            [chain.j_joint[k], -m * cz, m * cy],
            [-m * cz, m, 0.0],
            [m * cy, 0.0, m],
        ];
        for (a, row) in blk.iter().enumerate() {
            for (b, v) in row.iter().enumerate() {
                nws.m[(r + a, r + b)] = *v;
            }
        }
        nws.a[(r, 0)] = 0.0;
        nws.a[(r + 1, 0)] = ws.ay[k];
        nws.a[(r + 2, 0)] = ws.az[k];
        nws.v[(r, 0)] = 0.0;
        nws.v[(r + 1, 0)] = ws.by[k];
        nws.v[(r + 2, 0)] = ws.bz[k];
    }
    // gravity: Φ_{1,0} a_b folded into a_1 (seed eq. 2.64)
    let ab = chain.base_acc;
    nws.a[(0, 0)] += ab[0];
    nws.a[(1, 0)] += ab[1] - ws.dz[0] * ab[0];
    nws.a[(2, 0)] += ab[2] + ws.dy[0] * ab[0];
    let r = 3 * (n - 1);
    nws.phit[(0, r)] = 1.0;
    nws.phit[(1, r + 1)] = 1.0;
    nws.phit[(2, r + 2)] = 1.0;
    nws.phit[(1, r)] = -ws.tip_d[1];
    nws.phit[(2, r)] = ws.tip_d[0];
}

/// The products of the operators [`fill_operators`] wrote: `X = Φ H`, `M X`, `𝓜 = Xᵀ M X`,
/// `C = Xᵀ (M Φ a + b)` (into `c`), `J = Φ_t X`.
fn form_products(nws: &mut NaiveWorkspace, c: &mut [f64]) {
    let par = Par::Seq;
    matmul(
        nws.phih.as_mut(),
        Accum::Replace,
        nws.phi.as_ref(),
        nws.h.as_ref(),
        1.0,
        par,
    );
    matmul(
        nws.mphih.as_mut(),
        Accum::Replace,
        nws.m.as_ref(),
        nws.phih.as_ref(),
        1.0,
        par,
    );
    matmul(
        nws.mass.as_mut(),
        Accum::Replace,
        nws.phih.as_ref().transpose(),
        nws.mphih.as_ref(),
        1.0,
        par,
    );
    matmul(
        nws.phia.as_mut(),
        Accum::Replace,
        nws.phi.as_ref(),
        nws.a.as_ref(),
        1.0,
        par,
    );
    // v = M Φ a + b   (v holds b)
    matmul(
        nws.v.as_mut(),
        Accum::Add,
        nws.m.as_ref(),
        nws.phia.as_ref(),
        1.0,
        par,
    );
    matmul(
        nws.rhs.as_mut(),
        Accum::Replace,
        nws.phih.as_ref().transpose(),
        nws.v.as_ref(),
        1.0,
        par,
    );
    for (k, ck) in c.iter_mut().enumerate() {
        *ck = nws.rhs[(k, 0)];
    }
    matmul(
        nws.jac.as_mut(),
        Accum::Replace,
        nws.phit.as_ref(),
        nws.phih.as_ref(),
        1.0,
        par,
    );
}

/// The mass matrix `𝓜 = Hᵀ Φᵀ M Φ H` formed from the dense operators (O(n³)).
pub fn naive_mass_matrix<'a>(
    chain: &Chain,
    ws: &mut Workspace,
    nws: &'a mut NaiveWorkspace,
    q: &[f64],
    qd: &[f64],
) -> Result<&'a Mat<f64>, SoaError> {
    let mut c = std::mem::take(&mut ws.tmp);
    let r = build(chain, ws, nws, q, qd, &mut c);
    ws.tmp = c;
    r?;
    Ok(&nws.mass)
}

/// Forward dynamics from the dense operator form with an LU solve (O(n³)).
/// Same arguments and result as [`crate::aba::aba`].
#[allow(clippy::too_many_arguments)]
pub fn naive_forward_dynamics(
    chain: &Chain,
    ws: &mut Workspace,
    nws: &mut NaiveWorkspace,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
    f_tip: Option<[f64; 3]>,
    qdd: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    check_len("tau", n, tau.len())?;
    check_len("qdd", n, qdd.len())?;
    let mut c = std::mem::take(&mut ws.tmp);
    let r = build(chain, ws, nws, q, qd, &mut c);
    if r.is_ok() {
        let ft = f_tip.unwrap_or([0.0; 3]);
        for k in 0..n {
            let jt = nws.jac[(0, k)] * ft[0] + nws.jac[(1, k)] * ft[1] + nws.jac[(2, k)] * ft[2];
            nws.rhs[(k, 0)] = tau[k] - c[k] - jt;
        }
    }
    ws.tmp = c;
    r?;
    let stack = MemStack::new(&mut nws.mem);
    let (_, perm) = lu_factor::lu_in_place(
        nws.mass.as_mut(),
        &mut nws.perm,
        &mut nws.perm_inv,
        Par::Seq,
        stack,
        Default::default(),
    );
    lu_solve::solve_in_place_with_conj(
        nws.mass.as_ref(),
        nws.mass.as_ref(),
        perm,
        Conj::No,
        nws.rhs.as_mut(),
        Par::Seq,
        stack,
    );
    for (k, out) in qdd.iter_mut().enumerate() {
        *out = nws.rhs[(k, 0)];
    }
    Ok(())
}

impl std::fmt::Debug for NaiveWorkspace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NaiveWorkspace")
            .field("n", &self.n)
            .finish_non_exhaustive()
    }
}
