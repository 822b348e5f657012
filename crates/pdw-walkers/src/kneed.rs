//! The kneed walker of V. F. Hsu Chen (MIT thesis, 2007; after McGeer 1990) as a three-link
//! chain on the planar SOA kernel ([`pdw_soa`]).
//!
//! Point feet; each leg is a shank (length `a₁ + b₁`, point mass `m_s` at `a₁` from the foot)
//! and a thigh (length `a₂ + b₂`, point mass `m_t` at `a₂` from the knee); point mass `m_H` at the
//! hip. The stance leg is rigid (its knee stays locked); the swing knee is free until it
//! straightens (knee strike) and locked from then until heel strike. Units as in Hsu Chen:
//! `L = 1`, `g = 9.8`, masses in the thesis' units. Default preset: Hsu Chen 2007 (shared
//! REFERENCES §4): `a₁ = 0.375, b₁ = 0.125, a₂ = 0.175, b₂ = 0.325, m_H = 0.5, m_t = 0.5,
//! m_s = 0.05, γ = 0.0504, g = 9.8`.
//!
//! # Frame, coordinates and signs
//! As for [`crate::compass`]: slope frame with `y` downhill, `z` up, positive angles from `+y`
//! to `+z`. State `x = (q₁, q₂, q₃, q̇₁, q̇₂, q̇₃)`:
//! - `q₁` — stance-leg angle from the slope normal (positive: stance foot ahead of the hip);
//! - `q₂` — swing thigh relative to the stance leg (thigh absolute angle `ψ_t = q₁ + q₂`);
//! - `q₃` — swing knee, shank relative to thigh (shank absolute angle `ψ_s = ψ_t + q₃`).
//!   **Knee flexion is `q₃ < 0`** (the foot swings back behind the knee); `q₃ > 0` would be
//!   hyper-extension, which the knee stop prevents.
//!
//! Hsu Chen's absolute angles are measured from the vertical: `(θ₁, θ₂, θ₃) = (q₁ − γ, ψ_t − γ,
//! ψ_s − γ)`.
//!
//! # Modes
//! - mode 0, [`UNLOCKED`]: 3-link swing, the kernel's [`pdw_soa::aba`].
//! - mode 1, [`LOCKED`]: the knee is a pseudo joint (seed §3.4), the kernel's
//!   [`pdw_soa::pseudo_joint_dynamics`] with joint 2 locked: `q̈₃ = 0`, `q₃ = q̇₃ = 0`
//!   throughout. It equals the two-link model with thigh and shank merged into one rigid link
//!   (tested).
//!
//! # Guards
//! Mode 0: 0 `knee_strike` (reset → mode 1): `q₃` **rising** through 0 (the knee straightens).
//! 1 `foot_strike_knee_bent` (terminal, [`FALL_KNEE_BENT`]): swing-foot height falling through
//! 0 with the swing foot ahead of the stance foot, before the knee locked. 2–4: falls as in
//! [`crate::compass`] (`stance_reverses`, `hip_on_ground_behind`, `hip_on_ground_ahead`).
//!
//! Mode 1: 0 `heel_strike` (reset → mode 0): swing-foot height falling through 0; admissible
//! with the swing foot ahead and on the heel-strike factor `|2q₁ + q₂| < |q₂|` (with the knee
//! locked the swing foot height is `2L sin(q₁ + q₂/2) sin(q₂/2)`, as the compass gait's).
//! 1–3: the falls.
//!
//! # Resets
//! - Knee strike: plastic lock of the knee, the kernel's [`pdw_soa::joint_lock_impact`]
//!   (`q̇⁺ = q̇⁻ − 𝓜⁻¹eₖ(eₖᵀ𝓜⁻¹eₖ)⁻¹eₖᵀq̇⁻`, k = knee) with the stance foot pinned; it conserves
//!   the whole walker's angular momentum about the stance foot and the swing leg's about the
//!   hip. `q₃` is set to exactly 0.
//! - Heel strike: plastic impact at the swing foot with the knee held locked, old stance foot
//!   free, the kernel's [`pdw_soa::tip_impact`] on the floating chain `(P_y, P_z, q₁, q₂, q₃)`;
//!   then the leg swap: `q₁' = q₁ + q₂ + q₃`, `q₂' = −(q₂ + q₃)`, `q₃' = 0`, and for the rates
//!   `q̇₁' = q̇₁⁺ + q̇₂⁺ + q̇₃⁺`, `q̇₂' = −(q̇₂⁺ + q̇₃⁺)`, `q̇₃' = 0` (the new swing leg is the
//!   old, rigid, stance leg).
//!
//! # Section
//! Just after heel strike, mode 0, with `q₂ = −2q₁`, `q₃ = q̇₃ = 0`: reduced coordinates
//! `s = (q₁, q̇₁, q̇₂)` (`"stance"`, `"stance_rate"`, `"hip_rate"`).
//!
//! # Constraint forces
//! Ground reaction at the stance foot by the kernel's `base_reaction`; the swing-knee locking
//! torque (mode 1) from the pseudo joint; the stance-knee torque from a four-link report chain
//! (stance shank, stance knee locked, thigh, shank) with the same dynamics. Both reported
//! positive towards flexion (see [`ConstraintForces`]).

