//! The model registry: names, parameters (units, defaults, meaning), coordinates, and a
//! constructor from parameter values, so that a front end can list and build models by name.
//!
//! To add a model: implement [`Walker`] for it, give its module a `pub static INFO: ModelInfo`,
//! and append `&crate::<module>::INFO` to [`MODELS`].

use crate::compass::{ConstraintForces, StepFlags};
use crate::error::WalkerError;
use pdw_hybrid::Section;

/// One user-settable model parameter.
#[derive(Clone, Copy, Debug)]
pub struct ParamSpec {
    /// Name used on the command line (`--set NAME=VALUE`); every model calls its slope `slope`.
    pub name: &'static str,
    /// Unit, e.g. `"rad"`, `"m"`, `"kg"`, `"1"` (dimensionless).
    pub unit: &'static str,
    /// Default value (the model's reference preset).
    pub default: f64,
    /// One-line meaning, with the preset's source.
    pub description: &'static str,
}

/// A starting point for a fixed-point search on the section.
#[derive(Clone, Debug, PartialEq)]
pub struct GaitGuess {
    /// Which gait this is meant to find, e.g. `"stable"`, `"unstable"`.
    pub gait: &'static str,
    /// Reduced section coordinates (in [`Section::section_names`] order).
    pub section: Vec<f64>,
    /// Where the guess comes from (e.g. "Garcia 1998 App. A.2 small-slope asymptotics").
    pub source: &'static str,
}

/// Model-level extras on top of the hybrid system and its section.
pub trait Walker: Section {
    /// Registry name, e.g. `"simplest"`.
    fn name(&self) -> &'static str;
    /// Names of the full state components, in state order.
    fn state_names(&self) -> &'static [&'static str];
    /// Current parameter values, in [`ModelInfo::params`] order.
    fn param_values(&self) -> Vec<(&'static str, f64)>;
    /// Step length (distance between the feet along the slope, model length units) at the
    /// stride-ending event, from the *pre-reset* state `x_pre` on the section guard.
    fn step_length(&self, x_pre: &[f64]) -> f64;
    /// Human name of a terminal guard's fall code (`GuardKind::Terminal(code)`).
    fn fall_name(&self, code: u8) -> &'static str;
    /// Initial guesses for the gaits the model is known to have at its current parameters.
    fn gait_guesses(&self) -> Vec<GaitGuess>;
    /// The walker's drawing at full state `x`, for animations; `None` if the model has none.
    fn pose(&self, _x: &[f64]) -> Option<Pose> {
        None
    }
    /// Stance-foot ground reaction and knee-lock torques at `(mode, x)`, if the model
    /// computes them.
    fn constraint_forces(&self, _mode: usize, _x: &[f64]) -> Option<ConstraintForces> {
        None
    }
    /// Validity flags at `(mode, x)` (negative normal force, a knee that would unlock, a swing
    /// foot below ground after mid-stance), if the model computes them.
    fn step_flags(&self, _mode: usize, _x: &[f64]) -> Option<StepFlags> {
        None
    }
}

/// The pose of a planar serial chain rooted at the stance foot: link `k` has absolute angle
/// `θ_k = q₀ + … + q_k` from the slope normal and signed length `len[k]`, and runs from `P_k` to
/// `P_{k+1} = P_k + len[k] (−sin θ_k, cos θ_k)` (the convention of the chain walkers).
pub fn chain_pose(q: &[f64], len: &[f64]) -> Pose {
    let mut p = [0.0, 0.0];
    let mut th = 0.0;
    let mut pts = vec![p];
    for (qk, lk) in q.iter().zip(len) {
        th += qk;
        let (s, c) = f64::sin_cos(th);
        p = [p[0] - lk * s, p[1] + lk * c];
        pts.push(p);
    }
    Pose {
        links: pts.windows(2).map(|w| [w[0], w[1]]).collect(),
        joints: pts[1..pts.len() - 1].to_vec(),
        swing_foot: pts.last().copied(),
    }
}

/// A drawing of the walker in the slope frame: `x` along the slope (downhill positive), `y`
/// along the slope normal, stance foot at the origin (model length units).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Pose {
    /// Rigid links as segments.
    pub links: Vec<[[f64; 2]; 2]>,
    /// Joint and point-mass positions.
    pub joints: Vec<[f64; 2]>,
    /// The swing foot (traced in animations).
    pub swing_foot: Option<[f64; 2]>,
}

/// Constructor from parameter values in [`ModelInfo::params`] order.
pub type BuildFn = fn(&[f64]) -> Result<Box<dyn Walker>, WalkerError>;

/// Static description of a model and its constructor.
pub struct ModelInfo {
    pub name: &'static str,
    pub description: &'static str,
    pub params: &'static [ParamSpec],
    pub state_names: &'static [&'static str],
    pub section_names: &'static [&'static str],
    /// Builds the model from values in `params` order (already resolved by [`ModelInfo::resolve`]).
    pub build_from: BuildFn,
}

impl ModelInfo {
    /// Default values with `overrides` applied; an unknown name is an error listing the valid ones.
    pub fn resolve(&self, overrides: &[(&str, f64)]) -> Result<Vec<f64>, WalkerError> {
        let mut v: Vec<f64> = self.params.iter().map(|p| p.default).collect();
        for (name, value) in overrides {
            match self.params.iter().position(|p| p.name == *name) {
                Some(i) => v[i] = *value,
                None => {
                    return Err(WalkerError::UnknownParam {
                        model: self.name,
                        name: (*name).to_string(),
                        valid: self
                            .params
                            .iter()
                            .map(|p| p.name)
                            .collect::<Vec<_>>()
                            .join(", "),
                    })
                }
            }
        }
        Ok(v)
    }

    /// Builds the model with `overrides` applied to the defaults.
    pub fn build(&self, overrides: &[(&str, f64)]) -> Result<Box<dyn Walker>, WalkerError> {
        (self.build_from)(&self.resolve(overrides)?)
    }
}

/// Every registered model, in listing order.
pub static MODELS: &[&ModelInfo] = &[
    &crate::rimless::INFO,
    &crate::simplest::INFO,
    &crate::compass::INFO,
    &crate::kneed::INFO,
    &crate::seed5::INFO,
];

/// Looks a model up by name; an unknown name is an error listing the valid ones.
pub fn model_info(name: &str) -> Result<&'static ModelInfo, WalkerError> {
    MODELS
        .iter()
        .copied()
        .find(|m| m.name == name)
        .ok_or_else(|| WalkerError::UnknownModel {
            name: name.to_string(),
            valid: MODELS.iter().map(|m| m.name).collect::<Vec<_>>().join(", "),
        })
}

/// Builds model `name` with parameter `overrides` (e.g. `[("slope", 0.01)]`).
pub fn build(name: &str, overrides: &[(&str, f64)]) -> Result<Box<dyn Walker>, WalkerError> {
    model_info(name)?.build(overrides)
}
