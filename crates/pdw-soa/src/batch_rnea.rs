//! Batched inverse dynamics: the RNEA of [`crate::rnea`] over `(lanes × n)` matrices,
//! bit-for-bit equal per lane to the scalar [`crate::rnea::rnea`].

use faer::Mat;

use crate::batch::{batch_kin_pass, check_batch, BatchWorkspace};
use crate::chain::Chain;
use crate::error::{check_len, SoaError};
use crate::spatial;

/// Batched inverse dynamics `τ = 𝓜 q̈ + C + Jᵀ F_t` for every lane.
///
/// - `q`, `qd`, `qdd`: `(lanes × n)`; `tau`: output `(lanes × n)`;
/// - `f_tip`: optional `(lanes × 3)` tip force on the environment (see [`crate::rnea`]).
pub fn batch_rnea(
    chain: &Chain,
    bw: &mut BatchWorkspace,
    q: &Mat<f64>,
    qd: &Mat<f64>,
    qdd: &Mat<f64>,
    f_tip: Option<&Mat<f64>>,
    tau: &mut Mat<f64>,
) -> Result<(), SoaError> {
    let n = chain.dof();
    let lanes = bw.lanes;
    check_len("batch workspace dof", n, bw.n)?;
    check_batch("q", q, lanes, n)?;
    check_batch("qd", qd, lanes, n)?;
    check_batch("qdd", qdd, lanes, n)?;
    check_batch("tau", tau, lanes, n)?;
    if let Some(ft) = f_tip {
        check_batch("f_tip", ft, lanes, 3)?;
    }
    let mut l0 = 0;
    while l0 < lanes {
        let bl = bw.block.min(lanes - l0);
        batch_kin_pass(chain, bw, q.as_ref(), qd.as_ref(), l0, bl);
        // forward accelerations
        let ab = chain.base_acc;
        for k in 0..n {
            let qk = &qdd.col_as_slice(k)[l0..l0 + bl];
            let ay = &bw.ay.col(k)[..bl];
            let az = &bw.az.col(k)[..bl];
            let dy = &bw.dy.col(k)[..bl];
            let dz = &bw.dz.col(k)[..bl];
            let hy = &bw.hy.col(k)[..bl];
            let hz = &bw.hz.col(k)[..bl];
            let prism = chain.prismatic[k];
            for (col, base) in [
                (&mut bw.a0, ab[0]),
                (&mut bw.a1, ab[1]),
                (&mut bw.a2, ab[2]),
            ] {
                // column k starts as Φ-independent copy of the previous acceleration
                if k == 0 {
                    col.col_mut(0)[..bl].fill(base);
                } else {
                    let (p, c) = col.prev_cur(k);
                    c[..bl].copy_from_slice(&p[..bl]);
                }
            }
            let a0 = &mut bw.a0.col_mut(k)[..bl];
            let a1 = &mut bw.a1.col_mut(k)[..bl];
            let a2 = &mut bw.a2.col_mut(k)[..bl];
            for l in 0..bl {
                let ap = [a0[l], a1[l], a2[l]];
                let a = if prism {
                    spatial::rnea_fwd_pri(&ap, qk[l], ay[l], az[l], hy[l], hz[l], dy[l], dz[l])
                } else {
                    spatial::rnea_fwd_rev(&ap, qk[l], ay[l], az[l], dy[l], dz[l])
                };
                a0[l] = a[0];
                a1[l] = a[1];
                a2[l] = a[2];
            }
        }
        // backward forces
        {
            let [f0, f1, f2] = bw.carry_a.all_mut::<3>();
            match f_tip {
                Some(ft) => {
                    let ty = bw.tip.col(0);
                    let tz = bw.tip.col(1);
                    for l in 0..bl {
                        let i = l0 + l;
                        let f = [ft[(i, 0)], ft[(i, 1)], ft[(i, 2)]];
                        let c = spatial::force_transport(&f, ty[l], tz[l]);
                        f0[l] = c[0];
                        f1[l] = c[1];
                        f2[l] = c[2];
                    }
                }
                None => {
                    f0[..bl].fill(0.0);
                    f1[..bl].fill(0.0);
                    f2[..bl].fill(0.0);
                }
            }
        }
        for k in (0..n).rev() {
            let link = &chain.links[k];
            let (j, m) = (chain.j_joint[k], link.mass);
            let out = &mut tau.col_as_slice_mut(k)[l0..l0 + bl];
            let a0 = &bw.a0.col(k)[..bl];
            let a1 = &bw.a1.col(k)[..bl];
            let a2 = &bw.a2.col(k)[..bl];
            let cy = &bw.cy.col(k)[..bl];
            let cz = &bw.cz.col(k)[..bl];
            let by = &bw.by.col(k)[..bl];
            let bz = &bw.bz.col(k)[..bl];
            let dy = &bw.dy.col(k)[..bl];
            let dz = &bw.dz.col(k)[..bl];
            let hy = &bw.hy.col(k)[..bl];
            let hz = &bw.hz.col(k)[..bl];
            let prism = chain.prismatic[k];
            let [f0, f1, f2] = bw.carry_a.all_mut::<3>();
            let (f0, f1, f2) = (&mut f0[..bl], &mut f1[..bl], &mut f2[..bl]);
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
                out[l] = if prism {
                    hy[l] * f[1] + hz[l] * f[2]
                } else {
                    f[0]
                };
                let c = spatial::force_transport(&f, dy[l], dz[l]);
                f0[l] = c[0];
                f1[l] = c[1];
                f2[l] = c[2];
            }
        }
        l0 += bl;
    }
    Ok(())
}
