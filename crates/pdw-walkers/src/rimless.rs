//! The rimless wheel (Coleman; Tedrake, *Underactuated Robotics* ch. 4): a point mass at the hub
//! of `N` massless spokes of length `l`, rolling down a slope `γ` from spoke to spoke.
//!
//! # Coordinates and signs
//! State `x = (θ, θ̇)`: `θ` is the stance spoke's angle from the slope normal, positive when the
//! hub is downhill of the contact point (the rolling direction); `θ̇ > 0` rolls forward. With
//! the half inter-spoke angle `α = π/N`, a step runs from `θ = −α` (the previous spoke just
//! left the ground) to `θ = +α` (the next spoke touches down).
//!
//! # Flow
//! An inverted pendulum about the contact point; the hub is vertically above it at `θ = −γ`:
//! `θ̈ = (g/l) sin(θ + γ)`. Energy per unit mass `E = ½ l² θ̇² + g l cos(θ + γ)` is conserved.
//!
//! # Spoke impact (guard 0) and reset
//! Rising crossing of `θ − α`. Plastic impact at the new contact, angular momentum about it
//! conserved: the hub velocity (perpendicular to the old spoke) keeps only its component
//! perpendicular to the new spoke, which is at angle `2α` from the old one, so
//! `θ̇⁺ = cos 2α · θ̇⁻`, and `θ⁺ = θ⁻ − 2α` (`= −α` on the guard). The kinetic energy lost is
//! `½ l² θ̇⁻² (1 − cos² 2α)`.
//!
//! # Step down (random step heights; Schwab & Wisse 2001, Hobbelen & Wisse 2007)
//! With `step_down = h ≠ 0` the next foothold lies `h` below the contact point along the slope
//! normal (a step down positive), on a line parallel to the slope. The next spoke's tip is at
//! height `l (cos θ − cos(θ − 2α)) = −2 l sin α sin(θ − α)`, so it lands at
//! `θ⁻ = α + asin(h / (2 l sin α))` (guard `θ − θ⁻`; `|h| < 2 l sin α`, the spoke's reach). The
//! spokes stay `2α` apart, so the impact map is unchanged: `θ⁺ = θ⁻ − 2α`,
//! `θ̇⁺ = cos 2α · θ̇⁻` (angular momentum about the new contact). The flow sees only angles, so
//! nothing shifts between steps; the lift of the model with `step_down = h` starts the next step
//! at `θ⁺ = θ⁻ − 2α` of that `h`. Closed-form step map from `θ⁺` (previous height) to `θ⁻`
//! (this one): `ω' = cos 2α · √(ω² + 2 (g/l)(cos(θ⁺ + γ) − cos(θ⁻ + γ)))`. Guard 2 stays
//! `θ + α` (a start rolling backwards; guard 1 ends every walking stride that turns back).
//!
//! # Section
//! Just after a spoke impact, reduced coordinate `θ̇` (the lift sets `θ = −α`, or `θ⁺` on a
//! step). Return map
//! (Coleman; Tedrake ch. 4): `ω' = cos 2α · √(ω² + 4 (g/l) sin α sin γ)`.
//!
//! # Stopping (terminal guards)
//! [`FallKind::RollsBack`]: the wheel does not reach the next spoke — `θ̇` falls through zero (guard 1), or
//! the hub moves back past the previous spoke, `θ = −α` falling (guard 2, for a start with
//! `θ̇ ≤ 0`). On a slope too shallow for the rolling gait (`ω* ≤ ω₁`), every stride ends this
//! way: the caller sees the wheel come to rest (rocking between two spokes, then standing).
//!
//! # Ground reaction (per unit mass)
//! The model has no mass parameter: forces are per unit hub mass (N/kg = m/s²), impulses per
//! unit mass (m/s), energies in J/kg. In the slope frame of [`Walker::pose`] (`x` downhill along
//! the slope, `y` along its normal, stance foot at the origin) the hub is at
//! `l e` with `e = (sin θ, cos θ)`, and gravity is `g (sin γ, −cos γ)`. The wheel is rigid and
//! massless, so the moments about the hub of the forces on it vanish: the ground's force on
//! the stance foot acts along the stance spoke, `F = S e`, and reaches the hub unchanged.
//! Newton's law for the hub along the spoke — its acceleration there is the centripetal
//! `−l θ̇²` — gives `−l θ̇² = S − g cos(θ + γ)`, i.e. the axial spoke force
//! `S = g cos(θ + γ) − l θ̇²` (per unit mass); across the spoke it gives the flow above.
//! The ground reaction is then normal `S cos θ`, tangential (downhill) `S sin θ`, and the
//! friction it needs `|tan θ|`. Because `|θ| ≤ α < π/2`, the normal force has the sign of `S`:
//! fast wheels on steep slopes, where `l θ̇² > g cos(θ + γ)` before the next spoke lands, would
//! need a spoke that pulls the ground (flagged, [`StepFlags::normal_force_negative`]).
//!
//! # Spoke-impact impulses
//! With the old spoke at `θ⁻` and the new one at `θ' = θ⁻ − 2α`, the massless new spoke carries
//! only an axial impulse, along `e' = (sin θ', cos θ')`; it removes the hub velocity
//! `v⁻ = l θ̇⁻ (cos θ⁻, −sin θ⁻)`'s component along `e'`, `v⁻·e' = −l θ̇⁻ sin 2α`, so the
//! impulse per unit mass is `Λ = l θ̇⁻ sin 2α · e'` (normal `Λ cos θ'`, pushing for a rolling
//! wheel; tangential `Λ sin θ'`) and the energy lost is `½ l² θ̇⁻² sin² 2α` (the reset above).
//! After the impact the wheel turns about the new contact at `θ̇⁺`, so the old contact point
//! leaves the slope at `ḣ = l θ̇⁺ (sin θ⁻ − sin θ')` (`= 2 l sin α cos 2α θ̇⁻` on the guard):
//! positive for `N > 4`; for `N = 3` the plastic impact about the new spoke alone would drive
//! the trailing spoke into the ground (negative margin, flagged).

