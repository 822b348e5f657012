//! Basins of attraction: iterate the stride map from many section states ("cells") and classify
//! where each one ends up.
//!
//! # Classification of one cell
//! Starting from the section state `s₀` (the cell), the stride map is applied,
//! `s_{k+1} = P(s_k) = Π(R(x⁻_k))` followed by the lift `L` (so the iteration is exactly that of
//! [`StrideMap`](crate::StrideMap)), until one of:
//! - **gait** — (only when a gait `s*` is given; [`BasinProblem::gait`] may be empty)
//!   `‖s_k − s*‖∞ < tol_gait` at `confirm` consecutive section states
//!   (`s₀` included). Requiring several consecutive states, not one, makes the label robust when
//!   the selected fixed point is a saddle: a trajectory that merely passes near an unstable `s*`
//!   does not stay. For a stable `s*` with largest multiplier modulus ρ the price is
//!   `confirm − 1` extra strides.
//! - **other** — a known other attractor (an orbit given in [`BasinProblem::others`]) was reached
//!   in the same sense as a gait, or a recurrence was detected: `‖s_k − s_{k−p}‖∞ <
//!   tol_recur·σ(s_k)` for some `p ∈ 1..=max_period` at `confirm` consecutive strides while not
//!   at `s*` (a single coincidental near-return of a transient is not enough), with the state's
//!   scale `σ(s) = min(1, ‖s‖∞)` ([`state_scale`], the scale of Newton's acceptance test,
//!   [`crate::newton::residual_scale`]): a state of scale 10⁻⁶ must return to 10⁻¹⁶, not to
//!   10⁻¹⁰, its own size in ten thousandths. The recorded period is the smallest divisor q of
//!   the smallest such p with `‖s_k − s_{k−q}‖∞ < tol_gait·σ(s_k)` (or the known orbit's
//!   length). `tol_recur` must be much smaller than `tol_gait·|1 − λ^p|` so that a slow
//!   approach to `s*` (multiplier λ near ±1) is not mistaken for a recurrence; the defaults
//!   (1e-6 and 1e-10) leave four decades. A recurrence of a walker that stands still (below) is
//!   not an attractor: it is labelled [`Outcome::Fall`].
//! - **fall** with its kind — a terminal guard of the model fired (the kind comes from the
//!   guard's code through [`BasinProblem::fall_outcome`]: forward, backward, the swing knee bent
//!   at the foot strike, a stance knee buckled, a rimless wheel rolling back, each its own class
//!   by [`Outcome::of_fall`]), or no section event occurred within
//!   the stride time budget [`Section::max_stride_time`] ([`Outcome::FallNoHeelStrike`], the
//!   end the stride map gives such a stride: [`StrideOutcome::NoHeelStrike`]).
//! - **stands still** ([`Outcome::Fall`]) — where the cell would be labelled by a recurrence or
//!   time out, the walk has died out ([`stands_still`]): its section state is within `tol_gait`
//!   of the standing state `s = 0`, or its scale `a_k = ‖s_k‖∞` fell at each of the last
//!   [`STANDSTILL_WINDOW`] strides in a decay towards zero, not towards a gait
//!   ([`walk_dies_out`]). On a level floor a passive walker loses energy at every heel strike
//!   and has no gait: its steps shrink for ever (as `k^{−1/2}` for the simplest walker, whose
//!   heel strike keeps the fraction `cos² 2θ ≈ 1 − 4θ²` of its kinetic energy — Garcia et al.
//!   1998's jump map `θ̇⁺ = cos 2θ · θ̇⁻` — so that `θ` falls by `∝ θ³` a stride; measured:
//!   `θ ≈ 0.0139` after 100 strides, `0.0046` after 1000), which no stride budget outlasts and
//!   which must be neither a chaotic attractor nor, once the state is too small for the
//!   integrator to resolve its change, a periodic one. Checked only where the label would
//!   otherwise be `other` or `timeout`, so a cell that converges to a gait or falls is labelled
//!   as before.
//! - **timeout** — `max_strides` strides without any of the above (e.g. a chaotic attractor).
//! - **nonfinite** — the state became non-finite (including a non-finite cell).
//! - **integrator_failure** — the step size collapsed, the step budget ran out, or a stride had
//!   more than [`MAX_EVENTS_PER_STRIDE`] intermediate events.
//!
//! The names and codes are the one vocabulary of [`crate::end`]; a stride's stop means what it
//! means to the stride map ([`StrideStop::of`], [`StrideOutcome::end`]).
//!
//! `strides` is the number of completed strides (heel strikes) when the label was decided.
//! [`crate::attractors`] finds every attractor before a basin is computed, passes the periodic
//! ones as known orbits, and turns `other` (known orbit) and `timeout` (on a chaotic attractor)
//! into per-attractor codes from [`ATTRACTOR_CODE_BASE`] on.
//!
//! # Engine
//! [`BasinDriver`] is a [`LaneDriver`]: each cell is one work item; a lane integrates its cell's
//! strides back to back (the reset and classification happen in `on_stop`) and is refilled with
//! the next cell when the cell is classified, so many cells run as lanes of one lockstep batched
//! integration ([`run_batch_par`] on the caller's rayon pool). The engine guarantees that a
//! work item's arithmetic does not depend on its lane, its neighbours, the lane count, the chunk
//! size or the thread count, and equals the scalar integrator's; therefore
//! [`classify_cells`] gives identical results for any of those choices and for any split of
//! the cells into row blocks or shards, and equals [`classify_cells_scalar`] cell for cell.
//!
//! # Basin entropy (Daza, Wagemakers, Georgeot, Guéry-Odelin, Sanjuán 2016, Sci. Rep. 6:31416)
//! The grid is tiled by non-overlapping boxes of `ε × ε` cells (default ε = 5; boxes that would
//! stick out of the grid are left out). In box `i` let `p_{ij}` be the fraction of its cells with
//! outcome code `j`; its entropy is `S_i = Σ_j −p_{ij} ln p_{ij}` (natural log). The basin entropy
//! is `S_b = (1/N) Σ_i S_i` over all N boxes (their eq. 3), the boundary basin entropy
//! `S_bb = (1/N_b) Σ_i S_i` over the N_b boxes that hold more than one outcome (their eq. 4;
//! 0 when there is none). Every outcome code is its own class (fall kinds are distinct final
//! states).

