//! The compass-gait walker of Goswami, Thuilot & Espiau (INRIA RR-2996, 1996; IJRR 1998) as a
//! two-link chain on the planar SOA kernel ([`pdw_soa`]).
//!
//! Two rigid legs of length `l = a + b`, each with a point mass `m` at distance `a` from its foot
//! (`b` from the hip), and a point mass `m_H` at the hip, on a slope `γ`. SI units (m, kg, s).
//! Default preset: Goswami et al. (`m = 5`, `m_H = 10`, `a = b = 0.5`, `g = 9.81`, slope 3°).
//!
//! # Frame, coordinates and signs
//! The kernel's slope frame: `y` along the slope **pointing downhill**, `z` normal to the slope
//! pointing up; gravity `(g sin γ, −g cos γ)` enters as the base acceleration
//! `[0, −g sin γ, g cos γ]` (seed eq. 3.12 with `y` downhill). A revolute joint angle is positive
//! from `+y` towards `+z`.
//!
//! State `x = (q₁, q₂, q̇₁, q̇₂)` in the kernel's joint coordinates of the chain rooted at the
//! stance foot (the origin):
//! - `q₁` — stance-leg angle from the slope normal: hip `= l(−sin q₁, cos q₁)`. Positive when
//!   the stance foot is ahead of (downhill from) the hip — Garcia's θ. A step runs from
//!   `q₁ ≈ +α` to `q₁ ≈ −α`; the stance leg is vertical at `q₁ = γ`.
//! - `q₂` — hip angle, swing leg relative to stance leg; the swing leg's absolute angle is
//!   `ψ = q₁ + q₂`, swing foot `= hip + l(sin ψ, −cos ψ)`. `q₂ = 0`: legs together;
//!   `q₂ > 0`: swing foot ahead of the stance foot. Garcia's `φ = −q₂`.
//!
//! Goswami's absolute angles from the vertical are `θ_s = q₁ − γ`, `θ_ns = ψ − γ` (up to one
//! common sign, which their equations do not see).
//!
//! # Chain (kernel model)
//! Link 0 (stance leg, joint at the stance foot): `to_next = (0, l)`, mass `m + m_H` with COM
//! `(0, (m a + m_H l)/(m + m_H))` and inertia about it `m(a − c)² + m_H(l − c)²` (the two point
//! masses). Link 1 (swing leg, joint at the hip): tip offset `(0, −l)` (the swing foot), point
//! mass `m` at `(0, −b)`. The flow is the kernel's O(n) [`pdw_soa::aba`] with τ = 0.
//!
//! # Heel strike (guard 0, reset)
//! `g = z_tip = l(cos q₁ − cos ψ) = 2l sin(q₁ + q₂/2) sin(q₂/2)`, the swing-foot height,
//! **falling** through zero. The height vanishes on the heel-strike factor `2q₁ + q₂ = 0`
//! (symmetric legs) and on the scuffing factor `q₂ = 0` (legs together, mid-stance). A crossing
//! is admissible only if the swing foot is ahead of the stance foot (`y_tip > 0`) **and** the
//! crossing is on the heel-strike factor: `|2q₁ + q₂| < |q₂|`. Both tests are scale free; the
//! scuffing crossing (where `q₂ ≈ 0`, `y_tip ≈ 0`) is never taken.
//!
//! The reset is a plastic impact at the swing foot with the old stance foot free, computed by
//! the kernel on the *floating* chain `(P_y, P_z, q₁, q₂)` rooted at the stance foot:
//! `q̇⁺ = q̇⁻ − 𝓜⁻¹Jᵀ(J𝓜⁻¹Jᵀ)⁻¹J q̇⁻` with `J` the swing-foot velocity rows — it conserves the
//! whole walker's angular momentum about the new contact point and the trailing leg's about the
//! hip (Goswami's `Q⁺ q̇⁺ = Q⁻ q̇⁻`). Then the leg swap (the new stance leg is the old swing leg):
//! `q₁' = q₁ + q₂`, `q₂' = −q₂`, `q̇₁' = q̇₁⁺ + q̇₂⁺`, `q̇₂' = −q̇₂⁺` (the rates of the floating
//! chain's revolute joints are the links' absolute angular rates and their difference).
//! The kernel requires every link mass to be positive, so the two prismatic base links carry
//! [`FLOATING_BASE_MASS`] = 1e-30 kg, which changes no sum of masses by even one ulp.
//!
//! # Falls (terminal guards)
//! - guard 1 `stance_reverses` ([`FALL_BACKWARD`]): `q̇₁` rises through 0 while the stance leg
//!   has not reached the vertical (`q₁ > γ`): the walker falls back over its stance foot.
//! - guard 2 `hip_on_ground_behind` ([`FALL_BACKWARD`]): `q₁ − π/2` rising (hip height zero).
//! - guard 3 `hip_on_ground_ahead` ([`FALL_FORWARD`]): `q₁ + π/2` falling.
//!
//! # Section
//! Just after heel strike (mode 0). The heel-strike geometry gives `q₂ = −2q₁`, so the reduced
//! coordinates are `s = (q₁, q̇₁, q̇₂)` (`"stance"`, `"stance_rate"`, `"hip_rate"`), lifted to
//! `x = (s₀, −2s₀, s₁, s₂)`.
//!
//! # Workspace
//! [`HybridSystem::flow`] takes `&self`; the kernel's [`Workspace`] lives in a per-thread cache
//! (`thread_local!`, one workspace per chain size, allocated on first use), so the flow does not
//! allocate after the first call on a thread.

