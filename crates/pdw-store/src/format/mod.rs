//! Every file format declared once: for each dataset and attribute its path, type and shape,
//! unit, meaning, and the checksum or digest that covers it ([`Format`], [`Item`]).
//!
//! The tables ([`ALL`]: [`BASIN`], [`SWEEP`], [`CURVE`], [`STABILITY`], [`TRAJECTORY`],
//! [`MFPT`], [`MFPT_CURVE`], [`MFPT_OVER`], [`DESIGN`]) are what the rest
//! reads: the `units` attribute of every dataset comes from [`Format::units`] (a unit that
//! depends on the model is a [`Unit`] rule resolved against the run's [`UnitContext`], not a
//! closure per command); the tables of `docs/hdf5.md` are [`Format::markdown`] (a test fails
//! when they are stale); and the tests write each format and check that every dataset and
//! attribute in the file is declared and every declared one is present ([`Format::check`]).
//!
//! # Paths
//! A dataset or group is named by its path without the leading `/` (`basin/outcome`); an
//! attribute by its holder's path, `@` and its name (`@format` on the root,
//! `basin/outcome@legend`). A segment part in angle brackets matches any non-empty name
//! without `/`: `attractors/<name>/section`, `metrics@fraction_<name>`.
//!
//! The dimension-scale attributes (`CLASS`, `NAME`, `REFERENCE_LIST`, `DIMENSION_LIST`, see
//! [`crate::provenance`]) and the `units` attribute of each dataset are declared once for all
//! files ([`GENERIC_ATTRS`]); the `unit` column says what `units` holds.

mod series;
mod tables;

pub use series::{CURVE, MFPT_CURVE, MFPT_OVER, STABILITY};
pub use tables::{BASIN, DESIGN, MFPT, PROVENANCE, SWEEP, TRAJECTORY};

/// Every declared format, in the order of `docs/hdf5.md`.
pub const ALL: [&Format; 9] = [
    &BASIN,
    &SWEEP,
    &CURVE,
    &STABILITY,
    &TRAJECTORY,
    &MFPT,
    &MFPT_CURVE,
    &MFPT_OVER,
    &DESIGN,
];

/// The attributes every file may carry on any dataset, declared here once rather than per item:
/// the dataset's `units` (its value is the item's [`Unit`]) and the HDF5 dimension-scale
/// attributes.
pub const GENERIC_ATTRS: [&str; 5] = ["units", "CLASS", "NAME", "REFERENCE_LIST", "DIMENSION_LIST"];

/// A declared file format: the value of its root attribute `format` and its items, in parts
/// (a part may be shared by several formats, e.g. [`PROVENANCE`]).
#[derive(Debug)]
pub struct Format {
    /// Short name, e.g. `"basin"` (the marker of its table in `docs/hdf5.md`).
    pub name: &'static str,
    /// The root attribute `format`, e.g. `"pdw-sweep basin v1"`.
    pub format: &'static str,
    /// The items, part by part.
    pub parts: &'static [&'static [Item]],
}

/// One dataset or attribute of a format.
#[derive(Clone, Copy, Debug)]
pub struct Item {
    /// `group/dataset`, or `holder@attribute` (`@name` on the root); see the module docs.
    pub path: &'static str,
    /// Element type: `u8`, `u16`, `u64`, `f64`, `bool`, `str` (UTF-8 text), `json` (UTF-8 JSON
    /// text), `group`.
    pub dtype: &'static str,
    /// Shape of a dataset, e.g. `[ny, nx]`; empty for an attribute or a group.
    pub shape: &'static str,
    /// What its `units` attribute holds (datasets); [`Unit::None`] for attributes and groups.
    pub unit: Unit,
    /// What it means.
    pub meaning: &'static str,
    /// The checksum or digest that covers it, if any (e.g. `header_digest`).
    pub covered_by: Option<&'static str>,
    /// `None`: in every file of the format; `Some(when)`: only when `when` holds.
    pub when: Option<&'static str>,
}