use crate::error::LimitError;
use crate::stride::{StrideOutcome, StrideStop, MAX_EVENTS_PER_STRIDE};
use pdw_hybrid::{
    run_batch_par, run_scalar_with, BatchOptions, Control, FallKind, Integrator, LaneDriver,
    Options, Scratch, Section, StopReason,
};

/// The end of a cell: the one vocabulary of strides and cells ([`crate::end::End`]), whose
/// codes are those of `/basin/outcome`. A cell ends with one of [`Outcome::CELL_ENDS`], never at
/// [`Outcome::HeelStrike`] (a stride's end).
pub use crate::end::End as Outcome;

/// First outcome code of the attractors found besides the selected gait (see
/// [`crate::attractors`]): attractor `i` of them has code `ATTRACTOR_CODE_BASE + i`. Codes below
/// are the fixed [`Outcome`] codes (0–12 a cell's ends, 13 a stride's `heel_strike`, 14–15
/// kept for fall kinds to come).
pub const ATTRACTOR_CODE_BASE: u8 = 16;

/// `(code, name)` of every end a cell can have ([`Outcome::CELL_ENDS`]), by code: the legend of a
/// basin file.
pub fn legend() -> Vec<(u8, &'static str)> {
    Outcome::CELL_ENDS
        .iter()
        .map(|o| (o.code(), o.name()))
        .collect()
}

/// Options of the basin engine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BasinOptions {
    /// Integrator of the strides.
    pub integrator: Options,
    /// Lanes stepped in lockstep per batch.
    pub lanes: usize,
    /// Cells claimed at a time by a batch from the run's shared queue, and the granularity of
    /// the progress reports (results do not depend on it).
    pub chunk: usize,
    /// Stride budget per cell (≥ 1).
    pub max_strides: u16,
    /// Gait tolerance: `‖s_k − s*‖∞ < tol_gait` (section units).
    pub tol_gait: f64,
    /// Consecutive section states within `tol_gait` needed for `gait` (≥ 1).
    pub confirm: u8,
    /// Recurrence tolerance relative to the state's scale: `‖s_k − s_{k−p}‖∞ <
    /// tol_recur·σ(s_k)` ([`state_scale`]) means an attractor of period p.
    pub tol_recur: f64,
    /// Largest recurrence period tested (1..=16).
    pub max_period: u8,
}

impl Default for BasinOptions {
    /// DOP853 at `rtol = atol = 1e-9` (chosen from label agreement against tighter
    /// tolerances, see [`BasinOptions::default_integrator`]), 256 lanes, blocks of 1024 cells, 100 strides,
    /// `tol_gait = 1e-6`, `confirm = 2`, `tol_recur = 1e-10`, `max_period = 8`.
    fn default() -> Self {
        Self {
            integrator: Self::default_integrator(),
            lanes: 256,
            chunk: 1024,
            max_strides: 100,
            tol_gait: 1e-6,
            confirm: 2,
            tol_recur: 1e-10,
            max_period: 8,
        }
    }
}

