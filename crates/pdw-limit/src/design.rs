//! Design search: which values of a walker's free design parameters give a stable, physically
//! valid and robust passive gait (Schwab & Wisse 2001: the most robust design has the largest
//! basin of attraction).
//!
//! # One design
//! [`evaluate_design`] takes a built walker (the design) and:
//! 1. finds its period-one gaits by Newton from the given guesses ([`crate::gaits::search`]) and
//!    keeps the one with the smallest largest multiplier modulus `ρ = max |λ|`;
//! 2. walks one stride of it ([`crate::simulate`]) and locates the constraint loads, the
//!    swing-foot clearance and the impacts on the dense solution ([`crate::Validity::along`],
//!    [`crate::validity`]): the stance normal force must stay positive, the friction needed
//!    `|f_t/f_n|` (along the flow and at every impact) at most `mu`, every locked knee's lock
//!    torque at least `knee_margin` (a passive hyper-extension stop can only push: the margin
//!    is the torque it must have in hand), the swing foot clear of the ground where the model's
//!    clearance rule checks it, every impact physical (no pulling contact or stop), every
//!    criterion's margin relative to its natural scale at least `min_margin`, and — with a
//!    free-swing knee — a knee strike before the heel strike;
//! 3. scores it ([`graded_cost`]). Feasible designs (stable, valid, every relative margin at
//!    least `min_margin`) get the objective: `margin` — `ρ` (smaller is better); `basin` — minus
//!    the fraction of a box of section states around the gait that walk into it
//!    ([`crate::classify_cells`] on a coarse grid; the box is `stance ± Δ₀`,
//!    `stance_rate ± Δ₁`, `hip_rate` at the gait's; `Δ` given, or by default scaled to the
//!    gait, `Δ = 0.15 · (|stance|, |stance_rate|)`, [`basin_box`]), plus `1e-3·ρ` to break ties
//!    between equal coarse fractions.
//!
//! # How close to valid: the graded cost
//! Every other design is graded in both directions, so that a local method climbs towards
//! validity instead of meeting a plateau. For a gait, its *shortfall* `d ≥ 0` ([`Shortfall`]):
//!
//! ```text
//! d = max(0, min_margin − r_b)                        r_b the binding relative margin
//!   + max(0, μ_req − μ) / μ                           flow and impacts, the larger
//!   + max(0, knee_margin − τ_min) / (m g l)           the knee-lock torque asked for
//!   + 0.5 · (falls, no knee strike, not re-walkable)   discrete failures without a margin
//! ```
//!
//! (`r_b` is [`Validity::binding`]'s relative margin, negative when a criterion fails, on the
//! natural scales of [`crate::validity`]; `m g l` from [`pdw_model::Scales`]). Then, with
//! `ρ = max |λ|`:
//!
//! ```text
//! stable, d > 0 (invalid):   1 + 3 δ / (1 + δ) + 0.5 ρ                  in [1, 4.5)
//! unstable (ρ ≥ 1):          5 + 2 (1 − 1/ρ) + 2 δ / (1 + δ)           in [5, 9)
//! no gait:                   9 + 0.5 (1 − n / N) + 0.5 q / (1 + q)     in [9, 10]
//! not a model:               11
//! ```
//!
//! with `δ = d / u` the shortfall in units of `u` = [`SHORTFALL_UNIT`] (one per cent of the
//! natural scales, the margin asked by default). On that unit a shortfall of a per cent weighs
//! as much as the stability term at `ρ = 1`, so a local run trades the margin for stability
//! only where the margin is nearly met: with `d` unscaled (as before) a 2 % pull cost 0.06
//! against `0.5 ρ`'s 0.3, and the runs bought smaller `ρ` with a larger pull.
//!
//! Where, without a gait, every guess is iterated up to `N` = [`PROBE_STRIDES`] strides
//! ([`probe`]): `n` is the most strides any guess walked before its stride ended otherwise than
//! at a heel strike, and `q` the smallest relative stride-to-stride change
//! `‖P(x) − x‖∞ / (1 + ‖x‖∞)` met along the way (the fixed-point residual Newton drives to 0;
//! when no stride completed, `q = 1 + b` where the first stride buckles a knee, `b` the flexion
//! rate over `√(g / l)` at which its fatal impact releases the knee stops (0 where a stop would
//! begin to hold: how far the stop is from holding), and `q = ∞` for every other end). Each band is increasing in `d`, `ρ` and `q` and
//! decreasing in `n`, and every band lies above the ones nearer to feasible. How the guesses
//! ended is kept with the design ([`DesignEval::fates`], e.g. `4 starts: 3 stance knee
//! buckled, 1 fell forward`), and the binding criterion's name ([`DesignEval::binding`]).
//!
//! # The search
//! [`search`] is one local run: it evaluates the start (the model's own values of the free
//! parameters, or the centre of the bounds) and `init` seeded random designs, then runs
//! argmin's Nelder–Mead (Nelder & Mead 1965) over the free parameters scaled to the unit cube
//! `[0, 1]ᵏ` (a point outside it costs `20 + distance` and is not evaluated) from the best
//! design so far with an initial simplex of edge 0.25 (its `k + 1` vertices evaluated before
//! the solver starts: a budget that runs out among them ends the run there); when the simplex
//! collapses (standard deviation of its costs below 1e-6) with budget left, it restarts from
//! the best design found with half the edge. Every evaluated design goes through a cache keyed
//! by its exact parameter bits, so that a rerun over a stored history replays the same
//! deterministic sequence at no cost and continues where the stored run stopped (resumable),
//! and the same seed gives the same designs (reproducible). Guesses for a design's gait: the
//! model's own, then the gaits of the (at most 3) nearest designs of the run's history with a
//! gait (in the unit cube), nearest first.
//!
//! [`search_multi`] is the global search: `R` such runs (a multi-start), run 0 as above and
//! run `r ≥ 1` from the seeded random design `init + r − 1` of the same sequence, without
//! random designs of its own; the budget is shared out evenly (the first `B mod R` runs one
//! more). The runs are independent — each sees only its own designs, for its cache and its
//! guesses — and run on the caller's pool, so the result, returned run by run in each run's
//! evaluation order, is the same on any number of threads; a stored history is split by
//! [`DesignEval::run`] and each run replays its own.

