//! Every attractor of the stride map reachable from a region of the section, found before a
//! basin is computed, and the basin's cells labelled by attractor (after Attractors.jl's
//! recurrence approach: Datseris & Wagemakers 2022, Chaos 32:023104).
//!
//! # Discovery (deterministic, up front)
//! A fixed, ordered seed set — the selected period-one gait's neighbourhood and the other
//! period-one orbits perturbed by 10⁻³, then an `n × n` lattice over the whole grid box — is
//! run through the basin engine ([`classify_cells`]) for [`DiscoveryOptions::seed_strides`]
//! strides, with recurrence detection (`‖s_k − s_{k−p}‖∞ < tol_recur·σ(s_k)` at `confirm`
//! consecutive strides, `σ(s) = min(1, ‖s‖∞)` the state's scale,
//! [`crate::basin::state_scale`]). A seed whose walk dies out towards standing still is labelled
//! a fall there ([`crate::basin::stands_still`]) and seeds nothing. Every distance below is
//! relative to the scale σ of the seed's last state `f` (absolute for states of size 1 and
//! more), so that an attractor is told from a walker that merely moves slowly because it is
//! small. The seeds' results are then read **in seed order**:
//! - a recurrence of period p: Newton on `P^p − id` from the seed's last state
//!   ([`find_periodic_orbit`], tight integrator) confirms the orbit and gives its exact points
//!   and the multipliers of `DP^p`; a stable orbit not seen before is a new **periodic**
//!   attractor;
//! - still walking after the budget, not near a known attractor (a periodic one within
//!   10⁻³·σ(f), a chaotic one within its radius): Newton on `P^k − id` for
//!   k = 1..=`max_period` from the last state; a stable orbit within 10⁻²·σ(f) of it is a slowly
//!   attracting periodic attractor; otherwise the map is iterated
//!   [`DiscoveryOptions::cloud_points`] more strides from there: if all of them walk and the
//!   sample's last strides are not a walk dying out ([`crate::basin::walk_dies_out`] on the
//!   scales of its last [`crate::basin::STANDSTILL_WINDOW`] + 1 points), the points are a
//!   sample of a **chaotic** (non-periodic bounded) attractor, its membership radius
//!   [`DiscoveryOptions::chaos_radius`] × the sample's extent (largest coordinate range), at
//!   least `tol_gait`·σ of the sample's last point; if the walker falls or dies out, it was a
//!   transient and nothing is recorded.
//!
//! A recurrence seed within 10⁻⁶·σ(f) of a known periodic attractor of its period is that
//! attractor (no Newton run).
//!
//! Because the seed set depends only on the grid's box (never on a shard's rows) and the engine
//! is deterministic for any thread count, the attractors, their numbering, names and codes are
//! identical for every thread count and shard split; no cell's label depends on which lane met
//! an attractor first.
//!
//! # Labels of the basin pass
//! The selected period-one gait keeps code 0 (`gait`); every other attractor `i` (discovery
//! order) has code [`ATTRACTOR_CODE_BASE`]` + i`. Periodic attractors are given to the engine as
//! known orbits ([`BasinProblem::others`]): a cell is labelled with one when `confirm`
//! consecutive section states lie within `tol_gait` of its points. A cell still walking after
//! the stride budget whose last state lies within a chaotic attractor's radius of its sample is
//! labelled with that attractor (the nearest); otherwise it stays `timeout`. A periodic
//! attractor the seeds missed is still detected by recurrence in the pass and labelled `other`.
//!
//! # Names
//! The selected gait is `gait`; the others `period-k` (`k` strides per period) or `chaotic`,
//! with `b`, `c`, … appended for the second, third of the same kind (`period-2b`, `chaotic-b`;
//! the selected gait counts as the first period-1).

