//! A mesh of the Markov chain that follows the states the walkers visit: nodes scattered over
//! the visited set, not a regular grid over its box.
//!
//! # Why
//! A walker on random terrain visits a thin set of the section — near the gait's slow manifold,
//! a band or sheet in a 3-D box. A regular grid over the box ([`crate::markov::Mesh`]) puts most
//! nodes where no walker goes, and its multilinear weights hand every landing near the thin set
//! to the corners of its cell, some of them off the set, where the next stride falls: the chain
//! leaks probability into falls faster than doubling the mesh removes it (the compass at 3°,
//! σ = 0.2°: 77 / 108 steps at a 30³ / 60³ grid against the walkers' 137 ± 3). A cloud puts
//! its nodes on the set itself, so that a landing's weights go to states a walker reaches.
//!
//! # Rules
//! - **Metric.** Distances are measured in the walkers' principal frame
//!   ([`Frame::principal`]) scaled to unit standard deviation along each principal axis: the
//!   section's coordinates (angles, rates) have no common unit, the visited set's spread gives
//!   one. Each axis points to the side of the first visited state, so that the metric and the
//!   cubes below are the same in any units of the section (the distances are those of any
//!   whitening of the visited states: the same under every affine map of the section).
//! - **Nodes.** The metric's space is cut into cubes of side `cell`; a cloud keeps at most one
//!   node per cube, the first point offered in it ([`Cloud::add`]): the visited states thinned
//!   to a spacing of about one cell, in the order they were offered (deterministic).
//! - **Weights** ([`Cloud::weights`]): a point's weights go to its `k` nearest nodes (`k = 2^d`,
//!   the corners of a grid cell) within [`REACH`] cells, by inverse squared distance (Shepard,
//!   "A two-dimensional interpolation function for irregularly-spaced data", ACM 1968): weights
//!   ≥ 0 summing to 1, all on one node that the point hits exactly. A point with no node within
//!   [`REACH`] cells is outside the cloud (`None`), as a landing outside a grid's box.
//! - **Closure** (the chain's, [`crate::mid_stance::cloud_transitions`]): the landings of the
//!   nodes that fall outside the cloud are offered as nodes in turn, and mapped, until no
//!   landing is outside or the passes run out — the cloud grows to the set its own chain
//!   reaches, as a box is widened to hold its nodes' landings ([`crate::markov::widen_box`]).
//!
//! Shepard's weights reproduce constants, not linear functions: the landing's interpolation
//! error is of the order of the spacing, as nearest-node snapping's, but spread over `2^d`
//! nodes on the visited set. The tests compare the chain with the Monte Carlo walkers.

use crate::error::LimitError;
use crate::section_frame::Frame;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A multiply–rotate hash of a cube's integer coordinates. A landing's weights look up to
/// `(2⌈REACH⌉ + 1)^d` cubes (125 in 3-D), and with the standard library's SipHash those lookups
/// were most of the time of a cloud's weights; the keys are the walk's own states, not chosen
/// by an adversary, so a hash without SipHash's resistance to chosen keys is enough.
#[derive(Default)]
struct CubeHasher(u64);

impl CubeHasher {
    fn add(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(23) ^ v).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
}

impl Hasher for CubeHasher {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut b = [0u8; 8];
            b[..chunk.len()].copy_from_slice(chunk);
            self.add(u64::from_le_bytes(b));
        }
    }

    fn write_u64(&mut self, v: u64) {
        self.add(v);
    }

    fn write_usize(&mut self, v: usize) {
        self.add(v as u64);
    }

    /// The high bits folded into the low ones (the table indexes by the low bits).
    fn finish(&self) -> u64 {
        self.0 ^ (self.0 >> 29)
    }
}

type Cubes = HashMap<Vec<i64>, u32, BuildHasherDefault<CubeHasher>>;

/// A landing is outside the cloud when its nearest node is farther than `REACH` cells.
pub const REACH: f64 = 2.0;

