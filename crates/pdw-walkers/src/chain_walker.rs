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

use crate::error::WalkerError;
use crate::spec::{ParamTable, Resolved, WalkerSpec};
use crate::validity::{
    ClearanceRule, ConstraintForces, ImpactReport, ImpulseEntry, ImpulseKind, Scales, StepFlags,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{MatMut, MatRef};
use pdw_hybrid::{Crossing, FallKind, GuardKind, GuardSpec, HybridSystem, Scratch, Section};
use pdw_model::{BodyPoints, GaitGuess, Pose, StepHeight, Walker};
use pdw_soa::{BatchWorkspace, Chain, ChainBuilder, Link, Workspace};
use std::f64::consts::FRAC_PI_2;

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

const SECTION_NAMES: [&str; 4] = ["stance", "stance_rate", "hip_rate", "swing_knee_rate"];

/// The section coordinates of a chain walker resolved as `r`: `(stance, stance_rate,
/// hip_rate)`, and `swing_knee_rate` when the swing knee is free and held by a stop or by a
/// latch with a `latch_impulse` while its leg is the stance leg — it may release at heel
/// strike, and the new swing knee then starts flexing (module docs, "Section", "Latches").
pub fn section_names_of(r: &Resolved) -> &'static [&'static str] {
    let releases = r
        .free_swing
        .iter()
        .zip(r.latched.iter().zip(&r.latch_impulse))
        .any(|(free, (latched, limit))| *free && (!*latched || limit.is_some()));
    if releases {
        &SECTION_NAMES
    } else {
        &SECTION_NAMES[..3]
    }
}

const FALLS: [GuardSpec; 3] = [
    GuardSpec {
        name: "stance_reverses",
        crossing: Crossing::Rising,
        kind: GuardKind::Terminal(FallKind::Backward),
    },
    GuardSpec {
        name: "hip_on_ground_behind",
        crossing: Crossing::Rising,
        kind: GuardKind::Terminal(FallKind::Backward),
    },
    GuardSpec {
        name: "hip_on_ground_ahead",
        crossing: Crossing::Falling,
        kind: GuardKind::Terminal(FallKind::Forward),
    },
];

const GUARDS_FREE: [GuardSpec; 6] = [
    GuardSpec {
        name: "knee_strike",
        crossing: Crossing::Rising,
        kind: GuardKind::Reset,
    },
    GuardSpec {
        name: "foot_strike_knee_bent",
        crossing: Crossing::Falling,
        kind: GuardKind::Terminal(FallKind::KneeBent),
    },
    FALLS[0],
    FALLS[1],
    FALLS[2],
    GuardSpec {
        name: "knee_strike_buckles",
        crossing: Crossing::Rising,
        kind: GuardKind::Terminal(FallKind::KneeBuckled),
    },
];

const GUARDS_LOCKED: [GuardSpec; 5] = [
    GuardSpec {
        name: "heel_strike",
        crossing: Crossing::Falling,
        kind: GuardKind::Reset,
    },
    FALLS[0],
    FALLS[1],
    FALLS[2],
    GuardSpec {
        name: "heel_strike_buckles",
        crossing: Crossing::Falling,
        kind: GuardKind::Terminal(FallKind::KneeBuckled),
    },
];

/// The guard of a stance knee's latch letting go (module docs, "Latches"): its lock torque
/// plus `latch_torque` falling through 0. The stance leg buckles: a fall.
const STANCE_LATCH: GuardSpec = GuardSpec {
    name: "stance_latch_releases",
    crossing: Crossing::Falling,
    kind: GuardKind::Terminal(FallKind::KneeBuckled),
};

/// The guard of the locked swing knee's latch letting go (module docs, "Latches"): reset to
/// the mode with the swing knee free, the state unchanged.
const SWING_LATCH: GuardSpec = GuardSpec {
    name: "swing_latch_releases",
    crossing: Crossing::Falling,
    kind: GuardKind::Reset,
};

/// The free mode's guards of a walker whose latch has a `latch_torque`.
const GUARDS_FREE_LATCH: [GuardSpec; 7] = [
    GUARDS_FREE[0],
    GUARDS_FREE[1],
    GUARDS_FREE[2],
    GUARDS_FREE[3],
    GUARDS_FREE[4],
    GUARDS_FREE[5],
    STANCE_LATCH,
];

/// The locked mode's guards of a walker whose latch has a `latch_torque`.
const GUARDS_LOCKED_LATCH: [GuardSpec; 7] = [
    GUARDS_LOCKED[0],
    GUARDS_LOCKED[1],
    GUARDS_LOCKED[2],
    GUARDS_LOCKED[3],
    GUARDS_LOCKED[4],
    STANCE_LATCH,
    SWING_LATCH,
];

/// Which latch a latch guard watches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum LatchGuard {
    Stance,
    Swing,
}

