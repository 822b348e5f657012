//! The simplest walking model of Garcia, Chatterjee, Ruina & Coleman (1998), in their exact
//! convention.
//!
//! A point-mass hip `M` on two massless legs of length `l` with infinitesimal point feet
//! (`m/M → 0`), on a slope `γ`; time in units of `√(l/g)`.
//!
//! # Coordinates and signs
//! State `x = (θ, θ̇, φ, φ̇)`:
//! - `θ` — stance-leg angle from the slope normal; positive when the stance foot is ahead of the
//!   hip (downhill). During a step θ decreases from about `+0.2` to about `−0.2`.
//! - `φ` — angle between the legs, `φ = θ − ψ` with `ψ` the swing leg's angle from the slope
//!   normal (same sign convention as θ).
//!
//! In a slope frame with `x` downhill along the slope and `y` along the normal, stance foot at the
//! origin: hip `= (−sin θ, cos θ)`, swing foot `= hip + (sin ψ, −cos ψ)`, gravity
//! `= (sin γ, −cos γ)`.
//!
//! # Flow (Garcia 1998 eq. 3)
//! ```text
//! θ̈ = sin(θ − γ)
//! φ̈ = sin(θ − γ) + θ̇² sin φ − cos(θ − γ) sin φ
//! ```
//! Energy (per unit hip mass, units `M g l`): `E = ½ θ̇² + cos(θ − γ)` is conserved by the flow.
//!
//! # Heel strike (guard 0)
//! `g = φ − 2θ`. The swing-foot height above the slope is `h = cos θ − cos ψ =
//! 2 sin(φ/2) sin(g/2)`, which vanishes both when the legs coincide (`φ = 0`, the mid-stance
//! *scuffing*, ignored as in the paper) and at `g = 0`. The foot strikes the ground when `h`
//! goes from positive to negative with the swing foot *ahead* of the stance foot; the swing-foot
//! position along the slope on `g = 0` is `−2 sin θ`, so "ahead" means `θ < 0` (hence `φ < 0`),
//! and with `sin(φ/2) < 0` a decreasing `h` means an increasing `g`. The heel strike is therefore
//! the **rising** crossing of `g` with the admissibility test **`θ < 0`**. Both conditions are
//! scale free, so the same test holds for the tiny gaits of very small slopes (θ* ∝ γ^{1/3}).
//! The mid-stance crossings of `g` (falling, or rising with `θ > 0` just after the previous heel
//! strike where `g = 0`) are not heel strikes.
//!
//! # Jump map (Garcia 1998, rank 2)
//! ```text
//! θ⁺ = −θ⁻,  θ̇⁺ = cos 2θ⁻ θ̇⁻,  φ⁺ = −2θ⁻,  φ̇⁺ = cos 2θ⁻ (1 − cos 2θ⁻) θ̇⁻
//! ```
//! It follows from conservation of the hip's angular momentum about the new contact point (the
//! hip velocity keeps only its component perpendicular to the new stance leg) and of the
//! trailing foot's angular momentum about the hip (the new swing foot leaves with no velocity
//! perpendicular to its leg).
//!
//! # Step down (random step heights; Schwab & Wisse 2001, Hobbelen & Wisse 2007)
//! With `step_down = h ≠ 0` the next foothold lies `h` below the stance foot along the slope
//! normal (a step down positive, up negative), on a line parallel to the slope. The swing foot
//! `(sin ψ − sin θ, cos θ − cos ψ)` strikes when its height reaches `−h`: guard
//! `cos ψ − cos θ − h` rising, admissible with the foot ahead, `sin ψ − sin θ > 0` (at `h = 0`
//! the old guard `φ − 2θ` and test `θ < 0` run unchanged, bit for bit). The same two
//! conservation laws give the jump map for the unsymmetric configuration: the hip velocity
//! keeps its component across the new stance leg (the old swing leg, angle `ψ⁻ = θ⁻ − φ⁻`),
//! `θ⁺ = θ⁻ − φ⁻`, `θ̇⁺ = cos φ⁻ θ̇⁻`; the legs swap, `φ⁺ = −φ⁻`; and the new swing foot keeps no
//! velocity across its leg, `ψ̇⁺ = cos φ⁺ θ̇⁺`, so `φ̇⁺ = cos φ⁻ (1 − cos φ⁻) θ̇⁻` (at
//! `φ⁻ = 2θ⁻` Garcia's map). Energy lost: `½ θ̇⁻² sin² φ⁻`. The dynamics do not see where the
//! feet are, only the angles, so nothing shifts between steps: the next step's foothold is
//! measured from the new stance foot. After a strike onto `h` the trailing foot is `h` above the
//! new stance foot, so the lift of the model with `step_down = h` puts it there:
//! `ψ = −acos(cos θ − h)` (behind), `φ = θ − ψ`, `φ̇ = (1 − cos φ) θ̇`.
//! [`Walker::swing_clearance`] stays the height over the stance foot's line.
//!
//! # Section
//! Just after heel strike, reduced coordinates `(θ, θ̇)` in Garcia's convention. Because the jump
//! map's image satisfies `φ⁺ = 2θ⁺` and, with `cos 2θ⁺ = cos 2θ⁻` and `θ̇⁻ = θ̇⁺ / cos 2θ⁺`,
//! `φ̇⁺ = (1 − cos 2θ⁺) θ̇⁺`, the lift is `(θ, θ̇) ↦ (θ, θ̇, 2θ, (1 − cos 2θ) θ̇)`.
//! (Writing `cos 2θ (1 − cos 2θ) θ̇` with the *post*-impact θ̇ would be wrong by a factor
//! `cos 2θ`.)
//!
//! # Falls (terminal guards)
//! - guard 1, [`FallKind::Backward`]: `θ̇` rises through 0 before heel strike. The stance motion
//!   `θ̈ = sin(θ − γ)` does not depend on the swing leg, and θ̇ can only rise through 0 where
//!   `θ > γ`, after which the walker falls back over its stance foot.
//! - guard 2, [`FallKind::Backward`]: the hip reaches the ground behind, `θ = π/2` (rising) — catches
//!   states that start with `θ̇ ≥ 0`.
//! - guard 3, [`FallKind::Forward`]: the hip reaches the ground ahead, `θ = −π/2` (falling).
//! - a stride longer than `max_stride_time` ([`Section::max_stride_time`]).
//!
//! # Vectorised right-hand side
//! `flow_batch` runs column loops over lanes, compiled for the run-time SIMD path, in blocks of
//! 64 lanes: a block whose angles `θ − γ` and `φ` are all below `pdw_simd::trig::SMALL` skips
//! the trigonometric reduction (the identity there) and `cos φ`, any other block takes the full
//! branch-free routine. Both give the bits of `pdw_simd::sincos`, which the scalar
//! [`HybridSystem::flow`] runs on its two angles, so the scalar and batched right-hand sides are
//! bit-identical.

