//! Walker specs: a planar legged chain described as data (TOML), validated, with named
//! parameters that `--set NAME=V` changes.
//!
//! A spec describes **one leg** (both legs are identical, so that the stride map from one heel
//! strike to the next is the same map every step) as a list of segments from the foot up to the
//! hip, the knees between consecutive segments, a hip point mass, gravity, slope and the gait
//! guesses of the Poincaré section. Every numeric field is either a number or an expression over
//! the spec's parameters (`"a + b"`, `"0.5 * thigh_length"`, `"m * l^2 / 12"`: `+ − * /`, `^` or
//! `**`, unary minus, parentheses; [`eval_expr`]), so that a
//! preset keeps the parameter names of its source (Goswami's `a`, `b`, `leg_mass`, …).
//!
//! ```toml
//! name = "compass"
//! description = "Goswami et al. 1998 compass gait"
//! source = "Goswami, Thuilot & Espiau, IJRR 17(12), 1998"
//! hip_mass = "hip_mass"
//! foot_radius = 0.0           # round (arc) feet rolling without slip; 0: point feet (m)
//!
//! [parameters]
//! slope = { value = 0.05235987755982988, unit = "rad", description = "slope angle (3°)" }
//! a = { value = 0.5, unit = "m", description = "foot to leg mass" }
//!
//! [[segments]]                # from the foot up
//! length = "a + b"            # m
//! mass = "leg_mass"           # kg
//! com = "a"                   # COM along the segment from its lower end (m)
//! com_normal = 0.0            # COM normal to the segment, + forward (m)
//! inertia = 0.0               # about the COM (kg m²)
//!
//! [[knees]]                   # one per joint between consecutive segments (foot side first)
//! mode = "free-swing"         # "locked" | "free-swing" | an expression: 0 locked, 1 free-swing
//! hold = "stop"               # "stop" (pushes only; default) | "latch" (holds both ways)
//! # latch_torque = "latch_torque"    # a latch's largest pull in stance and swing (N m, >= 0)
//! # latch_impulse = "latch_impulse"  # a latch's largest pulling impulse at an impact (N m s)
//!
//! [[gaits]]                   # optional starting points of the fixed-point search
//! name = "stable"
//! section = [0.271, -1.092, 0.715]   # stance, stance_rate, hip_rate
//! source = "…"
//! ```
//!
//! The parameters `slope` (rad), `gravity`, `max_stride_time` and `step_down` always exist
//! (defaults: slope required, 9.81, 5.0, 0 — the chain walker's module docs, "Step down"); a spec sets their defaults, units and descriptions in `[parameters]`
//! like any other parameter. A parameter's value is in its `unit`, converted into the spec's
//! base unit by the table of [`crate::units`] (`{ value = 3, unit = "deg" }` is 3° in rad,
//! `{ value = 50, unit = "cm" }` 0.5 m in an SI spec; `L`, `M`, `T` and `1` are taken as is).
//! A unit must measure what its parameter is in the walker (a mass in kg or g, a length in m,
//! a slope in rad or deg; [`crate::units::Dimension`]): each field's expression is computed in
//! its parameters' units and refused when it is another quantity.
//! Unknown keys, unknown units, a leg without segments, a knee on a one-segment leg,
//! non-positive masses and lengths, NaN, unknown names in expressions are errors that name the
//! field, its value and the rule.

use crate::error::WalkerError;
use crate::units::{self, Dimension, UnitSystem};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

mod resolve;

/// A number or an expression over the spec's parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Num {
    Value(f64),
    Expr(String),
}

impl Default for Num {
    fn default() -> Self {
        Num::Value(0.0)
    }
}

impl Num {
    /// Whether it is the plain number 0 (for skipping a default field when writing TOML).
    pub fn is_zero(&self) -> bool {
        matches!(self, Num::Value(v) if *v == 0.0)
    }

