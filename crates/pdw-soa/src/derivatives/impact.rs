//! Plastic impacts (heel strike, knee strike, an offset contact point) and their exact
//! Jacobians (module docs of [`crate::derivatives`]).

use std::mem::MaybeUninit;

use faer::dyn_stack::MemStack;
use faer::linalg::cholesky::llt;
use faer::{Conj, MatMut, Par};

use crate::chain::Chain;
use crate::dual::{Dual, Scalar};
use crate::error::{check_len, SoaError};
use crate::spatial;

use super::{by_dof, check_dof, kin, ldl, ldl_solve, positions, Kin, Mat8, MAX_DOF};

/// Heel strike / tip impact of [`crate::tip_impact`] (the tip point's velocity and the rates of
/// the joints in `locked` become zero) with its exact Jacobian.
///
/// - `q`, `qd`: configuration and pre-impact rates `q̇⁻`, length `n`;
/// - `locked`: joints stopped in the same instant (distinct indices `< n`; `2 + len ≤ n`);
/// - `qd_post`: output `q̇⁺`, length `n`;
/// - `jac`: output `[∂q̇⁺/∂q | ∂q̇⁺/∂q̇⁻]`, `n × 2n` row-major (entry `(i, j)` at `i·2n + j`).
///
/// # Errors
/// As [`crate::tip_impact`] ([`SoaError::DimensionMismatch`], [`SoaError::InvalidJointIndex`],
/// [`SoaError::SingularConstraint`], [`SoaError::MassMatrixNotPositiveDefinite`]), and
/// [`SoaError::DimensionMismatch`] for `n > MAX_DOF`.
pub fn tip_impact_derivatives(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    locked: &[usize],
    qd_post: &mut [f64],
    jac: &mut [f64],
) -> Result<(), SoaError> {
    impact_derivatives(chain, q, qd, true, [0.0, 0.0], locked, qd_post, jac)
}

/// Knee strike of [`crate::joint_lock_impact`] (the rates of the joints in `locked` become zero)
/// with its exact Jacobian; arguments, layout and errors as [`tip_impact_derivatives`]
/// (`1 ≤ locked.len() ≤ n`).
pub fn joint_lock_impact_derivatives(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    locked: &[usize],
    qd_post: &mut [f64],
    jac: &mut [f64],
) -> Result<(), SoaError> {
    impact_derivatives(chain, q, qd, false, [0.0, 0.0], locked, qd_post, jac)
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn impact_derivatives(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    tip: bool,
    offset: [f64; 2],
    locked: &[usize],
    qd_post: &mut [f64],
    jac: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    check_dof(n)?;
    let m = locked.len() + if tip { 2 } else { 0 };
    check_len("q", n, q.len())?;
    check_len("qd_minus", n, qd.len())?;
    check_len("qd_plus", n, qd_post.len())?;
    check_len("jac (n x 2n)", 2 * n * n, jac.len())?;
    if m == 0 || m > n {
        return Err(SoaError::DimensionMismatch {
            what: "number of impulsive constraints (1 ≤ rows ≤ n)",
            expected: format!("1..={n}"),
            got: m.to_string(),
        });
    }
    let mut seen = [false; MAX_DOF];
    for &k in locked {
        if k >= n || seen[k] {
            return Err(SoaError::InvalidJointIndex { index: k, n });
        }
        seen[k] = true;
    }
    by_dof!(
        n,
        1,
        impact_derivatives_w(chain, q, qd, tip, offset, locked, qd_post, jac)
    )
}

/// [`impact_derivatives`] with duals of width `W = n` seeded on `q`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn impact_derivatives_w<const W: usize>(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    tip: bool,
    offset: [f64; 2],
    locked: &[usize],
    qd_post: &mut [f64],
    jac: &mut [f64],
) -> Result<(), SoaError> {
    let n = chain.dof();
    debug_assert_eq!(W, n);
    // value: the kernel's computation
    let k64 = kin::<f64>(chain, q, None);
    let mut mass = [[0.0; MAX_DOF]; MAX_DOF];
    mass_matrix(chain, &k64, &mut mass);
    let arows = constraint_rows(chain, &k64, tip, locked, offset);
    let m = locked.len() + if tip { 2 } else { 0 };
    impact_value(n, m, &mass, &arows, qd, qd_post)?;

    // derivatives: the same map in duals seeded on q (q̇ = 0: no bias terms)
    let zero = Dual::<W>::constant(0.0);
    let mut qx = [zero; MAX_DOF];
    for k in 0..n {
        qx[k] = Dual::variable(q[k], k);
    }
    let kd = kin(chain, &qx[..n], None);
    let mut mm = [[zero; MAX_DOF]; MAX_DOF];
    mass_matrix(chain, &kd, &mut mm);
    ldl(&mut mm, n).ok_or(SoaError::MassMatrixNotPositiveDefinite)?;
    let arows = constraint_rows(chain, &kd, tip, locked, offset);
    let (mut v, mut lam) = ([0.0; MAX_DOF], [0.0; MAX_DOF]);
    impact_in_duals(n, m, &mm, &arows, qd, &mut v, &mut lam, Some(jac))?;
    Ok(())
}