use crate::error::{check_open, WalkerError};
use crate::registry::{closed_params, ClosedInfo};
use crate::validity::{ClearanceRule, ConstraintForces, ImpactReport, Scales, StepFlags};
use faer::{MatMut, MatRef};
use pdw_hybrid::{Crossing, FallKind, GuardKind, GuardSpec, HybridSystem, Scratch, Section};
use pdw_model::{BodyPoints, GaitGuess, ModelUnits, Pose, StepHeight, Walker};
use std::f64::consts::FRAC_PI_2;

/// Guard index of the heel strike.
pub const HEEL_STRIKE: usize = 0;

const GUARDS: [GuardSpec; 4] = [
    GuardSpec {
        name: "heel_strike",
        crossing: Crossing::Rising,
        kind: GuardKind::Reset,
    },
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

const STATE_NAMES: [&str; 4] = ["theta", "thetadot", "phi", "phidot"];
const SECTION_NAMES: [&str; 2] = ["theta", "thetadot"];

closed_params! {
    /// User-facing parameters of [`Simplest`].
    pub struct SimplestParams in PARAMS {
        /// In (−π/2, π/2).
        slope: "rad" = 0.009 => "slope angle γ (Garcia et al. 1998 use 0.009)",
        /// Finite and > 0; the gaits take ≈ 3.1–3.9.
        max_stride_time: "sqrt(l/g)" = 12.0
            => "stride time budget; a longer stride counts as a fall (gait period ≈ 3.9)",
        /// Finite, in (−1, 1) leg lengths; 0 is level ground (module docs, "Step down").
        step_down: "l" = 0.0
            => "height by which the next foothold lies below the stance foot, along the slope \
                normal (a step down positive, a step up negative)",
    }
}

/// Registry entry.
pub static INFO: ClosedInfo = ClosedInfo {
    name: "simplest",
    description: "Garcia et al. 1998 simplest walker: point-mass hip, massless legs, \
                  infinitesimal feet; time in sqrt(l/g)",
    params: PARAMS,
    state_names: &STATE_NAMES,
    section_names: &SECTION_NAMES,
    build_from: |v| Ok(Box::new(Simplest::new(SimplestParams::from_values(v))?)),
};

/// The simplest walker (immutable model).
#[derive(Clone, Debug)]
pub struct Simplest {
    /// The validated parameters (γ is `params.slope`).
    params: SimplestParams,
}

/// `φ̈ = sin(θ − γ) + (θ̇² − cos(θ − γ))·sin φ` (Garcia 1998 eq. 4, swing leg) from
/// `s = sin(θ − γ)`, `c = cos(θ − γ)`, `sp = sin φ`: one expression for the scalar and the
/// batched right-hand side, so both round alike.
#[inline(always)]
fn phi_ddot(s: f64, c: f64, sp: f64, thd: f64) -> f64 {
    s + (thd * thd - c) * sp
}

/// The right-hand side `(θ̇, θ̈, φ̇, φ̈)` of one state (Garcia 1998 eqs. 3–4), with
/// `[cos(θ − γ), sin φ, cos φ]` for the Jacobian: `θ − γ` and `φ` in one two-element
/// `sincos_lanes` (element-wise, so every value has the bits `flow_batch` gives that state's
/// lane).
#[inline(always)]
fn rhs1(gamma: f64, x: &[f64]) -> ([f64; 4], [f64; 3]) {
    let (th, thd, ph, phd) = (x[0], x[1], x[2], x[3]);
    let a = th - gamma;
    let (sv, cv) = pdw_simd::sincos_lanes([a, ph]);
    let (s, c, sp, cp) = (sv[0], cv[0], sv[1], cv[1]);
    let phdd = phi_ddot(s, c, sp, thd);
    ([thd, s, phd, phdd], [c, sp, cp])
}

/// Lanes per trigonometric choice of [`rhs_block`].
const RHS_BLOCK: usize = 64;

/// `θ̈` and `φ̈` of a block of lanes (columns θ, θ̇, φ in, θ̈ and φ̈ out), every value with the
/// bits of [`rhs1`] on that lane's state. When every angle of the block is below
/// `pdw_simd::trig::SMALL` (walkers near their gait) the trigonometric reduction is the
/// identity and is skipped, and cos φ, not needed, is not evaluated: under half the
/// operations. Otherwise the full routine runs on all lanes of the block.
#[inline(always)]
fn rhs_block(gamma: f64, th: &[f64], thd: &[f64], ph: &[f64], o1: &mut [f64], o3: &mut [f64]) {
    use pdw_simd::trig::{REDUCED_RANGE, SMALL};
    let n = th.len();
    let (thd, ph, o1, o3) = (&thd[..n], &ph[..n], &mut o1[..n], &mut o3[..n]);
    let mut small = true;
    for l in 0..n {
        small &= ((th[l] - gamma).abs() < SMALL) & (ph[l].abs() < SMALL);
    }
    if small {
        for l in 0..n {
            let (s, c) = pdw_simd::sincos_small(th[l] - gamma);
            let sp = pdw_simd::sin_small(ph[l]);
            o1[l] = s;
            o3[l] = phi_ddot(s, c, sp, thd[l]);
        }
        return;
    }
    let mut big = false;
    for l in 0..n {
        let a = th[l] - gamma;
        let (s, c) = pdw_simd::sincos_reduced_range(a);
        let sp = pdw_simd::sincos_reduced_range(ph[l]).0;
        big |= (a.abs() > REDUCED_RANGE) | (ph[l].abs() > REDUCED_RANGE);
        o1[l] = s;
        o3[l] = phi_ddot(s, c, sp, thd[l]);
    }
    if big {
        // Angles beyond the reduced range (a state far off any walking motion): those lanes
        // again through `sincos`, which takes libm's values there.
        for l in 0..n {
            let a = th[l] - gamma;
            if a.abs() > REDUCED_RANGE || ph[l].abs() > REDUCED_RANGE {
                let (s, c) = pdw_simd::sincos(a);
                let sp = pdw_simd::sincos(ph[l]).0;
                o1[l] = s;
                o3[l] = phi_ddot(s, c, sp, thd[l]);
            }
        }
    }
}

/// The guards of [`HybridSystem::guard`] at `(θ, θ̇, φ)` and their rates from
/// `f = (θ̇, θ̈, φ̇, ·)`: heel strike `φ − 2θ` (rate `φ̇ − 2θ̇`) on level ground (`h = 0`) or
/// [`step_guard`] onto a foothold `h` below, stance reversal `θ̇` (rate `θ̈`), hip on the
/// ground behind `θ − π/2` and ahead `θ + π/2` (rate `θ̇`).
#[inline(always)]
fn guards_and_rates(
    h: f64,
    th: f64,
    thd: f64,
    ph: f64,
    f0: f64,
    f1: f64,
    f2: f64,
) -> ([f64; 4], [f64; 4]) {
    let (g0, r0) = if h == 0.0 {
        (ph - 2.0 * th, f2 - 2.0 * f0)
    } else {
        step_guard(h, th, ph, f0, f2)
    };
    ([g0, thd, th - FRAC_PI_2, th + FRAC_PI_2], [r0, f1, f0, f0])
}

/// The heel-strike guard onto a foothold `h` below the stance foot (module docs, "Step down"):
/// `cos ψ − cos θ − h` (minus the swing foot's height over the foothold's level, `ψ = θ − φ`)
/// and its rate `−sin ψ (θ̇ − φ̇) + sin θ θ̇`.
#[inline(always)]
fn step_guard(h: f64, th: f64, ph: f64, thd: f64, phd: f64) -> (f64, f64) {
    let psi = th - ph;
    (
        psi.cos() - th.cos() - h,
        -psi.sin() * (thd - phd) + th.sin() * thd,
    )
}

/// The jump map onto a step (module docs, "Step down"): `θ⁺ = θ⁻ − φ⁻`,
/// `θ̇⁺ = cos φ⁻ θ̇⁻`, `φ⁺ = −φ⁻`, `φ̇⁺ = cos φ⁻ (1 − cos φ⁻) θ̇⁻` — Garcia 1998's map with
/// the inter-leg angle `φ⁻` in place of `2θ⁻`.
fn step_reset(x: &[f64], out: &mut [f64]) {
    let (th, thd, ph) = (x[0], x[1], x[2]);
    let c = pdw_simd::sincos(ph).1;
    out[0] = th - ph;
    out[1] = c * thd;
    out[2] = -ph;
    out[3] = c * (1.0 - c) * thd;
}

/// The derivative of [`step_reset`]: θ⁻, θ̇⁻ and φ⁻ enter.
fn step_reset_jacobian(x: &[f64], jac: &mut [f64]) {
    let (thd, ph) = (x[1], x[2]);
    let (s, c) = pdw_simd::sincos(ph);
    jac[..16].fill(0.0);
    jac[0] = 1.0;
    jac[2] = -1.0;
    jac[5] = c;
    jac[6] = -s * thd;
    jac[10] = -1.0;
    // d/dφ [c (1 − c)] = −s (1 − c) + c s = s (2c − 1)
    jac[13] = c * (1.0 - c);
    jac[14] = s * (2.0 * c - 1.0) * thd;
}

/// The lift after a heel strike onto a foothold `h` below the previous one (module docs, "Step
/// down"): the trailing foot is `h` above the new stance foot and behind it, so
/// `ψ = −acos(cos θ − h)`, `φ = θ − ψ`, and `φ̇ = (1 − cos φ) θ̇` as on level ground.
fn step_lift(h: f64, s: &[f64], x: &mut [f64]) {
    let psi = -(s[0].cos() - h).clamp(-1.0, 1.0).acos();
    let ph = s[0] - psi;
    x[0] = s[0];
    x[1] = s[1];
    x[2] = ph;
    x[3] = (1.0 - pdw_simd::sincos(ph).1) * s[1];
}

/// The four columns of a `(lanes × 4)` view as slices, when they are contiguous.
fn cols4_mut(m: MatMut<'_, f64>) -> Option<[&mut [f64]; 4]> {
    let (a, b) = m.split_at_col_mut(2);
    let (c0, c1) = a.split_at_col_mut(1);
    let (c2, c3) = b.split_at_col_mut(1);
    Some([
        c0.col_mut(0).try_as_col_major_mut()?.as_slice_mut(),
        c1.col_mut(0).try_as_col_major_mut()?.as_slice_mut(),
        c2.col_mut(0).try_as_col_major_mut()?.as_slice_mut(),
        c3.col_mut(0).try_as_col_major_mut()?.as_slice_mut(),
    ])
}

/// Which of Garcia's two period-one gaits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GarciaGait {
    /// The "long period" gait (τ ≈ 3.8–3.9), stable for 0 < γ < ≈0.0151.
    LongPeriod,
    /// The "short period" gait (τ ≈ π), unstable.
    ShortPeriod,
}