use crate::error::{check_open, WalkerError};
use crate::registry::{GaitGuess, ModelInfo, ParamSpec, Pose, Walker};
use pdw_hybrid::{Crossing, GuardKind, GuardSpec, HybridSystem, Scratch, Section};
use pdw_soa::{Chain, ChainBuilder, Link, Workspace};
use std::cell::RefCell;
use std::f64::consts::FRAC_PI_2;

/// Guard index of the heel strike.
pub const HEEL_STRIKE: usize = 0;
/// Fall code: the walker falls backward (over its stance foot, uphill).
pub const FALL_BACKWARD: u8 = 1;
/// Fall code: the walker falls forward (hip reaches the ground ahead).
pub const FALL_FORWARD: u8 = 2;
/// Mass (kg) of the fictitious prismatic base links of the floating chains used for impacts.
pub const FLOATING_BASE_MASS: f64 = 1e-30;

/// The fall guards shared by the chain walkers (compass, kneed, seed5), in this order: the
/// stance leg reverses, the hip reaches the ground behind, the hip reaches the ground ahead.
pub(crate) const FALL_GUARDS: [GuardSpec; 3] = [
    GuardSpec {
        name: "stance_reverses",
        crossing: Crossing::Rising,
        kind: GuardKind::Terminal(FALL_BACKWARD),
    },
    GuardSpec {
        name: "hip_on_ground_behind",
        crossing: Crossing::Rising,
        kind: GuardKind::Terminal(FALL_BACKWARD),
    },
    GuardSpec {
        name: "hip_on_ground_ahead",
        crossing: Crossing::Falling,
        kind: GuardKind::Terminal(FALL_FORWARD),
    },
];

const GUARDS: [GuardSpec; 4] = [
    GuardSpec {
        name: "heel_strike",
        crossing: Crossing::Falling,
        kind: GuardKind::Reset,
    },
    FALL_GUARDS[0],
    FALL_GUARDS[1],
    FALL_GUARDS[2],
];

const STATE_NAMES: [&str; 4] = ["stance", "hip", "stance_rate", "hip_rate"];
const SECTION_NAMES: [&str; 3] = ["stance", "stance_rate", "hip_rate"];