use crate::error::{check_open, WalkerError};
use crate::registry::{closed_params, ClosedInfo};
use crate::validity::{ConstraintForces, ImpactReport, Scales, StepFlags};
use pdw_hybrid::{Crossing, FallKind, GuardKind, GuardSpec, HybridSystem, Scratch, Section};
use pdw_model::{
    BodyPoints, ClosedEnd, ClosedStride, GaitGuess, Ground, ModelUnits, Pose, StepHeight, Walker,
};
use std::f64::consts::{FRAC_PI_2, PI};

/// Guard index of the spoke impact.
pub const SPOKE_IMPACT: usize = 0;

const GUARDS: [GuardSpec; 3] = [
    GuardSpec {
        name: "spoke_impact",
        crossing: Crossing::Rising,
        kind: GuardKind::Reset,
    },
    GuardSpec {
        name: "rolls_back",
        crossing: Crossing::Falling,
        kind: GuardKind::Terminal(FallKind::RollsBack),
    },
    GuardSpec {
        name: "back_past_previous_spoke",
        crossing: Crossing::Falling,
        kind: GuardKind::Terminal(FallKind::RollsBack),
    },
];

const STATE_NAMES: [&str; 2] = ["theta", "thetadot"];
const SECTION_NAMES: [&str; 1] = ["thetadot"];

closed_params! {
    /// User-facing parameters of [`Rimless`].
    pub struct RimlessParams in PARAMS {
        /// In (−π/2, π/2).
        slope: "rad" = 0.08 => "slope angle γ",
        /// An integer ≥ 3 (a float so that it can come from `--set`).
        n_spokes: "1" = 8.0
            => "number of spokes N (integer ≥ 3); α = π/N (Tedrake's example uses 8)",
        /// Finite and > 0.
        g: "m/s^2" = 9.81 => "gravitational acceleration",
        /// Finite and > 0.
        l: "m" = 1.0 => "spoke length",
        /// Finite and > 0.
        max_stride_time: "s" = 10.0 => "stride time budget; a longer stride counts as a timeout",
        /// Finite, `|h| < 2 l sin α` (module docs, "Step down").
        step_down: "m" = 0.0
            => "height by which the next spoke's foothold lies below the stance contact, along \
                the slope normal (a step down positive, a step up negative)",
    }
}