/// Coefficients of Garcia's small-slope asymptotics (Garcia 1998 Appendix A.2):
/// `θ* ≈ Θ₀ γ^{1/3} + Θ₁ γ`, `θ̇* ≈ α Θ₀ γ^{1/3} + (α Θ₁ + c₁) γ`,
/// `τ ≈ τ₀ + τ₁ γ^{2/3} + τ₂ γ^{4/3}`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GarciaAsymptotics {
    pub theta0: f64,
    pub theta1: f64,
    pub alpha: f64,
    pub c1: f64,
    pub tau0: f64,
    pub tau1: f64,
    pub tau2: f64,
}

impl GarciaGait {
    /// The published coefficients (their Appendix A.2: Garcia, Chatterjee, Ruina & Coleman,
    /// "The simplest walking model: stability, complexity, and scaling", J. Biomech. Eng. 120
    /// (1998) 281–288).
    pub fn asymptotics(self) -> GarciaAsymptotics {
        match self {
            GarciaGait::LongPeriod => GarciaAsymptotics {
                theta0: 0.970956,
                theta1: -0.270837,
                alpha: -1.045203,
                c1: 1.062895,
                tau0: 3.812092,
                tau1: 1.579129,
                tau2: 0.932019,
            },
            GarciaGait::ShortPeriod => GarciaAsymptotics {
                theta0: 0.943976,
                theta1: -0.264561,
                alpha: -1.090331,
                c1: 0.866610,
                tau0: std::f64::consts::PI,
                tau1: -0.907496,
                tau2: -4.562254,
            },
        }
    }

