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
//! 3. scores it. Feasible designs (stable and valid) get the objective: `margin` — `ρ` (smaller is
//!    better); `basin` — minus the fraction of a box of section states around the gait that
//!    walk into it ([`crate::classify_cells`] on a coarse grid; the box is `stance ± Δ₀`,
//!    `stance_rate ± Δ₁`, `hip_rate` at the gait's; `Δ` given, or by default scaled to the
//!    gait, `Δ = 0.15 · (|stance|, |stance_rate|)`, [`basin_box`]), plus `1e-3·ρ` to break ties
//!    between equal coarse fractions. Infeasible designs get a graded penalty above every feasible cost:
//!    `1 + v` (stable but invalid; `v` the normalised violation, at most 3), `5 + min(ρ − 1, 4)`
//!    (unstable), `10` (no gait found), `11` (the parameters do not make a model). The violation
//!    sums, over the failed constraints, the shortfall of the knee torque over a torque scale
//!    (the upright walker's potential energy at rest, ≈ weight × half a leg), of the normal force
//!    over a force scale (that torque over the step length), of the friction coefficient over 1,
//!    plus 0.1 per failed force constraint, 0.5 for a scuff, an unphysical impact, a fall or a
//!    missing knee strike, and the shortfall of the binding relative margin below `min_margin`
//!    (at most 1).
//!
//! # The search
//! [`search`] evaluates the start (the model's own values of the free parameters, or the
//! centre of the bounds) and `init` seeded random designs, then runs argmin's Nelder–Mead over
//! the free parameters scaled to the unit cube `[0, 1]ᵏ` (a point outside it costs
//! `20 + distance` and is not evaluated) from the best design so far with an initial simplex of
//! edge 0.25 (its `k + 1` vertices evaluated before the solver starts: a budget that runs out
//! among them ends the search there); when the simplex collapses (standard deviation of its
//! costs below 1e-6) with budget left, it restarts from the best design found with half the edge. Every evaluated design goes through a cache
//! keyed by its exact parameter bits, so that a rerun over a stored history replays the same
//! deterministic sequence at no cost and continues where the stored run stopped (resumable), and
//! the same seed gives the same designs (reproducible). Guesses for a design's gait: the model's
//! own, then the gaits of the (at most 3) nearest designs of the history with a gait (in the unit
//! cube), nearest first.

