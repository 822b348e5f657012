//! Small helpers over hdf5-metno: path context on errors, scalar attributes and datasets,
//! creating a new file without clobbering an existing one, and the one atomic writer
//! ([`write_atomically`]) every whole-file output goes through.

use std::path::{Path, PathBuf};

use hdf5::types::{H5Type, VarLenUnicode};
use hdf5::{Dataset, Group, Location};
use ndarray::{Array2, ArrayView};

use crate::{Result, StoreError};

/// Attaches the file path and what was being done to an HDF5 error.
pub(crate) trait At<T> {
    fn at(self, path: &Path, action: &str) -> Result<T>;
}

impl<T> At<T> for hdf5::Result<T> {
    fn at(self, path: &Path, action: &str) -> Result<T> {
        self.map_err(|source| {
            if is_no_space(&source) {
                StoreError::Io {
                    path: path.to_path_buf(),
                    action: "write",
                    source: std::io::Error::from_raw_os_error(28),
                }
            } else {
                StoreError::Hdf5 {
                    path: path.to_path_buf(),
                    action: action.to_string(),
                    source,
                }
            }
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
    // HDF5 does not check the bytes of a UTF-8 string attribute: a damaged file can hold
    // invalid UTF-8, which must be an error here, not a `String` that breaks later formatting.
    let s = get_attr::<VarLenUnicode>(path, expected, loc, name)?;
    std::str::from_utf8(s.as_bytes())
        .map(str::to_string)
        .map_err(|e| crate::StoreError::Format {
            path: path.to_path_buf(),
            expected,
            detail: format!("attribute {name} is not valid UTF-8 ({e})"),
        })
}

/// Whether `loc` has an attribute `name`.
pub(crate) fn has_attr(loc: &Location, name: &str) -> bool {
    loc.attr_names()
        .map(|n| n.iter().any(|x| x == name))
        .unwrap_or(false)
}

/// An exclusive advisory lock (`flock`) on an output file, held for as long as the file is
/// being written. Two pdw-sweep processes given the same output path exclude each other: the
/// second is refused *before* anything is truncated or modified (HDF5's own lock is taken only
/// after its create call has truncated the file, so it cannot protect a running job from a
/// second `--force` run). HDF5's own locking is turned off for the files this lock guards.
#[derive(Debug)]
pub(crate) struct OutputLock {
    _file: std::fs::File,
}

fn lock(path: &Path, file: std::fs::File) -> Result<OutputLock> {
    match file.try_lock() {
        Ok(()) => Ok(OutputLock { _file: file }),
        Err(std::fs::TryLockError::WouldBlock) => Err(StoreError::Busy {
            path: path.to_path_buf(),
        }),
        Err(std::fs::TryLockError::Error(source)) => Err(StoreError::Io {
            path: path.to_path_buf(),
            action: "lock the file",
            source,
        }),
    }
}

/// Refuses a path that exists and is not a regular file (a directory, FIFO, device or socket):
/// writing there would hang (FIFO) or replace something that is not ours (device node).
pub(crate) fn check_regular(path: &Path) -> Result<()> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_dir() => Err(StoreError::Io {
            path: path.to_path_buf(),
            action: "create a file",
            source: std::io::Error::new(std::io::ErrorKind::IsADirectory, "it is a directory"),
        }),
        Ok(m) if !m.is_file() => Err(StoreError::Io {
            path: path.to_path_buf(),
            action: "create a file",
            source: std::io::Error::other(
                "it exists and is not a regular file (a FIFO, device or socket); only regular \
                 files are written or replaced",
            ),
        }),
        _ => Ok(()),
    }
}

/// The largest text input read whole (a distribution file of `mfpt --dist file:`): 64 MiB,
/// millions of values; a larger file is refused before it is read.
pub const MAX_TEXT_INPUT: u64 = 64 << 20;

/// What kind of thing a path that is not a regular file is, in words.
fn special_kind(m: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = m.file_type();
    if t.is_dir() {
        "a directory"
    } else if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

/// Checks an input path before anything opens it for reading, and returns its size in bytes.
///
/// An input must be a regular file (links followed): opening a FIFO blocks until someone
/// writes to it, and a device such as `/dev/zero` never ends, so either would hang or exhaust
/// memory in the reader. With `max_bytes`, a larger file is refused too (the limit of a text
/// input read whole). Only the path's metadata is read, so the check itself never blocks.
/// Every reader of a file named by a user goes through it: this crate's HDF5 readers (basin,
/// sweep, trajectory, MFPT and design files, `merge`'s shards), the text inputs
/// ([`read_text_input`]) and the explorer's file list.
pub fn check_input(path: &Path, max_bytes: Option<u64>) -> Result<u64> {
    let refuse = |msg: String| StoreError::Io {
        path: path.to_path_buf(),
        action: "read the file",
        source: std::io::Error::other(msg),
    };
    let m = std::fs::metadata(path).map_err(|source| StoreError::Io {
        path: path.to_path_buf(),
        action: "read the file",
        source,
    })?;
    if !m.is_file() {
        return Err(refuse(format!(
            "it is {}; an input must be a regular file",
            special_kind(&m)
        )));
    }
    match max_bytes {
        Some(cap) if m.len() > cap => Err(refuse(format!(
            "it holds {} ({} bytes), more than the {} a text input may hold",
            human_bytes(m.len()),
            m.len(),
            human_bytes(cap)
        ))),
        _ => Ok(m.len()),
    }
}

/// A text input read whole, after [`check_input`] with the cap `max_bytes`: at most that many
/// bytes are read even if the file grows meanwhile (then it is refused), and it must be UTF-8.
pub fn read_text_input(path: &Path, max_bytes: u64) -> Result<String> {
    use std::io::Read;
    check_input(path, Some(max_bytes))?;
    let io = |source| StoreError::Io {
        path: path.to_path_buf(),
        action: "read the file",
        source,
    };
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(max_bytes + 1).read_to_end(&mut bytes))
        .map_err(io)?;
    if bytes.len() as u64 > max_bytes {
        return Err(io(std::io::Error::other(format!(
            "it grew beyond the {} a text input may hold while being read",
            human_bytes(max_bytes)
        ))));
    }
    String::from_utf8(bytes).map_err(|_| io(std::io::Error::other("it is not UTF-8 text")))
}

/// Free bytes for an unprivileged writer on the file system holding `path` (its directory if
/// the file does not exist yet); `None` if it cannot be queried.
pub(crate) fn free_bytes(path: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let dir = if path.exists() {
        path.to_path_buf()
    } else {
        match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        }
    };
    let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
    let mut st: libc::statvfs = unsafe { std::mem::zeroed() };
    // SAFETY: `c` is a valid NUL-terminated path and `st` a properly sized out-parameter.
    let rc = unsafe { libc::statvfs(c.as_ptr(), &mut st) };
    (rc == 0).then(|| (st.f_bavail as u64).saturating_mul(st.f_frsize as u64))
}