/// Index of the twin of guard 0 (the impact guard) in `mode`: the same function, a fall where the
/// impact's complementarity problem releases a stance knee (see the module docs).
const TWIN_FREE: usize = 5;
const TWIN_LOCKED: usize = 4;

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
    /// Builds the walker from a spec at its default parameter values.
    pub fn from_spec(spec: WalkerSpec) -> Result<Self, WalkerError> {
        let values = spec.param_table().values;
        Self::new(spec, &values)
    }

    /// Builds the walker from a spec at parameter values `values` (in
    /// [`WalkerSpec::param_table`] order).
    pub fn new(spec: WalkerSpec, values: &[f64]) -> Result<Self, WalkerError> {
        let r = spec.resolve(values)?;
        let m = r.segments.len();
        if m > MAX_SEGMENTS {
            return Err(WalkerError::InvalidSpec {
                source_name: spec.name.clone(),
                field: "segments".into(),
                value: format!("{m} segments"),
                rule: format!("at most {MAX_SEGMENTS} segments per leg"),
            });
        }
        let n = 2 * m;
        check_step_down(&spec, &r)?;
        let mut table = spec.param_table();
        table.values = values.to_vec();
        let mut links = Vec::with_capacity(n);
        // with round feet the chain is rooted at the stance foot's arc centre, `r` above the
        // foot's lower end on the lowest segment; the swing chain ends at the swing arc centre
        let radius = r.foot_radius;
        let cut = |k: usize| if k == 0 { radius } else { 0.0 };
        for (k, s) in r.segments.iter().enumerate() {
            let [l, mass, c, cn, inertia] = *s;
            let l = l - cut(k);
            let c = c - cut(k);
            let mut link = Link {
                to_next: [0.0, l],
                com: [cn, c],
                mass,
                inertia,
            };
            if k + 1 == m && r.hip_mass > 0.0 {
                link = add_point_mass(link, r.hip_mass, [0.0, l]);
            }
            links.push(link);
        }
        for (k, s) in r.segments.iter().enumerate().rev() {
            let [l, mass, c, cn, inertia] = *s;
            links.push(Link {
                to_next: [0.0, -(l - cut(k))],
                com: [cn, -(l - c)],
                mass,
                inertia,
            });
        }
        let kernel_error = |e: pdw_soa::SoaError| WalkerError::InvalidSpec {
            source_name: spec.name.clone(),
            field: "segments".into(),
            value: "the chain".into(),
            rule: format!("the kernel rejects the chain: {e}"),
        };
        let mut b = ChainBuilder::new().gravity(r.gravity).slope(r.slope);
        for l in &links {
            b = b.revolute(*l);
        }
        let chain = b.build().map_err(kernel_error)?;
        let base = Link {
            to_next: [0.0, 0.0],
            com: [0.0, 0.0],
            mass: FLOATING_BASE_MASS,
            inertia: 0.0,
        };
        let mut fb = ChainBuilder::new()
            .gravity(r.gravity)
            .slope(r.slope)
            .prismatic([1.0, 0.0], base)
            .prismatic([0.0, 1.0], base);
        for l in &links {
            fb = fb.revolute(*l);
        }
        let floating = fb.build().map_err(kernel_error)?;
        let len: Vec<f64> = links.iter().map(|l| l.to_next[1]).collect();
        let leg_length = r.segments.iter().map(|s| s[0]).sum();
        let knees: Vec<usize> = (1..m).chain(m + 1..n).collect();
        let free_knee = r.free_swing.iter().position(|f| *f).map(|i| 2 * m - 1 - i);
        // knee i (foot side first) is stance joint i + 1 and swing joint 2m − 1 − i
        let mut latched = vec![false; n];
        for (i, l) in r.latched.iter().enumerate() {
            latched[i + 1] = *l;
            latched[2 * m - 1 - i] = *l;
        }
        let locked_mode = |free: Option<usize>| -> Vec<usize> {
            knees.iter().copied().filter(|k| Some(*k) != free).collect()
        };
        let locked: Vec<Vec<usize>> = match free_knee {
            Some(f) => vec![locked_mode(Some(f)), locked_mode(None)],
            None => vec![locked_mode(None)],
        };
        let masks = locked
            .iter()
            .map(|l| (0..n).map(|k| l.contains(&k)).collect())
            .collect();
        let floating_knees = knees.iter().map(|k| k + 2).collect();
        // old stance joint i + 1 becomes new swing joint 2m − 1 − i at the leg swap
        let latch_torque = r.latch_torque.iter().flatten().copied().next();
        let latch_impulse = r.latch_impulse.iter().flatten().copied().next();
        let trailing_free = free_knee
            .map(|fk| 2 * m - fk)
            .filter(|j| !latched[*j] || latch_impulse.is_some());
        let mut names = vec!["stance".to_string()];
        let knee_name = |side: &str, i: usize| {
            if m == 2 {
                format!("{side}_knee")
            } else {
                format!("{side}_knee{}", i + 1)
            }
        };
        names.extend((0..m - 1).map(|i| knee_name("stance", i)));
        names.push("hip".into());
        names.extend((0..m - 1).rev().map(|i| knee_name("swing", i)));
        let rates: Vec<String> = names.iter().map(|s| format!("{s}_rate")).collect();
        names.extend(rates);
        Ok(Self {
            spec,
            table,
            r,
            m,
            n,
            chain,
            floating,
            len,
            leg_length,
            radius,
            free_knee,
            masks,
            locked,
            floating_knees,
            latched,
            trailing_free,
            latch_torque,
            latch_impulse,
            state_names: names,
            tilt: 0.0,
            tilt_sc: (0.0, 1.0),
        })
    }

    /// The same walker landing on a line through the stance foot's contact point inclined `Δ`
    /// (`delta`, rad, downhill positive) against the line the stance foot stands on (module
    /// docs, "Landing on a tilted line"): one step of random slopes for round feet. The state
    /// stays in the stance line's frame (gravity at the spec's `slope`); the swing-foot guards,
    /// the heel strike's admissibility and contact point see the landing line. Refused with
    /// `step_down ≠ 0` (one ground change per step) and for `|Δ| ≥ π/4`.
    pub fn with_tilt(&self, delta: f64) -> Result<Self, WalkerError> {
        if !(delta.is_finite() && delta.abs() < std::f64::consts::FRAC_PI_4) {
            return Err(WalkerError::InvalidSpec {
                source_name: self.spec.name.clone(),
                field: "tilt".into(),
                value: delta.to_string(),
                rule: "a landing line inclined less than pi/4 rad against the stance line".into(),
            });
        }
        if self.r.step_down != 0.0 && delta != 0.0 {
            return Err(WalkerError::InvalidSpec {
                source_name: self.spec.name.clone(),
                field: "parameters.step_down".into(),
                value: self.r.step_down.to_string(),
                rule: "a tilted landing line starts at the stance foot: step_down must be 0".into(),
            });
        }
        let mut w = self.clone();
        w.tilt = delta;
        w.tilt_sc = if delta == 0.0 {
            (0.0, 1.0)
        } else {
            delta.sin_cos()
        };
        Ok(w)
    }

    /// The new contact point from the swing arc centre at a heel strike: `r` along the landing
    /// line's inward normal, `−r n = −r (sin Δ, cos Δ)` (`[0, −r]` on the stance line).
    fn landing_offset(&self) -> [f64; 2] {
        if self.tilt == 0.0 {
            [0.0, -self.radius]
        } else {
            let (s, c) = self.tilt_sc;
            [-self.radius * s, -self.radius * c]
        }
    }

    /// Inclination `Δ` of the landing line against the stance line (0 unless
    /// [`ChainWalker::with_tilt`]).
    pub fn tilt(&self) -> f64 {
        self.tilt
    }

    /// Height of the swing arc's lowest point over the tilted landing line (module docs,
    /// "Landing on a tilted line"), from the swing arc centre `p` relative to the stance arc
    /// centre: `p·n + r (cos Δ − 1)`; its rate from `ṗ`.
    #[inline]
    fn above_tilted(&self, p: [f64; 2], pd: [f64; 2]) -> (f64, f64) {
        let (s, c) = self.tilt_sc;
        (
            p[0] * s + p[1] * c + self.radius * (c - 1.0),
            pd[0] * s + pd[1] * c,
        )
    }

    /// The swing arc centre relative to the stance arc centre ([`ChainWalker::swing_foot`])
    /// and its rate along `f = (q̇, q̈)`: `ṗ = Σ len_i θ̇_i (−cos θ_i, −sin θ_i)`.
    fn swing_foot_and_rate(&self, x: &[f64], f: &[f64]) -> ([f64; 2], [f64; 2]) {
        let (mut th, mut thd) = (0.0, 0.0);
        let (mut p, mut pd) = ([0.0; 2], [0.0; 2]);
        for ((qk, fk), len) in x[..self.n].iter().zip(&f[..self.n]).zip(&self.len) {
            th += qk;
            thd += fk;
            let (s, c) = pdw_simd::sincos(th);
            p[0] -= len * s;
            p[1] += len * c;
            pd[0] -= len * c * thd;
            pd[1] -= len * s * thd;
        }
        (p, pd)
    }

    /// Whether the swing foot is ahead of the stance foot: along the stance line, or along the
    /// landing line when it is tilted (its tangent `(cos Δ, −sin Δ)`).
    fn swing_ahead(&self, x: &[f64]) -> bool {
        let p = self.swing_foot(x);
        if self.tilt == 0.0 {
            p[0] > 0.0
        } else {
            let (s, c) = self.tilt_sc;
            p[0] * c - p[1] * s > 0.0
        }
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

    /// Swing-foot position `[y, z]` relative to the stance foot (sin/cos by the kernel's
    /// routine, so that the batched guard gives the same bits).
    pub fn swing_foot(&self, x: &[f64]) -> [f64; 2] {
        let mut th = 0.0;
        let mut p = [0.0, 0.0];
        for (qk, len) in x[..self.n].iter().zip(&self.len) {
            th += qk;
            let (s, c) = pdw_simd::sincos(th);
            p[0] -= len * s;
            p[1] += len * c;
        }
        p
    }

    /// Swing-foot height for every lane of `x` (`lanes × 2n`), four lanes at a time with the
    /// arithmetic of [`ChainWalker::swing_foot`].
    #[inline(always)]
    fn foot_height_lanes(&self, x: MatRef<'_, f64>, out: &mut [f64]) {
        let lanes = x.nrows();
        let mut cols: [&[f64]; 2 * MAX_SEGMENTS] = [&[]; 2 * MAX_SEGMENTS];
        for (k, c) in cols.iter_mut().enumerate().take(self.n) {
            *c = match x.col(k).try_as_col_major() {
                Some(v) => v.as_slice(),
                None => {
                    // non-contiguous view: lane by lane
                    let mut xi = [0.0; 4 * MAX_SEGMENTS];
                    for (l, o) in out.iter_mut().enumerate().take(lanes) {
                        for j in 0..self.n {
                            xi[j] = x[(l, j)];
                        }
                        *o = self.swing_foot(&xi)[1];
                    }
                    return;
                }
            };
        }
        let mut l0 = 0;
        while l0 < lanes {
            let w = (lanes - l0).min(4);
            let mut th = [0.0; 4];
            let mut z = [0.0; 4];
            for (col, len) in cols[..self.n].iter().zip(&self.len) {
                for i in 0..w {
                    th[i] += col[l0 + i];
                }
                let (_, c) = pdw_simd::sincos_lanes(th);
                for i in 0..4 {
                    z[i] += *len * c[i];
                }
            }
            out[l0..l0 + w].copy_from_slice(&z[..w]);
            l0 += w;
        }
    }

    /// Swing-foot height (the bits of [`ChainWalker::swing_foot`]'s second component) and its
    /// rate along the flow `ż = ∇z·f = −Σ_i len_i sin θ_i θ̇_i`, with `θ_i = q₀ + … + q_i` and
    /// `θ̇_i = f₀ + … + f_i` read from `f = (q̇, q̈)`.
    fn foot_height_and_rate(&self, x: &[f64], f: &[f64]) -> (f64, f64) {
        let (mut th, mut thd, mut z, mut zr) = (0.0, 0.0, 0.0, 0.0);
        for ((qk, fk), len) in x[..self.n].iter().zip(&f[..self.n]).zip(&self.len) {
            th += qk;
            thd += fk;
            let (s, c) = pdw_simd::sincos(th);
            z += len * c;
            zr -= len * s * thd;
        }
        (z, zr)
    }

    /// [`ChainWalker::foot_height_and_rate`] for every lane (four at a time, the same operations
    /// per lane), from column slices of `x` and `f`.
    #[inline(always)]
    fn foot_height_rate_lanes(
        &self,
        xc: &[&[f64]],
        fc: &[&[f64]],
        lanes: usize,
        z_out: &mut [f64],
        r_out: &mut [f64],
    ) {
        let mut l0 = 0;
        while l0 < lanes {
            let w = (lanes - l0).min(4);
            let (mut th, mut thd, mut z, mut zr) = ([0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4]);
            for ((xk, fk), len) in xc.iter().zip(fc).zip(&self.len) {
                for i in 0..w {
                    th[i] += xk[l0 + i];
                    thd[i] += fk[l0 + i];
                }
                let (s, c) = pdw_simd::sincos_lanes(th);
                for i in 0..4 {
                    z[i] += *len * c[i];
                    zr[i] -= *len * s[i] * thd[i];
                }
            }
            z_out[l0..l0 + w].copy_from_slice(&z[..w]);
            r_out[l0..l0 + w].copy_from_slice(&zr[..w]);
            l0 += w;
        }
    }

    /// A swing-foot height over the stance foot's line as the height over the next foothold
    /// `h` below, `z + h` (module docs, "Step down"); `z` itself on level ground (`h = 0`, bit
    /// for bit).
    #[inline(always)]
    fn above_foothold(z: f64, h: f64) -> f64 {
        if h == 0.0 {
            z
        } else {
            z + h
        }
    }

    /// [`ChainWalker::above_foothold`] on every lane's height.
    fn above_foothold_lanes(&self, z: &mut [f64]) {
        let h = self.r.step_down;
        if h != 0.0 {
            for v in z {
                *v += h;
            }
        }
    }

    /// Absolute angle of the stance leg's top segment (the stance leg's angle when its knees
    /// are straight).
    fn stance_angle(&self, x: &[f64]) -> f64 {
        x[..self.m].iter().sum()
    }

    /// The latch guard guard `k` of `mode` is, if any (module docs, "Latches"): the stance
    /// latch in both modes, the swing latch in the locked mode, after the model's other guards.
    fn latch_guard(&self, mode: usize, k: usize) -> Option<LatchGuard> {
        self.latch_torque?;
        let first = if self.free_knee.is_some() && mode == FREE {
            GUARDS_FREE.len()
        } else {
            GUARDS_LOCKED.len()
        };
        match k.checked_sub(first) {
            Some(0) => Some(LatchGuard::Stance),
            Some(1) if mode == LOCKED => Some(LatchGuard::Swing),
            _ => None,
        }
    }

    /// The latch guard's value at `x`: the knee's lock torque towards flexion `τ` (the stance
    /// knee's kernel torque, the swing knee's negated; [`ChainWalker::constraint_forces_ws`])
    /// plus the pull the latch holds, `τ + L`: positive while it holds, falling through 0 where
    /// the pull exceeds `latch_torque`.
    fn latch_guard_value(&self, ws: &mut Scratch, mode: usize, x: &[f64], g: LatchGuard) -> f64 {
        let n = self.n;
        let mut qdd = [0.0; 2 * MAX_SEGMENTS];
        let mut lock = [0.0; 2 * MAX_SEGMENTS];
        self.dynamics(ws, mode, x, &mut qdd[..n], &mut lock[..n]);
        let l = self.latch_torque.unwrap_or(0.0);
        match g {
            LatchGuard::Stance => lock[1] + l,
            LatchGuard::Swing => -lock[n - 1] + l,
        }
    }

    /// Gradient of a latch guard (the lock torque): central differences of
    /// [`ChainWalker::latch_guard_value`], step `ε^(1/3) max(|x_j|, 1)` (relative error
    /// ~1e-10). The kernel has no derivative of a locking torque; of this model's gradients it
    /// is the one computed by differences, and a stride map's Jacobian needs it only through
    /// the swing latch's release (the stance latch's is a fall).
    fn latch_guard_gradient(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        g: LatchGuard,
        grad: &mut [f64],
    ) {
        let d = 2 * self.n;
        let mut xp = [0.0; DMAX];
        xp[..d].copy_from_slice(&x[..d]);
        for j in 0..d {
            let h = f64::EPSILON.cbrt() * x[j].abs().max(1.0);
            xp[j] = x[j] + h;
            let gp = self.latch_guard_value(ws, mode, &xp[..d], g);
            xp[j] = x[j] - h;
            let gm = self.latch_guard_value(ws, mode, &xp[..d], g);
            xp[j] = x[j];
            grad[j] = (gp - gm) / (2.0 * h);
        }
    }

    /// The latch's `latch_torque` and `latch_impulse` (`None`: a stop, an ideal latch).
    pub fn latch_limits(&self) -> (Option<f64>, Option<f64>) {
        (self.latch_torque, self.latch_impulse)
    }

    /// The leg swap (seed switch rule, eq. 3.29–3.32) on joint angles `q` and rates `qd`
    /// (length `n` each) into `out` (length `2n`).
    pub fn swap(&self, q: &[f64], qd: &[f64], out: &mut [f64]) {
        let (m, n) = (self.m, self.n);
        for (src, off) in [(q, 0), (qd, n)] {
            out[off] = src.iter().sum();
            for i in 0..m - 1 {
                // stance knee i (joint i+1) ← −(swing knee i, joint 2m−1−i), and vice versa
                out[off + i + 1] = -src[2 * m - 1 - i];
                out[off + 2 * m - 1 - i] = -src[i + 1];
            }
            out[off + m] = -src[m];
        }
    }

    fn scratch<'a>(&self, ws: &'a mut Scratch) -> &'a mut ChainScratch {
        ws.get_or_init(|| ChainScratch::new(self), |s: &ChainScratch| s.n == self.n)
    }

    /// Joint accelerations in `mode`, the locking torques (kernel sign, per joint, 0 where
    /// free) and the ground's force on the stance foot `[τ, f_y, f_z]`, by the kernel's
    /// [`pdw_soa::pseudo_joint_dynamics`].
    pub fn dynamics(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        qdd: &mut [f64],
        lock: &mut [f64],
    ) -> [f64; 3] {
        let n = self.n;
        if self.radius > 0.0 {
            // round feet: the rolling base; the ground force and the locks from ID_F
            let mut tau = [0.0; FMAX];
            let ok = pdw_soa::rolling_base_dynamics(
                &self.floating,
                self.radius,
                &x[..n],
                &x[n..2 * n],
                &self.masks[mode],
                qdd,
                &mut tau[..n + 2],
            )
            .is_ok();
            if !ok {
                qdd.iter_mut().for_each(|v| *v = f64::NAN);
                lock.iter_mut().for_each(|v| *v = f64::NAN);
                return [f64::NAN; 3];
            }
            for k in 0..n {
                lock[k] = if self.masks[mode][k] { tau[k + 2] } else { 0.0 };
            }
            return [tau[2], tau[0], tau[1]];
        }
        let s = self.scratch(ws);
        let r = pdw_soa::pseudo_joint_dynamics(
            &self.chain,
            &mut s.ws,
            &x[..n],
            &x[n..2 * n],
            &s.zeros[..n],
            &self.locked[mode],
            None,
            qdd,
            lock,
        )
        .map(|_| s.ws.joint_forces()[0]);
        match r {
            Ok(f) => f,
            Err(_) => {
                qdd.iter_mut().for_each(|v| *v = f64::NAN);
                lock.iter_mut().for_each(|v| *v = f64::NAN);
                [f64::NAN; 3]
            }
        }
    }

    /// Ground reaction at the stance foot and the knee-lock torques, positive towards flexion
    /// (a stance knee's kernel torque as is, a swing knee's negated); of several knees per leg
    /// the smallest (the one nearest to unlocking) is reported.
    pub fn constraint_forces_ws(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
    ) -> ConstraintForces {
        let n = self.n;
        let mut qdd = [0.0; 2 * MAX_SEGMENTS];
        let mut lock = [0.0; 2 * MAX_SEGMENTS];
        let f = self.dynamics(ws, mode, x, &mut qdd[..n], &mut lock[..n]);
        let m = self.m;
        let stance = (1..m).map(|k| lock[k]).reduce(f64::min);
        let swing = (m + 1..n)
            .filter(|k| self.masks[mode][*k])
            .map(|k| -lock[k])
            .reduce(f64::min);
        ConstraintForces::from_ground(f, [stance, swing])
    }

    /// Validity flags at one state; a hyper-extended free knee (`q > 0` in the free mode) also
    /// raises `knee_unlocks`. A latch with a `latch_torque` `L` unlocks where its lock torque
    /// `τ` (positive towards flexion) pulls more than it holds, `τ + L < 0`.
    pub fn check_state_ws(&self, ws: &mut Scratch, mode: usize, x: &[f64]) -> StepFlags {
        let cf = self.constraint_forces_ws(ws, mode, x);
        let mut f = StepFlags::from_state(&cf, self.swing_foot(x), self.leg_length);
        if let Some(l) = self.latch_torque {
            f.knee_unlocks = cf.knee_torque.iter().flatten().any(|&t| t + l < 0.0);
        }
        if let (Some(k), FREE) = (self.free_knee, mode) {
            if x[k] > 1e-9 {
                f.knee_unlocks = true;
            }
        }
        f
    }

    /// The heel-strike impact at the pre-impact state `x` (every knee held): floating-chain rates
    /// `(ẏ, ż, q̇…)` after the impact into `qd_post` (length `n + 2`), before the leg swap; the
    /// ground's impulse on the new stance foot `[Λ_y, Λ_z]` is returned.
    pub fn heel_strike(&self, ws: &mut Scratch, x: &[f64], qd_post: &mut [f64]) -> [f64; 2] {
        let n = self.n;
        let s = self.scratch(ws);
        s.q[..2].fill(0.0);
        s.qd[..2].fill(0.0);
        s.q[2..n + 2].copy_from_slice(&x[..n]);
        s.qd[2..n + 2].copy_from_slice(&x[n..2 * n]);
        if self.radius > 0.0 {
            // the stance arc centre rolls: ẏ = −r q̇₀; the contact point r below the swing arc
            // centre (the chain's tip)
            s.qd[0] = -self.radius * x[n];
            return match pdw_soa::contact_impact(
                &self.floating,
                &s.q[..n + 2],
                &s.qd[..n + 2],
                self.landing_offset(),
                &self.floating_knees,
                qd_post,
                None,
            ) {
                Ok(imp) => imp,
                Err(_) => {
                    qd_post.iter_mut().for_each(|v| *v = f64::NAN);
                    [f64::NAN; 2]
                }
            };
        }
        let nl = 2 + self.floating_knees.len();
        let ok = pdw_soa::tip_impact(
            &self.floating,
            &mut s.fws,
            &s.q[..n + 2],
            &s.qd[..n + 2],
            &self.floating_knees,
            qd_post,
            &mut s.imp[..nl],
        )
        .is_ok();
        if ok {
            [-s.imp[0], -s.imp[1]]
        } else {
            qd_post.iter_mut().for_each(|v| *v = f64::NAN);
            [f64::NAN; 2]
        }
    }

    fn flow_views(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: MatRef<'_, f64>,
        mut dx: MatMut<'_, f64>,
    ) {
        let n = self.n;
        for j in 0..n {
            dx.rb_mut().col_mut(j).copy_from(x.col(n + j));
        }
        let s = self.scratch(ws);
        if self.radius > 0.0 {
            // round feet: lane by lane through the rolling-base dynamics (the scalar flow is
            // the one-lane case of this loop, hence the same bits)
            let mut q = [0.0; 2 * MAX_SEGMENTS];
            let mut qd = [0.0; 2 * MAX_SEGMENTS];
            let mut qdd = [0.0; 2 * MAX_SEGMENTS];
            let mut tau = [0.0; FMAX];
            for l in 0..x.nrows() {
                for j in 0..n {
                    q[j] = x[(l, j)];
                    qd[j] = x[(l, n + j)];
                }
                let ok = pdw_soa::rolling_base_dynamics(
                    &self.floating,
                    self.radius,
                    &q[..n],
                    &qd[..n],
                    &self.masks[mode],
                    &mut qdd[..n],
                    &mut tau[..n + 2],
                )
                .is_ok();
                for j in 0..n {
                    dx[(l, n + j)] = if ok { qdd[j] } else { f64::NAN };
                }
            }
            return;
        }
        let r = pdw_soa::batch_aba_view(
            &self.chain,
            &mut s.bw,
            x.subcols(0, n),
            x.subcols(n, n),
            None,
            None,
            Some(&self.masks[mode]),
            dx.rb_mut().subcols_mut(n, n),
        );
        if r.is_err() {
            dx.fill(f64::NAN);
        }
    }
}