use crate::basin::{classify_cells, grid_cells, linspace, BasinOptions, BasinProblem, Outcome};
use crate::error::LimitError;
use crate::gaits::{default_integrator, search as gait_search};
use crate::stride::StrideMap;
use crate::trajectory::{simulate, TrajectoryOptions, Validity};
use argmin::core::{CostFunction, Error as ArgminError, Executor};
use argmin::solver::neldermead::NelderMead;
use pdw_model::Walker;
use std::cell::RefCell;

/// What a feasible design is scored by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Objective {
    /// Fraction of a box of section states around the gait that reaches it (larger is
    /// better).
    Basin,
    /// Largest multiplier modulus (smaller is better).
    Margin,
}

impl Objective {
    pub fn name(self) -> &'static str {
        match self {
            Objective::Basin => "basin",
            Objective::Margin => "margin",
        }
    }
}

/// Options of a design evaluation and search.
#[derive(Clone, Debug)]
pub struct DesignOptions {
    pub objective: Objective,
    /// Largest friction coefficient the ground supplies.
    pub mu: f64,
    /// Smallest knee-lock torque a passive stop must be left with (N m, ≥ 0).
    pub knee_margin: f64,
    /// Smallest relative margin every validity criterion must keep ([`Validity::margins`]:
    /// each margin over its natural scale); 0 (the default) is the criteria's sign tests.
    pub min_margin: f64,
    /// Designs evaluated (cached replays included).
    pub budget: usize,
    /// Seed of the initial random designs.
    pub seed: u64,
    /// Start of the search (parameter values; clamped into the bounds); `None`: the centre.
    pub start: Option<Vec<f64>>,
    /// Seeded random designs evaluated after the start, before Nelder–Mead (which then starts
    /// from the best design so far).
    pub init: usize,
    /// Basin grid: `n × n` cells over the box (objective `basin`).
    pub basin_grid: usize,
    /// Half widths of the basin box in `stance` (rad) and `stance_rate` (rad/s); `None`: scaled
    /// to each design's gait ([`basin_box`]).
    pub basin_box: Option<[f64; 2]>,
    /// Basin engine options (coarse: fewer strides than a basin map).
    pub basin: BasinOptions,
    /// Newton residual tolerance of the gait search.
    pub newton_tol: f64,
}

/// Status codes of an evaluated design (stored in the file; never renumbered).
pub mod status {
    pub const FEASIBLE: u8 = 0;
    pub const INVALID: u8 = 1;
    pub const UNSTABLE: u8 = 2;
    pub const NO_GAIT: u8 = 3;
    pub const BAD_MODEL: u8 = 4;
    /// Names by code.
    pub const NAMES: [&str; 5] = ["feasible", "invalid", "unstable", "no_gait", "bad_model"];
}

/// One evaluated design.
#[derive(Clone, Debug, PartialEq)]
pub struct DesignEval {
    /// Free parameter values (in the search's order).
    pub params: Vec<f64>,
    /// [`status`] code.
    pub status: u8,
    /// What failed (empty when feasible).
    pub reason: String,
    /// The minimised cost (see the module docs).
    pub cost: f64,
    /// Basin fraction (objective `basin`, feasible designs) or NaN.
    pub basin_fraction: f64,
    /// Largest multiplier modulus of the gait, NaN without a gait.
    pub rho: f64,
    /// Gait `(stance, stance_rate, hip_rate)`, NaN without a gait.
    pub section: [f64; 3],
    /// Smallest normal force, largest friction needed, smallest knee-lock torque (NaN when not
    /// measured or without locked knees).
    pub min_normal_force: f64,
    pub max_friction: f64,
    pub min_knee_torque: f64,
    /// Period (s) and step length of the gait (NaN without).
    pub period: f64,
    pub step_length: f64,
    /// The smallest relative margin of the validity criteria (the binding one's,
    /// [`Validity::binding`]); NaN when not measured.
    pub min_relative_margin: f64,
    /// Half widths of the basin box the fraction was measured in (`stance`, `stance_rate`);
    /// NaN when not measured.
    pub basin_box: [f64; 2],
    /// The binding validity criterion's name ([`crate::validity::Margin::name`]); empty when
    /// not measured.
    pub binding: String,
    /// The shortfall `d` of the graded cost (module docs); NaN without a gait.
    pub shortfall: f64,
    /// Without a gait: the most strides any guess walked ([`probe`], at most
    /// [`PROBE_STRIDES`]) and the smallest relative stride-to-stride change met (NaN with a
    /// gait; infinite when no stride completed).
    pub strides_survived: f64,
    pub probe_residual: f64,
    /// Without a gait: how the guesses ended, by fate (`4 starts: 3 stance knee buckled, 1
    /// fell forward`); empty with a gait.
    pub fates: String,
    /// The search run that evaluated it ([`search_multi`]; 0 for a single run).
    pub run: u32,
}

