//! The walker-facing trait: what the analysis asks of a model beyond its hybrid system and
//! section — names, parameters, step length, gait guesses, a drawing, constraint forces and
//! impact impulses for validity, energy, natural scales and units.

use crate::validity::{ClearanceRule, ConstraintForces, ImpactReport, Scales, StepFlags};
use pdw_hybrid::{Scratch, Section};
use std::borrow::Cow;

/// A starting point for a fixed-point search on the section.
#[derive(Clone, Debug, PartialEq)]
pub struct GaitGuess {
    /// Which gait this is meant to find, e.g. `"stable"`, `"unstable"`.
    pub gait: String,
    /// Reduced section coordinates (in [`Section::section_names`] order).
    pub section: Vec<f64>,
    /// Where the guess comes from (e.g. "Garcia 1998 App. A.2 small-slope asymptotics").
    pub source: String,
}

/// Model-level extras on top of the hybrid system and its section.
pub trait Walker: Section {
    /// Registry name, e.g. `"simplest"`, or the spec's name.
    fn name(&self) -> &str;
    /// Names of the full state components, in state order.
    fn state_names(&self) -> Vec<String>;
    /// Current parameter values, in the order of the model's parameter table (its registry
    /// entry).
    fn param_values(&self) -> Vec<(String, f64)>;
    /// Step length (distance between the feet along the slope, model length units) at the
    /// stride-ending event, from the *pre-reset* state `x_pre` on the section guard.
    fn step_length(&self, x_pre: &[f64]) -> f64;
    /// Initial guesses for the gaits the model is known to have at its current parameters.
    fn gait_guesses(&self) -> Vec<GaitGuess>;
    /// Name of each mode of the flow, in mode order (what a trajectory's `mode` column means),
    /// e.g. `["swing knee free", "knees locked"]`; `mode k` where the model names none.
    fn mode_names(&self) -> Vec<String> {
        (0..self.n_modes()).map(|k| format!("mode {k}")).collect()
    }
    /// What each state component means — the angle it measures, from what, and its sign — in
    /// state order; empty where the model does not say.
    fn coordinate_meanings(&self) -> Vec<String> {
        Vec::new()
    }
    /// The walker's drawing at full state `x`, for animations; `None` if the model has none.
    fn pose(&self, _x: &[f64]) -> Option<Pose> {
        None
    }
    /// Named points of the walker (stance foot, knees, hip, swing foot, …) and its centre of
    /// mass at full state `x`, in the frame of [`Walker::pose`]; `None` if the model does not
    /// give them.
    fn body_points(&self, _x: &[f64]) -> Option<BodyPoints> {
        None
    }
    /// Stance-foot ground reaction and knee-lock torques at `(mode, x)`, if the model
    /// computes them.
    fn constraint_forces(&self, _mode: usize, _x: &[f64]) -> Option<ConstraintForces> {
        None
    }
    /// Validity flags at `(mode, x)` (negative normal force, a knee that would unlock, a swing
    /// foot below ground after mid-stance), if the model computes them.
    fn step_flags(&self, _mode: usize, _x: &[f64]) -> Option<StepFlags> {
        None
    }
    /// Total mechanical energy at the full state `x` (potential zero at the stance foot), if
    /// the model defines it; conserved between impacts.
    fn energy(&self, _x: &[f64]) -> Option<f64> {
        None
    }
    /// [`Walker::constraint_forces`] in the caller's scratch `ws`: a model whose kernel needs
    /// workspaces takes them from `ws` (filled on the first call), so that sampling a
    /// trajectory allocates nothing per sample. The same numbers as the call without `ws`.
    fn constraint_forces_in(
        &self,
        _ws: &mut Scratch,
        mode: usize,
        x: &[f64],
    ) -> Option<ConstraintForces> {
        self.constraint_forces(mode, x)
    }
    /// [`Walker::step_flags`] in the caller's scratch `ws` (see
    /// [`Walker::constraint_forces_in`]).
    fn step_flags_in(&self, _ws: &mut Scratch, mode: usize, x: &[f64]) -> Option<StepFlags> {
        self.step_flags(mode, x)
    }
    /// [`Walker::body_points`] in the caller's scratch `ws` (see
    /// [`Walker::constraint_forces_in`]): a model whose kernel needs a workspace takes it from
    /// `ws` instead of building one per call. Only the returned [`BodyPoints`] (its points and
    /// names) is allocated.
    fn body_points_in(&self, _ws: &mut Scratch, x: &[f64]) -> Option<BodyPoints> {
        self.body_points(x)
    }
    /// [`Walker::energy`] in the caller's scratch `ws` (see [`Walker::constraint_forces_in`]).
    fn energy_in(&self, _ws: &mut Scratch, x: &[f64]) -> Option<f64> {
        self.energy(x)
    }
    /// Unit of [`Walker::energy`], e.g. `"J"`, `"M g l"`.
    fn energy_unit(&self) -> &str {
        ""
    }
    /// Units of the model's time, lengths, forces and torques; SI ([`ModelUnits::SI`]) unless
    /// the model says otherwise.
    fn units(&self) -> ModelUnits {
        ModelUnits::SI
    }
    /// The impulses of the reset of guard `guard` of `mode` at the pre-impact state `x_pre`
    /// (contacts and knee stops from the impact's complementarity problem), if the model
    /// computes them.
    fn impact_report(&self, _mode: usize, _guard: usize, _x_pre: &[f64]) -> Option<ImpactReport> {
        None
    }
    /// Natural scales (total mass, leg length, gravity) for relative margins, if defined.
    fn scales(&self) -> Option<Scales> {
        None
    }
    /// The pull each locked knee's hardware holds, `[stance knee, swing knee]` (model torque
    /// units, ≥ 0): a latch's `latch_torque`, 0 for a stop (pushes only) and for an ideal latch
    /// (reported where it pulls). A lock torque `τ` (positive towards flexion,
    /// [`ConstraintForces::knee_torque`]) holds while `τ + limit ≥ 0`.
    fn knee_pull_limits(&self) -> [f64; 2] {
        [0.0; 2]
    }
    /// Height of the swing foot's lowest point above the slope at `(mode, x)` (model length
    /// units), if the model has a swing foot.
    fn swing_clearance(&self, _mode: usize, _x: &[f64]) -> Option<f64> {
        None
    }
    /// The box of section states (`lo`, `hi` per section coordinate) where the model's
    /// period-one gaits are looked for when no guess is given (a scan of the section, pdw-limit's
    /// `scan`): the physically meaningful ranges of its coordinates. `None` if the model does
    /// not say (a scan then needs a box from its caller).
    fn section_box(&self) -> Option<(Vec<f64>, Vec<f64>)> {
        None
    }
    /// Where the swing foot must clear the ground ([`ClearanceRule`]).
    fn clearance_rule(&self) -> ClearanceRule {
        ClearanceRule::AfterMidStance
    }
    /// How the state changes when the same configuration is measured in the frame of another
    /// ground line through the stance foot (random terrain): `(index, sign)` of the one absolute
    /// angle — the state component that becomes `x[index] + sign·(s' − s)` when the frame of a
    /// line inclined `s` (downhill positive) is replaced by that of a line inclined `s'`; every
    /// other component (relative angles, rates) is unchanged. `None`: the model does not walk
    /// on such terrain (e.g. round feet, whose contact point moves along the line).
    fn terrain_frame(&self) -> Option<(usize, f64)> {
        None
    }
    /// The model whose stance foot stays on its own line (the state's frame, gravity at the
    /// model's slope) and whose swing foot lands on the line through the stance foot's contact
    /// point inclined `delta` (rad, downhill positive) against it: a step of random slopes for a
    /// model whose change of line is not a rotation about the contact point (round feet,
    /// [`terrain_frame`](Walker::terrain_frame) `None`). `None` (the default): the model has no
    /// such step; `Some(Err)`: it refuses this `delta`, saying why.
    fn on_tilted_line(&self, delta: f64) -> Option<Result<Box<dyn Walker>, String>> {
        let _ = delta;
        None
    }
    /// `(index, sign)` of the state's one absolute angle, measured from the normal of the line
    /// the stance foot stands on: the stance leg is along gravity's vertical where
    /// `x[index] = sign·slope` (the mid-stance section of random terrain). Default:
    /// [`terrain_frame`](Walker::terrain_frame)'s. A model may have this angle without
    /// walking on random slopes: a round foot's angle is measured from its line as a point
    /// foot's is, but a change of line is not a rotation about its contact point, so round feet
    /// have this and no terrain frame (they walk on step heights, whose lines are parallel).
    fn absolute_angle(&self) -> Option<(usize, f64)> {
        self.terrain_frame()
    }
    /// Index of the angle between the legs whose zero is the swing foot passing the stance
    /// foot (straight legs of equal length, one mode): from there on the next foothold's
    /// height decides the heel strike, so the Markov chain of random step heights takes its
    /// section there (pdw-limit's `mid_stance`). `None` (the default): no swing leg, or legs
    /// that are not straight throughout the stride.
    fn legs_together(&self) -> Option<usize> {
        None
    }
    /// [`HybridSystem::admissible`](pdw_hybrid::HybridSystem::admissible) of the same model
    /// on another slope: whether a crossing of guard `k` of `mode` at `x` counts for the model
    /// with its slope parameter set to `slope` (every other parameter its own). A guard that
    /// measures the walker against the ground line sees no slope; one that measures it against
    /// gravity does (e.g. a stance leg that turns back while it is still behind the vertical).
    /// The lockstep walk on random terrain ([`terrain_frame`](Walker::terrain_frame)) runs
    /// every walker on the model of the mean slope and asks this for the slope of its own line.
    /// Default: [`admissible`](pdw_hybrid::HybridSystem::admissible), for models whose
    /// admissibility does not depend on the slope.
    fn admissible_on_slope(&self, mode: usize, k: usize, x: &[f64], slope: f64) -> bool {
        let _ = slope;
        self.admissible(mode, k, x)
    }
    /// The model's guards, their admissibility and its impacts at any step height (random step
    /// heights, [`StepHeight`]); `None` (the default): the model does not walk on random step
    /// heights in lockstep.
    fn step_height(&self) -> Option<&dyn StepHeight> {
        None
    }
    /// The model's stride map in closed form on any ground ([`ClosedStride`]); `None` (the
    /// default): its strides are integrated.
    fn closed_stride(&self) -> Option<&dyn ClosedStride> {
        None
    }
    /// The fully resolved model, one `key = value` line per quantity that determines its
    /// dynamics (floats in shortest round-trip form, so equal text means bit-equal values).
    /// Files that can be continued store it and refuse to continue under a different model,
    /// naming the first line that differs. The default, for models fully determined by their
    /// name and parameter values, lists those.
    fn fingerprint(&self) -> String {
        let mut s = format!("model = {}\n", self.name());
        for (n, v) in self.param_values() {
            s.push_str(&format!("{n} = {v:?}\n"));
        }
        s
    }
}

