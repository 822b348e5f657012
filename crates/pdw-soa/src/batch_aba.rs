//! Batched O(n) forward dynamics: the articulated-body recursion of [`crate::aba`] over
//! `(lanes × n)` matrices, bit-for-bit equal per lane to the scalar [`crate::aba::aba`].

use faer::reborrow::ReborrowMut;
use faer::{Mat, MatMut, MatRef};

use crate::batch::{batch_kin_pass, check_batch, check_view, col, BatchWorkspace};
use crate::chain::Chain;
use crate::error::{check_len, SoaError};
use crate::spatial;

/// Batched forward dynamics `q̈ = 𝓜⁻¹ (τ − C − Jᵀ F_t)` for every lane.
///
/// - `q`, `qd`, `tau`: `(lanes × n)`; `qdd`: output `(lanes × n)`;
/// - `f_tip`: optional `(lanes × 3)` spatial force `[τ, f_y, f_z]` each tip exerts on the
///   environment (convention of [`crate::rnea`]).
pub fn batch_aba(
    chain: &Chain,
    bw: &mut BatchWorkspace,
    q: &Mat<f64>,
    qd: &Mat<f64>,
    tau: &Mat<f64>,
    f_tip: Option<&Mat<f64>>,
    qdd: &mut Mat<f64>,
) -> Result<(), SoaError> {
    let n = chain.dof();
    let lanes = bw.lanes;
    check_len("batch workspace dof", n, bw.n)?;
    check_batch("q", q, lanes, n)?;
    check_batch("qd", qd, lanes, n)?;
    check_batch("tau", tau, lanes, n)?;
    check_batch("qdd", qdd, lanes, n)?;
    if let Some(ft) = f_tip {
        check_batch("f_tip", ft, lanes, 3)?;
    }
    batch_aba_view(
        chain,
        bw,
        q.as_ref(),
        qd.as_ref(),
        Some(tau.as_ref()),
        f_tip.map(|f| f.as_ref()),
        None,
        qdd.as_mut(),
    )
}

/// Batched forward dynamics on matrix views, with optional locked joints: the pseudo joints of
/// seed §3.4, welded in the articulated-body recursion (`P⁺ = P`, `z⁺ = z + P a`, `q̈ = 0`), as
/// the scalar [`crate::pseudo_joint_dynamics`] does.
///
/// - `q`, `qd`: `(lanes × n)` views with contiguous columns (e.g. column ranges of a state
///   matrix `(lanes × 2n)`); any lane count (processed in blocks of the workspace's block size);
/// - `tau`: `(lanes × n)` applied torques or `None` for zero (a passive walker);
/// - `f_tip`: optional `(lanes × 3)` tip force on the environment;
/// - `locked`: mask of length `n` (the same joints locked in every lane) or `None`;
/// - `qdd`: output `(lanes × n)`, exactly `0.0` at locked joints.
///
/// Each lane equals the one-lane call bit for bit, whatever the lane count or block.
#[allow(clippy::too_many_arguments)]
pub fn batch_aba_view(
    chain: &Chain,
    bw: &mut BatchWorkspace,
    q: MatRef<'_, f64>,
    qd: MatRef<'_, f64>,
    tau: Option<MatRef<'_, f64>>,
    f_tip: Option<MatRef<'_, f64>>,
    locked: Option<&[bool]>,
    mut qdd: MatMut<'_, f64>,
) -> Result<(), SoaError> {
    let n = chain.dof();
    let lanes = q.nrows();
    check_len("batch workspace dof", n, bw.n)?;
    check_view("q", q, lanes, n)?;
    check_view("qd", qd, lanes, n)?;
    if let Some(t) = tau {
        check_view("tau", t, lanes, n)?;
    }
    if let Some(ft) = f_tip {
        check_view("f_tip", ft, lanes, 3)?;
    }
    check_view("qdd", qdd.as_ref(), lanes, n)?;
    if let Some(m) = locked {
        check_len("locked", n, m.len())?;
    }
    // One dispatch per call: the passes and their lane loops are inlined into the copy compiled
    // for the selected instruction set (pdw-simd; every copy gives the same bits).
    pdw_simd::dispatch(
        #[inline(always)]
        || {
            let mut l0 = 0;
            while l0 < lanes {
                let bl = bw.block.min(lanes - l0);
                batch_kin_pass(chain, bw, q, qd, l0, bl);
                backward(chain, bw, tau, f_tip, locked, l0, bl);
                forward(chain, bw, locked, qdd.rb_mut(), l0, bl);
                l0 += bl;
            }
        },
    );
    Ok(())
}