impl DesignEval {
    fn failed(params: &[f64], status: u8, reason: String, cost: f64) -> Self {
        Self {
            params: params.to_vec(),
            status,
            reason,
            cost,
            basin_fraction: f64::NAN,
            rho: f64::NAN,
            section: [f64::NAN; 3],
            min_normal_force: f64::NAN,
            max_friction: f64::NAN,
            min_knee_torque: f64::NAN,
            period: f64::NAN,
            step_length: f64::NAN,
            min_relative_margin: f64::NAN,
            basin_box: [f64::NAN; 2],
            binding: String::new(),
            shortfall: f64::NAN,
            strides_survived: f64::NAN,
            probe_residual: f64::NAN,
            fates: String::new(),
            run: 0,
        }
    }

    /// A design whose parameters do not make a model (`reason`: the model's error).
    pub fn bad_model(params: &[f64], reason: String) -> Self {
        Self::failed(params, status::BAD_MODEL, reason, COST_BAD_MODEL)
    }

    /// Stable and physically valid.
    pub fn feasible(&self) -> bool {
        self.status == status::FEASIBLE
    }
}

/// Factor of the gait-scaled basin box: half widths `BASIN_BOX_SCALE · (|stance|,
/// |stance_rate|)` of the gait's section ([`basin_box`]). Chosen on the Goswami compass preset
/// (15 × 15 cells, 40 strides): factors 0.05, 0.1, 0.15, 0.2, 0.3 give it basin fractions
/// 0.93, 0.72, 0.50, 0.35, 0.17; 0.15 puts it mid-range, where designs can gain or lose.
pub const BASIN_BOX_SCALE: f64 = 0.15;

/// The basin box's half widths about the gait `section` (`stance`, `stance_rate` first): the
/// options' fixed box, else [`BASIN_BOX_SCALE`] times the gait's `|stance|` and
/// `|stance_rate|`, so that designs with larger or faster strides are perturbed in proportion
/// (a fixed box that is large for one gait and small for another measures the box, not the
/// basin). A zero component falls back to the default fixed box's (0.02 rad, 0.08 rad/s).
pub fn basin_box(opts: &DesignOptions, section: &[f64]) -> [f64; 2] {
    if let Some(b) = opts.basin_box {
        return b;
    }
    let scaled = |v: f64, fallback: f64| {
        let h = BASIN_BOX_SCALE * v.abs();
        if h.is_finite() && h > 0.0 {
            h
        } else {
            fallback
        }
    };
    [scaled(section[0], 0.02), scaled(section[1], 0.08)]
}

/// Cost of a design whose parameters do not make a model.
pub const COST_BAD_MODEL: f64 = 11.0;

/// Strides each guess of a design without a gait is iterated ([`probe`]): the `N` of the
/// no-gait band of the graded cost.
pub const PROBE_STRIDES: usize = 10;

/// Weight of one discrete failure (a fall, no knee strike, a stride that cannot be re-walked)
/// in the shortfall.
pub const DISCRETE_FAILURE: f64 = 0.5;

/// What a gait lacks to be feasible, criterion by criterion (module docs; every part ≥ 0).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Shortfall {
    /// `max(0, min_margin − r_b)`, `r_b` the binding relative margin.
    pub margin: f64,
    /// `max(0, μ_req − μ) / μ`.
    pub friction: f64,
    /// `max(0, knee_margin − τ_min) / (m g l)`.
    pub knee: f64,
    /// Discrete failures without a margin (falls, no knee strike, not re-walkable).
    pub discrete: usize,
}

impl Shortfall {
    /// The shortfall from the quantities it is built of: the binding relative margin `r_b`
    /// (NaN: none measured, no part), the required `min_margin`, the friction needed `mu_req`
    /// and supplied `mu`, the smallest knee-lock torque `tau` (NaN: no locked knee) and the
    /// required `knee_margin` on the torque scale `mgl`, and the discrete failures.
    pub fn of(
        (r_b, min_margin): (f64, f64),
        (mu_req, mu): (f64, f64),
        (tau, knee_margin, mgl): (f64, f64, f64),
        discrete: usize,
    ) -> Self {
        let pos = |x: f64| if x.is_finite() && x > 0.0 { x } else { 0.0 };
        Self {
            margin: pos(min_margin - r_b),
            friction: pos((mu_req - mu) / mu),
            knee: pos((knee_margin - tau) / mgl),
            discrete,
        }
    }

    /// `d`, the sum of the parts.
    pub fn total(&self) -> f64 {
        self.margin + self.friction + self.knee + DISCRETE_FAILURE * self.discrete as f64
    }
}