static PARAMS: [ParamSpec; 7] = [
    ParamSpec {
        name: "slope",
        unit: "rad",
        default: 3.0 * std::f64::consts::PI / 180.0,
        description: "slope angle γ (Goswami et al. 1998: 3°)",
    },
    ParamSpec {
        name: "leg_mass",
        unit: "kg",
        default: 5.0,
        description: "point mass m of each leg (Goswami et al. 1998: 5 kg)",
    },
    ParamSpec {
        name: "hip_mass",
        unit: "kg",
        default: 10.0,
        description: "point mass m_H at the hip (Goswami et al. 1998: 10 kg)",
    },
    ParamSpec {
        name: "a",
        unit: "m",
        default: 0.5,
        description: "foot to leg mass distance a (Goswami et al. 1998: 0.5 m)",
    },
    ParamSpec {
        name: "b",
        unit: "m",
        default: 0.5,
        description:
            "leg mass to hip distance b; leg length l = a + b (Goswami et al. 1998: 0.5 m)",
    },
    ParamSpec {
        name: "gravity",
        unit: "m/s^2",
        default: 9.81,
        description: "gravitational acceleration g (Goswami et al. 1998: 9.81)",
    },
    ParamSpec {
        name: "max_stride_time",
        unit: "s",
        default: 5.0,
        description: "stride time budget; a longer stride counts as a fall (gait period ≈ 0.73 s)",
    },
];

/// The registry entry of the compass gait.
pub static INFO: ModelInfo = ModelInfo {
    name: "compass",
    description: "Goswami et al. 1998 compass gait: two rigid legs with point masses and a hip \
                  mass, as a 2-link SOA chain; SI units",
    params: &PARAMS,
    state_names: &STATE_NAMES,
    section_names: &SECTION_NAMES,
    build_from: |v| {
        Ok(Box::new(Compass::new(CompassParams {
            slope: v[0],
            leg_mass: v[1],
            hip_mass: v[2],
            a: v[3],
            b: v[4],
            gravity: v[5],
            max_stride_time: v[6],
        })?))
    },
};

/// Parameters of the compass gait (SI units). [`Default`] is Goswami et al.'s preset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompassParams {
    /// Slope angle γ (rad), in (−π/2, π/2).
    pub slope: f64,
    /// Point mass `m` of each leg (kg), > 0.
    pub leg_mass: f64,
    /// Point mass `m_H` at the hip (kg), ≥ 0.
    pub hip_mass: f64,
    /// Distance `a` from the foot to the leg mass (m), ≥ 0.
    pub a: f64,
    /// Distance `b` from the leg mass to the hip (m), > 0.
    pub b: f64,
    /// Gravitational acceleration `g` (m/s²), > 0.
    pub gravity: f64,
    /// Stride time budget (s), > 0.
    pub max_stride_time: f64,
}

impl Default for CompassParams {
    /// Goswami, Thuilot & Espiau (1998): m = 5, m_H = 10, a = b = 0.5, g = 9.81, slope 3°.
    fn default() -> Self {
        Self {
            slope: 3.0f64.to_radians(),
            leg_mass: 5.0,
            hip_mass: 10.0,
            a: 0.5,
            b: 0.5,
            gravity: 9.81,
            max_stride_time: 5.0,
        }
    }
}

/// Checks that `value` is finite and in the half-open interval `[lo, hi)`.
pub(crate) fn check_closed_open(
    name: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    allowed: &'static str,
) -> Result<f64, WalkerError> {
    if value.is_finite() && value >= lo && value < hi {
        Ok(value)
    } else {
        Err(WalkerError::InvalidParam {
            name,
            value,
            allowed,
        })
    }
}

/// Validates a slope angle (rad): finite, in (−π/2, π/2).
pub(crate) fn check_slope(v: f64) -> Result<f64, WalkerError> {
    check_open(
        "slope",
        v,
        -FRAC_PI_2,
        FRAC_PI_2,
        "a finite angle in (-pi/2, pi/2) rad",
    )
}

/// Validates a positive finite quantity.
pub(crate) fn check_positive(name: &'static str, v: f64) -> Result<f64, WalkerError> {
    check_open(name, v, 0.0, f64::INFINITY, "finite and > 0")
}

/// The compass-gait walker (immutable model). See the module docs for conventions.
#[derive(Clone, Debug)]
pub struct Compass {
    p: CompassParams,
    l: f64,
    /// 2-joint chain rooted at the stance foot (flow, ground reaction).
    chain: Chain,
    /// 4-joint floating chain `(P_y, P_z, stance, hip)` for the heel-strike impulse.
    floating: Chain,
}