use crate::basin::{
    classify_cells, linspace, state_scale, walk_dies_out, BasinOptions, BasinProblem, CellResult,
    Outcome, ATTRACTOR_CODE_BASE, STANDSTILL_WINDOW,
};
use crate::error::LimitError;
use crate::floquet::Multiplier;
use crate::gaits::Found;
use crate::newton::{FixedPoint, NewtonOptions};
use crate::periodic::{canonical_start, find_periodic_orbit, same_orbit, PeriodicOrbit};
use crate::stride::StrideMap;
use crate::validity::{orbit_validity, OrbitValidity};
use pdw_hybrid::{FallKind, Integrator, Section};
use pdw_model::Walker;

/// Periodic or chaotic.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AttractorKind {
    Periodic,
    Chaotic,
}

/// One attractor.
#[derive(Clone, Debug, PartialEq)]
pub struct Attractor {
    /// `gait`, `period-2`, `period-2b`, `chaotic`, …
    pub name: String,
    /// Outcome code of its basin's cells.
    pub code: u8,
    pub kind: AttractorKind,
    /// Strides per period (0 for a chaotic attractor).
    pub period_k: usize,
    /// Periodic: the orbit's points in stride order, from its smallest point. Chaotic: a
    /// sample of consecutive points on it.
    pub points: Vec<Vec<f64>>,
    /// Multipliers of the K-stride map (empty for a chaotic attractor).
    pub multipliers: Vec<Multiplier>,
    /// Duration of one period (NaN for a chaotic attractor).
    pub period_time: f64,
    /// Chaotic: a walking cell whose last state lies within this ∞-distance of a sample point
    /// belongs to this attractor. 0 for periodic attractors.
    pub radius: f64,
    /// Physical validity of its orbit ([`AttractorSet::check_validity`]; unchecked until then).
    pub validity: OrbitValidity,
}

impl Attractor {
    /// The selected period-one gait, named `gait` with code 0.
    pub fn gait(fp: &FixedPoint) -> Self {
        Self {
            name: "gait".into(),
            code: Outcome::Gait.code(),
            kind: AttractorKind::Periodic,
            period_k: 1,
            points: vec![fp.section.clone()],
            multipliers: fp.multipliers.clone(),
            period_time: fp.metrics.period,
            radius: 0.0,
            validity: OrbitValidity::Unchecked,
        }
    }

    fn periodic(o: &PeriodicOrbit) -> Self {
        Self {
            name: String::new(),
            code: 0,
            kind: AttractorKind::Periodic,
            period_k: o.period_k,
            points: canonical_start(&o.orbit),
            multipliers: o.multipliers.clone(),
            period_time: o.period,
            radius: 0.0,
            validity: OrbitValidity::Unchecked,
        }
    }

    /// ∞-distance from `s` to the nearest of its points.
    pub fn distance(&self, s: &[f64]) -> f64 {
        self.points
            .iter()
            .map(|p| dist_inf(p, s))
            .fold(f64::INFINITY, f64::min)
    }
}

fn dist_inf(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

/// Settings of [`discover`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiscoveryOptions {
    /// Stride budget of every seed.
    pub seed_strides: u16,
    /// Points sampled on a chaotic attractor.
    pub cloud_points: usize,
    /// Membership radius of a chaotic attractor, as a fraction of its sample's extent.
    pub chaos_radius: f64,
    /// Lattice side n of the seed lattice (n × n seeds over the grid box).
    pub lattice: usize,
    /// Most attractors recorded (codes must fit a byte below [`crate::basin`]'s fill value).
    pub max_attractors: usize,
}

impl Default for DiscoveryOptions {
    /// 1000 strides per seed, 256 sample points, radius 5 % of the extent, a 16 × 16 lattice,
    /// at most 64 attractors.
    fn default() -> Self {
        Self {
            seed_strides: 1000,
            cloud_points: 256,
            chaos_radius: 0.05,
            lattice: 16,
            max_attractors: 64,
        }
    }
}

/// The attractors of a basin run, the selected gait (if any) first.
#[derive(Clone, Debug, PartialEq)]
pub struct AttractorSet {
    pub attractors: Vec<Attractor>,
}

