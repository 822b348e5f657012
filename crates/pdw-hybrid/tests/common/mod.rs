//! Test-local hybrid systems with closed-form solutions.
#![allow(dead_code)]

use faer::{MatMut, MatRef};
use pdw_hybrid::{Crossing, FallKind, GuardKind, GuardSpec, HybridSystem, Scratch};

/// Harmonic oscillator `q̇ = p, ṗ = −q` (exact: `q = q₀ cos t + p₀ sin t`) with configurable
/// guards `g_k = q − level_k`, optionally admissible only when `p` has a given sign.
pub struct Oscillator {
    pub guards: Vec<GuardSpec>,
    pub levels: Vec<f64>,
    /// `Some(s)`: guard k admissible only if `s·p > 0`.
    pub admit_sign: Vec<Option<f64>>,
    /// `Some(linear)`: the guards give their exact rates `ġ = p` and are declared affine or
    /// not; `None`: no rates (the default `+∞`, every step sampled).
    pub rates: Option<bool>,
}

impl Oscillator {
    pub fn new(spec: &[(f64, Crossing, Option<f64>)]) -> Self {
        Self {
            guards: spec
                .iter()
                .map(|&(_, c, _)| GuardSpec {
                    name: "q_level",
                    crossing: c,
                    kind: GuardKind::Reset,
                })
                .collect(),
            levels: spec.iter().map(|s| s.0).collect(),
            admit_sign: spec.iter().map(|s| s.2).collect(),
            rates: None,
        }
    }
    /// The same guards with their exact rates, declared affine when `linear`.
    pub fn with_rates(mut self, linear: bool) -> Self {
        self.rates = Some(linear);
        self
    }
    pub fn exact(q0: f64, p0: f64, t: f64) -> [f64; 2] {
        [q0 * t.cos() + p0 * t.sin(), -q0 * t.sin() + p0 * t.cos()]
    }
}

pdw_hybrid::integrate_through_dyn!(Oscillator);
impl HybridSystem for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn guards(&self, _mode: usize) -> &[GuardSpec] {
        &self.guards
    }
    fn flow(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], dx: &mut [f64]) {
        dx[0] = x[1];
        dx[1] = -x[0];
    }
    fn guard(&self, _ws: &mut Scratch, _mode: usize, k: usize, x: &[f64]) -> f64 {
        x[0] - self.levels[k]
    }
    fn admissible(&self, _mode: usize, k: usize, x: &[f64]) -> bool {
        self.admit_sign[k].is_none_or(|s| s * x[1] > 0.0)
    }
    fn guards_with_rates(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        x: &[f64],
        f: &[f64],
        g: &mut [f64],
        rate: &mut [f64],
    ) {
        for (k, (gk, rk)) in g.iter_mut().zip(rate.iter_mut()).enumerate() {
            *gk = x[0] - self.levels[k];
            *rk = if self.rates.is_some() {
                f[0]
            } else {
                f64::INFINITY
            };
        }
    }
    fn guard_is_linear(&self, _mode: usize, _k: usize) -> bool {
        self.rates == Some(true)
    }
    fn reset(
        &self,
        _ws: &mut Scratch,
        mode: usize,
        _k: usize,
        x: &[f64],
        out: &mut [f64],
    ) -> usize {
        out.copy_from_slice(x);
        mode
    }
}

/// A nonlinear autonomous test problem with a known solution, for convergence orders:
/// `q̇ = p, ṗ = −q, ẏ = −y²` from (1, 0, 1): exact `(cos t, −sin t, 1/(1 + t))`.
pub struct OscGrowth;

impl OscGrowth {
    pub fn exact(t: f64) -> [f64; 3] {
        [t.cos(), -t.sin(), 1.0 / (1.0 + t)]
    }
}

pdw_hybrid::integrate_through_dyn!(OscGrowth);
impl HybridSystem for OscGrowth {
    fn dim(&self) -> usize {
        3
    }
    fn guards(&self, _mode: usize) -> &[GuardSpec] {
        &[]
    }
    fn flow(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], dx: &mut [f64]) {
        dx[0] = x[1];
        dx[1] = -x[0];
        dx[2] = -x[2] * x[2];
    }
    fn guard(&self, _ws: &mut Scratch, _mode: usize, _k: usize, _x: &[f64]) -> f64 {
        0.0
    }
    fn reset(
        &self,
        _ws: &mut Scratch,
        mode: usize,
        _k: usize,
        x: &[f64],
        out: &mut [f64],
    ) -> usize {
        out.copy_from_slice(x);
        mode
    }
}