    /// Asymptotic section state `(θ*, θ̇*)` at slope γ (Garcia 1998 App. A.2).
    pub fn section_guess(self, gamma: f64) -> [f64; 2] {
        let a = self.asymptotics();
        let g13 = gamma.cbrt();
        [
            a.theta0 * g13 + a.theta1 * gamma,
            a.alpha * a.theta0 * g13 + (a.alpha * a.theta1 + a.c1) * gamma,
        ]
    }

    /// Asymptotic step period τ at slope γ (Garcia 1998 App. A.2).
    pub fn period_guess(self, gamma: f64) -> f64 {
        let a = self.asymptotics();
        let g23 = gamma.cbrt().powi(2);
        a.tau0 + a.tau1 * g23 + a.tau2 * g23 * g23
    }
}

impl Simplest {
    /// Builds the model; rejects a slope outside (−π/2, π/2), a non-finite value, or a
    /// non-positive time budget.
    pub fn new(p: SimplestParams) -> Result<Self, WalkerError> {
        let gamma = check_open(
            "slope",
            p.slope,
            -FRAC_PI_2,
            FRAC_PI_2,
            "a finite angle in (-pi/2, pi/2) rad",
        )?;
        let max_stride_time = check_open(
            "max_stride_time",
            p.max_stride_time,
            0.0,
            f64::INFINITY,
            "finite and > 0",
        )?;
        let step_down = check_open(
            "step_down",
            p.step_down,
            -1.0,
            1.0,
            "a finite height in (-1, 1) leg lengths",
        )?;
        Ok(Self {
            params: SimplestParams {
                slope: gamma,
                max_stride_time,
                step_down,
            },
        })
    }

    /// Slope γ (rad).
    pub fn slope(&self) -> f64 {
        self.params.slope
    }

    /// Mechanical energy per unit hip mass, `½ θ̇² + cos(θ − γ)` (units `M g l`); the swing
    /// foot is massless and does not contribute.
    pub fn energy(&self, x: &[f64]) -> f64 {
        0.5 * x[1] * x[1] + (x[0] - self.params.slope).cos()
    }
}

/// The flow Jacobian of [`Simplest`] from the flow `f = rhs1(x)` and its `[cos(θ − γ), sin φ,
/// cos φ]`: rows `(0,1,0,0)`, `(c,0,0,0)`, `(0,0,0,1)`, `(c + s sin φ, 2θ̇ sin φ,
/// (θ̇² − c) cos φ, 0)` with `s = f[1] = sin(θ − γ)`.
fn jacobian_from(x: &[f64], f: &[f64; 4], [c, sp, cp]: [f64; 3], jac: &mut [f64]) {
    let s = f[1];
    jac[..16].fill(0.0);
    jac[1] = 1.0;
    jac[4] = c;
    jac[2 * 4 + 3] = 1.0;
    jac[3 * 4] = c + s * sp;
    jac[3 * 4 + 1] = 2.0 * x[1] * sp;
    jac[3 * 4 + 2] = (x[1] * x[1] - c) * cp;
}

