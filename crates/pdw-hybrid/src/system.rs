//! The hybrid-system abstraction every walker implements and every integrator consumes.
//!
//! A hybrid system is a set of *modes*; in each mode the state `x ∈ ℝᵈ` follows an autonomous
//! flow `ẋ = f_m(x)`. Each mode has guards `g_k(x)`; when a guard crosses zero in its stated
//! direction *and* its admissibility test holds, the integrator stops (`StopReason::Guard`).
//! The caller then applies the reset map `x⁺ = R_{m,k}(x⁻)` (a separate call) or, for a terminal
//! guard (a fall), ends the trajectory.

use faer::{MatMut, MatRef};
use std::any::Any;

/// A model's scratch space (Pinocchio's `Data`, MuJoCo's `mjData`): the buffers a model needs to
/// evaluate its flow, guards, resets and Jacobians without allocating.
///
/// Callers own one per thread or per batch, created empty ([`Scratch::new`]), and pass it to
/// every call of the [`HybridSystem`] methods; the model fills it with its own buffers on first
/// use ([`Scratch::get_or_init`]) and reuses them afterwards. The model itself stays immutable
/// and is shared by all threads. Models that need no buffers ignore it.
#[derive(Default)]
pub struct Scratch(Option<Box<dyn Any + Send>>);

impl Scratch {
    /// An empty scratch; the first model call that needs buffers fills it.
    pub fn new() -> Self {
        Self(None)
    }

    /// The buffers of type `T` held here, created by `init` when the scratch is empty, holds
    /// another type, or holds a `T` for which `fits` is false (e.g. sized for another model).
    pub fn get_or_init<T: Any + Send>(
        &mut self,
        init: impl FnOnce() -> T,
        fits: impl FnOnce(&T) -> bool,
    ) -> &mut T {
        let ok = matches!(self.0.as_ref().and_then(|b| b.downcast_ref::<T>()), Some(t) if fits(t));
        if !ok {
            self.0 = Some(Box::new(init()));
        }
        match self.0.as_mut().and_then(|b| b.downcast_mut::<T>()) {
            Some(t) => t,
            None => unreachable!("scratch was just set to this type"),
        }
    }
}

impl std::fmt::Debug for Scratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(if self.0.is_some() {
            "Scratch(filled)"
        } else {
            "Scratch(empty)"
        })
    }
}

/// Direction in which a guard function must cross zero to count as an event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Crossing {
    /// g goes from negative to non-negative.
    Rising,
    /// g goes from positive to non-positive.
    Falling,
    /// Either direction.
    Either,
}

/// How a walker falls: the kind a terminal guard carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FallKind {
    /// Falls back, uphill (the stance leg reverses before mid-stance, or the hip reaches the
    /// ground behind the stance foot).
    Backward,
    /// Falls forward (the hip reaches the ground ahead).
    Forward,
    /// The swing foot strikes the ground before the swing knee locked.
    KneeBent,
    /// A rimless wheel rolls back (does not reach the next spoke).
    RollsBack,
    /// A knee of the stance leg buckles: at an impact its hyper-extension stop would have to
    /// pull to hold it straight, so the knee flexes under the walker's weight.
    KneeBuckled,
    /// Any other terminal event (test systems).
    Other,
}

impl FallKind {
    /// A small stable number for the kind (1 backward, 2 forward, 3 knee bent, 4 rolls back,
    /// 5 knee buckled, 0 other), for array outputs.
    pub fn code(self) -> u8 {
        match self {
            FallKind::Other => 0,
            FallKind::Backward => 1,
            FallKind::Forward => 2,
            FallKind::KneeBent => 3,
            FallKind::RollsBack => 4,
            FallKind::KneeBuckled => 5,
        }
    }

    /// Human name, for messages.
    pub fn name(self) -> &'static str {
        match self {
            FallKind::Backward => "fell backward",
            FallKind::Forward => "fell forward",
            FallKind::KneeBent => "swing foot struck the ground before the knee locked",
            FallKind::RollsBack => "rolls back",
            FallKind::KneeBuckled => "stance knee buckled",
            FallKind::Other => "fall",
        }
    }
}

/// What a guard means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GuardKind {
    /// An impact or switch: the caller applies [`HybridSystem::reset`] and continues.
    Reset,
    /// The trajectory ends here (a fall of the given kind).
    Terminal(FallKind),
}