impl BasinOptions {
    /// The default integrator for basins: DOP853 with `rtol = atol = 1e-9`.
    ///
    /// Measured on the simplest walker at γ = 0.009 (200 × 200 cells over θ ∈ [0.15, 0.25],
    /// θ̇ ∈ [−0.25, −0.15], 100 strides, 2 threads), labels changed against DOP853 at 1e-12:
    /// DOPRI5 1e-6: 5 cells (0.0125 %), 1e-7: 2, 1e-8: 1, 1e-9: 0 (1.7 s), 1e-10: 0 (3.0 s);
    /// DOP853 1e-7: 1 (0.7 s), 1e-9: 0 (1.0 s); RK4 h = 0.05: 3, h = 0.02: 0 (5.3 s).
    /// DOP853 at 1e-9 is the cheapest setting that changed no label (engine of 24 Nov).
    ///
    /// Measured again on 26 Nov, on the CLI's default grid (θ, θ̇ within 25 % of the gait),
    /// against DOP853 at 1e-14: one cell of 40 000 differs at 1e-9 (θ = 0.1769,
    /// θ̇ = −0.1835, on the boundary of the gait's basin: a forward fall after 21 strides, the
    /// gait after 42 at 1e-10 … 1e-14), none at 1e-10 (the test
    /// `default_basin_labels_against_a_dop853_1e14_reference` of pdw-sweep). On 1000 × 1000
    /// cells: 5 at 1e-9, 1 at 1e-10, 0 at 1e-11, every one on a boundary, for +19 % (1e-10)
    /// and +37 % (1e-11) of the CLI's time. The default stays at 1e-9: a label that flips with
    /// the tolerance belongs to a cell whose outcome a change at that level decides.
    ///
    /// With [`Options::warm_restart`]: every stride after a cell's first starts with the step the
    /// controller proposed at the heel strike, not with the starting-step heuristic (whose small
    /// first step and the rejection after the controller's largest growth cost two of the ten
    /// attempts of a simplest-walker stride at 1e-9). Measured: the 300 × 300 basin on one
    /// thread 0.52 s instead of 0.61 s, and the 200 × 200 labels identical cell for cell to the
    /// cold restarts'.
    pub fn default_integrator() -> Options {
        Options {
            warm_restart: true,
            ..Options::dop853(1e-9)
        }
    }

    /// Reject options the engine cannot honour.
    pub fn validate(&self) -> Result<(), LimitError> {
        let bad = |name, value: f64, allowed| {
            Err(LimitError::InvalidOption {
                name,
                value,
                allowed,
            })
        };
        self.integrator.validate()?;
        if self.lanes == 0 {
            return bad("lanes", 0.0, "must be >= 1");
        }
        if self.chunk == 0 {
            return bad("chunk", 0.0, "must be >= 1");
        }
        if self.max_strides == 0 {
            return bad("max_strides", 0.0, "must be >= 1");
        }
        if !(self.tol_gait.is_finite() && self.tol_gait > 0.0) {
            return bad("tol_gait", self.tol_gait, "must be finite and > 0");
        }
        if self.confirm == 0 {
            return bad("confirm", 0.0, "must be >= 1");
        }
        if !(self.tol_recur.is_finite() && self.tol_recur > 0.0 && self.tol_recur < self.tol_gait) {
            return bad(
                "tol_recur",
                self.tol_recur,
                "must be finite, > 0 and < tol_gait",
            );
        }
        if !(1..=16).contains(&self.max_period) {
            return bad(
                "max_period",
                f64::from(self.max_period),
                "must be in 1..=16",
            );
        }
        Ok(())
    }
}

/// The scale `σ(s) = min(1, ‖s‖∞)` of the relative recurrence and attractor tests (the scale
/// of Newton's acceptance test, [`crate::newton::residual_scale`]): absolute tolerances for
/// states of size 1 and more, relative ones for smaller states.
pub fn state_scale(s: &[f64]) -> f64 {
    crate::newton::residual_scale(s)
}

/// Strides over which [`walk_dies_out`] reads a cell's decay (the last `STANDSTILL_WINDOW + 1`
/// section states).
pub const STANDSTILL_WINDOW: usize = 16;

/// Largest local decay exponent of a walk that dies out ([`walk_dies_out`]).
pub const DYING_MAX_EXPONENT: f64 = 4.0;