use crate::compass::{
    chain_energy, check_closed_open, check_positive, check_slope, floating_chain, floating_impact,
    soa_param_error, with_workspace, ConstraintForces, HeelStrike, StepFlags, FALL_GUARDS,
};
use crate::error::WalkerError;
use crate::registry::{GaitGuess, ModelInfo, ParamSpec, Pose, Walker};
use pdw_hybrid::{Crossing, GuardKind, GuardSpec, HybridSystem, Scratch, Section};
use pdw_soa::{Chain, ChainBuilder, Link};
use std::f64::consts::FRAC_PI_2;

/// Mode: swing knee free.
pub const UNLOCKED: usize = 0;
/// Mode: swing knee locked.
pub const LOCKED: usize = 1;
/// Guard index (mode 0) of the knee strike.
pub const KNEE_STRIKE: usize = 0;
/// Guard index (mode 1) of the heel strike.
pub const HEEL_STRIKE: usize = 0;
/// Fall code: the walker falls backward.
pub const FALL_BACKWARD: u8 = 1;
/// Fall code: the walker falls forward.
pub const FALL_FORWARD: u8 = 2;
/// Fall code: the swing foot hits the ground before the knee locked.
pub const FALL_KNEE_BENT: u8 = 3;

const GUARDS_UNLOCKED: [GuardSpec; 5] = [
    GuardSpec {
        name: "knee_strike",
        crossing: Crossing::Rising,
        kind: GuardKind::Reset,
    },
    GuardSpec {
        name: "foot_strike_knee_bent",
        crossing: Crossing::Falling,
        kind: GuardKind::Terminal(FALL_KNEE_BENT),
    },
    FALL_GUARDS[0],
    FALL_GUARDS[1],
    FALL_GUARDS[2],
];

const GUARDS_LOCKED: [GuardSpec; 4] = [
    GuardSpec {
        name: "heel_strike",
        crossing: Crossing::Falling,
        kind: GuardKind::Reset,
    },
    FALL_GUARDS[0],
    FALL_GUARDS[1],
    FALL_GUARDS[2],
];

const STATE_NAMES: [&str; 6] = [
    "stance",
    "hip",
    "knee",
    "stance_rate",
    "hip_rate",
    "knee_rate",
];
const SECTION_NAMES: [&str; 3] = ["stance", "stance_rate", "hip_rate"];

static PARAMS: [ParamSpec; 10] = [
    ParamSpec {
        name: "slope",
        unit: "rad",
        default: 0.0504,
        description: "slope angle γ (Hsu Chen 2007: 0.0504)",
    },
    ParamSpec {
        name: "a1",
        unit: "L",
        default: 0.375,
        description: "foot to shank mass (Hsu Chen 2007: 0.375)",
    },
    ParamSpec {
        name: "b1",
        unit: "L",
        default: 0.125,
        description: "shank mass to knee (Hsu Chen 2007: 0.125)",
    },
    ParamSpec {
        name: "a2",
        unit: "L",
        default: 0.175,
        description: "knee to thigh mass (Hsu Chen 2007: 0.175)",
    },
    ParamSpec {
        name: "b2",
        unit: "L",
        default: 0.325,
        description: "thigh mass to hip (Hsu Chen 2007: 0.325)",
    },
    ParamSpec {
        name: "hip_mass",
        unit: "M",
        default: 0.5,
        description: "hip point mass m_H (Hsu Chen 2007: 0.5)",
    },
    ParamSpec {
        name: "thigh_mass",
        unit: "M",
        default: 0.5,
        description: "thigh point mass m_t (Hsu Chen 2007: 0.5)",
    },
    ParamSpec {
        name: "shank_mass",
        unit: "M",
        default: 0.05,
        description: "shank point mass m_s (Hsu Chen 2007: 0.05)",
    },
    ParamSpec {
        name: "gravity",
        unit: "L/T^2",
        default: 9.8,
        description: "gravitational acceleration g (Hsu Chen 2007: 9.8)",
    },
    ParamSpec {
        name: "max_stride_time",
        unit: "T",
        default: 5.0,
        description: "stride time budget; a longer stride counts as a fall",
    },
];