/// Static description of one guard of one mode.
#[derive(Clone, Copy, Debug)]
pub struct GuardSpec {
    /// Short name, e.g. `"heel_strike"`, `"hip_below_ground"`.
    pub name: &'static str,
    pub crossing: Crossing,
    pub kind: GuardKind,
}

/// A hybrid dynamical system with autonomous flows.
///
/// State vectors are plain slices of length [`dim`](HybridSystem::dim). Batched state is a faer
/// matrix of shape `(lanes × dim)`, one column per state component, lanes contiguous in each
/// column (use `col_as_slice`; faer pads the column stride).
pub trait HybridSystem: Send + Sync + IntegrateConcrete {
    /// State dimension d.
    fn dim(&self) -> usize;

    /// Number of leading state components that enter the step-size control (the error norm
    /// and the starting-step heuristic): components `0..error_dim()`. The remaining ones are
    /// integrated on the step sequence those choose; a non-finite value in any component still
    /// rejects the step. Default: all `dim()`. The variational equations can exclude their
    /// tangent columns (pdw-limit's `Variational` with `ErrorControl::State`, as CVODES does
    /// for sensitivities with `errconS` off), so that the state part of the augmented
    /// integration takes exactly the plain integration's steps. Values outside `1..=dim()`
    /// are clamped into it.
    fn error_dim(&self) -> usize {
        self.dim()
    }

    /// Number of modes (default 1).
    fn n_modes(&self) -> usize {
        1
    }

    /// The guards of `mode`, in a fixed order; guard indices refer to this slice.
    fn guards(&self, mode: usize) -> &[GuardSpec];

    /// Vector field: `dx = f_mode(x)`.
    fn flow(&self, ws: &mut Scratch, mode: usize, x: &[f64], dx: &mut [f64]);

    /// Batched vector field over lanes that are all in `mode`: `x`, `dx` are `(lanes × dim)`.
    ///
    /// The default gathers each lane and calls [`flow`](HybridSystem::flow). Models override it
    /// with a vectorised loop; an override must give, per lane, exactly the same bits as `flow`.
    fn flow_batch(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: MatRef<'_, f64>,
        mut dx: MatMut<'_, f64>,
    ) {
        let d = self.dim();
        let lanes = x.nrows();
        let (mut sx, mut sdx) = ([0.0; 16], [0.0; 16]);
        let (mut hx, mut hdx) = (Vec::new(), Vec::new());
        let (xi, dxi): (&mut [f64], &mut [f64]) = if d <= 16 {
            (&mut sx[..d], &mut sdx[..d])
        } else {
            hx.resize(d, 0.0);
            hdx.resize(d, 0.0);
            (&mut hx, &mut hdx)
        };
        for l in 0..lanes {
            for j in 0..d {
                xi[j] = x[(l, j)];
            }
            self.flow(ws, mode, xi, dxi);
            for j in 0..d {
                dx[(l, j)] = dxi[j];
            }
        }
    }

