//! Batched O(n) forward dynamics: the articulated-body recursion of [`crate::aba`] over
//! `(lanes × n)` matrices, bit-for-bit equal per lane to the scalar [`crate::aba::aba`].

use faer::reborrow::ReborrowMut;
use faer::{Mat, MatMut, MatRef};

use crate::aba::{aba_recursion, lanes_back, lanes_fwd, AbaLanes};
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
                start_carries(chain, bw, f_tip, l0, bl);
                let mut block = Block {
                    bw: &mut *bw,
                    tau,
                    qdd: qdd.rb_mut(),
                    l0,
                    bl,
                };
                aba_recursion(chain, locked, &mut block);
                l0 += bl;
            }
        },
    );
    Ok(())
}

/// Base values of the carries for lanes `l0..l0 + bl`: `P⁺ = 0`, `z⁺ = Φ_{t,n}ᵀ F_t` (or 0),
/// `A = a_b`.
#[inline(always)]
fn start_carries(
    chain: &Chain,
    bw: &mut BatchWorkspace,
    f_tip: Option<MatRef<'_, f64>>,
    l0: usize,
    bl: usize,
) {
    for col in bw.carry_p.all_mut::<6>() {
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
    let ab = chain.base_acc;
    let [a0, a1, a2] = bw.carry_a.all_mut::<3>();
    a0[..bl].fill(ab[0]);
    a1[..bl].fill(ab[1]);
    a2[..bl].fill(ab[2]);
}

/// A block of lanes `l0..l0 + bl` in the columns of a [`BatchWorkspace`].
struct Block<'a, 'm> {
    bw: &'a mut BatchWorkspace,
    tau: Option<MatRef<'m, f64>>,
    qdd: MatMut<'m, f64>,
    l0: usize,
    bl: usize,
}

impl AbaLanes for Block<'_, '_> {
    #[inline(always)]
    fn back<const K: u8>(&mut self, k: usize, j: f64, m: f64) {
        let (bw, l0, bl) = (&mut *self.bw, self.l0, self.bl);
        let tk = match self.tau {
            Some(t) => &col(t, k)[l0..l0 + bl],
            None => &bw.zeros[..bl],
        };
        let link = [
            &bw.cy, &bw.cz, &bw.by, &bw.bz, &bw.ay, &bw.az, &bw.hy, &bw.hz, &bw.dy, &bw.dz,
        ]
        .map(|c| &c.col(k)[..bl]);
        let g0 = &mut bw.g0.col_mut(k)[..bl];
        let g1 = &mut bw.g1.col_mut(k)[..bl];
        let g2 = &mut bw.g2.col_mut(k)[..bl];
        let nu = &mut bw.nu.col_mut(k)[..bl];
        let [p0, p1, p2, p3, p4, p5] = bw.carry_p.all_mut::<6>();
        let [z0, z1, z2] = bw.carry_z.all_mut::<3>();
        lanes_back::<K>(
            j,
            m,
            tk,
            link,
            g0,
            g1,
            g2,
            nu,
            p0,
            p1,
            p2,
            p3,
            p4,
            p5,
            z0,
            z1,
            z2,
            |_, _| {},
        );
    }

    #[inline(always)]
    fn fwd<const K: u8>(&mut self, k: usize) {
        let (bw, l0, bl) = (&mut *self.bw, self.l0, self.bl);
        let out = match self.qdd.rb_mut().col_mut(k).try_as_col_major_mut() {
            Some(c) => &mut c.as_slice_mut()[l0..l0 + bl],
            // unreachable: `batch_aba_view` checked the columns
            None => return,
        };
        let gain = [&bw.g0, &bw.g1, &bw.g2, &bw.nu].map(|c| &c.col(k)[..bl]);
        let link = [&bw.ay, &bw.az, &bw.hy, &bw.hz, &bw.dy, &bw.dz].map(|c| &c.col(k)[..bl]);
        let [a0, a1, a2] = bw.carry_a.all_mut::<3>();
        lanes_fwd::<K>(gain, link, out, a0, a1, a2);
    }
}
