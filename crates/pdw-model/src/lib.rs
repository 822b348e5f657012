//! What the analysis needs to know about a walker, and nothing about which walkers exist.
//!
//! [`Walker`] extends a hybrid system with a Poincaré section ([`pdw_hybrid::Section`]) by the
//! model-level quantities the stride map, the validity checks, trajectories and the front ends
//! read: names, parameter values, step length, gait guesses, a drawing ([`Pose`]), constraint
//! forces and impact impulses ([`validity`]), energy, natural scales and [`ModelUnits`]. The
//! models themselves (the catalogue, spec files, presets) live in `pdw-walkers`; the analysis
//! (`pdw-limit`) depends on this crate only, so it works for any model that implements the
//! trait.

pub mod validity;
pub mod walker;

pub use validity::{
    ClearanceRule, ConstraintForces, ImpactReport, ImpulseEntry, ImpulseKind, Scales, StepFlags,
};
pub use walker::{
    BodyPoints, ClosedEnd, ClosedStride, GaitGuess, Ground, ModelUnits, Pose, StepHeight, Walker,
};
