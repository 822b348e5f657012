//! What a finished basin file adds: the grid's [`BasinMetrics`] and the [`Attractor`]s its cells
//! were classified by (`/metrics`, `/attractors`), written by [`BasinWriter::finish`] and read
//! back.
//!
//! [`BasinWriter::finish`]: super::BasinWriter::finish

use std::path::Path;

use hdf5::{File, Group};
use ndarray::Array2;

use super::{format_err, KIND};
use crate::h5util::{get_attr, get_str, has_attr, set_attr, set_str, At};
use crate::{Result, StoreError};

/// Basin metrics of a finished grid (computed by the caller).
#[derive(Clone, Debug, PartialEq)]
pub struct BasinMetrics {
    /// Fraction of the file's cells per outcome name.
    pub fractions: Vec<(String, f64)>,
    /// Basin entropy S_b (Daza et al. 2016, Sci. Rep. 6:31416, eq. 3): mean over ε-boxes of
    /// −Σ p log p of the outcome frequencies in the box.
    pub basin_entropy: f64,
    /// Basin-boundary entropy S_bb (Daza et al. 2016, eq. 4): the same sum averaged over the
    /// boxes holding more than one outcome only.
    pub boundary_entropy: f64,
    /// Side ε of the boxes, in cells.
    pub entropy_box: usize,
}

/// An attractor used to classify cells (the selected gait, a period-2 orbit, a chaotic
/// attractor…). Its legend entry is the one of the same name. A chaotic attractor has
/// `period_strides` 0, `period_time` NaN, no multipliers, and a sample of consecutive points on
/// it as `section`.
#[derive(Clone, Debug, PartialEq)]
pub struct Attractor {
    /// Name, e.g. `"gait"`; unique in a file, no `/`.
    pub name: String,
    /// Strides per period (1 for a fixed point of the stride map).
    pub period_strides: u32,
    /// Duration of one period (model time units).
    pub period_time: f64,
    /// The `period_strides` points of the orbit on the section (a sample of points for a chaotic
    /// attractor), each of length d.
    pub section: Vec<Vec<f64>>,
    /// Floquet multipliers `(re, im)`, by decreasing modulus.
    pub multipliers: Vec<(f64, f64)>,
    /// Physical validity of the orbit (attributes `validity`, `invalid_reasons` of its group;
    /// files without them read as unchecked).
    pub validity: OrbitCheck,
}

/// Physical validity of an attractor's orbit as a file records it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum OrbitCheck {
    /// The model reports no constraint forces, or the attractor is chaotic.
    #[default]
    Unchecked,
    /// Every stride of the orbit valid.
    Valid,
    /// What fails (e.g. "a knee lock must pull"), each named once.
    Invalid(Vec<String>),
}

impl OrbitCheck {
    /// The `validity` attribute's value: `valid`, `invalid` or `not checked`.
    pub fn word(&self) -> &'static str {
        match self {
            OrbitCheck::Unchecked => "not checked",
            OrbitCheck::Valid => "valid",
            OrbitCheck::Invalid(_) => "invalid",
        }
    }

    /// What fails, if the orbit is invalid.
    pub fn reasons(&self) -> Option<&[String]> {
        match self {
            OrbitCheck::Invalid(r) => Some(r),
            _ => None,
        }
    }
}

impl Attractor {
    /// Equal name and period, and every number equal bit for bit (so that a chaotic
    /// attractor's NaN `period_time` equals itself): what [`crate::merge`] requires of shards.
    pub fn same_as(&self, other: &Attractor) -> bool {
        let bits = |v: &[f64], w: &[f64]| {
            v.len() == w.len() && v.iter().zip(w).all(|(a, b)| a.to_bits() == b.to_bits())
        };
        self.name == other.name
            && self.period_strides == other.period_strides
            && self.period_time.to_bits() == other.period_time.to_bits()
            && self.section.len() == other.section.len()
            && self
                .section
                .iter()
                .zip(&other.section)
                .all(|(a, b)| bits(a, b))
            && self.multipliers.len() == other.multipliers.len()
            && self
                .multipliers
                .iter()
                .zip(&other.multipliers)
                .all(|(a, b)| bits(&[a.0, a.1], &[b.0, b.1]))
            && self.validity == other.validity
    }

    /// `name (period k, n points)`, for messages.
    pub fn summary(&self) -> String {
        format!(
            "{} (period {}, {} points)",
            self.name,
            self.period_strides,
            self.section.len()
        )
    }
}

pub(crate) fn write_metrics(path: &Path, file: &File, m: &BasinMetrics) -> Result<()> {
    if file.link_exists("metrics") {
        file.unlink("metrics").at(path, "replacing /metrics")?;
    }
    let g = file.create_group("metrics").at(path, "creating /metrics")?;
    set_attr(path, &g, "basin_entropy", &m.basin_entropy)?;
    set_attr(path, &g, "boundary_entropy", &m.boundary_entropy)?;
    set_attr(path, &g, "entropy_box", &(m.entropy_box as u64))?;
    let mut obj = serde_json::Map::new();
    for (name, f) in &m.fractions {
        if name.is_empty() || name.contains('/') {
            return Err(StoreError::invalid(
                "metrics",
                format!("bad outcome name {name:?}"),
            ));
        }
        obj.insert(name.clone(), serde_json::json!(f));
        set_attr(path, &g, &format!("fraction_{name}"), f)?;
    }
    set_str(
        path,
        &g,
        "fractions",
        &serde_json::Value::Object(obj).to_string(),
    )
}

