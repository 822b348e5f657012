//! Event location on an accepted step `[t₀, t₁]`, `h = t₁ − t₀`, parametrised by `θ ∈ [0, 1]`.
//!
//! **Detection.** Every guard `g_k` of the mode is evaluated at the step's end points (exact
//! states x₀, x₁) together with its rate along the flow `ġ = ∇g·f`
//! ([`HybridSystem::guards_with_rates`], column-wise over lanes in a batch). From these four
//! numbers alone a column kernel decides whether the guard can show a crossing inside the step
//! (`may_cross`: the guard's cubic Hermite over the step, bounded by the convex hull of its
//! Bernstein control points, stays away from zero). Most steps of most guards are cleared
//! there. A flagged step is then cleared after all when its cubic rules out a crossing in the
//! guard's direction (`clears_direction`: it starts on the guard after a reset and moves
//! away, or crosses the other way), so that a stride samples only the step of its heel strike.
//! For a flagged guard the interior is sampled at [`N_SAMPLES`] = 4 points `θ = i/5` of
//! the step's cubic Hermite interpolant built from `(x₀, f(x₀), x₁, f(x₁))` — the guard on the
//! interpolated state, or, for a guard the model declares affine
//! ([`HybridSystem::guard_is_linear`]), the guard's own cubic from its end values and rates,
//! which is the same curve and needs no state. A model without rates (`+∞`, the default)
//! samples every step, as before the end-point test existed; the test never clears a step whose
//! samples would show a crossing (tested on random cubics, and stride by stride against a
//! model without rates), so events and their bits do not depend on it.
//! A *directional crossing* on a sub-interval `[θ_a, θ_b]` means: the left value is strictly on
//! the pre-crossing side and the right value is on the post-crossing side or zero (`Rising`:
//! `g_a < 0 ≤ g_b`; `Falling`: `g_a > 0 ≥ g_b`; `Either`: one of the two). Sampling the
//! interior catches a step that straddles two sign changes (the guard dips across zero and
//! back, ends on the same side) as long as the dip spans one of the five sub-intervals. A
//! window narrower than that — both crossings between two samples — is found where the model
//! gives the guard's rates: when no sample shows a crossing, the guard is also evaluated at each
//! interior extremum of its cubic from end values and rates that comes within the margin of the
//! crossing side (`probe_extrema`), and a crossing from the sample before that extremum to it is
//! refined like the others (the simplest walker's swing foot reaching a lower foothold for a few
//! hundredths of a stride on a step of 0.4). Without rates such a window is not resolved, and a
//! dip shallower than the Hermite interpolation error (O(h⁴), about the local error tolerance)
//! can be missed by the detection — a grazing contact of that depth is below the resolution of
//! the integration anyway.
//!
//! **Confirmation and refinement.** If any sub-interval shows a crossing, the method's own dense
//! output is built (RK4: the Hermite cubic itself; DOPRI5: Shampine's 4th-order continuous
//! extension, free; DOP853: the 7th-order one, three extra flow evaluations), the interior
//! samples of every flagged guard are recomputed on it (a guard the end-point test cleared
//! keeps g(x₀) inside: it has no crossing to show), and for each guard the first crossing
//! sub-interval is refined with the Illinois variant of regula falsi (Dowell & Jarratt 1971),
//! with a bisection step when three iterations fail to halve the bracket, until the bracket is
//! ≤ 4ε·max(|t₀|, |t₁|) in time (≈ 1e-15 for t ≈ 1). The *right-hand* end of the final bracket is reported: the returned state
//! is the dense-output state at that θ and its guard value is on the post-crossing side or zero.
//! A guard the model declares affine ([`HybridSystem::guard_is_linear`]) is, on the nested
//! dense output of DOPRI5 or DOP853, a scalar polynomial in θ with the same nesting: its rows
//! are the guard applied to the rows of the state's interpolant (`g(c₀)`, then
//! `g(c_r) − g(0)`). Its interior samples and its root then come from that polynomial — the
//! root by Newton's method from the bracket's secant point, safeguarded by the bracket and
//! closed to the same width by a probe across the root (about four polynomial evaluations
//! against seven Illinois iterations on states, each a dense-output state and a guard call);
//! the state at the root must show the crossing too, or the root moves right by up to four
//! bracket widths, and where neither holds (a grazing root hidden by rounding) the Illinois
//! iteration on states decides.
//!
//! **Admissibility.** [`HybridSystem::admissible`] is tested at the root; an inadmissible crossing
//! is skipped and the scan continues with the guard's later sub-intervals. The earliest admissible
//! root over all guards wins (ties: lowest guard index).
//!
//! **No re-triggering.** A crossing needs the left value strictly on the pre-crossing side. At a
//! segment start (after a reset) guard values within `guard_tolerance` of zero are stored as 0
//! (see [`HybridSystem::guard_tolerance`]), and a guard stop leaves the guard on the
//! post-crossing side or at zero: the next integration from that point cannot report the same
//! crossing again; the guard must first be seen strictly on its pre-crossing side.
//!
//! **Accuracy.** With DOPRI5/DOP853 the event time inherits the dense-output error (order 4 / 7 in
//! h per step, of the size of the tolerance) divided by |dg/dt|, plus the 1e-15 bracket. With RK4
//! the cubic Hermite interpolant has error ≤ h⁴/384·max‖x⁽⁴⁾‖ on each step (on top of the O(h⁴)
//! global error of the step values), so the event time error is O(h⁴)/|dg/dt|.
//!
//! **Files.** `detect`: the end-point test and its directional refinement; `dense`: the
//! interpolants (cubic Hermite, the methods' dense outputs); `poly`: an affine guard along a
//! dense output as a scalar polynomial; `refine`: the root finders on a bracket; `locate`: the
//! per-lane driver that ties them together.

