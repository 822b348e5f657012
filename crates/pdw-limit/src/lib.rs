//! Limit cycles of hybrid walkers: the stride map on the post-heel-strike Poincaré section, its
//! Jacobian two ways (variational equations with saltation matrices; batched finite
//! differences), fixed points by a Newton solver run through argmin, Floquet multipliers and
//! gait metrics, for any [`pdw_hybrid::Section`] (held as `dyn Section`: the analysis is compiled
//! once for every model; see the crate README).
//!
//! ```text
//! StrideMap::new(&model, Options::dop853(1e-13))?     P: s ↦ s'
//!   dp_variational / dp_finite_difference             DP(s)
//!   find_fixed_point(&map, &guess, &NewtonOptions)    s*, multipliers, period, step, speed
//! ```

pub mod attractors;
pub mod basin;
pub mod cloud;
pub mod codim2;
pub mod continuation;
pub mod design;
pub mod end;
pub mod ensemble;
pub mod error;
pub mod family;
pub mod floquet;
pub mod gaits;
pub mod gsn;
pub mod jacobian;
pub mod markov;
pub mod metrics;
pub mod mid_stance;
pub mod newton;
pub mod orbit;
pub mod periodic;
pub mod resources;
pub mod scan;
pub mod section_frame;
pub mod stride;
pub mod sweep;
pub mod terrain;
pub mod trajectory;
pub mod validity;
pub mod variational;

pub use attractors::{
    box_attractors, discover, grid_centre, seed_set, Attractor, AttractorKind, AttractorSet,
    DiscoveryOptions,
};
pub use basin::{
    basin_metrics, basin_metrics_slices, classify_cells, classify_cells_scalar, decay_exponent,
    grid_cells, legend, linspace, stands_still, state_scale, walk_dies_out, BasinDriver,
    BasinMetrics, BasinOptions, BasinProblem, CellResult, Outcome, STANDSTILL_WINDOW,
};
pub use codim2::{
    follow_curve, region_map, Codim2Kind, Codim2Options, Curve, CurveEnd, CurvePoint, CurveStart,
    LostReason, Region, RegionOptions,
};
pub use continuation::{
    branch_at_params, continue_both_ways, continue_branch, join_halves, period_doubling_cascade,
    real_eigenvector, switch_period_doubling, Bifurcation, BifurcationKind, Branch, BranchEnd,
    BranchPoint, ContinuationMethod, ContinuationOptions, SampledPoint,
};
pub use end::End;
pub use error::LimitError;
pub use floquet::{is_stable, multipliers, Multiplier};
pub use jacobian::{
    dp_finite_difference, dp_variational, dp_variational_with, richardson_jacobian, FdScheme,
};
pub use metrics::GaitMetrics;
pub use newton::{
    find_fixed_point, DpMethod, FixedPoint, FixedPointProblem, Newton, NewtonOptions, NewtonState,
};
pub use orbit::{orbit_diagram, OrbitColumn, OrbitOptions, OrbitStart};
pub use periodic::{find_periodic_orbit, PeriodKProblem, PeriodicOrbit};
pub use stride::{EventDriver, Stride, StrideEnd, StrideMap, StrideOutcome, MAX_EVENTS_PER_STRIDE};
pub use sweep::{grid_options, GridBranch, MeasuredPoint, Sweep, SweepProgress, SweepSpec};
pub use trajectory::{
    bytes_per_sample, initial_state, model_energy, simulate, Trajectory, TrajectoryError,
    TrajectoryEvent, TrajectoryOptions, Validity,
};
pub use validity::{orbit_validity, ImpactCheck, Margin, OrbitValidity, Violation};
pub use variational::{ErrorControl, Variational};