    /// The value as written, with its evaluation when it is an expression (for messages).
    fn shown(&self, v: f64) -> String {
        match self {
            Num::Value(_) => format!("{v}"),
            Num::Expr(e) => format!("{} = {v}", quoted(e)),
        }
    }
}

impl std::fmt::Display for Num {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Num::Value(v) => write!(f, "{v}"),
            Num::Expr(e) => write!(f, "\"{e}\""),
        }
    }
}

/// A named parameter: default value, unit, meaning (with its source).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamDef {
    /// The default, in `unit`.
    pub value: f64,
    /// The unit of `value` (default `"1"`): converted into the spec's base unit by
    /// [`crate::units`] (`deg` → rad, `cm` → m in an SI spec), refused when unknown.
    #[serde(default = "default_unit")]
    pub unit: String,
    #[serde(default)]
    pub description: String,
}

fn default_unit() -> String {
    "1".into()
}

/// One rigid segment of a leg, described in the **stance** orientation (lower end at the foot
/// side, upper end at the knee or hip above it).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentSpec {
    /// Optional name, e.g. `"shank"`.
    #[serde(default)]
    pub name: String,
    /// Length between its two joints (the lowest segment: from the point foot), > 0.
    pub length: Num,
    /// Mass, > 0.
    pub mass: Num,
    /// COM position along the segment, from its lower end.
    pub com: Num,
    /// COM offset normal to the segment, positive forward (the walking direction when the leg is
    /// upright). McGeer's offset thigh COM, which keeps a stance knee locked.
    #[serde(default)]
    pub com_normal: Num,
    /// Rotational inertia about the COM, ≥ 0.
    #[serde(default)]
    pub inertia: Num,
}

/// A knee between two consecutive segments.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KneeSpec {
    /// `"locked"` (a pseudo joint all step, seed §3.4), `"free-swing"` (the swing knee is free
    /// until it straightens — the knee strike — and locked after; the stance knee is locked), or
    /// an expression over the parameters that evaluates to 0 (locked) or 1 (free-swing).
    pub mode: String,
    /// What holds the knee straight while it is locked: `"stop"` (default) — a hyper-extension
    /// stop that can only push; where it would have to pull (at an impact) the stance knee
    /// buckles, a fall — or `"latch"` — a latch that holds both ways, the locked knee of the
    /// published kneed walkers (McGeer 1990, Hsu Chen 2007) and of the seed's pseudo joints
    /// (§3.4). Validity judges each knee by its hardware: a stop may not pull, a latch may pull
    /// up to its limits; an ideal latch (no limits) is reported where it pulls.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hold: Option<String>,
    /// A latch's holding limit in stance and swing: the largest pulling torque (towards
    /// extension, holding the knee against flexion: what a stop cannot do) it holds, ≥ 0 (N m in
    /// SI specs; mass × length² / time² in the spec's units). Beyond it the latch lets go and
    /// the model goes on with the knee released (chain walker module docs, "Latches"). Only
    /// with `hold = "latch"`; without it the latch is ideal (holds any pull).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub latch_torque: Option<Num>,
    /// A latch's holding limit at an impact: the largest pulling angular impulse it holds, ≥ 0
    /// (N m s in SI specs). Beyond it the impact is solved with the knee released. Only with
    /// `hold = "latch"`; without it the latch holds any impulse.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub latch_impulse: Option<Num>,
}

/// A starting point for the fixed-point search on the section.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaitSpec {
    pub name: String,
    /// Section coordinates `(stance, stance_rate, hip_rate)` (numbers or expressions).
    pub section: Vec<Num>,
    #[serde(default)]
    pub source: String,
}