/// Result of a plastic impact at the swing foot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeelStrike {
    /// Impulse of the ground on the new stance foot `[Λ_y, Λ_z]` (N s; y downhill, z normal).
    /// A physical heel strike has `Λ_z ≥ 0`.
    pub impulse: [f64; 2],
    /// Velocity of the trailing (old stance) foot just after the impact `[v_y, v_z]` (m/s); it
    /// must leave the ground, `v_z ≥ 0`, for the impact model to be consistent.
    pub trailing_foot_velocity: [f64; 2],
    /// Kinetic energy just before and just after the impact (J).
    pub kinetic_energy: [f64; 2],
}

impl Compass {
    /// Builds the model; rejects non-finite or out-of-range parameters.
    pub fn new(p: CompassParams) -> Result<Self, WalkerError> {
        check_slope(p.slope)?;
        check_positive("leg_mass", p.leg_mass)?;
        check_closed_open(
            "hip_mass",
            p.hip_mass,
            0.0,
            f64::INFINITY,
            "finite and >= 0",
        )?;
        check_closed_open("a", p.a, 0.0, f64::INFINITY, "finite and >= 0")?;
        check_positive("b", p.b)?;
        check_positive("gravity", p.gravity)?;
        check_positive("max_stride_time", p.max_stride_time)?;
        let l = p.a + p.b;
        let (m, mh) = (p.leg_mass, p.hip_mass);
        let c = (m * p.a + mh * l) / (m + mh);
        let stance = Link {
            to_next: [0.0, l],
            com: [0.0, c],
            mass: m + mh,
            inertia: m * (p.a - c).powi(2) + mh * (l - c).powi(2),
        };
        let swing = Link {
            to_next: [0.0, -l],
            com: [0.0, -p.b],
            mass: m,
            inertia: 0.0,
        };
        let chain = ChainBuilder::new()
            .gravity(p.gravity)
            .slope(p.slope)
            .revolute(stance)
            .revolute(swing)
            .build()
            .map_err(soa_param_error)?;
        let floating = floating_chain(&[stance, swing], p.gravity, p.slope)?;
        Ok(Self {
            p,
            l,
            chain,
            floating,
        })
    }

    /// The parameters the model was built from.
    pub fn params(&self) -> &CompassParams {
        &self.p
    }

    /// Leg length `l = a + b` (m).
    pub fn leg_length(&self) -> f64 {
        self.l
    }

    /// The kernel chain rooted at the stance foot.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// Swing-foot position `[y, z]` relative to the stance foot (m).
    pub fn swing_foot(&self, x: &[f64]) -> [f64; 2] {
        let (s1, c1) = x[0].sin_cos();
        let (sp, cp) = (x[0] + x[1]).sin_cos();
        [self.l * (sp - s1), self.l * (c1 - cp)]
    }

    /// Joint accelerations `q̈` at state `x` by the kernel's `aba`.
    pub fn accelerations(&self, x: &[f64]) -> [f64; 2] {
        let mut qdd = [0.0; 2];
        with_workspace(&self.chain, |ws| {
            if pdw_soa::aba(
                &self.chain,
                ws,
                &x[0..2],
                &x[2..4],
                &[0.0; 2],
                None,
                &mut qdd,
            )
            .is_err()
            {
                qdd = [f64::NAN; 2];
            }
        });
        qdd
    }

    /// Total mechanical energy `T + V` (J), potential energy zero at the stance foot.
    pub fn energy(&self, x: &[f64]) -> f64 {
        chain_energy(&self.chain, &x[0..2], &x[2..4])
    }

    /// The heel-strike impact (plastic, at the swing foot, old stance foot free) at the
    /// pre-impact state `x`; writes the post-impact state **before** the leg swap, in the old
    /// chain's coordinates, into `qd_post` (floating rates `(ẏ, ż, q̇₁, q̇₂)`).
    pub fn heel_strike(&self, x: &[f64], qd_post: &mut [f64; 4]) -> HeelStrike {
        let q = [0.0, 0.0, x[0], x[1]];
        let qd = [0.0, 0.0, x[2], x[3]];
        floating_impact(&self.floating, &q, &qd, &[], qd_post)
    }

    /// Ground reaction at the stance foot along the flow at state `x`.
    pub fn constraint_forces(&self, _mode: usize, x: &[f64]) -> ConstraintForces {
        let qdd = self.accelerations(x);
        let f = base_force(&self.chain, &x[0..2], &x[2..4], &qdd);
        ConstraintForces::from_ground(f, [None, None])
    }