impl AttractorSet {
    /// The selected gait, if one was given.
    pub fn gait(&self) -> Option<&Attractor> {
        self.attractors
            .first()
            .filter(|a| a.code == Outcome::Gait.code())
    }

    /// The file legend: the fixed outcome codes ([`crate::basin::legend`]) and one code per
    /// attractor besides the gait.
    pub fn legend(&self) -> Vec<(u8, String)> {
        let mut l: Vec<(u8, String)> = crate::basin::legend()
            .into_iter()
            .map(|(c, n)| (c, n.to_string()))
            .collect();
        for a in &self.attractors {
            if a.code >= ATTRACTOR_CODE_BASE {
                l.push((a.code, a.name.clone()));
            }
        }
        l
    }

    /// Checks every periodic attractor's orbit for physical validity ([`orbit_validity`]: one
    /// stride from each of its points, along the dense solution); chaotic ones stay unchecked.
    pub fn check_validity(&mut self, w: &dyn Walker) {
        for a in &mut self.attractors {
            if a.kind == AttractorKind::Periodic {
                a.validity = orbit_validity(w, &a.points);
            }
        }
    }

    /// The engine's problem: the gait (or none) and the periodic attractors as known orbits
    /// (their order is [`relabel`](Self::relabel)'s map back to codes).
    pub fn problem<'a, S: Section + ?Sized>(
        &self,
        sys: &'a S,
        fall_outcome: &'a (dyn Fn(FallKind) -> Outcome + Sync),
    ) -> BasinProblem<'a> {
        let mut p = BasinProblem::new(
            sys,
            self.gait().map(|g| g.points[0].clone()).unwrap_or_default(),
            fall_outcome,
        );
        p.others = self.others_periodic().map(|a| a.points.clone()).collect();
        p
    }

    fn others_periodic(&self) -> impl Iterator<Item = &Attractor> {
        self.attractors
            .iter()
            .filter(|a| a.code >= ATTRACTOR_CODE_BASE && a.kind == AttractorKind::Periodic)
    }

    /// Gives each cell of a pass run with [`problem`](Self::problem) its attractor's code (see
    /// the module docs); `attractor` becomes the attractor's index in this set.
    pub fn relabel(&self, cells: &mut [CellResult]) {
        let periodic: Vec<usize> = self
            .attractors
            .iter()
            .enumerate()
            .filter(|(_, a)| a.code >= ATTRACTOR_CODE_BASE && a.kind == AttractorKind::Periodic)
            .map(|(i, _)| i)
            .collect();
        for c in cells.iter_mut() {
            match Outcome::from_code(c.outcome) {
                Some(Outcome::Other) if c.attractor != u8::MAX => {
                    if let Some(&i) = periodic.get(c.attractor as usize) {
                        c.outcome = self.attractors[i].code;
                        c.attractor = i as u8;
                    }
                }
                Some(Outcome::Gait) => c.attractor = 0,
                Some(Outcome::Timeout) => {
                    let best = self
                        .attractors
                        .iter()
                        .enumerate()
                        .filter(|(_, a)| a.kind == AttractorKind::Chaotic)
                        .map(|(i, a)| (i, a.distance(&c.final_state), a.radius))
                        .filter(|(_, d, r)| *d <= *r)
                        .min_by(|a, b| a.1.total_cmp(&b.1));
                    if let Some((i, _, _)) = best {
                        c.outcome = self.attractors[i].code;
                        c.attractor = i as u8;
                    }
                }
                _ => {}
            }
        }
    }
}

