//! The chain walker: every planar legged chain (compass gait, kneed walkers, the seed's
//! walker, users' own) from a [`WalkerSpec`], on the batched planar SOA kernel ([`pdw_soa`]).
//!
//! # Chain, frame, coordinates and signs
//! Both legs have the spec's `m` segments. The kernel chain is rooted at the stance foot and has
//! `n = 2m` revolute joints: the stance foot (joint 0), the stance knees (joints `1..m`, foot
//! side first), the hip (joint `m`), the swing knees (joints `m+1..2m`, hip side first). Link
//! `k < m` is stance segment `k` (lower end at its joint, `to_next = (0, L_k)`, COM
//! `(c⊥_k, c_k)`); the top stance segment also carries the hip mass at its upper end. Link
//! `m + j` is swing segment `m−1−j` hanging from its joint (`to_next = (0, −L)`, COM
//! `(c⊥, −(L − c))`). Slope frame of the kernel: `y` along the slope **downhill**, `z` normal to
//! the slope, up; angles positive from `+y` to `+z`; gravity as the base acceleration
//! `[0, −g sin γ, g cos γ]` (seed eq. 3.12). State `x = (q, q̇)`, `q₀` the stance leg's angle from
//! the slope normal (positive: stance foot ahead of the hip — Garcia's θ), `q_m` the hip angle
//! (swing leg relative to the stance leg; `q_m = 0`: legs together). Knee flexion: a stance knee
//! flexes with `q > 0`, a swing knee with `q < 0`; a knee is straight at `q = 0`.
//!
//! # Modes
//! With a free-swing knee: mode 0 ([`FREE`]) — the swing knee is free, every other knee is a
//! pseudo joint (seed §3.4, `q̈ = 0`); mode 1 ([`LOCKED`]) — every knee locked. Without one:
//! a single mode 0 with every knee locked. The flow is the batched articulated-body recursion
//! with the locked joints welded ([`pdw_soa::batch_aba_view`]) over all lanes of a mode; the
//! scalar [`HybridSystem::flow`] is its one-lane case, so a lane of a batch equals the scalar
//! run bit for bit.
//!
//! # Guards
//! Free mode: 0 `knee_strike` (the free knee's angle rising through 0, reset → locked mode);
//! 1 `foot_strike_knee_bent` (terminal [`FallKind::KneeBent`]: swing-foot height falling through
//! 0 ahead of the stance foot). Locked mode: 0 `heel_strike` (swing-foot height falling through
//! 0, admissible with the swing foot ahead and on the heel-strike factor `|2θ_s + q_m| < |q_m|`,
//! `θ_s` the stance leg's absolute angle — with straight legs the swing-foot height is
//! `2L sin(θ_s + q_m/2) sin(q_m/2)`). Both modes then: `stance_reverses` (`q̇₀` rising through 0
//! while `q₀ > γ`, [`FallKind::Backward`]), `hip_on_ground_behind` (`q₀ − π/2` rising,
//! backward), `hip_on_ground_ahead` (`q₀ + π/2` falling, [`FallKind::Forward`]). Last, each
//! mode's impact guard has a twin on the same surface, `knee_strike_buckles` /
//! `heel_strike_buckles` (terminal [`FallKind::KneeBuckled`]): at the crossing the impact's
//! complementarity problem (below) decides which of the two counts.
//!
//! # Impacts: one set of impulse equations, unilateral contacts and stops
//! Every impact is solved on the floating chain `(y, z, q)` rooted at the stance arc centre
//! (the stance foot for point feet) by [`pdw_soa::unilateral_impact`]:
//! `𝓜(q̇⁺ − q̇⁻) = Aᵀλ`, `A_active q̇⁺ = 0`, with `q̇⁻_F = (−r q̇₀, 0, q̇)`. The rows are the
//! contacts — the stance foot's contact point (rolling: `ẏ + r q̇₀ = 0`, `ż = 0`; after the
//! impact the contact point, not the arc centre, is at rest) or the striking swing foot's — and
//! the knees' hyper-extension stops (`±e_k`: a stop allows flexion only and pushes only).
//! A knee whose spec says `hold = "latch"` (the published kneed walkers' and the seed's locked
//! knees) is held both ways: its row is never released, so it never buckles; its impulse is
//! still reported, and a negative one (a pull) makes the gait invalid as a walker with stops.
//! - Knee strike: the stance contact and the striking knee hold by definition; every other
//!   knee's stop is unilateral. If the complementarity problem (contacts and stops push only)
//!   releases a stance knee, the stance leg buckles: the twin guard fires, a named fall.
//! - Heel strike: the striking foot holds by definition; the trailing foot and every knee stop
//!   are unilateral. A released knee of the new stance leg buckles it (the twin guard).
//!
//! The model's heel-strike map releases the trailing foot and holds every knee but one: the
//! trailing knee that becomes the free swing knee, when a stop (not a latch) holds it, is
//! released where its stop would have to pull with the others held — the mode change of the
//! model: the new swing knee starts flexing at the impact's rate, the section carries that rate
//! (`swing_knee_rate`, below) and the stride map and its Jacobian stay exact (piecewise: the
//! map is continuous across the switch, where the released rate and the held impulse both
//! vanish). Where the complementarity problem would instead release another trailing knee
//! (three-segment legs), a latched trailing knee, or keep the trailing foot on the ground, the
//! map keeps the model's set; its impact report ([`ChainWalker::impact_report_at`],
//! [`Walker::impact_report`]) shows the negative margin and the gait is invalid — never
//! silently valid.
//!
//! # Latches with holding limits
//! A knee with `hold = "latch"` and `latch_torque = L_τ` / `latch_impulse = L_Λ` (two-segment
//! legs with a free swing knee; the spec refuses limits elsewhere) holds a pull up to those
//! limits and lets go beyond them; the model then goes on with the knee released:
//! - in stance (both modes) the guard `stance_latch_releases` is the stance knee's lock torque
//!   towards flexion plus `L_τ` (the pseudo joint's locking torque, seed eq. 3.18–3.23, by
//!   [`pdw_soa::pseudo_joint_dynamics`]), falling through 0 where the pull exceeds `L_τ`. The
//!   released stance knee buckles under the walker's weight: terminal, the fall
//!   [`FallKind::KneeBuckled`] the impacts name too;
//! - in the locked mode the guard `swing_latch_releases` is the swing knee's lock torque plus
//!   `L_τ`: where it falls through 0 the swing knee swings free again (reset to the free mode,
//!   the state unchanged) until its next knee strike;
//! - at an impact the latch is a constraint that may release: the model's map holds it where
//!   its impulse is `≥ −L_Λ`. A stance knee (at the knee strike) or new stance knee (at heel
//!   strike) that would pull more buckles its leg (the twin guard, as a stop's); the trailing
//!   knee that becomes the free swing knee is released as a stop's is (its impulse `< −L_Λ`
//!   instead of `< 0`), so the section has `swing_knee_rate`. A released latch gives no
//!   impulse (it lets go entirely), so the map jumps where the pull crosses `L_Λ`.
//!
//! A swing latch already beyond its limit just after the knee strike lets go at once (the
//! knee strike's reset returns to the free mode). A stance latch already beyond its limit just
//! after an impact is not caught (its guard needs a crossing): the gait's stance pull peaks
//! inside the stance, and validity reports any pull beyond the limit as a violation.
//! Without limits a latch is ideal (held both ways at every load), exactly as before limits
//! existed: no latch guard, no `swing_knee_rate`, the same bits. Margins (pdw-limit's
//! validity): a torque's `τ + L_τ` on `m g l`, an impulse's `Λ + L_Λ` on `m l √(g l)`.
//!
//! # Resets
//! - Knee strike: plastic lock of the free knee with the stance foot's contact point at rest and
//!   the other knees held. Point feet: the stance foot pinned, kernel
//!   [`pdw_soa::joint_lock_impact`] (`q̇⁺ = q̇⁻ − 𝓜⁻¹Eᵀ(E𝓜⁻¹Eᵀ)⁻¹E q̇⁻`, the same map as the
//!   floating chain's); round feet: the floating chain's impact problem above (the rolling
//!   contact conserves the walker's angular momentum about the contact point and the swing
//!   leg's about the hip). The knee angle and locked rates are set to exactly 0.
//! - Heel strike: plastic impact at the swing foot with every knee held and the old stance foot
//!   free (kernel [`pdw_soa::tip_impact`] on the floating chain `(P_y, P_z, q…)`), then the leg
//!   swap (the seed's switch rule, eq. 3.29–3.32): `q₀' = Σq`, new stance knees `= −`old swing
//!   knees, `q_m' = −q_m`, new swing knees `= −`old stance knees (same for the rates). The kernel
//!   requires positive link masses, so the two prismatic base links carry
//!   [`FLOATING_BASE_MASS`] = 1e-30 kg, which changes no sum of masses by even one ulp.
//!
//! # Round feet (`foot_radius = r > 0`)
//! Each lowest segment ends in a circular arc of radius `r` whose centre lies on the segment's
//! line `r` above its lower end (McGeer 1990, "Passive dynamic walking", IJRR 9(2)). The kernel
//! chain is then rooted at the stance arc centre (the stance shank shortened by `r`, its COM
//! measured from the arc centre) and ends at the swing arc centre. Stance: the foot rolls
//! without slip, so the arc centre stays `r` above the slope and moves along it by
//! `y = −r q₀` — a constant-Jacobian holonomic constraint on the floating chain `(y, z, q)`,
//! solved by [`pdw_soa::rolling_base_dynamics`] (`Jᵀ𝓜_F J q̈ = −Jᵀ C_F`, locked knees welded),
//! lane by lane in the batched flow (the scalar flow is its one-lane case). The swing arc's
//! lowest point is `r` below its centre, so the swing-foot guard (lowest point of the swing
//! arc above the slope) is the height of the swing arc centre over the stance arc centre, and
//! the step length is the distance between the two contact points. Heel strike: plastic impact
//! at the new contact point `[0, −r]` below the swing arc centre with the stance arc centre
//! moving at `ẏ = −r q̇₀` before it ([`pdw_soa::contact_impact`]; afterwards the new contact
//! point is at rest, i.e. the new stance foot rolls), then the same leg swap. Ground reaction:
//! the floating chain's base forces `[f_y, f_z]` at the contact point from `ID_F`; knee locks
//! from `ID_F` too. Energy counts the arc centre's travel. `r = 0` runs the point-foot code
//! unchanged.
//!
//! # Step down (random step heights; Schwab & Wisse 2001, Hobbelen & Wisse 2007)
//! With `step_down = h ≠ 0` the next foothold lies `h` below the stance foot along the slope
//! normal (a step down positive, up negative), on a line parallel to the slope — the simplest
//! walker's convention. Both swing-foot guards (`heel_strike`, `foot_strike_knee_bent` and
//! their twins) measure the foot's height over that line, `z + h`, `z` the height over the
//! stance foot's line; `heel_strike` is admissible with the swing foot ahead (the heel-strike
//! factor above tells a level-ground strike from the mid-stance crossing of `z = 0`, which a
//! foothold `h ≠ 0` away does not have). The impacts are unchanged in form: they depend on the
//! configuration at contact only. The dynamics see angles only, and every angle stays measured
//! from the slope normal, so the next step starts from the new stance foot with nothing
//! shifted. After a strike onto `h` the straight trailing leg's foot is `h` above the new
//! stance foot, so the lift of the model with `step_down = h` puts it there:
//! `ψ = −acos(cos q₀ − h/ℓ)` (behind), `q_m = ψ − q₀`, `ℓ` the leg length
//! ([`ChainWalker::trailing_leg_angle`]); at `h = 0` the level-ground lift and guards run
//! unchanged, bit for bit. [`Walker::swing_clearance`] measures a swing foot ahead of the
//! stance foot from the foothold's line when `h > 0` (a step down is not a scuff).
//!
//! Round feet take steps the same way, because both lines are parallel: every arc centre
//! stands `r` above the line its foot touches, so the swing arc's lowest point is `z + h` above
//! the foothold's line with `z` the height of the swing arc centre over the stance arc centre
//! (the level-ground guard's `z`); the impact's rows (the new contact point `r` below the swing
//! arc centre at rest, the trailing contact released) have the same directions on either
//! line; and the lift's `ℓ` is the length from the hip to the arc centre, `L − r` (the trailing
//! arc centre is `h` above the new stance arc centre). A height of `ℓ` or more is refused.
//!
//! # Landing on a tilted line (random slopes with round feet)
//! [`ChainWalker::with_tilt`]`(Δ)` keeps the stance foot on its line (the kernel's frame,
//! gravity at `slope`) and lands the swing foot on the line through the stance foot's contact
//! point `c` inclined `Δ` against it (downhill positive: tangent `t = (cos Δ, −sin Δ)`, normal
//! `n = (sin Δ, cos Δ)` in `(y, z)`). With `p` the swing arc centre relative to the stance arc
//! centre (so `c = (0, −r)` relative to it), the swing arc's lowest point over the landing line
//! is `(p − c)·n − r = p·n + r (cos Δ − 1)` — the swing-foot guards (and `ṗ·n` their rate,
//! `n`-weighted rows of the tip Jacobian their gradient); the foot is ahead where `p·t > 0`,
//! and the heel-strike factor is the level one in the landing line's frame, whose absolute
//! angle is `q₀ + Δ`: `|2(θ_s + Δ) + q_m| < |q_m|`. The heel strike's new contact point is
//! `r` along `−n` from the swing arc centre; the trailing foot's row (on the stance line) is
//! unchanged; the impact report gives the new stance foot's impulse along `(t, n)`. For point
//! feet (`r = 0`) all of this is the level model in the landing line's frame (the state's
//! `q₀ + Δ`), which is how point feet walk random slopes; with round feet it is how they do
//! (pdw-limit's `terrain`, "Round feet"). The guards run lane by lane on a tilted line. At
//! `Δ = 0` nothing changes, bit for bit.
//!
//! # Section
//! Just after heel strike, every knee straight: `q = (s₀, 0…, −2s₀, 0…)`,
//! `q̇ = (s₁, 0…, s₂, 0…)`; reduced coordinates `(q₀, q̇₀, q̇_m)` (`"stance"`, `"stance_rate"`,
//! `"hip_rate"`). A walker whose free swing knee is held by a stop while in stance
//! ([`section_names_of`]) has a fourth, `"swing_knee_rate"` `s₃` (the free knee's rate, ≤ 0
//! when the knee left the heel strike flexing, 0 when its stop held).
//!
//! # Layout
//! One file per operation: `construction` (the kernel chains and the knees from a spec),
//! `geometry` (the swing foot, the foothold and landing lines, the leg swap), `dynamics` (the
//! stance flow and constraint forces), `guards`, `impacts` (the impact problems and reports),
//! `resets` (the reset maps and their Jacobians), `hybrid` ([`HybridSystem`] and
//! [`StepHeight`]), `section` and `walker` ([`Walker`]).