/// The plastic impact with constraint rows `a` (the leading `m` of them) in duals of width `W`
/// seeded on `q`, with `mm` the `LDLᵀ` factor of `𝓜(q)` ([`ldl`]): `X = 𝓜⁻¹Aᵀ`, `S = A X`,
/// `Λ = S⁻¹ A q̇⁻`, `q̇⁺ = q̇⁻ − X Λ` (module docs). Writes the values of `q̇⁺` and `Λ`, and the
/// Jacobian `[∂q̇⁺/∂q | ∂q̇⁺/∂q̇⁻]` (`n × 2n` row-major; `∂q̇⁺/∂q̇⁻ = I − X S⁻¹ A`). Returns the
/// smallest and largest pivot of `S`'s factorisation (a caller rejects near-singular sets).
#[allow(clippy::too_many_arguments)]
pub(crate) fn impact_in_duals<const W: usize>(
    n: usize,
    m: usize,
    mm: &Mat8<Dual<W>>,
    arows: &Mat8<Dual<W>>,
    qd: &[f64],
    qd_post: &mut [f64],
    lam_out: &mut [f64],
    mut jac: Option<&mut [f64]>,
) -> Result<(f64, f64), SoaError> {
    let zero = Dual::<W>::constant(0.0);
    // X = 𝓜⁻¹ Aᵀ (column i of X in xt[i])
    let mut xt = *arows;
    for i in 0..m {
        ldl_solve(mm, n, &mut xt[i][..n]);
    }
    // S = A X (m × m, lower triangle), y = A q̇⁻
    let mut s = [[zero; MAX_DOF]; MAX_DOF];
    let mut lam = [zero; MAX_DOF];
    for i in 0..m {
        for j in 0..=i {
            let mut acc = zero;
            for k in 0..n {
                acc = acc + arows[i][k] * xt[j][k];
            }
            s[i][j] = acc;
        }
        let mut y = zero;
        for k in 0..n {
            y = y + arows[i][k] * Dual::constant(qd[k]);
        }
        lam[i] = y;
    }
    let pivots = ldl(&mut s, m).ok_or(SoaError::SingularConstraint {
        what: "A 𝓜⁻¹ Aᵀ (impact)",
    })?;
    // Λ = S⁻¹ y, q̇⁺ = q̇⁻ − X Λ
    ldl_solve(&s, m, &mut lam[..m]);
    for i in 0..m {
        lam_out[i] = lam[i].v;
    }
    let w2 = 2 * n;
    for k in 0..n {
        let mut v = Dual::constant(qd[k]);
        for i in 0..m {
            v = v - xt[i][k] * lam[i];
        }
        qd_post[k] = v.v;
        if let Some(j) = jac.as_deref_mut() {
            j[k * w2..k * w2 + n].copy_from_slice(&v.d[..n]);
        }
    }
    let Some(jac) = jac else {
        // the values only (W = 0: the same value arithmetic as any W)
        return Ok(pivots);
    };

    // ∂q̇⁺/∂q̇⁻ = I − X S⁻¹ A on the values
    let mut sv = [[0.0; MAX_DOF]; MAX_DOF];
    for i in 0..m {
        for j in 0..=i {
            sv[i][j] = s[i][j].v;
        }
    }
    let mut z = [0.0; MAX_DOF];
    for c in 0..n {
        for i in 0..m {
            z[i] = arows[i][c].v;
        }
        ldl_solve(&sv, m, &mut z[..m]);
        for k in 0..n {
            let mut v = if k == c { 1.0 } else { 0.0 };
            for i in 0..m {
                v -= xt[i][k].v * z[i];
            }
            jac[k * w2 + n + c] = v;
        }
    }
    Ok(pivots)
}

