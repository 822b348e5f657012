//! `animate`: the GIF of strides of the gait, or of a trajectory file, as `pdw-sweep animate`
//! draws it ([`pdw::animate`], [`pdw::animate_trajectory`]).

use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::err;
use crate::{build_kw, interruptible};
use pdw::animate::AnimOptions;

/// `animate(model="simplest", slope=None, out="gait.gif", force=False, strides=2, fps=None,
/// size=(640, 400), from_file=None, steps=None, **params)`: writes the GIF of `strides` strides
/// of the gait
/// (or, with `from_file`, of a trajectory file written by `pdw-sweep simulate`, its model
/// rebuilt from the file) to `out` (refusing an existing file unless `force`) and returns its
/// path. `fps` defaults to 16.7 (a 60 ms delay); one GIF second is one model time unit. Warns
/// (`UserWarning`) when the gait drawn is unstable or physically invalid.
#[pyfunction]
#[pyo3(
    signature = (model="simplest", slope=None, out=std::path::PathBuf::from("gait.gif"), force=false, strides=2, fps=None, size=(640, 400), from_file=None, steps=None, **params),
    text_signature = "(model='simplest', slope=None, out='gait.gif', force=False, strides=2, fps=None, size=(640, 400), from_file=None, steps=None, **params)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn animate<'py>(
    py: Python<'py>,
    model: &str,
    slope: Option<&Bound<'py, PyAny>>,
    out: std::path::PathBuf,
    force: bool,
    strides: i64,
    fps: Option<f64>,
    size: (u32, u32),
    from_file: Option<std::path::PathBuf>,
    steps: Option<i64>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<std::path::PathBuf> {
    if out.exists() && !force {
        return Err(err(format!(
            "out: '{}' exists; pass force=True to replace it",
            out.display()
        )));
    }
    let opts = AnimOptions {
        strides: pdw::animate::check_strides(
            crate::old_spelling(strides, 2, steps, "strides", "steps")?,
            "strides",
        )
        .map_err(err)?,
        fps: pdw::animate::check_fps(fps.unwrap_or(pdw::animate::DEFAULT_FPS), "fps")
            .map_err(err)?,
        size: pdw::animate::check_size(size, "size").map_err(err)?,
    };
    if let Some(f) = from_file {
        if slope.is_some() || params.is_some_and(|p| !p.is_empty()) {
            return Err(err(
                "from_file: the model is rebuilt from the file; give no slope or parameters",
            ));
        }
        return from_trajectory(py, &f, &out, &opts);
    }
    let m = build_kw(model, slope, params)?;
    pdw::animate::check_drawing(&m).map_err(err)?;
    let (fp, warnings, frames) = interruptible(py, || -> PyResult<_> {
        let (gait, failed) = pdw::animate::gait(&m).map_err(err)?;
        let Some(fp) = gait else {
            return Err(crate::errors::no_gait_error(
                &m,
                "all",
                failed.len(),
                &failed,
            ));
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
        let frames = pdw::animate::frames(&m, &fp, &opts).map_err(err)?;
        Ok((fp, (warnings, !flags.is_empty()), frames))
    })?;
    let (warnings, flagged) = warnings;
    crate::warn_all(py, &warnings)?;
    pdw::animate::write_gif(&out, &m, &fp, &frames, flagged, &opts).map_err(err)?;
    Ok(out)
}

/// `from_file`: the trajectory's walk, as `pdw-sweep animate --from` draws it.
fn from_trajectory(
    py: Python<'_>,
    from: &std::path::Path,
    out: &std::path::Path,
    opts: &AnimOptions,
) -> PyResult<std::path::PathBuf> {
    interruptible(py, || {
        pdw::animate_trajectory::animate_file(from, out, opts, "from_file")
            .map(|d| d.frames)
            .map_err(err)
    })?;
    Ok(out.to_path_buf())
}
