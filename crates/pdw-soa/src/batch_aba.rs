//! Batched O(n) forward dynamics: the articulated-body recursion of [`crate::aba()`] over
//! `(lanes × n)` matrices, bit-for-bit equal per lane to the scalar [`crate::aba::aba`].

use faer::reborrow::ReborrowMut;
use faer::{Mat, MatMut, MatRef};

use crate::aba::{aba_recursion, lanes_back, lanes_fwd, AbaLanes};
use crate::batch::{check_batch, check_view, col, BatchWorkspace, LinkChunk, PadChunk, WIDTH};
use crate::chain::Chain;
use crate::error::{check_len, SoaError};
use crate::spatial;
use crate::workspace::{kin_recursion, lanes_angles, lanes_kin, lanes_tip, KinLanes, KinLink};

/// Batched forward dynamics `q̈ = 𝓜⁻¹ (τ − C − Jᵀ F_t)` for every lane.
///
/// - `q`, `qd`, `tau`: `(lanes × n)`; `qdd`: output `(lanes × n)`;
/// - `f_tip`: optional `(lanes × 3)` spatial force `[τ, f_y, f_z]` each tip exerts on the
///   environment (convention of [`crate::rnea()`]).
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
///   matrix `(lanes × 2n)`); any lane count (processed 16 lanes at a time, then 8, then the
///   last 2–7 lanes as one padded chunk of 8, or a last lane alone);
/// - `tau`: `(lanes × n)` applied torques or `None` for zero (a passive walker);
/// - `f_tip`: optional `(lanes × 3)` tip force on the environment;
/// - `locked`: mask of length `n` (the same joints locked in every lane) or `None`;
/// - `qdd`: output `(lanes × n)`, exactly `0.0` at locked joints.
///
/// Each lane equals the one-lane call bit for bit, whatever the lane count.
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
            // WIDTH lanes at a time (two AVX-512 registers per quantity: two independent
            // dependency chains in flight), pass 1 and the recursion per chunk in the chunk's
            // link buffers, the carries in registers; then 8 lanes, then the last 2–7 as one
            // padded chunk of 8 or a last one alone (each lane the same arithmetic)
            let mut a = 0;
            while lanes - a >= WIDTH {
                chunk::<WIDTH>(
                    chain,
                    &mut bw.lc,
                    q,
                    qd,
                    tau,
                    f_tip,
                    locked,
                    qdd.rb_mut(),
                    a,
                );
                a += WIDTH;
            }
            let lc = &mut bw.lc;
            if lanes - a >= HALF {
                chunk::<HALF>(chain, lc, q, qd, tau, f_tip, locked, qdd.rb_mut(), a);
                a += HALF;
            }
            match lanes - a {
                0 => {}
                1 => chunk::<1>(chain, lc, q, qd, tau, f_tip, locked, qdd.rb_mut(), a),
                // 2..7 lanes: one chunk of 8 on padded copies costs about one single lane
                r => padded(
                    chain,
                    lc,
                    &mut bw.pad,
                    q,
                    qd,
                    tau,
                    f_tip,
                    locked,
                    qdd.rb_mut(),
                    a,
                    r,
                ),
            }
        },
    );
    Ok(())
}

/// Pass 1 ([`kin_recursion`]) and the articulated-body recursion ([`aba_recursion`]) for the
/// `W ≤ WIDTH` lanes `a..a + W` of the call, in the workspace's chunk buffers. The carries
/// start at their base values (`P⁺ = 0`, `z⁺ = Φ_{t,n}ᵀ F_t` or 0, `A = a_b`) and stay in the
/// chunk's arrays (registers once inlined) from link to link.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn chunk<const W: usize>(
    chain: &Chain,
    lc: &mut [LinkChunk],
    q: MatRef<'_, f64>,
    qd: MatRef<'_, f64>,
    tau: Option<MatRef<'_, f64>>,
    f_tip: Option<MatRef<'_, f64>>,
    locked: Option<&[bool]>,
    qdd: MatMut<'_, f64>,
    a: usize,
) {
    let mut tip = [[0.0; WIDTH]; 2];
    kin_recursion(
        chain,
        &mut KinChunk::<W> {
            lc: &mut *lc,
            tip: &mut tip,
            q,
            qd,
            a,
        },
    );
    let mut cz = [[0.0; W]; 3];
    if let Some(ft) = f_tip {
        let [ty, tz] = &tip;
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
        lc,
        tau,
        qdd,
        a,
        cp: [[0.0; W]; 6],
        cz,
        ca: [[ab[0]; W], [ab[1]; W], [ab[2]; W]],
    };
    aba_recursion(chain, locked, &mut c);
}