/// This process's file-size limit (`RLIMIT_FSIZE`, `ulimit -f`) and the current size of `path`
/// (0 if it does not exist), or `None` without a limit. A write past the limit fails with EFBIG
/// (SIGXFSZ is ignored by the CLI), which HDF5 survives no better than a full disk; checked
/// with the free space before each write ([`ensure_space`]).
fn size_limit(path: &Path) -> Option<(u64, u64)> {
    let mut r = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit with a valid resource and a properly sized out-parameter.
    let rc = unsafe { libc::getrlimit(libc::RLIMIT_FSIZE, &mut r) };
    if rc != 0 || r.rlim_cur == libc::RLIM_INFINITY {
        return None;
    }
    let len = std::fs::metadata(path).map_or(0, |m| m.len());
    Some((r.rlim_cur, len))
}

/// Head room kept free beyond the data of each write: HDF5 metadata (object headers, chunk
/// index, attributes) written by the flush that follows.
pub(crate) const SPACE_MARGIN: u64 = 256 << 10;

/// Fails with the operating system's "No space left on device" before a write of about
/// `bytes` (+ [`SPACE_MARGIN`]) that the file system cannot hold.
///
/// HDF5 (1.14) does not survive a full disk: after a failed write its next flush or close
/// dereferences a dataset it has already freed (SIGSEGV). Checking before each write turns that
/// into an error with the file left as of its last flush (resumable). A file system filled by
/// someone else between this check and the write can still reach HDF5's failure path; the
/// writer then leaves the HDF5 handles unclosed (see [`crate::basin::BasinWriter`]).
pub(crate) fn ensure_space(path: &Path, bytes: u64) -> Result<()> {
    if let Some((limit, len)) = size_limit(path) {
        let need = bytes.saturating_add(SPACE_MARGIN);
        if limit.saturating_sub(len) < need {
            return Err(StoreError::Io {
                path: path.to_path_buf(),
                action: "write",
                source: std::io::Error::other(format!(
                    "File too large: the file-size limit (ulimit -f) is {}, the file holds {}, \
                     about {} more needed",
                    human_bytes(limit),
                    human_bytes(len),
                    human_bytes(need)
                )),
            });
        }
    }
    match free_bytes(path) {
        Some(free) if free < bytes.saturating_add(SPACE_MARGIN) => Err(StoreError::Io {
            path: path.to_path_buf(),
            action: "write",
            source: std::io::Error::other(format!(
                "No space left on device ({} free, about {} needed)",
                human_bytes(free),
                human_bytes(bytes.saturating_add(SPACE_MARGIN))
            )),
        }),
        _ => Ok(()),
    }
}

