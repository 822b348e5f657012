//! Physical validity of a stride on its whole continuous trajectory.
//!
//! A passive gait is only a gait if the contacts and stops that define the model could hold
//! it: along the flow the stance foot must be pushed by the ground (normal force `N ≥ 0`), the
//! ground must supply the friction `|f_t / f_n|` the stance foot needs, every locked knee's
//! hyper-extension stop must push (lock torque `τ ≥ 0`), and the swing foot must stay above the
//! slope; at every impact the impulses of the impact map must be those of unilateral contacts
//! and stops (docs/models.md, "Validity" and "Impacts").
//!
//! # Criteria located on the dense solution
//! One stride is simulated ([`simulate`], DOP853 at [`TRAJECTORY_TOL`]); its samples (every
//! accepted step and both sides of every event) split into segments at the events. Between two
//! samples the solution is re-integrated from the earlier sample to any time `t` inside the
//! step (DOP853 at [`DENSE_TOL`], first step the whole interval), which is the trajectory to
//! the integration tolerance. Each step is cut into [`SUBDIVISIONS`] parts; every discrete local
//! minimum of a criterion over these points (segment ends included: both sides of every event)
//! is refined by Brent's minimisation in time (Brent 1973, *Algorithms for Minimization without
//! Derivatives*, ch. 5: golden section with parabolic steps) on the bracket of its two
//! neighbours, and every sign change between two points is located by the Illinois variant of
//! regula falsi (Dowell & Jarratt 1971) to [`TIME_TOL`] in time. The criteria:
//!
//! * `normal_force` — the smallest stance normal force; scale `m g`;
//! * `friction_required` — the largest `|f_t / f_n|` (reported, not a sign: the ground's friction
//!   coefficient is the user's, see [`crate::design`]);
//! * `stance_knee_torque`, `swing_knee_torque` — the smallest lock torque `τ` of each locked knee
//!   (positive towards flexion; negative: the stop would have to pull) against the pull its
//!   hardware holds ([`Walker::knee_pull_limits`]): the margin is `τ + L` = limit − pull, with
//!   `L` a latch's `latch_torque` and `L = 0` for a stop or an ideal latch (flagged wherever it
//!   pulls); scale `m g l`;
//! * `swing_clearance` — the swing foot's lowest point above the slope
//!   ([`Walker::swing_clearance`]); scale `l`. Where it must hold is the model's
//!   [`ClearanceRule`]: [`ClearanceRule::WholeSwing`] from lift-off to heel strike (any point
//!   strictly inside the swing below `−`[`CLEARANCE_TOL`]` l` is a violation; at lift-off the
//!   foot is at 0 and must rise, so a foot that starts into the ground shows as a negative
//!   interior minimum), or [`ClearanceRule::AfterMidStance`] — the point-foot literature's
//!   convention (Garcia et al. 1998, §2; McGeer 1990) that ignores the scuff of a straight swing
//!   leg before it passes the stance leg: only the part of the swing with the swing foot ahead
//!   of the stance foot is checked (from mid-stance, located as the root of the foot's position
//!   along the slope), and the depth of the mid-stance scuff is reported on its own
//!   ([`Validity::scuff_depth`]). The margin is the smallest interior local minimum of the
//!   clearance in the checked part (the swing's ends are at 0 by construction and are not
//!   margins); `None` when the foot only rises and falls.
//!
//! # Impacts
//! At every reset along the stride the model's [`ImpactReport`] at the pre-impact state is
//! taken ([`Walker::impact_report`]); every entry's consistency margin
//! ([`pdw_model::ImpulseEntry::margin`]: the impulse of a constraint that holds plus the pull
//! its hardware holds — a latch's `latch_impulse`, so limit − pull — and the separation rate of
//! one that releases) is a criterion named `"<event>:<entry>"`, scaled by
//! `m √(g l)` (contact impulse), `m l √(g l)` (knee-stop angular impulse), `√(g l)` (contact
//! separation velocity) or `√(g / l)` (knee flexion rate); a negative one is a violation. The
//! impact's friction requirement is reported ([`Validity::impact_friction_required`]). A model
//! without impact reports (`None`) has its impacts recorded as unchecked.
//!
//! # Margins on a scale
//! Every criterion carries its raw margin (model units), its natural scale ([`Scales`]: `m` the
//! total mass, `l` the leg length, `g` gravity) and the ratio; the *binding* criterion is the
//! one with the smallest relative margin ([`Validity::binding`]).

use crate::trajectory::{simulate, Trajectory, TrajectoryOptions, TRAJECTORY_TOL};
use pdw_hybrid::{Integrator, Options, StopReason};
use pdw_model::{ClearanceRule, ImpactReport, ImpulseKind, Scales, Walker};

/// Tolerance (DOP853, `rtol = atol`) of the re-integration between samples: a hundredth of
/// the trajectory's, so that the dense solution is the trajectory to [`TRAJECTORY_TOL`].
pub const DENSE_TOL: f64 = 1e-2 * TRAJECTORY_TOL;
/// Parts each accepted step is cut into before minima are refined.
pub const SUBDIVISIONS: usize = 3;
/// Relative time tolerance of located minima and sign changes.
pub const TIME_TOL: f64 = 1e-13;
/// A clearance below `−CLEARANCE_TOL · l` is below the slope (the integration tolerance: a
/// swing foot that ends a stride on the slope is at 0 only to the accuracy of the state).
pub const CLEARANCE_TOL: f64 = 1e-9;

