//! The seed thesis' planar kneed biped (Table 3.1; ch. 3) on the planar SOA kernel.
//!
//! Five revolute joints in the thesis: stance foot, stance knee, hip, swing knee, swing foot.
//! Shanks 2 kg, thighs 3 kg, every segment 2 m, centre of mass at mid-segment, point masses
//! (the thesis' link inertia is `I_k = m_k |l_kc|²` about the joint, eq. 3.15–3.16), g = 9.81,
//! no hip mass (the [`Seed5Params::hip_mass`] parameter, default 0, is ours, for gait
//! searches). The thesis gives no slope value; the default 0.05 rad is ours.
//!
//! # The fifth joint
//! The swing-foot joint has no link beyond it: it carries no inertia (its column of the mass
//! matrix is zero, so 𝓜 would be singular) and a point foot's angle does not enter the
//! dynamics. It is therefore **dropped from the dynamic chain**: the chain has four joints and
//! its kinematic tip is the swing foot (tip offset = the swing shank). When the swing foot is on
//! the ground the thesis' fifth angle is the closing angle `q₅ = −(q₁ + q₂ + q₃ + q₄)` (the
//! ground's orientation seen from the swing shank); [`Seed5::fifth_joint_angle`] returns it.
//!
//! # Frame, coordinates and signs
//! As for [`crate::compass`]: slope frame with `y` downhill, `z` up, angles positive from `+y`
//! to `+z`. State `x = (q₁, q₂, q₃, q₄, q̇₁, q̇₂, q̇₃, q̇₄)`:
//! - `q₁` stance shank from the slope normal (positive: stance foot ahead of the knee),
//! - `q₂` stance knee (thigh relative to shank; **flexion is `q₂ > 0`**),
//! - `q₃` hip (swing thigh relative to stance thigh),
//! - `q₄` swing knee (shank relative to thigh; **flexion is `q₄ < 0`**).
//!
//! The stance knee is always a locked pseudo joint (seed §3.4): `q₂ = q̇₂ = 0`.
//!
//! # Variants and modes
//! - [`Seed5Variant::LockedKnees`] (default; the thesis' §5.2): both knees locked for the whole
//!   step — mode 1 only. Note that with straight legs the swing foot dips below the ground
//!   before the feet pass (as for the compass gait; not flagged) and may after (flagged).
//! - [`Seed5Variant::FreeSwingKnee`]: mode 0 (swing knee free) until the knee straightens
//!   (knee strike, plastic, [`pdw_soa::joint_lock_impact`]), then mode 1 until heel strike.
//!
//! Mode 0 uses [`pdw_soa::pseudo_joint_dynamics`] with joint 1 locked, mode 1 with joints 1
//! and 3 locked.
//!
//! # Guards
//! Mode 0: 0 `knee_strike` (`q₄` rising through 0, reset → mode 1); 1 `foot_strike_knee_bent`
//! (terminal, [`FALL_KNEE_BENT`]); 2–4 falls. Mode 1: 0 `heel_strike` (swing-foot height
//! falling through 0, swing foot ahead, on the heel-strike factor `|2q₁ + q₃| < |q₃|`), 1–3 falls
//! (`stance_reverses`: `q̇₁` rising through 0 with `q₁ > γ`; hip on the ground behind/ahead).
//!
//! # Heel strike and switch rule (seed eq. 3.29–3.32)
//! Instantaneous double support: plastic impact at the swing foot with both knees held locked
//! and the old stance foot free (kernel [`pdw_soa::tip_impact`] on the floating chain
//! `(P_y, P_z, q₁…q₄)`), then the switch rule. The thesis' `T` reverses and negates the five
//! joint angles; with `q₅` the closing angle this is, on our four joints,
//! `q' = (q₁ + q₂ + q₃ + q₄, −q₄, −q₃, −q₂)` and the same for the rates (the new stance shank
//! is the old swing shank, whose absolute rate is `q̇₁ + q̇₂ + q̇₃ + q̇₄`). The thesis' `T_c`
//! (eq. 3.31–3.32) re-expresses the link coordinates; here the chain is rebuilt implicitly
//! because both legs are identical. The thesis switches when the old stance foot's normal
//! force reaches zero after a phase of closed-chain double support; the plastic impulse is the
//! limit of that phase as its duration tends to zero (the opt-in [`crate::seed5::Seed5Compliant`]
//! model keeps the thesis' finite double support).
//!
//! # Section
//! Just after heel strike (mode 0 for `FreeSwingKnee`, mode 1 for `LockedKnees`):
//! `q = (s₀, 0, −2s₀, 0)`, `q̇ = (s₁, 0, s₂, 0)`; reduced coordinates `(q₁, q̇₁, q̇₃)`
//! (`"stance"`, `"stance_rate"`, `"hip_rate"`).