/// What the graded cost of a design is computed from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Grade {
    /// A gait with largest multiplier modulus `rho` and shortfall `d` (infeasible when
    /// `rho ≥ 1` or `d > 0`; a feasible one costs its objective instead).
    Gait { rho: f64, d: f64 },
    /// No gait: the most strides `n` any guess walked of `of` and the smallest relative
    /// stride-to-stride change `q` (∞ when no stride completed).
    NoGait { n: usize, of: usize, q: f64 },
    /// The parameters make no model.
    BadModel,
}

/// The unit of a gait's shortfall in the graded cost: one per cent of the natural scales (the
/// default `--min-margin`), module docs.
pub const SHORTFALL_UNIT: f64 = 0.01;

/// The graded cost of an infeasible design (the bands of the module docs).
pub fn graded_cost(g: Grade) -> f64 {
    let squash = |x: f64| if x.is_finite() { x / (1.0 + x) } else { 1.0 };
    match g {
        Grade::Gait { rho, d } if rho < 1.0 => 1.0 + 3.0 * squash(d / SHORTFALL_UNIT) + 0.5 * rho,
        Grade::Gait { rho, d } => 5.0 + 2.0 * (1.0 - 1.0 / rho) + 2.0 * squash(d / SHORTFALL_UNIT),
        Grade::NoGait { n, of, q } => {
            let walked = n.min(of) as f64 / of.max(1) as f64;
            9.0 + 0.5 * (1.0 - walked) + 0.5 * squash(q)
        }
        Grade::BadModel => COST_BAD_MODEL,
    }
}

/// How each guess of a design without a gait fares when the stride map is iterated from it.
#[derive(Clone, Debug, PartialEq)]
pub struct Probe {
    /// The most strides any guess walked (at most [`PROBE_STRIDES`]).
    pub strides: usize,
    /// The smallest relative stride-to-stride change `‖P(x) − x‖∞ / (1 + ‖x‖∞)` met; where
    /// no stride completed, `1 +` the released knee stops' flexion rate of a first stride that
    /// buckles a knee, else ∞ (module docs).
    pub residual: f64,
    /// The guesses by fate: a stride's end ([`crate::StrideOutcome`]'s words, e.g. `stance knee
    /// buckled`), `walked N strides` for one that did not fall, `the stride map failed`.
    pub fates: Vec<(String, usize)>,
}

/// Iterates the stride map of `walker` up to [`PROBE_STRIDES`] strides from every guess
/// (integrator of the gait search at residual tolerance `tol`).
pub fn probe(walker: &dyn Walker, guesses: &[(String, Vec<f64>)], tol: f64) -> Probe {
    let mut out = Probe {
        strides: 0,
        residual: f64::INFINITY,
        fates: Vec::new(),
    };
    let step = |x: &[f64]| walker.step_length(x);
    let map = match StrideMap::new(walker, default_integrator(tol)) {
        Ok(m) => m.with_step_length(&step),
        Err(_) => {
            out.fates
                .push(("the stride map failed".into(), guesses.len()));
            return out;
        }
    };
    let mut tally: Vec<(String, usize)> = Vec::new();
    for (_, g) in guesses {
        let mut x = g.clone();
        let mut walked = 0;
        let mut fate = format!("walked {PROBE_STRIDES} strides without settling");
        for _ in 0..PROBE_STRIDES {
            match map.stride(&x) {
                Ok(st) if st.outcome.is_ok() && st.next.iter().all(|v| v.is_finite()) => {
                    let norm = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    let change = x
                        .iter()
                        .zip(&st.next)
                        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                    out.residual = out.residual.min(change / (1.0 + norm));
                    walked += 1;
                    x = st.next;
                }
                Ok(st) => {
                    fate = st.outcome.to_string();
                    if walked == 0 {
                        if let Some(b) = buckle_rate(walker, &st) {
                            out.residual = out.residual.min(1.0 + b);
                        }
                    }
                    break;
                }
                Err(_) => {
                    fate = "the stride map failed".into();
                    break;
                }
            }
        }
        out.strides = out.strides.max(walked);
        match tally.iter_mut().find(|t| t.0 == fate) {
            Some(t) => t.1 += 1,
            None => tally.push((fate, 1)),
        }
    }
    out.fates = crate::scan::by_count(tally);
    out
}

/// How far a knee stop is from holding where a first stride ends in a buckled knee: the
/// flexion rate (over `√(g / l)`) at which the fatal impact releases its knee stops, summed over
/// the released stops (the complementarity of a stop's impulse and its separation rate: the rate
/// falls to 0 where the stop would begin to hold). `None` for other ends, or where the model
/// reports no impact.
fn buckle_rate(walker: &dyn Walker, st: &crate::stride::Stride) -> Option<f64> {
    let crate::stride::StrideOutcome::Fall {
        kind: pdw_hybrid::FallKind::KneeBuckled,
        guard,
    } = st.outcome
    else {
        return None;
    };
    // the mode whose guard of that index is the buckling twin of its impact guard (guard 0)
    let mode = (0..walker.n_modes()).find(|&m| {
        walker.guards(m).get(guard).is_some_and(|g| {
            g.kind == pdw_hybrid::GuardKind::Terminal(pdw_hybrid::FallKind::KneeBuckled)
        })
    })?;
    let report = walker.impact_report(mode, 0, &st.pre_event)?;
    let rate_scale = walker
        .scales()
        .map(|s| (s.gravity / s.length).sqrt())
        .filter(|r| r.is_finite() && *r > 0.0)
        .unwrap_or(1.0);
    let b: f64 = report
        .entries
        .iter()
        .filter(|e| e.kind == pdw_model::ImpulseKind::KneeStop && e.unilateral && !e.active)
        .map(|e| e.rate_after.abs() / rate_scale)
        .sum();
    b.is_finite().then_some(b)
}

