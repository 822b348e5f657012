//! Batched (structure-of-arrays) evaluation: many independent states of one chain at once.
//!
//! Inputs and outputs are faer matrices of shape `(lanes × n)`, one column per joint, lanes
//! contiguous in each column ([`faer::Mat::col_as_slice`]). The kernels process the lanes in
//! blocks of at most [`BLOCK`] (so the per-link scratch stays in cache), and within a block loop
//! over links outside and lanes inside, so that the inner loops vectorise. Each lane performs
//! exactly the arithmetic of the scalar kernel (the same per-link step functions of
//! [`crate::spatial`], the same sin/cos routine), so every lane equals the scalar result bit for
//! bit. No allocation happens per call.

use faer::{Mat, MatRef};

use crate::chain::Chain;
use crate::error::{check_shape, SoaError};
use crate::spatial;

/// Lanes per block of the batched kernels.
pub const BLOCK: usize = 256;

/// Column-major scratch of `rows × cols` values (`rows` = block size), one column per link or
/// per component.
#[derive(Debug, Clone)]
pub(crate) struct Cols {
    rows: usize,
    data: Vec<f64>,
}

impl Cols {
    fn new(rows: usize, cols: usize) -> Self {
        Cols {
            rows,
            data: vec![0.0; rows * cols],
        }
    }
    #[inline(always)]
    pub(crate) fn col(&self, k: usize) -> &[f64] {
        &self.data[k * self.rows..(k + 1) * self.rows]
    }
    #[inline(always)]
    pub(crate) fn col_mut(&mut self, k: usize) -> &mut [f64] {
        &mut self.data[k * self.rows..(k + 1) * self.rows]
    }
    /// Column `k − 1` (read) and column `k` (write), `k ≥ 1`.
    #[inline(always)]
    pub(crate) fn prev_cur(&mut self, k: usize) -> (&[f64], &mut [f64]) {
        let (a, b) = self.data.split_at_mut(k * self.rows);
        (&a[(k - 1) * self.rows..], &mut b[..self.rows])
    }
    /// All `K` columns at once, mutably.
    #[inline(always)]
    pub(crate) fn all_mut<const K: usize>(&mut self) -> [&mut [f64]; K] {
        let mut it = self.data.chunks_exact_mut(self.rows);
        std::array::from_fn(|_| it.next().unwrap_or_default())
    }
}

/// Scratch of the batched kernels, sized from a chain and a lane count, allocated once.
///
/// Per-link buffers have shape `(block × n)` with `block = min(lanes, BLOCK)`.
#[derive(Debug, Clone)]
pub struct BatchWorkspace {
    pub(crate) n: usize,
    pub(crate) lanes: usize,
    pub(crate) block: usize,
    // --- pass 1 (kinematics and biases), each (block × n) ---
    /// absolute angle θ_k, sin θ_k, cos θ_k, angular rate ω_k
    pub(crate) theta: Cols,
    pub(crate) s: Cols,
    pub(crate) c: Cols,
    pub(crate) w: Cols,
    /// lever d_k (world)
    pub(crate) dy: Cols,
    pub(crate) dz: Cols,
    /// prismatic world axis h_k
    pub(crate) hy: Cols,
    pub(crate) hz: Cols,
    /// world COM offset c_k
    pub(crate) cy: Cols,
    pub(crate) cz: Cols,
    /// acceleration bias a_k, force bias b_k (linear parts)
    pub(crate) ay: Cols,
    pub(crate) az: Cols,
    pub(crate) by: Cols,
    pub(crate) bz: Cols,
    /// tip lever (block × 2)
    pub(crate) tip: Cols,
    // --- articulated-body backward pass, each (block × n) ---
    /// gain G_k components and ν_k
    pub(crate) g0: Cols,
    pub(crate) g1: Cols,
    pub(crate) g2: Cols,
    pub(crate) nu: Cols,
    // --- RNEA forward pass: spatial accelerations A_k, each (block × n) ---
    pub(crate) a0: Cols,
    pub(crate) a1: Cols,
    pub(crate) a2: Cols,
    /// carries between links: articulated inertia (block × 6), bias force (block × 3),
    /// acceleration / force (block × 3)
    pub(crate) carry_p: Cols,
    pub(crate) carry_z: Cols,
    pub(crate) carry_a: Cols,
    /// base values: zeros and ones (block × 1)
    pub(crate) zeros: Vec<f64>,
    pub(crate) ones: Vec<f64>,
}

