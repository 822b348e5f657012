//! Models by name or spec file with parameter overrides: the one place both front ends build
//! a model, check its overrides and read its units, and where a slope that looks like degrees
//! given as radians draws a warning ([`steep_slope_warning`]).

use crate::input::{self, InputError};
use pdw_hybrid::Options;
use pdw_walkers::{ModelInfo, Walker};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::OnceLock;

/// Slopes steeper than this (rad, in magnitude) draw a warning. Passive walkers walk down a few
/// degrees: Garcia et al. 1998's simplest walker up to γ ≈ 0.019 (then chaos and falls),
/// Goswami et al. 1998's compass gait at 3°–5°, McGeer 1990's walkers at 1–3 %; 0.3 rad (17°)
/// is far beyond all of them, and a slope of 1 (meant as 1°) is 57°.
pub const STEEP_SLOPE: f64 = 0.3;

/// The warning for a slope (rad) steeper than [`STEEP_SLOPE`], naming it in degrees:
/// "slope 1 rad = 57.3° is far steeper than passive walking (≲ 0.3 rad); did you mean 1deg?".
pub fn steep_slope_warning(slope: f64) -> Option<String> {
    (slope.abs() > STEEP_SLOPE).then(|| {
        format!(
            "slope {slope} rad = {:.1}° is far steeper than passive walking (≲ {STEEP_SLOPE} \
             rad); did you mean {slope}deg?",
            slope.to_degrees()
        )
    })
}

/// Where the library's warnings go when a front end says so (Python: `warnings.warn`);
/// without one, to stderr as `warning: …` (the CLI).
static WARNING_SINK: OnceLock<fn(&str)> = OnceLock::new();

/// Whether the steep-slope warning was given in this run.
static STEEP_SLOPE_WARNED: AtomicBool = AtomicBool::new(false);

/// Sends the library's warnings to `sink` instead of stderr. The first sink set stays; returns
/// whether this one was set.
pub fn set_warning_sink(sink: fn(&str)) -> bool {
    WARNING_SINK.set(sink).is_ok()
}

/// Lets each warning be given once more: a new run begins (the CLI's run is the process;
/// Python calls this after each call has given its warnings).
pub fn rearm_warnings() {
    STEEP_SLOPE_WARNED.store(false, Ordering::Relaxed);
    INTEGRATOR_WARNED.store(false, Ordering::Relaxed);
}

/// Whether the integrator warning ([`crate::integrator::check_integrator`]) was given in this
/// run.
static INTEGRATOR_WARNED: AtomicBool = AtomicBool::new(false);

/// Gives the integrator warning, once per run.
pub(crate) fn warn_integrator(msg: &str) {
    warn_once(&INTEGRATOR_WARNED, msg);
}

/// Gives `msg` unless `given` says it was given in this run.
fn warn_once(given: &AtomicBool, msg: &str) {
    if !given.swap(true, Ordering::Relaxed) {
        match WARNING_SINK.get() {
            Some(sink) => sink(msg),
            None => eprintln!("warning: {msg}"),
        }
    }
}

/// Which model, in the front ends' terms: a registry name or a spec file (`.toml`), the slope
/// as text (radians, or degrees with `deg` or `°`), and `NAME=VALUE` overrides.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ModelChoice {
    /// Model name (`pdw-sweep models`) or a walker spec file.
    pub model: String,
    /// The slope as given (`0.009`, `3deg`, `3°`); `None`: the model's preset.
    pub slope: Option<String>,
    /// `NAME=VALUE` overrides, each parameter at most once.
    pub set: Vec<String>,
}

/// A model built by name (or spec file) with its parameter overrides, with the resolved
/// parameter values.
pub struct BuiltModel {
    pub info: ModelInfo,
    pub walker: Box<dyn Walker>,
    /// `(name, value)` in the model's parameter order.
    pub params: Vec<(String, f64)>,
}

impl BuiltModel {
    pub fn slope(&self) -> f64 {
        self.params
            .iter()
            .find(|(n, _)| *n == "slope")
            .map(|p| p.1)
            .unwrap_or(f64::NAN)
    }

    /// What each state component means ([`Walker::coordinate_meanings`]) as a JSON object,
    /// state name → meaning: the `coordinates` attribute of every file; `{}` where the model
    /// does not say.
    pub fn coordinates_json(&self) -> String {
        serde_json::Value::Object(
            self.walker
                .state_names()
                .into_iter()
                .zip(
                    self.walker
                        .coordinate_meanings()
                        .into_iter()
                        .map(Into::into),
                )
                .collect(),
        )
        .to_string()
    }

    /// Parameters as a JSON object.
    pub fn params_json(&self) -> serde_json::Value {
        serde_json::Value::Object(
            self.params
                .iter()
                .map(|(n, v)| (n.to_string(), serde_json::json!(v)))
                .collect(),
        )
    }
}