use crate::compass::{
    chain_energy, check_closed_open, check_positive, check_slope, floating_chain, floating_impact,
    soa_param_error, with_workspace, ConstraintForces, HeelStrike, StepFlags, FALL_GUARDS,
};
use crate::error::WalkerError;
use crate::kneed::point_mass_link;
use crate::registry::{GaitGuess, ModelInfo, ParamSpec, Pose, Walker};
use pdw_hybrid::{Crossing, GuardKind, GuardSpec, HybridSystem, Scratch, Section};
use pdw_soa::{Chain, ChainBuilder};
use std::f64::consts::FRAC_PI_2;

/// Mode: swing knee free (stance knee locked).
pub const SWING_KNEE_FREE: usize = 0;
/// Mode: both knees locked.
pub const KNEES_LOCKED: usize = 1;
/// Guard index (mode 0) of the knee strike.
pub const KNEE_STRIKE: usize = 0;
/// Guard index (mode 1) of the heel strike.
pub const HEEL_STRIKE: usize = 0;
/// Fall code: backward.
pub const FALL_BACKWARD: u8 = 1;
/// Fall code: forward.
pub const FALL_FORWARD: u8 = 2;
/// Fall code: the swing foot struck the ground before the swing knee locked.
pub const FALL_KNEE_BENT: u8 = 3;

const GUARDS_FREE: [GuardSpec; 5] = [
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

const STATE_NAMES: [&str; 8] = [
    "stance",
    "stance_knee",
    "hip",
    "swing_knee",
    "stance_rate",
    "stance_knee_rate",
    "hip_rate",
    "swing_knee_rate",
];
const SECTION_NAMES: [&str; 3] = ["stance", "stance_rate", "hip_rate"];

/// Which knees move during a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Seed5Variant {
    /// Both knees locked for the whole step (the thesis, §5.2).
    #[default]
    LockedKnees,
    /// Swing knee free until a knee strike locks it.
    FreeSwingKnee,
}

static PARAMS: [ParamSpec; 9] = [
    ParamSpec {
        name: "slope",
        unit: "rad",
        default: 0.05,
        description: "slope angle γ (the thesis gives none; 0.05 is ours)",
    },
    ParamSpec {
        name: "shank_mass",
        unit: "kg",
        default: 2.0,
        description: "shank mass, point mass mid-segment (seed Table 3.1: 2 kg)",
    },
    ParamSpec {
        name: "thigh_mass",
        unit: "kg",
        default: 3.0,
        description: "thigh mass, point mass mid-segment (seed Table 3.1: 3 kg)",
    },
    ParamSpec {
        name: "shank_length",
        unit: "m",
        default: 2.0,
        description: "shank length (seed Table 3.1: 2 m)",
    },
    ParamSpec {
        name: "thigh_length",
        unit: "m",
        default: 2.0,
        description: "thigh length (seed Table 3.1: 2 m)",
    },
    ParamSpec {
        name: "hip_mass",
        unit: "kg",
        default: 0.0,
        description: "hip point mass (the thesis has none; an added search parameter)",
    },
    ParamSpec {
        name: "gravity",
        unit: "m/s^2",
        default: 9.81,
        description: "gravitational acceleration (seed Table 3.1: 9.81)",
    },
    ParamSpec {
        name: "free_swing_knee",
        unit: "1",
        default: 0.0,
        description:
            "0: both knees locked all step (seed §5.2); 1: swing knee free until knee strike",
    },
    ParamSpec {
        name: "max_stride_time",
        unit: "s",
        default: 10.0,
        description: "stride time budget; a longer stride counts as a fall",
    },
];

/// The registry entry of the seed walker.
pub static INFO: ModelInfo = ModelInfo {
    name: "seed5",
    description: "the seed thesis' 5-joint kneed biped (Table 3.1): pseudo-joint knees, plastic \
                  heel strike and the switch rule (eq. 3.29-3.32); SI units",
    params: &PARAMS,
    state_names: &STATE_NAMES,
    section_names: &SECTION_NAMES,
    build_from: |v| {
        let variant = if v[7] == 0.0 {
            Seed5Variant::LockedKnees
        } else if v[7] == 1.0 {
            Seed5Variant::FreeSwingKnee
        } else {
            return Err(WalkerError::InvalidParam {
                name: "free_swing_knee",
                value: v[7],
                allowed: "0 (knees locked) or 1 (swing knee free)",
            });
        };
        Ok(Box::new(Seed5::new(Seed5Params {
            slope: v[0],
            shank_mass: v[1],
            thigh_mass: v[2],
            shank_length: v[3],
            thigh_length: v[4],
            hip_mass: v[5],
            gravity: v[6],
            variant,
            max_stride_time: v[8],
        })?))
    },
};