/// Largest state dimension `2n` of a chain walker.
const DMAX: usize = 4 * MAX_SEGMENTS;
/// Largest joint count of the floating chain.
const FMAX: usize = 2 * MAX_SEGMENTS + 2;

/// What a constraint of an impact problem is, for the report's names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    /// Knee strike: the stance foot (rolling or pinned, held).
    StanceFoot,
    /// Heel strike: the swing foot that strikes (the new stance foot).
    NewStanceFoot,
    /// Heel strike: the old stance foot (must leave the ground).
    TrailingFoot,
    /// Knee strike: the knee that strikes its stop (joint index).
    StrikingKnee(usize),
    /// Knee strike: a stance knee (held by its stop; releasing it buckles the stance leg).
    StanceKnee(usize),
    /// Knee strike: another swing knee (three-segment legs).
    SwingKnee(usize),
    /// Heel strike: a knee of the old stance leg (the new swing leg).
    TrailingKnee(usize),
    /// Heel strike: a knee of the old swing leg (the new stance leg; releasing it buckles).
    NewStanceKnee(usize),
}

/// The impact problem of a reset (module docs, "Impacts"): the floating chain's configuration
/// and pre-impact rates, the constraints, the model's active set and which releases are a fall.
struct ImpactProblem {
    q: [f64; FMAX],
    qd: [f64; FMAX],
    items: [pdw_soa::ImpactItem; pdw_soa::unilateral::MAX_ITEMS],
    roles: [Role; pdw_soa::unilateral::MAX_ITEMS],
    hold: [bool; pdw_soa::unilateral::MAX_ITEMS],
    /// the pulling impulse each item's hardware holds (a latch's `latch_impulse`, else 0)
    limit: [f64; pdw_soa::unilateral::MAX_ITEMS],
    len: usize,
}

impl ImpactProblem {
    fn push(&mut self, row: pdw_soa::ImpactRow, unilateral: bool, hold: bool, role: Role) {
        self.items[self.len] = pdw_soa::ImpactItem { row, unilateral };
        self.roles[self.len] = role;
        self.hold[self.len] = hold;
        self.len += 1;
    }

    /// [`ImpactProblem::push`] of a knee: a stop (unilateral), an ideal latch (bilateral) or
    /// a latch with `latch_impulse` `limit` (it may release: unilateral for the solver, released
    /// by the model where it would pull more than `limit`, module docs "Latches").
    fn push_knee(
        &mut self,
        row: pdw_soa::ImpactRow,
        latched: bool,
        limit: Option<f64>,
        role: Role,
    ) {
        let i = self.len;
        self.push(row, !latched || limit.is_some(), true, role);
        self.limit[i] = limit.filter(|_| latched).unwrap_or(0.0);
    }
}

impl ChainWalker {
    /// The absolute angle `ψ` of the straight trailing leg just after a heel strike onto a
    /// foothold `h` below, when the new stance leg's angle is `q₀`: the trailing foot is `h`
    /// above the new stance foot, `ℓ cos q₀ − ℓ cos ψ = h`, behind it: `ψ = −acos(cos q₀ − h/ℓ)`
    /// (module docs, "Step down"; the simplest walker's lift). `ℓ` is the length from the hip
    /// to the point that stays a fixed height above the ground: the foot (`ℓ = L`, the leg
    /// length) for point feet, the foot's arc centre (`ℓ = L − r`) for round feet, whose arc
    /// centres both stand `r` above their lines.
    pub fn trailing_leg_angle(&self, q0: f64) -> f64 {
        let l = self.leg_length - self.radius;
        -(q0.cos() - self.r.step_down / l).clamp(-1.0, 1.0).acos()
    }

