//! Hybrid simulation for passive walkers: the [`HybridSystem`] abstraction, Runge–Kutta
//! integrators with dense output and event location, and batched lockstep integration over lanes.
//!
//! - [`Integrator`]: scalar RK4 (fixed step), DOPRI5 and DOP853 (adaptive, Hairer–Nørsett–Wanner
//!   error control), stopping at the earliest admissible directional guard crossing
//!   ([`StopReason::Guard`]), at `t_end`, or on failure. Resets are the caller's business.
//! - [`run_batch`] / [`run_batch_par`]: the same per-lane arithmetic over many lanes in lockstep,
//!   driven by a [`LaneDriver`] that applies resets and decides when a work item is finished;
//!   [`run_scalar`] runs the same driver through [`Integrator`] (the reference path). Per lane
//!   the results are identical bit for bit.
//!
//! # Design decisions
//!
//! - **Methods** (HNW I): RK4 (Table II.1.2); DOPRI5 = Dormand–Prince 5(4) with Shampine's
//!   4th-order dense output (§II.5–II.6); DOP853 with its 7th-order dense output (§II.10).
//!   Error norm: RMS of `err_i / (atol + rtol·max(|x₀ᵢ|, |x₁ᵢ|))` (eq. II.4.11; DOP853 uses the
//!   code's stretched 5th/3rd-order combination). Step control: `h_new = h·clamp(safety·err^(−α)
//!   ·facold^β)` (eq. II.4.13, PI stabilisation β = 0.04 for DOPRI5, β = 0 for DOP853, the codes'
//!   defaults), no growth right after a rejection, `h ≤ h_max`. Starting step: HNW II.4 heuristic.
//! - **Every `integrate` call starts afresh** (first step from `h_init` or the heuristic,
//!   controller memory reset). A call's result depends only on its arguments, which makes runs
//!   deterministic and lets any lane of a batch reproduce the scalar path. The cost is two flow
//!   evaluations and a conservative first step per call (per reset).
//! - **Events** (see [`event`]): guard values and rates at the step ends clear most steps at
//!   once (the guard's cubic over the step cannot reach zero); on the others, guard values at 4
//!   interior points of the step's cubic Hermite interpolant (subdivision, not an extremum
//!   search) detect directional crossings, including a step that straddles two sign changes;
//!   a detected crossing is confirmed
//!   and solved on the method's dense output (Illinois, bracket ≤ 4ε·|t|), and the right-hand end
//!   of the bracket is returned: at a `Guard` stop the guard is on its post-crossing side or zero.
//!   Admissibility is tested at the root; inadmissible crossings are skipped. Terminal guards stop
//!   the same way as reset guards.
//! - **No re-triggering after a reset**: a crossing needs the guard strictly on its pre-crossing
//!   side first. Start values with `|g| ≤` [`HybridSystem::guard_tolerance`] (default 1e-12)
//!   count as 0, so a state placed on a guard surface by a reset (roundoff on either side) and a
//!   restart from a `Guard` stop point cannot report the same event again.
//! - **Batches** (see [`batch`]): column kernels over lanes for stages, error norms and the
//!   end-point event test; `flow_batch` and `guards_with_rates_batch` once per mode (lanes are
//!   kept grouped by mode, moved between groups by row swaps at their events); accept/reject,
//!   interior samples of flagged steps, event refinement and the driver per lane. No allocation
//!   inside the lockstep loop.
//! - **Bit-for-bit equality** of batch and scalar: both run the same kernels (the scalar path is
//!   one lane with stride 1); Rust does not contract `a·b + c` into FMAs, so vectorised and scalar
//!   loops round identically. The only assumption is the trait's: a model's `flow_batch` and
//!   `guards_with_rates_batch` agree bit for bit with `flow` and `guards_with_rates`.

pub mod batch;
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub mod engine;
pub mod error;
pub mod event;
pub mod integrator;
pub mod interrupt;
pub mod options;
pub mod phases;
pub mod system;
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub mod tableau;

pub use batch::{
    run_batch, run_batch_counted, run_batch_par, run_scalar, run_scalar_with, BatchOptions,
    Control, LaneDriver,
};
pub use error::HybridError;
pub use integrator::Integrator;
pub use options::{Controller, Method, Options, Stats, StopReason};
pub use system::{
    guards_with_rates_by_lane, AsSection, Crossing, FallKind, GuardKind, GuardSpec, HybridSystem,
    IntegrateConcrete, Scratch, Section,
};