/// What a model with a `step_down` parameter (the next foothold `h` below the stance foot along
/// the slope normal, a step down positive) computes at another height `h` than its own, for the
/// lockstep walk on random step heights: every walker runs on one model and carries the height
/// of its next foothold beside its state. Each method is the model's own
/// [`HybridSystem`](pdw_hybrid::HybridSystem) method of the same name (without `_at`) for the
/// model with `step_down = h` and every other parameter its own — bit for bit: the model's
/// methods are these at its own `step_down`. The flow does not see the foothold (the dynamics
/// see angles only), so only guards, admissibility and impacts are here.
pub trait StepHeight: Sync {
    /// [`HybridSystem::guard`](pdw_hybrid::HybridSystem::guard) at step height `h`.
    fn guard_at(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], h: f64) -> f64;
    /// [`HybridSystem::guards_with_rates`](pdw_hybrid::HybridSystem::guards_with_rates) at
    /// step height `h`.
    #[allow(clippy::too_many_arguments)]
    fn guards_with_rates_at(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        f: &[f64],
        g: &mut [f64],
        rate: &mut [f64],
        h: f64,
    );
    /// [`HybridSystem::guard_gradient`](pdw_hybrid::HybridSystem::guard_gradient) at step
    /// height `h`.
    fn guard_gradient_at(
        &self,
        ws: &mut Scratch,
        mode: usize,
        k: usize,
        x: &[f64],
        grad: &mut [f64],
        h: f64,
    );
    /// [`HybridSystem::admissible`](pdw_hybrid::HybridSystem::admissible) at step height `h`.
    fn admissible_at(&self, mode: usize, k: usize, x: &[f64], h: f64) -> bool;
    /// [`HybridSystem::reset`](pdw_hybrid::HybridSystem::reset) at step height `h`.
    fn reset_at(
        &self,
        ws: &mut Scratch,
        mode: usize,
        k: usize,
        x: &[f64],
        out: &mut [f64],
        h: f64,
    ) -> usize;
    /// Whether guard `k` of `mode` is affine in the state at every step height
    /// ([`HybridSystem::guard_is_linear`](pdw_hybrid::HybridSystem::guard_is_linear) for all
    /// `h`).
    fn guard_is_linear_at_every_height(&self, mode: usize, k: usize) -> bool;
}

