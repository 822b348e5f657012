//! Batched (structure-of-arrays) evaluation: many independent states of one chain at once.
//!
//! Inputs and outputs are faer matrices of shape `(lanes × n)`, one column per joint, lanes
//! contiguous in each column ([`faer::Mat::col_as_slice`]). The RNEA and the kinematic pass
//! process the lanes in blocks of at most [`BLOCK`] (so the per-link scratch stays in cache), and
//! within a block loop over links outside and lanes inside, so that the inner loops vectorise;
//! the articulated-body recursion takes 16 lanes at a time through all links (`WIDTH`,
//! `LinkChunk`), its carries in registers. Each lane performs
//! exactly the arithmetic of the scalar kernel (the same per-link step functions of
//! [`crate::spatial`], the same sin/cos routine), so every lane equals the scalar result bit for
//! bit. No allocation happens per call.

use faer::{Mat, MatRef};

use crate::chain::Chain;
use crate::error::{check_shape, SoaError};
use crate::workspace::{kin_recursion, lanes_angles, lanes_kin, lanes_tip, KinLanes, KinLink};

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
    // --- RNEA forward pass: spatial accelerations A_k, each (block × n) ---
    pub(crate) a0: Cols,
    pub(crate) a1: Cols,
    pub(crate) a2: Cols,
    /// the RNEA's carry between links: acceleration, then force (block × 3); the
    /// articulated-body recursion keeps its carries in registers (`batch_aba`'s chunks)
    pub(crate) carry_a: Cols,
    /// base values: zeros and ones (block × 1)
    pub(crate) zeros: Vec<f64>,
    pub(crate) ones: Vec<f64>,
    /// the articulated-body recursion's pass 1 and gains for one chunk of [`WIDTH`] lanes,
    /// one entry per link (`batch_aba`)
    pub(crate) lc: Vec<LinkChunk>,
    /// the last lanes of a call, fewer than a chunk of 8, padded to 8 (`batch_aba`)
    pub(crate) pad: PadChunk,
}

/// Inputs and output of one padded chunk of `WIDTH / 2` lanes, column-major (`q`, `qd`, `tau`,
/// `qdd`: `WIDTH / 2 × n`; `ft`: `WIDTH / 2 × 3`).
#[derive(Debug, Clone, Default)]
pub(crate) struct PadChunk {
    pub(crate) q: Vec<f64>,
    pub(crate) qd: Vec<f64>,
    pub(crate) tau: Vec<f64>,
    pub(crate) qdd: Vec<f64>,
    pub(crate) ft: Vec<f64>,
}

/// Lanes of one chunk of the batched articulated-body recursion: 16 doubles, two AVX-512
/// registers per quantity (with one, the recursion's dependency chain through the carries
/// leaves the units idle: 7.5 against 5.3 ns per lane-DoF at n = 5, 1024 lanes; with four, the
/// carries no longer fit the registers: 8.6).
pub(crate) const WIDTH: usize = 16;

