//! The model registry: names, parameters (units, defaults, meaning), coordinates, and a
//! constructor from parameter values, so that a front end can list and build models by name —
//! or from a walker spec file (`.toml`, see [`crate::spec`]).
//!
//! Closed-form models (rimless, simplest) are Rust modules with a `pub static INFO:
//! ClosedInfo`, their parameters declared once (`closed_params!`); every chain walker is a
//! spec: the presets `compass`, `kneed`, `seed5` are the spec files in the repository's
//! `models/` folder, compiled in.

use crate::chain_walker::ChainWalker;
use crate::error::WalkerError;
use crate::spec::WalkerSpec;
use pdw_model::{Pose, Walker};

/// One user-settable model parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamSpec {
    /// Name used on the command line (`--set NAME=VALUE`); every model calls its slope `slope`.
    pub name: String,
    /// Unit, e.g. `"rad"`, `"m"`, `"kg"`, `"1"` (dimensionless).
    pub unit: String,
    /// Default value (the model's reference preset).
    pub default: f64,
    /// One-line meaning, with the preset's source.
    pub description: String,
}

/// A parameter of a closed-form model (static form of [`ParamSpec`]).
#[derive(Clone, Copy, Debug)]
pub struct StaticParam {
    pub name: &'static str,
    pub unit: &'static str,
    pub default: f64,
    pub description: &'static str,
}

/// The parameters of a closed-form model, each written once — field name (the `--set` name),
/// unit, default, one-line meaning with the default's source — and everything that lists
/// them generated from that one list, in its order:
///
/// - the public parameter struct, one `pub f64` field per parameter, documented with its
///   meaning, unit and default (plus the doc comment written above the entry, e.g. the
///   allowed range), deriving `Clone, Copy, Debug, PartialEq`;
/// - its `Default` (the defaults of the list);
/// - the registry's table, a private `const TABLE: &[StaticParam]` for
///   [`ClosedInfo::params`] (what `pdw-sweep models` lists);
/// - `from_values(&[f64])`, the struct from values in table order (for
///   [`ClosedInfo::build_from`]; panics when a value is missing);
/// - `named_values()`, `(name, value)` in table order (for `Walker::param_values`, hence the
///   model's fingerprint and the parameters stored with results).
///
/// ```ignore
/// closed_params! {
///     /// User-facing parameters of [`Model`].
///     pub struct ModelParams in PARAMS {
///         /// In (−π/2, π/2).
///         slope: "rad" = 0.009 => "slope angle γ (Garcia et al. 1998 use 0.009)",
///     }
/// }
/// ```
///
/// The model validates the values in its constructor (with its own error messages).
/// The fingerprint ([`pdw_model::Walker::fingerprint`]) of a closed-form model from its name
/// and parameters, leaving out `step_down` when it is 0 (level ground), so that a file written
/// before step heights existed names the same model.
pub(crate) fn level_fingerprint(name: &str, params: &[(String, f64)]) -> String {
    let mut s = format!("model = {name}\n");
    for (n, v) in params {
        if !(n == "step_down" && *v == 0.0) {
            s.push_str(&format!("{n} = {v:?}\n"));
        }
    }
    s
}

macro_rules! closed_params {
    (
        $(#[$meta:meta])*
        pub struct $name:ident in $table:ident {
            $(
                $(#[doc = $doc:literal])*
                $field:ident: $unit:literal = $default:expr => $desc:literal,
            )+
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct $name {
            $(
                #[doc = concat!(
                    $desc, "; unit `", $unit, "`, default `", stringify!($default), "`."
                )]
                #[doc = ""]
                $(#[doc = $doc])*
                pub $field: f64,
            )+
        }

        impl Default for $name {
            fn default() -> Self {
                Self {
                    $($field: $default,)+
                }
            }
        }

        /// The registry's parameter table ([`ClosedInfo::params`](crate::ClosedInfo)).
        const $table: &[$crate::registry::StaticParam] = &[
            $(
                $crate::registry::StaticParam {
                    name: stringify!($field),
                    unit: $unit,
                    default: $default,
                    description: $desc,
                },
            )+
        ];

        impl $name {
            /// The parameters from values in table order; panics when a value is missing.
            pub(crate) fn from_values(values: &[f64]) -> Self {
                let mut values = values.iter().copied();
                let mut next = || {
                    values
                        .next()
                        .expect("one value per parameter, in table order")
                };
                Self {
                    $($field: next(),)+
                }
            }

            /// `(name, value)` of every parameter, in table order.
            pub(crate) fn named_values(&self) -> Vec<(String, f64)> {
                vec![$((stringify!($field).to_string(), self.$field),)+]
            }
        }
    };
}
pub(crate) use closed_params;

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

/// Constructor of a closed-form model from parameter values in [`ClosedInfo::params`] order.
pub type BuildFn = fn(&[f64]) -> Result<Box<dyn Walker>, WalkerError>;

/// Static description of a closed-form model and its constructor.
pub struct ClosedInfo {
    pub name: &'static str,
    pub description: &'static str,
    pub params: &'static [StaticParam],
    pub state_names: &'static [&'static str],
    pub section_names: &'static [&'static str],
    /// Builds the model from values in `params` order.
    pub build_from: BuildFn,
}