/// Parameters of the seed walker (SI units). [`Default`] is the thesis' Table 3.1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seed5Params {
    /// Slope angle γ (rad), in (−π/2, π/2).
    pub slope: f64,
    /// Shank mass (kg), > 0.
    pub shank_mass: f64,
    /// Thigh mass (kg), > 0.
    pub thigh_mass: f64,
    /// Shank length (m), > 0.
    pub shank_length: f64,
    /// Thigh length (m), > 0.
    pub thigh_length: f64,
    /// Hip point mass (kg), ≥ 0 (0 in the thesis).
    pub hip_mass: f64,
    /// Gravity (m/s²), > 0.
    pub gravity: f64,
    /// Which knees move.
    pub variant: Seed5Variant,
    /// Stride time budget (s), > 0.
    pub max_stride_time: f64,
}

impl Default for Seed5Params {
    /// Seed thesis Table 3.1; slope 0.05 rad (ours).
    fn default() -> Self {
        Self {
            slope: 0.05,
            shank_mass: 2.0,
            thigh_mass: 3.0,
            shank_length: 2.0,
            thigh_length: 2.0,
            hip_mass: 0.0,
            gravity: 9.81,
            variant: Seed5Variant::LockedKnees,
            max_stride_time: 10.0,
        }
    }
}

/// The seed walker (immutable model). See the module docs.
#[derive(Clone, Debug)]
pub struct Seed5 {
    p: Seed5Params,
    chain: Chain,
    floating: Chain,
}

impl Seed5 {
    /// Builds the model; rejects non-finite or out-of-range parameters.
    pub fn new(p: Seed5Params) -> Result<Self, WalkerError> {
        check_slope(p.slope)?;
        check_positive("shank_mass", p.shank_mass)?;
        check_positive("thigh_mass", p.thigh_mass)?;
        check_positive("shank_length", p.shank_length)?;
        check_positive("thigh_length", p.thigh_length)?;
        check_closed_open(
            "hip_mass",
            p.hip_mass,
            0.0,
            f64::INFINITY,
            "finite and >= 0",
        )?;
        check_positive("gravity", p.gravity)?;
        check_positive("max_stride_time", p.max_stride_time)?;
        let (ls, lt) = (p.shank_length, p.thigh_length);
        let (ms, mt) = (p.shank_mass, p.thigh_mass);
        let mut thigh_up = vec![(mt, 0.5 * lt)];
        if p.hip_mass > 0.0 {
            thigh_up.push((p.hip_mass, lt));
        }
        let links = [
            point_mass_link(ls, &[(ms, 0.5 * ls)]),
            point_mass_link(lt, &thigh_up),
            point_mass_link(-lt, &[(mt, -0.5 * lt)]),
            point_mass_link(-ls, &[(ms, -0.5 * ls)]),
        ];
        let mut b = ChainBuilder::new().gravity(p.gravity).slope(p.slope);
        for l in links {
            b = b.revolute(l);
        }
        let chain = b.build().map_err(soa_param_error)?;
        let floating = floating_chain(&links, p.gravity, p.slope)?;
        Ok(Self { p, chain, floating })
    }

    /// The parameters the model was built from.
    pub fn params(&self) -> &Seed5Params {
        &self.p
    }

    /// Leg length (shank + thigh).
    pub fn leg_length(&self) -> f64 {
        self.p.shank_length + self.p.thigh_length
    }

    /// The four-joint kernel chain rooted at the stance foot (tip: the swing foot).
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// The thesis' fifth joint angle when the swing foot is on the ground: the closing angle
    /// `q₅ = −(q₁ + q₂ + q₃ + q₄)`.
    pub fn fifth_joint_angle(&self, x: &[f64]) -> f64 {
        -(x[0] + x[1] + x[2] + x[3])
    }

