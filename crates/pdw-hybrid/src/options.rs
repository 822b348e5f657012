//! Integrator options, stop reasons and counters.

// `!(a > b)` is deliberate: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::HybridError;

/// Integration method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// Classical fixed-step RK4 with step `h` (the last step is shortened to hit `t_end`);
    /// events are located on the cubic Hermite interpolant of the step.
    Rk4 { h: f64 },
    /// Dormand–Prince 5(4), adaptive, 4th-order dense output (HNW I, §II.5–II.6).
    Dopri5,
    /// Dormand–Prince 8(5,3), adaptive, 7th-order dense output (HNW I, §II.10).
    Dop853,
}

/// Integrator options. Build with [`Options::dopri5`], [`Options::dop853`] or [`Options::rk4`]
/// and adjust fields; [`Options::validate`] is called by every constructor that takes options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    pub method: Method,
    /// Relative tolerance of the mixed error test `|err_i| ≤ atol + rtol·max(|x₀ᵢ|, |x₁ᵢ|)`.
    pub rtol: f64,
    /// Absolute tolerance (same units as the state components).
    pub atol: f64,
    /// First step of every `integrate` call; `None` = the HNW II.4 starting-step heuristic.
    pub h_init: Option<f64>,
    /// A segment that continues the same trajectory after a stop — the batched runner's
    /// [`Control::Continue`](crate::Control::Continue), the scalar
    /// [`Integrator::resume`](crate::Integrator::resume) — starts with the step the controller
    /// proposed when the previous segment stopped, instead of the starting-step heuristic
    /// (`h_init` takes precedence). Default `false`.
    ///
    /// It pays where a reset leaves the motion on its time scale: the strides of a walker (on
    /// the simplest walker at 1e-9 it saves two of the ten step attempts of every stride after
    /// the first — the heuristic's small first step and the rejection that follows the
    /// controller's largest growth factor), which is why
    /// `pdw_limit::BasinOptions::default_integrator` turns it on. It costs where a reset
    /// switches time scales — a soft contact after a flight phase: the flight's long step is
    /// rejected several times at touch-down (tested on the soft ball, where it takes more step
    /// attempts than the heuristic).
    pub warm_restart: bool,
    /// Step-size controller of DOPRI5 (DOP853's own is elementary either way; RK4 has none).
    /// Default [`Controller::Pi`], the code dopri5's.
    pub controller: Controller,
    /// Largest step (time units); `f64::INFINITY` for no limit.
    pub h_max: f64,
    /// A proposed step below `h_min` stops the integration with `StepTooSmall`.
    pub h_min: f64,
    /// Largest number of step attempts (accepted + rejected) per `integrate` call.
    pub max_steps: usize,
}

/// Step-size controller of DOPRI5 (HNW I eq. II.4.13 and §IV.2): `h_new = h·fac` with
/// `fac = 0.9·err^(−α)·facold^β`, clamped to `[0.2, 10]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Controller {
    /// The PI controller of the code dopri5 (its defaults: β = 0.04, α = 1/5 − 0.75β = 0.17):
    /// smoother step sequences, a few per cent more steps.
    #[default]
    Pi,
    /// The elementary controller (β = 0, α = 1/5), as MATLAB's `ode45` and SciPy's `RK45` use.
    Elementary,
}

impl Options {
    fn adaptive(method: Method, tol: f64) -> Self {
        Self {
            method,
            rtol: tol,
            atol: tol,
            h_init: None,
            warm_restart: false,
            controller: Controller::Pi,
            h_max: f64::INFINITY,
            h_min: 0.0,
            max_steps: 100_000,
        }
    }

    /// DOPRI5 with `rtol = atol = tol`.
    pub fn dopri5(tol: f64) -> Self {
        Self::adaptive(Method::Dopri5, tol)
    }

    /// DOP853 with `rtol = atol = tol`.
    pub fn dop853(tol: f64) -> Self {
        Self::adaptive(Method::Dop853, tol)
    }