/// How a registered model is built.
#[derive(Clone)]
enum Builder {
    Closed(BuildFn),
    Spec(Box<WalkerSpec>),
}

/// A model: name, parameters (units, defaults), coordinates, and how to build it.
#[derive(Clone)]
pub struct ModelInfo {
    pub name: String,
    pub description: String,
    pub params: Vec<ParamSpec>,
    pub state_names: Vec<String>,
    pub section_names: Vec<String>,
    builder: Builder,
}

impl std::fmt::Debug for ModelInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ModelInfo")
            .field("name", &self.name)
            .finish_non_exhaustive()
    }
}

impl From<&ClosedInfo> for ModelInfo {
    fn from(c: &ClosedInfo) -> Self {
        Self {
            name: c.name.into(),
            description: c.description.into(),
            params: c
                .params
                .iter()
                .map(|p| ParamSpec {
                    name: p.name.into(),
                    unit: p.unit.into(),
                    default: p.default,
                    description: p.description.into(),
                })
                .collect(),
            state_names: c.state_names.iter().map(|s| s.to_string()).collect(),
            section_names: c.section_names.iter().map(|s| s.to_string()).collect(),
            builder: Builder::Closed(c.build_from),
        }
    }
}

/// Names of the full state of a chain walker with `m` segments per leg.
pub fn chain_state_names(m: usize) -> Vec<String> {
    let knee = |side: &str, i: usize| {
        if m == 2 {
            format!("{side}_knee")
        } else {
            format!("{side}_knee{}", i + 1)
        }
    };
    let mut names = vec!["stance".to_string()];
    names.extend((0..m.saturating_sub(1)).map(|i| knee("stance", i)));
    names.push("hip".into());
    names.extend((0..m.saturating_sub(1)).rev().map(|i| knee("swing", i)));
    let rates: Vec<String> = names.iter().map(|s| format!("{s}_rate")).collect();
    names.extend(rates);
    names
}

impl ModelInfo {
    /// The model of a walker spec.
    ///
    /// The section coordinates are those of the walker at the spec's default values
    /// ([`crate::chain_walker::section_names_of`]); a parameter that changes them (a knee mode
    /// expression) is accounted for by [`ModelInfo::with_walker`].
    pub fn from_spec(spec: WalkerSpec) -> Self {
        let t = spec.param_table();
        let section_names: &[&str] = match spec.resolve(&t.values) {
            Ok(r) => crate::chain_walker::section_names_of(&r),
            Err(_) => &["stance", "stance_rate", "hip_rate"],
        };
        Self {
            name: spec.name.clone(),
            description: spec.description.clone(),
            params: (0..t.names.len())
                .map(|i| ParamSpec {
                    name: t.names[i].clone(),
                    unit: t.units[i].clone(),
                    default: t.values[i],
                    description: t.descriptions[i].clone(),
                })
                .collect(),
            state_names: chain_state_names(spec.segments.len()),
            section_names: section_names.iter().map(|s| s.to_string()).collect(),
            builder: Builder::Spec(Box::new(spec)),
        }
    }

    /// This description with the section coordinates of `walker`, a model built from it at
    /// some parameter values (a knee mode set by a parameter changes them).
    pub fn with_walker(mut self, walker: &dyn Walker) -> Self {
        self.section_names = walker
            .section_names()
            .iter()
            .map(|s| s.to_string())
            .collect();
        self
    }

    /// The walker spec, for chain walkers.
    pub fn spec(&self) -> Option<&WalkerSpec> {
        match &self.builder {
            Builder::Spec(s) => Some(s),
            Builder::Closed(_) => None,
        }
    }

    /// Default values with `overrides` applied; an unknown name is an error listing the valid ones.
    pub fn resolve(&self, overrides: &[(&str, f64)]) -> Result<Vec<f64>, WalkerError> {
        let mut v: Vec<f64> = self.params.iter().map(|p| p.default).collect();
        for (name, value) in overrides {
            match self.params.iter().position(|p| p.name == *name) {
                Some(i) => v[i] = *value,
                None => {
                    return Err(WalkerError::UnknownParam {
                        model: self.name.clone(),
                        name: (*name).to_string(),
                        valid: self
                            .params
                            .iter()
                            .map(|p| p.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", "),
                    })
                }
            }
        }
        Ok(v)
    }