/// `1.5 MiB` style.
pub(crate) fn human_bytes(b: u64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{b} B")
    } else {
        format!("{v:.1} {}", units[u])
    }
}

/// Whether an HDF5 error is the operating system's "No space left on device".
pub(crate) fn is_no_space(e: &hdf5::Error) -> bool {
    let t = e.to_string();
    t.contains("errno = 28") || t.contains("No space left on device")
}

/// Keeps HDF5 from flushing and closing files at process exit. After a failed write HDF5's own
/// close path can crash (see [`ensure_space`]); the writers close their files explicitly and
/// leave them unclosed after a failure, and this keeps the library's exit handler from closing
/// them either. Must run before the library is first used; later calls are no-ops.
pub(crate) fn no_close_at_exit() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // SAFETY: H5dont_atexit takes no arguments and only sets a flag read by H5open.
        unsafe {
            let _ = hdf5_sys::h5::H5dont_atexit();
        }
    });
}

/// Creates `path` for writing and locks it ([`OutputLock`]). Without `force`, an existing file
/// is an error and is left untouched (the check and the creation are one atomic `create_new`);
/// with `force` an existing regular file is replaced, but only once the lock is held (a file
/// another process is writing is refused, not truncated). Non-regular files are refused;
/// unwritable locations give the operating system's message; a file system without room for
/// `reserve` bytes (+ a margin) gives "No space left on device" before anything is created.
pub(crate) fn create_file(
    path: &Path,
    force: bool,
    resume_hint: bool,
    reserve: u64,
) -> Result<(hdf5::File, OutputLock)> {
    no_close_at_exit();
    check_regular(path)?;
    let io = |source| StoreError::Io {
        path: path.to_path_buf(),
        action: "create a file",
        source,
    };
    let (std_file, created_here) = if force {
        let existed = path.exists();
        let f = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(path)
            .map_err(io)?;
        (f, !existed)
    } else {
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)
        {
            Ok(f) => (f, true),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                return Err(StoreError::Exists {
                    path: path.to_path_buf(),
                    resumable: resume_hint,
                })
            }
            Err(source) => return Err(io(source)),
        }
    };
    let cleanup = |e: StoreError| {
        if created_here {
            let _ = std::fs::remove_file(path);
        }
        e
    };
    let guard = lock(path, std_file).map_err(cleanup)?;
    ensure_space(path, reserve).map_err(cleanup)?;
    // No free-space reuse: every allocation goes to the end of the file, so nothing the last
    // flushed state references is overwritten before the next flush (a kill between flushes
    // leaves that state intact). Needs HDF5 >= 1.10 to read.
    let file = hdf5::File::with_options()
        .with_fapl(|p| p.chunk_cache(1021, 32 << 20, 1.0).file_locking(false))
        .with_fcpl(|p| p.file_space_strategy(hdf5::file::FileSpaceStrategy::None))
        .create(path)
        .at(path, "creating the file")
        .map_err(cleanup)?;
    Ok((file, guard))
}