/// One link's quantities for the lanes of a chunk, side by side: every stream of the recursion
/// at a fixed offset from one base (no pointer per stream to keep in a register), in L1 for
/// any chain a spec can build.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct LinkChunk {
    pub(crate) theta: [f64; WIDTH],
    pub(crate) s: [f64; WIDTH],
    pub(crate) c: [f64; WIDTH],
    pub(crate) w: [f64; WIDTH],
    pub(crate) dy: [f64; WIDTH],
    pub(crate) dz: [f64; WIDTH],
    pub(crate) hy: [f64; WIDTH],
    pub(crate) hz: [f64; WIDTH],
    pub(crate) cy: [f64; WIDTH],
    pub(crate) cz: [f64; WIDTH],
    pub(crate) ay: [f64; WIDTH],
    pub(crate) az: [f64; WIDTH],
    pub(crate) by: [f64; WIDTH],
    pub(crate) bz: [f64; WIDTH],
    pub(crate) g0: [f64; WIDTH],
    pub(crate) g1: [f64; WIDTH],
    pub(crate) g2: [f64; WIDTH],
    pub(crate) nu: [f64; WIDTH],
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
            a0: per(),
            a1: per(),
            a2: per(),
            carry_a: Cols::new(b, 3),
            zeros: vec![0.0; b],
            ones: vec![1.0; b],
            lc: vec![LinkChunk::default(); n],
            pad: PadChunk {
                q: vec![0.0; WIDTH / 2 * n],
                qd: vec![0.0; WIDTH / 2 * n],
                tau: vec![0.0; WIDTH / 2 * n],
                qdd: vec![0.0; WIDTH / 2 * n],
                ft: vec![0.0; WIDTH / 2 * 3],
            },
        }
    }
    /// The bytes [`BatchWorkspace::new`] allocates for `lanes` states of a chain of `n` joints,
    /// known before building it (in the manner of faer's `*_scratch` queries): 17 per-link
    /// columns and 7 more of one block of `min(lanes, BLOCK)` lanes, one 16-lane
    /// chunk buffer per link for the articulated-body recursion and the inputs and output of
    /// one padded chunk of `WIDTH / 2` lanes (`4n + 3` columns). It stops growing at
    /// [`BLOCK`] lanes: any lane count is processed block by block in the same memory (tested
    /// against a byte-counting allocator).
    pub fn scratch_bytes(n: usize, lanes: usize) -> usize {
        const F: usize = std::mem::size_of::<f64>();
        let b = lanes.clamp(1, BLOCK);
        (17 * n + 2 + 3 + 2) * b * F
            + n * std::mem::size_of::<LinkChunk>()
            + (4 * n + 3) * (WIDTH / 2) * F
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

/// Batched pass 1 for lanes `l0 .. l0 + bl`: the block instance of
/// [`crate::workspace::kin_recursion`], the same arithmetic as the scalar `kin_pass`.
#[inline(always)]
pub(crate) fn batch_kin_pass(
    chain: &Chain,
    bw: &mut BatchWorkspace,
    q: MatRef<'_, f64>,
    qd: MatRef<'_, f64>,
    l0: usize,
    bl: usize,
) {
    kin_recursion(chain, &mut KinBlock { bw, q, qd, l0, bl });
}

/// A block of lanes `l0..l0 + bl` of pass 1 in the columns of a [`BatchWorkspace`].
struct KinBlock<'a, 'm> {
    bw: &'a mut BatchWorkspace,
    q: MatRef<'m, f64>,
    qd: MatRef<'m, f64>,
    l0: usize,
    bl: usize,
}

/// Column `k − 1` of `c` (or `base` for `k = 0`) and column `k`, over the first `bl` rows.
#[inline(always)]
fn prev_cur<'a>(
    c: &'a mut Cols,
    base: &'a [f64],
    k: usize,
    bl: usize,
) -> (&'a [f64], &'a mut [f64]) {
    if k == 0 {
        (&base[..bl], &mut c.col_mut(0)[..bl])
    } else {
        let (a, b) = c.prev_cur(k);
        (&a[..bl], &mut b[..bl])
    }
}

impl KinLanes for KinBlock<'_, '_> {
    #[inline(always)]
    fn link<const PRI: bool>(&mut self, k: usize, kl: &KinLink) {
        let (bw, l0, bl) = (&mut *self.bw, self.l0, self.bl);
        let qk = &col(self.q, k)[l0..l0 + bl];
        let qdk = &col(self.qd, k)[l0..l0 + bl];
        {
            let (thp, th) = prev_cur(&mut bw.theta, &bw.zeros, k, bl);
            let (sp, s) = prev_cur(&mut bw.s, &bw.zeros, k, bl);
            let (cp, c) = prev_cur(&mut bw.c, &bw.ones, k, bl);
            lanes_angles::<f64, PRI>([thp, sp, cp, qk], th, s, c);
        }
        let (sp, cp): (&[f64], &[f64]) = if k == 0 {
            (&bw.zeros[..bl], &bw.ones[..bl])
        } else {
            (&bw.s.col(k - 1)[..bl], &bw.c.col(k - 1)[..bl])
        };
        let (wp, w) = prev_cur(&mut bw.w, &bw.zeros, k, bl);
        let s = &bw.s.col(k)[..bl];
        let c = &bw.c.col(k)[..bl];
        let [dy, dz, hy, hz, cy, cz, ay, az, by, bz] = [
            &mut bw.dy, &mut bw.dz, &mut bw.hy, &mut bw.hz, &mut bw.cy, &mut bw.cz, &mut bw.ay,
            &mut bw.az, &mut bw.by, &mut bw.bz,
        ]
        .map(|c| &mut c.col_mut(k)[..bl]);
        lanes_kin::<f64, PRI>(
            kl,
            [sp, cp, s, c, wp, qk, qdk],
            dy,
            dz,
            hy,
            hz,
            cy,
            cz,
            w,
            ay,
            az,
            by,
            bz,
        );
    }

    #[inline(always)]
    fn tip(&mut self, lp: [f64; 2]) {
        let (bw, bl) = (&mut *self.bw, self.bl);
        let n = bw.n;
        let sp = &bw.s.col(n - 1)[..bl];
        let cp = &bw.c.col(n - 1)[..bl];
        let [ty, tz] = bw.tip.all_mut::<2>();
        lanes_tip(lp, sp, cp, &mut ty[..bl], tz);
    }
}