/// The ground of one stride of [`ClosedStride::stride_on`]: the model with its `slope` or its
/// `step_down` set to a value, every other parameter its own.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ground {
    /// The line the stride lands on is inclined by this slope (rad, downhill positive).
    Slope(f64),
    /// The foothold lies this far below the stance foot along the slope normal.
    StepDown(f64),
}

/// How a stride in closed form ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClosedEnd {
    /// It reached the section: the state just after the impact is written.
    Landed,
    /// The flow reaches the model's terminal guard `guard` (of the section's mode) first.
    Terminal { guard: usize },
    /// The closed form does not cover this start (the caller integrates the stride).
    Outside,
}

/// A stride map in closed form: the same stride as the integrated stride map of the model on
/// that ground (the flow from just after an impact to the next section event, and its reset),
/// without a tolerance — e.g. the rimless wheel's, from conservation of energy along the flow
/// and of angular momentum through the impact (Coleman; Byl & Tedrake 2009 walk it on random
/// slopes). It has no stride time budget: a stride that creeps over a maximum of the potential
/// more slowly than the budget allows completes here and times out when integrated.
pub trait ClosedStride: Sync {
    /// The stride of the model on `ground` from the full state `x` (just after an impact, in
    /// the section's mode, in the frame of that model), the full state just after the impact
    /// that ends it written to `out` when it [`ClosedEnd::Landed`].
    fn stride_on(&self, ground: Ground, x: &[f64], out: &mut [f64]) -> ClosedEnd;
}