/// Mass matrix 𝓜 (both triangles) by the composite-rigid-body steps of the kernel
/// (crate::crba), in the same order: for `f64` it is the kernel's 𝓜 bit for bit.
pub(crate) fn mass_matrix<T: Scalar>(chain: &Chain, kin: &Kin<T>, mass: &mut Mat8<T>) {
    let n = chain.dof();
    let zero = T::cst(0.0);
    let mut comp = [[zero; 6]; MAX_DOF];
    let mut carry = [zero; 6];
    for k in (0..n).rev() {
        let m = T::cst(chain.links[k].mass);
        let kk = [
            T::cst(chain.j_joint[k]) + carry[0],
            carry[1] - m * kin.cz[k],
            carry[2] + m * kin.cy[k],
            m + carry[3],
            carry[4],
            m + carry[5],
        ];
        comp[k] = kk;
        carry = spatial::congruence(&kk, kin.dy[k], kin.dz[k]);
    }
    let h_dot = |k: usize, f: &[T; 3]| {
        if chain.prismatic[k] {
            kin.hy[k] * f[1] + kin.hz[k] * f[2]
        } else {
            f[0]
        }
    };
    for k in 0..n {
        let x = &comp[k];
        let (hy, hz) = (kin.hy[k], kin.hz[k]);
        let mut f = if chain.prismatic[k] {
            [
                x[1] * hy + x[2] * hz,
                x[3] * hy + x[4] * hz,
                x[4] * hy + x[5] * hz,
            ]
        } else {
            [x[0], x[1], x[2]]
        };
        mass[k][k] = h_dot(k, &f);
        for j in (0..k).rev() {
            f = spatial::force_transport(&f, kin.dy[j + 1], kin.dz[j + 1]);
            let v = h_dot(j, &f);
            mass[j][k] = v;
            mass[k][j] = v;
        }
    }
}

/// Impulsive constraint rows `A` (`m × n` in the leading rows): the linear Jacobian of the
/// contact point (the tip moved by the world `offset`)
/// (`[−(t − p_k)_z, (t − p_k)_y]` for a revolute joint, `h_k` for a prismatic one; seed
/// eq. 2.24) if `tip`, then `e_kᵀ` for each locked `k`.
pub(crate) fn constraint_rows<T: Scalar>(
    chain: &Chain,
    kin: &Kin<T>,
    tip: bool,
    locked: &[usize],
    offset: [f64; 2],
) -> Mat8<T> {
    let n = chain.dof();
    let mut a = [[T::cst(0.0); MAX_DOF]; MAX_DOF];
    let mut row = 0;
    if tip {
        let (p, t) = positions(n, kin);
        // the contact point: the tip, or the tip moved by a world offset (a round foot's
        // lowest point below its arc centre); no arithmetic at all for a zero offset
        let t = if offset == [0.0, 0.0] {
            t
        } else {
            [t[0] + T::cst(offset[0]), t[1] + T::cst(offset[1])]
        };
        for k in 0..n {
            if chain.prismatic[k] {
                a[0][k] = kin.hy[k];
                a[1][k] = kin.hz[k];
            } else {
                a[0][k] = -(t[1] - p[k][1]);
                a[1][k] = t[0] - p[k][0];
            }
        }
        row = 2;
    }
    for (i, &k) in locked.iter().enumerate() {
        a[row + i][k] = T::cst(1.0);
    }
    a
}

/// Scratch bytes for faer's small Cholesky factorisations and solves (n ≤ MAX_DOF).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub const FAER_SCRATCH: usize = 1024;