    /// Validity check at one state of a step: see [`StepFlags`]. Accumulate with
    /// [`StepFlags::merge`] over the states of a step.
    pub fn check_state(&self, mode: usize, x: &[f64]) -> StepFlags {
        let cf = self.constraint_forces(mode, x);
        let foot = self.swing_foot(x);
        StepFlags::from_state(&cf, foot, self.l)
    }
}

impl HybridSystem for Compass {
    fn dim(&self) -> usize {
        4
    }

    fn guards(&self, _mode: usize) -> &[GuardSpec] {
        &GUARDS
    }

    fn flow(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], dx: &mut [f64]) {
        let qdd = self.accelerations(x);
        dx[0] = x[2];
        dx[1] = x[3];
        dx[2] = qdd[0];
        dx[3] = qdd[1];
    }

    fn guard(&self, _ws: &mut Scratch, _mode: usize, k: usize, x: &[f64]) -> f64 {
        match k {
            0 => self.swing_foot(x)[1],
            1 => x[2],
            2 => x[0] - FRAC_PI_2,
            _ => x[0] + FRAC_PI_2,
        }
    }

    fn admissible(&self, _mode: usize, k: usize, x: &[f64]) -> bool {
        match k {
            0 => self.swing_foot(x)[0] > 0.0 && (2.0 * x[0] + x[1]).abs() < x[1].abs(),
            1 => x[0] > self.p.slope,
            _ => true,
        }
    }

    fn reset(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        _k: usize,
        x: &[f64],
        out: &mut [f64],
    ) -> usize {
        let mut v = [0.0; 4];
        self.heel_strike(x, &mut v);
        out[0] = x[0] + x[1];
        out[1] = -x[1];
        out[2] = v[2] + v[3];
        out[3] = -v[3];
        0
    }
}

impl Section for Compass {
    fn section_dim(&self) -> usize {
        3
    }
    fn section_names(&self) -> &[&'static str] {
        &SECTION_NAMES
    }
    fn section_mode(&self) -> usize {
        0
    }
    fn section_guard(&self) -> (usize, usize) {
        (0, HEEL_STRIKE)
    }
    fn lift(&self, s: &[f64], x: &mut [f64]) {
        x[0] = s[0];
        x[1] = -2.0 * s[0];
        x[2] = s[1];
        x[3] = s[2];
    }
    fn project(&self, x: &[f64], s: &mut [f64]) {
        s[0] = x[0];
        s[1] = x[2];
        s[2] = x[3];
    }
    fn max_stride_time(&self) -> f64 {
        self.p.max_stride_time
    }
}

impl Walker for Compass {
    fn pose(&self, x: &[f64]) -> Option<Pose> {
        Some(crate::registry::chain_pose(&x[0..2], &[self.l, -self.l]))
    }
    fn constraint_forces(&self, mode: usize, x: &[f64]) -> Option<ConstraintForces> {
        Some(Self::constraint_forces(self, mode, x))
    }
    fn step_flags(&self, mode: usize, x: &[f64]) -> Option<StepFlags> {
        Some(self.check_state(mode, x))
    }
    fn name(&self) -> &'static str {
        "compass"
    }
    fn state_names(&self) -> &'static [&'static str] {
        &STATE_NAMES
    }
    fn param_values(&self) -> Vec<(&'static str, f64)> {
        let p = &self.p;
        vec![
            ("slope", p.slope),
            ("leg_mass", p.leg_mass),
            ("hip_mass", p.hip_mass),
            ("a", p.a),
            ("b", p.b),
            ("gravity", p.gravity),
            ("max_stride_time", p.max_stride_time),
        ]
    }
    fn step_length(&self, x_pre: &[f64]) -> f64 {
        self.swing_foot(x_pre)[0]
    }
    fn fall_name(&self, code: u8) -> &'static str {
        match code {
            FALL_BACKWARD => "fell backward",
            FALL_FORWARD => "fell forward",
            _ => "unknown fall",
        }
    }
    fn gait_guesses(&self) -> Vec<GaitGuess> {
        vec![GaitGuess {
            gait: "stable",
            section: COMPASS_GAIT_GUESS.to_vec(),
            source: "compass period-one gait at the Goswami preset (slope 3°), found by this \
                     engine; half inter-leg angle 0.27 rad ≈ 15.5° as in Goswami et al. 1998",
        }]
    }
}