/// The local decay exponent `m̂` of the scales `a` of consecutive section states (oldest
/// first, at least 3, an odd number), or `None` unless every stride shrinks the walker
/// (`0 ≤ a_{j+1} < a_j`, finite); `−∞` when the newest scale is 0.
///
/// A decay `a_{k+1} = a_k − c a_k^m` has the logarithmic rate `ln(a_k/a_{k+1}) ≈ c a_k^{m−1}`.
/// With `ρ₁ = ln(a_0/a_h)` and `ρ₂ = ln(a_h/a_{2h})` the log-shrinks of the window's two halves
/// (`h` strides each) and the halves' geometric-mean scales `√(a_0 a_h)`, `√(a_h a_{2h})`, whose
/// ratio is `e^{−(ρ₁+ρ₂)/2}`, the exponent is `m̂ = 1 − 2 ln(ρ₂/ρ₁)/(ρ₁ + ρ₂)`: 1 for a
/// geometric decay, 3 for the level-floor walker's `c a³` (module docs), below 1 for an
/// accelerating collapse. A walker converging to an orbit of scale `L > 0` instead,
/// `a_k − L ∝ λ^k` (0 < λ < 1), has `ρ₂/ρ₁ → λ^h` while its scale stops shrinking, so `m̂`
/// grows without bound.
pub fn decay_exponent(a: &[f64]) -> Option<f64> {
    let n = a.len();
    if n < 3 || n.is_multiple_of(2) || !a.iter().all(|v| v.is_finite() && *v >= 0.0) {
        return None;
    }
    if !a.windows(2).all(|w| w[1] < w[0]) {
        return None;
    }
    let (a0, ah, a2h) = (a[0], a[n / 2], a[n - 1]);
    if a2h == 0.0 {
        return Some(f64::NEG_INFINITY);
    }
    let (r1, r2) = ((a0 / ah).ln(), (ah / a2h).ln());
    Some(1.0 - 2.0 * (r2 / r1).ln() / (r1 + r2))
}

/// Whether the scales `a` of consecutive section states (oldest first) decay towards zero: the
/// walker shrinks at every stride and the decay's local exponent ([`decay_exponent`]) is at most
/// [`DYING_MAX_EXPONENT`]. A walker converging to an orbit of scale `L` passes only while
/// still far above it: with `a = L(1 + u)` at the window's newest state, `m̂ ≤ 4` needs
/// `u > 0.33` at λ = 0.999, `u > 0.31` at 0.99, `u > 0.13` at 0.9 (window of 16 strides) — not
/// a walker whose states recur to `tol_recur` or that creeps towards an orbit at the end of
/// its budget.
pub fn walk_dies_out(a: &[f64]) -> bool {
    decay_exponent(a).is_some_and(|m| m <= DYING_MAX_EXPONENT)
}

/// Whether a walker with the section states `hist` (oldest first, the newest last) has come to
/// a stand: the newest state is within `tol_gait` of the standing state `s = 0`, or the scales
/// `‖s‖∞` of the last [`STANDSTILL_WINDOW`] + 1 states decay towards zero
/// ([`walk_dies_out`]). See the module docs.
pub fn stands_still(hist: &[Vec<f64>], tol_gait: f64) -> bool {
    let Some(last) = hist.last() else {
        return false;
    };
    if last.iter().all(|v| v.abs() < tol_gait) {
        return true;
    }
    if hist.len() <= STANDSTILL_WINDOW {
        return false;
    }
    let a: Vec<f64> = hist[hist.len() - STANDSTILL_WINDOW - 1..]
        .iter()
        .map(|s| s.iter().fold(0.0f64, |m, v| m.max(v.abs())))
        .collect();
    walk_dies_out(&a)
}

/// What the cells are classified against.
pub struct BasinProblem<'a> {
    /// The model.
    pub sys: &'a dyn Section,
    /// The selected fixed point `s*` (section coordinates); empty when there is none (no cell
    /// is then labelled `gait`, e.g. past the first period doubling).
    pub gait: Vec<f64>,
    /// Other known attractors, each an orbit of section states (its period = its length).
    pub others: Vec<Vec<Vec<f64>>>,
    /// Outcome of a terminal guard's fall kind, usually `&Outcome::of_fall`.
    pub fall_outcome: &'a (dyn Fn(FallKind) -> Outcome + Sync),
}

impl<'a> BasinProblem<'a> {
    /// Problem with only the selected fixed point.
    pub fn new<S: Section + ?Sized>(
        sys: &'a S,
        gait: Vec<f64>,
        fall_outcome: &'a (dyn Fn(FallKind) -> Outcome + Sync),
    ) -> Self {
        Self {
            sys: sys.as_section(),
            gait,
            others: Vec::new(),
            fall_outcome,
        }
    }

    fn validate(&self) -> Result<(), LimitError> {
        let ds = self.sys.section_dim();
        let check = |v: &[f64]| {
            if v.len() != ds {
                Err(LimitError::SectionDim {
                    expected: ds,
                    got: v.len(),
                })
            } else if v.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(LimitError::InvalidOption {
                    name: "attractor",
                    value: f64::NAN,
                    allowed: "attractor states must be finite",
                })
            }
        };
        if !self.gait.is_empty() {
            check(&self.gait)?;
        }
        for orbit in &self.others {
            if orbit.is_empty() {
                return Err(LimitError::InvalidOption {
                    name: "others",
                    value: 0.0,
                    allowed: "a known attractor needs at least one point",
                });
            }
            for p in orbit {
                check(p)?;
            }
        }
        Ok(())
    }
}