/// Evaluates one design (see the module docs). `params` are stored with the result; `walker`
/// is the design built at them; `guesses` the starting points of the gait search.
pub fn evaluate_design(
    params: &[f64],
    walker: &dyn Walker,
    guesses: &[(String, Vec<f64>)],
    opts: &DesignOptions,
    pool: &rayon::ThreadPool,
) -> DesignEval {
    // stored designs keep (stance, stance_rate, hip_rate); a walker whose section carries the
    // swing knee's rate starts from 0 there (the rate when its stop holds at heel strike)
    let ds = walker.section_dim();
    let padded: Vec<(String, Vec<f64>)> = guesses
        .iter()
        .map(|(name, s)| {
            let mut s = s.clone();
            s.resize(ds.max(s.len()), 0.0);
            (name.clone(), s)
        })
        .collect();
    let guesses = &padded[..];
    let no_gait = |why: String| {
        let pr = probe(walker, guesses, opts.newton_tol);
        let cost = graded_cost(Grade::NoGait {
            n: pr.strides,
            of: PROBE_STRIDES,
            q: pr.residual,
        });
        let mut ev = DesignEval::failed(params, status::NO_GAIT, why, cost);
        ev.strides_survived = pr.strides as f64;
        ev.probe_residual = pr.residual;
        ev.fates = crate::scan::fates_text(guesses.len(), &pr.fates);
        ev.reason = format!("{}; {}", ev.reason, ev.fates);
        ev
    };
    let found = match gait_search(walker, guesses, opts.newton_tol) {
        Ok((found, _)) => found,
        Err(e) => return no_gait(format!("stride map: {e}")),
    };
    let rho_of = |f: &crate::gaits::Found| {
        f.fp.multipliers
            .iter()
            .map(|l| l.re.hypot(l.im))
            .fold(0.0, f64::max)
    };
    let Some(best) = found.iter().min_by(|a, b| rho_of(a).total_cmp(&rho_of(b))) else {
        return no_gait(format!("no gait from {} guesses", guesses.len()));
    };
    let rho = rho_of(best);
    let fp = &best.fp;
    let mut ev = DesignEval::failed(params, status::FEASIBLE, String::new(), 0.0);
    ev.rho = rho;
    ev.section = [fp.section[0], fp.section[1], fp.section[2]];
    ev.period = fp.metrics.period;
    ev.step_length = fp.metrics.step_length.unwrap_or(f64::NAN);
    let (d, why) = validity_shortfall(walker, &fp.state, opts, &mut ev);
    ev.shortfall = d;
    if rho >= 1.0 || d > 0.0 {
        let mut why = why;
        if rho >= 1.0 {
            why.insert(0, format!("unstable gait, max |λ| = {rho:.4}"));
            ev.status = status::UNSTABLE;
        } else {
            ev.status = status::INVALID;
        }
        ev.reason = why.join("; ");
        ev.cost = graded_cost(Grade::Gait { rho, d });
        return ev;
    }
    ev.cost = match opts.objective {
        Objective::Margin => rho,
        Objective::Basin => {
            let n = opts.basin_grid;
            let s = &fp.section;
            let bx = basin_box(opts, s);
            ev.basin_box = bx;
            let xs = linspace(s[0] - bx[0], s[0] + bx[0], n);
            let ys = linspace(s[1] - bx[1], s[1] + bx[1], n);
            let cells = grid_cells(s, 0, &xs, 1, &ys);
            let fall = Outcome::of_fall;
            let problem = BasinProblem::new(walker, s.clone(), &fall);
            match classify_cells(&problem, &cells, &opts.basin, pool, &|_| {}) {
                Ok(res) => {
                    let gait = Outcome::Gait.code();
                    let k = res.iter().filter(|c| c.outcome == gait).count();
                    ev.basin_fraction = k as f64 / cells.len() as f64;
                    -ev.basin_fraction + 1e-3 * rho
                }
                Err(e) => {
                    ev.status = status::INVALID;
                    ev.reason = format!("basin: {e}");
                    4.0
                }
            }
        }
    };
    ev
}