    /// Swing-foot position `[y, z]` relative to the stance foot (m).
    pub fn swing_foot(&self, x: &[f64]) -> [f64; 2] {
        let (ls, lt) = (self.p.shank_length, self.p.thigh_length);
        let th = [
            x[0],
            x[0] + x[1],
            x[0] + x[1] + x[2],
            x[0] + x[1] + x[2] + x[3],
        ];
        let len = [ls, lt, -lt, -ls];
        let mut r = [0.0; 2];
        for k in 0..4 {
            let (s, c) = th[k].sin_cos();
            r[0] -= len[k] * s;
            r[1] += len[k] * c;
        }
        r
    }

    fn locked_joints(mode: usize) -> &'static [usize] {
        if mode == SWING_KNEE_FREE {
            &[1]
        } else {
            &[1, 3]
        }
    }

    /// Accelerations in `mode` and the locking torques (kernel sign, per joint; 0 where free).
    pub fn accelerations(&self, mode: usize, x: &[f64]) -> ([f64; 4], [f64; 4], [f64; 3]) {
        let mut qdd = [0.0; 4];
        let mut lock = [0.0; 4];
        let r = with_workspace(&self.chain, |ws| {
            pdw_soa::pseudo_joint_dynamics(
                &self.chain,
                ws,
                &x[0..4],
                &x[4..8],
                &[0.0; 4],
                Self::locked_joints(mode),
                None,
                &mut qdd,
                &mut lock,
            )
            .map(|_| ws.joint_forces()[0])
        });
        match r {
            Ok(f) => (qdd, lock, f),
            Err(_) => ([f64::NAN; 4], [f64::NAN; 4], [f64::NAN; 3]),
        }
    }

    /// Total mechanical energy (J), potential zero at the stance foot.
    pub fn energy(&self, x: &[f64]) -> f64 {
        chain_energy(&self.chain, &x[0..4], &x[4..8])
    }

    /// Knee strike: plastic lock of the swing knee (the stance knee held locked), stance foot
    /// pinned. Post-impact rates into `qd_post`; returns the locking impulses
    /// `[stance knee, swing knee]` (kernel sign).
    pub fn knee_strike(&self, x: &[f64], qd_post: &mut [f64; 4]) -> [f64; 2] {
        let mut imp = [0.0; 2];
        let ok = with_workspace(&self.chain, |ws| {
            pdw_soa::joint_lock_impact(
                &self.chain,
                ws,
                &x[0..4],
                &x[4..8],
                &[1, 3],
                qd_post,
                &mut imp,
            )
            .is_ok()
        });
        if !ok {
            qd_post.iter_mut().for_each(|v| *v = f64::NAN);
            return [f64::NAN; 2];
        }
        imp
    }

    /// Heel strike with both knees held locked, old stance foot free: floating rates
    /// `(ẏ, ż, q̇₁…q̇₄)` into `qd_post`, before the switch rule.
    pub fn heel_strike(&self, x: &[f64], qd_post: &mut [f64; 6]) -> HeelStrike {
        let q = [0.0, 0.0, x[0], x[1], x[2], x[3]];
        let qd = [0.0, 0.0, x[4], x[5], x[6], x[7]];
        floating_impact(&self.floating, &q, &qd, &[3, 5], qd_post)
    }

    /// The switch rule (seed eq. 3.29–3.32 on the four dynamic joints): new stance leg = old
    /// swing leg. `q` and `qd` are the post-impact joint angles and rates.
    pub fn switch_rule(q: &[f64], qd: &[f64], out: &mut [f64]) {
        out[0] = q[0] + q[1] + q[2] + q[3];
        out[1] = -q[3];
        out[2] = -q[2];
        out[3] = -q[1];
        out[4] = qd[0] + qd[1] + qd[2] + qd[3];
        out[5] = -qd[3];
        out[6] = -qd[2];
        out[7] = -qd[1];
    }

    /// Ground reaction at the stance foot and knee-lock torques, positive towards flexion
    /// (stance knee: `+τ_lock`; swing knee: `−τ_lock`, since its flexion is `q₄ < 0`).
    pub fn constraint_forces(&self, mode: usize, x: &[f64]) -> ConstraintForces {
        let (_, lock, f) = self.accelerations(mode, x);
        let swing = (mode == KNEES_LOCKED).then_some(-lock[3]);
        ConstraintForces::from_ground(f, [Some(lock[1]), swing])
    }

    /// Validity flags at one state (see [`StepFlags`]); a hyper-extended free swing knee
    /// (`q₄ > 0` in mode 0) also raises `knee_unlocks`.
    pub fn check_state(&self, mode: usize, x: &[f64]) -> StepFlags {
        let cf = self.constraint_forces(mode, x);
        let mut f = StepFlags::from_state(&cf, self.swing_foot(x), self.leg_length());
        if mode == SWING_KNEE_FREE && x[3] > 1e-9 {
            f.knee_unlocks = true;
        }
        f
    }
}