/// The registry entry of the kneed walker.
pub static INFO: ModelInfo = ModelInfo {
    name: "kneed",
    description: "Hsu Chen 2007 kneed walker (point feet): unlocked 3-link swing, knee strike, \
                  locked 2-link swing, heel strike; SOA chain with a pseudo-joint knee",
    params: &PARAMS,
    state_names: &STATE_NAMES,
    section_names: &SECTION_NAMES,
    build_from: |v| {
        Ok(Box::new(Kneed::new(KneedParams {
            slope: v[0],
            a1: v[1],
            b1: v[2],
            a2: v[3],
            b2: v[4],
            hip_mass: v[5],
            thigh_mass: v[6],
            shank_mass: v[7],
            gravity: v[8],
            max_stride_time: v[9],
        })?))
    },
};

/// Parameters of the kneed walker. [`Default`] is Hsu Chen's (2007) preset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KneedParams {
    /// Slope angle γ (rad), in (−π/2, π/2).
    pub slope: f64,
    /// Foot to shank mass, `a₁ ≥ 0`.
    pub a1: f64,
    /// Shank mass to knee, `b₁ ≥ 0` (`a₁ + b₁ > 0`).
    pub b1: f64,
    /// Knee to thigh mass, `a₂ ≥ 0`.
    pub a2: f64,
    /// Thigh mass to hip, `b₂ > 0`.
    pub b2: f64,
    /// Hip mass `m_H ≥ 0`.
    pub hip_mass: f64,
    /// Thigh mass `m_t > 0`.
    pub thigh_mass: f64,
    /// Shank mass `m_s > 0`.
    pub shank_mass: f64,
    /// Gravity `g > 0`.
    pub gravity: f64,
    /// Stride time budget `> 0`.
    pub max_stride_time: f64,
}

impl Default for KneedParams {
    /// Hsu Chen (2007), shared REFERENCES §4.
    fn default() -> Self {
        Self {
            slope: 0.0504,
            a1: 0.375,
            b1: 0.125,
            a2: 0.175,
            b2: 0.325,
            hip_mass: 0.5,
            thigh_mass: 0.5,
            shank_mass: 0.05,
            gravity: 9.8,
            max_stride_time: 5.0,
        }
    }
}

/// The kneed walker (immutable model). See the module docs.
#[derive(Clone, Debug)]
pub struct Kneed {
    p: KneedParams,
    ls: f64,
    lt: f64,
    chain: Chain,
    floating: Chain,
    /// stance shank, stance knee, swing thigh, swing shank (for the stance-knee torque)
    report: Chain,
}