/// Walks one stride of the gait from `state`, records its loads and margins in `ev`, and
/// returns its shortfall ([`Shortfall`]) with what fails, in words.
fn validity_shortfall(
    walker: &dyn Walker,
    state: &[f64],
    opts: &DesignOptions,
    ev: &mut DesignEval,
) -> (f64, Vec<String>) {
    let tr = simulate(walker, state, &TrajectoryOptions::new(1));
    let (validity, knee_strike) = match &tr {
        Ok(t) => (
            Validity::along(walker, t, 0),
            t.events.iter().any(|e| e.kind == "knee_strike"),
        ),
        Err(_) => (None, false),
    };
    let Some(v) = validity else {
        let d = Shortfall {
            discrete: 1,
            ..Shortfall::default()
        };
        return (
            d.total(),
            vec!["the stride could not be re-walked for its forces".into()],
        );
    };
    ev.min_normal_force = v.min_normal_force;
    ev.max_friction = v.max_friction_required;
    ev.min_knee_torque = v.min_knee_torque.unwrap_or(f64::NAN);
    ev.min_relative_margin = v.min_relative_margin().unwrap_or(f64::NAN);
    if let Some(b) = v.binding() {
        ev.binding = b.name.clone();
    }
    // the torque scale m g l of the model's natural scales; without them, the potential energy
    // of the upright walker at rest (about weight × half the leg length)
    let mgl = torque_scale(walker, &v);
    let mu_req = if v.impact_friction_required.is_finite() {
        v.max_friction_required.max(v.impact_friction_required)
    } else {
        v.max_friction_required
    };
    let mut why = Vec::new();
    let mut discrete = 0;
    if let Some(f) = &v.fell {
        discrete += 1;
        why.push(format!("the stride falls: {f}"));
    }
    let free_knee = walker.guards(0).iter().any(|g| g.name == "knee_strike");
    if free_knee && !knee_strike {
        discrete += 1;
        why.push("no knee strike".into());
    }
    let tau = v.min_knee_torque.unwrap_or(f64::NAN);
    let mut sf = Shortfall::of(
        (ev.min_relative_margin, opts.min_margin),
        (mu_req, opts.mu),
        (tau, opts.knee_margin, mgl),
        discrete,
    );
    why.extend(criteria_failures(&v, opts));
    // a flag the margins do not carry (none of the criteria below its requirement, yet the
    // model flags the stride): one discrete failure
    if !why.is_empty() && sf.total() == 0.0 {
        sf.discrete += 1;
    }
    (sf.total(), why)
}

/// The torque scale `m g l` of the model's natural scales in `v`; without them, the potential
/// energy of the upright `walker` at rest (about weight × half the leg length), else 1.
fn torque_scale(walker: &dyn Walker, v: &Validity) -> f64 {
    match v.scales.as_ref() {
        Some(s) if (s.mass * s.gravity * s.length).is_finite() => s.mass * s.gravity * s.length,
        _ => {
            let mut up = vec![0.0; walker.dim()];
            walker.lift(&vec![0.0; walker.section_dim()], &mut up);
            walker
                .energy(&up)
                .filter(|e| e.is_finite() && *e > 0.0)
                .unwrap_or(1.0)
        }
    }
}

/// What fails of the criteria in `v` against the requirements of `opts`, in words: a pulling
/// ground, friction beyond `mu` (stance and impacts), a knee torque below its margin, a scuff,
/// an impact that needs a pulling contact or stop, and a binding margin below `min_margin`.
fn criteria_failures(v: &Validity, opts: &DesignOptions) -> Vec<String> {
    let mut why = Vec::new();
    if v.normal_force_negative || v.min_normal_force <= 0.0 {
        why.push(format!("normal force {:.3} N", v.min_normal_force));
    }
    if v.max_friction_required > opts.mu {
        why.push(format!(
            "friction {:.3} > mu {}",
            v.max_friction_required, opts.mu
        ));
    }
    if v.impact_friction_required > opts.mu {
        why.push(format!(
            "impact friction {:.3} > mu {}",
            v.impact_friction_required, opts.mu
        ));
    }
    if let Some(k) = v.min_knee_torque {
        if k < opts.knee_margin || v.knee_unlocks {
            why.push(format!(
                "knee torque {k:.4} N m < margin {} N m",
                opts.knee_margin
            ));
        }
    }
    if v.swing_foot_scuffs {
        why.push(format!(
            "swing foot below the slope by {:.4} where its clearance rule checks it",
            -v.min_clearance.unwrap_or(0.0)
        ));
    }
    if v.impact_violation {
        let names: Vec<&str> = v
            .violations
            .iter()
            .filter(|x| x.criterion.contains(':'))
            .map(|x| x.criterion.as_str())
            .collect();
        why.push(format!(
            "impact needs a pulling contact or stop: {}",
            names.join(", ")
        ));
    }
    if let Some(b) = v.binding().filter(|b| b.relative < opts.min_margin) {
        why.push(format!(
            "margin of {} {:.4} (relative to {}) < min margin {}",
            b.name, b.relative, b.scale_name, opts.min_margin
        ));
    }
    why
}

/// The free parameters and their bounds.
#[derive(Clone, Debug, PartialEq)]
pub struct DesignSpace {
    pub names: Vec<String>,
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
}

impl DesignSpace {
    /// Parameter values at unit-cube coordinates `u`.
    pub fn at(&self, u: &[f64]) -> Vec<f64> {
        (0..u.len())
            .map(|i| self.lo[i] + u[i] * (self.hi[i] - self.lo[i]))
            .collect()
    }
    /// Unit-cube coordinates of parameter values `p`.
    pub fn unit(&self, p: &[f64]) -> Vec<f64> {
        (0..p.len())
            .map(|i| (p[i] - self.lo[i]) / (self.hi[i] - self.lo[i]))
            .collect()
    }
}

