//! The walker's geometry: the swing foot's position, height and rate (scalar and four lanes at a
//! time), the foothold and landing lines the swing-foot guards measure against, the trailing
//! leg's angle after a step down and the leg swap (chain walker docs, "Step down", "Landing on a
//! tilted line", "Resets").

use super::{ChainWalker, MAX_SEGMENTS};
use faer::MatRef;

impl ChainWalker {
    /// The new contact point from the swing arc centre at a heel strike: `r` along the landing
    /// line's inward normal, `−r n = −r (sin Δ, cos Δ)` (`[0, −r]` on the stance line).
    pub(super) fn landing_offset(&self) -> [f64; 2] {
        if self.tilt == 0.0 {
            [0.0, -self.radius]
        } else {
            let (s, c) = self.tilt_sc;
            [-self.radius * s, -self.radius * c]
        }
    }

    /// Height of the swing arc's lowest point over the tilted landing line (chain walker docs,
    /// "Landing on a tilted line"), from the swing arc centre `p` relative to the stance arc
    /// centre: `p·n + r (cos Δ − 1)`; its rate from `ṗ`.
    #[inline]
    pub(super) fn above_tilted(&self, p: [f64; 2], pd: [f64; 2]) -> (f64, f64) {
        let (s, c) = self.tilt_sc;
        (
            p[0] * s + p[1] * c + self.radius * (c - 1.0),
            pd[0] * s + pd[1] * c,
        )
    }

    /// The swing arc centre relative to the stance arc centre ([`ChainWalker::swing_foot`])
    /// and its rate along `f = (q̇, q̈)`: `ṗ = Σ len_i θ̇_i (−cos θ_i, −sin θ_i)`.
    pub(super) fn swing_foot_and_rate(&self, x: &[f64], f: &[f64]) -> ([f64; 2], [f64; 2]) {
        let (mut th, mut thd) = (0.0, 0.0);
        let (mut p, mut pd) = ([0.0; 2], [0.0; 2]);
        for ((qk, fk), len) in x[..self.n].iter().zip(&f[..self.n]).zip(&self.len) {
            th += qk;
            thd += fk;
            let (s, c) = pdw_simd::sincos(th);
            p[0] -= len * s;
            p[1] += len * c;
            pd[0] -= len * c * thd;
            pd[1] -= len * s * thd;
        }
        (p, pd)
    }

    /// Whether the swing foot is ahead of the stance foot: along the stance line, or along the
    /// landing line when it is tilted (its tangent `(cos Δ, −sin Δ)`).
    pub(super) fn swing_ahead(&self, x: &[f64]) -> bool {
        let p = self.swing_foot(x);
        if self.tilt == 0.0 {
            p[0] > 0.0
        } else {
            let (s, c) = self.tilt_sc;
            p[0] * c - p[1] * s > 0.0
        }
    }

    /// Swing-foot position `[y, z]` relative to the stance foot (sin/cos by the kernel's
    /// routine, so that the batched guard gives the same bits).
    pub fn swing_foot(&self, x: &[f64]) -> [f64; 2] {
        let mut th = 0.0;
        let mut p = [0.0, 0.0];
        for (qk, len) in x[..self.n].iter().zip(&self.len) {
            th += qk;
            let (s, c) = pdw_simd::sincos(th);
            p[0] -= len * s;
            p[1] += len * c;
        }
        p
    }

    /// Swing-foot height for every lane of `x` (`lanes × 2n`), four lanes at a time with the
    /// arithmetic of [`ChainWalker::swing_foot`].
    #[inline(always)]
    pub(super) fn foot_height_lanes(&self, x: MatRef<'_, f64>, out: &mut [f64]) {
        let lanes = x.nrows();
        let mut cols: [&[f64]; 2 * MAX_SEGMENTS] = [&[]; 2 * MAX_SEGMENTS];
        for (k, c) in cols.iter_mut().enumerate().take(self.n) {
            *c = match x.col(k).try_as_col_major() {
                Some(v) => v.as_slice(),
                None => {
                    // non-contiguous view: lane by lane
                    let mut xi = [0.0; 4 * MAX_SEGMENTS];
                    for (l, o) in out.iter_mut().enumerate().take(lanes) {
                        for j in 0..self.n {
                            xi[j] = x[(l, j)];
                        }
                        *o = self.swing_foot(&xi)[1];
                    }
                    return;
                }
            };
        }
        let mut l0 = 0;
        while l0 < lanes {
            let w = (lanes - l0).min(4);
            let mut th = [0.0; 4];
            let mut z = [0.0; 4];
            for (col, len) in cols[..self.n].iter().zip(&self.len) {
                for i in 0..w {
                    th[i] += col[l0 + i];
                }
                let (_, c) = pdw_simd::sincos_lanes(th);
                for i in 0..4 {
                    z[i] += *len * c[i];
                }
            }
            out[l0..l0 + w].copy_from_slice(&z[..w]);
            l0 += w;
        }
    }

