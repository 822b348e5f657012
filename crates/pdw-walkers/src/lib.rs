//! Passive dynamic walker models as hybrid systems ([`pdw_hybrid::HybridSystem`]) with a
//! Poincaré section just after heel strike ([`pdw_hybrid::Section`]).
//!
//! Closed-form models: [`rimless`] (rimless wheel) and [`simplest`] (Garcia et al. 1998). Every
//! planar legged chain — the compass gait, kneed walkers, the seed thesis' walker, a user's own
//! — is one [`chain_walker::ChainWalker`] built from a [`spec::WalkerSpec`] (TOML; the presets
//! are the files in `models/`). Every model documents its coordinates, sign conventions,
//! guards, reset maps and section in its module docs, validates its parameters at
//! construction ([`WalkerError`]) and implements [`Walker`] (crate `pdw-model`), the model-level
//! extras the stride map and the CLI need. [`registry::model_info`] finds a model by name or spec file.

pub mod chain_walker;
pub mod error;
pub mod registry;
pub mod rimless;
pub mod simplest;
pub mod spec;
pub mod units;
/// The validity types every model reports in ([`pdw_model::validity`]).
pub use pdw_model::validity;

pub use chain_walker::ChainWalker;
pub use error::WalkerError;
pub use pdw_model::{BodyPoints, GaitGuess, ModelUnits, Pose, Walker};
pub use registry::{
    build, chain_pose, model_info, models, preset_text, presets, ClosedInfo, ModelInfo, ParamSpec,
    StaticParam, PRESETS,
};
pub use spec::WalkerSpec;
pub use validity::{
    ClearanceRule, ConstraintForces, ImpactReport, ImpulseEntry, ImpulseKind, Scales, StepFlags,
};