    /// Fixed-step RK4 with step `h` (tolerances unused).
    pub fn rk4(h: f64) -> Self {
        Self {
            method: Method::Rk4 { h },
            rtol: 0.0,
            atol: 0.0,
            h_init: None,
            warm_restart: false,
            controller: Controller::Pi,
            h_max: f64::INFINITY,
            h_min: 0.0,
            max_steps: usize::MAX,
        }
    }

    /// Reject values the integrator cannot honour.
    pub fn validate(&self) -> Result<(), HybridError> {
        let bad = |name, value, allowed| {
            Err(HybridError::InvalidOption {
                name,
                value,
                allowed,
            })
        };
        match self.method {
            Method::Rk4 { h } => {
                if !(h.is_finite() && h > 0.0) {
                    return bad("h", h, "the RK4 step must be finite and > 0");
                }
            }
            Method::Dopri5 | Method::Dop853 => {
                if !(self.rtol.is_finite() && self.rtol >= 0.0) {
                    return bad("rtol", self.rtol, "must be finite and >= 0");
                }
                if self.rtol > 0.0 && self.rtol < 10.0 * f64::EPSILON {
                    return bad("rtol", self.rtol, "must be 0 or >= 10·ε ≈ 2.2e-15");
                }
                // atol > 0 keeps the weights atol + rtol·|x| positive where a component is 0.
                if !(self.atol.is_finite() && self.atol > 0.0) {
                    return bad("atol", self.atol, "must be finite and > 0");
                }
                if let Some(h) = self.h_init {
                    if !(h.is_finite() && h > 0.0) {
                        return bad("h_init", h, "must be finite and > 0");
                    }
                }
            }
        }
        if self.h_max.is_nan() || self.h_max <= 0.0 {
            return bad(
                "h_max",
                self.h_max,
                "must be > 0 (f64::INFINITY for no limit)",
            );
        }
        if !(self.h_min.is_finite() && self.h_min >= 0.0 && self.h_min < self.h_max) {
            return bad("h_min", self.h_min, "must be finite, >= 0 and < h_max");
        }
        if self.max_steps == 0 {
            return bad("max_steps", 0.0, "must be >= 1");
        }
        Ok(())
    }
}

/// Why an integration stopped. `t` and `x` always hold a valid (finite) point of the trajectory.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StopReason {
    /// Guard `guard` of the current mode crossed zero in its direction and was admissible;
    /// `(t, x)` is the event point (pre-reset), with the guard on its post-crossing side or zero.
    Guard { guard: usize },
    /// `t` reached `t_end`.
    EndTime,
    /// The flow or the state became non-finite and no smaller step avoided it; `(t, x)` is the
    /// last finite accepted point.
    NonFinite,
    /// The step size fell below `h_min` or below the resolution of `t` (HNW: 0.1·|h| ≤ ε·|t|).
    StepTooSmall,
    /// `max_steps` step attempts in one call.
    MaxSteps,
}

/// Why an integration stopped, in plain words (for messages).
impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StopReason::Guard { guard } => write!(f, "guard {guard} crossed zero"),
            StopReason::EndTime => f.write_str("the end time was reached"),
            StopReason::NonFinite => f.write_str("the state became non-finite"),
            StopReason::StepTooSmall => f.write_str("the step size became too small"),
            StopReason::MaxSteps => f.write_str("the most steps in one call were taken"),
        }
    }
}

/// Work counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Accepted steps.
    pub accepted: u64,
    /// Rejected step attempts.
    pub rejected: u64,
    /// Right-hand-side (flow) evaluations, lane by lane.
    pub rhs_evals: u64,
    /// Accepted steps whose interior was sampled for guard crossings (the others were cleared
    /// from their end points alone, see [`event`](crate::event)).
    pub sampled: u64,
}

impl std::ops::AddAssign for Stats {
    fn add_assign(&mut self, o: Self) {
        self.accepted += o.accepted;
        self.rejected += o.rejected;
        self.rhs_evals += o.rhs_evals;
        self.sampled += o.sampled;
    }
}