mod construction;
mod dynamics;
mod geometry;
mod guards;
mod hybrid;
mod impacts;
mod resets;
mod section;
mod walker;

pub use section::section_names_of;

use crate::spec::{ParamTable, Resolved, WalkerSpec};
use pdw_hybrid::Scratch;
use pdw_soa::{BatchWorkspace, Chain, Workspace};
// the module docs' links
#[cfg(doc)]
use pdw_hybrid::{FallKind, HybridSystem};
#[cfg(doc)]
use pdw_model::{StepHeight, Walker};

/// Mode with the swing knee free (only with a free-swing knee).
pub const FREE: usize = 0;
/// Mode with every knee locked (mode 0 when there is no free-swing knee).
pub const LOCKED: usize = 1;
/// Mass (kg) of the fictitious prismatic base links of the floating chain used for heel strikes.
pub const FLOATING_BASE_MASS: f64 = 1e-30;
/// Largest number of segments per leg.
pub const MAX_SEGMENTS: usize = 3;

// The kernel's exact derivatives take chains of at most `MAX_DOF` joints; the longest chain a
// spec can ask for is the floating chain of heel strikes and round feet (two prismatic base
// joints, then both legs), so no spec meets that cap.
const _: () = assert!(2 + 2 * MAX_SEGMENTS <= pdw_soa::derivatives::MAX_DOF);