    /// `value` in `unit` as a value of parameter `name` in the unit the model lists it in (a
    /// spec's base unit): through [`crate::units::convert`] with that unit's dimension, so a
    /// unit of another quantity is refused ("unit `deg` is an angle, hip_mass is a mass (kg,
    /// g, …)"). A parameter in a model's own unit that no unit of the table converts into (the
    /// simplest walker's `sqrt(l/g)`) takes plain numbers only.
    pub fn value_in_unit(&self, name: &str, value: f64, unit: &str) -> Result<f64, String> {
        let Some(p) = self.params.iter().find(|p| p.name == name) else {
            return Err(WalkerError::UnknownParam {
                model: self.name.clone(),
                name: name.to_string(),
                valid: self
                    .params
                    .iter()
                    .map(|p| p.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            }
            .to_string());
        };
        let expected = crate::units::dimension_of(&p.unit).map_err(|_| {
            format!(
                "model '{}' has {name} in `{}`, its own unit, which no unit converts into: give \
                 a plain number",
                self.name, p.unit
            )
        })?;
        let system = self
            .spec()
            .map_or(crate::units::UnitSystem::Si, WalkerSpec::unit_system);
        crate::units::convert(value, unit, name, expected, system)
    }

    /// Builds the model from values in `params` order (as [`ModelInfo::resolve`] gives them).
    pub fn build_from(&self, values: &[f64]) -> Result<Box<dyn Walker>, WalkerError> {
        match &self.builder {
            Builder::Closed(f) => f(values),
            Builder::Spec(s) => Ok(Box::new(ChainWalker::new((**s).clone(), values)?)),
        }
    }

    /// Builds the model with `overrides` applied to the defaults.
    pub fn build(&self, overrides: &[(&str, f64)]) -> Result<Box<dyn Walker>, WalkerError> {
        self.build_from(&self.resolve(overrides)?)
    }
}

/// The chain-walker presets: name and spec text (the files in `models/`).
pub const PRESETS: [(&str, &str); 3] = [
    ("compass", include_str!("../../../models/compass.toml")),
    ("kneed", include_str!("../../../models/kneed.toml")),
    ("seed5", include_str!("../../../models/seed5.toml")),
];

/// The spec text of a preset (`models/NAME.toml`), if `name` is one.
pub fn preset_text(name: &str) -> Option<&'static str> {
    PRESETS.iter().find(|p| p.0 == name).map(|p| p.1)
}

/// Every built-in model, in listing order: the closed-form models, then the chain presets.
pub fn models() -> Vec<ModelInfo> {
    let mut v: Vec<ModelInfo> = vec![
        (&crate::rimless::INFO).into(),
        (&crate::simplest::INFO).into(),
    ];
    for (name, text) in PRESETS {
        match WalkerSpec::from_toml(text, name) {
            Ok(spec) => v.push(ModelInfo::from_spec(spec)),
            Err(e) => unreachable!("preset {name} does not parse (tested): {e}"),
        }
    }
    v
}

fn builtin_names() -> String {
    let mut names = vec!["rimless", "simplest"];
    names.extend(PRESETS.iter().map(|p| p.0));
    names.join(", ")
}

/// Looks a model up by name, or reads a walker spec file when `name` is a path (ends in
/// `.toml` or names an existing file); an unknown name is an error listing the valid ones.
pub fn model_info(name: &str) -> Result<ModelInfo, WalkerError> {
    match name {
        "rimless" => return Ok((&crate::rimless::INFO).into()),
        "simplest" => return Ok((&crate::simplest::INFO).into()),
        _ => {}
    }
    if let Some(text) = preset_text(name) {
        return Ok(ModelInfo::from_spec(WalkerSpec::from_toml(text, name)?));
    }
    let path = std::path::Path::new(name);
    if name.ends_with(".toml") || path.is_file() {
        return Ok(ModelInfo::from_spec(WalkerSpec::from_file(path)?));
    }
    Err(WalkerError::UnknownModel {
        name: name.to_string(),
        valid: builtin_names(),
    })
}

/// Builds model `name` (or spec file) with parameter `overrides` (e.g. `[("slope", 0.01)]`).
pub fn build(name: &str, overrides: &[(&str, f64)]) -> Result<Box<dyn Walker>, WalkerError> {
    model_info(name)?.build(overrides)
}

/// The chain-walker presets as concrete types (for code that needs the chain walker's own API).
pub mod presets {
    use super::*;

    fn preset(name: &str, overrides: &[(&str, f64)]) -> Result<ChainWalker, WalkerError> {
        let info = model_info(name)?;
        let values = info.resolve(overrides)?;
        match info.spec() {
            Some(spec) => ChainWalker::new(spec.clone(), &values),
            None => unreachable!("{name} is a chain preset"),
        }
    }

    /// Goswami et al.'s compass gait (`models/compass.toml`) with `overrides`.
    pub fn compass(overrides: &[(&str, f64)]) -> Result<ChainWalker, WalkerError> {
        preset("compass", overrides)
    }

    /// Hsu Chen's kneed walker (`models/kneed.toml`) with `overrides`.
    pub fn kneed(overrides: &[(&str, f64)]) -> Result<ChainWalker, WalkerError> {
        preset("kneed", overrides)
    }

    /// The seed thesis' walker (`models/seed5.toml`) with `overrides`.
    pub fn seed5(overrides: &[(&str, f64)]) -> Result<ChainWalker, WalkerError> {
        preset("seed5", overrides)
    }
}