pdw_hybrid::integrate_concretely!(Simplest);
impl HybridSystem for Simplest {
    fn dim(&self) -> usize {
        4
    }

    fn guards(&self, _mode: usize) -> &[GuardSpec] {
        &GUARDS
    }

    #[inline(always)]
    fn flow(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], dx: &mut [f64]) {
        let (f, _) = rhs1(self.params.slope, x);
        dx[..4].copy_from_slice(&f);
    }

    fn flow_batch(&self, _ws: &mut Scratch, _mode: usize, x: MatRef<'_, f64>, dx: MatMut<'_, f64>) {
        let lanes = x.nrows();
        let col = |j: usize| x.col(j).try_as_col_major().map(|c| c.as_slice());
        let (Some(c0), Some(c1), Some(c2), Some(c3)) = (col(0), col(1), col(2), col(3)) else {
            // Non-contiguous columns: per-lane scalar path (same operations, same bits).
            let mut dx = dx;
            let mut xi = [0.0; 4];
            for l in 0..lanes {
                for j in 0..4 {
                    xi[j] = x[(l, j)];
                }
                let (f, _) = rhs1(self.params.slope, &xi);
                for j in 0..4 {
                    dx[(l, j)] = f[j];
                }
            }
            return;
        };
        let cols = [c0, c1, c2, c3];
        let (d01, d23) = dx.split_at_col_mut(2);
        let (d0, d1) = d01.split_at_col_mut(1);
        let (d2, d3) = d23.split_at_col_mut(1);
        let (Some(d0), Some(d1), Some(d2), Some(d3)) = (
            d0.col_mut(0).try_as_col_major_mut(),
            d1.col_mut(0).try_as_col_major_mut(),
            d2.col_mut(0).try_as_col_major_mut(),
            d3.col_mut(0).try_as_col_major_mut(),
        ) else {
            unreachable!("a column of a MatMut with unit row stride is contiguous")
        };
        let out = [
            d0.as_slice_mut(),
            d1.as_slice_mut(),
            d2.as_slice_mut(),
            d3.as_slice_mut(),
        ];
        let [o0, o1, o2, o3] = out;
        let [th, thd, ph, phd] = cols.map(|c| &c[..lanes]);
        let (o0, o1, o2, o3) = (
            &mut o0[..lanes],
            &mut o1[..lanes],
            &mut o2[..lanes],
            &mut o3[..lanes],
        );
        let gamma = self.params.slope;
        // Column loops over lanes, compiled per instruction set (pdw-simd) and vectorised at
        // its full width, in blocks of RHS_BLOCK lanes with one trigonometric choice each
        // (`rhs_block`); every value has the bits of `rhs1` on that lane's state. (Measured
        // and not kept: a choice per group of four lanes, or per lane with the large lanes
        // flagged and recomputed, mispredicts or re-scans wherever walking and falling lanes
        // alternate, as in a basin, and gained nothing there; one choice per call of 256
        // lanes rarely finds a basin's call free of falling lanes.)
        pdw_simd::dispatch(
            #[inline(always)]
            || {
                o0.copy_from_slice(thd);
                o2.copy_from_slice(phd);
                for (((th, thd), ph), (o1, o3)) in th
                    .chunks(RHS_BLOCK)
                    .zip(thd.chunks(RHS_BLOCK))
                    .zip(ph.chunks(RHS_BLOCK))
                    .zip(o1.chunks_mut(RHS_BLOCK).zip(o3.chunks_mut(RHS_BLOCK)))
                {
                    rhs_block(gamma, th, thd, ph, o1, o3);
                }
            },
        );
    }

    fn guard(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64]) -> f64 {
        self.guard_at(ws, mode, k, x, self.params.step_down)
    }

    /// The four guards (linear in the state) and their exact rates `∇g·f`:
    /// `(φ̇ − 2θ̇, θ̈, θ̇, θ̇)` read from `f = (θ̇, θ̈, φ̇, φ̈)`.
    #[inline(always)]
    fn guards_with_rates(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        f: &[f64],
        g: &mut [f64],
        rate: &mut [f64],
    ) {
        self.guards_with_rates_at(ws, mode, x, f, g, rate, self.params.step_down);
    }

    /// [`HybridSystem::guards_with_rates`] as column loops over lanes (same expressions, same
    /// bits per lane).
    fn guards_with_rates_batch(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: MatRef<'_, f64>,
        f: MatRef<'_, f64>,
        g: MatMut<'_, f64>,
        rate: MatMut<'_, f64>,
    ) {
        let lanes = x.nrows();
        fn col(m: MatRef<'_, f64>, j: usize) -> Option<&[f64]> {
            m.col(j).try_as_col_major().map(|c| c.as_slice())
        }
        let (Some(th), Some(thd), Some(ph), Some(f0), Some(f1), Some(f2)) = (
            col(x, 0),
            col(x, 1),
            col(x, 2),
            col(f, 0),
            col(f, 1),
            col(f, 2),
        ) else {
            return pdw_hybrid::guards_with_rates_by_lane(self, ws, mode, x, f, g, rate);
        };
        if g.row_stride() != 1 || rate.row_stride() != 1 {
            return pdw_hybrid::guards_with_rates_by_lane(self, ws, mode, x, f, g, rate);
        }
        let (Some(gc), Some(rc)) = (cols4_mut(g), cols4_mut(rate)) else {
            unreachable!("columns of a view with unit row stride are contiguous")
        };
        let [g0, g1, g2, g3] = gc;
        let [r0, r1, r2, r3] = rc;
        let h = self.params.step_down;
        pdw_simd::dispatch(
            #[inline(always)]
            || {
                for l in 0..lanes {
                    let (gv, rv) = guards_and_rates(h, th[l], thd[l], ph[l], f0[l], f1[l], f2[l]);
                    (g0[l], g1[l], g2[l], g3[l]) = (gv[0], gv[1], gv[2], gv[3]);
                    (r0[l], r1[l], r2[l], r3[l]) = (rv[0], rv[1], rv[2], rv[3]);
                }
            },
        );
    }

    /// All four guards are affine in the state on level ground; the heel strike onto a step is
    /// not.
    fn guard_is_linear(&self, _mode: usize, k: usize) -> bool {
        k != HEEL_STRIKE || self.params.step_down == 0.0
    }

    fn admissible(&self, mode: usize, k: usize, x: &[f64]) -> bool {
        self.admissible_at(mode, k, x, self.params.step_down)
    }

    fn reset(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], out: &mut [f64]) -> usize {
        self.reset_at(ws, mode, k, x, out, self.params.step_down)
    }

    /// Closed form: rows `(0,1,0,0)`, `(c,0,0,0)`, `(0,0,0,1)`,
    /// `(c + s sin φ, 2θ̇ sin φ, (θ̇² − c) cos φ, 0)` with `s, c = sin, cos(θ − γ)`.
    fn flow_jacobian(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], jac: &mut [f64]) {
        let (f, trig) = rhs1(self.params.slope, x);
        jacobian_from(x, &f, trig, jac);
    }

    /// Flow and Jacobian from one evaluation of the sines and cosines.
    fn flow_with_jacobian(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        x: &[f64],
        dx: &mut [f64],
        jac: &mut [f64],
    ) {
        let (f, trig) = rhs1(self.params.slope, x);
        dx[..4].copy_from_slice(&f);
        jacobian_from(x, &f, trig, jac);
    }

    fn guard_gradient(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], grad: &mut [f64]) {
        self.guard_gradient_at(ws, mode, k, x, grad, self.params.step_down)
    }

    /// Closed form derivative of the jump map; only θ⁻ and θ̇⁻ enter (rank 2).
    fn reset_jacobian(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        _k: usize,
        x: &[f64],
        jac: &mut [f64],
    ) {
        if self.params.step_down != 0.0 {
            return step_reset_jacobian(x, jac);
        }
        let (th, thd) = (x[0], x[1]);
        let (s2, c2) = pdw_simd::sincos(2.0 * th);
        jac[..16].fill(0.0);
        jac[0] = -1.0;
        jac[4] = -2.0 * s2 * thd;
        jac[5] = c2;
        jac[8] = -2.0;
        // d/dθ [c2 (1 − c2)] = −2 s2 (1 − c2) + c2 · 2 s2 = 2 s2 (2 c2 − 1)
        jac[12] = 2.0 * s2 * (2.0 * c2 - 1.0) * thd;
        jac[13] = c2 * (1.0 - c2);
    }
}