impl HybridSystem for Seed5 {
    fn dim(&self) -> usize {
        8
    }
    fn n_modes(&self) -> usize {
        2
    }
    fn guards(&self, mode: usize) -> &[GuardSpec] {
        if mode == SWING_KNEE_FREE {
            &GUARDS_FREE
        } else {
            &GUARDS_LOCKED
        }
    }
    fn flow(&self, _ws: &mut Scratch, mode: usize, x: &[f64], dx: &mut [f64]) {
        let (qdd, _, _) = self.accelerations(mode, x);
        dx[0..4].copy_from_slice(&x[4..8]);
        dx[4..8].copy_from_slice(&qdd);
    }
    fn guard(&self, _ws: &mut Scratch, mode: usize, k: usize, x: &[f64]) -> f64 {
        let tail = if mode == SWING_KNEE_FREE {
            k.checked_sub(2)
        } else {
            k.checked_sub(1)
        };
        match (mode, k, tail) {
            (SWING_KNEE_FREE, 0, _) => x[3],
            (_, _, None) => self.swing_foot(x)[1],
            (_, _, Some(0)) => x[4],
            (_, _, Some(1)) => x[0] - FRAC_PI_2,
            _ => x[0] + FRAC_PI_2,
        }
    }
    fn admissible(&self, mode: usize, k: usize, x: &[f64]) -> bool {
        match (mode, k) {
            (SWING_KNEE_FREE, 0) => true,
            (SWING_KNEE_FREE, 1) => self.swing_foot(x)[0] > 0.0,
            (_, 0) => self.swing_foot(x)[0] > 0.0 && (2.0 * x[0] + x[2]).abs() < x[2].abs(),
            (SWING_KNEE_FREE, 2) | (_, 1) => x[0] > self.p.slope,
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
        if mode == SWING_KNEE_FREE {
            let mut v = [0.0; 4];
            self.knee_strike(x, &mut v);
            out[0..4].copy_from_slice(&x[0..4]);
            out[3] = 0.0;
            out[4..8].copy_from_slice(&v);
            out[5] = 0.0;
            out[7] = 0.0;
            KNEES_LOCKED
        } else {
            let mut v = [0.0; 6];
            self.heel_strike(x, &mut v);
            let q = [x[0], 0.0, x[2], 0.0];
            let qd = [v[2], 0.0, v[4], 0.0];
            Self::switch_rule(&q, &qd, out);
            self.section_mode()
        }
    }
}

impl Section for Seed5 {
    fn section_dim(&self) -> usize {
        3
    }
    fn section_names(&self) -> &[&'static str] {
        &SECTION_NAMES
    }
    fn section_mode(&self) -> usize {
        match self.p.variant {
            Seed5Variant::LockedKnees => KNEES_LOCKED,
            Seed5Variant::FreeSwingKnee => SWING_KNEE_FREE,
        }
    }
    fn section_guard(&self) -> (usize, usize) {
        (KNEES_LOCKED, HEEL_STRIKE)
    }
    fn lift(&self, s: &[f64], x: &mut [f64]) {
        x[..8].copy_from_slice(&[s[0], 0.0, -2.0 * s[0], 0.0, s[1], 0.0, s[2], 0.0]);
    }
    fn project(&self, x: &[f64], s: &mut [f64]) {
        s[0] = x[0];
        s[1] = x[4];
        s[2] = x[6];
    }
    fn max_stride_time(&self) -> f64 {
        self.p.max_stride_time
    }
}

impl Walker for Seed5 {
    fn pose(&self, x: &[f64]) -> Option<Pose> {
        let (ls, lt) = (self.p.shank_length, self.p.thigh_length);
        Some(crate::registry::chain_pose(&x[0..4], &[ls, lt, -lt, -ls]))
    }
    fn constraint_forces(&self, mode: usize, x: &[f64]) -> Option<ConstraintForces> {
        Some(Self::constraint_forces(self, mode, x))
    }
    fn step_flags(&self, mode: usize, x: &[f64]) -> Option<StepFlags> {
        Some(self.check_state(mode, x))
    }
    fn name(&self) -> &'static str {
        "seed5"
    }
    fn state_names(&self) -> &'static [&'static str] {
        &STATE_NAMES
    }
    fn param_values(&self) -> Vec<(&'static str, f64)> {
        let p = &self.p;
        vec![
            ("slope", p.slope),
            ("shank_mass", p.shank_mass),
            ("thigh_mass", p.thigh_mass),
            ("shank_length", p.shank_length),
            ("thigh_length", p.thigh_length),
            ("hip_mass", p.hip_mass),
            ("gravity", p.gravity),
            (
                "free_swing_knee",
                f64::from(u8::from(p.variant == Seed5Variant::FreeSwingKnee)),
            ),
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
        // Both knees locked: the two period-one gaits found at slope 0.05 rad by a Newton search
        // over a grid of starts (they continue to slopes 0.01..0.12). The thesis gives no gait.
        vec![
            GaitGuess {
                gait: "stable",
                section: vec![0.215124650, -0.570787311, 0.277583131],
                source: "long-period gait of the locked-knee model at slope 0.05, found by this \
                         engine (Newton from a grid of starts); the thesis gives no gait",
            },
            GaitGuess {
                gait: "unstable",
                section: vec![0.205618696, -0.646181471, 0.123497612],
                source: "short-period gait of the locked-knee model at slope 0.05, found by this \
                         engine (Newton from a grid of starts); the thesis gives no gait",
            },
        ]
    }
}