/// Pendulum `θ̈ = −sin θ`, state (θ, ω); guard θ = 0 falling (the swing through the bottom).
/// Energy `E = ω²/2 − cos θ`.
pub struct Pendulum;

pub const PENDULUM_GUARDS: [GuardSpec; 1] = [GuardSpec {
    name: "bottom",
    crossing: Crossing::Falling,
    kind: GuardKind::Reset,
}];

impl Pendulum {
    pub fn energy(x: &[f64]) -> f64 {
        0.5 * x[1] * x[1] - x[0].cos()
    }
    /// Complete elliptic integral of the first kind K(m = k²) by the arithmetic–geometric mean:
    /// K = π / (2·AGM(1, √(1−k²))) (Abramowitz & Stegun 17.6).
    pub fn ellip_k(k: f64) -> f64 {
        let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
        for _ in 0..60 {
            let an = 0.5 * (a + b);
            let bn = (a * b).sqrt();
            a = an;
            b = bn;
        }
        std::f64::consts::PI / (2.0 * a)
    }
}

pdw_hybrid::integrate_through_dyn!(Pendulum);
impl HybridSystem for Pendulum {
    fn dim(&self) -> usize {
        2
    }
    fn guards(&self, _mode: usize) -> &[GuardSpec] {
        &PENDULUM_GUARDS
    }
    fn flow(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], dx: &mut [f64]) {
        dx[0] = x[1];
        dx[1] = -x[0].sin();
    }
    fn guard(&self, _ws: &mut Scratch, _mode: usize, _k: usize, x: &[f64]) -> f64 {
        x[0]
    }
    fn reset(
        &self,
        _ws: &mut Scratch,
        mode: usize,
        _k: usize,
        x: &[f64],
        out: &mut [f64],
    ) -> usize {
        out.copy_from_slice(x);
        mode
    }
}

/// Bouncing ball, state (height y, velocity v), gravity `g`, restitution `e`:
/// mode 0 = flight (`ẏ = v, v̇ = −g`), guard 0: `y` falling → reset `v ← −e v`;
/// guard 1 (terminal, code 7): `v − v_min` falling (the ball has come to rest, never reached in
/// the tests unless asked).
pub struct Ball {
    pub g: f64,
    pub e: f64,
}

pub const BALL_GUARDS: [GuardSpec; 1] = [GuardSpec {
    name: "ground",
    crossing: Crossing::Falling,
    kind: GuardKind::Reset,
}];

pdw_hybrid::integrate_through_dyn!(Ball);
impl HybridSystem for Ball {
    fn dim(&self) -> usize {
        2
    }
    fn guards(&self, _mode: usize) -> &[GuardSpec] {
        &BALL_GUARDS
    }
    fn flow(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], dx: &mut [f64]) {
        dx[0] = x[1];
        dx[1] = -self.g;
    }
    fn guard(&self, _ws: &mut Scratch, _mode: usize, _k: usize, x: &[f64]) -> f64 {
        x[0]
    }
    fn reset(
        &self,
        _ws: &mut Scratch,
        mode: usize,
        _k: usize,
        x: &[f64],
        out: &mut [f64],
    ) -> usize {
        out[0] = x[0];
        out[1] = -self.e * x[1];
        mode
    }
}

/// Two-mode ball on a soft floor: mode 0 = flight (`ÿ = −g`), guard `y` falling → mode 1;
/// mode 1 = contact with a nonlinear spring (`ÿ = −g − k·y − c·y³`), guard `y` rising → mode 0.
/// The resets are identities: only the mode changes. `flow_batch` is a column loop (as a real
/// model's would be), exercising row-range views.
pub struct SoftBall {
    pub g: f64,
    pub k: f64,
    pub c: f64,
}

pub const SOFT_GUARDS_AIR: [GuardSpec; 1] = [GuardSpec {
    name: "touch",
    crossing: Crossing::Falling,
    kind: GuardKind::Reset,
}];
pub const SOFT_GUARDS_CONTACT: [GuardSpec; 2] = [
    GuardSpec {
        name: "lift_off",
        crossing: Crossing::Rising,
        kind: GuardKind::Reset,
    },
    GuardSpec {
        name: "too_deep",
        crossing: Crossing::Falling,
        kind: GuardKind::Terminal(FallKind::Other),
    },
];