impl BatchWorkspace {
    /// Allocate the scratch for `lanes` states of `chain`.
    pub fn new(chain: &Chain, lanes: usize) -> Self {
        let n = chain.dof();
        let b = lanes.clamp(1, BLOCK);
        let per = || Cols::new(b, n);
        BatchWorkspace {
            n,
            lanes,
            block: b,
            theta: per(),
            s: per(),
            c: per(),
            w: per(),
            dy: per(),
            dz: per(),
            hy: per(),
            hz: per(),
            cy: per(),
            cz: per(),
            ay: per(),
            az: per(),
            by: per(),
            bz: per(),
            tip: Cols::new(b, 2),
            g0: per(),
            g1: per(),
            g2: per(),
            nu: per(),
            a0: per(),
            a1: per(),
            a2: per(),
            carry_p: Cols::new(b, 6),
            carry_z: Cols::new(b, 3),
            carry_a: Cols::new(b, 3),
            zeros: vec![0.0; b],
            ones: vec![1.0; b],
        }
    }
    /// Lane count this workspace was sized for.
    pub fn lanes(&self) -> usize {
        self.lanes
    }
}

/// Check that `m` is `(lanes × n)`.
pub(crate) fn check_batch(
    what: &'static str,
    m: &Mat<f64>,
    lanes: usize,
    ncols: usize,
) -> Result<(), SoaError> {
    check_shape(what, (lanes, ncols), (m.nrows(), m.ncols()))
}

/// Checks that a batch view has `ncols` columns and contiguous columns (unit row stride), so
/// that [`col`] can hand out each column as a slice.
pub(crate) fn check_view(
    what: &'static str,
    m: MatRef<'_, f64>,
    lanes: usize,
    ncols: usize,
) -> Result<(), SoaError> {
    check_shape(what, (lanes, ncols), (m.nrows(), m.ncols()))?;
    if lanes > 0 && m.row_stride() != 1 {
        return Err(SoaError::DimensionMismatch {
            what,
            expected: "contiguous columns (row stride 1)".into(),
            got: format!("row stride {}", m.row_stride()),
        });
    }
    Ok(())
}

/// Column `k` of a view checked by [`check_view`], as a slice of its lanes.
#[inline(always)]
pub(crate) fn col(m: MatRef<'_, f64>, k: usize) -> &[f64] {
    match m.col(k).try_as_col_major() {
        Some(c) => c.as_slice(),
        None => &[],
    }
}