/// One criterion's margin, raw and on its natural scale.
#[derive(Clone, Debug, PartialEq)]
pub struct Margin {
    /// `normal_force`, `stance_knee_torque`, `swing_knee_torque`, `swing_clearance`, or
    /// `"<event>:<entry>"` for an impact entry (e.g. `heel_strike:new_stance_foot`).
    pub name: String,
    /// The margin in model units (negative: violated).
    pub raw: f64,
    /// The natural scale (model units; NaN for a model without [`Scales`]).
    pub scale: f64,
    /// What the scale is, e.g. `"m g"`, `"m g l"`, `"l"`, `"m sqrt(g l)"`.
    pub scale_name: &'static str,
    /// `raw / scale`.
    pub relative: f64,
    /// Where it was located: time from the start of the stride.
    pub t: f64,
}

/// A criterion below zero over a time interval of the stride.
#[derive(Clone, Debug, PartialEq)]
pub struct Violation {
    /// The criterion's name (as in [`Margin::name`]).
    pub criterion: String,
    /// Start and end of the interval (equal for an impact).
    pub t_start: f64,
    pub t_end: f64,
    /// The worst value inside it (model units).
    pub worst: f64,
}

/// One reset along the stride and the model's impulses there.
#[derive(Clone, Debug, PartialEq)]
pub struct ImpactCheck {
    /// Event time from the start of the stride.
    pub t: f64,
    /// The guard's name (e.g. `heel_strike`).
    pub event: String,
    /// Mode and guard index of the reset.
    pub mode: usize,
    pub guard: usize,
    /// The model's report; `None` where the model computes none (unchecked).
    pub report: Option<ImpactReport>,
}

/// Constraint loads, clearance and impacts along a stride, and the verdict.
///
/// The first seven fields keep their meaning from the sampled check ([`Validity::of`]); from
/// [`Validity::along`] they are located on the dense solution (module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Validity {
    pub min_normal_force: f64,
    pub max_friction_required: f64,
    /// Smallest knee-lock torque (negative: the knee would unlock); `None` without locked knees.
    pub min_knee_torque: Option<f64>,
    pub normal_force_negative: bool,
    /// A locked knee's torque became negative, or a free knee hyper-extended (model flags).
    pub knee_unlocks: bool,
    /// The swing foot went below the slope where its [`ClearanceRule`] checks it.
    pub swing_foot_scuffs: bool,
    /// Samples of the trajectory checked (accepted steps and both sides of every event).
    pub samples: usize,
    /// The stride ended in this fall (its name) instead of the section event: the criteria
    /// hold up to the fall, and the stride is not valid.
    pub fell: Option<String>,
    /// True when the criteria were located on the dense solution ([`Validity::along`]).
    pub continuous: bool,
    /// Dense points evaluated (samples, subdivisions and refinements).
    pub evaluations: usize,
    /// Times (from the start of the stride) of the smallest normal force and of the largest
    /// friction requirement.
    pub t_min_normal_force: f64,
    pub t_max_friction_required: f64,
    /// Smallest lock torque of `[stance knee, swing knee]` where locked.
    pub knee_torque: [Option<f64>; 2],
    /// Where the swing foot must clear the ground; `None` without a swing-foot clearance.
    pub clearance_rule: Option<ClearanceRule>,
    /// Smallest interior local minimum of the clearance where the rule checks it (`None`: the
    /// foot only rises and falls there).
    pub min_clearance: Option<f64>,
    pub t_min_clearance: f64,
    /// Deepest point of the swing foot below the slope anywhere in the swing (0 if never below):
    /// with [`ClearanceRule::AfterMidStance`] the mid-stance scuff the convention ignores.
    pub scuff_depth: f64,
    /// Where the swing foot is below the slope (`−CLEARANCE_TOL · l` or lower), over the whole
    /// swing: `(start, end)` times.
    pub scuff_intervals: Vec<(f64, f64)>,
    /// Time of mid-stance (the swing foot passes the stance foot), if located.
    pub t_mid_stance: Option<f64>,
    /// Every reset of the stride.
    pub impacts: Vec<ImpactCheck>,
    /// An entry of an impact report has a negative margin.
    pub impact_violation: bool,
    /// Largest friction coefficient an impact needs (NaN without impact reports).
    pub impact_friction_required: f64,
    /// Every criterion's margin (module docs).
    pub margins: Vec<Margin>,
    /// Every criterion below zero, with where.
    pub violations: Vec<Violation>,
    /// The model's natural scales, if it has them.
    pub scales: Option<Scales>,
}

impl Validity {
    /// No criterion violated.
    pub fn valid(&self) -> bool {
        !(self.fell.is_some()
            || self.normal_force_negative
            || self.knee_unlocks
            || self.swing_foot_scuffs
            || self.impact_violation)
    }

