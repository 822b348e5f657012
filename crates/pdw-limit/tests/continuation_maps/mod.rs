//! A hybrid system whose stride map is a given map `F(s; μ)` exactly: state `(s, τ)`, flow
//! `ṡ = 0, τ̇ = 1`, one guard `τ − 1` (rising) whose reset is `(s, τ) ↦ (F(s; μ), 0)`. Every
//! Runge–Kutta method integrates this flow exactly, so fixed points, multipliers and
//! bifurcations of the "walker" are those of the map — known in closed form.

#![allow(dead_code)]

use faer::{MatMut, MatRef};
use pdw_hybrid::{Crossing, GuardKind, GuardSpec, HybridSystem, Scratch, Section};

/// `F(s; μ)` into `out`.
pub type MapFn = fn(&[f64], f64, &mut [f64]);
/// `DF(s; μ)` row-major into `out`.
pub type MapJac = fn(&[f64], f64, &mut [f64]);

pub struct MapSystem {
    pub n: usize,
    pub mu: f64,
    pub f: MapFn,
    pub jac: MapJac,
}

const GUARDS: [GuardSpec; 1] = [GuardSpec {
    name: "tick",
    crossing: Crossing::Rising,
    kind: GuardKind::Reset,
}];
const NAMES: [&str; 3] = ["s0", "s1", "s2"];

pdw_hybrid::integrate_through_dyn!(MapSystem);
impl HybridSystem for MapSystem {
    fn dim(&self) -> usize {
        self.n + 1
    }
    fn guards(&self, _mode: usize) -> &[GuardSpec] {
        &GUARDS
    }
    fn flow(&self, _ws: &mut Scratch, _mode: usize, _x: &[f64], dx: &mut [f64]) {
        dx.fill(0.0);
        dx[self.n] = 1.0;
    }
    fn flow_batch(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        _x: MatRef<'_, f64>,
        mut dx: MatMut<'_, f64>,
    ) {
        for l in 0..dx.nrows() {
            for j in 0..self.n {
                dx[(l, j)] = 0.0;
            }
            dx[(l, self.n)] = 1.0;
        }
    }
    fn guard(&self, _ws: &mut Scratch, _mode: usize, _k: usize, x: &[f64]) -> f64 {
        x[self.n] - 1.0
    }
    fn reset(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        _k: usize,
        x: &[f64],
        out: &mut [f64],
    ) -> usize {
        (self.f)(&x[..self.n], self.mu, &mut out[..self.n]);
        out[self.n] = 0.0;
        0
    }
    fn flow_jacobian(&self, _ws: &mut Scratch, _mode: usize, _x: &[f64], jac: &mut [f64]) {
        jac.fill(0.0);
    }
    fn guard_gradient(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        _k: usize,
        _x: &[f64],
        grad: &mut [f64],
    ) {
        grad.fill(0.0);
        grad[self.n] = 1.0;
    }
    fn reset_jacobian(
        &self,
        _ws: &mut Scratch,
        _mode: usize,
        _k: usize,
        x: &[f64],
        jac: &mut [f64],
    ) {
        let (n, d) = (self.n, self.n + 1);
        let mut df = vec![0.0; n * n];
        (self.jac)(&x[..n], self.mu, &mut df);
        jac.fill(0.0);
        for i in 0..n {
            for j in 0..n {
                jac[i * d + j] = df[i * n + j];
            }
        }
    }
}

impl Section for MapSystem {
    fn section_dim(&self) -> usize {
        self.n
    }
    fn section_names(&self) -> &[&'static str] {
        &NAMES[..self.n]
    }
    fn section_mode(&self) -> usize {
        0
    }
    fn section_guard(&self) -> (usize, usize) {
        (0, 0)
    }
    fn lift(&self, s: &[f64], x: &mut [f64]) {
        x[..self.n].copy_from_slice(s);
        x[self.n] = 0.0;
    }
    fn project(&self, x: &[f64], s: &mut [f64]) {
        s.copy_from_slice(&x[..self.n]);
    }
    fn max_stride_time(&self) -> f64 {
        2.0
    }
}

/// Logistic map `x ↦ μ x (1 − x)`: fixed point `1 − 1/μ` with multiplier `2 − μ`; period
/// doublings at μ = 3, 1 + √6, … (the Feigenbaum cascade).
pub fn logistic(mu: f64) -> Result<Box<MapSystem>, String> {
    Ok(Box::new(MapSystem {
        n: 1,
        mu,
        f: |s, mu, o| o[0] = mu * s[0] * (1.0 - s[0]),
        jac: |s, mu, o| o[0] = mu * (1.0 - 2.0 * s[0]),
    }))
}

/// Saddle-node family `x ↦ x + μ − x²`: fixed points `±√μ` (multipliers `1 ∓ 2√μ`) for μ > 0,
/// none for μ < 0; a fold at μ = 0.
pub fn saddle_node(mu: f64) -> Result<Box<MapSystem>, String> {
    Ok(Box::new(MapSystem {
        n: 1,
        mu,
        f: |s, mu, o| o[0] = s[0] + mu - s[0] * s[0],
        jac: |s, _mu, o| o[0] = 1.0 - 2.0 * s[0],
    }))
}

/// Rotation angle of the Neimark–Sacker normal-form map.
pub const NS_OMEGA: f64 = 0.7;

/// `z ↦ e^{iω} z ((1 + μ) − |z|²)` in real coordinates: the origin is a fixed point for every μ
/// with multipliers `(1 + μ) e^{±iω}`; a Neimark–Sacker bifurcation at μ = 0.
pub fn neimark_sacker(mu: f64) -> Result<Box<MapSystem>, String> {
    Ok(Box::new(MapSystem {
        n: 2,
        mu,
        f: |s, mu, o| {
            let (c, sn) = (NS_OMEGA.cos(), NS_OMEGA.sin());
            let a = 1.0 + mu - (s[0] * s[0] + s[1] * s[1]);
            o[0] = a * (c * s[0] - sn * s[1]);
            o[1] = a * (sn * s[0] + c * s[1]);
        },
        jac: |s, mu, o| {
            let (c, sn) = (NS_OMEGA.cos(), NS_OMEGA.sin());
            let r2 = s[0] * s[0] + s[1] * s[1];
            let a = 1.0 + mu - r2;
            let (u, v) = (c * s[0] - sn * s[1], sn * s[0] + c * s[1]);
            o[0] = a * c - 2.0 * s[0] * u;
            o[1] = -a * sn - 2.0 * s[1] * u;
            o[2] = a * sn - 2.0 * s[0] * v;
            o[3] = a * c - 2.0 * s[1] * v;
        },
    }))
}