/// Result of one cell.
#[derive(Clone, Debug, PartialEq)]
pub struct CellResult {
    /// [`Outcome`] code.
    pub outcome: u8,
    /// Completed strides when the label was decided.
    pub strides: u16,
    /// Period of the `other` attractor (recurrence period, or the known orbit's length); 0
    /// otherwise.
    pub period: u8,
    /// Index of the known attractor in [`BasinProblem::others`] for `other`, `u8::MAX` if it
    /// was detected by recurrence or the outcome is not `other`.
    pub attractor: u8,
    /// Last section state (after the last completed stride; for a fall, the projection of the
    /// state where the fall was detected).
    pub final_state: Vec<f64>,
}

impl CellResult {
    /// The outcome; an attractor code (≥ [`ATTRACTOR_CODE_BASE`], given by
    /// [`crate::attractors::AttractorSet::relabel`]) is an attractor other than the selected
    /// gait, [`Outcome::Other`].
    pub fn outcome(&self) -> Outcome {
        match Outcome::from_code(self.outcome) {
            Some(o) => o,
            None if self.outcome >= ATTRACTOR_CODE_BASE => Outcome::Other,
            None => Outcome::IntegratorFailure,
        }
    }
}

/// The basin [`LaneDriver`]: one item per cell (a section state), all strides of the cell in one
/// lane. Exposed so that other front ends can run it through [`pdw_hybrid::run_batch`] or
/// [`pdw_hybrid::run_scalar`] directly.
pub struct BasinDriver<'p, 'a> {
    problem: &'p BasinProblem<'a>,
    opts: BasinOptions,
    section_guard: (usize, usize),
    start_mode: usize,
    t_max: f64,
    ds: usize,
}

impl<'p, 'a> BasinDriver<'p, 'a> {
    /// Driver for `problem` (validated with `opts`).
    pub fn new(problem: &'p BasinProblem<'a>, opts: &BasinOptions) -> Result<Self, LimitError> {
        opts.validate()?;
        problem.validate()?;
        let sys = problem.sys;
        Ok(Self {
            problem,
            opts: *opts,
            section_guard: sys.section_guard(),
            start_mode: sys.section_mode(),
            t_max: sys.max_stride_time(),
            ds: sys.section_dim(),
        })
    }

    fn near(a: &[f64], b: &[f64], tol: f64) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < tol)
    }

    /// Classify after a new section state was pushed into the history. Returns the decision.
    fn classify(&self, lane: &mut BasinLane) -> Option<(Outcome, u8, u8)> {
        let ds = self.ds;
        let s = &lane.hist[lane.head * ds..(lane.head + 1) * ds];
        if !s.iter().all(|v| v.is_finite()) {
            return Some((Outcome::NonFinite, 0, u8::MAX));
        }
        let confirm = self.opts.confirm;
        if !self.problem.gait.is_empty() && Self::near(s, &self.problem.gait, self.opts.tol_gait) {
            lane.near_gait = lane.near_gait.saturating_add(1);
            if lane.near_gait >= confirm {
                return Some((Outcome::Gait, 0, u8::MAX));
            }
            // Approaching the gait: neither a recurrence nor another attractor.
            return None;
        }
        lane.near_gait = 0;
        for (a, orbit) in self.problem.others.iter().enumerate() {
            if orbit.iter().any(|p| Self::near(s, p, self.opts.tol_gait)) {
                lane.near_other[a.min(MAX_KNOWN - 1)] =
                    lane.near_other[a.min(MAX_KNOWN - 1)].saturating_add(1);
                if lane.near_other[a.min(MAX_KNOWN - 1)] >= confirm {
                    let period = orbit.len().min(255) as u8;
                    return Some((Outcome::Other, period, a.min(254) as u8));
                }
            } else {
                lane.near_other[a.min(MAX_KNOWN - 1)] = 0;
            }
        }
        let max_p = usize::from(self.opts.max_period).min(HIST - 1);
        let sigma = state_scale(s);
        let mut found = None;
        for p in 1..=max_p {
            if p >= lane.count {
                lane.recur[p] = 0;
                continue;
            }
            let q = &lane.hist[Self::slot(lane.head, p) * ds..(Self::slot(lane.head, p) + 1) * ds];
            if Self::near(s, q, self.opts.tol_recur * sigma) {
                lane.recur[p] = lane.recur[p].saturating_add(1);
                if found.is_none() && lane.recur[p] >= confirm {
                    found = Some(p);
                }
            } else {
                lane.recur[p] = 0;
            }
        }
        let p = found?;
        // A walker that stands still is not on an attractor.
        if self.stands_still(lane) {
            return Some((Outcome::Fall, 0, u8::MAX));
        }
        // Minimal period: the smallest divisor q of p whose shift also returns within
        // tol_gait·σ (a period-p recurrence of a period-q orbit, q | p).
        let period = (1..p)
            .filter(|q| p % q == 0 && *q < lane.count)
            .find(|&q| {
                let r =
                    &lane.hist[Self::slot(lane.head, q) * ds..(Self::slot(lane.head, q) + 1) * ds];
                Self::near(s, r, self.opts.tol_gait * sigma)
            })
            .unwrap_or(p);
        Some((Outcome::Other, period as u8, u8::MAX))
    }

    /// [`stands_still`] on the lane's history (at most [`HIST`] states, oldest first).
    fn stands_still(&self, lane: &BasinLane) -> bool {
        let ds = self.ds;
        let n = lane.count.min(HIST);
        let hist: Vec<Vec<f64>> = (0..n)
            .rev()
            .map(|p| {
                let k = Self::slot(lane.head, p);
                lane.hist[k * ds..(k + 1) * ds].to_vec()
            })
            .collect();
        stands_still(&hist, self.opts.tol_gait)
    }

    /// Ring slot of the state `p` strides before the newest.
    fn slot(head: usize, p: usize) -> usize {
        (head + HIST - p) % HIST
    }

    /// Push `Π(x)` into the lane's history ring.
    fn push(&self, hist: &mut [f64], head: &mut usize, count: &mut usize, x: &[f64]) {
        let ds = self.ds;
        *head = (*head + 1) % HIST;
        *count += 1;
        self.problem
            .sys
            .project(x, &mut hist[*head * ds..(*head + 1) * ds]);
    }
}