/// A planar chain walker as data.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WalkerSpec {
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// Where the preset's values come from.
    #[serde(default)]
    pub source: String,
    /// Named parameters (`--set NAME=V`); `slope`, `gravity`, `max_stride_time`, `step_down`
    /// always exist.
    #[serde(default)]
    pub parameters: BTreeMap<String, ParamDef>,
    /// Hip point mass (≥ 0), carried by the stance leg's top segment at its upper end.
    #[serde(default)]
    pub hip_mass: Num,
    /// Radius of the round (arc) feet (m, ≥ 0, less than the lowest segment's length; default
    /// 0: point feet). The arc's centre lies on the lowest segment's line at this distance above
    /// the segment's lower end (the foot's lowest point when the leg is upright); the stance foot
    /// rolls without slip (McGeer 1990).
    #[serde(default, skip_serializing_if = "Num::is_zero")]
    pub foot_radius: Num,
    /// One leg's segments from the foot up (both legs are identical).
    #[serde(default)]
    pub segments: Vec<SegmentSpec>,
    /// The knees between consecutive segments, foot side first (`segments.len() − 1` of them).
    #[serde(default)]
    pub knees: Vec<KneeSpec>,
    /// Gait guesses; without any, one generic guess scaled by `√(g/L)` is used.
    #[serde(default)]
    pub gaits: Vec<GaitSpec>,
}

/// Parameters every chain walker has, with their defaults when a spec does not set them.
pub(crate) const BUILTIN_PARAMS: [(&str, f64, &str, &str); 4] = [
    ("slope", f64::NAN, "rad", "slope angle γ"),
    ("gravity", 9.81, "m/s^2", "gravitational acceleration g"),
    (
        "max_stride_time",
        5.0,
        "s",
        "stride time budget; a longer stride counts as a fall",
    ),
    (
        "step_down",
        0.0,
        "m",
        "height of the next foothold below the stance foot, normal to the slope (negative: a \
         step up)",
    ),
];

/// A spec's parameters with values (in a fixed order: the spec's own names sorted, builtins
/// added where missing).
#[derive(Clone, Debug, PartialEq)]
pub struct ParamTable {
    pub names: Vec<String>,
    pub values: Vec<f64>,
    pub units: Vec<String>,
    pub descriptions: Vec<String>,
}

impl ParamTable {
    pub fn get(&self, name: &str) -> Option<f64> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|i| self.values[i])
    }

    /// The (base) unit of parameter `name`.
    pub fn get_unit(&self, name: &str) -> Option<&str> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|i| self.units[i].as_str())
    }
}

/// The evaluated, validated geometry of a spec at given parameter values (SI or the spec's units).
#[derive(Clone, Debug, PartialEq)]
pub struct Resolved {
    pub slope: f64,
    pub gravity: f64,
    pub max_stride_time: f64,
    /// Height of the next foothold below the stance foot, normal to the slope (0: level).
    pub step_down: f64,
    pub hip_mass: f64,
    /// Radius of the round feet (0: point feet).
    pub foot_radius: f64,
    /// Per segment (foot up): length, mass, com along, com normal, inertia about the COM.
    pub segments: Vec<[f64; 5]>,
    /// Per knee (foot side first): free-swing?
    pub free_swing: Vec<bool>,
    /// Per knee (foot side first): held by a latch (both ways) rather than a stop?
    pub latched: Vec<bool>,
    /// Per knee (foot side first): the latch's largest pulling torque (`None`: a stop, or an
    /// ideal latch that holds any pull).
    pub latch_torque: Vec<Option<f64>>,
    /// Per knee (foot side first): the latch's largest pulling impulse at an impact (`None`: a
    /// stop, or an ideal latch).
    pub latch_impulse: Vec<Option<f64>>,
    /// Gait guesses `(name, section, source)` with their sections evaluated.
    pub gaits: Vec<(String, Vec<f64>, String)>,
}

impl WalkerSpec {
    /// Parses a spec from TOML text; `source_name` names it in errors (a file path or preset).
    /// Every parameter's unit is checked ([`crate::units`]).
    pub fn from_toml(text: &str, source_name: &str) -> Result<Self, WalkerError> {
        let spec: Self = toml::from_str(text).map_err(|e| WalkerError::SpecSyntax {
            source_name: source_name.to_string(),
            message: e.message().to_string()
                + &e.span()
                    .map(|s| {
                        let line = text[..s.start.min(text.len())].lines().count().max(1);
                        format!(" (line {line})")
                    })
                    .unwrap_or_default(),
        })?;
        spec.check_units(source_name)?;
        Ok(spec)
    }

