//! The Markov chain of random terrain on a section at **mid-stance** — the stance leg along
//! gravity's vertical — where the walker's state does not remember the line it last landed on.
//!
//! # Why a second section
//! Just after a heel strike the walker's state remembers the line it landed on (both feet are
//! on it): the chain of [`crate::markov`] carries that line as a layer per quadrature node, so a
//! section of `d` coordinates with `N` terrain nodes has `N` layers of `n^d` states and each
//! state is mapped onto `N` nodes — `N² n^d` strides. At the instant the stance leg passes the
//! vertical no foot is on a line the walk chose: the configuration is measured from gravity, the
//! landing line of the stride ahead is not drawn yet and the last one is forgotten. The state
//! there — every relative angle and every rate; the one absolute angle ([`Walker::absolute_angle`])
//! is fixed by the section — is the whole Markov state: `n^d` states, `N n^d` strides (the
//! compass gait: 3 coordinates, the same as just after a heel strike, without the layers).
//!
//! # The map
//! From mid-stance the walker of terrain value `v` (the landing line's slope, or the
//! foothold's height) walks to its heel strike on `v`, swaps legs and walks on to the next
//! mid-stance, all in the frame of line `v` (where the stance leg is vertical at
//! `x_a = σ s_v`, `x_a` the absolute angle, `σ` its sign and `s_v` the model's slope: the angle
//! from gravity's vertical is `x_a − σ s_v`, module docs of [`crate::terrain`]). [`MidStance`]
//! is the model with one more guard, `g = ρ (x_a − σ s_v)` rising through zero (`ρ = ±1`, the
//! sense in which the stance leg sweeps), admissible only after a heel strike, and one more
//! state component that counts the heel strikes. The heel strikes of each transition are the
//! chain's reward: a walker that lands and then rolls back before the vertical has completed
//! one more step than one that falls before landing.
//!
//! # What it assumes
//! Between a heel strike and the next mid-stance the walk of [`crate::terrain`] already moves in
//! the frame of the next line; here it stays in the frame of the line just landed on. Only
//! guards that measure the walker against the line could tell the two apart in that half
//! stride: the heel strike and the hip reaching the line (a fall either way). On slopes the
//! heel strike is not admissible before mid-stance: a chain walker's needs the heel-strike
//! factor `|2θ_s + q_m| < |q_m|` (false with the legs together), the simplest walker's `θ < 0`
//! (past its vertical `θ = γ`). The swing foot alone is already ahead before mid-stance in the
//! compass gait and the simplest walker — which is why step heights, whose heel strike needs no
//! more than that, take another section (below). The chain walkers' and the
//! rimless wheel's other falls are measured from gravity. The tests compare the chain with the
//! Monte Carlo walk that has no such assumption.
//!
//! # Step heights: the section at the legs together
//! On random step heights the line never turns, so no frame is forgotten anywhere; what a
//! section must avoid is a stretch of the stride where the walker's fate depends on a height
//! the transition has not drawn yet. The next foothold's height `h` enters the moment the
//! swing foot comes ahead of the stance foot: from there the heel strike is admissible and
//! its guard measures the swing foot from the foothold's line. In the compass gait and the
//! simplest walker the legs pass each other *before* the stance leg is vertical (the compass at
//! 3°: legs together at 0.30 s, vertical at 0.34 s), so a section at the vertical walks that
//! stretch on the last height: the compass's chain gave 16.4 steps against its walkers'
//! 13.38 ± 0.22 (σ = 4 mm), the simplest walker's 36.9 against 10.73 ± 0.11 (σ = 0.0005). On
//! step heights the section is therefore where the swing foot passes the stance foot, the
//! angle between the legs at zero ([`Walker::legs_together`], [`plane`]): before it no guard
//! reads `h`, and the heights landed on before are remembered by the state alone (the trailing
//! foot's height is in the angles). Models without legs (the rimless wheel) keep the vertical.
//! Measured at σ = 4 mm, 2000 walkers, 20 nodes (`pdw-sweep mfpt --terrain step-down
//! --chain-section mid-stance --chain-mesh cloud`): the compass 11.37 / 13.35 on clouds at the
//! spacing of mesh 60 / 120 against 13.38 ± 0.22 (tested); the round-footed compass
//! (`foot_radius = 0.1`) 22.19 / 26.15 against 25.11 ± 0.47 (the refinement still moving,
//! flagged); the simplest walker at σ = 0.0005, 4000 walkers: 11.21 / 11.28 (11.0 / 11.2 with
//! 40 nodes) against 10.73 ± 0.11 — 4 % and 4 standard errors high. Not the map: walked
//! without mesh or quadrature on each walker's own draws ([`walk_map`]) it gives 10.72 ± 0.08
//! against the walkers' 10.75 (8000 walkers). The quadrature: each walker's own draws
//! quantised onto the 20 Gauss–Hermite nodes (the node whose cell of cumulative weight holds
//! `Φ(ξ)`, so the difference to the walkers is paired) walk +0.53 ± 0.08 steps longer (8000
//! walkers; 80 nodes +0.30 ± 0.07, 1000 equal-probability nodes −0.04 ± 0.02, 100 000
//! −0.01 ± 0.01): the rule converges slowly in its nodes for this walker. Not the edge where
//! a state's one-step fall begins: splitting each state's cells there (bisection on the map,
//! the fall's probability exact to 1e-9) moved the chain by less than 0.05 % (11.2111 and
//! 11.2840 at the spacing of mesh 60 / 120, at twice the time); what the rule misses lies
//! further down the walk. For the compass on slopes (3°, σ = 0.2°, 20 000 walkers
//! 133.94 ± 0.91) the same pairing gives −0.58 ± 0.91: no measurable error of its rule.
//!
//! # Which models
//! Models of one mode with an absolute angle: the compass gait (and chain walkers without free
//! knees; with round feet on step heights only, as everywhere), the rimless wheel, the simplest
//! walker. A walker whose knee unlocks
//! during the stride may pass the vertical in either mode: its state there is not one
//! section's, and [`MidStance::new`] refuses it.