/// Nodes scattered over a set of the section (module docs).
#[derive(Clone, Debug)]
pub struct Cloud {
    frame: Frame,
    /// Standard deviation of the visited points along each principal axis, signed so that the
    /// first point has a positive coordinate.
    scale: Vec<f64>,
    cell: f64,
    k: usize,
    d: usize,
    /// Section coordinates of the nodes, node-major.
    nodes: Vec<f64>,
    /// Their metric coordinates, node-major.
    coords: Vec<f64>,
    cubes: Cubes,
}

/// The metric of `points` (module docs, "Metric"): their principal frame and the standard
/// deviation along each of its axes, and the points' extent in it.
struct Metric {
    frame: Frame,
    scale: Vec<f64>,
    extent: Vec<f64>,
}

fn metric(points: &[Vec<f64>]) -> Result<Metric, LimitError> {
    let bad = |message: String| LimitError::Model {
        param: f64::NAN,
        message,
    };
    let d = points.first().map_or(0, Vec::len);
    if d == 0 || points.len() <= d {
        return Err(bad(format!(
            "a cloud needs more visited states than section coordinates: {} states of {d}",
            points.len()
        )));
    }
    if points
        .iter()
        .any(|p| p.len() != d || p.iter().any(|v| !v.is_finite()))
    {
        return Err(bad(
            "a visited state is not finite or has the wrong length".into()
        ));
    }
    let frame = Frame::principal(points, d);
    let us: Vec<Vec<f64>> = points.iter().map(|p| frame.to_frame(p)).collect();
    let n = us.len() as f64;
    let mut scale = Vec::with_capacity(d);
    let mut extent = Vec::with_capacity(d);
    for a in 0..d {
        let mean = us.iter().map(|u| u[a]).sum::<f64>() / n;
        let sd = (us.iter().map(|u| (u[a] - mean).powi(2)).sum::<f64>() / n).sqrt();
        let (lo, hi) = us
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), u| (l.min(u[a]), h.max(u[a])));
        if sd.is_nan() || sd <= 0.0 {
            return Err(bad(format!(
                "the visited states do not spread along principal axis {a}: no metric for a cloud"
            )));
        }
        // the axis's sign from the first point, not from the section's units (module docs)
        scale.push(if us[0][a] < 0.0 { -sd } else { sd });
        extent.push((hi - lo) / sd);
    }
    Ok(Metric {
        frame,
        scale,
        extent,
    })
}

impl Cloud {
    /// An empty cloud in the metric of `points` (module docs), its cell the spacing of a grid
    /// of `per_axis` nodes per axis over the points' box in that metric (the geometric mean of
    /// the axes' spacings): a cloud and a grid of the same `per_axis` have the same resolution.
    /// [`LimitError::Model`] for `per_axis < 2`, for `d + 1` points or fewer, for points that are
    /// not finite or do not spread along an axis.
    pub fn empty(points: &[Vec<f64>], per_axis: usize) -> Result<Self, LimitError> {
        if per_axis < 2 {
            return Err(LimitError::Model {
                param: f64::NAN,
                message: format!(
                    "a cloud's spacing needs at least 2 nodes per axis, not {per_axis}"
                ),
            });
        }
        let m = metric(points)?;
        let d = m.scale.len();
        let mean_log = m.extent.iter().map(|e| e.ln()).sum::<f64>() / d as f64;
        let cell = mean_log.exp() / (per_axis - 1) as f64;
        Ok(Self {
            frame: m.frame,
            scale: m.scale,
            cell,
            k: 1 << d,
            d,
            nodes: Vec::new(),
            coords: Vec::new(),
            cubes: Cubes::default(),
        })
    }

    /// [`Cloud::empty`] with `points` offered as nodes ([`Cloud::add`]).
    pub fn thinned(points: &[Vec<f64>], per_axis: usize) -> Result<Self, LimitError> {
        let mut c = Self::empty(points, per_axis)?;
        c.add(points);
        Ok(c)
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len() / self.d
    }

    /// True for a cloud without nodes.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Section coordinates.
    pub fn dim(&self) -> usize {
        self.d
    }