    /// The unit system of the spec's lengths, masses and times: abstract when a parameter uses
    /// `L`, `M` or `T`, else SI ([`crate::units::system_of`]).
    pub fn unit_system(&self) -> UnitSystem {
        units::system_of(self.parameters.values().map(|p| p.unit.as_str()))
    }

    /// Refuses a parameter whose unit the table of [`crate::units`] does not know or cannot
    /// convert, naming the parameter, the unit and the units accepted.
    pub fn check_units(&self, source_name: &str) -> Result<(), WalkerError> {
        let system = self.unit_system();
        for (name, p) in &self.parameters {
            if let Err(why) = units::to_base(p.value, &p.unit, system) {
                return Err(WalkerError::InvalidSpec {
                    source_name: source_name.to_string(),
                    field: format!("parameters.{name}.unit"),
                    value: format!("\"{}\"", p.unit),
                    rule: format!("{why}; units accepted: {}", units::ACCEPTED),
                });
            }
        }
        self.check_dimensions(source_name, system)
    }

    /// The dimension each field's value has by its role in the walker (a segment's `mass` is a
    /// mass, its `com` a length, a gait's rates angular rates): `(field, expression,
    /// dimension)` for every field written as an expression (a plain number is in the base
    /// unit of its field). The unit check walks this table; a new field adds a row.
    fn dimensioned_fields<'a>(&'a self) -> Vec<(String, &'a str, Dimension)> {
        let mut out = Vec::new();
        let mut num = |field: String, n: &'a Num, d: Dimension| {
            if let Num::Expr(e) = n {
                out.push((field, e.as_str(), d));
            }
        };
        num("hip_mass".into(), &self.hip_mass, Dimension::MASS);
        num("foot_radius".into(), &self.foot_radius, Dimension::LENGTH);
        for (i, s) in self.segments.iter().enumerate() {
            let f = |k: &str| format!("segments[{i}].{k}");
            num(f("length"), &s.length, Dimension::LENGTH);
            num(f("mass"), &s.mass, Dimension::MASS);
            num(f("com"), &s.com, Dimension::LENGTH);
            num(f("com_normal"), &s.com_normal, Dimension::LENGTH);
            num(f("inertia"), &s.inertia, Dimension::INERTIA);
        }
        let section = [
            Dimension::ANGLE,
            Dimension::ANGULAR_RATE,
            Dimension::ANGULAR_RATE,
        ];
        for (i, g) in self.gaits.iter().enumerate() {
            for (j, (v, d)) in g.section.iter().zip(section).enumerate() {
                num(format!("gaits[{i}].section[{j}]"), v, d);
            }
        }
        for (i, k) in self.knees.iter().enumerate() {
            if !matches!(k.mode.trim(), "locked" | "free-swing" | "free_swing") {
                out.push((
                    format!("knees[{i}].mode"),
                    k.mode.as_str(),
                    Dimension::DIMENSIONLESS,
                ));
            }
        }
        out
    }

    /// Refuses a unit of another dimension than its parameter's role: a builtin parameter
    /// whose unit is not of its quantity (`max_stride_time` in `m`), and a field whose
    /// expression, computed in its parameters' units, is not of the field's quantity
    /// ([`WalkerSpec::dimensioned_fields`]: `hip_mass` in `deg`, a length in `rad`). A field
    /// that is one parameter blames the parameter's unit; an expression that adds two
    /// quantities or is of the wrong quantity is blamed as written. Expressions that do not
    /// evaluate are left to [`WalkerSpec::resolve`], which says why.
    fn check_dimensions(&self, source_name: &str, system: UnitSystem) -> Result<(), WalkerError> {
        let fail = |field: String, value: String, rule: String| WalkerError::InvalidSpec {
            source_name: source_name.to_string(),
            field,
            value,
            rule,
        };
        for (name, _, unit, _) in BUILTIN_PARAMS {
            let (Some(p), Ok(expected)) = (self.parameters.get(name), units::dimension_of(unit))
            else {
                continue;
            };
            let given = units::dimension_of(&p.unit).unwrap_or(expected);
            if !expected.accepts(given) {
                return Err(fail(
                    format!("parameters.{name}.unit"),
                    format!("\"{}\"", p.unit),
                    units::mismatch(&p.unit, given, name, expected, system),
                ));
            }
        }
        let table = self.param_table();
        let values: Vec<(&str, f64)> = table
            .names
            .iter()
            .map(String::as_str)
            .zip(table.values.iter().copied())
            .collect();
        let quantities: Vec<(&str, units::Quantity)> = values
            .iter()
            .zip(&table.units)
            .map(|(&(n, value), u)| {
                let dim = units::dimension_of(u).ok();
                (n, units::Quantity { value, dim })
            })
            .collect();
        for (field, e, expected) in self.dimensioned_fields() {
            if eval_expr(e, &values).is_err() {
                continue;
            }
            let used = || {
                let names: Vec<String> = tokenize(e)
                    .unwrap_or_default()
                    .into_iter()
                    .filter_map(|t| match t {
                        Tok::Name(n) => Some(n),
                        _ => None,
                    })
                    .collect();
                let mut shown: Vec<String> = Vec::new();
                for n in names {
                    let unit = self.parameters.get(&n).map_or_else(
                        || table.get_unit(&n).unwrap_or("1").to_string(),
                        |p| p.unit.clone(),
                    );
                    let item = format!("{n} in `{unit}`");
                    if !shown.contains(&item) {
                        shown.push(item);
                    }
                }
                shown.join(", ")
            };
            match eval_in(e, &quantities) {
                Err(why) => {
                    return Err(fail(
                        field.clone(),
                        quoted(e),
                        format!("{why} ({}); {field} is {}", used(), expected.name()),
                    ))
                }
                Ok(units::Quantity { dim: Some(d), .. }) if !expected.accepts(d) => {
                    let what = match self.parameters.get(e.trim()) {
                        Some(p) => {
                            let name = e.trim();
                            let mut rule = units::mismatch(&p.unit, d, name, expected, system);
                            if field != name {
                                rule.push_str(&format!(" (it is the spec's {field})"));
                            }
                            fail(
                                format!("parameters.{name}.unit"),
                                format!("\"{}\"", p.unit),
                                rule,
                            )
                        }
                        None => fail(
                            field.clone(),
                            quoted(e),
                            format!(
                                "it is {} ({}), {field} is {} ({}, …)",
                                d.name(),
                                used(),
                                expected.name(),
                                expected.examples(system)
                            ),
                        ),
                    };
                    return Err(what);
                }
                Ok(_) => {}
            }
        }
        Ok(())
    }

    /// Reads and parses a spec file: a regular file (after following links) of at most
    /// [`MAX_SPEC_BYTES`]; devices, FIFOs and directories are refused before reading.
    pub fn from_file(path: &std::path::Path) -> Result<Self, WalkerError> {
        use std::io::Read;
        let name = path.display().to_string();
        let fail = |message: String| WalkerError::SpecSyntax {
            source_name: name.clone(),
            message,
        };
        let meta =
            std::fs::metadata(path).map_err(|e| fail(format!("cannot read the spec file: {e}")))?;
        if !meta.is_file() {
            return Err(fail(
                "not a regular file (a directory, device, FIFO or socket); a spec is a TOML file"
                    .into(),
            ));
        }
        let too_big = || {
            fail(format!(
                "the spec file is larger than {} KiB; a spec is a short TOML file",
                MAX_SPEC_BYTES >> 10
            ))
        };
        if meta.len() > MAX_SPEC_BYTES {
            return Err(too_big());
        }
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|f| f.take(MAX_SPEC_BYTES + 1).read_to_end(&mut bytes))
            .map_err(|e| fail(format!("cannot read the spec file: {e}")))?;
        // a file that grew while being read
        if bytes.len() as u64 > MAX_SPEC_BYTES {
            return Err(too_big());
        }
        let text = String::from_utf8(bytes)
            .map_err(|_| fail("cannot read the spec file: it is not UTF-8 text".into()))?;
        Self::from_toml(&text, &name)
    }

    /// The spec as TOML text (parses back to an equal spec).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }

    /// The parameter table with the spec's defaults (builtins added where missing), each value
    /// converted into its base unit ([`crate::units::to_base`]: `3 deg` is 0.0523… rad, `50 cm`
    /// 0.5 m) and listed with that unit. A unit the table refuses is left as written here;
    /// [`WalkerSpec::resolve`] refuses it.
    pub fn param_table(&self) -> ParamTable {
        let system = self.unit_system();
        let base = |p: &ParamDef| {
            units::to_base(p.value, &p.unit, system).unwrap_or_else(|_| (p.value, p.unit.clone()))
        };
        let mut t = ParamTable {
            names: vec![],
            values: vec![],
            units: vec![],
            descriptions: vec![],
        };
        // builtins first, in a fixed order, then the spec's own names sorted
        for (name, default, unit, desc) in BUILTIN_PARAMS {
            let (v, u, d) = match self.parameters.get(name) {
                Some(p) => {
                    let (v, u) = base(p);
                    (v, u, p.description.clone())
                }
                None => (default, unit.to_string(), desc.to_string()),
            };
            t.names.push(name.to_string());
            t.values.push(v);
            t.units.push(u);
            t.descriptions.push(d);
        }
        for (name, p) in &self.parameters {
            if BUILTIN_PARAMS.iter().any(|b| b.0 == name) {
                continue;
            }
            let (v, u) = base(p);
            t.names.push(name.clone());
            t.values.push(v);
            t.units.push(u);
            t.descriptions.push(p.description.clone());
        }
        t
    }

    fn err(
        &self,
        field: impl Into<String>,
        value: impl Into<String>,
        rule: impl Into<String>,
    ) -> WalkerError {
        WalkerError::InvalidSpec {
            source_name: self.name.clone(),
            field: field.into(),
            value: value.into(),
            rule: rule.into(),
        }
    }
}