/// Largest state dimension `2n` of a chain walker.
const DMAX: usize = 4 * MAX_SEGMENTS;
/// Largest joint count of the floating chain.
const FMAX: usize = 2 * MAX_SEGMENTS + 2;

/// The chain walker (immutable model, shared by threads). See the module docs.
#[derive(Clone, Debug)]
pub struct ChainWalker {
    spec: WalkerSpec,
    table: ParamTable,
    r: Resolved,
    /// segments per leg
    m: usize,
    /// joints, `2m`
    n: usize,
    chain: Chain,
    floating: Chain,
    /// signed link lengths along each link's z axis (stance `+L`, swing `−L`)
    len: Vec<f64>,
    leg_length: f64,
    /// round-foot radius (0: point feet)
    radius: f64,
    /// joint index of the free swing knee
    free_knee: Option<usize>,
    /// locked-joint mask per mode (index by mode)
    masks: Vec<Vec<bool>>,
    /// locked joints per mode
    locked: Vec<Vec<usize>>,
    /// knee joints of the floating chain (offset by the two base joints)
    floating_knees: Vec<usize>,
    /// per joint: a knee held by a latch (both ways) rather than a stop
    latched: Vec<bool>,
    /// the stance joint of the trailing knee that becomes the free swing knee at heel strike,
    /// when it is held by a stop or a latch with a `latch_impulse` (its release at heel strike
    /// is a mode change of the model)
    trailing_free: Option<usize>,
    /// the latch's `latch_torque` (two-segment legs with a free swing knee only; `None`: a stop
    /// or an ideal latch)
    latch_torque: Option<f64>,
    /// the latch's `latch_impulse` (as `latch_torque`)
    latch_impulse: Option<f64>,
    state_names: Vec<String>,
    /// inclination `Δ` of the landing line against the stance foot's line (0: the same line;
    /// module docs, "Landing on a tilted line")
    tilt: f64,
    /// `(sin Δ, cos Δ)`: the landing line's normal `n = (sin Δ, cos Δ)` in the stance line's
    /// frame
    tilt_sc: (f64, f64),
}