/// Starting point for the period-one gait search at the Goswami preset.
const COMPASS_GAIT_GUESS: [f64; 3] = [0.271029, -1.092384, 0.715010];

// ---------------------------------------------------------------------------------------------
// Shared by the chain walkers (compass, kneed, seed5).
// ---------------------------------------------------------------------------------------------

/// Constraint forces at one state along the flow.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConstraintForces {
    /// Normal ground reaction on the stance foot (N); positive: the ground pushes up.
    pub normal: f64,
    /// Tangential ground reaction on the stance foot (N), along `+y` (downhill).
    pub tangential: f64,
    /// Friction coefficient the ground must supply, `|f_t / f_n|` (`+∞` if `f_n ≤ 0`).
    pub friction_required: f64,
    /// Locking torques of the knees `[stance knee, swing knee]` (N m) where the knee is locked
    /// (`None` where it is free or absent). Sign: the torque the lock applies to the shank
    /// relative to the thigh, positive towards knee flexion; the hyper-extension stop can only
    /// push, so a **negative** torque means the knee would unlock (flex).
    pub knee_torque: [Option<f64>; 2],
}

impl ConstraintForces {
    pub(crate) fn from_ground(f: [f64; 3], knee_torque: [Option<f64>; 2]) -> Self {
        let (ft, fnrm) = (f[1], f[2]);
        let friction_required = if fnrm > 0.0 {
            (ft / fnrm).abs()
        } else {
            f64::INFINITY
        };
        Self {
            normal: fnrm,
            tangential: ft,
            friction_required,
            knee_torque,
        }
    }
}

/// Validity flags of a step (all `false` for a valid step).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepFlags {
    /// The normal ground reaction on the stance foot became negative (the foot would lift off).
    pub normal_force_negative: bool,
    /// A locked knee needed a locking torque of the wrong sign (it would unlock).
    pub knee_unlocks: bool,
    /// The swing foot was below the ground while ahead of the stance foot, i.e. between
    /// mid-stance (the feet passing each other) and heel strike. The unavoidable dip of a
    /// straight swing leg *before* the feet pass is not flagged (as in Garcia et al. 1998).
    pub swing_foot_scuffs: bool,
}

impl StepFlags {
    /// Flags at one state from its constraint forces and swing-foot position `[y, z]`
    /// (relative to the stance foot); `scale` sets the tolerance of the scuff test
    /// (`z < −1e-12·scale`).
    pub fn from_state(cf: &ConstraintForces, swing_foot: [f64; 2], scale: f64) -> Self {
        Self {
            normal_force_negative: cf.normal < 0.0,
            knee_unlocks: cf.knee_torque.iter().flatten().any(|&t| t < 0.0),
            swing_foot_scuffs: swing_foot[0] > 0.0 && swing_foot[1] < -1e-12 * scale,
        }
    }

    /// Union of two sets of flags.
    pub fn merge(self, o: Self) -> Self {
        Self {
            normal_force_negative: self.normal_force_negative || o.normal_force_negative,
            knee_unlocks: self.knee_unlocks || o.knee_unlocks,
            swing_foot_scuffs: self.swing_foot_scuffs || o.swing_foot_scuffs,
        }
    }

    /// Whether any flag is raised.
    pub fn any(&self) -> bool {
        self.normal_force_negative || self.knee_unlocks || self.swing_foot_scuffs
    }
}