fn is_identifier(s: &str) -> bool {
    let mut c = s.chars();
    matches!(c.next(), Some(ch) if ch.is_ascii_alphabetic() || ch == '_')
        && c.all(|ch| ch.is_ascii_alphanumeric() || ch == '_')
}

/// Largest spec file read, in bytes (the presets are a few KiB).
pub const MAX_SPEC_BYTES: u64 = 1 << 20;

/// Longest expression evaluated, in characters.
pub const MAX_EXPR_CHARS: usize = 10_000;

/// Deepest nesting of parentheses, unary minus and powers in an expression (the parser
/// recurses once per level; the limit keeps a hostile spec from exhausting the stack).
pub const MAX_EXPR_DEPTH: usize = 256;

/// Characters of an expression echoed in a message.
const SHOWN_EXPR_CHARS: usize = 80;

/// An expression quoted for a message: whole up to 80 characters, else its start and its
/// length.
pub fn quoted(e: &str) -> String {
    let n = e.chars().count();
    if n <= SHOWN_EXPR_CHARS {
        format!("\"{e}\"")
    } else {
        let head: String = e.chars().take(SHOWN_EXPR_CHARS).collect();
        format!("\"{head}…\" ({n} characters)")
    }
}

/// Evaluates an arithmetic expression over `env`: numbers (`0.5`, `1e-3`), parameter names,
/// `+ − * /`, powers `^` or `**`, unary minus and parentheses, with the usual precedence — `^`
/// first and right-associative (`2^3^2` = 512), then unary minus (`-2^2` = −4, as in
/// mathematics and Python), then `* /`, then `+ −`, each left to right. Errors name what is
/// wrong. Expressions longer than [`MAX_EXPR_CHARS`] or nested (parentheses, unary minus,
/// powers) deeper than [`MAX_EXPR_DEPTH`] are refused.
pub fn eval_expr(text: &str, env: &[(&str, f64)]) -> Result<f64, String> {
    eval_in(text, env)
}