impl Item {
    /// An item present in every file, covered by no digest.
    pub const fn new(
        path: &'static str,
        dtype: &'static str,
        shape: &'static str,
        unit: Unit,
        meaning: &'static str,
    ) -> Self {
        Item {
            path,
            dtype,
            shape,
            unit,
            meaning,
            covered_by: None,
            when: None,
        }
    }
    /// An attribute (no shape, no unit).
    pub const fn attr(path: &'static str, dtype: &'static str, meaning: &'static str) -> Self {
        Item::new(path, dtype, "", Unit::None, meaning)
    }
    /// A group.
    pub const fn group(path: &'static str, meaning: &'static str) -> Self {
        Item::new(path, "group", "", Unit::None, meaning)
    }
    /// The same item, covered by `digest`.
    pub const fn covered(mut self, digest: &'static str) -> Self {
        self.covered_by = Some(digest);
        self
    }
    /// The same item, present only when `when` holds.
    pub const fn only(mut self, when: &'static str) -> Self {
        self.when = Some(when);
        self
    }
    /// Whether this is an attribute (its path holds `@`).
    pub fn is_attr(&self) -> bool {
        self.path.contains('@')
    }
    /// Whether `path` (a concrete dataset, group or `holder@attribute`) is this item.
    pub fn matches(&self, path: &str) -> bool {
        glob(self.path.as_bytes(), path.as_bytes())
    }
}

/// What a dataset's `units` attribute holds, as a rule resolved against a run's
/// [`UnitContext`] ([`Unit::resolve`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    /// No `units` attribute (attributes and groups).
    None,
    /// `"1"`: codes, counts, flags, digests, dimensionless numbers.
    One,
    /// A fixed unit, e.g. `"rad"`.
    Fixed(&'static str),
    /// A JSON list of the units of the section coordinates, in order (the last axis runs over
    /// them), e.g. `["rad","rad/s"]`.
    Section,
    /// The unit of the section coordinate along grid axis 0 (x), 1 (y) or 2 (z).
    Axis(usize),
    /// The unit of section coordinate `i` (e.g. a design's basin box, stance and its rate).
    SectionCoordinate(usize),
    /// The unit of a model quantity.
    Model(Quantity),
    /// A JSON list of the units of the free parameters (a design's `params`).
    FreeParameters,
    /// The unit of the swept parameter (a sweep's, `--over`'s, a curve's stepped one).
    Parameter,
    /// The unit of the free parameter of a two-parameter curve (the first of the context's
    /// free parameters).
    FreeParameter,
    /// The unit of the terrain's mean and spread: `rad` for slopes, the model's length unit
    /// for step heights.
    Terrain,
    /// The maximum over the coordinates of the dataset named (a residual's `max over
    /// /curve/section's coordinates ["rad","rad/s"]`).
    MaxOverSection(&'static str),
    /// A JSON list of the units of the state components, in order.
    State,
    /// Written by the writer with the data (a trajectory column's own unit); not annotated.
    Own,
}

/// A quantity of the model whose unit depends on its unit system (e.g. `s` or `sqrt(l/g)`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    Time,
    Length,
    Force,
    Torque,
    /// Length per time (`{length}/{time}`).
    Speed,
}

/// The units of one run, from its model: what the [`Unit`] rules resolve against. Fields a
/// format does not use may stay empty.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UnitContext {
    /// Unit of each section coordinate, in order.
    pub section: Vec<String>,
    /// The section coordinates along the grid axes x, y (and z), by index into `section`.
    pub axes: Vec<usize>,
    /// The model's time, length, force and torque units.
    pub time: String,
    pub length: String,
    pub force: String,
    pub torque: String,
    /// Units of the free parameters (design).
    pub free_parameters: Vec<String>,
    /// Unit of the swept parameter (sweep, `--over`, a curve's stepped parameter).
    pub parameter: String,
    /// Unit of the terrain's mean and spread (MFPT curve).
    pub terrain: String,
    /// Unit of each state component, in order (trajectory).
    pub state: Vec<String>,
}