/// The deterministic seed set of [`discover`]: each of `extra` (e.g. period-one orbits) and that
/// point ± 10⁻³ in its `ix` coordinate, then an `n × n` lattice over `[xlo, xhi] × [ylo, yhi]`
/// in coordinates `ix`, `iy` (other coordinates from `base`), row by row.
pub fn seed_set(
    base: &[f64],
    ix: usize,
    (xlo, xhi): (f64, f64),
    iy: usize,
    (ylo, yhi): (f64, f64),
    n: usize,
    extra: &[Vec<f64>],
) -> Vec<Vec<f64>> {
    let mut seeds = Vec::new();
    for e in extra {
        for d in [0.0, 1e-3, -1e-3] {
            let mut s = e.clone();
            s[ix] += d;
            seeds.push(s);
        }
    }
    let n = n.max(1);
    for y in linspace(ylo, yhi, n) {
        for x in linspace(xlo, xhi, n) {
            let mut s = base.to_vec();
            s[ix] = x;
            s[iy] = y;
            seeds.push(s);
        }
    }
    seeds
}

/// Finds the attractors reached from `seeds` (see the module docs). `gait`, if given, is the
/// selected period-one gait (code 0); `newton_map` (tight integrator) confirms periodic orbits;
/// `basin` are the options of the basin pass (integrator, tolerances, lanes), whose
/// `max_strides` is replaced by `disc.seed_strides`.
#[allow(clippy::too_many_arguments)]
pub fn discover(
    sys: &dyn Section,
    newton_map: &StrideMap<'_>,
    gait: Option<Attractor>,
    seeds: &[Vec<f64>],
    basin: &BasinOptions,
    disc: &DiscoveryOptions,
    fall_outcome: &(dyn Fn(FallKind) -> Outcome + Sync),
    pool: &rayon::ThreadPool,
) -> Result<AttractorSet, LimitError> {
    disc.validate()?;
    let max_att = disc
        .max_attractors
        .min(usize::from(u8::MAX - 1 - ATTRACTOR_CODE_BASE));
    let mut found: Vec<Attractor> = gait.into_iter().collect();
    let seed_opts = BasinOptions {
        max_strides: disc.seed_strides,
        ..*basin
    };
    let mut problem = BasinProblem::new(
        sys,
        found
            .first()
            .map(|g| g.points[0].clone())
            .unwrap_or_default(),
        fall_outcome,
    );
    problem.others = Vec::new();
    let res = classify_cells(&problem, seeds, &seed_opts, pool, &|_| {})?;
    let newton = NewtonOptions {
        tol: 1e-11,
        max_iters: 20,
        ..NewtonOptions::default()
    };
    let push_periodic = |found: &mut Vec<Attractor>, o: &PeriodicOrbit| {
        if o.stable
            && !found
                .iter()
                .any(|a| a.kind == AttractorKind::Periodic && same_orbit(&a.points, &o.orbit))
        {
            found.push(Attractor::periodic(o));
        }
    };
    for c in &res {
        if found.len() >= max_att {
            break;
        }
        match c.outcome() {
            Outcome::Other if c.period > 0 => {
                let p = usize::from(c.period);
                let sigma = state_scale(&c.final_state);
                if found.iter().any(|a| {
                    a.kind == AttractorKind::Periodic
                        && a.period_k == p
                        && a.distance(&c.final_state) < 1e-6 * sigma
                }) {
                    continue;
                }
                if let Ok(o) = find_periodic_orbit(newton_map, &c.final_state, p, &newton) {
                    push_periodic(&mut found, &o);
                }
            }
            Outcome::Timeout => {
                let f = &c.final_state;
                let sigma = state_scale(f);
                let near_known = found.iter().any(|a| match a.kind {
                    AttractorKind::Periodic => a.distance(f) < 1e-3 * sigma,
                    AttractorKind::Chaotic => a.distance(f) <= a.radius,
                });
                if near_known {
                    continue;
                }
                // A slowly attracting periodic orbit?
                let slow = (1..=usize::from(basin.max_period)).find_map(|k| {
                    find_periodic_orbit(newton_map, f, k, &newton)
                        .ok()
                        .filter(|o| {
                            o.stable && o.orbit.iter().any(|p| dist_inf(p, f) < 1e-2 * sigma)
                        })
                });
                if let Some(o) = slow {
                    push_periodic(&mut found, &o);
                    continue;
                }
                if let Some(cloud) = sample_orbit(sys, basin, f, disc.cloud_points) {
                    found.push(Attractor::chaotic(cloud, f.len(), basin, disc));
                }
            }
            _ => {}
        }
    }
    name_and_code(&mut found);
    Ok(AttractorSet { attractors: found })
}

