//! First-order variational equations of a hybrid system, with the saltation matrix at every
//! event: the exact derivative of the stride map.
//!
//! # Flow
//! The augmented state is `z = (x, Φ)` with `x ∈ ℝᵈ` and `Φ ∈ ℝ^{d×m}` stored row-major after
//! `x` (`z[d + i·m + j] = Φᵢⱼ`). Between events `ẋ = f(x)`, `Φ̇ = Df(x) Φ` (`Df` from
//! [`HybridSystem::flow_jacobian`]), so `Φ(t) = ∂x(t)/∂x(0) · Φ(0)`.
//!
//! # Events: the saltation matrix
//! At an event `g(x⁻) = 0` with reset `x⁺ = R(x⁻)`, a perturbed trajectory `x⁻ + δx` reaches
//! the guard at `t + δt` with `∇g·(δx + f⁻ δt) = 0`, i.e. `δt = −∇g·δx / (∇g·f⁻)`. Comparing
//! both trajectories at the same time after the event gives `δx⁺ = Ξ δx⁻` with the saltation
//! matrix (Aizerman & Gantmacher 1958; Müller 1995, "Calculation of Lyapunov exponents for
//! dynamic systems with discontinuities", Chaos Solitons Fractals 5(9))
//! ```text
//! Ξ = DR + (f⁺ − DR f⁻) ∇gᵀ / (∇g · f⁻),     f⁻ = f(x⁻), f⁺ = f(R(x⁻)) (new mode)
//! ```
//! and `Φ⁺ = Ξ Φ⁻`.
//!
//! # The Poincaré (stride) map
//! The stride map compares the perturbed trajectory's *own* post-event state, at `t + δt`,
//! not the state at the nominal event time: `δx_section = δx⁺ + f⁺ δt`, which removes the
//! `f⁺` term:
//! ```text
//! Ξ_P = DR (I − f⁻ ∇gᵀ / (∇g · f⁻))
//! ```
//! [`Variational::poincare_at`] selects the `(mode, guard)` whose reset ends a stride; that
//! reset uses `Ξ_P`, every other reset (e.g. a knee strike inside a stride) the full `Ξ`.
//! Then `DP = DΠ(x⁺) · Ξ_P · Φ(T⁻) · DL(s)` in section coordinates (lift `L`, projection `Π`).
//!
//! # Error control
//! By default the step-size control sees all of `z` ([`ErrorControl::Full`]). With
//! [`ErrorControl::State`] it sees `x` alone ([`HybridSystem::error_dim`] = `d`), as CVODES
//! does for sensitivities with `errconS` off: the tangent columns ride on the steps the state
//! chooses. Every operation on the state components is then the plain integration's (same
//! stages, same steps, same guard values and event location, same resets), so the `x` part —
//! the stride map `P(s)` — is the plain map's bit for bit (tested); `Φ` carries the local
//! errors of a step sequence chosen for `x`, measured against the fully controlled `Φ` and
//! finite differences in the tests, in experiments/cli-measurements.md (`fixedpoint`) and in
//! experiments/results/benchmarks/README.md.

use pdw_hybrid::{GuardSpec, HybridSystem, Scratch};

/// Which components of `z = (x, Φ)` the step-size control sees.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ErrorControl {
    /// All of `z`: the tangent's local errors bound the steps too.
    #[default]
    Full,
    /// `x` alone: the steps, events and `x` part are the plain integration's, bit for bit.
    State,
}

/// Variational extension of `sys` carrying `m` tangent columns.
pub struct Variational<'a, S: ?Sized> {
    sys: &'a S,
    d: usize,
    m: usize,
    poincare: Option<(usize, usize)>,
    control: ErrorControl,
}

impl<'a, S: HybridSystem + ?Sized> Variational<'a, S> {
    /// Wraps `sys`; the tangent block `Φ` has `m` columns (`m = d` for the full monodromy,
    /// `m = d_s` when `Φ(0) = DL(s)`).
    pub fn new(sys: &'a S, m: usize) -> Self {
        Self {
            sys,
            d: sys.dim(),
            m,
            poincare: None,
            control: ErrorControl::Full,
        }
    }

    /// The components the step-size control sees (see "Error control").
    pub fn error_control(mut self, control: ErrorControl) -> Self {
        self.control = control;
        self
    }

    /// Use the Poincaré-section matrix `Ξ_P` at the reset of `(mode, guard)`.
    pub fn poincare_at(mut self, mode: usize, guard: usize) -> Self {
        self.poincare = Some((mode, guard));
        self
    }

    /// The wrapped system's dimension `d`.
    pub fn base_dim(&self) -> usize {
        self.d
    }

    /// Number of tangent columns `m`.
    pub fn columns(&self) -> usize {
        self.m
    }