/// The last `r` (2 ≤ r < 8) lanes `a..a + r` of a call as one chunk of 8: their inputs copied
/// into the workspace's padded chunk, the rows after `r` repeating lane `a + r − 1` (a valid
/// state: no NaN or subnormal enters the vector units), and the first `r` rows of the result
/// copied out. Each lane's arithmetic is that of every chunk width, so its bits are those of
/// the single-lane call.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn padded(
    chain: &Chain,
    lc: &mut [LinkChunk],
    pad: &mut PadChunk,
    q: MatRef<'_, f64>,
    qd: MatRef<'_, f64>,
    tau: Option<MatRef<'_, f64>>,
    f_tip: Option<MatRef<'_, f64>>,
    locked: Option<&[bool]>,
    mut qdd: MatMut<'_, f64>,
    a: usize,
    r: usize,
) {
    let n = chain.dof();
    let fill = |dst: &mut [f64], src: &[f64]| {
        for (l, d) in dst.iter_mut().enumerate() {
            *d = src[a + l.min(r - 1)];
        }
    };
    for k in 0..n {
        let cols = k * HALF..(k + 1) * HALF;
        fill(&mut pad.q[cols.clone()], col(q, k));
        fill(&mut pad.qd[cols.clone()], col(qd, k));
        if let Some(t) = tau {
            fill(&mut pad.tau[cols], col(t, k));
        }
    }
    if let Some(ft) = f_tip {
        for k in 0..3 {
            fill(&mut pad.ft[k * HALF..(k + 1) * HALF], col(ft, k));
        }
    }
    fn view(v: &[f64], cols: usize) -> MatRef<'_, f64> {
        MatRef::from_column_major_slice(&v[..HALF * cols], HALF, cols)
    }
    chunk::<HALF>(
        chain,
        lc,
        view(&pad.q, n),
        view(&pad.qd, n),
        tau.map(|_| view(&pad.tau, n)),
        f_tip.map(|_| view(&pad.ft, 3)),
        locked,
        MatMut::from_column_major_slice_mut(&mut pad.qdd[..HALF * n], HALF, n),
        0,
    );
    for k in 0..n {
        if let Some(out) = qdd.rb_mut().col_mut(k).try_as_col_major_mut() {
            out.as_slice_mut()[a..a + r].copy_from_slice(&pad.qdd[k * HALF..k * HALF + r]);
        }
    }
}

/// The chunk after the last full one, when 8 or more lanes are left.
const HALF: usize = WIDTH / 2;
/// The base values of pass 1's carries (`θ`, `sin θ`, `ω` before the first link; `cos θ`).
const ZEROS: [f64; WIDTH] = [0.0; WIDTH];
const ONES: [f64; WIDTH] = [1.0; WIDTH];

/// Pass 1 of `W` lanes into the chunk's link buffers (the chunk instance of
/// [`kin_recursion`], the arithmetic of the scalar `kin_pass`).
struct KinChunk<'a, 'm, const W: usize> {
    lc: &'a mut [LinkChunk],
    tip: &'a mut [[f64; WIDTH]; 2],
    q: MatRef<'m, f64>,
    qd: MatRef<'m, f64>,
    a: usize,
}