/// The simplest walker's guards, admissibility and impact at any step height: the model's own
/// (module docs, "Step down"), which its [`HybridSystem`] methods call at its `step_down`.
impl StepHeight for Simplest {
    fn guard_at(&self, _ws: &mut Scratch, _mode: usize, k: usize, x: &[f64], h: f64) -> f64 {
        match k {
            0 if h != 0.0 => step_guard(h, x[0], x[2], 0.0, 0.0).0,
            0 => x[2] - 2.0 * x[0],
            1 => x[1],
            2 => x[0] - FRAC_PI_2,
            _ => x[0] + FRAC_PI_2,
        }
    }

    #[inline(always)]
    fn guards_with_rates_at(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        x: &[f64],
        f: &[f64],
        g: &mut [f64],
        rate: &mut [f64],
        h: f64,
    ) {
        let (gv, rv) = guards_and_rates(h, x[0], x[1], x[2], f[0], f[1], f[2]);
        g[..4].copy_from_slice(&gv);
        rate[..4].copy_from_slice(&rv);
    }

    fn admissible_at(&self, _mode: usize, k: usize, x: &[f64], h: f64) -> bool {
        // Heel strike only with the swing foot ahead of the stance foot (θ < 0 on level ground,
        // sin ψ − sin θ > 0 onto a step); see module docs.
        k != HEEL_STRIKE
            || if h == 0.0 {
                x[0] < 0.0
            } else {
                (x[0] - x[2]).sin() - x[0].sin() > 0.0
            }
    }

    fn reset_at(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        _k: usize,
        x: &[f64],
        out: &mut [f64],
        h: f64,
    ) -> usize {
        let (th, thd) = (x[0], x[1]);
        if h != 0.0 {
            step_reset(x, out);
            return 0;
        }
        // pdw-simd's cosine: the same bits with every libm (shards merge across machines).
        let c2 = pdw_simd::sincos(2.0 * th).1;
        out[0] = -th;
        out[1] = c2 * thd;
        out[2] = -2.0 * th;
        out[3] = c2 * (1.0 - c2) * thd;
        0
    }

    /// Only the heel strike onto a step (`h ≠ 0`) is not affine.
    fn guard_is_linear_at_every_height(&self, _mode: usize, k: usize) -> bool {
        k != HEEL_STRIKE
    }

    fn guard_gradient_at(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        k: usize,
        x: &[f64],
        grad: &mut [f64],
        h: f64,
    ) {
        grad[..4].fill(0.0);
        match k {
            0 if h != 0.0 => {
                // ∂/∂θ, ∂/∂φ of cos(θ − φ) − cos θ − h
                let psi = x[0] - x[2];
                grad[0] = x[0].sin() - psi.sin();
                grad[2] = psi.sin();
            }
            0 => {
                grad[0] = -2.0;
                grad[2] = 1.0;
            }
            1 => grad[1] = 1.0,
            _ => grad[0] = 1.0,
        }
    }
}