/// Opens an existing file read-only or read-write with a 32 MiB chunk cache. HDF5's own file
/// locking is off: our writers guard their files with [`OutputLock`] and turn HDF5's lock off,
/// so a reader's HDF5 lock would protect nothing — and, HDF5 opening files without
/// close-on-exec, a child process started meanwhile would inherit the lock and make a later
/// writer of the same file report it busy.
pub(crate) fn open_file(path: &Path, rw: bool) -> Result<hdf5::File> {
    no_close_at_exit();
    if !path.exists() {
        return Err(StoreError::Io {
            path: path.to_path_buf(),
            action: "open the file",
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        });
    }
    check_input(path, None)?;
    check_global_heaps(path)?;
    let mut b = hdf5::File::with_options();
    b.with_fapl(|p| p.chunk_cache(1021, 32 << 20, 1.0).file_locking(false));
    if rw { b.open_rw(path) } else { b.open(path) }.at(path, "opening the file")
}

/// Opens an existing file as HDF5's `File::open` / `File::open_rw` would, but with HDF5's own
/// file locking off (see [`open_file`] for why); `action` names the step in an error. For the
/// small annotation and provenance reads and writes, which need no chunk cache.
pub(crate) fn open_unlocked(path: &Path, rw: bool, action: &'static str) -> Result<hdf5::File> {
    no_close_at_exit();
    check_input(path, None)?;
    let mut b = hdf5::File::with_options();
    b.with_fapl(|p| p.file_locking(false));
    if rw { b.open_rw(path) } else { b.open(path) }.at(path, action)
}

/// Locks an existing file for writing ([`OutputLock`]); a file another process is writing is
/// refused.
pub(crate) fn lock_existing(path: &Path) -> Result<OutputLock> {
    no_close_at_exit();
    check_regular(path)?;
    let f = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)
        .map_err(|source| StoreError::Io {
            path: path.to_path_buf(),
            action: "open the file for writing",
            source,
        })?;
    lock(path, f)
}

/// Opens a file guarded by an [`OutputLock`] of this process (HDF5's own locking off, since
/// the advisory lock already excludes other writers and would conflict with it).
pub(crate) fn open_locked(path: &Path, rw: bool) -> Result<hdf5::File> {
    no_close_at_exit();
    check_input(path, None)?;
    check_global_heaps(path)?;
    let mut b = hdf5::File::with_options();
    b.with_fapl(|p| p.chunk_cache(1021, 32 << 20, 1.0).file_locking(false));
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

/// Removes the temporary siblings ([`temp_sibling`], `.NAME.partial-PID…`) of `path` that a
/// process no longer running left behind (killed by SIGKILL, or by a signal it could not
/// catch, between creating its temporary file and renaming it into place). Called by whoever
/// holds `path`'s claim: no other live writer of `path` exists then, and a temporary file of a
/// running process (its PID alive) is left alone all the same. Returns the paths removed.
pub fn remove_stale_partials(path: &Path) -> Vec<PathBuf> {
    let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return Vec::new();
    };
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let prefix = format!(".{name}.partial-");
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return Vec::new();
    };
    let mut removed = Vec::new();
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        let Some(rest) = file.strip_prefix(&prefix) else {
            continue;
        };
        let pid: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
        let Ok(pid) = pid.parse::<u32>() else {
            continue;
        };
        let alive = pid == std::process::id() || Path::new(&format!("/proc/{pid}")).exists();
        let regular = e.file_type().is_ok_and(|t| t.is_file());
        if !alive && regular && std::fs::remove_file(e.path()).is_ok() {
            removed.push(e.path());
        }
    }
    removed
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
    check_regular(path)?;
    if path.exists() && !force {
        return Err(StoreError::Exists {
            path: path.to_path_buf(),
            resumable: false,
        });
    }
    Ok(())
}

/// A temporary sibling of an output path that becomes the output only when
/// [`commit`](Self::commit)ted: the one write-then-rename path of every file this crate writes
/// whole (HDF5, CSV, pictures). A reader never sees a half-written file, and a failed write
/// (full disk, an error while filling) leaves an existing file untouched. Dropped without
/// `commit`, it removes the temporary file.
pub(crate) struct Staged {
    tmp: PathBuf,
    done: bool,
}