#[inline(always)]
fn backward(
    chain: &Chain,
    bw: &mut BatchWorkspace,
    tau: Option<MatRef<'_, f64>>,
    f_tip: Option<MatRef<'_, f64>>,
    locked: Option<&[bool]>,
    l0: usize,
    bl: usize,
) {
    let n = chain.dof();
    {
        let cp = bw.carry_p.all_mut::<6>();
        for col in cp {
            col[..bl].fill(0.0);
        }
        let [z0, z1, z2] = bw.carry_z.all_mut::<3>();
        match f_tip {
            Some(ft) => {
                let (f0, f1, f2) = (
                    &col(ft, 0)[l0..l0 + bl],
                    &col(ft, 1)[l0..l0 + bl],
                    &col(ft, 2)[l0..l0 + bl],
                );
                let ty = &bw.tip.col(0)[..bl];
                let tz = &bw.tip.col(1)[..bl];
                for l in 0..bl {
                    let z = spatial::force_transport(&[f0[l], f1[l], f2[l]], ty[l], tz[l]);
                    z0[l] = z[0];
                    z1[l] = z[1];
                    z2[l] = z[2];
                }
            }
            None => {
                z0[..bl].fill(0.0);
                z1[..bl].fill(0.0);
                z2[..bl].fill(0.0);
            }
        }
    }
    for k in (0..n).rev() {
        let link = &chain.links[k];
        let (j, m) = (chain.j_joint[k], link.mass);
        let tk = match tau {
            Some(t) => &col(t, k)[l0..l0 + bl],
            None => &bw.zeros[..bl],
        };
        let is_locked = locked.is_some_and(|m| m[k]);
        let cy = &bw.cy.col(k)[..bl];
        let cz = &bw.cz.col(k)[..bl];
        let by = &bw.by.col(k)[..bl];
        let bz = &bw.bz.col(k)[..bl];
        let ay = &bw.ay.col(k)[..bl];
        let az = &bw.az.col(k)[..bl];
        let dy = &bw.dy.col(k)[..bl];
        let dz = &bw.dz.col(k)[..bl];
        let g0 = &mut bw.g0.col_mut(k)[..bl];
        let g1 = &mut bw.g1.col_mut(k)[..bl];
        let g2 = &mut bw.g2.col_mut(k)[..bl];
        let nu = &mut bw.nu.col_mut(k)[..bl];
        let [p0, p1, p2, p3, p4, p5] = bw.carry_p.all_mut::<6>();
        let (p0, p1, p2, p3, p4, p5) = (
            &mut p0[..bl],
            &mut p1[..bl],
            &mut p2[..bl],
            &mut p3[..bl],
            &mut p4[..bl],
            &mut p5[..bl],
        );
        let [z0, z1, z2] = bw.carry_z.all_mut::<3>();
        let (z0, z1, z2) = (&mut z0[..bl], &mut z1[..bl], &mut z2[..bl]);
        if is_locked {
            lanes_back_locked(
                j, m, cy, cz, by, bz, ay, az, dy, dz, p0, p1, p2, p3, p4, p5, z0, z1, z2,
            );
        } else if chain.prismatic[k] {
            let hy = &bw.hy.col(k)[..bl];
            let hz = &bw.hz.col(k)[..bl];
            lanes_back_pri(
                j, m, tk, cy, cz, by, bz, ay, az, hy, hz, dy, dz, g0, g1, g2, nu, p0, p1, p2, p3,
                p4, p5, z0, z1, z2,
            );
        } else {
            lanes_back_rev(
                j, m, tk, cy, cz, by, bz, ay, az, dy, dz, g0, g1, g2, nu, p0, p1, p2, p3, p4, p5,
                z0, z1, z2,
            );
        }
    }
}