use crate::cloud::Cloud;
use crate::ensemble::{flow_batch_with_constants, flow_with_constants};
use crate::error::LimitError;
use crate::markov::{Mesh, Transitions};
use crate::stride::{EventDriver, StrideOutcome};
use crate::terrain::{SlopeTerrain, SlopeWalk, TerrainKind};
use faer::{MatMut, MatRef};
use pdw_hybrid::{
    run_batch_par, run_scalar_with, BatchOptions, Crossing, GuardKind, GuardSpec, HybridSystem,
    Integrator, Scratch,
};
use pdw_model::Walker;
use rayon::prelude::*;

/// The mid-stance guard: the stance leg's angle from gravity's vertical, rising through zero.
pub const MID_STANCE: GuardSpec = GuardSpec {
    name: "mid_stance",
    crossing: Crossing::Rising,
    kind: GuardKind::Reset,
};

/// A one-mode model with the mid-stance guard appended (module docs, "The map"): state
/// `(x, p)`, `x` the model's state in the frame of the model's own line, `p` the heel strikes
/// so far (constant along the flow).
pub struct MidStance<'a> {
    model: &'a dyn Walker,
    /// The section's fixed coordinate ([`plane`]): its index and its value on the section
    /// (`σ s` for the stance leg along the vertical, 0 for the legs together).
    index: usize,
    at: f64,
    /// `ρ`: the guard is `ρ (x[index] − at)`.
    sense: f64,
    /// The model's heel strike `(mode, guard)`: its section guard.
    heel: (usize, usize),
    guards: Vec<GuardSpec>,
    d: usize,
}

/// The model's slope parameter (`slope` in its parameter table).
fn slope_of(model: &dyn Walker) -> Result<f64, LimitError> {
    model
        .param_values()
        .iter()
        .find(|(n, _)| n == "slope")
        .map(|(_, v)| *v)
        .ok_or_else(|| LimitError::Model {
            param: f64::NAN,
            message: format!("model '{}' has no slope parameter", model.name()),
        })
}