impl<const W: usize> KinLanes for KinChunk<'_, '_, W> {
    #[inline(always)]
    fn link<const PRI: bool>(&mut self, k: usize, kl: &KinLink) {
        let a = self.a;
        let qk = &col(self.q, k)[a..a + W];
        let qdk = &col(self.qd, k)[a..a + W];
        let (before, rest) = self.lc.split_at_mut(k);
        let LinkChunk {
            theta,
            s,
            c,
            w,
            dy,
            dz,
            hy,
            hz,
            cy,
            cz,
            ay,
            az,
            by,
            bz,
            ..
        } = &mut rest[0];
        let (thp, sp, cp, wp) = match before.last() {
            Some(p) => (&p.theta, &p.s, &p.c, &p.w),
            None => (&ZEROS, &ZEROS, &ONES, &ZEROS),
        };
        let (thp, sp, cp, wp) = (&thp[..W], &sp[..W], &cp[..W], &wp[..W]);
        lanes_angles::<f64, PRI>([thp, sp, cp, qk], &mut theta[..W], &mut s[..W], &mut c[..W]);
        lanes_kin::<f64, PRI>(
            kl,
            [sp, cp, &s[..W], &c[..W], wp, qk, qdk],
            &mut dy[..W],
            &mut dz[..W],
            &mut hy[..W],
            &mut hz[..W],
            &mut cy[..W],
            &mut cz[..W],
            &mut w[..W],
            &mut ay[..W],
            &mut az[..W],
            &mut by[..W],
            &mut bz[..W],
        );
    }

    #[inline(always)]
    fn tip(&mut self, lp: [f64; 2]) {
        let last = &self.lc[self.lc.len() - 1];
        let [ty, tz] = &mut *self.tip;
        lanes_tip(lp, &last.s[..W], &last.c[..W], &mut ty[..W], &mut tz[..W]);
    }
}

/// `W` lanes: the link quantities and gains in the chunk's link buffers, the carries
/// `(P⁺, z⁺)` and `A` in arrays.
struct Chunk<'a, 'm, const W: usize> {
    lc: &'a mut [LinkChunk],
    tau: Option<MatRef<'m, f64>>,
    qdd: MatMut<'m, f64>,
    /// first lane of the chunk in the call's matrices
    a: usize,
    cp: [[f64; W]; 6],
    cz: [[f64; W]; 3],
    ca: [[f64; W]; 3],
}

impl<const W: usize> AbaLanes for Chunk<'_, '_, W> {
    #[inline(always)]
    fn back<const K: u8>(&mut self, k: usize, j: f64, m: f64) {
        let a = self.a;
        let tk = match self.tau {
            Some(t) => &col(t, k)[a..a + W],
            None => &ZEROS[..W],
        };
        let LinkChunk {
            cy,
            cz,
            by,
            bz,
            ay,
            az,
            hy,
            hz,
            dy,
            dz,
            g0,
            g1,
            g2,
            nu,
            ..
        } = &mut self.lc[k];
        let link = [
            &cy[..W],
            &cz[..W],
            &by[..W],
            &bz[..W],
            &ay[..W],
            &az[..W],
            &hy[..W],
            &hz[..W],
            &dy[..W],
            &dz[..W],
        ];
        let [p0, p1, p2, p3, p4, p5] = &mut self.cp;
        let [z0, z1, z2] = &mut self.cz;
        lanes_back::<K>(
            j,
            m,
            tk,
            link,
            &mut g0[..W],
            &mut g1[..W],
            &mut g2[..W],
            &mut nu[..W],
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
        let a = self.a;
        let out = match self.qdd.rb_mut().col_mut(k).try_as_col_major_mut() {
            Some(c) => &mut c.as_slice_mut()[a..a + W],
            // unreachable: `batch_aba_view` checked the columns
            None => return,
        };
        let l = &self.lc[k];
        let gain = [&l.g0[..W], &l.g1[..W], &l.g2[..W], &l.nu[..W]];
        let link = [
            &l.ay[..W],
            &l.az[..W],
            &l.hy[..W],
            &l.hz[..W],
            &l.dy[..W],
            &l.dz[..W],
        ];
        let [a0, a1, a2] = &mut self.ca;
        lanes_fwd::<K>(gain, link, out, a0, a1, a2);
    }
}