    /// Event matrix (row-major `d × d`) of guard `k` of `mode` at the pre-event state `x`
    /// (length `d`): `Ξ` or, when `poincare`, `Ξ_P`. Returns the new mode and writes `x⁺`.
    #[allow(clippy::too_many_arguments)]
    pub fn event_matrix(
        &self,
        ws: &mut Scratch,
        mode: usize,
        k: usize,
        x: &[f64],
        poincare: bool,
        x_plus: &mut [f64],
        xi: &mut [f64],
    ) -> usize {
        let d = self.d;
        let sys = self.sys;
        let new_mode = sys.reset(ws, mode, k, x, x_plus);
        let mut f_minus = vec![0.0; d];
        let mut f_plus = vec![0.0; d];
        let mut grad = vec![0.0; d];
        let mut dr = vec![0.0; d * d];
        sys.flow(ws, mode, x, &mut f_minus);
        sys.flow(ws, new_mode, x_plus, &mut f_plus);
        sys.guard_gradient(ws, mode, k, x, &mut grad);
        sys.reset_jacobian(ws, mode, k, x, &mut dr);
        let denom: f64 = grad.iter().zip(&f_minus).map(|(a, b)| a * b).sum();
        // v = (f⁺ or 0) − DR f⁻
        let mut v = vec![0.0; d];
        for i in 0..d {
            let drf: f64 = (0..d).map(|j| dr[i * d + j] * f_minus[j]).sum();
            v[i] = if poincare { 0.0 } else { f_plus[i] } - drf;
        }
        for i in 0..d {
            for j in 0..d {
                xi[i * d + j] = dr[i * d + j] + v[i] * grad[j] / denom;
            }
        }
        new_mode
    }
}

/// Calls `f` with `n` zeroed values on the stack (up to 64), else on the heap.
#[inline(always)]
fn with_scratch<R>(n: usize, f: impl FnOnce(&mut [f64]) -> R) -> R {
    if n <= 16 {
        f(&mut [0.0; 16][..n])
    } else if n <= 64 {
        f(&mut [0.0; 64][..n])
    } else {
        f(&mut vec![0.0; n])
    }
}

/// The integrator's loop compiled for the variational system (pdw-hybrid's
/// `IntegrateConcrete`): its flow is the model's flow and Jacobian in one pass, inlined into the
/// Runge–Kutta stages. Instantiated where the wrapper is built — `jacobian.rs` for
/// `dyn Section`, once, in this crate.
impl<S: HybridSystem + ?Sized> pdw_hybrid::IntegrateConcrete for Variational<'_, S> {
    #[inline(never)]
    fn integrate_concrete(
        &self,
        integ: &mut pdw_hybrid::Integrator,
        mode: usize,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
        resume: bool,
        obs: Option<&mut dyn FnMut(f64, &[f64]) -> bool>,
    ) -> pdw_hybrid::StopReason {
        integ.run_concrete(self, mode, t, x, t_end, resume, obs)
    }
}

impl<S: HybridSystem + ?Sized> HybridSystem for Variational<'_, S> {
    fn dim(&self) -> usize {
        self.d + self.d * self.m
    }

    fn error_dim(&self) -> usize {
        match self.control {
            ErrorControl::Full => self.dim(),
            ErrorControl::State => self.d,
        }
    }

    fn n_modes(&self) -> usize {
        self.sys.n_modes()
    }

    fn guards(&self, mode: usize) -> &[GuardSpec] {
        self.sys.guards(mode)
    }

    fn flow(&self, ws: &mut Scratch, mode: usize, z: &[f64], dz: &mut [f64]) {
        let (d, m) = (self.d, self.m);
        let (x, phi) = z.split_at(d);
        let (dx, dphi) = dz.split_at_mut(d);
        // The Jacobian in a stack buffer sized to the model: a fixed buffer of 256 values,
        // zeroed at every call, cost as much as the flow of a four-state model.
        with_scratch(d * d, |jac| {
            self.sys.flow_with_jacobian(ws, mode, x, dx, jac);
            for i in 0..d {
                for j in 0..m {
                    let mut acc = 0.0;
                    for k in 0..d {
                        acc += jac[i * d + k] * phi[k * m + j];
                    }
                    dphi[i * m + j] = acc;
                }
            }
        })
    }

    fn guard(&self, ws: &mut Scratch, mode: usize, k: usize, z: &[f64]) -> f64 {
        self.sys.guard(ws, mode, k, &z[..self.d])
    }

    /// The guards depend on `x` alone: their values and rates `ġ = ∇g·ẋ` are the wrapped
    /// system's, from `x` and its derivative `ẋ = f(x)` (the first `d` components of `ż`).
    fn guards_with_rates(
        &self,
        ws: &mut Scratch,
        mode: usize,
        z: &[f64],
        dz: &[f64],
        g: &mut [f64],
        rate: &mut [f64],
    ) {
        let d = self.d;
        self.sys
            .guards_with_rates(ws, mode, &z[..d], &dz[..d], g, rate)
    }

    /// A guard affine in `x` is affine in `z = (x, Φ)`.
    fn guard_is_linear(&self, mode: usize, k: usize) -> bool {
        self.sys.guard_is_linear(mode, k)
    }

    fn guard_tolerance(&self, mode: usize, k: usize) -> f64 {
        self.sys.guard_tolerance(mode, k)
    }

    fn admissible(&self, mode: usize, k: usize, z: &[f64]) -> bool {
        self.sys.admissible(mode, k, &z[..self.d])
    }

    fn reset(&self, ws: &mut Scratch, mode: usize, k: usize, z: &[f64], out: &mut [f64]) -> usize {
        let (d, m) = (self.d, self.m);
        let poincare = self.poincare == Some((mode, k));
        let mut xi = vec![0.0; d * d];
        let (xo, phio) = out.split_at_mut(d);
        let new_mode = self.event_matrix(ws, mode, k, &z[..d], poincare, xo, &mut xi);
        let phi = &z[d..];
        for i in 0..d {
            for j in 0..m {
                phio[i * m + j] = (0..d).map(|l| xi[i * d + l] * phi[l * m + j]).sum();
            }
        }
        new_mode
    }
}