/// Why a model has no mid-stance section, or `None` when it has one.
pub fn unsupported(model: &dyn Walker) -> Option<String> {
    if model.absolute_angle().is_none() {
        return Some(format!(
            "model '{}' has no absolute angle measured from its line (Walker::absolute_angle)",
            model.name()
        ));
    }
    if model.n_modes() != 1 {
        return Some(format!(
            "model '{}' has {} modes (a knee that unlocks): it may pass the vertical in either, \
             so mid-stance is not one section; use the section just after heel strike",
            model.name(),
            model.n_modes()
        ));
    }
    slope_of(model).err().map(|e| e.to_string())
}

/// The section's fixed coordinate on terrain of kind `kind` (module docs, "Step heights"):
/// `(index, value)` — the absolute angle at the vertical, `(a, σ s)`, on random slopes and
/// for a model without legs ([`Walker::legs_together`]); the angle between the legs at 0 on
/// step heights.
pub fn plane(model: &dyn Walker, kind: TerrainKind) -> Result<(usize, f64), LimitError> {
    if let Some(i) = legs_together_on(model, kind) {
        return Ok((i, 0.0));
    }
    let (a, sign) = model.absolute_angle().unwrap_or((0, 1.0));
    Ok((a, sign * slope_of(model)?))
}

/// The index of the angle between the legs where the section on terrain of kind `kind` is
/// the legs together ([`plane`]: step heights on a model with legs), else `None`.
pub fn legs_together_on(model: &dyn Walker, kind: TerrainKind) -> Option<usize> {
    (kind == TerrainKind::StepDown)
        .then(|| model.legs_together())
        .flatten()
}

impl<'a> MidStance<'a> {
    /// The mid-stance system of `model` on terrain of kind `kind` ([`plane`]), the section's
    /// coordinate sweeping in the sense `sense` (±1, [`sweep_sense`]); [`LimitError::Model`]
    /// for a model without the section ([`unsupported`]).
    pub fn new(model: &'a dyn Walker, kind: TerrainKind, sense: f64) -> Result<Self, LimitError> {
        if let Some(message) = unsupported(model) {
            return Err(LimitError::Model {
                param: f64::NAN,
                message,
            });
        }
        let (index, at) = plane(model, kind)?;
        let mut guards = model.guards(0).to_vec();
        guards.push(MID_STANCE);
        Ok(Self {
            model,
            index,
            at,
            sense,
            heel: model.section_guard(),
            guards,
            d: model.dim(),
        })
    }

    /// Coordinates of the section: every state component but the absolute angle.
    pub fn section_dim(&self) -> usize {
        self.d - 1
    }

    /// The section point of a full state `(x, p)` on the section.
    pub fn project(&self, x: &[f64]) -> Vec<f64> {
        (0..self.d)
            .filter(|&j| j != self.index)
            .map(|j| x[j])
            .collect()
    }

    /// The full state at the section point `s`, stance leg vertical, with `p` heel strikes.
    pub fn lift(&self, s: &[f64], p: f64) -> Vec<f64> {
        let mut x = Vec::with_capacity(self.d + 1);
        let mut it = s.iter();
        for j in 0..self.d {
            x.push(if j == self.index {
                self.at
            } else {
                *it.next().unwrap_or(&f64::NAN)
            });
        }
        x.push(p);
        x
    }

    /// The driver of one transition: from mid-stance to the next mid-stance guard.
    pub fn driver(&self) -> EventDriver {
        EventDriver {
            section_guard: (0, self.guards.len() - 1),
            start_mode: 0,
            t_max: self.model.max_stride_time(),
        }
    }

    fn n_model(&self) -> usize {
        self.guards.len() - 1
    }

    fn mid(&self, x: &[f64]) -> f64 {
        self.sense * (x[self.index] - self.at)
    }
}

/// `ρ` for the walk that starts at `x0` (just after a heel strike on the model's own line) on
/// terrain of kind `kind`: the sense from the start's value of the section's coordinate
/// ([`plane`]) to the section; [`LimitError::Model`] when the start already lies on it.
pub fn sweep_sense(model: &dyn Walker, kind: TerrainKind, x0: &[f64]) -> Result<f64, LimitError> {
    let (a, at) = plane(model, kind)?;
    let from = x0[a] - at;
    if from == 0.0 || !from.is_finite() {
        return Err(LimitError::Model {
            param: f64::NAN,
            message: "the start lies on the mid-stance section just after heel strike (stance \
                      leg vertical, or legs together on step heights)"
                .into(),
        });
    }
    Ok(-from.signum())
}