impl Staged {
    /// A temporary sibling of `path` ([`temp_sibling`]); nothing is checked or created.
    pub(crate) fn beside(path: &Path) -> Self {
        Staged {
            tmp: temp_sibling(path),
            done: false,
        }
    }

    /// A picture's temporary file: [`check_target`] with `force` (an existing picture is
    /// replaced; whether it may be is the caller's decision), and `path`'s extension appended
    /// to the temporary name, by which the bitmap backend chooses the encoder. The picture is
    /// drawn into [`path`](Self::path), then [`commit`](Self::commit)ted.
    pub(crate) fn picture(path: &Path) -> Result<Self> {
        check_target(path, true)?;
        let mut s = Self::beside(path);
        if let Some(ext) = path.extension() {
            let mut name = s.tmp.file_name().unwrap_or_default().to_os_string();
            name.push(".");
            name.push(ext);
            s.tmp = s.tmp.with_file_name(name);
        }
        Ok(s)
    }

    /// The temporary path to write.
    pub(crate) fn path(&self) -> &Path {
        &self.tmp
    }

    /// Renames the finished temporary file onto `path` ([`rename_into_place`]).
    pub(crate) fn commit(mut self, path: &Path) -> Result<()> {
        self.done = true;
        rename_into_place(&self.tmp, path)
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.done {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Writes a whole file atomically: refuses an existing `path` unless `force`
/// ([`check_target`]), lets `write` fill a temporary sibling, then renames it into place. On an
/// error from `write` the temporary file is removed and `path` is left as it was.
pub(crate) fn write_atomically<T>(
    path: &Path,
    force: bool,
    write: impl FnOnce(&Path) -> Result<T>,
) -> Result<T> {
    check_target(path, force)?;
    let staged = Staged::beside(path);
    let v = write(staged.path())?;
    staged.commit(path)?;
    Ok(v)
}

/// [`write_atomically`] for an HDF5 file: `fill` writes into the new temporary file (created
/// and locked by [`create_file`]), which is then flushed and closed before the rename. After a
/// failed write the file handle is leaked, not closed (HDF5's close after a failed write can
/// crash; see [`ensure_space`]); the temporary file is removed.
pub(crate) fn write_h5_atomically(
    path: &Path,
    force: bool,
    fill: impl FnOnce(&Path, &hdf5::File) -> Result<()>,
) -> Result<()> {
    write_atomically(path, force, |tmp| {
        let (f, _lock) = create_file(tmp, true, false, 0)?;
        match fill(tmp, &f).and_then(|()| f.flush().at(tmp, "flushing")) {
            Ok(()) => f.close().at(tmp, "closing"),
            Err(e) => {
                std::mem::forget(f);
                Err(e)
            }
        }
    })
}

/// [`write_atomically`] for a text file written through a buffered writer (CSV): any I/O
/// error, creating the temporary file included, is reported as [`StoreError::Io`] "write" on
/// `path`.
pub(crate) fn write_text_atomically(
    path: &Path,
    force: bool,
    write: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> Result<()> {
    use std::io::Write;
    write_atomically(path, force, |tmp| {
        let res = std::fs::File::create(tmp).and_then(|f| {
            let mut w = std::io::BufWriter::new(f);
            write(&mut w)?;
            w.flush()
        });
        res.map_err(|source| StoreError::Io {
            path: path.to_path_buf(),
            action: "write",
            source,
        })
    })
}

/// Creates the dataset `name` in `g` holding `data` (a slice, an array or an array view of
/// any rank), contiguous and unfiltered. An HDF5 failure names the dataset's full path
/// ("writing /curve/p_step").
pub(crate) fn put<'d, T, D>(
    path: &Path,
    g: &Group,
    name: &str,
    data: impl Into<ArrayView<'d, T, D>>,
) -> Result<Dataset>
where
    T: H5Type + 'd,
    D: ndarray::Dimension,
{
    let parent = g.name();
    let full = if parent == "/" {
        format!("/{name}")
    } else {
        format!("{parent}/{name}")
    };
    g.new_dataset_builder()
        .with_data(data.into())
        .create(name)
        .at(path, &format!("writing {full}"))
}

/// A list of equally long rows as an (n × `ncols`) array; the caller has checked the lengths.
pub(crate) fn matrix(rows: &[Vec<f64>], ncols: usize) -> Array2<f64> {
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    Array2::from_shape_vec((rows.len(), ncols), flat).expect("shape validated")
}

/// Refuses a file with a global heap collection the HDF5 library would loop on forever.
///
/// Variable-length strings (every string attribute here) live in global heap collections
/// (HDF5 File Format Specification v3, §III.E "Global Heap": signature `GCOL`, version 1, three
/// reserved bytes, the collection size; then objects of index (2 bytes), reference count (2),
/// reserved (4), size (8), data padded to 8 bytes; index 0 is the free space, whose size
/// includes its header). The library's reader steps from one object to the next by its stored
/// size; a damaged free-space object of size 0 never moves it (`H5HG__cache_heap_deserialize`,
/// HDF5 2.2.0), so one flipped byte there would hang any read of the file. This walks every
/// collection the same way first and refuses such a file as damaged. Collections are found by
/// their signature with the version, reserved bytes and a size that fits the file checked, so
/// the same four bytes inside a dataset are not taken for one.
pub(crate) fn check_global_heaps(path: &Path) -> Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    let Ok(mut f) = std::fs::File::open(path) else {
        return Ok(()); // unreadable: HDF5's own open names the error
    };
    let len = f.metadata().map_or(0, |m| m.len());
    // Chunks overlap by 3 bytes so that a signature across a boundary is seen.
    const CHUNK: usize = 8 << 20;
    let mut buf = vec![0u8; CHUNK + 3];
    let (mut base, mut carry) = (0u64, 0usize);
    loop {
        let n = f.read(&mut buf[carry..]).unwrap_or(0);
        if n == 0 {
            return Ok(());
        }
        let filled = carry + n;
        let hits: Vec<u64> = buf[..filled]
            .windows(4)
            .enumerate()
            .filter(|(_, w)| *w == b"GCOL")
            .map(|(i, _)| base + i as u64)
            .collect();
        let resume_at = base + filled as u64;
        for start in hits {
            let mut c = vec![0u8; (len - start).min(1 << 24) as usize];
            let read = f
                .seek(SeekFrom::Start(start))
                .and_then(|_| f.read_exact(&mut c));
            if read.is_ok() {
                if let Some(offset) = stuck_heap_object(&c) {
                    return Err(crate::StoreError::Format {
                        path: path.to_path_buf(),
                        expected: "HDF5",
                        detail: format!(
                            "damaged global heap at byte {}: an object of size 0 (the HDF5 \
                             library would never finish reading it)",
                            start + offset as u64
                        ),
                    });
                }
            }
        }
        if f.seek(SeekFrom::Start(resume_at)).is_err() {
            return Ok(());
        }
        carry = filled.min(3);
        buf.copy_within(filled - carry..filled, 0);
        base = resume_at - carry as u64;
    }
}

/// The offset, from the collection's start, of a free-space object of size 0 in the global heap
/// collection at the start of `c` ([`check_global_heaps`]); `None` for a sound collection or
/// bytes that are not one.
fn stuck_heap_object(c: &[u8]) -> Option<usize> {
    const HEADER: usize = 16;
    let u64_at =
        |i: usize| -> Option<u64> { Some(u64::from_le_bytes(c.get(i..i + 8)?.try_into().ok()?)) };
    if c.get(4..8)? != [1, 0, 0, 0] {
        return None;
    }
    let size = usize::try_from(u64_at(8)?).ok()?;
    if !(4096..=c.len()).contains(&size) {
        return None;
    }
    let mut p = HEADER;
    while p + HEADER <= size {
        let idx = u16::from_le_bytes([c[p], c[p + 1]]);
        let len = usize::try_from(u64_at(p + 8)?).ok()?;
        let need = if idx > 0 {
            HEADER.checked_add(len.checked_add(7)? & !7)?
        } else {
            len
        };
        if need == 0 {
            return Some(p);
        }
        p = p.checked_add(need)?;
    }
    None
}