impl SoftBall {
    fn acc(&self, mode: usize, y: f64) -> f64 {
        if mode == 0 {
            -self.g
        } else {
            -self.g - self.k * y - self.c * y * y * y
        }
    }
}

pdw_hybrid::integrate_through_dyn!(SoftBall);
impl HybridSystem for SoftBall {
    fn dim(&self) -> usize {
        2
    }
    fn n_modes(&self) -> usize {
        2
    }
    fn guards(&self, mode: usize) -> &[GuardSpec] {
        if mode == 0 {
            &SOFT_GUARDS_AIR
        } else {
            &SOFT_GUARDS_CONTACT
        }
    }
    fn flow(&self, _ws: &mut Scratch, mode: usize, x: &[f64], dx: &mut [f64]) {
        dx[0] = x[1];
        dx[1] = self.acc(mode, x[0]);
    }
    fn flow_batch(
        &self,
        _ws: &mut Scratch,
        mode: usize,
        x: MatRef<'_, f64>,
        mut dx: MatMut<'_, f64>,
    ) {
        let n = x.nrows();
        let y = x.col(0).try_as_col_major().unwrap().as_slice();
        let v = x.col(1).try_as_col_major().unwrap().as_slice();
        {
            let dy = dx
                .as_mut()
                .col_mut(0)
                .try_as_col_major_mut()
                .unwrap()
                .as_slice_mut();
            dy[..n].copy_from_slice(&v[..n]);
        }
        let dv = dx.col_mut(1).try_as_col_major_mut().unwrap().as_slice_mut();
        for l in 0..n {
            dv[l] = self.acc(mode, y[l]);
        }
    }
    fn guard(&self, _ws: &mut Scratch, mode: usize, k: usize, x: &[f64]) -> f64 {
        if mode == 0 || k == 0 {
            x[0]
        } else {
            x[0] + 0.5
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
        out.copy_from_slice(x);
        1 - mode
    }
}

/// `ẋ = x²` (exact `x = x₀/(1 − x₀ t)`, blows up at `t = 1/x₀`).
pub struct BlowUp;

pdw_hybrid::integrate_through_dyn!(BlowUp);
impl HybridSystem for BlowUp {
    fn dim(&self) -> usize {
        1
    }
    fn guards(&self, _mode: usize) -> &[GuardSpec] {
        &[]
    }
    fn flow(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], dx: &mut [f64]) {
        dx[0] = x[0] * x[0];
    }
    fn guard(&self, _ws: &mut Scratch, _mode: usize, _k: usize, _x: &[f64]) -> f64 {
        0.0
    }
    fn reset(
        &self,
        _ws: &mut Scratch,
        mode: usize,
        _k: usize,
        x: &[f64],
        out: &mut [f64],
    ) -> usize {
        out.copy_from_slice(x);
        mode
    }
}

/// `ẋ = 1` on `x ≤ 1.5`, NaN beyond: the flow leaves its domain at `t = 1.5 − x₀`.
pub struct Cliff;

pdw_hybrid::integrate_through_dyn!(Cliff);
impl HybridSystem for Cliff {
    fn dim(&self) -> usize {
        1
    }
    fn guards(&self, _mode: usize) -> &[GuardSpec] {
        &[]
    }
    fn flow(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], dx: &mut [f64]) {
        dx[0] = if x[0] <= 1.5 { 1.0 } else { f64::NAN };
    }
    fn guard(&self, _ws: &mut Scratch, _mode: usize, _k: usize, _x: &[f64]) -> f64 {
        0.0
    }
    fn reset(
        &self,
        _ws: &mut Scratch,
        mode: usize,
        _k: usize,
        x: &[f64],
        out: &mut [f64],
    ) -> usize {
        out.copy_from_slice(x);
        mode
    }
}

/// Least-squares slope of `ys` against `xs`.
pub fn slope(xs: &[f64], ys: &[f64]) -> f64 {
    let n = xs.len() as f64;
    let mx = xs.iter().sum::<f64>() / n;
    let my = ys.iter().sum::<f64>() / n;
    let sxy: f64 = xs.iter().zip(ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}