    /// Index of the twin of the impact guard 0 in `mode` (a fall on the same surface).
    fn twin_guard(&self, mode: usize) -> usize {
        if self.free_knee.is_some() && mode == FREE {
            TWIN_FREE
        } else {
            TWIN_LOCKED
        }
    }

    /// The guard whose function guard `k` of `mode` evaluates (the twin evaluates guard 0).
    fn base_guard(&self, mode: usize, k: usize) -> usize {
        if k == self.twin_guard(mode) {
            0
        } else {
            k
        }
    }

    /// [`HybridSystem::admissible`] for the model at slope `slope` and step height `h`: only `stance_reverses`
    /// ("while `q₀ > γ`", the stance leg behind the vertical) sees the slope; every other
    /// condition measures the walker against the ground line.
    fn admissible_on(&self, mode: usize, k: usize, x: &[f64], slope: f64, h: f64) -> bool {
        if self.latch_guard(mode, k).is_some() {
            return true;
        }
        let free = self.free_knee.is_some() && mode == FREE;
        let lead = if free { 2 } else { 1 };
        let twin = k != 0 && k == self.twin_guard(mode);
        let base = match (free, self.base_guard(mode, k)) {
            (true, 0) => true,
            (true, 1) => self.swing_ahead(x),
            (false, 0) if h != 0.0 => self.swing_ahead(x),
            (false, 0) => {
                // the heel-strike factor in the landing line's frame (stance angle + Δ; adding
                // Δ = 0 changes no bit of the factor)
                let qh = x[self.m];
                self.swing_ahead(x)
                    && (2.0 * (self.stance_angle(x) + self.tilt) + qh).abs() < qh.abs()
            }
            (_, k) if k == lead => x[0] > slope,
            _ => true,
        };
        if !base || self.base_guard(mode, k) != 0 {
            return base;
        }
        self.stance_knee_buckles(mode, x) == twin
    }

    /// The impact of the reset of `mode` (the knee strike in the free mode, the heel strike in
    /// the locked mode) at the pre-impact state `x`, on the floating chain (module docs).
    fn impact_problem(&self, mode: usize, x: &[f64]) -> ImpactProblem {
        use pdw_soa::ImpactRow::{BaseContact, Stop, TipContact};
        let (n, m, r) = (self.n, self.m, self.radius);
        let mut p = ImpactProblem {
            q: [0.0; FMAX],
            qd: [0.0; FMAX],
            items: [pdw_soa::ImpactItem {
                row: Stop {
                    joint: 0,
                    sign: 1.0,
                },
                unilateral: false,
            }; pdw_soa::unilateral::MAX_ITEMS],
            roles: [Role::StanceFoot; pdw_soa::unilateral::MAX_ITEMS],
            hold: [false; pdw_soa::unilateral::MAX_ITEMS],
            limit: [0.0; pdw_soa::unilateral::MAX_ITEMS],
            len: 0,
        };
        p.q[2..n + 2].copy_from_slice(&x[..n]);
        p.qd[2..n + 2].copy_from_slice(&x[n..2 * n]);
        // the stance arc centre rolls: ẏ = −r q̇₀ (0 for point feet)
        p.qd[0] = -r * x[n];
        // a stance knee flexes with q > 0, a swing knee with q < 0 (module docs)
        let stop = |j: usize| Stop {
            joint: j + 2,
            sign: if j < m { 1.0 } else { -1.0 },
        };
        match (self.free_knee, mode) {
            (Some(fk), FREE) => {
                p.push(BaseContact { radius: r }, false, true, Role::StanceFoot);
                p.push(stop(fk), false, true, Role::StrikingKnee(fk));
                for &j in &self.locked[FREE] {
                    let role = if j < m {
                        Role::StanceKnee(j)
                    } else {
                        Role::SwingKnee(j)
                    };
                    p.push_knee(stop(j), self.latched[j], self.latch_impulse, role);
                }
            }
            _ => {
                p.push(
                    TipContact {
                        offset: self.landing_offset(),
                    },
                    false,
                    true,
                    Role::NewStanceFoot,
                );
                p.push(BaseContact { radius: r }, true, false, Role::TrailingFoot);
                for &j in &self.locked[self.locked_mode()] {
                    let role = if j < m {
                        Role::TrailingKnee(j)
                    } else {
                        Role::NewStanceKnee(j)
                    };
                    p.push_knee(stop(j), self.latched[j], self.latch_impulse, role);
                }
            }
        }
        p
    }

    /// Whether the impact of `mode` at `x` buckles a stance knee: the impact's complementarity
    /// problem (contacts and stops push only, [`pdw_soa::unilateral_impact`]) releases a knee of
    /// the leg that is the stance leg after the impact. `false` where the problem has no
    /// solution (the reset then reports the failure).
    ///
    /// A latch with a `latch_impulse` `L` (module docs, "Latches") buckles where, in the
    /// model's impact map ([`ChainWalker::impact_map`]: every knee held but a released trailing
    /// knee), the stance knee's latch would pull more than it holds: impulse `< −L`.
    pub fn stance_knee_buckles(&self, mode: usize, x: &[f64]) -> bool {
        if self.latch_impulse.is_some() {
            let mut v = [0.0; FMAX];
            return match self.impact_map(mode, x, &mut v, None) {
                Ok((p, sol)) => (0..p.len).any(|i| {
                    matches!(p.roles[i], Role::StanceKnee(_) | Role::NewStanceKnee(_))
                        && sol.items[i].impulse[0] < -p.limit[i]
                }),
                Err(_) => false,
            };
        }
        let p = self.impact_problem(mode, x);
        let stance_knee =
            |i: usize| matches!(p.roles[i], Role::StanceKnee(_) | Role::NewStanceKnee(_));
        if !(0..p.len).any(|i| stance_knee(i) && p.items[i].unilateral) {
            // no stance knee in the problem (a compass gait), or only latched ones (bilateral:
            // held in every active set the solve may choose): none can buckle, no solve needed
            return false;
        }
        let nf = self.n + 2;
        let mut v = [0.0; FMAX];
        match pdw_soa::unilateral_impact(
            &self.floating,
            &p.q[..nf],
            &p.qd[..nf],
            &p.items[..p.len],
            None,
            &mut v[..nf],
            None,
        ) {
            Ok(sol) => (0..p.len).any(|i| stance_knee(i) && !sol.items[i].active),
            Err(_) => false,
        }
    }

    /// The model's impact map of `mode` at `x` on the floating chain (every knee held but a
    /// trailing free knee whose stop would pull, the trailing foot released at heel strike):
    /// floating-chain rates after the impact into `v` (length `n + 2`) and, if given, the
    /// Jacobian `[∂q̇_F⁺/∂q_F | ∂q̇_F⁺/∂q̇_F⁻]`.
    fn impact_map(
        &self,
        mode: usize,
        x: &[f64],
        v: &mut [f64],
        jac: Option<&mut [f64]>,
    ) -> Result<(ImpactProblem, pdw_soa::ImpactSolution), pdw_soa::SoaError> {
        let mut p = self.impact_problem(mode, x);
        let nf = self.n + 2;
        if let Some(i) = self.trailing_release_item(mode, &p) {
            p.hold[i] = false;
        }
        let sol = pdw_soa::unilateral_impact(
            &self.floating,
            &p.q[..nf],
            &p.qd[..nf],
            &p.items[..p.len],
            Some(&p.hold[..p.len]),
            &mut v[..nf],
            jac,
        )?;
        Ok((p, sol))
    }

    /// At a heel strike of a walker whose trailing free knee is held by a stop or a latch with
    /// a `latch_impulse` `L` (`trailing_free`): the index of that knee's item in `p` if it would
    /// have to pull (more than `L`) with every constraint of the model held (an impulse below
    /// `−L`; `L = 0` for a stop), i.e. if the model releases it. The released problem is then consistent for that knee: with the others held, the
    /// stop's impulse and the knee's flexion rate after release have opposite signs (the
    /// Schur complement `e 𝓜⁻¹ eᵀ` restricted to the held rows is positive).
    fn trailing_release_item(&self, mode: usize, p: &ImpactProblem) -> Option<usize> {
        let tk = self.trailing_free?;
        if self.free_knee.is_some() && mode == FREE {
            return None;
        }
        let i = (0..p.len).find(|&i| p.roles[i] == Role::TrailingKnee(tk))?;
        let nf = self.n + 2;
        let mut v = [0.0; FMAX];
        let sol = pdw_soa::unilateral_impact(
            &self.floating,
            &p.q[..nf],
            &p.qd[..nf],
            &p.items[..p.len],
            Some(&p.hold[..p.len]),
            &mut v[..nf],
            None,
        )
        .ok()?;
        (sol.items[i].impulse[0] < -p.limit[i]).then_some(i)
    }

    /// Whether the model releases the trailing free knee at the heel strike at the pre-impact
    /// state `x` (its stop would have to pull; the new swing knee then starts flexing).
    pub fn trailing_knee_releases_at(&self, x: &[f64]) -> bool {
        if self.trailing_free.is_none() {
            return false;
        }
        let mode = self.locked_mode();
        let p = self.impact_problem(mode, x);
        self.trailing_release_item(mode, &p).is_some()
    }

    /// Name of a knee joint in a report: `prefix` and the knee's number for three-segment
    /// legs (`"stance_knee2"` is the state's `stance_knee2`).
    fn knee_name(&self, prefix: &str, j: usize) -> String {
        let state = &self.state_names[j];
        let digits = state.trim_start_matches(|c: char| !c.is_ascii_digit());
        format!("{prefix}{digits}")
    }

    /// The impulses of the reset of `mode` at the pre-impact state `x` (see
    /// [`Walker::impact_report`]).
    pub fn impact_report_at(&self, mode: usize, x: &[f64]) -> Option<ImpactReport> {
        let mut v = [0.0; FMAX];
        let (p, sol) = self.impact_map(mode, x, &mut v, None).ok()?;
        let mut entries = Vec::with_capacity(2 * p.len);
        let mut friction = f64::INFINITY;
        for i in 0..p.len {
            let (it, res) = (&p.items[i], &sol.items[i]);
            let (name, contact) = match p.roles[i] {
                Role::StanceFoot => ("stance_foot".to_string(), true),
                Role::NewStanceFoot => ("new_stance_foot".to_string(), true),
                Role::TrailingFoot => ("trailing_foot".to_string(), true),
                Role::StrikingKnee(j) => (self.knee_name("striking_knee", j), false),
                Role::StanceKnee(j) => (self.knee_name("stance_knee", j), false),
                Role::SwingKnee(j) => (self.knee_name("swing_knee", j), false),
                Role::TrailingKnee(j) => (self.knee_name("trailing_knee", j), false),
                Role::NewStanceKnee(j) => (self.knee_name("new_stance_knee", j), false),
            };
            let (impulse, rate) = match p.roles[i] {
                // the landing line's tangent (cos Δ, −sin Δ) and normal (sin Δ, cos Δ)
                Role::NewStanceFoot if self.tilt != 0.0 => {
                    let (s, c) = self.tilt_sc;
                    let along = |v: [f64; 2]| [v[0] * c - v[1] * s, v[0] * s + v[1] * c];
                    (along(res.impulse), along(res.rate))
                }
                _ => (res.impulse, res.rate),
            };
            if contact {
                if !it.unilateral {
                    friction = if impulse[1] > 0.0 {
                        (impulse[0] / impulse[1]).abs()
                    } else {
                        f64::INFINITY
                    };
                }
                for (kind, c) in [
                    (ImpulseKind::ContactTangential, 0),
                    (ImpulseKind::ContactNormal, 1),
                ] {
                    entries.push(ImpulseEntry {
                        name: name.clone(),
                        kind,
                        unilateral: it.unilateral,
                        active: res.active,
                        impulse: impulse[c],
                        rate_after: if res.active { 0.0 } else { rate[c] },
                        pull_limit: 0.0,
                    });
                }
            } else {
                entries.push(ImpulseEntry {
                    name,
                    kind: ImpulseKind::KneeStop,
                    unilateral: it.unilateral,
                    active: res.active,
                    impulse: impulse[0],
                    rate_after: if res.active { 0.0 } else { rate[0] },
                    pull_limit: p.limit[i],
                });
            }
        }
        let event = if self.free_knee.is_some() && mode == FREE {
            "knee_strike"
        } else {
            "heel_strike"
        };
        Some(ImpactReport {
            event: event.into(),
            entries,
            friction_required: friction,
            energy_lost: sol.energy_lost,
        })
    }