/// `q̇⁺ = q̇⁻ − 𝓜⁻¹Aᵀ(A𝓜⁻¹Aᵀ)⁻¹A q̇⁻` by the kernel's operations in the kernel's order (faer
/// `LLᵀ` of 𝓜 and of `A𝓜⁻¹Aᵀ`, crate::impact), on stack storage: the same bits as
/// [`crate::tip_impact`] / [`crate::joint_lock_impact`] and the same singularity test.
pub(crate) fn impact_value(
    n: usize,
    m: usize,
    mass: &Mat8<f64>,
    arows: &Mat8<f64>,
    qd: &[f64],
    qd_post: &mut [f64],
) -> Result<(), SoaError> {
    let mut buf = [MaybeUninit::<u8>::uninit(); FAER_SCRATCH];
    let stack = MemStack::new(&mut buf);
    // 𝓜 = L Lᵀ (column-major n × n)
    let mut chol = [0.0; MAX_DOF * MAX_DOF];
    for j in 0..n {
        for i in 0..n {
            chol[i + j * n] = mass[i][j];
        }
    }
    let mut lm = MatMut::from_column_major_slice_mut(&mut chol[..n * n], n, n);
    llt::factor::cholesky_in_place(
        lm.as_mut(),
        Default::default(),
        Par::Seq,
        stack,
        Default::default(),
    )
    .map_err(|_| SoaError::MassMatrixNotPositiveDefinite)?;
    // X = 𝓜⁻¹ Aᵀ (column-major n × m)
    let mut x = [0.0; MAX_DOF * MAX_DOF];
    for i in 0..m {
        for k in 0..n {
            x[k + i * n] = arows[i][k];
        }
    }
    llt::solve::solve_in_place_with_conj(
        lm.as_ref(),
        Conj::No,
        MatMut::from_column_major_slice_mut(&mut x[..n * m], n, m),
        Par::Seq,
        stack,
    );
    // S = A X (column-major m × m), y = A q̇⁻
    let mut sm = [0.0; MAX_DOF * MAX_DOF];
    let mut y = [0.0; MAX_DOF];
    for i in 0..m {
        for j in 0..m {
            let mut s = 0.0;
            for k in 0..n {
                s += arows[i][k] * x[k + j * n];
            }
            sm[i + j * m] = s;
        }
        let mut v = 0.0;
        for k in 0..n {
            v += arows[i][k] * qd[k];
        }
        y[i] = v;
    }
    let singular = || SoaError::SingularConstraint {
        what: "A 𝓜⁻¹ Aᵀ (impact)",
    };
    let mut ls = MatMut::from_column_major_slice_mut(&mut sm[..m * m], m, m);
    llt::factor::cholesky_in_place(
        ls.as_mut(),
        Default::default(),
        Par::Seq,
        stack,
        Default::default(),
    )
    .map_err(|_| singular())?;
    // the kernel's rejection of numerically rank-deficient constraint sets
    let (mut dmin, mut dmax) = (f64::INFINITY, 0.0f64);
    for i in 0..m {
        let d = ls[(i, i)].abs();
        dmin = dmin.min(d);
        dmax = dmax.max(d);
    }
    if dmin.is_nan() || dmin <= 1e-7 * dmax {
        return Err(singular());
    }
    llt::solve::solve_in_place_with_conj(
        ls.as_ref(),
        Conj::No,
        MatMut::from_column_major_slice_mut(&mut y[..m], m, 1),
        Par::Seq,
        stack,
    );
    for k in 0..n {
        let mut s = 0.0;
        for (i, l) in y[..m].iter().enumerate() {
            s += x[k + i * n] * l;
        }
        qd_post[k] = qd[k] - s;
    }
    Ok(())
}

/// Plastic impact at a contact point offset from the tip by a fixed **world** vector `offset`
/// (a round foot of radius `r` touching the slope at `offset = [0, −r]` below its arc centre,
/// the tip): the contact point's velocity (as a point of the last link) and the rates of the
/// joints in `locked` become zero, `q̇⁺ = q̇⁻ − 𝓜⁻¹Aᵀ(A𝓜⁻¹Aᵀ)⁻¹A q̇⁻` with `A` the contact
/// point's linear Jacobian and `e_kᵀ` rows (the map of [`crate::tip_impact`], equal to it bit for
/// bit at `offset = [0, 0]`). Also returns the impulse on the chain along the first two
/// joints `[(𝓜Δq̇)₀, (𝓜Δq̇)₁]` — with a floating base (prismatic `y`, `z` first), the
/// ground's impulse on the contact. Arguments, layout and errors as [`tip_impact_derivatives`];
/// `jac = None` skips the Jacobian.
pub fn contact_impact(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    offset: [f64; 2],
    locked: &[usize],
    qd_post: &mut [f64],
    jac: Option<&mut [f64]>,
) -> Result<[f64; 2], SoaError> {
    let n = chain.dof();
    check_dof(n)?;
    // the value comes with the Jacobian (one dual pass of width n; small next to a stride)
    let mut scratch = [0.0; 2 * MAX_DOF * MAX_DOF];
    let j = match jac {
        Some(j) => j,
        None => &mut scratch[..2 * n * n],
    };
    impact_derivatives(chain, q, qd, true, offset, locked, qd_post, j)?;
    let k64 = kin::<f64>(chain, q, None);
    let mut mass = [[0.0; MAX_DOF]; MAX_DOF];
    mass_matrix(chain, &k64, &mut mass);
    let mut imp = [0.0; 2];
    for (i, v) in imp.iter_mut().enumerate().take(n.min(2)) {
        for k in 0..n {
            *v += mass[i][k] * (qd_post[k] - qd[k]);
        }
    }
    Ok(imp)
}
