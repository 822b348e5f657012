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
                // the recursion over 8 lanes at a time, its carries in registers; the last
                // lanes of the block one at a time (each lane the same arithmetic)
                let full = bl - bl % WIDTH;
                for b0 in (0..full).step_by(WIDTH) {
                    chunk::<WIDTH>(chain, bw, tau, f_tip, locked, qdd.rb_mut(), l0, b0);
                }
                for b0 in full..bl {
                    chunk::<1>(chain, bw, tau, f_tip, locked, qdd.rb_mut(), l0, b0);
                }
                l0 += bl;
            }
        },
    );
    Ok(())
}

/// Lanes of one [`Chunk`] of the full width: 8 doubles, one AVX-512 register per quantity.
const WIDTH: usize = 8;

/// The articulated-body recursion ([`aba_recursion`]) for the `W` lanes `l0 + b0 ..` of a block
/// whose pass 1 is in `bw` (at rows `b0..b0 + W`). The carries start at their base values
/// (`P⁺ = 0`, `z⁺ = Φ_{t,n}ᵀ F_t` or 0, `A = a_b`) and stay in the chunk's arrays (registers
/// once inlined) from link to link instead of going through the workspace's columns.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn chunk<const W: usize>(
    chain: &Chain,
    bw: &mut BatchWorkspace,
    tau: Option<MatRef<'_, f64>>,
    f_tip: Option<MatRef<'_, f64>>,
    locked: Option<&[bool]>,
    qdd: MatMut<'_, f64>,
    l0: usize,
    b0: usize,
) {
    let a = l0 + b0;
    let mut cz = [[0.0; W]; 3];
    if let Some(ft) = f_tip {
        let (ty, tz) = (&bw.tip.col(0)[b0..b0 + W], &bw.tip.col(1)[b0..b0 + W]);
        let (f0, f1, f2) = (
            &col(ft, 0)[a..a + W],
            &col(ft, 1)[a..a + W],
            &col(ft, 2)[a..a + W],
        );
        for l in 0..W {
            let z = spatial::force_transport(&[f0[l], f1[l], f2[l]], ty[l], tz[l]);
            cz[0][l] = z[0];
            cz[1][l] = z[1];
            cz[2][l] = z[2];
        }
    }
    let ab = chain.base_acc;
    let mut c = Chunk::<W> {
        bw,
        tau,
        qdd,
        a,
        b0,
        cp: [[0.0; W]; 6],
        cz,
        ca: [[ab[0]; W], [ab[1]; W], [ab[2]; W]],
    };
    aba_recursion(chain, locked, &mut c);
}

/// `W` lanes of a block: the link quantities and gains in the columns of a [`BatchWorkspace`]
/// (rows `b0..b0 + W`), the carries `(P⁺, z⁺)` and `A` in arrays.
struct Chunk<'a, 'm, const W: usize> {
    bw: &'a mut BatchWorkspace,
    tau: Option<MatRef<'m, f64>>,
    qdd: MatMut<'m, f64>,
    /// first lane of the chunk in the call's matrices
    a: usize,
    /// first row of the chunk in the workspace's columns
    b0: usize,
    cp: [[f64; W]; 6],
    cz: [[f64; W]; 3],
    ca: [[f64; W]; 3],
}

impl<const W: usize> AbaLanes for Chunk<'_, '_, W> {
    #[inline(always)]
    fn back<const K: u8>(&mut self, k: usize, j: f64, m: f64) {
        let (bw, a, r) = (&mut *self.bw, self.a, self.b0..self.b0 + W);
        let tk = match self.tau {
            Some(t) => &col(t, k)[a..a + W],
            None => &bw.zeros[..W],
        };
        let link = [
            &bw.cy.col(k)[r.clone()],
            &bw.cz.col(k)[r.clone()],
            &bw.by.col(k)[r.clone()],
            &bw.bz.col(k)[r.clone()],
            &bw.ay.col(k)[r.clone()],
            &bw.az.col(k)[r.clone()],
            &bw.hy.col(k)[r.clone()],
            &bw.hz.col(k)[r.clone()],
            &bw.dy.col(k)[r.clone()],
            &bw.dz.col(k)[r.clone()],
        ];
        let g0 = &mut bw.g0.col_mut(k)[r.clone()];
        let g1 = &mut bw.g1.col_mut(k)[r.clone()];
        let g2 = &mut bw.g2.col_mut(k)[r.clone()];
        let nu = &mut bw.nu.col_mut(k)[r];
        let [p0, p1, p2, p3, p4, p5] = &mut self.cp;
        let [z0, z1, z2] = &mut self.cz;
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
        let (bw, a, r) = (&*self.bw, self.a, self.b0..self.b0 + W);
        let out = match self.qdd.rb_mut().col_mut(k).try_as_col_major_mut() {
            Some(c) => &mut c.as_slice_mut()[a..a + W],
            // unreachable: `batch_aba_view` checked the columns
            None => return,
        };
        let gain = [
            &bw.g0.col(k)[r.clone()],
            &bw.g1.col(k)[r.clone()],
            &bw.g2.col(k)[r.clone()],
            &bw.nu.col(k)[r.clone()],
        ];
        let link = [
            &bw.ay.col(k)[r.clone()],
            &bw.az.col(k)[r.clone()],
            &bw.hy.col(k)[r.clone()],
            &bw.hz.col(k)[r.clone()],
            &bw.dy.col(k)[r.clone()],
            &bw.dz.col(k)[r],
        ];
        let [a0, a1, a2] = &mut self.ca;
        lanes_fwd::<K>(gain, link, out, a0, a1, a2);
    }
}