    /// The criterion with the smallest relative margin (the one that binds), if any.
    pub fn binding(&self) -> Option<&Margin> {
        self.margins
            .iter()
            .filter(|m| m.relative.is_finite())
            .min_by(|a, b| a.relative.total_cmp(&b.relative))
    }

    /// What fails, in words (empty when [`valid`](Self::valid)): "the ground must pull",
    /// "a knee lock must pull", "an impact must pull", "the swing foot scuffs", and "it falls"
    /// for a stride that does not end in a heel strike — the wording of the bifurcation
    /// diagrams' legend (`pdw_store::invalid_reasons`).
    pub fn failures(&self) -> Vec<&'static str> {
        [
            (self.fell.is_some(), "it falls"),
            (self.normal_force_negative, "the ground must pull"),
            (self.knee_unlocks, "a knee lock must pull"),
            (self.impact_violation, "an impact must pull"),
            (self.swing_foot_scuffs, "the swing foot scuffs"),
        ]
        .into_iter()
        .filter_map(|(raised, what)| raised.then_some(what))
        .collect()
    }

    /// The flags raised along the stride, each as a sentence for a report (empty for none):
    /// what `fixedpoint` prints under "flag:" and `animate` warns with.
    pub fn flag_descriptions(&self) -> Vec<&'static str> {
        [
            (
                self.normal_force_negative,
                "the stance foot would lift off (normal force < 0)",
            ),
            (
                self.knee_unlocks,
                "a locked knee would unlock (lock torque < 0)",
            ),
            (
                self.swing_foot_scuffs,
                "the swing foot goes below the slope where its clearance rule checks it",
            ),
            (
                self.impact_violation,
                "an impact needs a pulling contact or stop (negative impulse margin)",
            ),
        ]
        .into_iter()
        .filter_map(|(raised, what)| raised.then_some(what))
        .collect()
    }

    /// The smallest relative margin, if any.
    pub fn min_relative_margin(&self) -> Option<f64> {
        self.binding().map(|m| m.relative)
    }

    /// The margin named `name`.
    pub fn margin(&self, name: &str) -> Option<&Margin> {
        self.margins.iter().find(|m| m.name == name)
    }

    /// Summary of a trajectory's forces and flags **at its samples only** (the sampled check
    /// the dense one refines); `None` if the model computes neither or the walk did not
    /// complete its steps.
    pub fn of(tr: &Trajectory) -> Option<Self> {
        use crate::trajectory::{FLAG_KNEE_UNLOCKS, FLAG_NORMAL_NEGATIVE, FLAG_SWING_FOOT_SCUFFS};
        let (f, flags) = (tr.forces.as_ref()?, tr.flags.as_ref()?);
        if !tr.outcome.is_ok() || flags.is_empty() {
            return None;
        }
        let or = |bit| flags.iter().any(|b| b & bit != 0);
        let min_of = |k: usize| {
            f.knee_torque
                .iter()
                .skip(k)
                .step_by(2)
                .filter(|k| !k.is_nan())
                .copied()
                .reduce(f64::min)
        };
        let knee_torque = [min_of(0), min_of(1)];
        Some(Self {
            min_normal_force: f.normal.iter().copied().fold(f64::INFINITY, f64::min),
            max_friction_required: f.friction_required.iter().copied().fold(0.0, f64::max),
            min_knee_torque: knee_torque.iter().flatten().copied().reduce(f64::min),
            normal_force_negative: or(FLAG_NORMAL_NEGATIVE),
            knee_unlocks: or(FLAG_KNEE_UNLOCKS),
            swing_foot_scuffs: or(FLAG_SWING_FOOT_SCUFFS),
            samples: flags.len(),
            knee_torque,
            impact_friction_required: f64::NAN,
            ..Self::default()
        })
    }

    /// Validity along one stride of the gait from the post-impact state `x0`, located on the
    /// dense solution (module docs); see [`Validity::along`].
    pub fn along_step(w: &dyn Walker, x0: &[f64]) -> Option<Self> {
        Self::along_step_with(w, x0, &TrajectoryOptions::new(1))
    }

    /// [`Validity::along_step`] with the stride's samples from `opts` (its `steps` and `dt_out`
    /// are ignored: one stride, every accepted step).
    pub fn along_step_with(w: &dyn Walker, x0: &[f64], opts: &TrajectoryOptions) -> Option<Self> {
        let opts = TrajectoryOptions {
            steps: 1,
            dt_out: None,
            integrator: opts.integrator,
            max_samples: opts.max_samples,
            event_samples: false,
        };
        let tr = simulate(w, x0, &opts).ok()?;
        Self::along(w, &tr, 0)
    }

    /// Validity along stride `step` of the trajectory `tr` of `w` (sampled with `dt_out =
    /// None`: every accepted step and both sides of every event), located on the dense
    /// solution; `None` if the model computes no constraint forces or the stride neither
    /// completed nor fell (a timeout, a numerical failure). A stride that fell is checked up to
    /// the fall and is not valid ([`Validity::fell`]).
    pub fn along(w: &dyn Walker, tr: &Trajectory, step: usize) -> Option<Self> {
        let ended = tr.steps_done > step;
        let fall = tr.events.iter().find(|e| e.step == step && e.fall);
        if !ended && fall.is_none() {
            return None;
        }
        tr.forces.as_ref()?;
        let d = tr.dim();
        let (idx, segs) = stride_segments(tr, step);
        let t0 = *segs.first()?.t.first()?;
        let t_event = tr
            .events
            .iter()
            .find(|e| e.step == step && (e.ends_step || e.fall))
            .map(|e| e.t)?;
        let mut dense = Dense {
            w,
            segs,
            d,
            evaluations: 0,
        };
        let pts = dense.points();
        let scales = w.scales();
        let mut v = Validity {
            fell: fall.map(|e| e.kind.clone()),
            samples: idx.len(),
            continuous: true,
            scales,
            impact_friction_required: f64::NAN,
            ..Self::default()
        };
        v.check_loads(w, &mut dense, &pts, t0);
        // a free knee's hyper-extension is the model's own flag
        if let Some(flags) = &tr.flags {
            v.knee_unlocks |= idx
                .iter()
                .any(|&i| flags[i] & crate::trajectory::FLAG_KNEE_UNLOCKS != 0);
        }
        v.check_clearance(w, &mut dense, &pts, t_event, t0);
        v.check_impacts(w, tr, step, t0);
        v.evaluations = dense.evaluations;
        Some(v)
    }

    /// Records the margin `raw` of criterion `name` on `scale` (named `scale_name`), located
    /// at time `t` of a stride that starts at `t0`.
    fn push_margin(
        &mut self,
        name: &str,
        raw: f64,
        scale: f64,
        scale_name: &'static str,
        t: f64,
        t0: f64,
    ) {
        self.margins.push(Margin {
            name: name.to_string(),
            raw,
            scale,
            scale_name,
            relative: raw / scale,
            t: t - t0,
        })
    }

    /// The stance loads along the dense points `pts` of a stride that starts at `t0`: the
    /// smallest normal force, the largest friction requirement and each locked knee's smallest
    /// lock torque against the pull its hardware holds, with their margins and violations.
    fn check_loads(&mut self, w: &dyn Walker, dense: &mut Dense<'_>, pts: &[Pt], t0: f64) {
        let scales = self.scales;
        let sc = |f: fn(&Scales) -> f64| scales.as_ref().map_or(f64::NAN, f);
        let all = 0..pts.len();
        // stance normal force (both sides of every event: segment ends included)
        let f_n = |e: &Eval| Some(e.normal);
        if let Some((m, t)) = dense.minimum(pts, all.clone(), &f_n, false) {
            self.min_normal_force = m;
            self.t_min_normal_force = t - t0;
            self.push_margin("normal_force", m, sc(Scales::force), "m g", t, t0);
            if m < 0.0 {
                self.normal_force_negative = true;
                dense.violations(pts, all.clone(), &f_n, 0.0, "normal_force", t0, self);
            }
        }
        // friction needed: the largest |f_t / f_n|
        let f_mu = |e: &Eval| Some(-e.friction);
        if let Some((m, t)) = dense.minimum(pts, all.clone(), &f_mu, false) {
            self.max_friction_required = -m;
            self.t_max_friction_required = t - t0;
        }
        // knee-lock torques, each against the pull its hardware holds
        let limits = w.knee_pull_limits();
        for (k, name) in ["stance_knee_torque", "swing_knee_torque"]
            .iter()
            .enumerate()
        {
            let lim = limits[k];
            // the margin `τ + L` (limit − pull); a stop's and an ideal latch's is `τ` itself
            let f_k = move |e: &Eval| e.knee[k].map(|t| if lim > 0.0 { t + lim } else { t });
            if let Some((m, t)) = dense.minimum(pts, all.clone(), &f_k, false) {
                self.knee_torque[k] = Some(if lim > 0.0 { m - lim } else { m });
                self.push_margin(name, m, sc(Scales::torque), "m g l", t, t0);
                if m < 0.0 {
                    self.knee_unlocks = true;
                    dense.violations(pts, all.clone(), &f_k, 0.0, name, t0, self);
                }
            }
        }
        self.min_knee_torque = self.knee_torque.iter().flatten().copied().reduce(f64::min);
    }

    /// The swing foot's clearance over the swing (the dense points `pts` up to the pre-impact
    /// side of the heel strike at `t_event`) of a stride that starts at `t0`: the depth of any
    /// scuff over the whole swing, and the margin and violations where the model's
    /// [`ClearanceRule`] checks it.
    fn check_clearance(
        &mut self,
        w: &dyn Walker,
        dense: &mut Dense<'_>,
        pts: &[Pt],
        t_event: f64,
        t0: f64,
    ) {
        let swing = 0..pts.iter().take_while(|p| p.t <= t_event).count();
        let f_c = |e: &Eval| e.clearance;
        if !pts[swing.clone()].iter().all(|p| p.ev.clearance.is_some()) || swing.len() <= 2 {
            return;
        }
        let rule = w.clearance_rule();
        self.clearance_rule = Some(rule);
        let l = self.scales.map_or(1.0, |s| s.length);
        let tol = CLEARANCE_TOL * l;
        // the whole swing: depth below the slope and where
        if let Some((m, _)) = dense.minimum(pts, swing.clone(), &f_c, true) {
            if m < -tol {
                self.scuff_depth = -m;
                let mut whole = Validity::default();
                let name = "swing_clearance";
                dense.violations(pts, swing.clone(), &f_c, tol, name, t0, &mut whole);
                self.scuff_intervals = whole
                    .violations
                    .iter()
                    .map(|x| (x.t_start, x.t_end))
                    .collect();
            }
        }
        // the checked part
        let checked = match rule {
            ClearanceRule::WholeSwing => Some((swing.clone(), None)),
            ClearanceRule::AfterMidStance => dense
                .mid_stance(pts, swing.clone())
                .map(|(j, pt)| (j..swing.end, Some(pt))),
        };
        let Some((range, start)) = checked else {
            return;
        };
        let mut cpts: Vec<Pt> = Vec::new();
        if let Some(p) = start {
            self.t_mid_stance = Some(p.t - t0);
            cpts.push(p);
        }
        cpts.extend(pts[range].iter().cloned());
        let r = 0..cpts.len();
        let mut m_c = dense.minimum(&cpts, r.clone(), &f_c, true);
        if let (Some(p), ClearanceRule::AfterMidStance) = (cpts.first(), rule) {
            // the foot passes the stance foot below the slope: ahead and below
            let c = p.ev.clearance.unwrap_or(0.0);
            if c < -tol && m_c.is_none_or(|(m, _)| c < m) {
                m_c = Some((c, p.t));
            }
        }
        if let Some((m, t)) = m_c {
            self.min_clearance = Some(m);
            self.t_min_clearance = t - t0;
            self.push_margin("swing_clearance", m, l, "l", t, t0);
            if m < -tol {
                self.swing_foot_scuffs = true;
                dense.violations(&cpts, r, &f_c, tol, "swing_clearance", t0, self);
            }
        }
    }

    /// Every reset of stride `step` of `tr` (a stride that starts at `t0`), with the model's
    /// impact report at its pre-impact state: each entry's consistency margin, a violation
    /// where it is negative, and the largest friction an impact needs.
    fn check_impacts(&mut self, w: &dyn Walker, tr: &Trajectory, step: usize, t0: f64) {
        let scales = self.scales;
        let sc = |f: fn(&Scales) -> f64| scales.as_ref().map_or(f64::NAN, f);
        for e in tr.events.iter().filter(|e| e.step == step && !e.fall) {
            let report = w.impact_report(e.mode_before, e.guard, &e.pre);
            if let Some(r) = &report {
                if !r.friction_required.is_nan() {
                    self.impact_friction_required = if self.impact_friction_required.is_nan() {
                        r.friction_required
                    } else {
                        self.impact_friction_required.max(r.friction_required)
                    };
                }
                for en in &r.entries {
                    let Some(m) = en.margin() else { continue };
                    let (scale, sn) = match (en.kind, en.active) {
                        (ImpulseKind::KneeStop, true) => {
                            (sc(Scales::angular_impulse), "m l sqrt(g l)")
                        }
                        (ImpulseKind::KneeStop, false) => (sc(Scales::rate), "sqrt(g/l)"),
                        (_, true) => (sc(Scales::impulse), "m sqrt(g l)"),
                        (_, false) => (sc(Scales::speed), "sqrt(g l)"),
                    };
                    let name = format!("{}:{}", r.event, en.name);
                    self.push_margin(&name, m, scale, sn, e.t, t0);
                    if m < 0.0 {
                        self.impact_violation = true;
                        self.violations.push(Violation {
                            criterion: name,
                            t_start: e.t - t0,
                            t_end: e.t - t0,
                            worst: m,
                        });
                    }
                }
            }
            self.impacts.push(ImpactCheck {
                t: e.t - t0,
                event: e.kind.clone(),
                mode: e.mode_before,
                guard: e.guard,
                report,
            });
        }
    }
}