use crate::basin::{classify_cells, grid_cells, linspace, BasinOptions, BasinProblem, Outcome};
use crate::error::LimitError;
use crate::gaits::search as gait_search;
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
const COST_NO_GAIT: f64 = 10.0;

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
    let found = match gait_search(walker, guesses, opts.newton_tol) {
        Ok((found, _)) => found,
        Err(e) => {
            return DesignEval::failed(
                params,
                status::NO_GAIT,
                format!("stride map: {e}"),
                COST_NO_GAIT,
            )
        }
    };
    let rho_of = |f: &crate::gaits::Found| {
        f.fp.multipliers
            .iter()
            .map(|l| l.re.hypot(l.im))
            .fold(0.0, f64::max)
    };
    let Some(best) = found.iter().min_by(|a, b| rho_of(a).total_cmp(&rho_of(b))) else {
        return DesignEval::failed(
            params,
            status::NO_GAIT,
            format!("no gait from {} guesses", guesses.len()),
            COST_NO_GAIT,
        );
    };
    let rho = rho_of(best);
    let fp = &best.fp;
    let mut ev = DesignEval::failed(params, status::FEASIBLE, String::new(), 0.0);
    ev.rho = rho;
    ev.section = [fp.section[0], fp.section[1], fp.section[2]];
    ev.period = fp.metrics.period;
    ev.step_length = fp.metrics.step_length.unwrap_or(f64::NAN);
    if rho >= 1.0 {
        ev.status = status::UNSTABLE;
        ev.reason = format!("unstable gait, max |λ| = {rho:.4}");
        ev.cost = 5.0 + (rho - 1.0).min(4.0);
        return ev;
    }
    // validity along the whole stride
    let tr = simulate(walker, &fp.state, &TrajectoryOptions::new(1));
    let (validity, knee_strike) = match &tr {
        Ok(t) => (
            Validity::along(walker, t, 0),
            t.events.iter().any(|e| e.kind == "knee_strike"),
        ),
        Err(_) => (None, false),
    };
    let Some(v) = validity else {
        ev.status = status::INVALID;
        ev.reason = "the stride could not be re-walked for its forces".into();
        ev.cost = 4.0;
        return ev;
    };
    ev.min_normal_force = v.min_normal_force;
    ev.max_friction = v.max_friction_required;
    ev.min_knee_torque = v.min_knee_torque.unwrap_or(f64::NAN);
    ev.min_relative_margin = v.min_relative_margin().unwrap_or(f64::NAN);
    // violation scales: torque — the potential energy of the upright walker at rest (about
    // weight × half the leg length, N m); force — that over the step length (N)
    let mut up = vec![0.0; walker.dim()];
    walker.lift(&vec![0.0; walker.section_dim()], &mut up);
    let ts = walker
        .energy(&up)
        .filter(|e| e.is_finite() && *e > 0.0)
        .unwrap_or(1.0);
    let fs = ts / ev.step_length.abs().max(1e-9);
    let mut viol = 0.0;
    let mut why = Vec::new();
    if v.normal_force_negative || v.min_normal_force <= 0.0 {
        viol += (-v.min_normal_force).max(0.0) / fs + 0.1;
        why.push(format!("normal force {:.3} N", v.min_normal_force));
    }
    if v.max_friction_required > opts.mu {
        viol += (v.max_friction_required - opts.mu).min(1.0);
        why.push(format!(
            "friction {:.3} > mu {}",
            v.max_friction_required, opts.mu
        ));
    }
    if let Some(k) = v.min_knee_torque {
        if k < opts.knee_margin || v.knee_unlocks {
            viol += (opts.knee_margin - k).max(0.0) / ts + 0.1;
            why.push(format!(
                "knee torque {k:.4} N m < margin {} N m",
                opts.knee_margin
            ));
        }
    }
    if v.impact_friction_required > opts.mu {
        viol += (v.impact_friction_required - opts.mu).min(1.0);
        why.push(format!(
            "impact friction {:.3} > mu {}",
            v.impact_friction_required, opts.mu
        ));
    }
    if v.swing_foot_scuffs {
        viol += 0.5;
        why.push(format!(
            "swing foot below the slope by {:.4} where its clearance rule checks it",
            -v.min_clearance.unwrap_or(0.0)
        ));
    }
    if v.impact_violation {
        viol += 0.5;
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
    if let Some(f) = &v.fell {
        viol += 0.5;
        why.push(format!("the stride falls: {f}"));
    }
    if let Some(b) = v.binding().filter(|b| b.relative < opts.min_margin) {
        viol += (opts.min_margin - b.relative).clamp(0.0, 1.0);
        why.push(format!(
            "margin of {} {:.4} (relative to {}) < min margin {}",
            b.name, b.relative, b.scale_name, opts.min_margin
        ));
    }
    let free_knee = walker.guards(0).iter().any(|g| g.name == "knee_strike");
    if free_knee && !knee_strike {
        viol += 0.5;
        why.push("no knee strike".into());
    }
    if !why.is_empty() {
        ev.status = status::INVALID;
        ev.reason = why.join("; ");
        ev.cost = 1.0 + viol.min(3.0);
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
        let ev = (self.eval.borrow_mut())(&p, &guesses);
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
    let k = space.names.len();
    if k == 0 {
        return Err(LimitError::InvalidOption {
            name: "free",
            value: 0.0,
            allowed: "at least one free parameter",
        });
    }
    let stored = history.len();
    let history = RefCell::new(history);
    let evaluations = RefCell::new(0usize);
    let eval = RefCell::new(eval);
    // the stored designs replay at no cost; only new ones count against what is left
    let budget = opts.budget.saturating_sub(stored);
    let trace = RefCell::new(Vec::new());
    let first = Problem {
        space,
        history: &history,
        evaluations: &evaluations,
        budget,
        eval: &eval,
        guesses: model_guesses,
        trace: &trace,
    };
    let x_start = match &opts.start {
        Some(p) => space.unit(p).iter().map(|u| u.clamp(0.0, 1.0)).collect(),
        None => vec![0.5; k],
    };
    let mut exhausted = first.cost_at(&x_start).is_err();
    for i in 0..opts.init {
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
