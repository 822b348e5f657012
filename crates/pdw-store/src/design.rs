//! Design-search files (`pdw-sweep design`): every evaluated design of a search, in evaluation
//! order, rewritten whole (write-then-rename) after each new design, so that a killed run
//! leaves the last complete file and a rerun continues from it.
//!
//! Layout: root attributes `format` (= [`DESIGN_FORMAT`]), `version`, `created`, `settings`
//! (JSON: model, fixed parameters, free parameters and bounds, objective, constraints, seed —
//! a rerun must match it to continue), `free_names` (JSON array); datasets `params [N, k]`,
//! `status [N]` (u8 codes, legend in the attribute `status_names`), `section [N, 3]`,
//! `reasons`, `bindings` (the binding validity criterion) and `fates` (how a gait search that
//! found nothing ended its guesses) (each a UTF-8 JSON array of strings, as bytes) and one `[N]` f64 dataset per named
//! measure (`cost`, `rho`, `basin_fraction`, …; NaN where not measured). Written by
//! [`write_design_annotated`], every dataset also carries a `units` attribute and the file a
//! `/provenance` group whose `commands` list every run that wrote the search, a continued run's
//! after the earlier ones.

use std::path::Path;

use hdf5::File;
use ndarray::Array2;

use crate::h5util::{get_str, has_attr, open_file, put, set_str, write_h5_atomically, At};
use crate::provenance::{annotate_file, Annotations};
use crate::{time, Result, StoreError};

/// Value of the root attribute `format` of a design file.
pub const DESIGN_FORMAT: &str = "pdw-sweep design v1";
const KIND: &str = "pdw-sweep design";

/// The contents of a design file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DesignData {
    /// JSON of the search's settings.
    pub settings: String,
    pub free_names: Vec<String>,
    /// Names of the status codes, by code.
    pub status_names: Vec<String>,
    /// Free parameter values per design (`N × k`).
    pub params: Vec<Vec<f64>>,
    pub status: Vec<u8>,
    pub reasons: Vec<String>,
    /// Per design: the binding validity criterion's name (empty where not measured). A file
    /// written before it was stored reads empty names.
    pub bindings: Vec<String>,
    /// Per design: how the gait search's guesses ended where it found no gait (`4 starts: 3
    /// stance knee buckled, 1 fell forward`; empty with a gait). Empty in older files.
    pub fates: Vec<String>,
    /// Gait section state per design (NaN without a gait).
    pub section: Vec<[f64; 3]>,
    /// Named per-design measures, each of length `N`.
    pub columns: Vec<(String, Vec<f64>)>,
}

impl DesignData {
    fn validate(&self) -> Result<()> {
        let n = self.params.len();
        let k = self.free_names.len();
        let bad = self.params.iter().any(|p| p.len() != k)
            || self.status.len() != n
            || self.reasons.len() != n
            || self.bindings.len() != n
            || self.fates.len() != n
            || self.section.len() != n
            || self.columns.iter().any(|c| c.1.len() != n);
        if bad {
            return Err(StoreError::invalid(
                "design data",
                format!("{n} designs of {k} parameters: every column needs {n} entries"),
            ));
        }
        Ok(())
    }

    /// A named measure's column.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.columns
            .iter()
            .find(|c| c.0 == name)
            .map(|c| c.1.as_slice())
    }
}

/// Writes `data` to `path`, replacing it atomically (temporary sibling, then rename).
pub fn write_design(path: impl AsRef<Path>, data: &DesignData) -> Result<()> {
    write_design_annotated(path, data, None, &[])
}

/// [`write_design`], then, in the same atomic write, the annotations `ann` (units on every
/// dataset, provenance). `earlier_commands` are the command lines of the runs that wrote the
/// search before this one (see [`read_design_commands`]); the provenance's `commands` lists
/// them, then this run's command.
pub fn write_design_annotated(
    path: impl AsRef<Path>,
    data: &DesignData,
    ann: Option<&Annotations<'_>>,
    earlier_commands: &[String],
) -> Result<()> {
    let path = path.as_ref();
    data.validate()?;
    // Always replaces an existing file: a search rewrites its own output as it goes.
    write_h5_atomically(path, true, |tmp, f| {
        fill(tmp, f, data)?;
        if let Some(a) = ann {
            if a.provenance.is_some() && !earlier_commands.is_empty() {
                let g = f
                    .create_group("provenance")
                    .at(tmp, "creating /provenance")?;
                let c = serde_json::to_string(earlier_commands).unwrap_or_default();
                set_str(tmp, &g, "commands", &c)?;
            }
            annotate_file(tmp, f, a)?;
        }
        Ok(())
    })
}