/// Ring size of the section-state history (periods up to 16; the standing-still window).
const HIST: usize = STANDSTILL_WINDOW + 1;
/// Known other attractors tracked separately for `confirm` (more share the last slot).
const MAX_KNOWN: usize = 8;

/// Per-lane bookkeeping of the [`BasinDriver`].
#[derive(Default)]
pub struct BasinLane {
    /// Ring of the last `HIST` section states, `(HIST × d_s)` row-major.
    hist: Vec<f64>,
    /// Slot of the newest state.
    head: usize,
    /// Section states seen (s₀ included).
    count: usize,
    /// Reset output `(d)`.
    buf: Vec<f64>,
    /// Consecutive states within `tol_gait` of `s*`.
    near_gait: u8,
    /// Same for the known other attractors.
    near_other: [u8; MAX_KNOWN],
    /// Consecutive recurrences `‖s_k − s_{k−p}‖∞ < tol_recur`, per p.
    recur: [u8; HIST],
    /// Intermediate events in the current stride.
    events: usize,
    strides: u16,
    decided: Option<(Outcome, u8, u8)>,
}

impl<'a> LaneDriver<dyn Section + 'a> for BasinDriver<'_, 'a> {
    type Item = Vec<f64>;
    type Output = CellResult;
    type Lane = BasinLane;