    /// Value of guard `k` of `mode` at `x`.
    fn guard(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64]) -> f64;

    /// Batched guard values over lanes that are all in `mode`: `x` is `(lanes × dim)`,
    /// `out[l] = g_k(x_l)` for every lane.
    ///
    /// The default gathers each lane and calls [`guard`](HybridSystem::guard). An override must
    /// give, per lane, exactly the same bits as `guard`.
    fn guard_batch(
        &self,
        ws: &mut Scratch,
        mode: usize,
        k: usize,
        x: MatRef<'_, f64>,
        out: &mut [f64],
    ) {
        let d = self.dim();
        let mut sx = [0.0; 16];
        let mut hx = Vec::new();
        let xi: &mut [f64] = if d <= 16 {
            &mut sx[..d]
        } else {
            hx.resize(d, 0.0);
            &mut hx
        };
        for (l, o) in out.iter_mut().enumerate().take(x.nrows()) {
            for (j, v) in xi.iter_mut().enumerate() {
                *v = x[(l, j)];
            }
            *o = self.guard(ws, mode, k, xi);
        }
    }

    /// Every guard of `mode` at `x` and its rate of change along the flow: `g[k] = g_k(x)` (the
    /// bits of [`guard`](HybridSystem::guard)) and `rate[k] = ∇g_k(x)·f`, where `f = f(x)` is
    /// the caller's own evaluation of the flow at `x`.
    ///
    /// The integrator uses the rates to decide, from the step's end points alone, that no guard
    /// can cross zero inside a step (see [`event`](crate::event)): only where a guard is near
    /// does it sample the step's interior. The default writes `rate[k] = +∞` ("unknown"), which
    /// makes every step sample its interior, as for a model without rates; models with exact
    /// guard gradients override it (exact rates, or upper bounds of `|ġ|`, are required: an
    /// underestimate can hide a crossing).
    fn guards_with_rates(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        _f: &[f64],
        g: &mut [f64],
        rate: &mut [f64],
    ) {
        for (k, (gk, rk)) in g.iter_mut().zip(rate.iter_mut()).enumerate() {
            *gk = self.guard(ws, mode, k, x);
            *rk = f64::INFINITY;
        }
    }

    /// Is guard `k` of `mode` an affine function of the state (e.g. `φ − 2θ`, a joint angle)?
    ///
    /// On a step that may see a crossing of such a guard, the integrator samples the guard's own
    /// cubic Hermite (from its end values and rates) instead of the guard on the state's
    /// interpolant: for an affine guard the two are the same curve, and the cubic needs no
    /// state. Default `false` (the state is sampled).
    fn guard_is_linear(&self, _mode: usize, _k: usize) -> bool {
        false
    }

    /// Batched [`guards_with_rates`](HybridSystem::guards_with_rates) over lanes that are all in
    /// `mode`: `x` and `f` are `(lanes × dim)`, `g` and `rate` are `(lanes × n_guards)`.
    ///
    /// The default gathers each lane and calls `guards_with_rates`; an override must give, per
    /// lane, exactly the same bits.
    fn guards_with_rates_batch(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: MatRef<'_, f64>,
        f: MatRef<'_, f64>,
        g: MatMut<'_, f64>,
        rate: MatMut<'_, f64>,
    ) {
        guards_with_rates_by_lane(self, ws, mode, x, f, g, rate)
    }

    /// Whether a crossing of guard `k` at `x` counts (e.g. the simplest walker's heel strike only
    /// with the swing foot ahead of the stance foot; the mid-stance scuffing crossing does not).
    fn admissible(&self, _mode: usize, _k: usize, _x: &[f64]) -> bool {
        true
    }

    /// Magnitude below which the value of guard `k` at the *start* of an integration counts as
    /// exactly zero (default `1e-12`, for guards that are O(1) quantities in model units).
    ///
    /// A reset typically places the state on a guard surface (the simplest walker's
    /// `φ − 2θ = 0` right after heel strike), where roundoff leaves the guard a few ulps on
    /// either side. Counting such a start value as zero means a crossing is only reported after
    /// the guard has been seen strictly on its pre-crossing side later in the integration, so
    /// the event just handled cannot fire again at `t₀ + ε`.
    fn guard_tolerance(&self, _mode: usize, _k: usize) -> f64 {
        1e-12
    }

    /// Reset map of guard `k` of `mode`: writes `x⁺` into `out`, returns the new mode.
    /// Only called for guards of kind [`GuardKind::Reset`].
    fn reset(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], out: &mut [f64]) -> usize;

    /// The flow and its Jacobian at one point: `dx = f(x)` as [`flow`](Self::flow) gives it
    /// and `jac = Df(x)` as [`flow_jacobian`](Self::flow_jacobian) gives it, bit for bit. The
    /// variational equations call it at every stage; a model whose Jacobian repeats the flow's
    /// work (its sines and cosines) overrides it to do that work once. Default: the two calls.
    fn flow_with_jacobian(
        &self,
        ws: &mut Scratch,
        mode: usize,
        x: &[f64],
        dx: &mut [f64],
        jac: &mut [f64],
    ) {
        self.flow(ws, mode, x, dx);
        self.flow_jacobian(ws, mode, x, jac);
    }

    /// Jacobian of the flow, `jac[i*d + j] = ∂f_i/∂x_j` (row-major d×d).
    ///
    /// Default: central differences with a step of ε^(1/3)·max(1, |x_j|) (truncation and
    /// roundoff both ~1e-10 relative). Models with closed-form Jacobians override it.
    fn flow_jacobian(&self, ws: &mut Scratch, mode: usize, x: &[f64], jac: &mut [f64]) {
        let d = self.dim();
        let mut xp = x.to_vec();
        let mut fp = vec![0.0; d];
        let mut fm = vec![0.0; d];
        for j in 0..d {
            let h = f64::EPSILON.cbrt() * x[j].abs().max(1.0);
            xp[j] = x[j] + h;
            self.flow(ws, mode, &xp, &mut fp);
            xp[j] = x[j] - h;
            self.flow(ws, mode, &xp, &mut fm);
            xp[j] = x[j];
            for i in 0..d {
                jac[i * d + j] = (fp[i] - fm[i]) / (2.0 * h);
            }
        }
    }

    /// Gradient of guard `k`: `grad[j] = ∂g/∂x_j`. Default: central differences.
    fn guard_gradient(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], grad: &mut [f64]) {
        let mut xp = x.to_vec();
        for j in 0..self.dim() {
            let h = f64::EPSILON.cbrt() * x[j].abs().max(1.0);
            xp[j] = x[j] + h;
            let gp = self.guard(ws, mode, k, &xp);
            xp[j] = x[j] - h;
            let gm = self.guard(ws, mode, k, &xp);
            xp[j] = x[j];
            grad[j] = (gp - gm) / (2.0 * h);
        }
    }

    /// Jacobian of the reset map of guard `k`, row-major d×d. Default: central differences.
    fn reset_jacobian(&self, ws: &mut Scratch, mode: usize, k: usize, x: &[f64], jac: &mut [f64]) {
        let d = self.dim();
        let mut xp = x.to_vec();
        let mut rp = vec![0.0; d];
        let mut rm = vec![0.0; d];
        for j in 0..d {
            let h = f64::EPSILON.cbrt() * x[j].abs().max(1.0);
            xp[j] = x[j] + h;
            self.reset(ws, mode, k, &xp, &mut rp);
            xp[j] = x[j] - h;
            self.reset(ws, mode, k, &xp, &mut rm);
            xp[j] = x[j];
            for i in 0..d {
                jac[i * d + j] = (rp[i] - rm[i]) / (2.0 * h);
            }
        }
    }
}