/// Batched pass 1 for lanes `l0 .. l0 + bl`: identical arithmetic to the scalar `kin_pass`.
#[inline(always)]
pub(crate) fn batch_kin_pass(
    chain: &Chain,
    bw: &mut BatchWorkspace,
    q: MatRef<'_, f64>,
    qd: MatRef<'_, f64>,
    l0: usize,
    bl: usize,
) {
    let n = chain.dof();
    for k in 0..n {
        let link = &chain.links[k];
        let qk = &col(q, k)[l0..l0 + bl];
        let qdk = &col(qd, k)[l0..l0 + bl];
        let (lyp, lzp) = if k == 0 {
            (0.0, 0.0)
        } else {
            (chain.links[k - 1].to_next[0], chain.links[k - 1].to_next[1])
        };
        let (comy, comz) = (link.com[0], link.com[1]);
        // angles, sin, cos
        {
            let (thp, th) = if k == 0 {
                (&bw.zeros[..bl], &mut bw.theta.col_mut(0)[..bl])
            } else {
                let (a, b) = bw.theta.prev_cur(k);
                (&a[..bl], &mut b[..bl])
            };
            if chain.prismatic[k] {
                th.copy_from_slice(thp);
            } else {
                for l in 0..bl {
                    th[l] = thp[l] + qk[l];
                }
            }
        }
        if chain.prismatic[k] {
            if k == 0 {
                bw.s.col_mut(0)[..bl].copy_from_slice(&bw.zeros[..bl]);
                bw.c.col_mut(0)[..bl].copy_from_slice(&bw.ones[..bl]);
            } else {
                let (a, b) = bw.s.prev_cur(k);
                b[..bl].copy_from_slice(&a[..bl]);
                let (a, b) = bw.c.prev_cur(k);
                b[..bl].copy_from_slice(&a[..bl]);
            }
        } else {
            let th = &bw.theta.col(k)[..bl];
            let (sv, cv) = (&mut bw.s.col_mut(k)[..bl], &mut bw.c.col_mut(k)[..bl]);
            // s and c live in different buffers
            sincos_into(th, sv, cv);
        }
        // geometry and velocity biases
        let (sp, cp): (&[f64], &[f64]) = if k == 0 {
            (&bw.zeros[..bl], &bw.ones[..bl])
        } else {
            (&bw.s.col(k - 1)[..bl], &bw.c.col(k - 1)[..bl])
        };
        // w is written at column k while column k−1 is read: split.
        let (wp, w) = if k == 0 {
            (&bw.zeros[..bl], &mut bw.w.col_mut(0)[..bl])
        } else {
            let (a, b) = bw.w.prev_cur(k);
            (&a[..bl], &mut b[..bl])
        };
        let s = &bw.s.col(k)[..bl];
        let c = &bw.c.col(k)[..bl];
        let dy = &mut bw.dy.col_mut(k)[..bl];
        let dz = &mut bw.dz.col_mut(k)[..bl];
        let hy = &mut bw.hy.col_mut(k)[..bl];
        let hz = &mut bw.hz.col_mut(k)[..bl];
        let cy = &mut bw.cy.col_mut(k)[..bl];
        let cz = &mut bw.cz.col_mut(k)[..bl];
        let ay = &mut bw.ay.col_mut(k)[..bl];
        let az = &mut bw.az.col_mut(k)[..bl];
        let by = &mut bw.by.col_mut(k)[..bl];
        let bz = &mut bw.bz.col_mut(k)[..bl];
        let m = link.mass;
        if chain.prismatic[k] {
            let u = chain.axis[k];
            lanes_kin_pri(
                m, lyp, lzp, u, comy, comz, sp, cp, wp, qk, qdk, dy, dz, hy, hz, cy, cz, w, ay, az,
                by, bz,
            );
        } else {
            lanes_kin_rev(
                m, lyp, lzp, comy, comz, sp, cp, s, c, wp, qdk, dy, dz, hy, hz, cy, cz, w, ay, az,
                by, bz,
            );
        }
    }
    // tip lever
    let last = &chain.links[n - 1];
    let (lyp, lzp) = (last.to_next[0], last.to_next[1]);
    let sp = &bw.s.col(n - 1)[..bl];
    let cp = &bw.c.col(n - 1)[..bl];
    let [ty, tz] = bw.tip.all_mut::<2>();
    let (ty, tz) = (&mut ty[..bl], &mut tz[..bl]);
    for l in 0..bl {
        ty[l] = cp[l] * lyp - sp[l] * lzp;
        tz[l] = sp[l] * lyp + cp[l] * lzp;
    }
}

#[inline(always)]
fn sincos_into(th: &[f64], s: &mut [f64], c: &mut [f64]) {
    spatial::sincos_slice(th, s, c);
}