impl HybridSystem for MidStance<'_> {
    fn dim(&self) -> usize {
        self.d + 1
    }

    /// The model's: the heel-strike count never enters the step-size control.
    fn error_dim(&self) -> usize {
        self.model.error_dim().clamp(1, self.d)
    }

    fn guards(&self, _mode: usize) -> &[GuardSpec] {
        &self.guards
    }

    fn flow(&self, ws: &mut Scratch, mode: usize, x: &[f64], dx: &mut [f64]) {
        flow_with_constants(self.model, ws, mode, x, dx);
    }

    fn flow_batch(&self, ws: &mut Scratch, mode: usize, x: MatRef<'_, f64>, dx: MatMut<'_, f64>) {
        flow_batch_with_constants(self.model, ws, mode, x, dx);
    }

    fn guard(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64]) -> f64 {
        if k < self.n_model() {
            self.model.guard(ws, mode, k, &x[..self.d])
        } else {
            self.mid(x)
        }
    }

    fn guards_with_rates(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        f: &[f64],
        g: &mut [f64],
        rate: &mut [f64],
    ) {
        let (d, n) = (self.d, self.n_model());
        self.model
            .guards_with_rates(ws, mode, &x[..d], &f[..d], &mut g[..n], &mut rate[..n]);
        g[n] = self.mid(x);
        rate[n] = self.sense * f[self.index];
    }

    fn guards_with_rates_batch(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: MatRef<'_, f64>,
        f: MatRef<'_, f64>,
        mut g: MatMut<'_, f64>,
        mut rate: MatMut<'_, f64>,
    ) {
        use faer::reborrow::ReborrowMut;
        let (d, n, a) = (self.d, self.n_model(), self.index);
        self.model.guards_with_rates_batch(
            ws,
            mode,
            x.subcols(0, d),
            f.subcols(0, d),
            g.rb_mut().subcols_mut(0, n),
            rate.rb_mut().subcols_mut(0, n),
        );
        for l in 0..x.nrows() {
            g[(l, n)] = self.sense * (x[(l, a)] - self.at);
            rate[(l, n)] = self.sense * f[(l, a)];
        }
    }

    fn guard_is_linear(&self, mode: usize, k: usize) -> bool {
        k >= self.n_model() || self.model.guard_is_linear(mode, k)
    }

    /// The model's; the mid-stance guard only after a heel strike.
    fn admissible(&self, mode: usize, k: usize, x: &[f64]) -> bool {
        if k < self.n_model() {
            self.model.admissible(mode, k, &x[..self.d])
        } else {
            x[self.d] >= 0.5
        }
    }

    fn guard_tolerance(&self, mode: usize, k: usize) -> f64 {
        if k < self.n_model() {
            self.model.guard_tolerance(mode, k)
        } else {
            1e-12
        }
    }

    /// The model's reset (a heel strike adds one to the count); the mid-stance guard changes
    /// nothing.
    fn reset(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], out: &mut [f64]) -> usize {
        let d = self.d;
        if k >= self.n_model() {
            out.copy_from_slice(x);
            return mode;
        }
        let next = self.model.reset(ws, mode, k, &x[..d], &mut out[..d]);
        out[d] = x[d] + f64::from(u8::from((mode, k) == self.heel));
        next
    }

    fn guard_gradient(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], grad: &mut [f64]) {
        let d = self.d;
        grad.fill(0.0);
        if k < self.n_model() {
            self.model
                .guard_gradient(ws, mode, k, &x[..d], &mut grad[..d]);
        } else {
            grad[self.index] = self.sense;
        }
    }
}