impl DiscoveryOptions {
    /// Checks the options of [`discover`]: at least one seed stride and one cloud point, and a
    /// finite positive chaos radius.
    fn validate(&self) -> Result<(), LimitError> {
        let disc = self;
        if disc.seed_strides == 0 || disc.cloud_points == 0 {
            return Err(LimitError::InvalidOption {
                name: "seed_strides",
                value: 0.0,
                allowed: "seed_strides and cloud_points must be >= 1",
            });
        }
        if !(disc.chaos_radius.is_finite() && disc.chaos_radius > 0.0) {
            return Err(LimitError::InvalidOption {
                name: "chaos_radius",
                value: disc.chaos_radius,
                allowed: "must be finite and > 0",
            });
        }
        Ok(())
    }
}

impl Attractor {
    /// The chaotic attractor sampled by `cloud` (points of dimension `d`): its radius is
    /// `chaos_radius` times the cloud's largest extent along a coordinate, at least the gait
    /// tolerance on the scale of the cloud's last point.
    fn chaotic(
        cloud: Vec<Vec<f64>>,
        d: usize,
        basin: &BasinOptions,
        disc: &DiscoveryOptions,
    ) -> Self {
        let extent = (0..d)
            .map(|j| {
                let (lo, hi) = cloud
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                        (lo.min(p[j]), hi.max(p[j]))
                    });
                hi - lo
            })
            .fold(0.0, f64::max);
        let floor = cloud
            .last()
            .map_or(basin.tol_gait, |p| basin.tol_gait * state_scale(p));
        Attractor {
            name: String::new(),
            code: 0,
            kind: AttractorKind::Chaotic,
            period_k: 0,
            points: cloud,
            multipliers: Vec::new(),
            period_time: f64::NAN,
            radius: (disc.chaos_radius * extent).max(floor),
            validity: OrbitValidity::Unchecked,
        }
    }
}

/// The point a basin grid's default box is centred on (and whose other section coordinates the
/// grid's cells take): the stable period-one gait among `found`, else the first period-one orbit
/// found; when both axes are given explicitly and no orbit was found, the model's first gait
/// guess (or the origin of its section). `None` when an axis must default and there is no
/// orbit to centre it on.
pub fn grid_centre(walker: &dyn Walker, found: &[Found], axes_given: bool) -> Option<Vec<f64>> {
    if let Some(f) = found.iter().find(|f| f.fp.stable).or(found.first()) {
        return Some(f.fp.section.clone());
    }
    axes_given.then(|| {
        walker
            .gait_guesses()
            .first()
            .map(|g| g.section.clone())
            .unwrap_or_else(|| vec![0.0; walker.section_dim()])
    })
}