/// The chain walker's scratch (held in a [`Scratch`]): kernel workspaces sized by the number
/// of joints, so that chain walkers of equal size share one.
pub struct ChainScratch {
    n: usize,
    bw: BatchWorkspace,
    ws: Workspace,
    fws: Workspace,
    zeros: Vec<f64>,
    q: Vec<f64>,
    qd: Vec<f64>,
    v: Vec<f64>,
    imp: Vec<f64>,
}

impl ChainScratch {
    fn new(w: &ChainWalker) -> Self {
        let n = w.n;
        Self {
            n,
            bw: BatchWorkspace::new(&w.chain, pdw_soa::batch::BLOCK),
            ws: Workspace::new(&w.chain),
            fws: Workspace::new(&w.floating),
            zeros: vec![0.0; n + 2],
            q: vec![0.0; n + 2],
            qd: vec![0.0; n + 2],
            v: vec![0.0; n + 2],
            imp: vec![0.0; n + 2],
        }
    }
}

impl ChainWalker {
    /// Inclination `Δ` of the landing line against the stance line (0 unless
    /// [`ChainWalker::with_tilt`]).
    pub fn tilt(&self) -> f64 {
        self.tilt
    }

    /// The spec the walker was built from.
    pub fn spec(&self) -> &WalkerSpec {
        &self.spec
    }