/// How the scalar integrator's loop reaches a system: compiled for its concrete type, or once
/// for every system through the trait object. The analysis holds its model as `&dyn Section`
/// (one compiled analysis for every model); a virtual call per evaluation of a model's flow
/// could not be inlined into the Runge–Kutta stages, which costs a model with a cheap flow (the
/// simplest walker: a few dozen flops) a third of a stride. Through this trait a trait object
/// pays one virtual call per integrated segment instead, and
/// [`Integrator`](crate::Integrator)'s loop runs on the concrete type.
///
/// Every [`HybridSystem`] implements it with one of two macros, next to its `HybridSystem`
/// impl:
/// - [`integrate_concretely!`](crate::integrate_concretely) — the loop compiled for the type,
///   once, in the crate that invokes the macro (the models of pdw-walkers, the variational
///   system of pdw-limit): the fast path;
/// - [`integrate_through_dyn!`](crate::integrate_through_dyn) — the loop compiled once in
///   pdw-hybrid for `dyn HybridSystem`, every flow and guard call virtual: the same arithmetic
///   and the same bits, at the price of a call per evaluation; for test systems and models
///   whose flow outweighs a call.
///
/// The loop is some 200 kB of machine code; a blanket implementation would compile it again
/// for every type in every crate that makes a trait object of it (Rust shares no generic
/// instantiation between crates in a release build), minutes of every test build.
pub trait IntegrateConcrete {
    /// Runs [`Integrator`](crate::Integrator)'s loop on `self` (see
    /// [`Integrator::integrate`](crate::Integrator::integrate) for the arguments).
    #[doc(hidden)]
    #[allow(clippy::too_many_arguments)]
    fn integrate_concrete(
        &self,
        integ: &mut crate::Integrator,
        mode: usize,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
        resume: bool,
        obs: Option<crate::integrator::Observer<'_>>,
    ) -> crate::StopReason;
}

/// Implements [`IntegrateConcrete`] for the listed types with the integrator's loop compiled
/// for each of them, in the invoking crate (the fast path; see [`IntegrateConcrete`]).
/// `pdw_hybrid::integrate_concretely!(MyModel);`
#[macro_export]
macro_rules! integrate_concretely {
    ($($t:ty),+ $(,)?) => {$( $crate::__integrate_with!(run_concrete, $t); )+};
}

/// Implements [`IntegrateConcrete`] for the listed types through the loop compiled once for
/// `dyn HybridSystem` (see [`IntegrateConcrete`]): no code per type.
/// `pdw_hybrid::integrate_through_dyn!(MyTestSystem);`
#[macro_export]
macro_rules! integrate_through_dyn {
    ($($t:ty),+ $(,)?) => {$( $crate::__integrate_with!(run_dyn, $t); )+};
}