    fn start(
        &self,
        sys: &(dyn Section + 'a),
        item: &Vec<f64>,
        lane: &mut BasinLane,
        x: &mut [f64],
    ) -> (usize, f64) {
        let ds = self.ds;
        lane.hist.resize(HIST * ds, 0.0);
        lane.buf.resize(sys.dim(), 0.0);
        lane.head = 0;
        lane.count = 1;
        let n = item.len().min(ds);
        lane.hist[..n].copy_from_slice(&item[..n]);
        if item.len() != ds || !item.iter().all(|v| v.is_finite()) {
            // Not a valid section state: the engine stops at once (NonFinite) and `on_stop`
            // records the decision taken here.
            lane.decided = Some((Outcome::NonFinite, 0, u8::MAX));
            x.fill(f64::NAN);
            return (self.start_mode, self.t_max);
        }
        sys.lift(item, x);
        lane.decided = self.classify(lane);
        if lane.decided.is_some() {
            // Decided before any stride (only possible with confirm = 1): stop immediately.
            x.fill(f64::NAN);
        }
        (self.start_mode, self.t_max)
    }

    fn on_stop(
        &self,
        sys: &(dyn Section + 'a),
        ws: &mut Scratch,
        _item: &Vec<f64>,
        lane: &mut BasinLane,
        stop: StopReason,
        mode: usize,
        t: f64,
        x: &mut [f64],
    ) -> Control {
        if lane.decided.is_some() {
            return Control::Finish;
        }
        // The stride's stops as the stride map reads them ([`StrideStop::of`]); the cell's
        // end is the stride's ([`StrideOutcome::end`]), a fall's through the problem's
        // `fall_outcome`.
        let outcome = match StrideStop::of(stop, sys.guards(mode)) {
            StrideStop::Reset { guard } => {
                let new_mode = sys.reset(ws, mode, guard, x, &mut lane.buf);
                if (mode, guard) == self.section_guard {
                    lane.events = 0;
                    lane.strides = lane.strides.saturating_add(1);
                    self.push(&mut lane.hist, &mut lane.head, &mut lane.count, &lane.buf);
                    let ds = self.ds;
                    let h = lane.head;
                    sys.lift(&lane.hist[h * ds..(h + 1) * ds], x);
                    if let Some(d) = self.classify(lane) {
                        lane.decided = Some(d);
                        return Control::Finish;
                    }
                    if lane.strides >= self.opts.max_strides {
                        let o = if self.stands_still(lane) {
                            Outcome::Fall
                        } else {
                            Outcome::Timeout
                        };
                        lane.decided = Some((o, 0, u8::MAX));
                        return Control::Finish;
                    }
                    return Control::Continue {
                        mode: self.start_mode,
                        t_end: t + self.t_max,
                    };
                } else if lane.events >= MAX_EVENTS_PER_STRIDE {
                    StrideOutcome::TooManyEvents.end()
                } else {
                    lane.events += 1;
                    x.copy_from_slice(&lane.buf);
                    return Control::Continue {
                        mode: new_mode,
                        t_end: t + self.t_max,
                    };
                }
            }
            StrideStop::End(StrideOutcome::Fall { kind, .. }) => (self.problem.fall_outcome)(kind),
            StrideStop::End(o) => o.end(),
        };
        // Record where the fall happened (projection of the stop state).
        self.push(&mut lane.hist, &mut lane.head, &mut lane.count, x);
        lane.decided = Some((outcome, 0, u8::MAX));
        Control::Finish
    }

    fn finish(
        &self,
        _sys: &(dyn Section + 'a),
        _item: &Vec<f64>,
        lane: BasinLane,
        _t: f64,
        _x: &[f64],
    ) -> CellResult {
        let (outcome, period, attractor) = lane.decided.unwrap_or((Outcome::NonFinite, 0, u8::MAX));
        let ds = self.ds;
        let h = lane.head;
        let final_state = if lane.hist.len() >= (h + 1) * ds {
            lane.hist[h * ds..(h + 1) * ds].to_vec()
        } else {
            vec![f64::NAN; ds]
        };
        CellResult {
            outcome: outcome.code(),
            strides: lane.strides,
            period,
            attractor,
            final_state,
        }
    }
}

/// Classify every cell (section states of the model's section dimension), batched on `pool`
/// (see the module docs); `progress(n_done)` is called as blocks of `chunk` cells finish. Results in cell order,
/// identical for any thread count, lane count, chunk size and split of `cells`.
pub fn classify_cells(
    problem: &BasinProblem<'_>,
    cells: &[Vec<f64>],
    opts: &BasinOptions,
    pool: &rayon::ThreadPool,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Vec<CellResult>, LimitError> {
    let driver = BasinDriver::new(problem, opts)?;
    let bopts = BatchOptions {
        lanes: opts.lanes,
        integrator: opts.integrator,
    };
    Ok(run_batch_par(
        problem.sys,
        &driver,
        cells,
        &bopts,
        pool,
        opts.chunk,
        progress,
    )?)
}

/// The slow reference path: one cell at a time through the scalar integrator
/// ([`pdw_hybrid::run_scalar_with`]), serial.
pub fn classify_cells_scalar(
    problem: &BasinProblem<'_>,
    cells: &[Vec<f64>],
    opts: &BasinOptions,
) -> Result<Vec<CellResult>, LimitError> {
    let driver = BasinDriver::new(problem, opts)?;
    let mut integ = Integrator::new(problem.sys.dim(), opts.integrator)?;
    cells
        .iter()
        .map(|c| Ok(run_scalar_with(&mut integ, problem.sys, &driver, c)?))
        .collect()
}

/// Cells of a grid over section coordinates `ix` (values `xs`) and `iy` (values `ys`), the
/// other coordinates taken from `base`; row-major with the row = y index (`cells[i·nx + j]` is
/// `(xs[j], ys[i])`), the layout of `/basin/outcome [ny, nx]`.
pub fn grid_cells(base: &[f64], ix: usize, xs: &[f64], iy: usize, ys: &[f64]) -> Vec<Vec<f64>> {
    let mut cells = Vec::with_capacity(xs.len() * ys.len());
    for &y in ys {
        for &x in xs {
            let mut c = base.to_vec();
            c[ix] = x;
            c[iy] = y;
            cells.push(c);
        }
    }
    cells
}

/// `n` evenly spaced values from `a` to `b` inclusive (`a` alone when `n = 1`).
pub fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    if n == 1 {
        return vec![a];
    }
    (0..n)
        .map(|i| {
            if i + 1 == n {
                b
            } else {
                a + (b - a) * (i as f64) / ((n - 1) as f64)
            }
        })
        .collect()
}

/// Fractions and basin entropies of a classified grid.
#[derive(Clone, Debug, PartialEq)]
pub struct BasinMetrics {
    /// `(code, name, fraction of cells)` for every outcome in the legend (zeros included).
    pub fractions: Vec<(u8, &'static str, f64)>,
    /// Basin entropy S_b (Daza et al. 2016 eq. 3), natural log.
    pub basin_entropy: f64,
    /// Boundary basin entropy S_bb (Daza et al. 2016 eq. 4); 0 if no box holds two outcomes.
    pub boundary_entropy: f64,
    /// Box side ε in cells.
    pub box_size: usize,
    /// Number of boxes N.
    pub boxes: usize,
    /// Boxes holding more than one outcome, N_b.
    pub boundary_boxes: usize,
}

/// Default entropy box side (cells): 5 × 5 boxes, small enough to resolve the boundary of a
/// 100 × 100 grid with 400 boxes, large enough that a box holds 25 samples.
pub const DEFAULT_ENTROPY_BOX: usize = 5;

/// Fractions per outcome and basin entropy of `outcomes` (row-major `[ny, nx]`) with boxes of
/// `box_size × box_size` cells (see the module docs).
pub fn basin_metrics(
    outcomes: &[u8],
    nx: usize,
    ny: usize,
    box_size: usize,
) -> Result<BasinMetrics, LimitError> {
    if outcomes.len() != nx * ny || nx == 0 || ny == 0 {
        return Err(LimitError::InvalidOption {
            name: "outcomes",
            value: outcomes.len() as f64,
            allowed: "must hold nx·ny > 0 codes",
        });
    }
    if box_size == 0 {
        return Err(LimitError::InvalidOption {
            name: "box_size",
            value: 0.0,
            allowed: "must be >= 1",
        });
    }
    let n = outcomes.len() as f64;
    let mut counts = [0usize; 256];
    for &o in outcomes {
        counts[o as usize] += 1;
    }
    let mut fractions: Vec<(u8, &'static str, f64)> = Outcome::CELL_ENDS
        .iter()
        .map(|o| (o.code(), o.name(), counts[o.code() as usize] as f64 / n))
        .collect();
    for (c, &k) in counts.iter().enumerate() {
        if k > 0 && !Outcome::from_code(c as u8).is_some_and(Outcome::is_cell_end) {
            fractions.push((c as u8, "unknown", k as f64 / n));
        }
    }
    let (bx, by) = (nx / box_size, ny / box_size);
    let (mut sum, mut sum_b, mut nb) = (0.0, 0.0, 0usize);
    let m = (box_size * box_size) as f64;
    for bi in 0..by {
        for bj in 0..bx {
            let mut c = [0u32; 256];
            for i in bi * box_size..(bi + 1) * box_size {
                for j in bj * box_size..(bj + 1) * box_size {
                    c[outcomes[i * nx + j] as usize] += 1;
                }
            }
            let mut s = 0.0;
            let mut kinds = 0;
            for &k in c.iter().filter(|&&k| k > 0) {
                let p = f64::from(k) / m;
                s -= p * p.ln();
                kinds += 1;
            }
            sum += s;
            if kinds > 1 {
                sum_b += s;
                nb += 1;
            }
        }
    }
    let boxes = bx * by;
    Ok(BasinMetrics {
        fractions,
        basin_entropy: if boxes > 0 { sum / boxes as f64 } else { 0.0 },
        boundary_entropy: if nb > 0 { sum_b / nb as f64 } else { 0.0 },
        box_size,
        boxes,
        boundary_boxes: nb,
    })
}

/// [`basin_metrics`] of a 3-D grid of `nz` slices of `ny × nx` cells (`outcomes` slice by
/// slice, each row-major): the fractions over every cell, and the basin entropies of Daza et
/// al. 2016 (Sci. Rep. 6:31416, eqs. 3–4) over the `box_size × box_size` boxes of every
/// z-slice pooled — S_b the mean over all of them, S_bb over all that hold more than one
/// outcome. With `nz = 1` it is [`basin_metrics`].
pub fn basin_metrics_slices(
    outcomes: &[u8],
    nx: usize,
    ny: usize,
    nz: usize,
    box_size: usize,
) -> Result<BasinMetrics, LimitError> {
    if nz == 0 || outcomes.len() != nx * ny * nz {
        return Err(LimitError::InvalidOption {
            name: "outcomes",
            value: outcomes.len() as f64,
            allowed: "must hold nx·ny·nz > 0 codes",
        });
    }
    if nz == 1 {
        return basin_metrics(outcomes, nx, ny, box_size);
    }
    let mut all = basin_metrics(outcomes, nx, ny * nz, box_size)?;
    let (mut sum, mut sum_b, mut boxes, mut nb) = (0.0, 0.0, 0, 0);
    for slice in outcomes.chunks(nx * ny) {
        let m = basin_metrics(slice, nx, ny, box_size)?;
        sum += m.basin_entropy * m.boxes as f64;
        sum_b += m.boundary_entropy * m.boundary_boxes as f64;
        boxes += m.boxes;
        nb += m.boundary_boxes;
    }
    all.basin_entropy = if boxes > 0 { sum / boxes as f64 } else { 0.0 };
    all.boundary_entropy = if nb > 0 { sum_b / nb as f64 } else { 0.0 };
    all.boxes = boxes;
    all.boundary_boxes = nb;
    Ok(all)
}
