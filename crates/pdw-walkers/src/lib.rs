//! Passive dynamic walker models as hybrid systems ([`pdw_hybrid::HybridSystem`]) with a
//! Poincaré section just after heel strike ([`pdw_hybrid::Section`]).
//!
//! Every model documents its coordinates, sign conventions, guards, reset maps and section in
//! its module docs, validates its parameters at construction ([`WalkerError`]) and implements
//! [`Walker`], the model-level extras (names, step length, fall kinds, initial gait guesses)
//! the stride map and the CLI need. [`registry::MODELS`] lists every model with its parameters
//! (units, defaults) so that a front end can list, describe and build them by name.

pub mod compass;
pub mod error;
pub mod kneed;
pub mod registry;
pub mod rimless;
pub mod seed5;
pub mod simplest;

pub use error::WalkerError;
pub use registry::{
    build, chain_pose, model_info, GaitGuess, ModelInfo, ParamSpec, Pose, Walker, MODELS,
};