thread_local! {
    /// Per-thread kernel workspaces, one per chain size (allocated on first use).
    static WORKSPACES: RefCell<Vec<Workspace>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f` with this thread's cached workspace for chains of `chain.dof()` joints. A
/// workspace holds only buffers sized by the number of joints, so chains of equal size share one.
/// A re-entrant call (not made by this crate) gets a fresh workspace.
pub(crate) fn with_workspace<R>(chain: &Chain, f: impl FnOnce(&mut Workspace) -> R) -> R {
    WORKSPACES.with(|cell| match cell.try_borrow_mut() {
        Ok(mut v) => {
            let n = chain.dof();
            let i = match v.iter().position(|w| w.dof() == n) {
                Some(i) => i,
                None => {
                    v.push(Workspace::new(chain));
                    v.len() - 1
                }
            };
            f(&mut v[i])
        }
        Err(_) => f(&mut Workspace::new(chain)),
    })
}

/// Maps a kernel construction error (only reachable through extreme parameter values that pass
/// the model's own checks) to a parameter error.
pub(crate) fn soa_param_error(e: pdw_soa::SoaError) -> WalkerError {
    let _ = e;
    WalkerError::InvalidParam {
        name: "geometry",
        value: f64::NAN,
        allowed: "a chain the kernel accepts (positive masses, non-degenerate inertias)",
    }
}

/// The floating version of a chain rooted at a foot: two prismatic joints `(y, z)` carrying
/// [`FLOATING_BASE_MASS`], then the given revolute links.
pub(crate) fn floating_chain(links: &[Link], g: f64, slope: f64) -> Result<Chain, WalkerError> {
    let base = Link {
        to_next: [0.0, 0.0],
        com: [0.0, 0.0],
        mass: FLOATING_BASE_MASS,
        inertia: 0.0,
    };
    let mut b = ChainBuilder::new()
        .gravity(g)
        .slope(slope)
        .prismatic([1.0, 0.0], base)
        .prismatic([0.0, 1.0], base);
    for l in links {
        b = b.revolute(*l);
    }
    b.build().map_err(soa_param_error)
}

/// Base force `F_0 = [τ, f_y, f_z]` the ground exerts on link 0 for the motion `(q, q̇, q̈)`
/// (kernel `base_reaction`); NaN on a kernel error.
pub(crate) fn base_force(chain: &Chain, q: &[f64], qd: &[f64], qdd: &[f64]) -> [f64; 3] {
    with_workspace(chain, |ws| {
        pdw_soa::base_reaction(chain, ws, q, qd, qdd, None).unwrap_or([f64::NAN; 3])
    })
}

/// Total energy `T + U` (J) of a chain by the kernel's `total_energy` (potential energy zero
/// at the base point); NaN on a kernel error.
pub(crate) fn chain_energy(chain: &Chain, q: &[f64], qd: &[f64]) -> f64 {
    with_workspace(chain, |ws| {
        pdw_soa::total_energy(chain, ws, q, qd).unwrap_or(f64::NAN)
    })
}

/// Plastic impact on a floating chain `(P_y, P_z, revolute…)` at its tip, with the joints in
/// `locked` (indices into the floating chain) held impulsively, by the kernel's
/// [`pdw_soa::tip_impact`]: `q̇⁺ = q̇⁻ − 𝓜⁻¹Aᵀ(A𝓜⁻¹Aᵀ)⁻¹A q̇⁻` with `A` the tip's linear
/// velocity rows and `e_kᵀ` for `k ∈ locked`. `qd_post` has the floating chain's length.
pub(crate) fn floating_impact(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    locked: &[usize],
    qd_post: &mut [f64],
) -> HeelStrike {
    const NMAX: usize = 8;
    let m = 2 + locked.len();
    let mut imp = [0.0; NMAX];
    with_workspace(chain, |ws| {
        let ok = pdw_soa::tip_impact(chain, ws, q, qd, locked, qd_post, &mut imp[..m]).is_ok();
        let t0 = pdw_soa::kinetic_energy(chain, ws, q, qd);
        let t1 = pdw_soa::kinetic_energy(chain, ws, q, qd_post);
        match (ok, t0, t1) {
            (true, Ok(t0), Ok(t1)) => HeelStrike {
                impulse: [-imp[0], -imp[1]],
                trailing_foot_velocity: [qd_post[0], qd_post[1]],
                kinetic_energy: [t0, t1],
            },
            _ => {
                qd_post.iter_mut().for_each(|v| *v = f64::NAN);
                HeelStrike {
                    impulse: [f64::NAN; 2],
                    trailing_foot_velocity: [f64::NAN; 2],
                    kinetic_energy: [f64::NAN; 2],
                }
            }
        }
    })
}