fn fill(p: &Path, f: &File, d: &DesignData) -> Result<()> {
    let names = serde_json::to_string(&d.free_names).unwrap_or_default();
    let status_names = serde_json::to_string(&d.status_names).unwrap_or_default();
    for (k, v) in [
        ("format", DESIGN_FORMAT),
        ("version", env!("CARGO_PKG_VERSION")),
        ("created", &time::now_rfc3339()),
        ("settings", &d.settings),
        ("free_names", &names),
        ("status_names", &status_names),
    ] {
        set_str(p, f, k, v)?;
    }
    let n = d.params.len();
    let k = d.free_names.len();
    let flat: Vec<f64> = d.params.iter().flatten().copied().collect();
    let params = Array2::from_shape_vec((n, k), flat).expect("validated");
    let sec: Vec<f64> = d.section.iter().flatten().copied().collect();
    let section = Array2::from_shape_vec((n, 3), sec).expect("validated");
    put(p, f, "params", &params)?;
    put(p, f, "section", &section)?;
    put(p, f, "status", &d.status)?;
    for (name, texts) in [
        ("reasons", &d.reasons),
        ("bindings", &d.bindings),
        ("fates", &d.fates),
    ] {
        let t = serde_json::to_string(texts).unwrap_or_default();
        put(p, f, name, t.as_bytes())?;
    }
    for (name, v) in &d.columns {
        put(p, f, name, v)?;
    }
    Ok(())
}

/// The command lines stored in a design file's `/provenance` (empty for a file without one).
pub fn read_design_commands(path: impl AsRef<Path>) -> Result<Vec<String>> {
    let p = path.as_ref();
    let f = open_file(p, false)?;
    let Ok(g) = f.group("provenance") else {
        return Ok(Vec::new());
    };
    if !has_attr(&g, "commands") {
        return Ok(Vec::new());
    }
    let c = get_str(p, KIND, &g, "commands")?;
    serde_json::from_str(&c).map_err(|e| StoreError::Format {
        path: p.to_path_buf(),
        expected: KIND,
        detail: format!("/provenance commands: {e}"),
    })
}

/// Reads a design file; `columns` are the measures to read (missing ones are an error).
pub fn read_design(path: impl AsRef<Path>, columns: &[&str]) -> Result<DesignData> {
    let p = path.as_ref();
    let f = open_file(p, false)?;
    let fmt = get_str(p, KIND, &f, "format")?;
    let bad = |detail: String| StoreError::Format {
        path: p.to_path_buf(),
        expected: KIND,
        detail,
    };
    if fmt != DESIGN_FORMAT {
        return Err(bad(format!(
            "format is {fmt:?}, expected {DESIGN_FORMAT:?}"
        )));
    }
    let settings = get_str(p, KIND, &f, "settings")?;
    let free_names: Vec<String> = serde_json::from_str(&get_str(p, KIND, &f, "free_names")?)
        .map_err(|e| bad(format!("free_names: {e}")))?;
    let status_names: Vec<String> = serde_json::from_str(&get_str(p, KIND, &f, "status_names")?)
        .map_err(|e| bad(format!("status_names: {e}")))?;
    let params = f
        .dataset("params")
        .and_then(|d| d.read_2d::<f64>())
        .at(p, "params")?;
    let section = f
        .dataset("section")
        .and_then(|d| d.read_2d::<f64>())
        .at(p, "section")?;
    let status = f
        .dataset("status")
        .and_then(|d| d.read_raw::<u8>())
        .at(p, "status")?;
    let reason_bytes = f
        .dataset("reasons")
        .and_then(|d| d.read_raw::<u8>())
        .at(p, "reasons")?;
    let reasons: Vec<String> =
        serde_json::from_slice(&reason_bytes).map_err(|e| bad(format!("reasons: {e}")))?;
    // per-design texts added later: absent in older files, read as empty
    let texts = |name: &str| -> Result<Vec<String>> {
        let Ok(ds) = f.dataset(name) else {
            return Ok(vec![String::new(); reasons.len()]);
        };
        let b = ds.read_raw::<u8>().at(p, name)?;
        serde_json::from_slice(&b).map_err(|e| bad(format!("{name}: {e}")))
    };
    let bindings = texts("bindings")?;
    let fates = texts("fates")?;
    let mut cols = Vec::new();
    for c in columns {
        let v = f.dataset(c).and_then(|d| d.read_raw::<f64>()).at(p, c)?;
        cols.push((c.to_string(), v));
    }
    let data = DesignData {
        settings,
        free_names,
        status_names,
        params: params.rows().into_iter().map(|r| r.to_vec()).collect(),
        status,
        reasons,
        bindings,
        fates,
        section: section
            .rows()
            .into_iter()
            .map(|r| [r[0], r[1], r[2]])
            .collect(),
        columns: cols,
    };
    data.validate().map_err(|e| bad(e.to_string()))?;
    Ok(data)
}