/// What an expression computes in, by one grammar: plain numbers ([`eval_expr`]) or
/// quantities with a dimension ([`crate::units::Quantity`], the spec's unit check).
pub(crate) trait Arith: Copy {
    fn number(v: f64) -> Self;
    fn add(self, r: Self, minus: bool) -> Result<Self, String>;
    fn mul(self, r: Self, divide: bool) -> Self;
    fn neg(self) -> Self;
    fn pow(self, e: Self) -> Result<Self, String>;
}

impl Arith for f64 {
    fn number(v: f64) -> Self {
        v
    }
    fn add(self, r: Self, minus: bool) -> Result<Self, String> {
        Ok(if minus { self - r } else { self + r })
    }
    fn mul(self, r: Self, divide: bool) -> Self {
        if divide {
            self / r
        } else {
            self * r
        }
    }
    fn neg(self) -> Self {
        -self
    }
    fn pow(self, e: Self) -> Result<Self, String> {
        Ok(self.powf(e))
    }
}

impl Arith for units::Quantity {
    fn number(v: f64) -> Self {
        Self {
            value: v,
            dim: None,
        }
    }
    fn add(self, r: Self, minus: bool) -> Result<Self, String> {
        units::Quantity::add(self, r, minus)
    }
    fn mul(self, r: Self, divide: bool) -> Self {
        units::Quantity::mul(self, r, divide)
    }
    fn neg(self) -> Self {
        Self {
            value: -self.value,
            ..self
        }
    }
    fn pow(self, e: Self) -> Result<Self, String> {
        units::Quantity::pow(self, e)
    }
}