/// The samples of stride `step` of `tr` (their indices in `tr`) and the segments they split
/// into: a new segment at every change of mode and wherever the time does not increase (both
/// sides of an event).
fn stride_segments(tr: &Trajectory, step: usize) -> (Vec<usize>, Vec<Seg>) {
    let idx: Vec<usize> = (0..tr.len())
        .filter(|&i| tr.step[i] as usize == step)
        .collect();
    let mut segs: Vec<Seg> = Vec::new();
    for &i in &idx {
        let new = match segs.last() {
            None => true,
            Some(s) => s.mode != tr.mode[i] as usize || s.t.last().is_some_and(|&t| t >= tr.t[i]),
        };
        if new {
            segs.push(Seg {
                mode: tr.mode[i] as usize,
                t: Vec::new(),
                x: Vec::new(),
            });
        }
        let s = segs.last_mut().expect("pushed");
        s.t.push(tr.t[i]);
        s.x.push(tr.state(i).to_vec());
    }
    (idx, segs)
}

/// The loads and the clearance at one state.
#[derive(Clone, Copy, Debug)]
struct Eval {
    normal: f64,
    friction: f64,
    knee: [Option<f64>; 2],
    clearance: Option<f64>,
    /// Swing-foot position along the slope (downhill positive) relative to the stance foot.
    ahead: Option<f64>,
}