impl Kneed {
    /// Builds the model; rejects non-finite or out-of-range parameters.
    pub fn new(p: KneedParams) -> Result<Self, WalkerError> {
        check_slope(p.slope)?;
        let nonneg = |n, v| check_closed_open(n, v, 0.0, f64::INFINITY, "finite and >= 0");
        nonneg("a1", p.a1)?;
        check_positive("b1", p.b1)?;
        nonneg("a2", p.a2)?;
        check_positive("b2", p.b2)?;
        nonneg("hip_mass", p.hip_mass)?;
        check_positive("thigh_mass", p.thigh_mass)?;
        check_positive("shank_mass", p.shank_mass)?;
        check_positive("gravity", p.gravity)?;
        check_positive("max_stride_time", p.max_stride_time)?;
        let (ls, lt) = (p.a1 + p.b1, p.a2 + p.b2);
        let l = ls + lt;
        let (ms, mt, mh) = (p.shank_mass, p.thigh_mass, p.hip_mass);
        let stance = point_mass_link(l, &[(ms, p.a1), (mt, ls + p.a2), (mh, l)]);
        let thigh = point_mass_link(-lt, &[(mt, -p.b2)]);
        let shank = point_mass_link(-ls, &[(ms, -p.b1)]);
        let chain = ChainBuilder::new()
            .gravity(p.gravity)
            .slope(p.slope)
            .revolute(stance)
            .revolute(thigh)
            .revolute(shank)
            .build()
            .map_err(soa_param_error)?;
        let floating = floating_chain(&[stance, thigh, shank], p.gravity, p.slope)?;
        let report = ChainBuilder::new()
            .gravity(p.gravity)
            .slope(p.slope)
            .revolute(point_mass_link(ls, &[(ms, p.a1)]))
            .revolute(point_mass_link(lt, &[(mt, p.a2), (mh, lt)]))
            .revolute(thigh)
            .revolute(shank)
            .build()
            .map_err(soa_param_error)?;
        Ok(Self {
            p,
            ls,
            lt,
            chain,
            floating,
            report,
        })
    }

    /// The parameters the model was built from.
    pub fn params(&self) -> &KneedParams {
        &self.p
    }

    /// Leg length `L = a₁ + b₁ + a₂ + b₂`.
    pub fn leg_length(&self) -> f64 {
        self.ls + self.lt
    }

    /// The kernel chain (stance leg, swing thigh, swing shank) rooted at the stance foot.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// Swing-foot position `[y, z]` relative to the stance foot.
    pub fn swing_foot(&self, x: &[f64]) -> [f64; 2] {
        let l = self.ls + self.lt;
        let (s1, c1) = x[0].sin_cos();
        let (st, ct) = (x[0] + x[1]).sin_cos();
        let (ss, cs) = (x[0] + x[1] + x[2]).sin_cos();
        [
            -l * s1 + self.lt * st + self.ls * ss,
            l * c1 - self.lt * ct - self.ls * cs,
        ]
    }

    /// Accelerations in `mode` and the swing-knee locking torque (kernel sign, `+q₃` sense;
    /// 0 in mode 0).
    pub fn accelerations(&self, mode: usize, x: &[f64]) -> ([f64; 3], f64) {
        let mut qdd = [0.0; 3];
        let mut lock = [0.0; 3];
        let ok = with_workspace(&self.chain, |ws| {
            if mode == UNLOCKED {
                pdw_soa::aba(
                    &self.chain,
                    ws,
                    &x[0..3],
                    &x[3..6],
                    &[0.0; 3],
                    None,
                    &mut qdd,
                )
            } else {
                pdw_soa::pseudo_joint_dynamics(
                    &self.chain,
                    ws,
                    &x[0..3],
                    &x[3..6],
                    &[0.0; 3],
                    &[2],
                    None,
                    &mut qdd,
                    &mut lock,
                )
            }
            .is_ok()
        });
        if ok {
            (qdd, lock[2])
        } else {
            ([f64::NAN; 3], f64::NAN)
        }
    }

    /// Total mechanical energy (potential zero at the stance foot).
    pub fn energy(&self, x: &[f64]) -> f64 {
        chain_energy(&self.chain, &x[0..3], &x[3..6])
    }

    /// The knee strike (plastic knee lock) at `x`: post-impact rates into `qd_post` and the
    /// locking angular impulse (kernel sign, `+q₃` sense).
    pub fn knee_strike(&self, x: &[f64], qd_post: &mut [f64; 3]) -> f64 {
        let mut imp = [0.0];
        let ok = with_workspace(&self.chain, |ws| {
            pdw_soa::joint_lock_impact(&self.chain, ws, &x[0..3], &x[3..6], &[2], qd_post, &mut imp)
                .is_ok()
        });
        if ok {
            imp[0]
        } else {
            qd_post.iter_mut().for_each(|v| *v = f64::NAN);
            f64::NAN
        }
    }