    /// The side of a cube, in the metric's units (standard deviations of the visited states).
    pub fn cell(&self) -> f64 {
        self.cell
    }

    /// The section coordinates of node `k`.
    pub fn node(&self, k: usize) -> &[f64] {
        &self.nodes[k * self.d..(k + 1) * self.d]
    }

    /// The metric coordinates of the section point `p`.
    fn to_metric(&self, p: &[f64]) -> Vec<f64> {
        self.frame
            .to_frame(p)
            .iter()
            .zip(&self.scale)
            .map(|(u, s)| u / s)
            .collect()
    }

    fn cube(&self, u: &[f64]) -> Vec<i64> {
        u.iter().map(|v| (v / self.cell).floor() as i64).collect()
    }

    /// Offers `points` (section coordinates) as nodes in order: each one that is finite and
    /// falls in a cube without a node becomes one (module docs, "Nodes"). Returns how many did.
    pub fn add(&mut self, points: &[Vec<f64>]) -> usize {
        let mut added = 0;
        for p in points {
            if p.len() != self.d || p.iter().any(|v| !v.is_finite()) {
                continue;
            }
            let u = self.to_metric(p);
            let key = self.cube(&u);
            if self.cubes.contains_key(&key) {
                continue;
            }
            self.cubes.insert(key, self.len() as u32);
            self.nodes.extend_from_slice(p);
            self.coords.extend_from_slice(&u);
            added += 1;
        }
        added
    }

    /// The weights of the section point `p` on its nearest nodes (module docs, "Weights"):
    /// `(node, weight)`, weights > 0 summing to 1; `None` when no node is within [`REACH`]
    /// cells, or for a point that is not finite.
    pub fn weights(&self, p: &[f64]) -> Option<Vec<(usize, f64)>> {
        if p.len() != self.d || p.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let u = self.to_metric(p);
        let base = self.cube(&u);
        let reach2 = (REACH * self.cell).powi(2);
        // every node within REACH cells lies in a cube at most ceil(REACH) cubes away per axis;
        // a cube whose nearest point is farther than REACH cells holds none (skipped: the
        // nodes found, and so the weights, are those of the whole search)
        let r = REACH.ceil() as i64;
        let span = (2 * r + 1) as usize;
        // gap[a][o + r]: squared distance along axis a from u to the cubes at offset o
        let gap: Vec<f64> = (0..self.d)
            .flat_map(|a| {
                let f = u[a] / self.cell - base[a] as f64;
                (-r..=r).map(move |o| {
                    let g = match o {
                        0 => 0.0,
                        o if o > 0 => o as f64 - f,
                        o => f - o as f64 - 1.0,
                    };
                    (g.max(0.0) * self.cell).powi(2)
                })
            })
            .collect();
        let mut near: Vec<(f64, usize)> = Vec::new();
        let mut key = base.clone();
        for c in 0..span.pow(self.d as u32) {
            let (mut rest, mut lower) = (c, 0.0);
            for (a, k) in key.iter_mut().enumerate() {
                let o = rest % span;
                *k = base[a] + o as i64 - r;
                lower += gap[a * span + o];
                rest /= span;
            }
            if lower > reach2 * (1.0 + 1e-9) {
                continue;
            }
            if let Some(&j) = self.cubes.get(&key) {
                let j = j as usize;
                let q = &self.coords[j * self.d..(j + 1) * self.d];
                let d2: f64 = q.iter().zip(&u).map(|(a, b)| (a - b) * (a - b)).sum();
                if d2 <= reach2 {
                    near.push((d2, j));
                }
            }
        }
        if near.is_empty() {
            return None;
        }
        near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        near.truncate(self.k);
        if near[0].0 == 0.0 {
            return Some(vec![(near[0].1, 1.0)]);
        }
        let total: f64 = near.iter().map(|(d2, _)| 1.0 / d2).sum();
        Some(near.iter().map(|(d2, j)| (*j, 1.0 / d2 / total)).collect())
    }
}