/// The impl behind [`integrate_concretely!`] and [`integrate_through_dyn!`]: `integrate_concrete`
/// forwarding to the integrator's `$run` (never inlined into another crate, so that the
/// instantiation of the loop stays in the crate that invoked the macro).
#[doc(hidden)]
#[macro_export]
macro_rules! __integrate_with {
    ($run:ident, $t:ty) => {
        impl $crate::IntegrateConcrete for $t {
            #[inline(never)]
            fn integrate_concrete(
                &self,
                integ: &mut $crate::Integrator,
                mode: usize,
                t: &mut f64,
                x: &mut [f64],
                t_end: f64,
                resume: bool,
                obs: ::core::option::Option<&mut dyn FnMut(f64, &[f64]) -> bool>,
            ) -> $crate::StopReason {
                integ.$run(self, mode, t, x, t_end, resume, obs)
            }
        }
    };
}

/// A section model seen as `&dyn Section`, whatever its type (a concrete model or a trait object
/// such as `dyn Walker` built on [`Section`]). Implemented for every [`Section`]; the analysis
/// layer takes models through it so that its algorithms are compiled once, for `dyn Section`,
/// and not again for every model type in every crate that calls them.
pub trait AsSection {
    /// `self` as a section trait object.
    fn as_section(&self) -> &dyn Section;
}

impl<T: Section> AsSection for T {
    fn as_section(&self) -> &dyn Section {
        self
    }
}

/// A hybrid system with a Poincaré section: the state just after one designated reset (the
/// heel strike). A *stride* runs from the section to the next firing of that reset, through
/// any intermediate resets (e.g. the kneed walker's knee strike).
pub trait Section: HybridSystem + AsSection {
    /// Dimension of the reduced section coordinates.
    fn section_dim(&self) -> usize;

    /// Names of the reduced coordinates, e.g. `["theta", "thetadot"]`.
    fn section_names(&self) -> &[&'static str];

    /// Mode in which a stride starts (the mode the section reset leads to).
    fn section_mode(&self) -> usize;

    /// `(mode, guard)` whose reset ends a stride.
    fn section_guard(&self) -> (usize, usize);

    /// Full state on the section from reduced coordinates `s` (post-reset state).
    fn lift(&self, s: &[f64], x: &mut [f64]);

    /// Reduced coordinates of a full post-reset state.
    fn project(&self, x: &[f64], s: &mut [f64]);

    /// Upper bound on the duration of one stride (model time units); a stride that takes longer
    /// is a fall of kind "no heel strike in time".
    fn max_stride_time(&self) -> f64;
}

/// [`HybridSystem::guards_with_rates_batch`] lane by lane: gathers each lane of `x` and `f`
/// and calls [`HybridSystem::guards_with_rates`] (the trait's default, and a fallback for
/// models whose vectorised version needs contiguous columns).
pub fn guards_with_rates_by_lane<S: HybridSystem + ?Sized>(
    sys: &S,
    ws: &mut Scratch,
    mode: usize,
    x: MatRef<'_, f64>,
    f: MatRef<'_, f64>,
    mut g: MatMut<'_, f64>,
    mut rate: MatMut<'_, f64>,
) {
    let d = sys.dim();
    let ng = g.ncols();
    const S: usize = 16;
    let (mut sx, mut sf, mut sg, mut sr) = ([0.0; S], [0.0; S], [0.0; S], [0.0; S]);
    let (mut hx, mut hf, mut hg, mut hr) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (xi, fi): (&mut [f64], &mut [f64]) = if d <= S {
        (&mut sx[..d], &mut sf[..d])
    } else {
        hx.resize(d, 0.0);
        hf.resize(d, 0.0);
        (&mut hx, &mut hf)
    };
    let (gi, ri): (&mut [f64], &mut [f64]) = if ng <= S {
        (&mut sg[..ng], &mut sr[..ng])
    } else {
        hg.resize(ng, 0.0);
        hr.resize(ng, 0.0);
        (&mut hg, &mut hr)
    };
    for l in 0..x.nrows() {
        for j in 0..d {
            xi[j] = x[(l, j)];
            fi[j] = f[(l, j)];
        }
        sys.guards_with_rates(ws, mode, xi, fi, gi, ri);
        for k in 0..ng {
            g[(l, k)] = gi[k];
            rate[(l, k)] = ri[k];
        }
    }
}