pub(crate) fn write_attractors(
    path: &Path,
    file: &File,
    list: &[Attractor],
    d: usize,
) -> Result<()> {
    for (i, a) in list.iter().enumerate() {
        if a.name.is_empty() || a.name.contains('/') || a.name == "." || a.name == ".." {
            return Err(StoreError::invalid(
                "attractor",
                format!("bad name {:?}", a.name),
            ));
        }
        if list[..i].iter().any(|b| b.name == a.name) {
            return Err(StoreError::invalid(
                "attractor",
                format!("duplicate name {:?}", a.name),
            ));
        }
        if a.section.is_empty() || a.section.iter().any(|p| p.len() != d) {
            return Err(StoreError::invalid(
                "attractor",
                format!("{}: section points must each have d = {d} values", a.name),
            ));
        }
    }
    if file.link_exists("attractors") {
        file.unlink("attractors")
            .at(path, "replacing /attractors")?;
    }
    let g = file
        .create_group("attractors")
        .at(path, "creating /attractors")?;
    for a in list {
        let ga = g.create_group(&a.name).at(path, "creating an attractor")?;
        set_attr(path, &ga, "period_strides", &a.period_strides)?;
        // The same number under the name of `fixedpoint --period K` (0: chaotic).
        set_attr(path, &ga, "period_k", &a.period_strides)?;
        set_attr(path, &ga, "period_time", &a.period_time)?;
        let k = a.section.len();
        let flat: Vec<f64> = a.section.iter().flatten().copied().collect();
        let sec = Array2::from_shape_vec((k, d), flat).expect("lengths checked");
        ga.new_dataset_builder()
            .with_data(&sec)
            .create("section")
            .at(path, "writing an attractor")?;
        let re: Vec<f64> = a.multipliers.iter().map(|m| m.0).collect();
        let im: Vec<f64> = a.multipliers.iter().map(|m| m.1).collect();
        for (n, v) in [("multipliers_re", re), ("multipliers_im", im)] {
            ga.new_dataset_builder()
                .with_data(&v)
                .create(n)
                .at(path, "writing an attractor")?;
        }
        set_str(path, &ga, "validity", a.validity.word())?;
        if let Some(r) = a.validity.reasons() {
            set_str(path, &ga, "invalid_reasons", &r.join("; "))?;
        }
    }
    Ok(())
}

/// An attractor group's `validity` and `invalid_reasons` (unchecked where absent: files written
/// before validity was recorded).
fn read_orbit_check(path: &Path, ga: &Group) -> Result<OrbitCheck> {
    if !has_attr(ga, "validity") {
        return Ok(OrbitCheck::Unchecked);
    }
    Ok(match get_str(path, KIND, ga, "validity")?.as_str() {
        "valid" => OrbitCheck::Valid,
        "invalid" => OrbitCheck::Invalid(
            get_str(path, KIND, ga, "invalid_reasons")?
                .split("; ")
                .map(str::to_string)
                .collect(),
        ),
        "not checked" => OrbitCheck::Unchecked,
        other => {
            return Err(format_err(
                path,
                format!("attractor validity {other:?} is not valid, invalid or not checked"),
            ))
        }
    })
}

pub(super) fn read_metrics(
    path: &Path,
    f: &File,
    legend: &[(u8, String)],
) -> Result<Option<BasinMetrics>> {
    if !f.link_exists("metrics") {
        return Ok(None);
    }
    let g = f.group("metrics").at(path, "opening /metrics")?;
    let text = get_str(path, KIND, &g, "fractions")?;
    let obj: serde_json::Map<String, serde_json::Value> = serde_json::from_str(&text)
        .map_err(|e| format_err(path, format!("/metrics fractions: {e}")))?;
    // Names from the JSON object, exact values from the f64 attributes, in legend order.
    let rank = |n: &str| {
        legend
            .iter()
            .position(|(_, l)| l == n)
            .unwrap_or(usize::MAX)
    };
    let mut names: Vec<String> = obj.keys().cloned().collect();
    names.sort_by_key(|n| rank(n));
    let fractions = names
        .into_iter()
        .map(|n| {
            let v = get_attr::<f64>(path, KIND, &g, &format!("fraction_{n}"))?;
            Ok((n, v))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Some(BasinMetrics {
        fractions,
        basin_entropy: get_attr(path, KIND, &g, "basin_entropy")?,
        boundary_entropy: get_attr(path, KIND, &g, "boundary_entropy")?,
        entropy_box: get_attr::<u64>(path, KIND, &g, "entropy_box")? as usize,
    }))
}

pub(crate) fn read_attractors(path: &Path, f: &File) -> Result<Vec<Attractor>> {
    if !f.link_exists("attractors") {
        return Ok(Vec::new());
    }
    let g = f.group("attractors").at(path, "opening /attractors")?;
    let mut out = Vec::new();
    for ga in g.groups().at(path, "listing /attractors")? {
        let name = ga.name().rsplit('/').next().unwrap_or_default().to_string();
        let sec = ga
            .dataset("section")
            .and_then(|d| d.read_2d::<f64>())
            .at(path, "reading an attractor")?;
        let rd = |n: &str| {
            ga.dataset(n)
                .and_then(|d| d.read_raw::<f64>())
                .at(path, "reading an attractor")
        };
        let (re, im) = (rd("multipliers_re")?, rd("multipliers_im")?);
        out.push(Attractor {
            name,
            period_strides: get_attr(path, KIND, &ga, "period_strides")?,
            period_time: get_attr(path, KIND, &ga, "period_time")?,
            section: sec.rows().into_iter().map(|r| r.to_vec()).collect(),
            multipliers: re.into_iter().zip(im).collect(),
            validity: read_orbit_check(path, &ga)?,
        });
    }
    Ok(out)
}