    /// The spec's gaits as given, or the generic start.
    fn gait_guesses3(&self) -> Vec<GaitGuess> {
        if self.r.gaits.is_empty() {
            // Goswami's compass gait at 3° scaled by √(g/L): a start that reaches the
            // period-one gait of most straight-legged walkers on small slopes.
            let w = (self.r.gravity / self.leg_length).sqrt();
            return vec![GaitGuess {
                gait: "stable".into(),
                section: vec![0.27, -0.35 * w, 0.23 * w],
                source: "generic start (the compass gait's at 3°, rates scaled by √(g/L)); the \
                         spec gives no gait"
                    .into(),
            }];
        }
        self.r
            .gaits
            .iter()
            .map(|(name, section, source)| GaitGuess {
                gait: name.clone(),
                section: section.clone(),
                source: source.clone(),
            })
            .collect()
    }

    /// The leg swap as a matrix `S` (row-major `n × n`): `q' = S q`, `q̇' = S q̇`.
    fn swap_matrix(&self, out: &mut [f64]) {
        let n = self.n;
        let mut e = [0.0; 2 * MAX_SEGMENTS];
        let mut col = [0.0; 4 * MAX_SEGMENTS];
        for j in 0..n {
            e[..n].fill(0.0);
            e[j] = 1.0;
            self.swap(&e[..n], &e[..n], &mut col[..2 * n]);
            for i in 0..n {
                out[i * n + j] = col[i];
            }
        }
    }
}

/// Refuses a step down the walker cannot take: a height of the hip's reach or more — a leg
/// length for point feet, the length from the hip to the foot's arc centre (`L − r`) for round
/// feet (module docs, "Step down": the swing foot never reaches a foothold that far below, nor
/// the trailing foot one that far above).
fn check_step_down(spec: &WalkerSpec, r: &Resolved) -> Result<(), WalkerError> {
    let h = r.step_down;
    if h == 0.0 {
        return Ok(());
    }
    let leg: f64 = r.segments.iter().map(|s| s[0]).sum::<f64>() - r.foot_radius;
    let rule = if h.abs() >= leg && r.foot_radius > 0.0 {
        format!(
            "a height within (-{leg}, {leg}), less than the length from the hip to the foot's \
             arc centre (leg length − foot_radius)"
        )
    } else if h.abs() >= leg {
        format!("a height within (-{leg}, {leg}), less than one leg length")
    } else {
        return Ok(());
    };
    Err(WalkerError::InvalidSpec {
        source_name: spec.name.clone(),
        field: "parameters.step_down".into(),
        value: h.to_string(),
        rule,
    })
}

/// A link with a point mass `mp` added at `p` (link frame): composite mass, COM and inertia
/// about the new COM (parallel-axis theorem).
fn add_point_mass(l: Link, mp: f64, p: [f64; 2]) -> Link {
    let mass = l.mass + mp;
    let com = [
        (l.mass * l.com[0] + mp * p[0]) / mass,
        (l.mass * l.com[1] + mp * p[1]) / mass,
    ];
    let d2 = |a: [f64; 2]| (a[0] - com[0]).powi(2) + (a[1] - com[1]).powi(2);
    Link {
        to_next: l.to_next,
        com,
        mass,
        inertia: l.inertia + l.mass * d2(l.com) + mp * d2(p),
    }
}

pdw_hybrid::integrate_concretely!(ChainWalker);
impl HybridSystem for ChainWalker {
    fn dim(&self) -> usize {
        2 * self.n
    }

    fn n_modes(&self) -> usize {
        self.masks.len()
    }

    fn guards(&self, mode: usize) -> &[GuardSpec] {
        match (
            self.free_knee.is_some() && mode == FREE,
            self.latch_torque.is_some(),
        ) {
            (true, false) => &GUARDS_FREE,
            (false, false) => &GUARDS_LOCKED,
            (true, true) => &GUARDS_FREE_LATCH,
            (false, true) => &GUARDS_LOCKED_LATCH,
        }
    }

    /// One lane of [`HybridSystem::flow_batch`]: with point feet the one-lane instance of the
    /// same recursion ([`pdw_soa::aba_masked`] in the scalar workspace: the same bits, without
    /// wrapping the state in matrix views and the batched call's shape checks; event location
    /// and dense output evaluate one lane at a time).
    fn flow(&self, ws: &mut Scratch, mode: usize, x: &[f64], dx: &mut [f64]) {
        let n = self.n;
        let d = 2 * n;
        if self.radius <= 0.0 {
            let s = self.scratch(ws);
            dx[..n].copy_from_slice(&x[n..d]);
            let (q, qd) = x[..d].split_at(n);
            let r = pdw_soa::aba_masked(
                &self.chain,
                &mut s.ws,
                q,
                qd,
                &self.masks[mode],
                &mut dx[n..d],
            );
            if r.is_err() {
                dx[..d].fill(f64::NAN);
            }
            return;
        }
        let xv = MatRef::from_column_major_slice(&x[..d], 1, d);
        let dxv = MatMut::from_column_major_slice_mut(&mut dx[..d], 1, d);
        self.flow_views(ws, mode, xv, dxv);
    }

    fn flow_batch(&self, ws: &mut Scratch, mode: usize, x: MatRef<'_, f64>, dx: MatMut<'_, f64>) {
        self.flow_views(ws, mode, x.rb(), dx);
    }

    /// The guards over all lanes: columns of `x` directly, the swing-foot height four lanes at a
    /// time (same bits as [`HybridSystem::guard`]).
    fn guard_batch(
        &self,
        ws: &mut Scratch,
        mode: usize,
        k: usize,
        x: MatRef<'_, f64>,
        out: &mut [f64],
    ) {
        let n = self.n;
        let lanes = x.nrows();
        if let Some(g) = self.latch_guard(mode, k) {
            // a latch's lock torque: lane by lane through the scalar dynamics
            let mut xi = [0.0; DMAX];
            for (l, o) in out.iter_mut().enumerate().take(lanes) {
                for (j, v) in xi.iter_mut().enumerate().take(2 * n) {
                    *v = x[(l, j)];
                }
                *o = self.latch_guard_value(ws, mode, &xi[..2 * n], g);
            }
            return;
        }
        let k = self.base_guard(mode, k);
        let free = self.free_knee.is_some() && mode == FREE;
        let lead = if free { 2 } else { 1 };
        let column = |j: usize, out: &mut [f64], shift: f64| {
            for (l, o) in out.iter_mut().enumerate().take(lanes) {
                *o = x[(l, j)] + shift;
            }
        };
        match (free, k) {
            (true, 0) => column(self.free_knee.unwrap_or(0), out, 0.0),
            (_, k) if k < lead && self.tilt != 0.0 => {
                // a tilted landing line (one walker's step of random slopes): lane by lane
                let mut xi = [0.0; 2 * MAX_SEGMENTS];
                for (l, o) in out.iter_mut().enumerate().take(lanes) {
                    for (j, v) in xi.iter_mut().enumerate().take(n) {
                        *v = x[(l, j)];
                    }
                    *o = self.above_tilted(self.swing_foot(&xi[..n]), [0.0; 2]).0;
                }
            }
            (_, k) if k < lead => {
                pdw_simd::dispatch(
                    #[inline(always)]
                    || self.foot_height_lanes(x, out),
                );
                self.above_foothold_lanes(&mut out[..lanes]);
            }
            (_, k) => match k - lead {
                0 => column(n, out, 0.0),
                1 => column(0, out, -FRAC_PI_2),
                _ => column(0, out, FRAC_PI_2),
            },
        }
    }

    /// Every guard with its exact rate `∇g·f`: the knee angle (rate `q̇_knee`), the swing-foot
    /// height (`ChainWalker::foot_height_and_rate`), the stance rate (rate `q̈₀`), the stance
    /// angle (rate `q̇₀`); `f = (q̇, q̈)`.
    fn guards_with_rates(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        f: &[f64],
        g: &mut [f64],
        rate: &mut [f64],
    ) {
        self.guards_with_rates_at(ws, mode, x, f, g, rate, self.r.step_down);
    }

    /// [`HybridSystem::guards_with_rates`] over all lanes: columns of `x` and `f` directly, the
    /// swing-foot height and its rate four lanes at a time (same bits per lane).
    fn guards_with_rates_batch(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: MatRef<'_, f64>,
        f: MatRef<'_, f64>,
        mut g: MatMut<'_, f64>,
        mut rate: MatMut<'_, f64>,
    ) {
        let (n, lanes) = (self.n, x.nrows());
        let free = self.free_knee.is_some() && mode == FREE;
        let lead = if free { 2 } else { 1 };
        let ng = self.guards(mode).len();
        if self.tilt != 0.0 {
            // a tilted landing line (one walker's step of random slopes): lane by lane
            return pdw_hybrid::guards_with_rates_by_lane(self, ws, mode, x, f, g, rate);
        }
        let mut xc: [&[f64]; 4 * MAX_SEGMENTS] = [&[]; 4 * MAX_SEGMENTS];
        let mut fc: [&[f64]; 4 * MAX_SEGMENTS] = [&[]; 4 * MAX_SEGMENTS];
        for j in 0..2 * n {
            match (x.col(j).try_as_col_major(), f.col(j).try_as_col_major()) {
                (Some(a), Some(b)) => (xc[j], fc[j]) = (a.as_slice(), b.as_slice()),
                _ => return pdw_hybrid::guards_with_rates_by_lane(self, ws, mode, x, f, g, rate),
            }
        }
        if g.row_stride() != 1 || rate.row_stride() != 1 {
            return pdw_hybrid::guards_with_rates_by_lane(self, ws, mode, x, f, g, rate);
        }
        for k in 0..ng {
            let (Some(gk), Some(rk)) = (
                g.rb_mut().col_mut(k).try_as_col_major_mut(),
                rate.rb_mut().col_mut(k).try_as_col_major_mut(),
            ) else {
                unreachable!("columns of a view with unit row stride are contiguous")
            };
            let (gk, rk) = (gk.as_slice_mut(), rk.as_slice_mut());
            // x[j] itself (shift None) or x[j] ± π/2: the expressions of `guard`.
            let mut copy = |j: usize, shift: Option<f64>| {
                for l in 0..lanes {
                    gk[l] = shift.map_or(xc[j][l], |s| xc[j][l] + s);
                    rk[l] = fc[j][l];
                }
            };
            if let Some(lg) = self.latch_guard(mode, k) {
                // a latch's lock torque, lane by lane; its rate unknown (+∞: the integrator
                // samples every step's interior for it)
                let mut xi = [0.0; DMAX];
                for l in 0..lanes {
                    for (j, v) in xi.iter_mut().enumerate().take(2 * n) {
                        *v = xc[j][l];
                    }
                    gk[l] = self.latch_guard_value(ws, mode, &xi[..2 * n], lg);
                    rk[l] = f64::INFINITY;
                }
                continue;
            }
            match (free, self.base_guard(mode, k)) {
                (true, 0) => copy(self.free_knee.unwrap_or(0), None),
                (_, k) if k < lead => {
                    pdw_simd::dispatch(
                        #[inline(always)]
                        || self.foot_height_rate_lanes(&xc[..n], &fc[..n], lanes, gk, rk),
                    );
                    self.above_foothold_lanes(&mut gk[..lanes]);
                }
                (_, k) => match k - lead {
                    0 => copy(n, None),
                    1 => copy(0, Some(-FRAC_PI_2)),
                    _ => copy(0, Some(FRAC_PI_2)),
                },
            }
        }
    }