/// Registry entry.
pub static INFO: ClosedInfo = ClosedInfo {
    name: "rimless",
    description: "rimless wheel: point mass on N massless spokes (closed-form fixed point)",
    params: PARAMS,
    state_names: &STATE_NAMES,
    section_names: &SECTION_NAMES,
    build_from: |v| Ok(Box::new(Rimless::new(RimlessParams::from_values(v))?)),
};

/// The rimless wheel (immutable model).
#[derive(Clone, Debug)]
pub struct Rimless {
    /// The validated parameters (γ is `params.slope`, N is `params.n_spokes`).
    params: RimlessParams,
    /// Half inter-spoke angle α = π/N.
    alpha: f64,
    /// The stance angle at which the next spoke's tip reaches the foothold `step_down` below:
    /// `α + asin(h / (2 l sin α))` (`α` on level ground).
    strike: f64,
    /// The stance angle just after a spoke impact onto such a foothold, `strike − 2α`.
    after: f64,
}

impl Rimless {
    /// Builds the model, rejecting a non-integer or < 3 spoke count, a slope outside
    /// (−π/2, π/2), non-positive `g`, `l` or time budget, or non-finite values.
    pub fn new(p: RimlessParams) -> Result<Self, WalkerError> {
        let gamma = check_open(
            "slope",
            p.slope,
            -FRAC_PI_2,
            FRAC_PI_2,
            "a finite angle in (-pi/2, pi/2) rad",
        )?;
        if !(p.n_spokes.is_finite() && p.n_spokes >= 3.0 && p.n_spokes.fract() == 0.0) {
            return Err(WalkerError::InvalidParam {
                name: "n_spokes",
                value: p.n_spokes,
                allowed: "an integer >= 3",
            });
        }
        let g = check_open("g", p.g, 0.0, f64::INFINITY, "finite and > 0")?;
        let l = check_open("l", p.l, 0.0, f64::INFINITY, "finite and > 0")?;
        let max_stride_time = check_open(
            "max_stride_time",
            p.max_stride_time,
            0.0,
            f64::INFINITY,
            "finite and > 0",
        )?;
        let alpha = PI / p.n_spokes;
        let reach = 2.0 * l * alpha.sin();
        if !(p.step_down.is_finite() && p.step_down.abs() < reach) {
            return Err(WalkerError::InvalidParam {
                name: "step_down",
                value: p.step_down,
                allowed: "a finite height with |step_down| < 2 l sin(pi/n_spokes) (the next \
                          spoke's reach)",
            });
        }
        let strike = strike_angle(alpha, p.l, p.step_down);
        let after = if p.step_down == 0.0 {
            -alpha
        } else {
            strike - 2.0 * alpha
        };
        Ok(Self {
            params: RimlessParams {
                slope: gamma,
                n_spokes: p.n_spokes,
                g,
                l,
                max_stride_time,
                step_down: p.step_down,
            },
            alpha,
            strike,
            after,
        })
    }

    /// Half inter-spoke angle α = π/N.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// Energy per unit mass, `½ l² θ̇² + g l cos(θ + γ)`.
    pub fn energy(&self, x: &[f64]) -> f64 {
        let RimlessParams { slope, g, l, .. } = self.params;
        0.5 * l * l * x[1] * x[1] + g * l * (x[0] + slope).cos()
    }

    /// The stance angles a step runs between: `(θ⁺, θ⁻)`, just after the previous spoke
    /// impact onto a foothold `step_down` lower and at the next one (`(−α, α)` on level
    /// ground; module docs, "Step down").
    pub fn step_angles(&self) -> (f64, f64) {
        (self.after, self.strike)
    }

