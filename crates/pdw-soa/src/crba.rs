//! Mass matrix by the composite-rigid-body algorithm in O(n²), and forward dynamics by a
//! Cholesky solve — the good dense baseline.
//!
//! ```text
//! K_n = M_n,   K_k = M_k + Φ_{k+1,k}ᵀ K_{k+1} Φ_{k+1,k}      (composite inertia at joint k)
//! 𝓜_kk = H_kᵀ K_k H_k,   f = K_k H_k,   𝓜_jk = H_jᵀ (Φ_{k,j}ᵀ f)  for j < k
//! ```
//! which equals `𝓜 = Hᵀ Φᵀ M Φ H` (seed eq. 2.62) entry by entry. Then
//! `𝓜 q̈ = τ − C − Jᵀ F_t` with `C` from RNEA at `q̈ = 0` and faer's `LLᵀ` factorisation.

use faer::dyn_stack::MemStack;
use faer::linalg::cholesky::llt;
use faer::{Conj, Mat, Par};

use crate::chain::Chain;
use crate::error::{check_len, SoaError};
use crate::rnea::rnea_passes;
use crate::spatial::{self, Sym3};
use crate::workspace::{kin_pass, Workspace};

/// Fill the mass matrix 𝓜(q) (n × n, symmetric, both triangles) into the workspace and return
/// it. O(n²).
pub fn crba<'a>(chain: &Chain, ws: &'a mut Workspace, q: &[f64]) -> Result<&'a Mat<f64>, SoaError> {
    kin_pass(chain, ws, q, None)?;
    crba_from_kin(chain, ws);
    Ok(&ws.mass)
}

/// CRBA over a workspace already filled by `kin_pass` at the wanted `q`.
pub(crate) fn crba_from_kin(chain: &Chain, ws: &mut Workspace) {
    let n = chain.dof();
    let mut carry: Sym3 = [0.0; 6];
    for k in (0..n).rev() {
        let link = &chain.links[k];
        let m = link.mass;
        let kk = [
            chain.j_joint[k] + carry[0],
            carry[1] - m * ws.cz[k],
            carry[2] + m * ws.cy[k],
            m + carry[3],
            carry[4],
            m + carry[5],
        ];
        ws.p[k] = kk;
        carry = spatial::congruence(&kk, ws.dy[k], ws.dz[k]);
    }
    for k in 0..n {
        let x = &ws.p[k];
        let (hy, hz) = (ws.hy[k], ws.hz[k]);
        let mut f = if chain.prismatic[k] {
            [
                x[1] * hy + x[2] * hz,
                x[3] * hy + x[4] * hz,
                x[4] * hy + x[5] * hz,
            ]
        } else {
            [x[0], x[1], x[2]]
        };
        ws.mass[(k, k)] = h_dot(chain, ws, k, &f);
        for j in (0..k).rev() {
            f = spatial::force_transport(&f, ws.dy[j + 1], ws.dz[j + 1]);
            let v = h_dot(chain, ws, j, &f);
            ws.mass[(j, k)] = v;
            ws.mass[(k, j)] = v;
        }
    }
}

#[inline]
fn h_dot(chain: &Chain, ws: &Workspace, k: usize, f: &[f64; 3]) -> f64 {
    if chain.prismatic[k] {
        ws.hy[k] * f[1] + ws.hz[k] * f[2]
    } else {
        f[0]
    }
}

/// Factor `ws.mass` into `ws.chol` (lower triangle).
pub(crate) fn factor_mass(ws: &mut Workspace) -> Result<(), SoaError> {
    ws.chol.copy_from(&ws.mass);
    let stack = MemStack::new(&mut ws.mem);
    llt::factor::cholesky_in_place(
        ws.chol.as_mut(),
        Default::default(),
        Par::Seq,
        stack,
        Default::default(),
    )
    .map_err(|_| SoaError::MassMatrixNotPositiveDefinite)?;
    Ok(())
}

/// Solve `𝓜 X = B` in place for the first `ncols` columns of `ws.rhs`, using `ws.chol`.
pub(crate) fn solve_mass_in_place(ws: &mut Workspace, ncols: usize) {
    let n = ws.n;
    let stack = MemStack::new(&mut ws.mem);
    llt::solve::solve_in_place_with_conj(
        ws.chol.as_ref(),
        Conj::No,
        ws.rhs.as_mut().submatrix_mut(0, 0, n, ncols),
        Par::Seq,
        stack,
    );
}

/// Forward dynamics by CRBA + Cholesky: `q̈ = 𝓜⁻¹ (τ − C − Jᵀ F_t)` (seed eq. 2.63).
/// Same arguments and result as [`crate::aba::aba`]; O(n³) for the factorisation.
pub fn forward_dynamics_crba(
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
    crba_from_kin(chain, ws);
    // C + Jᵀ F_t = RNEA(q, q̇, 0, F_t)
    let mut zero = std::mem::take(&mut ws.tmp);
    let mut c = std::mem::take(&mut ws.tmp2);
    zero.iter_mut().for_each(|x| *x = 0.0);
    rnea_passes(chain, ws, &zero, f_tip, &mut c);
    for k in 0..n {
        ws.rhs[(k, 0)] = tau[k] - c[k];
    }
    ws.tmp = zero;
    ws.tmp2 = c;
    factor_mass(ws)?;
    solve_mass_in_place(ws, 1);
    for (k, out) in qdd.iter_mut().enumerate() {
        *out = ws.rhs[(k, 0)];
    }
    Ok(())
}
