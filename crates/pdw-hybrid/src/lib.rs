//! Hybrid simulation for passive walkers: the [`HybridSystem`] abstraction, integrators with
//! dense output and event location, and batched lockstep integration over lanes.

pub mod system;

pub use system::{Crossing, GuardKind, GuardSpec, HybridSystem, Section};