// ---------------------------------------------------------------------------------------------
// The thesis' own constraint handling (ch. 4): PI knee latch and compliant ground. Opt-in,
// for comparison only.
// ---------------------------------------------------------------------------------------------

/// Gains of the thesis' PI controllers (seed ch. 4, Fig. 4.1–4.2). The thesis gives no values;
/// the defaults are ours ("high P compared to I"). The derivative gains are not in the thesis
/// (default 0); they exist to show what the thesis' controllers lack.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PiGains {
    /// Knee latch: proportional (N m/rad), integral (N m/(rad s)), derivative (N m s/rad).
    pub knee_kp: f64,
    pub knee_ki: f64,
    pub knee_kd: f64,
    /// Ground under the touching swing foot: proportional (N/m), integral (N/(m s)),
    /// derivative (N s/m).
    pub ground_kp: f64,
    pub ground_ki: f64,
    pub ground_kd: f64,
}

impl Default for PiGains {
    fn default() -> Self {
        Self {
            knee_kp: 1e4,
            knee_ki: 1e2,
            knee_kd: 0.0,
            ground_kp: 1e5,
            ground_ki: 1e3,
            ground_kd: 0.0,
        }
    }
}

/// Mode of [`Seed5Compliant`]: single support.
pub const COMPLIANT_SINGLE: usize = 0;
/// Mode of [`Seed5Compliant`]: double support (swing foot held by the compliant ground).
pub const COMPLIANT_DOUBLE: usize = 1;

const COMPLIANT_GUARDS_SINGLE: [GuardSpec; 2] = [
    GuardSpec {
        name: "touchdown",
        crossing: Crossing::Falling,
        kind: GuardKind::Reset,
    },
    GuardSpec {
        name: "hip_on_ground",
        crossing: Crossing::Falling,
        kind: GuardKind::Terminal(FALL_FORWARD),
    },
];
const COMPLIANT_GUARDS_DOUBLE: [GuardSpec; 2] = [
    GuardSpec {
        name: "switch",
        crossing: Crossing::Falling,
        kind: GuardKind::Reset,
    },
    GuardSpec {
        name: "hip_on_ground",
        crossing: Crossing::Falling,
        kind: GuardKind::Terminal(FALL_FORWARD),
    },
];