impl Unit {
    /// The `units` attribute this rule gives under `c`; `None` writes none (an attribute, or a
    /// quantity `c` does not know, e.g. the z axis of a 2-D grid).
    pub fn resolve(&self, c: &UnitContext) -> Option<String> {
        let list = |u: &[String]| serde_json::to_string(u).unwrap_or_default();
        let section = |i: Option<&usize>| i.and_then(|&i| c.section.get(i)).cloned();
        match self {
            Unit::None => None,
            Unit::One => Some("1".into()),
            Unit::Fixed(u) => Some((*u).into()),
            Unit::Section => Some(list(&c.section)),
            Unit::Axis(k) => section(c.axes.get(*k)),
            Unit::SectionCoordinate(i) => Some(c.section.get(*i).cloned().unwrap_or_default()),
            Unit::Model(q) => Some(match q {
                Quantity::Time => c.time.clone(),
                Quantity::Length => c.length.clone(),
                Quantity::Force => c.force.clone(),
                Quantity::Torque => c.torque.clone(),
                Quantity::Speed => format!("{}/{}", c.length, c.time),
            }),
            Unit::FreeParameters => Some(list(&c.free_parameters)),
            Unit::Parameter => Some(c.parameter.clone()),
            Unit::FreeParameter => Some(c.free_parameters.first().cloned().unwrap_or_default()),
            Unit::Terrain => Some(c.terrain.clone()),
            Unit::MaxOverSection(d) => {
                Some(format!("max over /{d}'s coordinates {}", list(&c.section)))
            }
            Unit::State => Some(list(&c.state)),
            Unit::Own => None,
        }
    }

    /// The rule in words, for the docs' tables.
    pub fn describe(&self) -> String {
        match self {
            Unit::None => String::new(),
            Unit::One => "`1`".into(),
            Unit::Fixed(u) => format!("`{u}`"),
            Unit::Section => "section units (JSON list)".into(),
            Unit::Axis(k) => format!("its coordinate's ({})", ["x", "y", "z"][(*k).min(2)]),
            Unit::SectionCoordinate(i) => format!("section coordinate {i}'s"),
            Unit::Model(q) => format!("model {}", format!("{q:?}").to_lowercase()),
            Unit::FreeParameters => "free parameters' units (JSON list)".into(),
            Unit::Parameter => "the swept parameter's".into(),
            Unit::FreeParameter => "the free parameter's".into(),
            Unit::Terrain => "the terrain's (`rad`, or the model's length)".into(),
            Unit::MaxOverSection(d) => format!("max over `{d}`'s coordinates (their units)"),
            Unit::State => "state units (JSON list)".into(),
            Unit::Own => "its own (written with it)".into(),
        }
    }
}

/// A difference between a file and its declared format ([`Format::check`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Mismatch {
    /// In the file but declared by no item.
    pub undeclared: Vec<String>,
    /// Declared as always present but not in the file.
    pub missing: Vec<String>,
}

impl Mismatch {
    /// Whether the file and the format agree.
    pub fn is_empty(&self) -> bool {
        self.undeclared.is_empty() && self.missing.is_empty()
    }
}