    /// The evaluated geometry.
    pub fn resolved(&self) -> &Resolved {
        &self.r
    }

    /// The kernel chain rooted at the stance foot (tip: the swing foot).
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// Segments per leg.
    pub fn segments(&self) -> usize {
        self.m
    }

    /// Leg length (sum of the segment lengths).
    pub fn leg_length(&self) -> f64 {
        self.leg_length
    }

    /// Radius of the round feet (0: point feet).
    pub fn foot_radius(&self) -> f64 {
        self.radius
    }

    /// The floating chain (prismatic `y`, `z` at the stance arc centre, then the walker's
    /// joints) used by heel strikes and round feet.
    pub fn floating_chain(&self) -> &Chain {
        &self.floating
    }

    /// Joint index of the free swing knee, if the spec has one.
    pub fn free_knee(&self) -> Option<usize> {
        self.free_knee
    }

    /// Mode in which every knee is locked (the mode of the heel strike).
    pub fn locked_mode(&self) -> usize {
        if self.free_knee.is_some() {
            LOCKED
        } else {
            0
        }
    }

    /// Joints held locked (pseudo joints) in `mode`.
    pub fn locked_joints(&self, mode: usize) -> &[usize] {
        &self.locked[mode]
    }

    /// The latch's `latch_torque` and `latch_impulse` (`None`: a stop, an ideal latch).
    pub fn latch_limits(&self) -> (Option<f64>, Option<f64>) {
        (self.latch_torque, self.latch_impulse)
    }

    fn scratch<'a>(&self, ws: &'a mut Scratch) -> &'a mut ChainScratch {
        ws.get_or_init(|| ChainScratch::new(self), |s: &ChainScratch| s.n == self.n)
    }
}
