//! Batched inverse dynamics: the RNEA of [`crate::rnea()`] over `(lanes × n)` matrices,
//! bit-for-bit equal per lane to the scalar [`crate::rnea::rnea`].

use faer::Mat;

use crate::batch::{batch_kin_pass, check_batch, BatchWorkspace};
use crate::chain::Chain;
use crate::error::{check_len, SoaError};
use crate::rnea::{lanes_rnea_back, lanes_rnea_fwd, rnea_recursion, RneaLanes};
use crate::spatial;

/// Batched inverse dynamics `τ = 𝓜 q̈ + C + Jᵀ F_t` for every lane.
///
/// - `q`, `qd`, `qdd`: `(lanes × n)`; `tau`: output `(lanes × n)`;
/// - `f_tip`: optional `(lanes × 3)` tip force on the environment (see [`crate::rnea()`]).
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
        start_force(bw, f_tip, l0, bl);
        let mut block = Block {
            bw: &mut *bw,
            qdd,
            tau: &mut *tau,
            base_acc: chain.base_acc,
            l0,
            bl,
        };
        rnea_recursion(chain, &mut block);
        l0 += bl;
    }
    Ok(())
}

/// The force carry's base value `Φ_{t,n}ᵀ F_t` (or 0) for lanes `l0..l0 + bl`.
fn start_force(bw: &mut BatchWorkspace, f_tip: Option<&Mat<f64>>, l0: usize, bl: usize) {
    let [f0, f1, f2] = bw.carry_a.all_mut::<3>();
    match f_tip {
        Some(ft) => {
            let ty = bw.tip.col(0);
            let tz = bw.tip.col(1);
            for l in 0..bl {
                let i = l0 + l;
                let f = [ft[(i, 0)], ft[(i, 1)], ft[(i, 2)]];
                [f0[l], f1[l], f2[l]] = spatial::force_transport(&f, ty[l], tz[l]);
            }
        }
        None => {
            f0[..bl].fill(0.0);
            f1[..bl].fill(0.0);
            f2[..bl].fill(0.0);
        }
    }
}

/// A block of lanes `l0..l0 + bl` in the columns of a [`BatchWorkspace`]: `A_k` in the columns
/// `a0..a2`, the force carry in `carry_a`.
struct Block<'a, 'm> {
    bw: &'a mut BatchWorkspace,
    qdd: &'m Mat<f64>,
    tau: &'m mut Mat<f64>,
    base_acc: [f64; 3],
    l0: usize,
    bl: usize,
}

impl RneaLanes for Block<'_, '_> {
    #[inline(always)]
    fn fwd<const PRI: bool>(&mut self, k: usize) {
        let (bw, l0, bl) = (&mut *self.bw, self.l0, self.bl);
        let qk = &self.qdd.col_as_slice(k)[l0..l0 + bl];
        let link = [&bw.ay, &bw.az, &bw.hy, &bw.hz, &bw.dy, &bw.dz].map(|c| &c.col(k)[..bl]);
        let [ay, az, hy, hz, dy, dz] = link;
        let [a0, a1, a2] = [(&mut bw.a0, 0), (&mut bw.a1, 1), (&mut bw.a2, 2)].map(|(col, i)| {
            // column k starts as a copy of the previous acceleration (or the base's)
            if k == 0 {
                col.col_mut(0)[..bl].fill(self.base_acc[i]);
            } else {
                let (p, c) = col.prev_cur(k);
                c[..bl].copy_from_slice(&p[..bl]);
            }
            &mut col.col_mut(k)[..bl]
        });
        lanes_rnea_fwd::<f64, PRI>([qk, ay, az, hy, hz, dy, dz], a0, a1, a2);
    }

    #[inline(always)]
    fn back<const PRI: bool>(&mut self, k: usize, j: f64, m: f64) {
        let (bw, l0, bl) = (&mut *self.bw, self.l0, self.bl);
        let out = &mut self.tau.col_as_slice_mut(k)[l0..l0 + bl];
        let link = [
            &bw.a0, &bw.a1, &bw.a2, &bw.cy, &bw.cz, &bw.by, &bw.bz, &bw.dy, &bw.dz, &bw.hy, &bw.hz,
        ]
        .map(|c| &c.col(k)[..bl]);
        let [f0, f1, f2] = bw.carry_a.all_mut::<3>();
        lanes_rnea_back::<f64, PRI>(j, m, link, out, f0, f1, f2, |_, _| {});
    }
}