    /// Closed-form rolling fixed point `ω* = cot 2α · √(4 (g/l) sin α sin γ)` (Coleman; Tedrake),
    /// or `None` when the rolling gait does not exist (`γ ≤ 0`, `N = 4` (cot 2α = 0 is the
    /// standing limit) or `ω* ≤ ω₁ = √(2 (g/l)(1 − cos(γ − α)))`). On stairs (`step_down ≠ 0`)
    /// the same balance of energy over a step from `θ⁺` to `θ⁻` ([`Rimless::step_angles`]):
    /// `ω*² = 2 (g/l) D cos² 2α / sin² 2α`, `D = cos(θ⁺ + γ) − cos(θ⁻ + γ)`, and
    /// `ω₁² = 2 (g/l)(1 − cos(θ⁺ + γ))`.
    pub fn rolling_fixed_point(&self) -> Option<f64> {
        let a = self.alpha;
        let RimlessParams { slope, g, l, .. } = self.params;
        if self.params.step_down != 0.0 {
            let (t0, t1) = (self.after + slope, self.strike + slope);
            let d = t0.cos() - t1.cos();
            let w = (2.0 * g / l * d).sqrt() / (2.0 * a).tan();
            let w1 = (2.0 * g / l * (1.0 - t0.cos())).sqrt();
            return (w.is_finite() && w > w1).then_some(w);
        }
        if slope <= 0.0 {
            return None;
        }
        let w = (4.0 * g / l * a.sin() * slope.sin()).sqrt() / (2.0 * a).tan();
        let w1 = (2.0 * g / l * (1.0 - (slope - a).cos())).sqrt();
        (w.is_finite() && w > w1).then_some(w)
    }
}

/// The stance angle at which the next spoke's tip reaches a foothold `h` below the contact
/// point (module docs, "Step down"): `α + asin(h / (2 l sin α))`, `α` on level ground.
fn strike_angle(alpha: f64, l: f64, h: f64) -> f64 {
    if h == 0.0 {
        alpha
    } else {
        alpha + (h / (2.0 * l * alpha.sin())).asin()
    }
}

impl Rimless {
    /// The guards with the spoke impact at stance angle `strike`.
    fn guard_with_strike(&self, k: usize, x: &[f64], strike: f64) -> f64 {
        match k {
            0 => x[0] - strike,
            1 => x[1],
            _ => x[0] + self.alpha,
        }
    }
}