/// What [`search`] calls per new design (parameters, gait guesses): evaluate it.
pub type Evaluator<'a> = dyn FnMut(&[f64], &[(String, Vec<f64>)]) -> DesignEval + 'a;

struct Problem<'a, 'e, 'b> {
    space: &'a DesignSpace,
    history: &'a RefCell<Vec<DesignEval>>,
    /// New evaluations so far.
    evaluations: &'a RefCell<usize>,
    /// New evaluations allowed.
    budget: usize,
    eval: &'a RefCell<&'e mut Evaluator<'b>>,
    guesses: &'a [(String, Vec<f64>)],
    /// Every design the search asked for, replayed or new, with its cost: the search's own
    /// sequence, the same in a resumed run as in an uninterrupted one (a stored history may
    /// hold designs the search has not reached yet).
    trace: &'a RefCell<Vec<(Vec<f64>, f64)>>,
    /// The run every new design is recorded under ([`DesignEval::run`]).
    run: u32,
}

impl Problem<'_, '_, '_> {
    fn cost_at(&self, u: &[f64]) -> Result<f64, ArgminError> {
        let out: f64 = u
            .iter()
            .map(|v| (v.clamp(0.0, 1.0) - v).powi(2))
            .sum::<f64>()
            .sqrt();
        if out > 0.0 {
            return Ok(20.0 + out);
        }
        let p = self.space.at(u);
        // replay: the same parameters (bit for bit) were evaluated before
        if let Some(e) = self.history.borrow().iter().find(|e| {
            e.params
                .iter()
                .zip(&p)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        }) {
            self.trace.borrow_mut().push((u.to_vec(), e.cost));
            return Ok(e.cost);
        }
        let k = *self.evaluations.borrow();
        if k >= self.budget {
            return Err(ArgminError::msg("budget exhausted"));
        }
        let mut guesses = self.guesses.to_vec();
        {
            let h = self.history.borrow();
            let mut near: Vec<(f64, &DesignEval)> = h
                .iter()
                .filter(|e| e.section.iter().all(|v| v.is_finite()))
                .map(|e| {
                    let ue = self.space.unit(&e.params);
                    let d: f64 = ue.iter().zip(u).map(|(a, b)| (a - b).powi(2)).sum();
                    (d, e)
                })
                .collect();
            near.sort_by(|a, b| a.0.total_cmp(&b.0));
            for (i, (_, e)) in near.iter().take(3).enumerate() {
                guesses.push((format!("nearest design {i}"), e.section.to_vec()));
            }
        }
        let mut ev = (self.eval.borrow_mut())(&p, &guesses);
        ev.run = self.run;
        let cost = ev.cost;
        self.trace.borrow_mut().push((u.to_vec(), cost));
        self.history.borrow_mut().push(ev);
        *self.evaluations.borrow_mut() += 1;
        Ok(cost)
    }
}

impl CostFunction for Problem<'_, '_, '_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, u: &Self::Param) -> Result<f64, ArgminError> {
        self.cost_at(u)
    }
}

/// The `i`-th seeded random point of the unit cube (SplitMix64 on `seed` and `i`), in
/// `[0.02, 0.98]ᵏ`.
fn sample(k: usize, seed: u64, i: usize) -> Vec<f64> {
    let mut z = seed ^ (i as u64).wrapping_mul(0xd6e8_feb8_6659_fd93);
    (0..k)
        .map(|_| {
            z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut x = z;
            x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            x ^= x >> 31;
            0.02 + 0.96 * (x >> 11) as f64 / (1u64 << 53) as f64
        })
        .collect()
}

/// Nelder–Mead over the design space (see the module docs). `history` holds the designs
/// evaluated before (a resumed run); `eval` evaluates a new design (and may store it and
/// advance a progress bar). Returns the full history, stored designs first, in evaluation
/// order.
pub fn search(
    space: &DesignSpace,
    opts: &DesignOptions,
    model_guesses: &[(String, Vec<f64>)],
    history: Vec<DesignEval>,
    eval: &mut Evaluator<'_>,
) -> Result<Vec<DesignEval>, LimitError> {
    let k = check_space(space)?;
    let x_start = match &opts.start {
        Some(p) => space.unit(p).iter().map(|u| u.clamp(0.0, 1.0)).collect(),
        None => vec![0.5; k],
    };
    let run = Run {
        index: 0,
        start: x_start,
        init: opts.init,
        budget: opts.budget,
    };
    local_run(space, opts, model_guesses, history, eval, &run)
}

fn check_space(space: &DesignSpace) -> Result<usize, LimitError> {
    let k = space.names.len();
    if k == 0 {
        return Err(LimitError::InvalidOption {
            name: "free",
            value: 0.0,
            allowed: "at least one free parameter",
        });
    }
    Ok(k)
}

/// One local run of a search: its index, its start (unit cube), the random designs it
/// evaluates first and the designs it may evaluate in all (stored ones included).
struct Run {
    index: u32,
    start: Vec<f64>,
    init: usize,
    budget: usize,
}

/// What [`search_multi`] calls per new design (the run, parameters, gait guesses): evaluate
/// it. Called from the pool's threads, one design at a time per run.
pub type SharedEvaluator<'a> = dyn Fn(u32, &[f64], &[(String, Vec<f64>)]) -> DesignEval + Sync + 'a;