    /// Every guard but the swing-foot height and a latch's lock torque is a state coordinate
    /// (plus a constant).
    fn guard_is_linear(&self, mode: usize, k: usize) -> bool {
        if self.latch_guard(mode, k).is_some() {
            return false;
        }
        let k = self.base_guard(mode, k);
        let lead = if self.free_knee.is_some() && mode == FREE {
            2
        } else {
            1
        };
        !(k < lead && !(lead == 2 && k == 0))
    }

    fn guard(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64]) -> f64 {
        self.guard_at(ws, mode, k, x, self.r.step_down)
    }

    /// The impact guard (0) counts where the impact's complementarity problem keeps every
    /// stance knee locked, its twin (a fall) where it releases one
    /// ([`ChainWalker::stance_knee_buckles`]); both need the impact guard's own conditions.
    fn admissible(&self, mode: usize, k: usize, x: &[f64]) -> bool {
        self.admissible_on(mode, k, x, self.r.slope, self.r.step_down)
    }

    fn reset(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], out: &mut [f64]) -> usize {
        let n = self.n;
        if self.latch_guard(mode, k) == Some(LatchGuard::Swing) {
            // the swing knee's latch lets go: the knee swings free, nothing jumps
            out[..2 * n].copy_from_slice(&x[..2 * n]);
            return FREE;
        }
        if let (Some(knee), FREE) = (self.free_knee, mode) {
            let s = self.scratch(ws);
            let locked = &self.locked[LOCKED];
            let ok = if self.radius > 0.0 {
                // the stance foot rolls: its contact point, not the arc centre, is at rest
                // after the impact (the floating chain's impact problem, every knee held)
                let mut v = [0.0; FMAX];
                let ok = self.impact_map(FREE, x, &mut v, None).is_ok();
                s.v[..n].copy_from_slice(&v[2..n + 2]);
                ok
            } else {
                pdw_soa::joint_lock_impact(
                    &self.chain,
                    &mut s.ws,
                    &x[..n],
                    &x[n..2 * n],
                    locked,
                    &mut s.v[..n],
                    &mut s.imp[..locked.len()],
                )
                .is_ok()
            };
            out[..n].copy_from_slice(&x[..n]);
            out[knee] = 0.0;
            if ok {
                out[n..2 * n].copy_from_slice(&s.v[..n]);
                for &j in locked {
                    out[n + j] = 0.0;
                }
            } else {
                out[n..2 * n].fill(f64::NAN);
            }
            // a swing latch that must pull more than it holds right after catching the knee
            // lets go at once: no crossing of its guard would show it
            if ok
                && self.latch_torque.is_some()
                && self.latch_guard_value(ws, LOCKED, &out[..2 * n], LatchGuard::Swing) < 0.0
            {
                return FREE;
            }
            return LOCKED;
        }
        let mut v = [0.0; FMAX];
        if self.trailing_knee_releases_at(x) {
            // the mode change: the trailing free knee leaves the impact flexing, every other
            // knee held (their rates exactly 0 in the new mode)
            if self
                .impact_map(self.locked_mode(), x, &mut v[..n + 2], None)
                .is_err()
            {
                v.fill(f64::NAN);
            }
            self.swap(&x[..n], &v[2..n + 2], out);
            for &j in &self.locked[self.section_mode()] {
                out[n + j] = 0.0;
            }
            return self.section_mode();
        }
        self.heel_strike(ws, x, &mut v[..n + 2]);
        self.swap(&x[..n], &v[2..n + 2], out);
        if self.trailing_free.is_some() {
            // every knee held: their rates exactly 0 (the section's swing_knee_rate is 0)
            for k in (1..self.m).chain(self.m + 1..n) {
                out[n + k] = 0.0;
            }
        }
        self.section_mode()
    }

    /// Exact flow Jacobian: `∂q̇/∂x = [0 | I]`, and `∂q̈/∂(q, q̇)` by forward-mode dual numbers
    /// through the kernel's per-link steps with the mode's knees locked
    /// ([`pdw_soa::aba_derivatives`]: `∂q̈_f = −𝓜_ff⁻¹ ∂ID_f`, Carpentier & Mansard 2018).
    fn flow_jacobian(&self, ws: &mut Scratch, mode: usize, x: &[f64], jac: &mut [f64]) {
        let (n, d) = (self.n, 2 * self.n);
        let s = self.scratch(ws);
        let mut dq = [0.0; 4 * MAX_SEGMENTS * MAX_SEGMENTS];
        let mut dqd = [0.0; 4 * MAX_SEGMENTS * MAX_SEGMENTS];
        let ok = if self.radius > 0.0 {
            pdw_soa::rolling_base_derivatives(
                &self.floating,
                self.radius,
                &x[..n],
                &x[n..d],
                &self.masks[mode],
                &mut s.v[..n],
                &mut dq[..n * n],
                &mut dqd[..n * n],
            )
        } else {
            pdw_soa::aba_derivatives(
                &self.chain,
                &x[..n],
                &x[n..d],
                &s.zeros[..n],
                &self.masks[mode],
                &mut s.v[..n],
                &mut dq[..n * n],
                &mut dqd[..n * n],
            )
        }
        .is_ok();
        jac[..d * d].fill(0.0);
        for i in 0..n {
            jac[i * d + n + i] = 1.0;
            for j in 0..n {
                jac[(n + i) * d + j] = if ok { dq[i * n + j] } else { f64::NAN };
                jac[(n + i) * d + n + j] = if ok { dqd[i * n + j] } else { f64::NAN };
            }
        }
    }

    /// Exact gradients: the knee angle, the swing-foot height (kernel tip-position derivatives),
    /// the stance rate, the stance angle.
    fn guard_gradient(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], grad: &mut [f64]) {
        if let Some(g) = self.latch_guard(mode, k) {
            return self.latch_guard_gradient(ws, mode, x, g, grad);
        }
        let k = self.base_guard(mode, k);
        let (n, d) = (self.n, 2 * self.n);
        grad[..d].fill(0.0);
        let free = self.free_knee.is_some() && mode == FREE;
        let lead = if free { 2 } else { 1 };
        match (free, k) {
            (true, 0) => grad[self.free_knee.unwrap_or(0)] = 1.0,
            (_, k) if k < lead => {
                let mut pos = [0.0; 2];
                let mut j = [0.0; 2 * 2 * MAX_SEGMENTS];
                match pdw_soa::tip_position_derivatives(
                    &self.chain,
                    &x[..n],
                    &mut pos,
                    &mut j[..2 * n],
                ) {
                    Ok(()) if self.tilt != 0.0 => {
                        // ∇(p·n): rows y and z of the tip Jacobian weighted by n = (sin Δ, cos Δ)
                        let (s, c) = self.tilt_sc;
                        for i in 0..n {
                            grad[i] = s * j[i] + c * j[n + i];
                        }
                    }
                    Ok(()) => grad[..n].copy_from_slice(&j[n..2 * n]),
                    Err(_) => grad[..d].fill(f64::NAN),
                }
            }
            (_, k) if k == lead => grad[n] = 1.0,
            _ => grad[0] = 1.0,
        }
    }

    /// Exact reset Jacobians: the impact maps' derivatives by dual numbers through the kernel
    /// ([`pdw_soa::joint_lock_impact_derivatives`], [`pdw_soa::tip_impact_derivatives`]), the
    /// leg swap as its matrix.
    fn reset_jacobian(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], jac: &mut [f64]) {
        let (n, d) = (self.n, 2 * self.n);
        jac[..d * d].fill(0.0);
        if self.latch_guard(mode, k) == Some(LatchGuard::Swing) {
            // the identity: a mode change without a jump
            for i in 0..d {
                jac[i * d + i] = 1.0;
            }
            return;
        }
        if let (Some(knee), FREE) = (self.free_knee, mode) {
            let s = self.scratch(ws);
            let locked = &self.locked[LOCKED];
            let mut jl = [0.0; DMAX * DMAX / 2];
            let ok = if self.radius > 0.0 {
                // the floating chain's Jacobian, with q̇_F⁻ = (−r q̇₀, 0, q̇) by the chain rule
                // (the map does not depend on the base position: translation invariance)
                let f = n + 2;
                let mut v = [0.0; FMAX];
                let mut jf = [0.0; FMAX * 2 * FMAX];
                let ok = self
                    .impact_map(FREE, x, &mut v, Some(&mut jf[..f * 2 * f]))
                    .is_ok();
                for i in 0..n {
                    let row = (2 + i) * 2 * f;
                    for j in 0..n {
                        jl[i * d + j] = jf[row + 2 + j];
                        jl[i * d + n + j] = jf[row + f + 2 + j];
                    }
                    jl[i * d + n] += -self.radius * jf[row + f];
                }
                ok
            } else {
                pdw_soa::joint_lock_impact_derivatives(
                    &self.chain,
                    &x[..n],
                    &x[n..d],
                    locked,
                    &mut s.v[..n],
                    &mut jl[..n * d],
                )
                .is_ok()
            };
            for i in 0..n {
                if i != knee {
                    jac[i * d + i] = 1.0;
                }
                if locked.contains(&i) {
                    continue;
                }
                for j in 0..d {
                    jac[(n + i) * d + j] = if ok { jl[i * d + j] } else { f64::NAN };
                }
            }
            return;
        }
        let s = self.scratch(ws);
        let f = n + 2;
        s.q[..2].fill(0.0);
        s.qd[..2].fill(0.0);
        s.q[2..f].copy_from_slice(&x[..n]);
        s.qd[2..f].copy_from_slice(&x[n..d]);
        let mut jf = [0.0; FMAX * 2 * FMAX];
        let released = self.trailing_knee_releases_at(x);
        let ok = if released {
            let mut v = [0.0; FMAX];
            self.impact_map(
                self.locked_mode(),
                x,
                &mut v[..f],
                Some(&mut jf[..f * 2 * f]),
            )
            .is_ok()
        } else if self.radius > 0.0 {
            s.qd[0] = -self.radius * x[n];
            pdw_soa::contact_impact(
                &self.floating,
                &s.q[..f],
                &s.qd[..f],
                self.landing_offset(),
                &self.floating_knees,
                &mut s.v[..f],
                Some(&mut jf[..f * 2 * f]),
            )
            .is_ok()
        } else {
            pdw_soa::tip_impact_derivatives(
                &self.floating,
                &s.q[..f],
                &s.qd[..f],
                &self.floating_knees,
                &mut s.v[..f],
                &mut jf[..f * 2 * f],
            )
            .is_ok()
        };
        // q̇⁻_F = (−r q̇₀, 0, q̇): the chain rule through the rolling base rate
        if self.radius > 0.0 {
            for row in 0..f {
                jf[row * 2 * f + f + 2] += -self.radius * jf[row * 2 * f + f];
            }
        }
        let mut sm = [0.0; 4 * MAX_SEGMENTS * MAX_SEGMENTS];
        self.swap_matrix(&mut sm[..n * n]);
        for i in 0..n {
            for j in 0..n {
                // q' = S q
                jac[i * d + j] = sm[i * n + j];
                // q̇' = S v(q, q̇), v = floating rates 2.. of the impact
                let (mut a, mut b) = (0.0, 0.0);
                for l in 0..n {
                    a += sm[i * n + l] * jf[(2 + l) * 2 * f + 2 + j];
                    b += sm[i * n + l] * jf[(2 + l) * 2 * f + f + 2 + j];
                }
                jac[(n + i) * d + j] = if ok { a } else { f64::NAN };
                jac[(n + i) * d + n + j] = if ok { b } else { f64::NAN };
            }
        }
        // the held knees' rates are set to exactly 0 by the reset
        if released {
            for &j in &self.locked[self.section_mode()] {
                jac[(n + j) * d..(n + j + 1) * d].fill(0.0);
            }
        } else if self.trailing_free.is_some() {
            for k in (1..self.m).chain(self.m + 1..n) {
                jac[(n + k) * d..(n + k + 1) * d].fill(0.0);
            }
        }
    }
}