    /// The heel strike (knee held locked, old stance foot free) at the pre-impact state `x`:
    /// floating-chain rates `(ẏ, ż, q̇₁, q̇₂, q̇₃)` into `qd_post`, before the leg swap.
    pub fn heel_strike(&self, x: &[f64], qd_post: &mut [f64; 5]) -> HeelStrike {
        let q = [0.0, 0.0, x[0], x[1], x[2]];
        let qd = [0.0, 0.0, x[3], x[4], x[5]];
        floating_impact(&self.floating, &q, &qd, &[4], qd_post)
    }

    /// Ground reaction at the stance foot and knee-lock torques (stance knee always; swing
    /// knee in mode 1), positive towards flexion.
    pub fn constraint_forces(&self, mode: usize, x: &[f64]) -> ConstraintForces {
        // report chain: (stance shank, stance knee = 0, thigh, shank)
        let q = [x[0], 0.0, x[1], x[2]];
        let qd = [x[3], 0.0, x[4], x[5]];
        let mut qdd = [0.0; 4];
        let mut lock = [0.0; 4];
        let locked: &[usize] = if mode == UNLOCKED { &[1] } else { &[1, 3] };
        let r = with_workspace(&self.report, |ws| {
            pdw_soa::pseudo_joint_dynamics(
                &self.report,
                ws,
                &q,
                &qd,
                &[0.0; 4],
                locked,
                None,
                &mut qdd,
                &mut lock,
            )
            .map(|_| ws.joint_forces()[0])
        });
        match r {
            Ok(f) => {
                let swing = (mode == LOCKED).then_some(-lock[3]);
                ConstraintForces::from_ground(f, [Some(lock[1]), swing])
            }
            Err(_) => ConstraintForces::from_ground([f64::NAN; 3], [None, None]),
        }
    }

    /// Validity flags at one state (see [`StepFlags`]); in mode 0 a hyper-extended knee
    /// (`q₃ > 0`) also raises `knee_unlocks` (the stop would have to act).
    pub fn check_state(&self, mode: usize, x: &[f64]) -> StepFlags {
        let cf = self.constraint_forces(mode, x);
        let mut f = StepFlags::from_state(&cf, self.swing_foot(x), self.leg_length());
        if mode == UNLOCKED && x[2] > 1e-9 {
            f.knee_unlocks = true;
        }
        f
    }
}

/// A link carrying point masses `(m, d)` at `(0, d)` along its axis, length `len` along `z`.
pub(crate) fn point_mass_link(len: f64, masses: &[(f64, f64)]) -> Link {
    let m: f64 = masses.iter().map(|(m, _)| m).sum();
    let c = masses.iter().map(|(m, d)| m * d).sum::<f64>() / m;
    let inertia = masses.iter().map(|(m, d)| m * (d - c) * (d - c)).sum();
    Link {
        to_next: [0.0, len],
        com: [0.0, c],
        mass: m,
        inertia,
    }
}

impl HybridSystem for Kneed {
    fn dim(&self) -> usize {
        6
    }
    fn n_modes(&self) -> usize {
        2
    }
    fn guards(&self, mode: usize) -> &[GuardSpec] {
        if mode == UNLOCKED {
            &GUARDS_UNLOCKED
        } else {
            &GUARDS_LOCKED
        }
    }
    fn flow(&self, _ws: &mut Scratch, mode: usize, x: &[f64], dx: &mut [f64]) {
        let (qdd, _) = self.accelerations(mode, x);
        dx[0..3].copy_from_slice(&x[3..6]);
        dx[3..6].copy_from_slice(&qdd);
    }
    fn guard(&self, _ws: &mut Scratch, mode: usize, k: usize, x: &[f64]) -> f64 {
        // index into the common tail (falls): mode 0 has two leading guards, mode 1 one
        let tail = if mode == UNLOCKED {
            k.checked_sub(2)
        } else {
            k.checked_sub(1)
        };
        match (mode, k, tail) {
            (UNLOCKED, 0, _) => x[2],
            (_, _, None) => self.swing_foot(x)[1],
            (_, _, Some(0)) => x[3],
            (_, _, Some(1)) => x[0] - FRAC_PI_2,
            _ => x[0] + FRAC_PI_2,
        }
    }
    fn admissible(&self, mode: usize, k: usize, x: &[f64]) -> bool {
        match (mode, k) {
            (UNLOCKED, 0) => true,
            (UNLOCKED, 1) => self.swing_foot(x)[0] > 0.0,
            (_, 0) => self.swing_foot(x)[0] > 0.0 && (2.0 * x[0] + x[1]).abs() < x[1].abs(),
            (UNLOCKED, 2) | (_, 1) => x[0] > self.p.slope,
            _ => true,
        }
    }
    fn reset(
        &self,
        _ws: &mut Scratch,
        mode: usize,
        _k: usize,
        x: &[f64],
        out: &mut [f64],
    ) -> usize {
        if mode == UNLOCKED {
            let mut v = [0.0; 3];
            self.knee_strike(x, &mut v);
            out[0] = x[0];
            out[1] = x[1];
            out[2] = 0.0;
            out[3] = v[0];
            out[4] = v[1];
            out[5] = 0.0;
            LOCKED
        } else {
            let mut v = [0.0; 5];
            self.heel_strike(x, &mut v);
            out[0] = x[0] + x[1] + x[2];
            out[1] = -(x[1] + x[2]);
            out[2] = 0.0;
            out[3] = v[2] + v[3] + v[4];
            out[4] = -(v[3] + v[4]);
            out[5] = 0.0;
            UNLOCKED
        }
    }
}

