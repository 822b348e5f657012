//! Small helpers over hdf5-metno: path context on errors, scalar attributes, creating a new file
//! without clobbering an existing one.

use std::path::{Path, PathBuf};

use hdf5::types::{H5Type, VarLenUnicode};
use hdf5::Location;

use crate::{Result, StoreError};

/// Attaches the file path and what was being done to an HDF5 error.
pub(crate) trait At<T> {
    fn at(self, path: &Path, action: &str) -> Result<T>;
}

impl<T> At<T> for hdf5::Result<T> {
    fn at(self, path: &Path, action: &str) -> Result<T> {
        self.map_err(|source| StoreError::Hdf5 {
            path: path.to_path_buf(),
            action: action.to_string(),
            source,
        })
    }
}

/// Sets (creating or overwriting) a scalar attribute.
pub(crate) fn set_attr<T: H5Type>(path: &Path, loc: &Location, name: &str, v: &T) -> Result<()> {
    let action = format!("writing attribute {name}");
    let attr = if loc
        .attr_names()
        .at(path, &action)?
        .iter()
        .any(|n| n == name)
    {
        loc.attr(name).at(path, &action)?
    } else {
        loc.new_attr::<T>()
            .shape(())
            .create(name)
            .at(path, &action)?
    };
    attr.write_scalar(v).at(path, &action)
}

/// Sets a UTF-8 string attribute (h5py reads it as `str`).
pub(crate) fn set_str(path: &Path, loc: &Location, name: &str, s: &str) -> Result<()> {
    let v: VarLenUnicode = s.parse().map_err(|_| {
        StoreError::invalid("string attribute", format!("{name} contains a NUL byte"))
    })?;
    set_attr(path, loc, name, &v)
}

/// Reads a scalar attribute; a missing or mistyped one is a format error.
pub(crate) fn get_attr<T: H5Type>(
    path: &Path,
    expected: &'static str,
    loc: &Location,
    name: &str,
) -> Result<T> {
    loc.attr(name)
        .and_then(|a| a.read_scalar::<T>())
        .map_err(|e| StoreError::Format {
            path: path.to_path_buf(),
            expected,
            detail: format!("attribute `{name}` of `{}`: {e}", loc.name()),
        })
}

/// Reads a string attribute.
pub(crate) fn get_str(
    path: &Path,
    expected: &'static str,
    loc: &Location,
    name: &str,
) -> Result<String> {
    get_attr::<VarLenUnicode>(path, expected, loc, name).map(|s| s.as_str().to_string())
}

/// Whether `loc` has an attribute `name`.
pub(crate) fn has_attr(loc: &Location, name: &str) -> bool {
    loc.attr_names()
        .map(|n| n.iter().any(|x| x == name))
        .unwrap_or(false)
}

/// Creates `path` for writing. Without `force`, an existing file is an error and is left
/// untouched (the check and the creation are one atomic `create_new`); with `force` an existing
/// regular file is replaced. Unwritable locations give the operating system's message.
pub(crate) fn create_file(path: &Path, force: bool) -> Result<hdf5::File> {
    if path.is_dir() {
        return Err(StoreError::Io {
            path: path.to_path_buf(),
            action: "create a file",
            source: std::io::Error::new(std::io::ErrorKind::IsADirectory, "it is a directory"),
        });
    }
    let created_here = if force {
        // Probe writability with the OS's message before HDF5 truncates anything.
        std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(|source| StoreError::Io {
                path: path.to_path_buf(),
                action: "create a file",
                source,
            })?;
        false
    } else {
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)
        {
            Ok(_) => true,
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                return Err(StoreError::Exists {
                    path: path.to_path_buf(),
                })
            }
            Err(source) => {
                return Err(StoreError::Io {
                    path: path.to_path_buf(),
                    action: "create a file",
                    source,
                })
            }
        }
    };
    // No free-space reuse: every allocation goes to the end of the file, so nothing the last
    // flushed state references is overwritten before the next flush (a kill between flushes
    // leaves that state intact). Needs HDF5 >= 1.10 to read.
    let file = hdf5::File::with_options()
        .with_fapl(|p| p.chunk_cache(1021, 32 << 20, 1.0))
        .with_fcpl(|p| p.file_space_strategy(hdf5::file::FileSpaceStrategy::None))
        .create(path)
        .at(path, "creating the file");
    if file.is_err() && created_here {
        let _ = std::fs::remove_file(path);
    }
    file
}

/// Opens an existing file read-only or read-write with a 32 MiB chunk cache.
pub(crate) fn open_file(path: &Path, rw: bool) -> Result<hdf5::File> {
    if !path.exists() {
        return Err(StoreError::Io {
            path: path.to_path_buf(),
            action: "open the file",
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        });
    }
    let mut b = hdf5::File::with_options();
    b.with_fapl(|p| p.chunk_cache(1021, 32 << 20, 1.0));
    if rw { b.open_rw(path) } else { b.open(path) }.at(path, "opening the file")
}

/// A sibling temporary path for write-then-rename (same directory, so the rename is atomic).
pub(crate) fn temp_sibling(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    path.with_file_name(format!(".{name}.partial-{}", std::process::id()))
}

/// Renames the finished temporary file onto `path`.
pub(crate) fn rename_into_place(tmp: &Path, path: &Path) -> Result<()> {
    std::fs::rename(tmp, path).map_err(|source| {
        let _ = std::fs::remove_file(tmp);
        StoreError::Io {
            path: path.to_path_buf(),
            action: "move the finished file into place",
            source,
        }
    })
}

/// Refuses an existing `path` unless `force`, and checks its directory is writable, before a
/// write-then-rename.
pub(crate) fn check_target(path: &Path, force: bool) -> Result<()> {
    if path.is_dir() {
        return Err(StoreError::Io {
            path: path.to_path_buf(),
            action: "create a file",
            source: std::io::Error::new(std::io::ErrorKind::IsADirectory, "it is a directory"),
        });
    }
    if path.exists() && !force {
        return Err(StoreError::Exists {
            path: path.to_path_buf(),
        });
    }
    Ok(())
}