/// The chain walker at any step height (module docs, "Step down"): the swing-foot guards
/// measure the foot's height over the foothold's line and the heel strike's admissibility
/// drops the level-ground factor; the impacts, the gradients (`h` is a constant) and the lift
/// of the trailing leg (not part of a stride) do not see it.
impl StepHeight for ChainWalker {
    fn guard_at(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], h: f64) -> f64 {
        if let Some(g) = self.latch_guard(mode, k) {
            return self.latch_guard_value(ws, mode, x, g);
        }
        let k = self.base_guard(mode, k);
        let n = self.n;
        let free = self.free_knee.is_some() && mode == FREE;
        let lead = if free { 2 } else { 1 };
        match (free, k) {
            (true, 0) => x[self.free_knee.unwrap_or(0)],
            (_, k) if k < lead && self.tilt != 0.0 => {
                self.above_tilted(self.swing_foot(x), [0.0; 2]).0
            }
            (_, k) if k < lead => Self::above_foothold(self.swing_foot(x)[1], h),
            (_, k) => match k - lead {
                0 => x[n],
                1 => x[0] - FRAC_PI_2,
                _ => x[0] + FRAC_PI_2,
            },
        }
    }

    fn guards_with_rates_at(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        f: &[f64],
        g: &mut [f64],
        rate: &mut [f64],
        h: f64,
    ) {
        let n = self.n;
        let free = self.free_knee.is_some() && mode == FREE;
        let lead = if free { 2 } else { 1 };
        let ng = self.guards(mode).len();
        for k in 0..ng {
            if let Some(lg) = self.latch_guard(mode, k) {
                // rate unknown: +∞ (the integrator samples every step's interior for it)
                (g[k], rate[k]) = (self.latch_guard_value(ws, mode, x, lg), f64::INFINITY);
                continue;
            }
            (g[k], rate[k]) = match (free, self.base_guard(mode, k)) {
                (true, 0) => {
                    let j = self.free_knee.unwrap_or(0);
                    (x[j], f[j])
                }
                (_, k) if k < lead && self.tilt != 0.0 => {
                    let (p, pd) = self.swing_foot_and_rate(x, f);
                    self.above_tilted(p, pd)
                }
                (_, k) if k < lead => {
                    let (z, zr) = self.foot_height_and_rate(x, f);
                    (Self::above_foothold(z, h), zr)
                }
                (_, k) => match k - lead {
                    0 => (x[n], f[n]),
                    1 => (x[0] - FRAC_PI_2, f[0]),
                    _ => (x[0] + FRAC_PI_2, f[0]),
                },
            };
        }
    }

    fn guard_gradient_at(
        &self,
        ws: &mut Scratch,
        mode: usize,
        k: usize,
        x: &[f64],
        grad: &mut [f64],
        _h: f64,
    ) {
        self.guard_gradient(ws, mode, k, x, grad)
    }

    fn admissible_at(&self, mode: usize, k: usize, x: &[f64], h: f64) -> bool {
        self.admissible_on(mode, k, x, self.r.slope, h)
    }

    fn reset_at(
        &self,
        ws: &mut Scratch,
        mode: usize,
        k: usize,
        x: &[f64],
        out: &mut [f64],
        _h: f64,
    ) -> usize {
        self.reset(ws, mode, k, x, out)
    }

    fn guard_is_linear_at_every_height(&self, mode: usize, k: usize) -> bool {
        self.guard_is_linear(mode, k)
    }
}

impl Section for ChainWalker {
    fn section_dim(&self) -> usize {
        section_names_of(&self.r).len()
    }
    fn section_names(&self) -> &[&'static str] {
        section_names_of(&self.r)
    }
    fn section_mode(&self) -> usize {
        0
    }
    fn section_guard(&self) -> (usize, usize) {
        (self.locked_mode(), 0)
    }
    fn lift(&self, s: &[f64], x: &mut [f64]) {
        let (m, n) = (self.m, self.n);
        x[..2 * n].fill(0.0);
        x[0] = s[0];
        x[m] = if self.r.step_down == 0.0 {
            -2.0 * s[0]
        } else {
            self.trailing_leg_angle(s[0]) - s[0]
        };
        x[n] = s[1];
        x[n + m] = s[2];
        if let (Some(fk), Some(_)) = (self.free_knee, self.trailing_free) {
            x[n + fk] = s[3];
        }
    }
    fn project(&self, x: &[f64], s: &mut [f64]) {
        s[0] = x[0];
        s[1] = x[self.n];
        s[2] = x[self.n + self.m];
        if let (Some(fk), Some(_)) = (self.free_knee, self.trailing_free) {
            s[3] = x[self.n + fk];
        }
    }
    fn max_stride_time(&self) -> f64 {
        self.r.max_stride_time
    }
}