impl Section for Kneed {
    fn section_dim(&self) -> usize {
        3
    }
    fn section_names(&self) -> &[&'static str] {
        &SECTION_NAMES
    }
    fn section_mode(&self) -> usize {
        UNLOCKED
    }
    fn section_guard(&self) -> (usize, usize) {
        (LOCKED, HEEL_STRIKE)
    }
    fn lift(&self, s: &[f64], x: &mut [f64]) {
        x[0] = s[0];
        x[1] = -2.0 * s[0];
        x[2] = 0.0;
        x[3] = s[1];
        x[4] = s[2];
        x[5] = 0.0;
    }
    fn project(&self, x: &[f64], s: &mut [f64]) {
        s[0] = x[0];
        s[1] = x[3];
        s[2] = x[4];
    }
    fn max_stride_time(&self) -> f64 {
        self.p.max_stride_time
    }
}

impl Walker for Kneed {
    fn pose(&self, x: &[f64]) -> Option<Pose> {
        let l = self.ls + self.lt;
        Some(crate::registry::chain_pose(
            &x[0..3],
            &[l, -self.lt, -self.ls],
        ))
    }
    fn constraint_forces(&self, mode: usize, x: &[f64]) -> Option<ConstraintForces> {
        Some(Self::constraint_forces(self, mode, x))
    }
    fn step_flags(&self, mode: usize, x: &[f64]) -> Option<StepFlags> {
        Some(self.check_state(mode, x))
    }
    fn name(&self) -> &'static str {
        "kneed"
    }
    fn state_names(&self) -> &'static [&'static str] {
        &STATE_NAMES
    }
    fn param_values(&self) -> Vec<(&'static str, f64)> {
        let p = &self.p;
        vec![
            ("slope", p.slope),
            ("a1", p.a1),
            ("b1", p.b1),
            ("a2", p.a2),
            ("b2", p.b2),
            ("hip_mass", p.hip_mass),
            ("thigh_mass", p.thigh_mass),
            ("shank_mass", p.shank_mass),
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
            FALL_KNEE_BENT => "swing foot struck the ground before the knee locked",
            _ => "unknown fall",
        }
    }
    fn gait_guesses(&self) -> Vec<GaitGuess> {
        vec![GaitGuess {
            gait: "stable",
            section: hsu_chen_section(self.p.slope).to_vec(),
            source: "Hsu Chen 2007 published fixed point (forward Euler, dt = 1e-3), converted \
                     from angles from the vertical to angles from the slope normal",
        }]
    }
}

/// Hsu Chen's (2007) published post-heel-strike state `q = (0.1877, −0.2884, −0.2884)`,
/// `q̇ = (−1.1014, −0.0399, −0.0399)` (absolute angles from the vertical) in this model's
/// reduced section coordinates `(q₁, q̇₁, q̇₂)` for slope `γ`.
pub fn hsu_chen_section(gamma: f64) -> [f64; 3] {
    [0.1877 + gamma, -1.1014, -0.0399 + 1.1014]
}