impl Format {
    /// Every item, part by part.
    pub fn items(&self) -> impl Iterator<Item = &'static Item> {
        self.parts.iter().flat_map(|p| p.iter())
    }

    /// The item that declares `path` (a dataset, group or `holder@attribute`).
    pub fn find(&self, path: &str) -> Option<&'static Item> {
        self.items().find(|i| i.matches(path))
    }

    /// The `units` attribute of every dataset by path, under the run's units `c`: what
    /// [`crate::Annotations::units`] takes.
    pub fn units<'a>(&'static self, c: &'a UnitContext) -> impl Fn(&str) -> Option<String> + 'a {
        move |p: &str| {
            self.find(p)
                .filter(|i| !i.is_attr())
                .and_then(|i| i.unit.resolve(c))
        }
    }

    /// Compares `present` (every group, dataset and `holder@attribute` of a file, as
    /// [`inventory`] lists them) with the table: what is undeclared, and which items declared
    /// as always present are missing. [`GENERIC_ATTRS`] are declared for every holder.
    pub fn check(&self, present: &[String]) -> Mismatch {
        let generic = |p: &str| {
            p.rsplit_once('@')
                .is_some_and(|(_, a)| GENERIC_ATTRS.contains(&a))
        };
        Mismatch {
            undeclared: present
                .iter()
                .filter(|p| !generic(p) && self.find(p).is_none())
                .cloned()
                .collect(),
            missing: self
                .items()
                .filter(|i| i.when.is_none() && !present.iter().any(|p| i.matches(p)))
                .map(|i| i.path.to_string())
                .collect(),
        }
    }

    /// The format as a Markdown table (the generated part of `docs/hdf5.md`): one row per item
    /// with its type and shape, unit, meaning (and when present), and the digest covering it.
    pub fn markdown(&self) -> String {
        let mut s = format!(
            "| `{}` | type | unit | meaning | covered by |\n|---|---|---|---|---|\n",
            self.format
        );
        let cell = |t: &str| t.replace('|', "\\|");
        for i in self.items() {
            let ty = if i.shape.is_empty() {
                i.dtype.to_string()
            } else {
                format!("{} {}", i.dtype, i.shape)
            };
            let meaning = match i.when {
                Some(w) => format!("{} ({w} only)", i.meaning),
                None => i.meaning.to_string(),
            };
            s.push_str(&format!(
                "| `{}` | {} | {} | {} | {} |\n",
                i.path,
                cell(&ty),
                cell(&i.unit.describe()),
                cell(&meaning),
                i.covered_by.map_or(String::new(), |d| format!("`{d}`")),
            ));
        }
        s
    }
}

/// Every group, dataset and attribute of the file at `path`, as the tables name them (see the
/// module docs), in name order.
pub fn inventory(path: &std::path::Path) -> crate::Result<Vec<String>> {
    use crate::h5util::At;
    fn attrs(
        path: &std::path::Path,
        loc: &hdf5::Location,
        at: &str,
        out: &mut Vec<String>,
    ) -> crate::Result<()> {
        for a in loc.attr_names().at(path, "listing attributes")? {
            out.push(format!("{at}@{a}"));
        }
        Ok(())
    }
    fn walk(
        path: &std::path::Path,
        g: &hdf5::Group,
        prefix: &str,
        out: &mut Vec<String>,
    ) -> crate::Result<()> {
        let mut names = g.member_names().at(path, "listing a group")?;
        names.sort();
        for name in names {
            let full = if prefix.is_empty() {
                name.clone()
            } else {
                format!("{prefix}/{name}")
            };
            out.push(full.clone());
            if let Ok(sub) = g.group(&name) {
                attrs(path, &sub, &full, out)?;
                walk(path, &sub, &full, out)?;
            } else if let Ok(d) = g.dataset(&name) {
                attrs(path, &d, &full, out)?;
            }
        }
        Ok(())
    }
    let f = crate::h5util::open_file(path, false)?;
    let mut out = Vec::new();
    attrs(path, &f, "", &mut out)?;
    walk(path, &f, "", &mut out)?;
    Ok(out)
}

/// Whether `text` matches `pat`, where `<…>` in `pat` matches one or more bytes other than `/`.
fn glob(pat: &[u8], text: &[u8]) -> bool {
    match pat.first() {
        None => text.is_empty(),
        Some(b'<') => {
            let close = pat.iter().position(|&b| b == b'>').unwrap_or(pat.len() - 1);
            let rest = &pat[close + 1..];
            (1..=text.len())
                .take_while(|&n| text[n - 1] != b'/')
                .any(|n| glob(rest, &text[n..]))
        }
        Some(&c) => text.first() == Some(&c) && glob(&pat[1..], &text[1..]),
    }
}