    /// Swing-foot height (the bits of [`ChainWalker::swing_foot`]'s second component) and its
    /// rate along the flow `ż = ∇z·f = −Σ_i len_i sin θ_i θ̇_i`, with `θ_i = q₀ + … + q_i` and
    /// `θ̇_i = f₀ + … + f_i` read from `f = (q̇, q̈)`.
    pub(super) fn foot_height_and_rate(&self, x: &[f64], f: &[f64]) -> (f64, f64) {
        let (mut th, mut thd, mut z, mut zr) = (0.0, 0.0, 0.0, 0.0);
        for ((qk, fk), len) in x[..self.n].iter().zip(&f[..self.n]).zip(&self.len) {
            th += qk;
            thd += fk;
            let (s, c) = pdw_simd::sincos(th);
            z += len * c;
            zr -= len * s * thd;
        }
        (z, zr)
    }

    /// [`ChainWalker::foot_height_and_rate`] for every lane (four at a time, the same operations
    /// per lane), from column slices of `x` and `f`.
    #[inline(always)]
    pub(super) fn foot_height_rate_lanes(
        &self,
        xc: &[&[f64]],
        fc: &[&[f64]],
        lanes: usize,
        z_out: &mut [f64],
        r_out: &mut [f64],
    ) {
        let mut l0 = 0;
        while l0 < lanes {
            let w = (lanes - l0).min(4);
            let (mut th, mut thd, mut z, mut zr) = ([0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4]);
            for ((xk, fk), len) in xc.iter().zip(fc).zip(&self.len) {
                for i in 0..w {
                    th[i] += xk[l0 + i];
                    thd[i] += fk[l0 + i];
                }
                let (s, c) = pdw_simd::sincos_lanes(th);
                for i in 0..4 {
                    z[i] += *len * c[i];
                    zr[i] -= *len * s[i] * thd[i];
                }
            }
            z_out[l0..l0 + w].copy_from_slice(&z[..w]);
            r_out[l0..l0 + w].copy_from_slice(&zr[..w]);
            l0 += w;
        }
    }

    /// A swing-foot height over the stance foot's line as the height over the next foothold
    /// `h` below, `z + h` (chain walker docs, "Step down"); `z` itself on level ground (`h = 0`,
    /// bit for bit).
    #[inline(always)]
    pub(super) fn above_foothold(z: f64, h: f64) -> f64 {
        if h == 0.0 {
            z
        } else {
            z + h
        }
    }

    /// [`ChainWalker::above_foothold`] on every lane's height.
    pub(super) fn above_foothold_lanes(&self, z: &mut [f64]) {
        let h = self.r.step_down;
        if h != 0.0 {
            for v in z {
                *v += h;
            }
        }
    }

    /// Absolute angle of the stance leg's top segment (the stance leg's angle when its knees
    /// are straight).
    pub(super) fn stance_angle(&self, x: &[f64]) -> f64 {
        x[..self.m].iter().sum()
    }

    /// The absolute angle `ψ` of the straight trailing leg just after a heel strike onto a
    /// foothold `h` below, when the new stance leg's angle is `q₀`: the trailing foot is `h`
    /// above the new stance foot, `ℓ cos q₀ − ℓ cos ψ = h`, behind it: `ψ = −acos(cos q₀ − h/ℓ)`
    /// (chain walker docs, "Step down"; the simplest walker's lift). `ℓ` is the length from the hip
    /// to the point that stays a fixed height above the ground: the foot (`ℓ = L`, the leg
    /// length) for point feet, the foot's arc centre (`ℓ = L − r`) for round feet, whose arc
    /// centres both stand `r` above their lines.
    pub fn trailing_leg_angle(&self, q0: f64) -> f64 {
        let l = self.leg_length - self.radius;
        -(q0.cos() - self.r.step_down / l).clamp(-1.0, 1.0).acos()
    }

    /// The leg swap (seed switch rule, eq. 3.29–3.32) on joint angles `q` and rates `qd`
    /// (length `n` each) into `out` (length `2n`).
    pub fn swap(&self, q: &[f64], qd: &[f64], out: &mut [f64]) {
        let (m, n) = (self.m, self.n);
        for (src, off) in [(q, 0), (qd, n)] {
            out[off] = src.iter().sum();
            for i in 0..m - 1 {
                // stance knee i (joint i+1) ← −(swing knee i, joint 2m−1−i), and vice versa
                out[off + i + 1] = -src[2 * m - 1 - i];
                out[off + 2 * m - 1 - i] = -src[i + 1];
            }
            out[off + m] = -src[m];
        }
    }

    /// The leg swap as a matrix `S` (row-major `n × n`): `q' = S q`, `q̇' = S q̇`.
    pub(super) fn swap_matrix(&self, out: &mut [f64]) {
        let n = self.n;
        let mut e = [0.0; 2 * MAX_SEGMENTS];
        let mut col = [0.0; 4 * MAX_SEGMENTS];
        for j in 0..n {
            e[..n].fill(0.0);
            e[j] = 1.0;
            self.swap(&e[..n], &e[..n], &mut col[..2 * n]);
            for i in 0..n {
                out[i * n + j] = col[i];
            }
        }
    }
}