/// Parses `--model`, `--slope`, `--set` into overrides (without building).
///
/// The slope given twice (`--slope` and `--set slope=…`) is refused: one of the two would be
/// silently ignored.
pub fn overrides(opts: &ModelChoice) -> Result<Vec<(String, f64)>, InputError> {
    let mut ov: Vec<(String, f64)> = Vec::new();
    // the model's parameters, read once and only when a value carries a unit
    let mut info: Option<pdw_walkers::ModelInfo> = None;
    for s in &opts.set {
        let (name, v, unit) = input::parse_assignment_with_unit(s)?;
        let v = match unit {
            None => v,
            Some(u) => {
                if info.is_none() {
                    info = Some(
                        pdw_walkers::model_info(&opts.model)
                            .map_err(|e| InputError(e.to_string()))?,
                    );
                }
                let m = info.as_ref().expect("read above");
                m.value_in_unit(&name, v, &u)
                    .map_err(|why| InputError(format!("--set {s}: {why}")))?
            }
        };
        if let Some((_, prev)) = ov.iter().find(|(n, _)| *n == name) {
            return Err(InputError(format!(
                "--set {name}: given twice ({prev} and {v}); give each parameter once"
            )));
        }
        ov.push((name, v));
    }
    if let Some(s) = &opts.slope {
        if let Some(set) = opts
            .set
            .iter()
            .find(|a| a.split_once('=').is_some_and(|(n, _)| n.trim() == "slope"))
        {
            return Err(InputError(format!(
                "--slope {s} and --set {set} both set the slope; give it once (--slope accepts \
                 3deg as well)"
            )));
        }
        ov.push(("slope".to_string(), input::parse_slope(s)?));
    }
    Ok(ov)
}

/// Overrides given as numbers (keyword arguments in Python): each value finite, the slope (if
/// given) in (−π/2, π/2) rad. The slope comes last, as in [`overrides`].
pub fn overrides_from_values(
    values: Vec<(String, f64)>,
    slope: Option<f64>,
) -> Result<Vec<(String, f64)>, InputError> {
    let mut ov = Vec::with_capacity(values.len() + 1);
    for (name, value) in values {
        if !value.is_finite() {
            return Err(InputError(format!(
                "{name}: {value} is not a finite number"
            )));
        }
        ov.push((name, value));
    }
    if let Some(s) = slope {
        if !(s.is_finite() && s.abs() < std::f64::consts::FRAC_PI_2) {
            return Err(InputError(format!(
                "slope: {s} is outside (-pi/2, pi/2) rad"
            )));
        }
        ov.push(("slope".to_string(), s));
    }
    Ok(ov)
}

/// Builds the model of `choice` with its overrides.
pub fn build_model(choice: &ModelChoice) -> Result<BuiltModel, InputError> {
    build_with(choice, &[])
}

/// Builds the model of `choice` with its overrides and then `extra` overrides on top.
pub fn build_with(choice: &ModelChoice, extra: &[(String, f64)]) -> Result<BuiltModel, InputError> {
    let mut ov = overrides(choice)?;
    ov.extend_from_slice(extra);
    build(&choice.model, &ov)
}

/// Builds model `name` (a registry name or a spec file) with `overrides` (`(name, value)`,
/// checked against the model's parameters). Every model of both front ends is built here, so
/// a slope steeper than [`STEEP_SLOPE`] — from `--slope`, `--set slope`, a spec's default, a
/// sweep or Python's `slope=` — draws [`steep_slope_warning`], once per run.
pub fn build(name: &str, overrides: &[(String, f64)]) -> Result<BuiltModel, InputError> {
    let info = pdw_walkers::model_info(name).map_err(|e| InputError(e.to_string()))?;
    build_info(info, overrides)
}

/// The resolved spec of model `name` (a chain walker: a preset or a spec file) as TOML text
/// ([`pdw_walkers::spec::WalkerSpec::to_toml`], which parses back to an equal spec), for a
/// file's provenance (`model_spec`); `None` for the closed-form models, which are rebuilt by
/// name, and for a name that is no model.
pub fn spec_toml(name: &str) -> Option<String> {
    pdw_walkers::model_info(name)
        .ok()?
        .spec()
        .map(|s| s.to_toml())
}

/// Rebuilds the model a file records: from its resolved spec `spec` (the provenance's
/// `model_spec`, when the file has one) named `name`, else by `name` (a registry model, or a
/// spec file where the reader runs), with the file's parameter values `overrides`. A user's own
/// walker is then rebuilt anywhere, without its spec file.
pub fn build_recorded(
    name: &str,
    spec: Option<&str>,
    overrides: &[(String, f64)],
) -> Result<BuiltModel, InputError> {
    match spec.filter(|t| !t.trim().is_empty()) {
        Some(text) => {
            let spec = pdw_walkers::spec::WalkerSpec::from_toml(text, name)
                .map_err(|e| InputError(format!("the recorded spec of model '{name}': {e}")))?;
            build_info(pdw_walkers::registry::ModelInfo::from_spec(spec), overrides)
        }
        None => build(name, overrides),
    }
}

