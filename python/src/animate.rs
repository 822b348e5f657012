//! `animate`: the GIF of two strides of the gait, as `pdw-sweep animate` draws it
//! ([`pdw::animate`]).

use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::{build_kw, err, interruptible};

/// `animate(model="simplest", slope=None, out="gait.gif", force=False, **params)`: writes the
/// GIF to `out` (refusing an existing file unless `force`) and returns its path. Warns
/// (`UserWarning`) when the gait drawn is unstable or physically invalid.
#[pyfunction]
#[pyo3(
    signature = (model="simplest", slope=None, out=std::path::PathBuf::from("gait.gif"), force=false, **params),
    text_signature = "(model='simplest', slope=None, out='gait.gif', force=False, **params)"
)]
pub(crate) fn animate<'py>(
    py: Python<'py>,
    model: &str,
    slope: Option<&Bound<'py, PyAny>>,
    out: std::path::PathBuf,
    force: bool,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<std::path::PathBuf> {
    if out.exists() && !force {
        return Err(err(format!(
            "out: '{}' exists; pass force=True to replace it",
            out.display()
        )));
    }
    let m = build_kw(model, slope, params)?;
    pdw::animate::check_drawing(&m).map_err(err)?;
    let (fp, warnings, frames) = interruptible(py, || -> PyResult<_> {
        let (gait, failed) = pdw::animate::gait(&m).map_err(err)?;
        let Some(fp) = gait else {
            return Err(crate::no_gait_error(&m, "all", failed.len(), &failed));
        };
        let mut warnings = Vec::new();
        if !fp.stable {
            warnings.push(pdw::animate::unstable_warning(&m, &fp));
        }
        let flags = pdw::animate::flags(&m, &fp);
        if !flags.is_empty() {
            warnings.push(format!(
                "the animated gait is FLAGGED as physically invalid: {}",
                flags.join("; ")
            ));
        }
        let frames = pdw::animate::frames(&m, &fp).map_err(err)?;
        Ok((fp, (warnings, !flags.is_empty()), frames))
    })?;
    let (warnings, flagged) = warnings;
    crate::warn_all(py, &warnings)?;
    pdw::animate::write_gif(&out, &m, &fp, &frames, flagged).map_err(err)?;
    Ok(out)
}