impl Walker for ChainWalker {
    /// `q₀` is the one absolute angle (Garcia's θ, module docs "Coordinates"; gravity enters as
    /// the base acceleration of slope γ, so the stance leg's world angle is `q₀ − γ`): it grows by
    /// `s' − s`. Round feet: `None` — the stance arc's contact point moves along the line, so a
    /// change of line is not a rotation about the contact point.
    fn terrain_frame(&self) -> Option<(usize, f64)> {
        (self.radius == 0.0).then_some((0, 1.0))
    }
    /// `q₀`, from the slope normal for point and round feet alike.
    fn absolute_angle(&self) -> Option<(usize, f64)> {
        Some((0, 1.0))
    }
    /// The hip angle `q_m` of a walker whose knees stay locked (one mode): both legs straight
    /// and equally long, so the feet (or the arc centres, `r` above each foot) are level at
    /// `q_m = 0`.
    fn legs_together(&self) -> Option<usize> {
        (self.masks.len() == 1).then_some(self.m)
    }
    /// Point and round feet (module docs, "Step down").
    fn step_height(&self) -> Option<&dyn StepHeight> {
        Some(self as &dyn StepHeight)
    }
    /// [`ChainWalker::with_tilt`] (module docs, "Landing on a tilted line").
    fn on_tilted_line(&self, delta: f64) -> Option<Result<Box<dyn Walker>, String>> {
        Some(
            self.with_tilt(delta)
                .map(|w| Box::new(w) as Box<dyn Walker>)
                .map_err(|e| e.to_string()),
        )
    }
    /// `stance_reverses` counts while `q₀ > slope` (`ChainWalker::admissible_on`).
    fn admissible_on_slope(&self, mode: usize, k: usize, x: &[f64], slope: f64) -> bool {
        self.admissible_on(mode, k, x, slope, self.r.step_down)
    }
    fn name(&self) -> &str {
        &self.spec.name
    }
    fn state_names(&self) -> Vec<String> {
        self.state_names.clone()
    }
    /// Module docs, "Coordinates": `q₀` absolute from the slope normal, every other joint
    /// relative to the segment above it.
    fn coordinate_meanings(&self) -> Vec<String> {
        self.state_names
            .iter()
            .map(|n| chain_coordinate(n))
            .collect()
    }
    /// Module docs, "Modes".
    fn mode_names(&self) -> Vec<String> {
        if self.free_knee.is_some() {
            vec!["swing knee free".into(), "knees locked".into()]
        } else {
            vec!["knees locked".into()]
        }
    }
    /// The resolved geometry (every segment, knee and foot at the current
    /// parameter values), not the expressions that gave it: two specs that resolve to the
    /// same walker have the same fingerprint. Gait guesses are left out (they start Newton
    /// and do not change the dynamics).
    fn fingerprint(&self) -> String {
        let r = &self.r;
        let mut s = format!(
            "model = {}\nkind = chain walker\nslope = {:?}\ngravity = {:?}\n\
             max_stride_time = {:?}\nhip_mass = {:?}\nfoot_radius = {:?}\n",
            self.spec.name, r.slope, r.gravity, r.max_stride_time, r.hip_mass, r.foot_radius
        );
        // level ground names the model as before step heights existed
        if r.step_down != 0.0 {
            s.push_str(&format!("step_down = {:?}\n", r.step_down));
        }
        if self.tilt != 0.0 {
            s.push_str(&format!("tilt = {:?}\n", self.tilt));
        }
        for (k, g) in r.segments.iter().enumerate() {
            let [l, m, c, cn, i] = *g;
            s.push_str(&format!(
                "segments[{k}] = length {l:?}, mass {m:?}, com {c:?}, com_normal {cn:?}, \
                 inertia {i:?}\n"
            ));
        }
        for (k, (free, latch)) in r.free_swing.iter().zip(&r.latched).enumerate() {
            s.push_str(&format!(
                "knees[{k}] = free_swing {free}, hold {}",
                if *latch { "latch" } else { "stop" }
            ));
            // limits named where declared (an ideal latch's line as before they existed)
            if let Some(l) = r.latch_torque[k] {
                s.push_str(&format!(", latch_torque {l:?}"));
            }
            if let Some(l) = r.latch_impulse[k] {
                s.push_str(&format!(", latch_impulse {l:?}"));
            }
            s.push('\n');
        }
        s
    }
    fn param_values(&self) -> Vec<(String, f64)> {
        self.table
            .names
            .iter()
            .cloned()
            .zip(self.table.values.iter().copied())
            .collect()
    }
    fn step_length(&self, x_pre: &[f64]) -> f64 {
        self.swing_foot(x_pre)[0]
    }
    /// The spec's gaits (or a generic start); a section with the swing knee's rate starts it at
    /// 0 where a gait gives only `(stance, stance_rate, hip_rate)`.
    /// With `w = √(g/L)` (L the leg length): the stance leg's angle from 0.02 to 0.6 rad just
    /// after heel strike (legs apart up to 69°), its rate from −2w to 0 (rolling forward), the
    /// hip's and the swing knee's rates from −2w to 2w. The compass gait's `(0.27, −0.35w,
    /// 0.23w)` at 3° (Goswami et al. 1998) and Hsu Chen's kneed gait lie well inside.
    fn section_box(&self) -> Option<(Vec<f64>, Vec<f64>)> {
        let w = (self.r.gravity / self.leg_length).sqrt();
        let (mut lo, mut hi) = (vec![0.02, -2.0 * w, -2.0 * w], vec![0.6, 0.0, 2.0 * w]);
        if self.section_dim() == 4 {
            lo.push(-2.0 * w);
            hi.push(2.0 * w);
        }
        Some((lo, hi))
    }
    fn gait_guesses(&self) -> Vec<GaitGuess> {
        let ds = self.section_dim();
        let mut v = self.gait_guesses3();
        for g in &mut v {
            if g.section.len() < ds {
                g.section.resize(ds, 0.0);
            }
        }
        v
    }
    /// The chain drawn from the stance contact point; with round feet the chain starts at the
    /// stance arc centre `r` above it, and each foot is drawn as its arc (±0.6 rad about the
    /// foot's end) with the shank continued to the foot's end.
    fn pose(&self, x: &[f64]) -> Option<Pose> {
        let mut p = crate::registry::chain_pose(&x[..self.n], &self.len);
        let r = self.radius;
        if r > 0.0 {
            for l in p.links.iter_mut() {
                l[0][1] += r;
                l[1][1] += r;
            }
            for j in p.joints.iter_mut() {
                j[1] += r;
            }
            let th_st = x[0];
            let th_sw: f64 = x[..self.n].iter().sum();
            let cs = p.links[self.n - 1][1];
            let arc = |c: [f64; 2], th: f64| -> Vec<[[f64; 2]; 2]> {
                let pt = |a: f64| [c[0] + r * (th + a).sin(), c[1] - r * (th + a).cos()];
                let mut v = vec![[c, pt(0.0)]];
                for i in 0..8 {
                    let (a, b) = (-0.6 + 0.15 * i as f64, -0.6 + 0.15 * (i + 1) as f64);
                    v.push([pt(a), pt(b)]);
                }
                v
            };
            p.links.extend(arc([0.0, r], th_st));
            p.links.extend(arc(cs, th_sw));
            p.swing_foot = Some([cs[0], cs[1] - r]);
        }
        Some(p)
    }
    /// The kernel's joint points and tip ([`pdw_soa::forward_kinematics`]): the stance foot
    /// (joint 0), the stance knees, the hip (joint `m`), the swing knees (each named as its
    /// state coordinate) and the swing foot; the centre of mass is the link masses' weighted
    /// mean of the kernel's link COMs (the hip mass is part of the top stance link). With
    /// round feet the chain's root is the stance arc centre, `r` above the contact point at
    /// the origin (as in [`Walker::pose`]), and the feet are the arc centres.
    fn body_points(&self, x: &[f64]) -> Option<BodyPoints> {
        self.body_points_in(&mut Scratch::new(), x)
    }
    /// [`Walker::body_points`] with the kinematics in the scratch's kernel workspace.
    fn body_points_in(&self, ws: &mut Scratch, x: &[f64]) -> Option<BodyPoints> {
        let ws = &mut self.scratch(ws).ws;
        pdw_soa::forward_kinematics(&self.chain, ws, &x[..self.n]).ok()?;
        let r = self.radius;
        let up = |p: [f64; 2]| [p[0], p[1] + r];
        let mut points = Vec::with_capacity(self.n + 1);
        points.extend(ws.joint_positions().iter().copied().map(up));
        points.push(up(ws.tip_position()));
        let mut names = Vec::with_capacity(self.n + 1);
        names.push("stance_foot".to_string());
        for k in 1..self.n {
            names.push(if k == self.m {
                "hip".to_string()
            } else {
                self.state_names[k].clone()
            });
        }
        names.push("swing_foot".to_string());
        let links = self.chain.links();
        let total: f64 = links.iter().map(|l| l.mass).sum();
        let mut com = [0.0; 2];
        for (l, c) in links.iter().zip(ws.com_positions()) {
            com[0] += l.mass * c[0] / total;
            com[1] += l.mass * c[1] / total;
        }
        Some(BodyPoints {
            names,
            points,
            com: up(com),
        })
    }
    fn constraint_forces(&self, mode: usize, x: &[f64]) -> Option<ConstraintForces> {
        self.constraint_forces_in(&mut Scratch::new(), mode, x)
    }
    fn step_flags(&self, mode: usize, x: &[f64]) -> Option<StepFlags> {
        self.step_flags_in(&mut Scratch::new(), mode, x)
    }
    /// `T + V` by the kernel's `total_energy` (potential zero at the stance foot).
    fn energy(&self, x: &[f64]) -> Option<f64> {
        self.energy_in(&mut Scratch::new(), x)
    }
    fn constraint_forces_in(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
    ) -> Option<ConstraintForces> {
        Some(self.constraint_forces_ws(ws, mode, x))
    }
    fn step_flags_in(&self, ws: &mut Scratch, mode: usize, x: &[f64]) -> Option<StepFlags> {
        Some(self.check_state_ws(ws, mode, x))
    }
    /// `T + V` by the kernel's `total_energy` in the scratch's workspaces.
    fn energy_in(&self, ws: &mut Scratch, x: &[f64]) -> Option<f64> {
        let s = self.scratch(ws);
        let n = self.n;
        if self.radius > 0.0 {
            // the floating chain at the rolling base (y = −r q₀, ż = 0): the potential counts
            // the arc centre's travel along the slope
            let mut q = [0.0; FMAX];
            let mut qd = [0.0; FMAX];
            q[0] = -self.radius * x[0];
            qd[0] = -self.radius * x[n];
            q[2..n + 2].copy_from_slice(&x[..n]);
            qd[2..n + 2].copy_from_slice(&x[n..2 * n]);
            return pdw_soa::total_energy(&self.floating, &mut s.fws, &q[..n + 2], &qd[..n + 2])
                .ok();
        }
        pdw_soa::total_energy(&self.chain, &mut s.ws, &x[..n], &x[n..2 * n]).ok()
    }
    /// The spec's energy unit: J for SI specs, `M L^2/T^2` for a spec in its own units `L`,
    /// `M`, `T` (Hsu Chen's).
    fn energy_unit(&self) -> &str {
        match self.spec.unit_system() {
            crate::units::UnitSystem::Si => "J",
            crate::units::UnitSystem::Abstract => "M L^2/T^2",
        }
    }
    /// Time in the unit the spec declares for `max_stride_time` (`"s"` if none); lengths in m
    /// for a time in s, else in the spec's reference length `l`; forces and torques in N, N m
    /// for SI specs, in `M L/T^2` and `M L^2/T^2` for a spec in its own units `L`, `M`, `T`.
    fn units(&self) -> pdw_model::ModelUnits {
        let own = self.spec.unit_system() == crate::units::UnitSystem::Abstract;
        let time = self
            .spec
            .parameters
            .get("max_stride_time")
            .map(|p| p.unit.clone())
            .filter(|u| !u.is_empty())
            .unwrap_or_else(|| if own { "T" } else { "s" }.to_string());
        let length = if time == "s" && !own { "m" } else { "l" };
        let (force, torque) = if own {
            ("M L/T^2", "M L^2/T^2")
        } else {
            ("N", "N m")
        };
        pdw_model::ModelUnits {
            time: time.into(),
            length: length.into(),
            force: force.into(),
            torque: torque.into(),
        }
    }
    fn impact_report(&self, mode: usize, guard: usize, x_pre: &[f64]) -> Option<ImpactReport> {
        (guard == 0)
            .then(|| self.impact_report_at(mode, x_pre))
            .flatten()
    }
    /// A latch's `latch_torque` for both knees (it is one knee spec), else 0.
    fn knee_pull_limits(&self) -> [f64; 2] {
        [self.latch_torque.unwrap_or(0.0); 2]
    }
    /// Total mass (both legs and the hip mass), leg length, gravity.
    fn scales(&self) -> Option<Scales> {
        let legs: f64 = self.r.segments.iter().map(|s| s[1]).sum();
        Some(Scales {
            mass: 2.0 * legs + self.r.hip_mass,
            length: self.leg_length,
            gravity: self.r.gravity,
        })
    }
    /// Height of the swing foot's lowest point above the slope: with round feet both arc
    /// centres are `r` above their feet's lowest points (the stance one on the slope), so it is
    /// the height of the chain's tip over its root, as for point feet.
    /// With a step down (`h > 0`) the ground ahead of the stance foot is the foothold's line
    /// `h` lower (module docs, "Step down"), so a swing foot ahead is measured from there.
    fn swing_clearance(&self, _mode: usize, x: &[f64]) -> Option<f64> {
        let [y, z] = self.swing_foot(x);
        if self.tilt != 0.0 && self.swing_ahead(x) {
            return Some(self.above_tilted([y, z], [0.0; 2]).0);
        }
        let h = self.r.step_down;
        Some(if h > 0.0 && y > 0.0 { z + h } else { z })
    }
    /// Walkers with knees must clear the ground over the whole swing; straight-legged ones
    /// (the compass gait) keep the point-foot literature's mid-stance convention.
    fn clearance_rule(&self) -> ClearanceRule {
        if self.m > 1 {
            ClearanceRule::WholeSwing
        } else {
            ClearanceRule::AfterMidStance
        }
    }
}

/// What a chain walker's state component `name` measures (module docs, "Coordinates").
fn chain_coordinate(name: &str) -> String {
    if let Some(base) = name.strip_suffix("_rate") {
        return format!("rate of {base} (rad per time unit)");
    }
    match name {
        "stance" => "angle of the stance leg's lowest segment from the slope normal (rad); \
                     positive: stance foot downhill of the hip"
            .into(),
        "hip" => "swing leg relative to the stance leg at the hip (rad); 0: legs together".into(),
        n if n.starts_with("stance_knee") => {
            "stance knee flexion relative to the segment below (rad); flexes with q > 0, \
             straight at 0"
                .into()
        }
        n if n.starts_with("swing_knee") => {
            "swing knee flexion relative to the segment above (rad); flexes with q < 0, \
             straight at 0"
                .into()
        }
        n => format!("joint {n} (rad)"),
    }
}