/// Samples of one segment (between events) of a stride, in one mode.
struct Seg {
    mode: usize,
    /// Sample times (increasing) and states.
    t: Vec<f64>,
    x: Vec<Vec<f64>>,
}

/// A point of the dense solution.
#[derive(Clone, Debug)]
struct Pt {
    seg: usize,
    t: f64,
    ev: Eval,
}

/// The dense solution of one stride: samples and re-integration between them.
struct Dense<'a> {
    w: &'a dyn Walker,
    segs: Vec<Seg>,
    d: usize,
    evaluations: usize,
}

impl Dense<'_> {
    fn eval_state(&mut self, mode: usize, x: &[f64]) -> Option<Eval> {
        self.evaluations += 1;
        let cf = self.w.constraint_forces(mode, x)?;
        Some(Eval {
            normal: cf.normal,
            friction: cf.friction_required,
            knee: cf.knee_torque,
            clearance: self.w.swing_clearance(mode, x),
            ahead: self.w.pose(x).and_then(|p| p.swing_foot).map(|f| f[0]),
        })
    }

    /// The state of segment `s` at time `t` (inside it): re-integrated from the last sample at
    /// or before `t`.
    fn state_at(&self, s: usize, t: f64) -> Option<Vec<f64>> {
        let seg = &self.segs[s];
        let i = seg.t.partition_point(|&ti| ti <= t).saturating_sub(1);
        let (t0, x0) = (seg.t[i], &seg.x[i]);
        if t <= t0 {
            return Some(x0.clone());
        }
        let opts = Options {
            h_init: Some(t - t0),
            ..Options::dop853(DENSE_TOL)
        };
        let mut integ = Integrator::new(self.d, opts).ok()?;
        let (mut tt, mut x) = (t0, x0.clone());
        // a crossing the stride skipped (inadmissible, or within the tolerance of a stop) may
        // stop the re-integration: continue from it
        for k in 0..8 {
            let stop = if k == 0 {
                integ.integrate(self.w, seg.mode, &mut tt, &mut x, t)
            } else {
                integ.resume(self.w, seg.mode, &mut tt, &mut x, t)
            };
            match stop {
                StopReason::EndTime => return Some(x),
                StopReason::Guard { .. } if tt < t => continue,
                StopReason::Guard { .. } => return Some(x),
                _ => return None,
            }
        }
        None
    }

    fn eval_at(&mut self, s: usize, t: f64) -> Option<Eval> {
        let x = self.state_at(s, t)?;
        self.eval_state(self.segs[s].mode, &x)
    }

    /// Samples and [`SUBDIVISIONS`] − 1 points inside every step, in time order.
    fn points(&mut self) -> Vec<Pt> {
        let mut pts = Vec::new();
        for s in 0..self.segs.len() {
            let n = self.segs[s].t.len();
            for i in 0..n {
                let (t, mode) = (self.segs[s].t[i], self.segs[s].mode);
                let x = self.segs[s].x[i].clone();
                if let Some(ev) = self.eval_state(mode, &x) {
                    pts.push(Pt { seg: s, t, ev });
                }
                if i + 1 < n {
                    let t1 = self.segs[s].t[i + 1];
                    for k in 1..SUBDIVISIONS {
                        let tk = t + (t1 - t) * k as f64 / SUBDIVISIONS as f64;
                        if let Some(ev) = self.eval_at(s, tk) {
                            pts.push(Pt { seg: s, t: tk, ev });
                        }
                    }
                }
            }
        }
        pts
    }

    /// The smallest value of `f` over `pts[range]` and its time: every discrete local minimum
    /// refined by Brent's method on its neighbours' bracket (within its segment).
    /// `interior`: the first and last points are not minima (the swing's ends, at 0 by
    /// construction), nor are local minima at them.
    fn minimum(
        &mut self,
        pts: &[Pt],
        range: std::ops::Range<usize>,
        f: &dyn Fn(&Eval) -> Option<f64>,
        interior: bool,
    ) -> Option<(f64, f64)> {
        let val = |j: usize| f(&pts[j].ev);
        let mut best: Option<(f64, f64)> = None;
        for j in range.clone() {
            let Some(v) = val(j) else { continue };
            let left = (j > range.start)
                .then(|| j - 1)
                .filter(|&i| val(i).is_some());
            let right = (j + 1 < range.end)
                .then_some(j + 1)
                .filter(|&i| val(i).is_some());
            if interior && (left.is_none() || right.is_none()) {
                continue;
            }
            if left.is_some_and(|i| val(i).unwrap_or(f64::INFINITY) < v)
                || right.is_some_and(|i| val(i).unwrap_or(f64::INFINITY) < v)
            {
                continue;
            }
            let seg = pts[j].seg;
            let lo = left
                .filter(|&i| pts[i].seg == seg)
                .map_or(pts[j].t, |i| pts[i].t);
            let hi = right
                .filter(|&i| pts[i].seg == seg)
                .map_or(pts[j].t, |i| pts[i].t);
            let (mut m, mut tm) = (v, pts[j].t);
            if hi > lo {
                let mut g = |t: f64| {
                    self.eval_at(seg, t)
                        .and_then(|e| f(&e))
                        .unwrap_or(f64::INFINITY)
                };
                let (tb, vb) = brent_min(&mut g, lo, pts[j].t, hi, v);
                if vb < m {
                    (m, tm) = (vb, tb);
                }
            }
            if best.is_none_or(|(b, _)| m < b) {
                best = Some((m, tm));
            }
        }
        best
    }

    /// Records every interval of `pts[range]` where `f < 0` as a [`Violation`] of `name` (only
    /// those whose worst value is below `−tol`), with sign changes located by root finding.
    #[allow(clippy::too_many_arguments)]
    fn violations(
        &mut self,
        pts: &[Pt],
        range: std::ops::Range<usize>,
        f: &dyn Fn(&Eval) -> Option<f64>,
        tol: f64,
        name: &str,
        t0: f64,
        v: &mut Validity,
    ) {
        let whole = range.clone();
        let mut open: Option<(f64, f64)> = None; // (start, worst)
        let mut prev: Option<(usize, f64)> = None;
        let close = |open: &mut Option<(f64, f64)>, t_end: f64, v: &mut Validity| {
            if let Some((ts, worst)) = open.take() {
                if worst < -tol {
                    v.violations.push(Violation {
                        criterion: name.to_string(),
                        t_start: ts - t0,
                        t_end: t_end - t0,
                        worst,
                    });
                }
            }
        };
        for j in range {
            let Some(y) = f(&pts[j].ev) else {
                if let Some((i, _)) = prev {
                    close(&mut open, pts[i].t, v);
                }
                prev = None;
                continue;
            };
            match prev {
                Some((i, yp)) if pts[i].seg == pts[j].seg && (yp < 0.0) != (y < 0.0) => {
                    let seg = pts[j].seg;
                    let mut g =
                        |t: f64| self.eval_at(seg, t).and_then(|e| f(&e)).unwrap_or(f64::NAN);
                    let tr = illinois(&mut g, pts[i].t, yp, pts[j].t, y);
                    if y < 0.0 {
                        open = Some((tr, y));
                    } else {
                        close(&mut open, tr, v);
                    }
                }
                None if y < 0.0 => open = Some((pts[j].t, y)),
                Some((i, _)) if pts[i].seg != pts[j].seg && y < 0.0 && open.is_none() => {
                    open = Some((pts[j].t, y))
                }
                _ => {}
            }
            if let Some(o) = open.as_mut() {
                o.1 = o.1.min(y);
            }
            prev = Some((j, y));
        }
        if let Some((i, _)) = prev {
            close(&mut open, pts[i].t, v);
        }
        // the refined minimum is the worst value of its interval
        if let Some((m, t)) = self.minimum(pts, whole, f, false) {
            for x in v.violations.iter_mut().filter(|x| x.criterion == name) {
                if (x.t_start..=x.t_end).contains(&(t - t0)) {
                    x.worst = x.worst.min(m);
                }
            }
        }
    }

    /// Mid-stance in `pts[range]`: the last time the swing foot passes the stance foot going
    /// forward (its position along the slope rising through 0), located by root finding; the
    /// index of the first point after it and the point itself.
    fn mid_stance(&mut self, pts: &[Pt], range: std::ops::Range<usize>) -> Option<(usize, Pt)> {
        let ahead = |p: &Pt| p.ev.ahead;
        let mut found = None;
        for j in range.start + 1..range.end {
            let (Some(a), Some(b)) = (ahead(&pts[j - 1]), ahead(&pts[j])) else {
                continue;
            };
            if a <= 0.0 && b > 0.0 {
                found = Some(j);
            }
        }
        let j = found?;
        let (i, seg) = (j - 1, pts[j].seg);
        let tm = if pts[i].seg == seg {
            let mut g = |t: f64| {
                self.eval_at(seg, t)
                    .and_then(|e| e.ahead)
                    .unwrap_or(f64::NAN)
            };
            illinois(&mut g, pts[i].t, ahead(&pts[i])?, pts[j].t, ahead(&pts[j])?)
        } else {
            pts[j].t
        };
        let ev = self.eval_at(seg, tm)?;
        Some((j, Pt { seg, t: tm, ev }))
    }
}