mod dense;
mod detect;
mod locate;
mod poly;
mod refine;

// The internals below are public, hidden from the docs, for the integration tests
// (tests/internals.rs); the crate itself reaches them as `event::…`.
#[doc(hidden)]
pub use dense::{
    build_dense, dop853_dense_dyn, dop853_dense_fixed, gather_ends, hermite_basis, hermite_point,
    Dense,
};
pub(crate) use detect::guard_bit;
#[doc(hidden)]
pub use detect::{clears_direction, crosses, hull_and_margin, may_cross};
pub(crate) use locate::locate;
#[doc(hidden)]
pub use poly::{guard_poly, nested_rows, nested_values, nested_with_derivative, POLY_ROWS};
#[doc(hidden)]
pub use refine::{bracket_tol, refine, refine_linear};

use crate::system::Scratch;

/// Interior sample points per step used to detect crossings.
pub const N_SAMPLES: usize = 4;
/// Guard values per guard and step: θ = 0, the samples, θ = 1.
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub const N_COLS: usize = N_SAMPLES + 2;
const M: usize = N_COLS;

/// Per-lane scratch of the event locator (contiguous vectors of length `dim` unless noted).
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
pub struct EventScratch {
    pub x0: Vec<f64>,
    pub x1: Vec<f64>,
    pub f0: Vec<f64>,
    pub f1: Vec<f64>,
    /// State at a sample point.
    pub xs: Vec<f64>,
    /// State at the current root iterate.
    pub xr: Vec<f64>,
    /// State at the winning event.
    pub xbest: Vec<f64>,
    /// `(ng × (N_SAMPLES + 2))` guard values at θ = 0, 1/5, …, 1.
    pub gv: Vec<f64>,
    /// `(8 × dim)` dense-output coefficients.
    pub cont: Vec<f64>,
    /// `(16 × dim)` the lane's DOP853 stages k₀…k₁₂ gathered contiguously, then the three
    /// extra dense-output stages k₁₃…k₁₅.
    pub kl: Vec<f64>,
    pub ytmp: Vec<f64>,
    /// `(ng × 8)` coefficients of each affine guard along the dense output ([`guard_poly`]).
    pub poly: Vec<f64>,
    /// `(ng)` guard k has its polynomial in `poly`.
    pub lin: Vec<bool>,
    /// `(dim)` zeros (the affine guards' constant term is `g(0)`).
    pub zero: Vec<f64>,
    /// The model's own scratch, passed to every model call made for this lane.
    pub model: Scratch,
}

impl EventScratch {
    pub fn new(d: usize, ng: usize) -> Self {
        Self {
            x0: vec![0.0; d],
            x1: vec![0.0; d],
            f0: vec![0.0; d],
            f1: vec![0.0; d],
            xs: vec![0.0; d],
            xr: vec![0.0; d],
            xbest: vec![0.0; d],
            gv: vec![0.0; ng * M],
            cont: vec![0.0; 8 * d],
            kl: vec![0.0; 16 * d],
            ytmp: vec![0.0; d],
            poly: vec![0.0; ng * POLY_ROWS],
            lin: vec![false; ng],
            zero: vec![0.0; d],
            model: Scratch::new(),
        }
    }

    /// Room for `ng` guards per mode.
    pub fn reserve_guards(&mut self, ng: usize) {
        self.gv = vec![0.0; ng * M];
        self.poly = vec![0.0; ng * POLY_ROWS];
        self.lin = vec![false; ng];
    }
}

/// Which interpolant is in `cont` / the end-point vectors.
// Public, hidden from the docs, for the integration tests (tests/internals.rs).
#[doc(hidden)]
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Interp {
    Hermite,
    Dopri5,
    Dop853,
}