/// The rimless wheel at any step height: only the spoke impact's angle
/// ([`Rimless::step_angles`]) sees the foothold; the impact map, the gradients and the
/// admissibility do not.
impl StepHeight for Rimless {
    fn guard_at(&self, _ws: &mut Scratch, _mode: usize, k: usize, x: &[f64], h: f64) -> f64 {
        let strike = if k == SPOKE_IMPACT {
            strike_angle(self.alpha, self.params.l, h)
        } else {
            self.strike
        };
        self.guard_with_strike(k, x, strike)
    }
    /// The default of [`HybridSystem::guards_with_rates`] (the model's): the guards, rates
    /// unknown (`+∞`).
    fn guards_with_rates_at(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        x: &[f64],
        _f: &[f64],
        g: &mut [f64],
        rate: &mut [f64],
        h: f64,
    ) {
        let strike = strike_angle(self.alpha, self.params.l, h);
        for (k, (gk, rk)) in g.iter_mut().zip(rate.iter_mut()).enumerate() {
            *gk = self.guard_with_strike(k, x, strike);
            *rk = f64::INFINITY;
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
    fn admissible_at(&self, mode: usize, k: usize, x: &[f64], _h: f64) -> bool {
        self.admissible(mode, k, x)
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

/// The rimless wheel's stride in closed form (module docs, "Flow", "Spoke impact", "Step
/// down"): along the flow the energy `½ θ̇² + (g/l) cos(θ + γ)` (per `l²` and unit mass) is
/// conserved, so from `(θ₀, θ̇₀)`, `θ̇₀ > 0`, the wheel reaches the strike angle `θ⁻` iff
/// `θ̇²(θ) = θ̇₀² + 2 (g/l)(cos(θ₀ + γ) − cos(θ + γ))` stays positive on `[θ₀, θ⁻]` — its least
/// value is at the hub's top `θ = −γ` when that lies in the interval, else at an end — and
/// then lands with `θ̇⁻ = √θ̇²(θ⁻)`, `θ⁺ = θ⁻ − 2α`, `θ̇⁺ = cos 2α · θ̇⁻` (the reset). Otherwise
/// `θ̇` falls through zero first: guard 1 (rolls back). Differences of cosines are taken as
/// products of sines, `cos a − cos b = 2 sin((a + b)/2) sin((b − a)/2)`, so that a small
/// energy difference keeps its digits. A start with `θ̇₀ ≤ 0` or past the strike angle is
/// [`ClosedEnd::Outside`] (the integrated stride decides it: guard 2, or a turn over the top).
impl ClosedStride for Rimless {
    fn stride_on(&self, ground: Ground, x: &[f64], out: &mut [f64]) -> ClosedEnd {
        let RimlessParams { slope, g, l, .. } = self.params;
        let (gamma, strike) = match ground {
            Ground::Slope(s) => (s, self.strike),
            Ground::StepDown(h) => (slope, strike_angle(self.alpha, l, h)),
        };
        let (t0, w0) = (x[0], x[1]);
        if !(w0 > 0.0 && t0 < strike) {
            return ClosedEnd::Outside;
        }
        let k = g / l;
        let (a, b) = (t0 + gamma, strike + gamma);
        // θ̇² drops by 2 (g/l) rise(θ + γ) from θ₀ to θ, rise(c) = cos c − cos a: most at the
        // top (rise = 1 − cos a = 2 sin²(a/2)) when −γ lies between θ₀ and the strike, else at
        // the strike or not at all
        let rise = |c: f64| 2.0 * ((c + a) / 2.0).sin() * ((a - c) / 2.0).sin();
        let worst = if a <= 0.0 && b >= 0.0 {
            2.0 * (a / 2.0).sin().powi(2)
        } else {
            rise(b).max(0.0)
        };
        if w0 * w0 - 2.0 * k * worst <= 0.0 {
            return ClosedEnd::Terminal { guard: 1 };
        }
        let w1 = (w0 * w0 - 2.0 * k * rise(b)).sqrt();
        out[0] = strike - 2.0 * self.alpha;
        out[1] = (2.0 * self.alpha).cos() * w1;
        ClosedEnd::Landed
    }
}

pdw_hybrid::integrate_concretely!(Rimless);
impl HybridSystem for Rimless {
    fn dim(&self) -> usize {
        2
    }
    fn guards(&self, _mode: usize) -> &[GuardSpec] {
        &GUARDS
    }
    fn flow(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], dx: &mut [f64]) {
        dx[0] = x[1];
        let RimlessParams { slope, g, l, .. } = self.params;
        dx[1] = g / l * (x[0] + slope).sin();
    }
    fn guard(&self, _ws: &mut Scratch, _mode: usize, k: usize, x: &[f64]) -> f64 {
        self.guard_with_strike(k, x, self.strike)
    }
    fn reset(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        _k: usize,
        x: &[f64],
        out: &mut [f64],
    ) -> usize {
        out[0] = x[0] - 2.0 * self.alpha;
        out[1] = (2.0 * self.alpha).cos() * x[1];
        0
    }
    fn flow_jacobian(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], jac: &mut [f64]) {
        jac[0] = 0.0;
        jac[1] = 1.0;
        let RimlessParams { slope, g, l, .. } = self.params;
        jac[2] = g / l * (x[0] + slope).cos();
        jac[3] = 0.0;
    }
    fn guard_gradient(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        k: usize,
        _x: &[f64],
        grad: &mut [f64],
    ) {
        if k == 1 {
            grad[0] = 0.0;
            grad[1] = 1.0;
        } else {
            grad[0] = 1.0;
            grad[1] = 0.0;
        }
    }
    fn reset_jacobian(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        _k: usize,
        _x: &[f64],
        jac: &mut [f64],
    ) {
        jac[0] = 1.0;
        jac[1] = 0.0;
        jac[2] = 0.0;
        jac[3] = (2.0 * self.alpha).cos();
    }
}

impl Section for Rimless {
    fn section_dim(&self) -> usize {
        1
    }
    fn section_names(&self) -> &[&'static str] {
        &SECTION_NAMES
    }
    fn section_mode(&self) -> usize {
        0
    }
    fn section_guard(&self) -> (usize, usize) {
        (0, SPOKE_IMPACT)
    }
    fn lift(&self, s: &[f64], x: &mut [f64]) {
        x[0] = self.after;
        x[1] = s[0];
    }
    fn project(&self, x: &[f64], s: &mut [f64]) {
        s[0] = x[1];
    }
    fn max_stride_time(&self) -> f64 {
        self.params.max_stride_time
    }
}

impl Walker for Rimless {
    /// θ is absolute with the opposite sign to Garcia's (hub downhill positive), the flow sees
    /// `θ + γ` (module docs): θ changes by `−(s' − s)`.
    fn terrain_frame(&self) -> Option<(usize, f64)> {
        Some((0, -1.0))
    }
    fn step_height(&self) -> Option<&dyn StepHeight> {
        Some(self)
    }
    fn closed_stride(&self) -> Option<&dyn ClosedStride> {
        Some(self)
    }
    fn energy(&self, x: &[f64]) -> Option<f64> {
        Some(Self::energy(self, x))
    }
    /// Without `step_down` on level ground (files written before it existed match).
    fn fingerprint(&self) -> String {
        crate::registry::level_fingerprint(self.name(), &self.param_values())
    }
    fn energy_unit(&self) -> &str {
        "J/kg"
    }
    /// SI per unit hub mass: the wheel has no mass parameter, so forces are in N/kg.
    fn units(&self) -> ModelUnits {
        ModelUnits {
            force: "N/kg".into(),
            torque: "N m/kg".into(),
            ..ModelUnits::SI
        }
    }
    fn name(&self) -> &str {
        "rimless"
    }
    fn state_names(&self) -> Vec<String> {
        STATE_NAMES.iter().map(|s| s.to_string()).collect()
    }
    /// Module docs, "Coordinates and signs".
    fn coordinate_meanings(&self) -> Vec<String> {
        vec![
            "θ: stance spoke's angle from the slope normal (rad); positive: hub downhill of the \
             contact point"
                .into(),
            "θ̇: rate of θ (rad/s); positive rolls forward".into(),
        ]
    }
    fn mode_names(&self) -> Vec<String> {
        vec!["rolling on one spoke".into()]
    }
    fn param_values(&self) -> Vec<(String, f64)> {
        self.params.named_values()
    }
    /// Distance between consecutive contact points, `2 l sin α`.
    /// Onto a step, the distance along the slope `l (sin θ⁻ − sin(θ⁻ − 2α))`.
    fn step_length(&self, x_pre: &[f64]) -> f64 {
        if self.params.step_down != 0.0 {
            let th = x_pre[0];
            return self.params.l * (th.sin() - (th - 2.0 * self.alpha).sin());
        }
        2.0 * self.params.l * self.alpha.sin()
    }
    /// Hub at `l (sin θ, cos θ)` above the contact point; spoke `k` points from the hub at angle
    /// `θ + 2kα` from the downward normal (module docs).
    fn pose(&self, x: &[f64]) -> Option<Pose> {
        let th = x[0];
        let l = self.params.l;
        let hub = [l * th.sin(), l * th.cos()];
        let n = (PI / self.alpha).round() as usize;
        let links = (0..n)
            .map(|k| {
                let a = th + 2.0 * self.alpha * k as f64;
                [hub, [hub[0] - l * a.sin(), hub[1] - l * a.cos()]]
            })
            .collect();
        let next = th - 2.0 * self.alpha;
        Some(Pose {
            links,
            joints: vec![hub],
            swing_foot: Some([hub[0] - l * next.sin(), hub[1] - l * next.cos()]),
        })
    }
    /// The stance spoke's foot (the contact point) and the hub, `l (sin θ, cos θ)` above it
    /// (module docs); all the mass is at the hub, so the centre of mass is the hub.
    fn body_points(&self, x: &[f64]) -> Option<BodyPoints> {
        let l = self.params.l;
        let hub = [l * x[0].sin(), l * x[0].cos()];
        Some(BodyPoints {
            names: vec!["stance_foot".into(), "hub".into()],
            points: vec![[0.0, 0.0], hub],
            com: hub,
        })
    }
    /// Ground reaction on the stance spoke's foot per unit hub mass (module docs, "Ground
    /// reaction"): the axial spoke force `S = g cos(θ + γ) − l θ̇²` from Newton's law for the hub
    /// along the spoke, normal `S cos θ`, tangential (downhill) `S sin θ`, friction needed
    /// `|tan θ|` (`+∞` where the normal force is not positive). No knees.
    fn constraint_forces(&self, _mode: usize, x: &[f64]) -> Option<ConstraintForces> {
        let (th, thd) = (x[0], x[1]);
        let RimlessParams { slope, g, l, .. } = self.params;
        let axial = g * (th + slope).cos() - l * thd * thd;
        let (s, c) = th.sin_cos();
        let (normal, tangential) = (axial * c, axial * s);
        Some(ConstraintForces {
            normal,
            tangential,
            friction_required: if normal > 0.0 {
                (tangential / normal).abs()
            } else {
                f64::INFINITY
            },
            knee_torque: [None, None],
        })
    }
    /// Only the normal-force flag applies: no knees, and no swing foot to scuff (see
    /// [`Walker::swing_clearance`] below).
    fn step_flags(&self, mode: usize, x: &[f64]) -> Option<StepFlags> {
        let cf = Walker::constraint_forces(self, mode, x)?;
        Some(StepFlags {
            normal_force_negative: cf.normal < 0.0,
            ..StepFlags::default()
        })
    }
    /// Per unit hub mass (mass 1 in the model's units), the spoke length `l` and gravity `g`:
    /// forces relative to `g`, impulses to `√(g l)`.
    fn scales(&self) -> Option<Scales> {
        Some(Scales {
            mass: 1.0,
            length: self.params.l,
            gravity: self.params.g,
        })
    }
    /// A rimless wheel has no swing foot: its spokes are rigid at fixed angles `2α` apart, and
    /// the lowest other tip, the next spoke's, is `l (cos θ − cos(θ − 2α)) = 2 l sin α sin(α − θ)`
    /// above the slope, positive for every `θ < α` of a step and zero only at the spoke impact
    /// (the trailing spoke's, `2 l sin α sin(α + θ)`, is zero only where it lifted off). No
    /// clearance criterion applies; [`Walker::pose`]'s `swing_foot` (the next spoke's tip) is
    /// for drawings only.
    fn swing_clearance(&self, _mode: usize, _x: &[f64]) -> Option<f64> {
        None
    }
    /// The spoke impact's impulses per unit hub mass (module docs, "Spoke-impact impulses"):
    /// the new stance spoke's foot takes `Λ = l θ̇⁻ sin 2α` along the new spoke (normal
    /// `Λ cos θ'`, tangential `Λ sin θ'`, `θ' = θ⁻ − 2α`; it must push), and the trailing
    /// spoke's foot releases with separation rate `l θ̇⁺ (sin θ⁻ − sin θ')` (it must leave the
    /// ground). Energy lost `½ Λ²`.
    fn impact_report(&self, _mode: usize, guard: usize, x: &[f64]) -> Option<ImpactReport> {
        if guard != SPOKE_IMPACT {
            return None;
        }
        let (th, thd) = (x[0], x[1]);
        let th_new = th - 2.0 * self.alpha;
        let lam = self.params.l * thd * (2.0 * self.alpha).sin();
        let (ln, lt) = (lam * th_new.cos(), lam * th_new.sin());
        let mut post = [0.0; 2];
        self.reset(&mut Scratch::new(), 0, guard, x, &mut post);
        let rate = self.params.l * post[1] * (th.sin() - th_new.sin());
        Some(ImpactReport::point_contact(
            GUARDS[SPOKE_IMPACT].name,
            ln,
            lt,
            rate,
            0.5 * lam * lam,
        ))
    }
    /// `θ̇` just after a spoke impact from 0.01 to 4 √(g/l): rolling forward, up to a hub speed of
    /// four times √(g l) (the rolling fixed point's `ω*² = 4 (g/l) sin α sin γ cos² 2α / sin² 2α`,
    /// Coleman, is below it on slopes up to 45° for wheels of up to 50 spokes).
    fn section_box(&self) -> Option<(Vec<f64>, Vec<f64>)> {
        let w = (self.params.g / self.params.l).sqrt();
        Some((vec![0.01 * w], vec![4.0 * w]))
    }
    /// The closed-form rolling fixed point, when it exists.
    fn gait_guesses(&self) -> Vec<GaitGuess> {
        self.rolling_fixed_point()
            .map(|w| GaitGuess {
                gait: "stable".into(),
                section: vec![w],
                source: "closed form (Coleman; Tedrake, Underactuated Robotics)".into(),
            })
            .into_iter()
            .collect()
    }
}