/// Brent's minimisation of `f` on `[a, b]` from the interior point `x` with `f(x) = fx`
/// (golden-section steps with parabolic interpolation, Brent 1973 ch. 5); returns the best
/// `(t, f(t))` seen, to a relative time tolerance [`TIME_TOL`].
#[doc(hidden)]
pub fn brent_min(f: &mut dyn FnMut(f64) -> f64, a: f64, x: f64, b: f64, fx: f64) -> (f64, f64) {
    const CGOLD: f64 = 0.381_966_011_250_105_1; // (3 − √5) / 2
    let (mut a, mut b) = (a, b);
    let (mut x, mut w, mut v) = (x, x, x);
    let (mut fx, mut fw, mut fv) = (fx, fx, fx);
    // a point at an end of the bracket: start from the golden point inside
    if x <= a || x >= b {
        let t = a + CGOLD * (b - a);
        let ft = f(t);
        if ft < fx {
            (x, fx) = (t, ft);
        }
        (w, fw, v, fv) = (t, ft, t, ft);
        if x != t {
            // the end was lower: keep its side
            if x <= a {
                b = t;
            } else {
                a = t;
            }
        }
    }
    let (mut d, mut e) = (0.0f64, 0.0f64);
    for _ in 0..100 {
        let m = 0.5 * (a + b);
        let tol = TIME_TOL * x.abs().max(1.0) + 1e-15;
        let tol2 = 2.0 * tol;
        if (x - m).abs() <= tol2 - 0.5 * (b - a) {
            break;
        }
        let mut golden = true;
        if e.abs() > tol {
            // parabola through (x, fx), (w, fw), (v, fv)
            let r = (x - w) * (fx - fv);
            let mut q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            }
            q = q.abs();
            if p.abs() < (0.5 * q * e).abs() && p > q * (a - x) && p < q * (b - x) {
                e = d;
                d = p / q;
                let u = x + d;
                if u - a < tol2 || b - u < tol2 {
                    d = if x < m { tol } else { -tol };
                }
                golden = false;
            }
        }
        if golden {
            e = if x < m { b - x } else { a - x };
            d = CGOLD * e;
        }
        let u = if d.abs() >= tol {
            x + d
        } else {
            x + tol.copysign(d)
        };
        let fu = f(u);
        if fu <= fx {
            if u < x {
                b = x;
            } else {
                a = x;
            }
            (v, fv, w, fw, x, fx) = (w, fw, x, fx, u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                (v, fv, w, fw) = (w, fw, u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
    (x, fx)
}

/// The root of `f` in `[a, b]` (`f(a) = fa`, `f(b) = fb` of opposite signs) by the Illinois
/// variant of regula falsi (Dowell & Jarratt 1971), to [`TIME_TOL`] in time.
#[doc(hidden)]
pub fn illinois(f: &mut dyn FnMut(f64) -> f64, a: f64, fa: f64, b: f64, fb: f64) -> f64 {
    let (mut a, mut fa, mut b, mut fb) = (a, fa, b, fb);
    let mut side = 0i8;
    for _ in 0..200 {
        if (b - a).abs() <= TIME_TOL * a.abs().max(b.abs()).max(1.0) {
            break;
        }
        let mut c = (a * fb - b * fa) / (fb - fa);
        if !(c > a.min(b) && c < a.max(b)) {
            c = 0.5 * (a + b);
        }
        let fc = f(c);
        if fc.is_nan() {
            return 0.5 * (a + b);
        }
        if fc == 0.0 {
            return c;
        }
        if (fc < 0.0) == (fb < 0.0) {
            (b, fb) = (c, fc);
            if side == -1 {
                fa *= 0.5;
            }
            side = -1;
        } else {
            (a, fa) = (c, fc);
            if side == 1 {
                fb *= 0.5;
            }
            side = 1;
        }
    }
    if fa.abs() < fb.abs() {
        a
    } else {
        b
    }
}

/// Physical validity of an attractor's orbit: every stride of a periodic orbit checked along
/// the dense solution ([`Validity::along_step`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum OrbitValidity {
    /// Not checked: the model reports no constraint forces, or the attractor is chaotic (a
    /// sample of its points is no orbit whose strides all repeat).
    #[default]
    Unchecked,
    /// Every stride of the orbit valid.
    Valid,
    /// What fails on some stride of the orbit ([`Validity::failures`], each named once).
    Invalid(Vec<&'static str>),
}

impl OrbitValidity {
    /// `"valid"`, `"not checked"` or `"physically invalid: …"` (reasons joined by `, `).
    pub fn describe(&self) -> String {
        match self {
            OrbitValidity::Unchecked => "not checked".into(),
            OrbitValidity::Valid => "valid".into(),
            OrbitValidity::Invalid(r) => format!("physically invalid: {}", r.join(", ")),
        }
    }
}

/// The validity of the periodic orbit through the section points `points` of `w` (each lifted
/// with [`pdw_hybrid::Section::lift`] and checked over one stride); [`OrbitValidity::Unchecked`]
/// for no points or a model without constraint forces.
pub fn orbit_validity(w: &dyn Walker, points: &[Vec<f64>]) -> OrbitValidity {
    let mut reasons: Vec<&'static str> = Vec::new();
    let mut x = vec![0.0; w.dim()];
    for p in points {
        if p.len() != w.section_dim() {
            return OrbitValidity::Unchecked;
        }
        w.lift(p, &mut x);
        let Some(v) = Validity::along_step(w, &x) else {
            return OrbitValidity::Unchecked;
        };
        for f in v.failures() {
            if !reasons.contains(&f) {
                reasons.push(f);
            }
        }
    }
    match (points.is_empty(), reasons.is_empty()) {
        (true, _) => OrbitValidity::Unchecked,
        (false, true) => OrbitValidity::Valid,
        (false, false) => OrbitValidity::Invalid(reasons),
    }
}