/// A drawing of the walker in the slope frame: `x` along the slope (downhill positive), `y`
/// along the slope normal, stance foot at the origin (model length units).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Pose {
    /// Rigid links as segments.
    pub links: Vec<[[f64; 2]; 2]>,
    /// Joint and point-mass positions.
    pub joints: Vec<[f64; 2]>,
    /// The swing foot (traced in animations).
    pub swing_foot: Option<[f64; 2]>,
}

/// Named points of a walker and its centre of mass in the slope frame of [`Pose`] (`x` along
/// the slope, downhill positive; `y` along the slope normal; stance foot at the origin; model
/// length units).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BodyPoints {
    /// Point names, e.g. `["stance_foot", "hip", "swing_foot"]`; the same at every state.
    pub names: Vec<String>,
    /// Positions, one per name.
    pub points: Vec<[f64; 2]>,
    /// Centre of mass of the whole walker.
    pub com: [f64; 2],
}

/// Units of a model's quantities, as the model defines them: a dimensionless model (the
/// simplest walker: time in √(l/g), lengths in leg lengths, forces per hip weight), a model per
/// unit mass (the rimless wheel's forces in N/kg) or a spec that declares its own time unit says
/// so here, and every output labels its columns from this, never from the model's name. Angles
/// are always radians.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ModelUnits {
    /// Unit of time, e.g. `"s"`, `"sqrt(l/g)"`.
    pub time: Cow<'static, str>,
    /// Unit of length, e.g. `"m"`, `"l"` (leg lengths).
    pub length: Cow<'static, str>,
    /// Unit of force, e.g. `"N"`, `"M g"`.
    pub force: Cow<'static, str>,
    /// Unit of torque, e.g. `"N m"`, `"M g l"`.
    pub torque: Cow<'static, str>,
}

impl ModelUnits {
    /// Seconds, metres, newtons, newton metres.
    pub const SI: ModelUnits = ModelUnits {
        time: Cow::Borrowed("s"),
        length: Cow::Borrowed("m"),
        force: Cow::Borrowed("N"),
        torque: Cow::Borrowed("N m"),
    };
}