/// Every attractor reached from the box of a basin grid (coordinates `ix`, `iy` over their
/// ranges, the other coordinates at `base`): [`discover`] from the deterministic [`seed_set`]
/// (the period-one orbits `found`, with the `fixed` coordinates applied, and a
/// [`DiscoveryOptions::default`] lattice over the box), the selected `gait` first; periodic
/// orbits are confirmed on the fixed-point search's integrator
/// ([`crate::gaits::FIXEDPOINT_INTEGRATOR_TOL`]). A 3-D box (`z`: its coordinate and the
/// values it is seeded at) repeats the lattice at each of those values, in their order, after
/// the period-one seeds. Returns the set and the seeds' count. Every
/// basin (the CLI's `basin`, `basin --over`, Python's `basin`) labels a box with this, so they
/// agree cell for cell.
#[allow(clippy::too_many_arguments)]
pub fn box_attractors(
    walker: &dyn Walker,
    found: &[Found],
    gait: Option<&FixedPoint>,
    fixed: &[(usize, f64)],
    base: &[f64],
    (ix, xr): (usize, (f64, f64)),
    (iy, yr): (usize, (f64, f64)),
    z: Option<(usize, &[f64])>,
    opts: &BasinOptions,
    pool: &rayon::ThreadPool,
) -> Result<(AttractorSet, usize), LimitError> {
    let fall = Outcome::of_fall;
    let disc = DiscoveryOptions::default();
    let extra: Vec<Vec<f64>> = found
        .iter()
        .map(|f| {
            let mut s = f.fp.section.clone();
            for (i, v) in fixed {
                s[*i] = *v;
            }
            s
        })
        .collect();
    let seeds = match z {
        None => seed_set(base, ix, xr, iy, yr, disc.lattice, &extra),
        Some((iz, levels)) => {
            let mut seeds = Vec::new();
            for (k, &v) in levels.iter().enumerate() {
                let mut b = base.to_vec();
                b[iz] = v;
                let first = if k == 0 { &extra[..] } else { &[] };
                seeds.extend(seed_set(&b, ix, xr, iy, yr, disc.lattice, first));
            }
            seeds
        }
    };
    let step = |x: &[f64]| walker.step_length(x);
    let newton_map = StrideMap::new(
        walker,
        pdw_hybrid::Options::dop853(crate::gaits::FIXEDPOINT_INTEGRATOR_TOL),
    )?
    .with_step_length(&step);
    let set = discover(
        walker,
        &newton_map,
        gait.map(Attractor::gait),
        &seeds,
        opts,
        &disc,
        &fall,
        pool,
    )?;
    Ok((set, seeds.len()))
}

/// `n` consecutive section states from `s` (strides of the basin integrator), or `None` if a
/// stride does not reach the section (the walker falls: a transient, not an attractor) or the
/// last [`STANDSTILL_WINDOW`] strides are a walk dying out ([`walk_dies_out`]).
fn sample_orbit(
    sys: &dyn Section,
    basin: &BasinOptions,
    s: &[f64],
    n: usize,
) -> Option<Vec<Vec<f64>>> {
    let map = StrideMap::new(sys, basin.integrator).ok()?;
    let mut integ = Integrator::new(sys.dim(), basin.integrator).ok()?;
    let mut x = s.to_vec();
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let st = map.stride_with(&mut integ, &x).ok()?;
        if !st.outcome.is_ok() || !st.next.iter().all(|v| v.is_finite()) {
            return None;
        }
        x = st.next;
        out.push(x.clone());
    }
    if out.len() > STANDSTILL_WINDOW {
        let scales: Vec<f64> = out[out.len() - STANDSTILL_WINDOW - 1..]
            .iter()
            .map(|p| p.iter().fold(0.0f64, |m, v| m.max(v.abs())))
            .collect();
        if walk_dies_out(&scales) {
            return None;
        }
    }
    Some(out)
}

/// Names (`period-k`, `chaotic`, suffixes b, c, …) and codes in discovery order.
#[doc(hidden)]
pub fn name_and_code(found: &mut [Attractor]) {
    let mut next_code = ATTRACTOR_CODE_BASE;
    let mut seen: Vec<String> = Vec::new();
    for a in found.iter_mut() {
        let stem = match a.kind {
            AttractorKind::Periodic => format!("period-{}", a.period_k),
            AttractorKind::Chaotic => "chaotic".to_string(),
        };
        let nth = seen.iter().filter(|s| **s == stem).count();
        seen.push(stem.clone());
        if a.name == "gait" {
            continue;
        }
        let sep = if a.kind == AttractorKind::Chaotic {
            "-"
        } else {
            ""
        };
        a.name = if nth == 0 {
            stem
        } else {
            format!("{stem}{sep}{}", (b'a' + nth as u8) as char)
        };
        a.code = next_code;
        next_code += 1;
    }
}