impl Section for Simplest {
    fn section_dim(&self) -> usize {
        2
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
        if self.params.step_down != 0.0 {
            return step_lift(self.params.step_down, s, x);
        }
        let c2 = pdw_simd::sincos(2.0 * s[0]).1;
        x[0] = s[0];
        x[1] = s[1];
        x[2] = 2.0 * s[0];
        x[3] = (1.0 - c2) * s[1];
    }
    fn project(&self, x: &[f64], s: &mut [f64]) {
        s[0] = x[0];
        s[1] = x[1];
    }
    fn max_stride_time(&self) -> f64 {
        self.params.max_stride_time
    }
}

impl Walker for Simplest {
    /// θ is absolute (from the slope normal, stance foot ahead positive) and the flow sees only
    /// `θ − γ` (module docs): the world angle `θ − s` of the stance leg is the same in every
    /// line's frame, so θ grows by `s' − s`; φ is relative.
    fn terrain_frame(&self) -> Option<(usize, f64)> {
        Some((0, 1.0))
    }
    /// `φ = θ − ψ`: the swing foot passes the stance foot at `φ = 0` (module docs, "Step down":
    /// ahead means `sin ψ − sin θ > 0`).
    fn legs_together(&self) -> Option<usize> {
        Some(2)
    }
    /// Its strikes onto a step down just after mid-stance can last a few hundredths of a time
    /// unit; the event detection finds them at the extremum of the guard's cubic
    /// (`pdw_hybrid::event`), so the lockstep walk and the walk one walker at a time agree.
    fn step_height(&self) -> Option<&dyn StepHeight> {
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
        "M g l"
    }
    /// Dimensionless (Garcia 1998 §2): time in √(l/g), lengths in leg lengths l, forces per
    /// hip weight M g.
    fn units(&self) -> ModelUnits {
        ModelUnits {
            time: "sqrt(l/g)".into(),
            length: "l".into(),
            force: "M g".into(),
            torque: "M g l".into(),
        }
    }
    fn name(&self) -> &str {
        "simplest"
    }
    fn state_names(&self) -> Vec<String> {
        STATE_NAMES.iter().map(|s| s.to_string()).collect()
    }
    /// Module docs, "Coordinates and signs".
    fn coordinate_meanings(&self) -> Vec<String> {
        [
            "θ: stance-leg angle from the slope normal (rad); positive: stance foot downhill of \
             the hip",
            "θ̇: rate of θ (rad/√(l/g))",
            "φ: angle between the legs, θ − ψ with ψ the swing leg's angle from the slope normal \
             (rad)",
            "φ̇: rate of φ (rad/√(l/g))",
        ]
        .map(String::from)
        .to_vec()
    }
    fn mode_names(&self) -> Vec<String> {
        vec!["single support".into()]
    }
    fn param_values(&self) -> Vec<(String, f64)> {
        self.params.named_values()
    }
    /// Distance between the feet at heel strike, `2 |sin θ⁻|` (leg length 1).
    /// Onto a step, `|sin ψ⁻ − sin θ⁻|` (the swing foot's distance along the slope).
    fn step_length(&self, x_pre: &[f64]) -> f64 {
        if self.params.step_down != 0.0 {
            return ((x_pre[0] - x_pre[2]).sin() - x_pre[0].sin()).abs();
        }
        2.0 * x_pre[0].sin().abs()
    }
    /// Ground reaction on the stance foot per unit hip weight `M g` (the massless legs carry the
    /// hip's force to the foot): `R = a − g` with the hip acceleration
    /// `a = θ̈ (−cos θ, −sin θ) + θ̇² (sin θ, −cos θ)`, `θ̈ = sin(θ − γ)` and gravity
    /// `g = (sin γ, −cos γ)` in the slope frame (module docs). No knees.
    fn constraint_forces(&self, _mode: usize, x: &[f64]) -> Option<ConstraintForces> {
        let (th, thd) = (x[0], x[1]);
        let gamma = self.params.slope;
        let thdd = (th - gamma).sin();
        let (s, c) = th.sin_cos();
        let a = [-thdd * c + thd * thd * s, -thdd * s - thd * thd * c];
        let r = [a[0] - gamma.sin(), a[1] + gamma.cos()];
        Some(ConstraintForces {
            normal: r[1],
            tangential: r[0],
            friction_required: if r[1] > 0.0 {
                (r[0] / r[1]).abs()
            } else {
                f64::INFINITY
            },
            knee_torque: [None, None],
        })
    }
    fn step_flags(&self, mode: usize, x: &[f64]) -> Option<StepFlags> {
        let cf = Walker::constraint_forces(self, mode, x)?;
        let foot = self.pose(x)?.swing_foot?;
        Some(StepFlags::from_state(&cf, foot, 1.0))
    }
    /// Stance foot at the origin, hip `(−sin θ, cos θ)`, swing foot `hip + (sin ψ, −cos ψ)` with
    /// `ψ = θ − φ` (module docs).
    fn pose(&self, x: &[f64]) -> Option<Pose> {
        let (th, ph) = (x[0], x[2]);
        let psi = th - ph;
        let hip = [-th.sin(), th.cos()];
        let foot = [hip[0] + psi.sin(), hip[1] - psi.cos()];
        Some(Pose {
            links: vec![[[0.0, 0.0], hip], [hip, foot]],
            joints: vec![hip],
            swing_foot: Some(foot),
        })
    }
    /// The stance foot, the hip and the swing foot of [`Walker::pose`]; the centre of mass is
    /// the hip (Garcia et al. 1998: massless legs, `m/M → 0`).
    fn body_points(&self, x: &[f64]) -> Option<BodyPoints> {
        let p = self.pose(x)?;
        let (hip, foot) = (p.joints[0], p.swing_foot?);
        Some(BodyPoints {
            names: ["stance_foot", "hip", "swing_foot"]
                .map(String::from)
                .to_vec(),
            points: vec![[0.0, 0.0], hip, foot],
            com: hip,
        })
    }
    /// The model's own units: hip mass `M = 1`, leg length `l = 1`, `g = 1` (time in `√(l/g)`).
    /// Its forces are per unit hip weight `M g` and the legs are massless (`m/M → 0`), so the
    /// total mass is `M` and every relative margin is the raw number (forces already in `M g`,
    /// torques in `M g l`, impulses in `M √(g l)`).
    fn scales(&self) -> Option<Scales> {
        Some(Scales {
            mass: 1.0,
            length: 1.0,
            gravity: 1.0,
        })
    }
    /// `h = cos θ − cos ψ = 2 sin(φ/2) sin((φ − 2θ)/2)`, `ψ = θ − φ` (module docs; leg length 1).
    fn swing_clearance(&self, _mode: usize, x: &[f64]) -> Option<f64> {
        let (th, ph) = (x[0], x[2]);
        Some(2.0 * (0.5 * ph).sin() * (0.5 * (ph - 2.0 * th)).sin())
    }
    /// A straight massless swing leg must pass through the slope at mid-stance: the point-foot
    /// convention of Garcia et al. 1998 (§2, "we ignore this scuffing").
    fn clearance_rule(&self) -> ClearanceRule {
        ClearanceRule::AfterMidStance
    }
    /// The heel strike's impulses per unit `M √(g l)`: the massless new stance leg carries only
    /// an axial impulse, so the ground's impulse on the hip is along that leg and cancels the
    /// hip velocity's component along it (the jump map's conservation of angular momentum
    /// about the new contact; module docs, "Jump map"). With `θ = θ⁻` (the new stance leg at
    /// `e = (sin θ, cos θ)` from its foot, slope frame of the module docs) and hip velocity
    /// `θ̇ (−cos θ, −sin θ)`, `v·e = −θ̇ sin 2θ` and the impulse is `Λ = θ̇ sin 2θ · e`: normal
    /// `Λ_n = θ̇ sin 2θ cos θ` (> 0 for a gait: θ⁻, θ̇⁻ < 0), tangential `Λ_t = θ̇ sin 2θ sin θ`,
    /// friction needed `|tan θ|`, energy lost `½ θ̇² sin² 2θ`. The trailing foot releases; its
    /// separation rate is the rate of the new swing foot's height after the jump map,
    /// `ḣ⁺ = −sin θ⁺ θ̇⁺ + sin ψ⁺ ψ̇⁺` with `ψ = θ − φ`. Onto a step the new leg is at
    /// `e = (sin(φ − θ), cos(φ − θ))` and `2θ` becomes `φ⁻` throughout (module docs, "Step
    /// down").
    fn impact_report(&self, _mode: usize, guard: usize, x: &[f64]) -> Option<ImpactReport> {
        if guard != HEEL_STRIKE {
            return None;
        }
        let (th, thd) = (x[0], x[1]);
        // the inter-leg angle: 2θ⁻ on level ground, φ⁻ onto a step (module docs, "Step down")
        let ph = if self.params.step_down == 0.0 {
            2.0 * th
        } else {
            x[2]
        };
        let a = thd * ph.sin();
        let (ln, lt) = (a * (ph - th).cos(), a * (ph - th).sin());
        let mut post = [0.0; 4];
        self.reset(&mut Scratch::new(), 0, guard, x, &mut post);
        let (psi, psid) = (post[0] - post[2], post[1] - post[3]);
        let rate = -post[0].sin() * post[1] + psi.sin() * psid;
        Some(ImpactReport::point_contact(
            GUARDS[HEEL_STRIKE].name,
            ln,
            lt,
            rate,
            0.5 * a * a,
        ))
    }
    /// Garcia's small-slope asymptotics for both gaits (only meaningful for 0 < γ ≲ 0.015).
    /// `θ` from 0.03 to 0.35 rad and `θ̇` from −0.4 to −0.03 √(g/l) just after heel strike (the
    /// stance leg behind the hip, rolling forward): Garcia et al. 1998's gaits have `θ̇* ≈ −θ*`
    /// with `θ* ≈ 0.97 γ^{1/3}` (App. A.2), from 0.045 at γ = 10⁻⁴ to 0.27 at γ = 0.019, the end
    /// of their walking range — inside this box.
    fn section_box(&self) -> Option<(Vec<f64>, Vec<f64>)> {
        Some((vec![0.03, -0.4], vec![0.35, -0.03]))
    }
    fn gait_guesses(&self) -> Vec<GaitGuess> {
        let g = self.params.slope.max(1e-12);
        vec![
            GaitGuess {
                gait: "stable".into(),
                section: GarciaGait::LongPeriod.section_guess(g).to_vec(),
                source: "Garcia et al. 1998 App. A.2, long-period gait asymptotics".into(),
            },
            GaitGuess {
                gait: "unstable".into(),
                section: GarciaGait::ShortPeriod.section_guess(g).to_vec(),
                source: "Garcia et al. 1998 App. A.2, short-period gait asymptotics".into(),
            },
        ]
    }
}
