//! The seed thesis' walker with the thesis' own constraint handling (seed ch. 3.4–3.5 and
//! ch. 4): a PI-controlled knee latch and a compliant (PI) ground during a finite double
//! support, kept for comparison with the exact model. It is not one of the models
//! (`pdw-sweep models`): a stiff model whose failures are part of the point, used by the
//! `economy` experiment ("Model economy" in experiments/README.md) and checked by the tests
//! crate (`tests/tests/seed5_pi.rs`). The exact model — pseudo-joint knees, impulsive heel
//! strike, the switch rule — is the `seed5` preset of the chain walker
//! ([`pdw_walkers::presets::seed5`], `models/seed5.toml`).

use pdw_hybrid::{Crossing, FallKind, GuardKind, GuardSpec, HybridSystem, Scratch, Section};
use pdw_soa::Workspace;
use pdw_walkers::{ChainWalker, WalkerError};

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

/// Mode of [`PiLatchWalker`]: single support.
pub const COMPLIANT_SINGLE: usize = 0;
/// Mode of [`PiLatchWalker`]: double support (swing foot held by the compliant ground).
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
        kind: GuardKind::Terminal(FallKind::Forward),
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
        kind: GuardKind::Terminal(FallKind::Forward),
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
pub struct PiLatchWalker {
    model: ChainWalker,
    gains: PiGains,
}

/// Scratch of [`PiLatchWalker`]: the kernel workspace and the exact model's scratch.
struct CompliantScratch {
    ws: Workspace,
    inner: Scratch,
}

impl PiLatchWalker {
    /// Builds the model on a two-segment chain walker (the `seed5` preset or a variant of it);
    /// gains must be finite and ≥ 0.
    pub fn new(model: ChainWalker, gains: PiGains) -> Result<Self, WalkerError> {
        if model.segments() != 2 {
            return Err(WalkerError::InvalidSpec {
                source_name: model.spec().name.clone(),
                field: "segments".into(),
                value: format!("{} segments", model.segments()),
                rule: "the PI-latch model needs legs of two segments (shank, thigh)".into(),
            });
        }
        let nn = |name, value: f64| {
            if value.is_finite() && value >= 0.0 {
                Ok(value)
            } else {
                Err(WalkerError::InvalidParam {
                    name,
                    value,
                    allowed: "finite and >= 0",
                })
            }
        };
        nn("knee_kp", gains.knee_kp)?;
        nn("knee_ki", gains.knee_ki)?;
        nn("knee_kd", gains.knee_kd)?;
        nn("ground_kp", gains.ground_kp)?;
        nn("ground_ki", gains.ground_ki)?;
        nn("ground_kd", gains.ground_kd)?;
        Ok(Self { model, gains })
    }

    /// The underlying exact model (geometry and masses).
    pub fn model(&self) -> &ChainWalker {
        &self.model
    }

    fn scratch<'a>(&self, ws: &'a mut Scratch) -> &'a mut CompliantScratch {
        let chain = self.model.chain();
        ws.get_or_init(
            || CompliantScratch {
                ws: Workspace::new(chain),
                inner: Scratch::new(),
            },
            |s: &CompliantScratch| s.ws.dof() == chain.dof(),
        )
    }

    /// Joint accelerations, the knee torques applied and (mode 1) the ground reaction on the
    /// swing foot `[R_y, R_z]` and the stance-foot base reaction.
    pub fn accelerations(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
    ) -> ([f64; 4], [f64; 4], [f64; 2], [f64; 3]) {
        let m = &self.model;
        let g = &self.gains;
        let sc = self.scratch(ws);
        let (mut qdd0, mut lock) = ([0.0; 4], [0.0; 4]);
        m.dynamics(&mut sc.inner, m.locked_mode(), x, &mut qdd0, &mut lock);
        let mut tau = [0.0; 4];
        for (k, ik) in [(1usize, 8usize), (3, 9)] {
            tau[k] = lock[k] - g.knee_kp * x[k] - g.knee_ki * x[ik] - g.knee_kd * x[4 + k];
        }
        let mut qdd = [0.0; 4];
        let chain = m.chain();
        let ws = &mut sc.ws;
        let r = (|| -> Result<([f64; 2], [f64; 3]), pdw_soa::SoaError> {
            if mode == COMPLIANT_SINGLE {
                pdw_soa::aba(chain, ws, &x[0..4], &x[4..8], &tau, None, &mut qdd)?;
                let f0 = pdw_soa::base_reaction(chain, ws, &x[0..4], &x[4..8], &qdd, None)?;
                Ok(([0.0; 2], f0))
            } else {
                let cc =
                    pdw_soa::closed_chain_dynamics(chain, ws, &x[0..4], &x[4..8], &tau, &mut qdd)?;
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
        })();
        match r {
            Ok((rt, f0)) => (qdd, tau, rt, f0),
            Err(_) => ([f64::NAN; 4], [f64::NAN; 4], [f64::NAN; 2], [f64::NAN; 3]),
        }
    }

    fn chords(&self, x: &[f64]) -> (f64, f64, [f64; 2]) {
        let m = &self.model;
        let seg = &m.resolved().segments;
        let (ls, lt) = (seg[0][0], seg[1][0]);
        let (s1, c1) = x[0].sin_cos();
        let (s2, c2) = (x[0] + x[1]).sin_cos();
        let hip = [-ls * s1 - lt * s2, ls * c1 + lt * c2];
        let foot = m.swing_foot(x);
        let a_s = (-hip[0]).atan2(hip[1]);
        let a_w = (foot[0] - hip[0]).atan2(hip[1] - foot[1]);
        (a_s, a_w, hip)
    }
}

pdw_hybrid::integrate_concretely!(PiLatchWalker);
impl HybridSystem for PiLatchWalker {
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
    fn flow(&self, ws: &mut Scratch, mode: usize, x: &[f64], dx: &mut [f64]) {
        let (qdd, _, _, _) = self.accelerations(ws, mode, x);
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
    fn guard(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64]) -> f64 {
        match (mode, k) {
            (COMPLIANT_SINGLE, 0) => self.model.swing_foot(x)[1],
            (_, 0) => self.accelerations(ws, mode, x).3[2],
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
            self.model.swap(&x[0..4], &x[4..8], &mut y);
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

impl Section for PiLatchWalker {
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
        self.model.max_stride_time()
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