/// The multi-start search (module docs): `runs` local runs on `pool`, `history` the stored
/// designs of every run. Returns every design, run by run, each run's in its evaluation order.
pub fn search_multi(
    space: &DesignSpace,
    opts: &DesignOptions,
    runs: usize,
    model_guesses: &[(String, Vec<f64>)],
    history: Vec<DesignEval>,
    eval: &SharedEvaluator<'_>,
    pool: &rayon::ThreadPool,
) -> Result<Vec<DesignEval>, LimitError> {
    use rayon::prelude::*;
    let k = check_space(space)?;
    if runs == 0 {
        return Err(LimitError::InvalidOption {
            name: "starts",
            value: 0.0,
            allowed: "at least one start",
        });
    }
    let x0: Vec<f64> = match &opts.start {
        Some(p) => space.unit(p).iter().map(|u| u.clamp(0.0, 1.0)).collect(),
        None => vec![0.5; k],
    };
    let plan: Vec<Run> = (0..runs)
        .map(|r| Run {
            index: r as u32,
            start: if r == 0 {
                x0.clone()
            } else {
                sample(k, opts.seed, opts.init + r - 1)
            },
            init: if r == 0 { opts.init } else { 0 },
            budget: opts.budget / runs + usize::from(r < opts.budget % runs),
        })
        .collect();
    let mut stored: Vec<Vec<DesignEval>> = vec![Vec::new(); runs];
    for e in history {
        // designs of runs beyond this search's (a file of a wider search) are not replayed
        if let Some(h) = stored.get_mut(e.run as usize) {
            h.push(e);
        }
    }
    let per_run: Vec<Result<Vec<DesignEval>, LimitError>> = pool.install(|| {
        plan.par_iter()
            .zip(stored.into_par_iter())
            .map(|(run, h)| {
                let mut one = |p: &[f64], g: &[(String, Vec<f64>)]| eval(run.index, p, g);
                local_run(space, opts, model_guesses, h, &mut one, run)
            })
            .collect()
    });
    let mut out = Vec::new();
    for r in per_run {
        out.extend(r?);
    }
    Ok(out)
}

/// One local run (module docs): the start, the run's random designs, then Nelder–Mead with
/// restarts, all through the cache of the run's own `history`.
fn local_run(
    space: &DesignSpace,
    opts: &DesignOptions,
    model_guesses: &[(String, Vec<f64>)],
    history: Vec<DesignEval>,
    eval: &mut Evaluator<'_>,
    run: &Run,
) -> Result<Vec<DesignEval>, LimitError> {
    let k = space.names.len();
    let stored = history.len();
    let history = RefCell::new(history);
    let evaluations = RefCell::new(0usize);
    let eval = RefCell::new(eval);
    // the stored designs replay at no cost; only new ones count against what is left
    let budget = run.budget.saturating_sub(stored);
    let trace = RefCell::new(Vec::new());
    let first = Problem {
        space,
        history: &history,
        evaluations: &evaluations,
        budget,
        eval: &eval,
        guesses: model_guesses,
        trace: &trace,
        run: run.index,
    };
    let x_start = run.start.clone();
    let mut exhausted = first.cost_at(&x_start).is_err();
    for i in 0..run.init {
        if exhausted {
            break;
        }
        exhausted = first.cost_at(&sample(k, opts.seed, i)).is_err();
    }
    let best_unit = || {
        trace
            .borrow()
            .iter()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|b| b.0.clone())
    };
    let mut x0 = best_unit().unwrap_or(x_start);
    let mut edge = 0.25;
    for _restart in 0..64 {
        if exhausted {
            break;
        }
        if *evaluations.borrow() >= budget {
            break;
        }
        let problem = Problem {
            space,
            history: &history,
            evaluations: &evaluations,
            budget,
            eval: &eval,
            guesses: model_guesses,
            trace: &trace,
            run: run.index,
        };
        let mut simplex = vec![x0.clone()];
        for i in 0..k {
            let mut v = x0.clone();
            // step inward so that the vertex stays in the cube
            v[i] += if v[i] + edge <= 1.0 { edge } else { -edge };
            simplex.push(v);
        }
        // argmin's Nelder–Mead evaluates its first simplex without a way to stop (it unwraps
        // each cost), so every vertex is evaluated here first: the solver then replays them,
        // and a budget too small for the simplex ends the search with the history complete
        if simplex.iter().any(|v| problem.cost_at(v).is_err()) {
            break;
        }
        let solver = NelderMead::new(simplex)
            .with_sd_tolerance(1e-6)
            .map_err(|_| LimitError::InvalidOption {
                name: "sd_tolerance",
                value: 1e-6,
                allowed: "positive",
            })?;
        // an error is the budget running out inside a cost evaluation: the history is complete
        if Executor::new(problem, solver)
            .configure(|s| s.max_iters(10_000))
            .run()
            .is_err()
        {
            break;
        }
        // restart from the best design so far with half the edge
        if let Some(b) = best_unit() {
            x0 = b;
        }
        edge *= 0.5;
        if edge < 1e-3 {
            break;
        }
    }
    Ok(history.into_inner())
}