/// [`eval_expr`] in the arithmetic `T`.
pub(crate) fn eval_in<T: Arith>(text: &str, env: &[(&str, T)]) -> Result<T, String> {
    let n = text.chars().count();
    if n > MAX_EXPR_CHARS {
        return Err(format!(
            "the expression has {n} characters, more than the {MAX_EXPR_CHARS} allowed"
        ));
    }
    let toks = tokenize(text)?;
    let mut p = Parser {
        toks: &toks,
        i: 0,
        env,
        depth: 0,
    };
    let v = p.sum()?;
    if p.i != toks.len() {
        return Err(format!("unexpected `{}` in the expression", toks[p.i]));
    }
    Ok(v)
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(f64),
    Name(String),
    Op(char),
}

impl std::fmt::Display for Tok {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Tok::Num(v) => write!(f, "{v}"),
            Tok::Name(n) => write!(f, "{n}"),
            Tok::Op(c) => write!(f, "{c}"),
        }
    }
}

fn tokenize(s: &str) -> Result<Vec<Tok>, String> {
    let b: Vec<char> = s.chars().collect();
    let mut out = vec![];
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c.is_whitespace() {
            i += 1;
        } else if c == '*' && b.get(i + 1) == Some(&'*') {
            // `**` is `^` (Python's and Fortran's power)
            out.push(Tok::Op('^'));
            i += 2;
        } else if "+-*/^()".contains(c) {
            out.push(Tok::Op(c));
            i += 1;
        } else if c.is_ascii_digit() || c == '.' {
            let st = i;
            while i < b.len()
                && (b[i].is_ascii_digit()
                    || b[i] == '.'
                    || b[i] == 'e'
                    || b[i] == 'E'
                    || ((b[i] == '-' || b[i] == '+')
                        && i > st
                        && (b[i - 1] == 'e' || b[i - 1] == 'E')))
            {
                i += 1;
            }
            let t: String = b[st..i].iter().collect();
            out.push(Tok::Num(
                t.parse().map_err(|_| format!("`{t}` is not a number"))?,
            ));
        } else if c.is_ascii_alphabetic() || c == '_' {
            let st = i;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == '_') {
                i += 1;
            }
            out.push(Tok::Name(b[st..i].iter().collect()));
        } else {
            return Err(format!("unexpected character `{c}` in the expression"));
        }
    }
    if out.is_empty() {
        return Err("empty expression".into());
    }
    Ok(out)
}