// Lane loops as functions with distinct `noalias` slice parameters (see batch_aba.rs).

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn lanes_kin_rev(
    m: f64,
    lyp: f64,
    lzp: f64,
    comy: f64,
    comz: f64,
    sp: &[f64],
    cp: &[f64],
    s: &[f64],
    c: &[f64],
    wp: &[f64],
    qdk: &[f64],
    dy: &mut [f64],
    dz: &mut [f64],
    hy: &mut [f64],
    hz: &mut [f64],
    cy: &mut [f64],
    cz: &mut [f64],
    w: &mut [f64],
    ay: &mut [f64],
    az: &mut [f64],
    by: &mut [f64],
    bz: &mut [f64],
) {
    let bl = qdk.len();
    let (sp, cp, s, c, wp) = (&sp[..bl], &cp[..bl], &s[..bl], &c[..bl], &wp[..bl]);
    let (dy, dz, hy, hz, cy, cz) = (
        &mut dy[..bl],
        &mut dz[..bl],
        &mut hy[..bl],
        &mut hz[..bl],
        &mut cy[..bl],
        &mut cz[..bl],
    );
    let (w, ay, az, by, bz) = (
        &mut w[..bl],
        &mut ay[..bl],
        &mut az[..bl],
        &mut by[..bl],
        &mut bz[..bl],
    );
    for l in 0..bl {
        let (dyl, dzl, cyl, czl) =
            spatial::geom_rev(sp[l], cp[l], lyp, lzp, s[l], c[l], comy, comz);
        let (wl, ayl, azl) = spatial::vel_rev(wp[l], qdk[l], dyl, dzl);
        let (byl, bzl) = spatial::force_bias(m, wl, cyl, czl);
        dy[l] = dyl;
        dz[l] = dzl;
        hy[l] = 0.0;
        hz[l] = 0.0;
        cy[l] = cyl;
        cz[l] = czl;
        w[l] = wl;
        ay[l] = ayl;
        az[l] = azl;
        by[l] = byl;
        bz[l] = bzl;
    }
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn lanes_kin_pri(
    m: f64,
    lyp: f64,
    lzp: f64,
    u: [f64; 2],
    comy: f64,
    comz: f64,
    sp: &[f64],
    cp: &[f64],
    wp: &[f64],
    qk: &[f64],
    qdk: &[f64],
    dy: &mut [f64],
    dz: &mut [f64],
    hy: &mut [f64],
    hz: &mut [f64],
    cy: &mut [f64],
    cz: &mut [f64],
    w: &mut [f64],
    ay: &mut [f64],
    az: &mut [f64],
    by: &mut [f64],
    bz: &mut [f64],
) {
    let bl = qdk.len();
    let (sp, cp, wp, qk) = (&sp[..bl], &cp[..bl], &wp[..bl], &qk[..bl]);
    let (dy, dz, hy, hz, cy, cz) = (
        &mut dy[..bl],
        &mut dz[..bl],
        &mut hy[..bl],
        &mut hz[..bl],
        &mut cy[..bl],
        &mut cz[..bl],
    );
    let (w, ay, az, by, bz) = (
        &mut w[..bl],
        &mut ay[..bl],
        &mut az[..bl],
        &mut by[..bl],
        &mut bz[..bl],
    );
    for l in 0..bl {
        let (dyl, dzl, hyl, hzl, cyl, czl) =
            spatial::geom_pri(sp[l], cp[l], lyp, lzp, u[0], u[1], qk[l], comy, comz);
        let (wl, ayl, azl) = spatial::vel_pri(wp[l], qdk[l], dyl, dzl, hyl, hzl);
        let (byl, bzl) = spatial::force_bias(m, wl, cyl, czl);
        dy[l] = dyl;
        dz[l] = dzl;
        hy[l] = hyl;
        hz[l] = hzl;
        cy[l] = cyl;
        cz[l] = czl;
        w[l] = wl;
        ay[l] = ayl;
        az[l] = azl;
        by[l] = byl;
        bz[l] = bzl;
    }
}