/// The model of `choice` (with `extra` overrides on top) with every knee stop replaced by an
/// ideal latch (`hold = "latch"` without limits: it holds any pull, and validity reports the
/// pull as a violation), or `None` when the model has no knee stop (a closed-form model, or
/// every knee latched already). The design search grades a stop-only design without a gait by
/// this twin's gait: how much its stops would have to pull.
pub fn build_latched_twin(
    choice: &ModelChoice,
    extra: &[(String, f64)],
) -> Result<Option<BuiltModel>, InputError> {
    let info = pdw_walkers::model_info(&choice.model).map_err(|e| InputError(e.to_string()))?;
    let Some(spec) = info.spec() else {
        return Ok(None);
    };
    let is_stop = |h: &Option<String>| h.as_deref().map(str::trim).is_none_or(|h| h == "stop");
    if !spec.knees.iter().any(|k| is_stop(&k.hold)) {
        return Ok(None);
    }
    let mut twin = spec.clone();
    for k in &mut twin.knees {
        if is_stop(&k.hold) {
            k.hold = Some("latch".into());
        }
    }
    let mut ov = overrides(choice)?;
    ov.extend_from_slice(extra);
    build_info(pdw_walkers::registry::ModelInfo::from_spec(twin), &ov).map(Some)
}

fn build_info(
    info: pdw_walkers::registry::ModelInfo,
    overrides: &[(String, f64)],
) -> Result<BuiltModel, InputError> {
    let refs: Vec<(&str, f64)> = overrides.iter().map(|(n, v)| (n.as_str(), *v)).collect();
    let values = info.resolve(&refs).map_err(|e| InputError(e.to_string()))?;
    let walker = info
        .build_from(&values)
        .map_err(|e| InputError(e.to_string()))?;
    let info = info.with_walker(walker.as_ref());
    let params = info
        .params
        .iter()
        .map(|p| p.name.clone())
        .zip(values)
        .collect();
    let m = BuiltModel {
        info,
        walker,
        params,
    };
    if let Some(msg) = steep_slope_warning(m.slope()) {
        warn_once(&STEEP_SLOPE_WARNED, &msg);
    }
    Ok(m)
}

/// `‖P(s) − s‖∞` of the stride map integrated by `integrator` at section state `s` (infinite
/// when the stride fails): how far `s` is from a fixed point of that map.
pub fn stride_residual(
    m: &BuiltModel,
    integrator: Options,
    s: &[f64],
) -> Result<f64, pdw_limit::LimitError> {
    let map = pdw_limit::StrideMap::new(m.walker.as_ref(), integrator)?;
    Ok(map
        .apply(s)
        .map(|p| {
            p.iter()
                .zip(s)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        })
        .unwrap_or(f64::INFINITY))
}

/// Units of the model's quantities (time, every state component, forces, energy): the
/// simplest walker's are dimensionless (time in √(l/g), lengths in l), the rimless wheel's and
/// the chain walkers' SI (see [`pdw_limit::trajectory::units`]).
pub fn model_units(m: &BuiltModel) -> pdw_limit::trajectory::TrajectoryUnits {
    let w = m.walker.as_ref();
    let e = pdw_limit::trajectory::model_energy(w).unwrap_or_default();
    pdw_limit::trajectory::units(w, &e)
}

/// The time unit of the model (`s`, or `sqrt(l/g)` for the simplest walker).
pub fn time_unit(m: &BuiltModel) -> String {
    model_units(m).time
}

/// The length unit of the model (`l`, the leg, for the simplest walker; `m` otherwise).
pub fn length_unit(m: &BuiltModel) -> String {
    m.walker.units().length.into()
}

/// The unit of each section coordinate, in section order (by the state component of the same
/// name).
pub fn section_units(m: &BuiltModel) -> Vec<String> {
    let u = model_units(m);
    m.info
        .section_names
        .iter()
        .map(|n| {
            m.info
                .state_names
                .iter()
                .position(|s| s == n)
                .map_or_else(|| "rad".to_string(), |j| u.state[j].clone())
        })
        .collect()
}

/// The unit of the model parameter `name` (`""` if unknown).
pub fn param_unit(m: &BuiltModel, name: &str) -> String {
    m.info
        .params
        .iter()
        .find(|p| p.name == name)
        .map(|p| p.unit.clone())
        .unwrap_or_default()
}

/// The units of a file of `m` that the formats' unit rules ([`pdw_store::format::Unit`])
/// resolve against: the section coordinates' and the model's time, length, force and torque
/// units (a format's own fields, grid axes or free parameters, are the caller's to add).
pub fn unit_context(m: &BuiltModel) -> pdw_store::format::UnitContext {
    let u = model_units(m);
    pdw_store::format::UnitContext {
        section: section_units(m),
        state: u.state,
        time: u.time,
        length: length_unit(m),
        force: u.force,
        torque: u.torque,
        ..Default::default()
    }
}

/// A JSON list of units, the form of a `units` attribute on a dataset whose last axis runs
/// over components of different units.
pub fn units_list(u: &[String]) -> String {
    serde_json::to_string(u).unwrap_or_default()
}
