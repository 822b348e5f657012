//! Affine frames of the section in which a Markov chain's mesh is a regular grid
//! ([`crate::markov::Mesh`]).
//!
//! The states a walker visits on rough ground are rarely spread over an axis-aligned box: the
//! simplest walker's post-impact states lie along a narrow band of the (θ, θ̇) plane, oblique to
//! both axes, and its basin is thin across that band. An axis-aligned mesh then spends most of
//! its nodes on states no walker reaches and resolves the band's width with a few nodes only;
//! multilinear interpolation across a band thinner than the mesh spacing hands probability to
//! nodes that fall, and the chain's MFPT comes out far too short (measured: the simplest walker
//! at σ = 0.02°, 60 nodes per axis, 57 steps against the walkers' 2 560). A mesh along the
//! principal axes of the visited states' covariance (Pearson 1901; coordinates first scaled by
//! their ranges, so that the axes do not depend on the units) covers the band with a box
//! several times thinner at the same node count.
//!
//! A frame maps a section point `p` to frame coordinates `u = A (p − c)` and back by
//! `p = c + B u`, `B = A⁻¹`; with `S` the diagonal of the ranges and `V` the covariance's
//! orthonormal eigenvectors, `A = Vᵀ S⁻¹` and `B = S V` (no inversion).

use crate::markov::jacobi_vectors;

/// A box `(lo, hi)`, in section or frame coordinates.
pub type SectionBox = (Vec<f64>, Vec<f64>);

/// An affine frame of a `d`-dimensional section: origin `c`, row-major `d × d` matrices `A`
/// (section to frame) and `B = A⁻¹` (frame to section).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    pub origin: Vec<f64>,
    pub to: Vec<f64>,
    pub from: Vec<f64>,
}

impl Frame {
    /// The section's own coordinates (`u = p`).
    pub fn identity(d: usize) -> Self {
        let mut eye = vec![0.0; d * d];
        for i in 0..d {
            eye[i * d + i] = 1.0;
        }
        Frame {
            origin: vec![0.0; d],
            to: eye.clone(),
            from: eye,
        }
    }

    /// The section dimension.
    pub fn dim(&self) -> usize {
        self.origin.len()
    }

    /// Whether this is [`Frame::identity`] (its maps then add and multiply exact zeros and
    /// ones only, so a mesh in it has the bits of one without a frame).
    pub fn is_identity(&self) -> bool {
        *self == Frame::identity(self.dim())
    }

    /// Frame coordinates of the section point `p`: `u = A (p − c)`.
    pub fn to_frame(&self, p: &[f64]) -> Vec<f64> {
        if self.is_identity() {
            return p.to_vec();
        }
        let d = self.dim();
        (0..d)
            .map(|i| {
                (0..d)
                    .map(|j| self.to[i * d + j] * (p[j] - self.origin[j]))
                    .sum()
            })
            .collect()
    }

    /// The section point of frame coordinates `u`: `p = c + B u`.
    pub fn from_frame(&self, u: &[f64]) -> Vec<f64> {
        if self.is_identity() {
            return u.to_vec();
        }
        let d = self.dim();
        (0..d)
            .map(|i| self.origin[i] + (0..d).map(|j| self.from[i * d + j] * u[j]).sum::<f64>())
            .collect()
    }

    /// The principal axes of `points` (section coordinates, each of length `d`), scaled by
    /// the points' ranges (module docs), ordered by decreasing variance, each axis signed so
    /// that its largest component is positive. The identity for one dimension, for fewer than
    /// `d + 1` points, for a coordinate with zero range or for non-finite points: a frame
    /// needs a spread cloud.
    pub fn principal(points: &[Vec<f64>], d: usize) -> Self {
        let usable = d >= 2
            && points.len() > d
            && points
                .iter()
                .all(|p| p.len() == d && p.iter().all(|v| v.is_finite()));
        if !usable {
            return Frame::identity(d);
        }
        let n = points.len() as f64;
        let centre: Vec<f64> = (0..d)
            .map(|a| points.iter().map(|p| p[a]).sum::<f64>() / n)
            .collect();
        let range: Vec<f64> = (0..d)
            .map(|a| {
                let (lo, hi) = points
                    .iter()
                    .fold((f64::MAX, f64::MIN), |(l, h), p| (l.min(p[a]), h.max(p[a])));
                hi - lo
            })
            .collect();
        if range
            .iter()
            .any(|r| r.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater))
        {
            return Frame::identity(d);
        }
        let v = principal_vectors(points, &centre, &range);
        let mut to = vec![0.0; d * d];
        let mut from = vec![0.0; d * d];
        for i in 0..d {
            for j in 0..d {
                // A = Vᵀ S⁻¹, B = S V
                to[i * d + j] = v[j * d + i] / range[j];
                from[i * d + j] = range[i] * v[i * d + j];
            }
        }
        Frame {
            origin: centre,
            to,
            from,
        }
    }

    /// The smallest box in frame coordinates that holds `points` (section coordinates),
    /// starting from `start` (frame coordinates).
    pub fn bounds(&self, points: &[Vec<f64>], start: &[f64]) -> SectionBox {
        let (mut lo, mut hi) = (start.to_vec(), start.to_vec());
        for p in points {
            let u = self.to_frame(p);
            for (a, v) in u.iter().enumerate() {
                lo[a] = lo[a].min(*v);
                hi[a] = hi[a].max(*v);
            }
        }
        (lo, hi)
    }

    /// The mesh box `(lo, hi)` (frame coordinates) as the section point of its corner `lo` and
    /// its `d` edge vectors (section coordinates), for reports.
    pub fn edges(&self, bounds: &SectionBox) -> (Vec<f64>, Vec<Vec<f64>>) {
        let corner = self.from_frame(&bounds.0);
        let d = self.dim();
        let edges = (0..d)
            .map(|j| {
                let len = bounds.1[j] - bounds.0[j];
                (0..d).map(|i| self.from[i * d + j] * len).collect()
            })
            .collect();
        (corner, edges)
    }
}

/// The unit eigenvectors (row-major, one per column) of the covariance of `points` scaled by
/// `range` about `centre`, in order of decreasing eigenvalue, each signed so that its largest
/// component is positive.
fn principal_vectors(points: &[Vec<f64>], centre: &[f64], range: &[f64]) -> Vec<f64> {
    let d = centre.len();
    let n = points.len() as f64;
    let mut cov = vec![0.0; d * d];
    for p in points {
        for i in 0..d {
            let qi = (p[i] - centre[i]) / range[i];
            for j in 0..d {
                cov[i * d + j] += qi * (p[j] - centre[j]) / range[j] / n;
            }
        }
    }
    let v = jacobi_vectors(&mut cov, d);
    let mut order: Vec<usize> = (0..d).collect();
    order.sort_by(|a, b| cov[b * d + b].total_cmp(&cov[a * d + a]));
    let mut out = vec![0.0; d * d];
    for (k, &c) in order.iter().enumerate() {
        let big = (0..d)
            .map(|i| v[i * d + c])
            .fold(0.0_f64, |m, x| if x.abs() > m.abs() { x } else { m });
        let sign = if big < 0.0 { -1.0 } else { 1.0 };
        for i in 0..d {
            out[i * d + k] = sign * v[i * d + c];
        }
    }
    out
}