struct Parser<'a, T> {
    toks: &'a [Tok],
    i: usize,
    env: &'a [(&'a str, T)],
    /// Open parentheses, unary minuses and power exponents around the current token.
    depth: usize,
}

impl<T: Arith> Parser<'_, T> {
    /// Enters one level of nesting, refusing more than [`MAX_EXPR_DEPTH`].
    fn nest(&mut self) -> Result<(), String> {
        self.depth += 1;
        if self.depth > MAX_EXPR_DEPTH {
            return Err(format!(
                "the expression nests parentheses, unary minus or powers more than \
                 {MAX_EXPR_DEPTH} levels deep"
            ));
        }
        Ok(())
    }

    fn sum(&mut self) -> Result<T, String> {
        let mut v = self.product()?;
        while let Some(Tok::Op(c @ ('+' | '-'))) = self.toks.get(self.i) {
            self.i += 1;
            let r = self.product()?;
            v = v.add(r, *c == '-')?;
        }
        Ok(v)
    }
    fn product(&mut self) -> Result<T, String> {
        let mut v = self.unary()?;
        while let Some(Tok::Op(c @ ('*' | '/'))) = self.toks.get(self.i) {
            self.i += 1;
            let r = self.unary()?;
            v = v.mul(r, *c == '/');
        }
        Ok(v)
    }
    /// A unary minus applies to the power after it: `-2^2` is `-(2^2)` = −4, as in
    /// mathematics (and Python's `-2**2`).
    fn unary(&mut self) -> Result<T, String> {
        if let Some(Tok::Op('-')) = self.toks.get(self.i) {
            self.i += 1;
            self.nest()?;
            let v = self.unary()?.neg();
            self.depth -= 1;
            return Ok(v);
        }
        self.power()
    }
    /// `a ^ b` (or `a ** b`): right-associative (`2^3^2` is `2^(3^2)` = 512), binding tighter
    /// than a unary minus on its left; the exponent may carry its own minus (`2^-1` = 0.5).
    fn power(&mut self) -> Result<T, String> {
        let base = self.atom()?;
        if let Some(Tok::Op('^')) = self.toks.get(self.i) {
            self.i += 1;
            self.nest()?;
            let exponent = self.unary()?;
            self.depth -= 1;
            return base.pow(exponent);
        }
        Ok(base)
    }
    fn atom(&mut self) -> Result<T, String> {
        let t = self.toks.get(self.i).cloned();
        self.i += 1;
        match t {
            Some(Tok::Num(v)) => Ok(T::number(v)),
            Some(Tok::Name(n)) => self
                .env
                .iter()
                .find(|(k, _)| *k == n)
                .map(|p| p.1)
                .ok_or_else(|| {
                    format!(
                        "unknown parameter `{n}` (parameters: {})",
                        self.env.iter().map(|p| p.0).collect::<Vec<_>>().join(", ")
                    )
                }),
            Some(Tok::Op('(')) => {
                self.nest()?;
                let v = self.sum()?;
                self.depth -= 1;
                match self.toks.get(self.i) {
                    Some(Tok::Op(')')) => {
                        self.i += 1;
                        Ok(v)
                    }
                    _ => Err("missing `)`".into()),
                }
            }
            Some(t) => Err(format!("unexpected `{t}` in the expression")),
            None => Err("the expression ends too early".into()),
        }
    }
}