/// The seed walker with the thesis' own constraint handling (seed ch. 3.4–3.5 and ch. 4):
/// **opt-in, for comparison only** — a stiff model whose failures are part of the point.
///
/// - Knees (both, always): joint torque `τ_k = τ_lock,k + τ_PI,k`, where `τ_lock` is the
///   pseudo-joint locking torque of the open chain (kernel `pseudo_joint_dynamics`, eq. 3.23)
///   and `τ_PI = −K_p q_k − K_i ∫q_k − K_d q̇_k` (Fig. 4.1; `K_d = 0` in the thesis). The knees
///   are real joints of the flow: the latch only holds them as well as the controller does.
/// - Single support (mode 0) ends at touchdown: the swing-foot height falls through 0 with the
///   foot ahead of the stance foot and past the legs-passing (leg-chord test
///   `|a_s + a_w| < |a_w − a_s|`). No impulse: the thesis constrains accelerations only, so
///   the foot keeps its touchdown velocity.
/// - Double support (mode 1): the closed-chain constraint force `f_c` of eq. 3.26 (kernel
///   `closed_chain_dynamics`, zero tip acceleration) plus the ground PI force
///   `R = −K_p e − K_i ∫e − K_d ė`, `e = p_tip − p_touchdown` (Fig. 4.2); the flow is the kernel's
///   `aba` with that tip force.
/// - Switch (mode 1 → 0): the old stance foot's normal force falls through 0 (seed §3.5); the
///   switch rule (eq. 3.29–3.32) re-roots the chain at the swing foot, whose residual velocity
///   is dropped (the new base is pinned), and swaps the knee integrators.
///
/// State (dimension 13): `(q₁…q₄, q̇₁…q̇₄, ∫q₂, ∫q₄, ∫e_y, ∫e_z, y_touchdown)`.
/// Section (after a switch, mode 0): all but the last three components (which are 0 there).
#[derive(Clone, Debug)]
pub struct Seed5Compliant {
    model: Seed5,
    gains: PiGains,
}

impl Seed5Compliant {
    /// Builds the model; gains must be finite and ≥ 0, the geometry as [`Seed5::new`].
    pub fn new(p: Seed5Params, gains: PiGains) -> Result<Self, WalkerError> {
        let model = Seed5::new(p)?;
        let nn = |n, v| check_closed_open(n, v, 0.0, f64::INFINITY, "finite and >= 0");
        nn("knee_kp", gains.knee_kp)?;
        nn("knee_ki", gains.knee_ki)?;
        nn("knee_kd", gains.knee_kd)?;
        nn("ground_kp", gains.ground_kp)?;
        nn("ground_ki", gains.ground_ki)?;
        nn("ground_kd", gains.ground_kd)?;
        Ok(Self { model, gains })
    }

    /// The underlying geometry and masses.
    pub fn model(&self) -> &Seed5 {
        &self.model
    }

    /// Joint accelerations, the knee torques applied and (mode 1) the ground reaction on the
    /// swing foot `[R_y, R_z]` and the stance-foot base reaction.
    pub fn accelerations(
        &self,
        mode: usize,
        x: &[f64],
    ) -> ([f64; 4], [f64; 4], [f64; 2], [f64; 3]) {
        let m = &self.model;
        let g = &self.gains;
        let (_, lock, _) = m.accelerations(KNEES_LOCKED, x);
        let mut tau = [0.0; 4];
        for (k, ik) in [(1usize, 8usize), (3, 9)] {
            tau[k] = lock[k] - g.knee_kp * x[k] - g.knee_ki * x[ik] - g.knee_kd * x[4 + k];
        }
        let mut qdd = [0.0; 4];
        let chain = &m.chain;
        let r = with_workspace(
            chain,
            |ws| -> Result<([f64; 2], [f64; 3]), pdw_soa::SoaError> {
                if mode == COMPLIANT_SINGLE {
                    pdw_soa::aba(chain, ws, &x[0..4], &x[4..8], &tau, None, &mut qdd)?;
                    let f0 = pdw_soa::base_reaction(chain, ws, &x[0..4], &x[4..8], &qdd, None)?;
                    Ok(([0.0; 2], f0))
                } else {
                    let cc = pdw_soa::closed_chain_dynamics(
                        chain,
                        ws,
                        &x[0..4],
                        &x[4..8],
                        &tau,
                        &mut qdd,
                    )?;
                    let foot = m.swing_foot(x);
                    let v = pdw_soa::tip_velocity(chain, ws, &x[0..4], &x[4..8])?;
                    let e = [foot[0] - x[12], foot[1]];
                    let rpi = [
                        -g.ground_kp * e[0] - g.ground_ki * x[10] - g.ground_kd * v[1],
                        -g.ground_kp * e[1] - g.ground_ki * x[11] - g.ground_kd * v[2],
                    ];
                    // environment's reaction on the tip: −f_c + R_PI; tip force on it: f_c − R_PI
                    let ft = [0.0, cc.tip_force[0] - rpi[0], cc.tip_force[1] - rpi[1]];
                    pdw_soa::aba(chain, ws, &x[0..4], &x[4..8], &tau, Some(ft), &mut qdd)?;
                    let f0 = pdw_soa::base_reaction(chain, ws, &x[0..4], &x[4..8], &qdd, Some(ft))?;
                    Ok(([-ft[1], -ft[2]], f0))
                }
            },
        );
        match r {
            Ok((rt, f0)) => (qdd, tau, rt, f0),
            Err(_) => ([f64::NAN; 4], [f64::NAN; 4], [f64::NAN; 2], [f64::NAN; 3]),
        }
    }