pdw_hybrid::integrate_through_dyn!(MidStance<'_>);

/// Where one transition from mid-stance ended: the next mid-stance's section point (`None`: a
/// fall, or an integration that failed), and the heel strikes on the way.
#[derive(Clone, Debug, PartialEq)]
pub struct Landing {
    pub point: Option<Vec<f64>>,
    pub strikes: f64,
}

fn landing(sys: &MidStance, outcome: &StrideOutcome, post: &[f64]) -> Landing {
    let strikes = post[sys.d];
    Landing {
        point: outcome.is_ok().then(|| sys.project(post)),
        strikes: if strikes.is_finite() { strikes } else { 0.0 },
    }
}

/// Every section point of `starts` (mid-stance) walked on terrain value `v` to the next
/// mid-stance, batched on `pool`.
pub fn map_onto(
    walk: &SlopeWalk,
    v: f64,
    sense: f64,
    starts: &[Vec<f64>],
    pool: &rayon::ThreadPool,
) -> Result<Vec<Landing>, LimitError> {
    let w = walk.model(v)?;
    let sys = MidStance::new(w.as_ref(), walk.kind(), sense)?;
    let items: Vec<Vec<f64>> = starts.iter().map(|s| sys.lift(s, 0.0)).collect();
    let opts = BatchOptions {
        lanes: 256,
        integrator: walk.options(),
    };
    let progress = walk.batch_progress();
    let ends = run_batch_par(&sys, &sys.driver(), &items, &opts, pool, 1024, &progress)?;
    Ok(ends
        .iter()
        .map(|e| landing(&sys, &e.outcome, &e.post))
        .collect())
}

/// The start `x0` (just after a heel strike on the mean line, in its frame) walked to its
/// first mid-stance on the model of the mean terrain: the heel strikes counted are those after
/// the start (none on a walk that passes the vertical before landing again).
pub fn first_mid_stance(walk: &SlopeWalk, sense: f64, x0: &[f64]) -> Result<Landing, LimitError> {
    let w = walk.model(walk.mean())?;
    let sys = MidStance::new(w.as_ref(), walk.kind(), sense)?;
    let mut integ = Integrator::new(sys.d + 1, walk.options())?;
    let mut x = x0.to_vec();
    x.push(1.0);
    let end = run_scalar_with(&mut integ, &sys, &sys.driver(), &x)?;
    let mut l = landing(&sys, &end.outcome, &end.post);
    l.strikes -= 1.0;
    Ok(l)
}

/// The chain on `mesh` (a mesh of the mid-stance section) for `walk` with terrain nodes
/// `nodes` (`(v_l, w_l)`), the start `x0`'s row last ([`first_mid_stance`], no terrain drawn):
/// the transitions with their expected heel strikes ([`Transitions::strikes`]).
pub fn transitions(
    walk: &SlopeWalk,
    nodes: &[(f64, f64)],
    mesh: &Mesh,
    x0: &[f64],
    sense: f64,
    pool: &rayon::ThreadPool,
) -> Result<Transitions, LimitError> {
    let starts: Vec<Vec<f64>> = (0..mesh.len()).map(|k| mesh.node(k)).collect();
    let n = starts.len();
    let mut t = Transitions {
        rows: vec![Vec::new(); n + 1],
        fall: vec![0.0; n + 1],
        out: vec![0.0; n + 1],
        strikes: Some(vec![0.0; n + 1]),
    };
    for (v, w) in nodes {
        let ls = map_onto(walk, *v, sense, &starts, pool)?;
        // the weights in parallel, added in the states' order (as a serial loop adds them)
        let spread: Vec<_> = pool.install(|| {
            ls.par_iter()
                .with_min_len(256)
                .map(|l| l.point.as_ref().map(|p| mesh.weights(p)))
                .collect()
        });
        for (i, (l, sp)) in ls.into_iter().zip(spread).enumerate() {
            add_spread(&mut t, i, *w, l.strikes, sp);
        }
    }
    let first = first_mid_stance(walk, sense, x0)?;
    add(&mut t, n, 1.0, first, mesh);
    Ok(t)
}

/// Row `i`'s transition of probability `w` ending at `l`, spread over the mesh's nodes.
fn add(t: &mut Transitions, i: usize, w: f64, l: Landing, mesh: &Mesh) {
    let spread = l.point.as_ref().map(|p| mesh.weights(p));
    add_spread(t, i, w, l.strikes, spread);
}

/// Row `i`'s transition of probability `w` with `strikes` heel strikes: `spread` the landing's
/// weights on the nodes (`Some(None)`: outside them; `None`: a fall).
fn add_spread(
    t: &mut Transitions,
    i: usize,
    w: f64,
    strikes: f64,
    spread: Option<Option<Vec<(usize, f64)>>>,
) {
    if let Some(s) = t.strikes.as_mut() {
        s[i] += w * strikes;
    }
    match spread {
        Some(Some(ws)) => t.rows[i].extend(ws.into_iter().map(|(k, q)| (k, w * q))),
        Some(None) => t.out[i] += w,
        None => t.fall[i] += w,
    }
}

/// The chain on a cloud ([`cloud_transitions`]) and how its closure went.
#[derive(Clone, Debug, PartialEq)]
pub struct CloudChain {
    pub transitions: Transitions,
    /// Nodes before the closure (the visited states thinned) and after it.
    pub seeds: usize,
    pub nodes: usize,
    /// Closure passes that added nodes.
    pub passes: usize,
}

/// The chain on `cloud` (its nodes mid-stance section points, [`crate::cloud`]) for `walk`
/// with terrain nodes `nodes`, as [`transitions`], with the cloud's closure: after its nodes
/// are mapped, every landing (on a terrain node of weight at least
/// [`crate::markov::HULL_MIN_WEIGHT`]) outside the cloud is offered as a node
/// ([`Cloud::add`]) and the new nodes are mapped in turn, at most `passes` times or until no
/// landing is outside. What is still outside after the last pass is the chain's
/// [`Transitions::out`].
pub fn cloud_transitions(
    walk: &SlopeWalk,
    nodes: &[(f64, f64)],
    cloud: &mut Cloud,
    x0: &[f64],
    sense: f64,
    passes: usize,
    pool: &rayon::ThreadPool,
) -> Result<CloudChain, LimitError> {
    let mut cache = LandingCache::default();
    cloud_transitions_cached(walk, nodes, cloud, x0, sense, passes, pool, &mut cache)
}

/// Landings already mapped, by the bits of their start (a mid-stance section point): one per
/// terrain node, for one walk, sense and list of terrain nodes. A lane's result does not
/// depend on the batch it ran in (module docs of [`pdw_hybrid::batch`]), so a start met again
/// — the two clouds of a pair share most of the visited states they are thinned from — is
/// answered from here bit for bit. Records only while [`LandingCache::record`] is set.
#[derive(Clone, Debug, Default)]
pub struct LandingCache {
    pub record: bool,
    map: std::collections::HashMap<Vec<u64>, Vec<Landing>>,
    /// Starts answered from the cache.
    pub hits: usize,
}

impl LandingCache {
    /// An empty cache that records.
    pub fn recording() -> Self {
        Self {
            record: true,
            ..Self::default()
        }
    }
}

fn start_key(p: &[f64]) -> Vec<u64> {
    p.iter().map(|v| v.to_bits()).collect()
}

/// Every start of `new` mapped onto every terrain node of `nodes` (`out[l][k]`: start `k`
/// onto node `l`), the starts the cache holds answered from it.
fn map_cached(
    walk: &SlopeWalk,
    nodes: &[(f64, f64)],
    sense: f64,
    new: &[Vec<f64>],
    pool: &rayon::ThreadPool,
    cache: &mut LandingCache,
) -> Result<Vec<Vec<Landing>>, LimitError> {
    let todo: Vec<&Vec<f64>> = new
        .iter()
        .filter(|p| !cache.map.contains_key(&start_key(p)))
        .collect();
    cache.hits += new.len() - todo.len();
    let fresh: Vec<Vec<f64>> = todo.iter().map(|p| p.to_vec()).collect();
    let mut mapped: Vec<std::vec::IntoIter<Landing>> = Vec::with_capacity(nodes.len());
    for (v, _) in nodes {
        mapped.push(map_onto(walk, *v, sense, &fresh, pool)?.into_iter());
    }
    let mut fresh_of = std::collections::HashMap::new();
    for p in &fresh {
        let ls: Vec<Landing> = mapped.iter_mut().filter_map(Iterator::next).collect();
        fresh_of.insert(start_key(p), ls);
    }
    let mut out: Vec<Vec<Landing>> = vec![Vec::with_capacity(new.len()); nodes.len()];
    for p in new {
        let key = start_key(p);
        let ls = fresh_of.get(&key).or_else(|| cache.map.get(&key));
        for (o, l) in out.iter_mut().zip(ls.into_iter().flatten()) {
            o.push(l.clone());
        }
    }
    if cache.record {
        cache.map.extend(fresh_of);
    }
    Ok(out)
}

/// [`cloud_transitions`] with the strides of starts already mapped taken from `cache`, and
/// the new ones recorded there where it records ([`LandingCache`]).
#[allow(clippy::too_many_arguments)]
pub fn cloud_transitions_cached(
    walk: &SlopeWalk,
    nodes: &[(f64, f64)],
    cloud: &mut Cloud,
    x0: &[f64],
    sense: f64,
    passes: usize,
    pool: &rayon::ThreadPool,
    cache: &mut LandingCache,
) -> Result<CloudChain, LimitError> {
    let seeds = cloud.len();
    let mut land: Vec<Vec<Landing>> = vec![Vec::new(); nodes.len()];
    let (mut mapped, mut run) = (0, 0);
    loop {
        let new: Vec<Vec<f64>> = (mapped..cloud.len())
            .map(|k| cloud.node(k).to_vec())
            .collect();
        for (l, ls) in map_cached(walk, nodes, sense, &new, pool, cache)?
            .into_iter()
            .enumerate()
        {
            land[l].extend(ls);
        }
        if run == passes {
            break;
        }
        // a point offered is a node or lies in a node's cube (within REACH cells in d ≤ 3):
        // only the new nodes' landings can be outside
        let c: &Cloud = cloud;
        let outside: Vec<Vec<f64>> = pool.install(|| {
            nodes
                .iter()
                .zip(&land)
                .filter(|((_, w), _)| *w >= crate::markov::HULL_MIN_WEIGHT)
                .flat_map(|(_, ls)| &ls[mapped..])
                .filter_map(|l| l.point.as_ref())
                .collect::<Vec<_>>()
                .into_par_iter()
                .filter(|p| c.weights(p).is_none())
                .cloned()
                .collect()
        });
        mapped = cloud.len();
        if cloud.add(&outside) == 0 {
            break;
        }
        run += 1;
    }
    let n = cloud.len();
    let mut t = Transitions {
        rows: vec![Vec::new(); n + 1],
        fall: vec![0.0; n + 1],
        out: vec![0.0; n + 1],
        strikes: Some(vec![0.0; n + 1]),
    };
    let c: &Cloud = cloud;
    for ((_, w), ls) in nodes.iter().zip(land) {
        let spread: Vec<_> = pool.install(|| {
            ls.par_iter()
                .map(|l| l.point.as_ref().map(|p| c.weights(p)))
                .collect()
        });
        for (i, (l, s)) in ls.into_iter().zip(spread).enumerate() {
            add_spread(&mut t, i, *w, l.strikes, s);
        }
    }
    let first = first_mid_stance(walk, sense, x0)?;
    let spread = first.point.as_ref().map(|p| c.weights(p));
    add_spread(&mut t, n, 1.0, first.strikes, spread);
    Ok(CloudChain {
        transitions: t,
        seeds,
        nodes: n,
        passes: run,
    })
}

/// Every landing (not a fall) of the nodes of `mesh` onto the terrain nodes `nodes` of weight
/// at least [`crate::markov::HULL_MIN_WEIGHT`], in section coordinates.
pub fn landings(
    walk: &SlopeWalk,
    nodes: &[(f64, f64)],
    mesh: &Mesh,
    sense: f64,
    pool: &rayon::ThreadPool,
) -> Result<Vec<Vec<f64>>, LimitError> {
    let starts: Vec<Vec<f64>> = (0..mesh.len()).map(|k| mesh.node(k)).collect();
    let mut out = Vec::new();
    for (v, w) in nodes {
        if *w < crate::markov::HULL_MIN_WEIGHT {
            continue;
        }
        let ls = map_onto(walk, *v, sense, &starts, pool)?;
        out.extend(ls.into_iter().filter_map(|l| l.point));
    }
    Ok(out)
}

/// The mid-stance section points of `walkers` walkers of `terrain` (their own draws, as the
/// Monte Carlo walk's), at most `max_steps` transitions each, from `x0`'s first mid-stance:
/// the states the walkers visit, one walker at a time per thread.
pub fn visited(
    walk: &SlopeWalk,
    terrain: &SlopeTerrain,
    x0: &[f64],
    sense: f64,
    walkers: usize,
    max_steps: usize,
    pool: &rayon::ThreadPool,
) -> Result<Vec<Vec<f64>>, LimitError> {
    let Some(first) = first_mid_stance(walk, sense, x0)?.point else {
        return Ok(Vec::new());
    };
    let per: Vec<Vec<Vec<f64>>> = pool.install(|| {
        (0..walkers)
            .into_par_iter()
            .map(|i| walk_visits(walk, terrain, &first, sense, i as u64, max_steps))
            .collect::<Result<_, LimitError>>()
    })?;
    let mut pts = vec![first];
    pts.extend(per.into_iter().flatten());
    Ok(pts)
}

/// Walker `i`'s mid-stance points from `first`.
fn walk_visits(
    walk: &SlopeWalk,
    terrain: &SlopeTerrain,
    first: &[f64],
    sense: f64,
    i: u64,
    max_steps: usize,
) -> Result<Vec<Vec<f64>>, LimitError> {
    let mut integ: Option<Integrator> = None;
    let mut s = first.to_vec();
    let mut out = Vec::new();
    for k in 0..max_steps {
        let w = walk.model(terrain.slope(i, k as u64 + 1))?;
        let sys = MidStance::new(w.as_ref(), walk.kind(), sense)?;
        let integ = match integ.as_mut() {
            Some(g) => g,
            None => integ.insert(Integrator::new(sys.d + 1, walk.options())?),
        };
        let end = run_scalar_with(integ, &sys, &sys.driver(), &sys.lift(&s, 0.0))?;
        walk.report(1);
        match landing(&sys, &end.outcome, &end.post).point {
            Some(p) => {
                out.push(p.clone());
                s = p;
            }
            None => break,
        }
    }
    Ok(out)
}

/// Walker `i` walked by the chain's own map ([`MidStance`], no mesh, no quadrature) from the
/// mid-stance point `first`, its terrain value at transition `k` (1, 2, …) `draw(i, k)`, for
/// at most `max_steps` transitions: the heel strikes completed before it fell (or by the
/// limit). With the walkers' own draws ([`SlopeTerrain::slope`]) this is the Monte Carlo walk
/// through the section — a check of the map that the chain discretises; with draws from the
/// quadrature's nodes it measures the quadrature alone.
pub fn walk_map(
    walk: &SlopeWalk,
    draw: &(dyn Fn(u64, u64) -> f64 + Sync),
    first: &[f64],
    sense: f64,
    i: u64,
    max_steps: usize,
) -> Result<f64, LimitError> {
    let mut integ: Option<Integrator> = None;
    let mut s = first.to_vec();
    let mut total = 0.0;
    for k in 0..max_steps {
        let w = walk.model(draw(i, k as u64 + 1))?;
        let sys = MidStance::new(w.as_ref(), walk.kind(), sense)?;
        let integ = match integ.as_mut() {
            Some(g) => g,
            None => integ.insert(Integrator::new(sys.d + 1, walk.options())?),
        };
        let end = run_scalar_with(integ, &sys, &sys.driver(), &sys.lift(&s, 0.0))?;
        let l = landing(&sys, &end.outcome, &end.post);
        total += l.strikes;
        match l.point {
            Some(p) => s = p,
            None => break,
        }
    }
    Ok(total)
}