// The lane loops live in their own functions so that every slice is a distinct `noalias`
// parameter (kept as alias scopes when inlined): the loop vectoriser then needs no runtime
// overlap checks between the ~25 streams. They are inlined into the per-instruction-set copies
// made by `pdw_simd::dispatch`.

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn lanes_back_rev(
    j: f64,
    m: f64,
    tk: &[f64],
    cy: &[f64],
    cz: &[f64],
    by: &[f64],
    bz: &[f64],
    ay: &[f64],
    az: &[f64],
    dy: &[f64],
    dz: &[f64],
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
) {
    let bl = tk.len();
    let (cy, cz, by, bz, ay, az, dy, dz) = (
        &cy[..bl],
        &cz[..bl],
        &by[..bl],
        &bz[..bl],
        &ay[..bl],
        &az[..bl],
        &dy[..bl],
        &dz[..bl],
    );
    let (g0, g1, g2, nu) = (&mut g0[..bl], &mut g1[..bl], &mut g2[..bl], &mut nu[..bl]);
    let (p0, p1, p2, p3, p4, p5) = (
        &mut p0[..bl],
        &mut p1[..bl],
        &mut p2[..bl],
        &mut p3[..bl],
        &mut p4[..bl],
        &mut p5[..bl],
    );
    let (z0, z1, z2) = (&mut z0[..bl], &mut z1[..bl], &mut z2[..bl]);
    for l in 0..bl {
        let cp = [p0[l], p1[l], p2[l], p3[l], p4[l], p5[l]];
        let czc = [z0[l], z1[l], z2[l]];
        let r = spatial::aba_back_rev(
            &cp, &czc, j, m, cy[l], cz[l], by[l], bz[l], ay[l], az[l], tk[l], dy[l], dz[l],
        );
        g0[l] = r.g[0];
        g1[l] = r.g[1];
        g2[l] = r.g[2];
        nu[l] = r.nu;
        p0[l] = r.cp[0];
        p1[l] = r.cp[1];
        p2[l] = r.cp[2];
        p3[l] = r.cp[3];
        p4[l] = r.cp[4];
        p5[l] = r.cp[5];
        z0[l] = r.cz[0];
        z1[l] = r.cz[1];
        z2[l] = r.cz[2];
    }
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn lanes_back_pri(
    j: f64,
    m: f64,
    tk: &[f64],
    cy: &[f64],
    cz: &[f64],
    by: &[f64],
    bz: &[f64],
    ay: &[f64],
    az: &[f64],
    hy: &[f64],
    hz: &[f64],
    dy: &[f64],
    dz: &[f64],
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
) {
    let bl = tk.len();
    let (cy, cz, by, bz, ay, az, dy, dz) = (
        &cy[..bl],
        &cz[..bl],
        &by[..bl],
        &bz[..bl],
        &ay[..bl],
        &az[..bl],
        &dy[..bl],
        &dz[..bl],
    );
    let (hy, hz) = (&hy[..bl], &hz[..bl]);
    let (g0, g1, g2, nu) = (&mut g0[..bl], &mut g1[..bl], &mut g2[..bl], &mut nu[..bl]);
    let (p0, p1, p2, p3, p4, p5) = (
        &mut p0[..bl],
        &mut p1[..bl],
        &mut p2[..bl],
        &mut p3[..bl],
        &mut p4[..bl],
        &mut p5[..bl],
    );
    let (z0, z1, z2) = (&mut z0[..bl], &mut z1[..bl], &mut z2[..bl]);
    for l in 0..bl {
        let cp = [p0[l], p1[l], p2[l], p3[l], p4[l], p5[l]];
        let czc = [z0[l], z1[l], z2[l]];
        let r = spatial::aba_back_pri(
            &cp, &czc, j, m, cy[l], cz[l], by[l], bz[l], ay[l], az[l], hy[l], hz[l], tk[l], dy[l],
            dz[l],
        );
        g0[l] = r.g[0];
        g1[l] = r.g[1];
        g2[l] = r.g[2];
        nu[l] = r.nu;
        p0[l] = r.cp[0];
        p1[l] = r.cp[1];
        p2[l] = r.cp[2];
        p3[l] = r.cp[3];
        p4[l] = r.cp[4];
        p5[l] = r.cp[5];
        z0[l] = r.cz[0];
        z1[l] = r.cz[1];
        z2[l] = r.cz[2];
    }
}

#[inline(always)]
fn forward(
    chain: &Chain,
    bw: &mut BatchWorkspace,
    locked: Option<&[bool]>,
    mut qdd: MatMut<'_, f64>,
    l0: usize,
    bl: usize,
) {
    let n = chain.dof();
    let ab = chain.base_acc;
    {
        let [a0, a1, a2] = bw.carry_a.all_mut::<3>();
        a0[..bl].fill(ab[0]);
        a1[..bl].fill(ab[1]);
        a2[..bl].fill(ab[2]);
    }
    for k in 0..n {
        let out = match qdd.rb_mut().col_mut(k).try_as_col_major_mut() {
            Some(c) => &mut c.as_slice_mut()[l0..l0 + bl],
            None => return,
        };
        let g0 = &bw.g0.col(k)[..bl];
        let g1 = &bw.g1.col(k)[..bl];
        let g2 = &bw.g2.col(k)[..bl];
        let nu = &bw.nu.col(k)[..bl];
        let ay = &bw.ay.col(k)[..bl];
        let az = &bw.az.col(k)[..bl];
        let dy = &bw.dy.col(k)[..bl];
        let dz = &bw.dz.col(k)[..bl];
        let [a0, a1, a2] = bw.carry_a.all_mut::<3>();
        let (a0, a1, a2) = (&mut a0[..bl], &mut a1[..bl], &mut a2[..bl]);
        if locked.is_some_and(|m| m[k]) {
            lanes_fwd_locked(ay, az, dy, dz, out, a0, a1, a2);
        } else if chain.prismatic[k] {
            let hy = &bw.hy.col(k)[..bl];
            let hz = &bw.hz.col(k)[..bl];
            lanes_fwd_pri(g0, g1, g2, nu, ay, az, hy, hz, dy, dz, out, a0, a1, a2);
        } else {
            lanes_fwd_rev(g1, g2, nu, ay, az, dy, dz, out, a0, a1, a2);
        }
    }
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn lanes_fwd_rev(
    g1: &[f64],
    g2: &[f64],
    nu: &[f64],
    ay: &[f64],
    az: &[f64],
    dy: &[f64],
    dz: &[f64],
    out: &mut [f64],
    a0: &mut [f64],
    a1: &mut [f64],
    a2: &mut [f64],
) {
    let bl = out.len();
    let (g1, g2, nu, ay, az, dy, dz) = (
        &g1[..bl],
        &g2[..bl],
        &nu[..bl],
        &ay[..bl],
        &az[..bl],
        &dy[..bl],
        &dz[..bl],
    );
    let (a0, a1, a2) = (&mut a0[..bl], &mut a1[..bl], &mut a2[..bl]);
    for l in 0..bl {
        let (qk, a) = spatial::aba_fwd_rev(
            &[a0[l], a1[l], a2[l]],
            g1[l],
            g2[l],
            nu[l],
            ay[l],
            az[l],
            dy[l],
            dz[l],
        );
        out[l] = qk;
        a0[l] = a[0];
        a1[l] = a[1];
        a2[l] = a[2];
    }
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn lanes_fwd_pri(
    g0: &[f64],
    g1: &[f64],
    g2: &[f64],
    nu: &[f64],
    ay: &[f64],
    az: &[f64],
    hy: &[f64],
    hz: &[f64],
    dy: &[f64],
    dz: &[f64],
    out: &mut [f64],
    a0: &mut [f64],
    a1: &mut [f64],
    a2: &mut [f64],
) {
    let bl = out.len();
    let (g0, g1, g2, nu, ay, az) = (
        &g0[..bl],
        &g1[..bl],
        &g2[..bl],
        &nu[..bl],
        &ay[..bl],
        &az[..bl],
    );
    let (hy, hz, dy, dz) = (&hy[..bl], &hz[..bl], &dy[..bl], &dz[..bl]);
    let (a0, a1, a2) = (&mut a0[..bl], &mut a1[..bl], &mut a2[..bl]);
    for l in 0..bl {
        let (qk, a) = spatial::aba_fwd_pri(
            &[a0[l], a1[l], a2[l]],
            &[g0[l], g1[l], g2[l]],
            nu[l],
            ay[l],
            az[l],
            hy[l],
            hz[l],
            dy[l],
            dz[l],
        );
        out[l] = qk;
        a0[l] = a[0];
        a1[l] = a[1];
        a2[l] = a[2];
    }
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn lanes_back_locked(
    j: f64,
    m: f64,
    cy: &[f64],
    cz: &[f64],
    by: &[f64],
    bz: &[f64],
    ay: &[f64],
    az: &[f64],
    dy: &[f64],
    dz: &[f64],
    p0: &mut [f64],
    p1: &mut [f64],
    p2: &mut [f64],
    p3: &mut [f64],
    p4: &mut [f64],
    p5: &mut [f64],
    z0: &mut [f64],
    z1: &mut [f64],
    z2: &mut [f64],
) {
    let bl = cy.len();
    let (cz, by, bz, ay, az, dy, dz) = (
        &cz[..bl],
        &by[..bl],
        &bz[..bl],
        &ay[..bl],
        &az[..bl],
        &dy[..bl],
        &dz[..bl],
    );
    let (p0, p1, p2, p3, p4, p5) = (
        &mut p0[..bl],
        &mut p1[..bl],
        &mut p2[..bl],
        &mut p3[..bl],
        &mut p4[..bl],
        &mut p5[..bl],
    );
    let (z0, z1, z2) = (&mut z0[..bl], &mut z1[..bl], &mut z2[..bl]);
    for l in 0..bl {
        let cp = [p0[l], p1[l], p2[l], p3[l], p4[l], p5[l]];
        let czc = [z0[l], z1[l], z2[l]];
        let r = spatial::aba_back_locked(
            &cp, &czc, j, m, cy[l], cz[l], by[l], bz[l], ay[l], az[l], dy[l], dz[l],
        );
        p0[l] = r.cp[0];
        p1[l] = r.cp[1];
        p2[l] = r.cp[2];
        p3[l] = r.cp[3];
        p4[l] = r.cp[4];
        p5[l] = r.cp[5];
        z0[l] = r.cz[0];
        z1[l] = r.cz[1];
        z2[l] = r.cz[2];
    }
}

/// Forward step across a locked joint: `A = Φ A_p + a`, `q̈ = 0` (as the scalar pseudo-joint
/// pass).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn lanes_fwd_locked(
    ay: &[f64],
    az: &[f64],
    dy: &[f64],
    dz: &[f64],
    out: &mut [f64],
    a0: &mut [f64],
    a1: &mut [f64],
    a2: &mut [f64],
) {
    let bl = out.len();
    let (ay, az, dy, dz) = (&ay[..bl], &az[..bl], &dy[..bl], &dz[..bl]);
    let (a0, a1, a2) = (&mut a0[..bl], &mut a1[..bl], &mut a2[..bl]);
    for l in 0..bl {
        let ab = spatial::motion_transport(&[a0[l], a1[l], a2[l]], dy[l], dz[l]);
        out[l] = 0.0;
        a0[l] = ab[0];
        a1[l] = ab[1] + ay[l];
        a2[l] = ab[2] + az[l];
    }
}