    fn chords(&self, x: &[f64]) -> (f64, f64, [f64; 2]) {
        let m = &self.model;
        let (ls, lt) = (m.p.shank_length, m.p.thigh_length);
        let (s1, c1) = x[0].sin_cos();
        let (s2, c2) = (x[0] + x[1]).sin_cos();
        let hip = [-ls * s1 - lt * s2, ls * c1 + lt * c2];
        let foot = m.swing_foot(x);
        let a_s = (-hip[0]).atan2(hip[1]);
        let a_w = (foot[0] - hip[0]).atan2(hip[1] - foot[1]);
        (a_s, a_w, hip)
    }
}

impl HybridSystem for Seed5Compliant {
    fn dim(&self) -> usize {
        13
    }
    fn n_modes(&self) -> usize {
        2
    }
    fn guards(&self, mode: usize) -> &[GuardSpec] {
        if mode == COMPLIANT_SINGLE {
            &COMPLIANT_GUARDS_SINGLE
        } else {
            &COMPLIANT_GUARDS_DOUBLE
        }
    }
    fn flow(&self, _ws: &mut Scratch, mode: usize, x: &[f64], dx: &mut [f64]) {
        let (qdd, _, _, _) = self.accelerations(mode, x);
        dx[0..4].copy_from_slice(&x[4..8]);
        dx[4..8].copy_from_slice(&qdd);
        dx[8] = x[1];
        dx[9] = x[3];
        if mode == COMPLIANT_DOUBLE {
            let foot = self.model.swing_foot(x);
            dx[10] = foot[0] - x[12];
            dx[11] = foot[1];
        } else {
            dx[10] = 0.0;
            dx[11] = 0.0;
        }
        dx[12] = 0.0;
    }
    fn guard(&self, _ws: &mut Scratch, mode: usize, k: usize, x: &[f64]) -> f64 {
        match (mode, k) {
            (COMPLIANT_SINGLE, 0) => self.model.swing_foot(x)[1],
            (_, 0) => self.accelerations(mode, x).3[2],
            _ => self.chords(x).2[1],
        }
    }
    fn admissible(&self, mode: usize, k: usize, x: &[f64]) -> bool {
        if (mode, k) == (COMPLIANT_SINGLE, 0) {
            let (a_s, a_w, _) = self.chords(x);
            self.model.swing_foot(x)[0] > 0.0 && (a_s + a_w).abs() < (a_w - a_s).abs()
        } else {
            true
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
        out[..13].copy_from_slice(&x[..13]);
        if mode == COMPLIANT_SINGLE {
            out[10] = 0.0;
            out[11] = 0.0;
            out[12] = self.model.swing_foot(x)[0];
            COMPLIANT_DOUBLE
        } else {
            let mut y = [0.0; 8];
            Seed5::switch_rule(&x[0..4], &x[4..8], &mut y);
            out[..8].copy_from_slice(&y);
            out[8] = -x[9];
            out[9] = -x[8];
            out[10] = 0.0;
            out[11] = 0.0;
            out[12] = 0.0;
            COMPLIANT_SINGLE
        }
    }
}

impl Section for Seed5Compliant {
    fn section_dim(&self) -> usize {
        10
    }
    fn section_names(&self) -> &[&'static str] {
        &COMPLIANT_SECTION_NAMES
    }
    fn section_mode(&self) -> usize {
        COMPLIANT_SINGLE
    }
    fn section_guard(&self) -> (usize, usize) {
        (COMPLIANT_DOUBLE, 0)
    }
    fn lift(&self, s: &[f64], x: &mut [f64]) {
        x[..10].copy_from_slice(&s[..10]);
        x[10] = 0.0;
        x[11] = 0.0;
        x[12] = 0.0;
    }
    fn project(&self, x: &[f64], s: &mut [f64]) {
        s[..10].copy_from_slice(&x[..10]);
    }
    fn max_stride_time(&self) -> f64 {
        self.model.p.max_stride_time
    }
}

const COMPLIANT_SECTION_NAMES: [&str; 10] = [
    "stance",
    "stance_knee",
    "hip",
    "swing_knee",
    "stance_rate",
    "stance_knee_rate",
    "hip_rate",
    "swing_knee_rate",
    "stance_knee_integral",
    "swing_knee_integral",
];
