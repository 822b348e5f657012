//! The files a command writes (HDF5, PNG, GIF, CSV), claimed before anything is computed.
//!
//! Every writer goes through [`claim`] — the CLI's subcommands and the explorer's save (a fresh
//! name in its `--save-dir`, the explored file its input) —, which, in this order:
//! 1. identifies each path by (device, inode) after following links, and a path that does not
//!    exist yet by its resolved directory and file name;
//! 2. refuses an output that is the same file as another output or as an input (the `--model`
//!    spec file, the shards of `merge`, the `--dist` file of `mfpt`), with or without
//!    `--force`, and an input that is not a regular file ([`pdw_store::check_input`]);
//! 3. refuses an existing output without `--force` (unless the command continues it, e.g.
//!    `basin --resume`), and anything that is not a regular file;
//! 4. refuses an extension that does not name the format written (`--out a.csv` on a sweep,
//!    whose `--out` is HDF5);
//! 5. checks that the directory is writable by creating and removing a probe file;
//! 6. takes the exclusive advisory lock (`flock`) that pdw-store's writers take on their files:
//!    an existing output is locked as it is, a new one through an empty placeholder created in
//!    its place. A second writer of the same path, whichever command it runs, is refused
//!    before it truncates anything, with the path and the holder of the lock;
//! 7. removes the temporary files (`.NAME.partial-PID…`) a killed writer of the same output
//!    left behind ([`pdw_store::remove_stale_partials`]).
//!
//! A command lists every file it writes, derived pictures included, in one place that both the
//! claim and the writer read (e.g. [`crate::mfpt::output_files`]), so a picture cannot be written
//! without having been claimed.
//!
//! **Placeholders and kills.** A new output is locked through an empty placeholder at its path.
//! A run killed by SIGKILL leaves that empty file behind. An output the command continues
//! (`may_exist`, e.g. `basin --resume`) treats an existing *empty* file as such a placeholder,
//! not as a file it would replace: a requeued job resumes after any kill, and its picture is
//! drawn as if the file were new. Every writer renames finished, non-empty files into place,
//! so an empty file at an output path is never a result.
//!
//! Messages name the user's path and the operating system's reason. The claim is held for the
//! whole command; dropped, it removes the placeholders nothing was written into.

use crate::input::InputError;
use std::ffi::OsString;
use std::fs::File;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

/// The format a writer produces, told by the output's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Hdf5,
    Png,
    Gif,
    Csv,
}

impl Format {
    fn extensions(self) -> &'static [&'static str] {
        match self {
            Format::Hdf5 => &["h5", "hdf5"],
            Format::Png => &["png"],
            Format::Gif => &["gif"],
            Format::Csv => &["csv"],
        }
    }

    fn name(self) -> &'static str {
        match self {
            Format::Hdf5 => "HDF5",
            Format::Png => "PNG",
            Format::Gif => "GIF",
            Format::Csv => "CSV",
        }
    }

    /// Whether `path`'s extension (any case) names this format.
    pub fn matches(self, path: &Path) -> bool {
        path.extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| self.extensions().contains(&e.to_ascii_lowercase().as_str()))
    }
}

/// A file the command will write.
pub struct Output<'a> {
    pub flag: &'static str,
    pub path: &'a Path,
    pub format: Format,
    /// An existing file is expected here (the command continues it: `--resume`, a design
    /// search), not refused without `--force`.
    pub may_exist: bool,
}

/// A file a plan will write, owned: a plan lists every output it writes, derived pictures
/// included, and the claim and the writer both read that one list ([`Planned::output`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Planned {
    pub flag: &'static str,
    pub path: PathBuf,
    pub format: Format,
}

impl Planned {
    /// The output to [`claim`] (never continued: `may_exist` false).
    pub fn output(&self) -> Output<'_> {
        Output {
            flag: self.flag,
            path: &self.path,
            format: self.format,
            may_exist: false,
        }
    }
}

/// A file the command reads.
pub struct Input<'a> {
    pub flag: &'static str,
    pub path: &'a Path,
}

/// The spec file named by `--model`, if it names one (not a built-in model).
pub fn model_input(model: &str) -> Option<Input<'_>> {
    let builtin = matches!(model, "rimless" | "simplest")
        || pdw_walkers::registry::preset_text(model).is_some();
    let path = Path::new(model);
    (!builtin && path.is_file()).then_some(Input {
        flag: "--model",
        path,
    })
}

/// What a path is: an existing file's (device, inode), or a new file's resolved directory and
/// name.
#[derive(Debug, PartialEq, Eq)]
enum Identity {
    File { dev: u64, ino: u64 },
    New { dir: PathBuf, name: OsString },
}

fn kind_text(e: &std::io::Error) -> String {
    e.kind().to_string()
}

/// The identity of output `o`, with the checks that need only its path: it names a file, its
/// directory exists, and it is a regular file if it exists.
fn output_identity(o: &Output<'_>) -> Result<(Identity, bool), InputError> {
    let shown = o.path.display();
    let Some(name) = o.path.file_name() else {
        return Err(InputError(format!(
            "{}: '{shown}' does not name a file",
            o.flag
        )));
    };
    match std::fs::metadata(o.path) {
        Ok(m) if m.is_dir() => Err(InputError(format!("{}: '{shown}' is a directory", o.flag))),
        Ok(m) if !m.is_file() => Err(InputError(format!(
            "{}: '{shown}' is not a regular file (a FIFO, device or socket); only regular files \
             are written or replaced",
            o.flag
        ))),
        Ok(m) => Ok((
            Identity::File {
                dev: m.dev(),
                ino: m.ino(),
            },
            true,
        )),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let dir = directory(o.path);
            match std::fs::canonicalize(&dir) {
                Ok(d) if d.is_dir() => Ok((
                    Identity::New {
                        dir: d,
                        name: name.to_os_string(),
                    },
                    false,
                )),
                Ok(_) => Err(InputError(format!(
                    "{}: '{}' in '{shown}' is not a directory",
                    o.flag,
                    dir.display()
                ))),
                Err(_) => Err(InputError(format!(
                    "{}: the directory '{}' of '{shown}' does not exist",
                    o.flag,
                    dir.display()
                ))),
            }
        }
        Err(e) => Err(InputError(format!(
            "{}: cannot examine '{shown}': {}",
            o.flag,
            kind_text(&e)
        ))),
    }
}

/// The directory a path's file is in (`.` for a bare name).
fn directory(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// One claimed output.
struct Held {
    path: PathBuf,
    /// The locked file (none once handed over to a writer that locks it itself).
    file: Option<File>,
    /// The inode of the empty placeholder this claim created, while it may still be there.
    placeholder: Option<u64>,
    existed: bool,
}

/// The outputs of a command, checked and locked; see the module docs.
pub struct Claim {
    held: Vec<Held>,
}

impl Claim {
    /// Whether `path` existed before the claim (a placeholder stands there now otherwise).
    pub fn existed(&self, path: &Path) -> bool {
        self.held.iter().any(|h| h.path == path && h.existed)
    }

    /// Hands `path` to a writer that takes the same lock itself (pdw-store's basin writer,
    /// which creates or continues its file in place): the placeholder is removed and the lock
    /// released, just before the writer locks it.
    pub fn hand_over(&mut self, path: &Path) {
        for h in self.held.iter_mut().filter(|h| h.path == path) {
            remove_placeholder(h);
            h.file = None;
        }
    }

    /// Locks `path` again after a write-then-rename replaced the file there (the lock held
    /// was on the replaced file): a writer that writes its output more than once keeps
    /// others out between its writes.
    pub fn renew(&mut self, path: &Path, flag: &'static str) -> Result<(), InputError> {
        for h in self.held.iter_mut().filter(|h| h.path == path) {
            h.placeholder = None;
            let file = open_for_lock(path, flag)?;
            lock(&file, path, flag)?;
            h.file = Some(file);
        }
        Ok(())
    }
}

fn remove_placeholder(h: &mut Held) {
    if let Some(ino) = h.placeholder.take() {
        if std::fs::metadata(&h.path).is_ok_and(|m| m.ino() == ino && m.len() == 0) {
            let _ = std::fs::remove_file(&h.path);
        }
    }
}

impl Drop for Claim {
    fn drop(&mut self) {
        for h in &mut self.held {
            remove_placeholder(h);
        }
    }
}

fn open_for_lock(path: &Path, flag: &'static str) -> Result<File, InputError> {
    std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)
        .map_err(|e| {
            InputError(format!(
                "{flag}: cannot open '{}' for writing: {}",
                path.display(),
                kind_text(&e)
            ))
        })
}

fn lock(file: &File, path: &Path, flag: &'static str) -> Result<(), InputError> {
    match file.try_lock() {
        Ok(()) => Ok(()),
        Err(std::fs::TryLockError::WouldBlock) => {
            let by = file
                .metadata()
                .ok()
                .and_then(|m| holder(&m))
                .map(|h| format!(" ({h})"))
                .unwrap_or_default();
            Err(InputError(format!(
                "{flag}: '{}' is being written by another process{by}, which holds its lock; \
                 wait for it to finish, or choose another output path",
                path.display()
            )))
        }
        Err(std::fs::TryLockError::Error(e)) => Err(InputError(format!(
            "{flag}: cannot lock '{}': {}",
            path.display(),
            kind_text(&e)
        ))),
    }
}

/// The process holding the `flock` of the file with metadata `m`, as `process PID (command
/// line)`, read from /proc/locks (`N: FLOCK ADVISORY WRITE PID MAJ:MIN:INODE 0 EOF`).
fn holder(m: &std::fs::Metadata) -> Option<String> {
    let dev = m.dev();
    let major = ((dev >> 8) & 0xfff) | ((dev >> 32) & !0xfff);
    let minor = (dev & 0xff) | ((dev >> 12) & !0xff);
    let exact = format!("{major:02x}:{minor:02x}:{}", m.ino());
    let suffix = format!(":{}", m.ino());
    let locks = std::fs::read_to_string("/proc/locks").ok()?;
    let flocks: Vec<Vec<&str>> = locks
        .lines()
        .map(|l| l.split_whitespace().collect::<Vec<_>>())
        .filter(|f| f.len() > 5 && f[1] == "FLOCK")
        .collect();
    // The device numbers of a file on an overlay differ from the ones the kernel lists; the
    // inode alone identifies the lock when it is the only one with that number.
    let by_ino: Vec<&Vec<&str>> = flocks.iter().filter(|f| f[5].ends_with(&suffix)).collect();
    let line = flocks
        .iter()
        .find(|f| f[5] == exact)
        .or_else(|| (by_ino.len() == 1).then(|| by_ino[0]))?;
    let pid = line[4];
    let cmd = std::fs::read(format!("/proc/{pid}/cmdline"))
        .ok()
        .map(|b| {
            let s: String = String::from_utf8_lossy(&b)
                .split('\0')
                .filter(|s| !s.is_empty())
                .collect::<Vec<_>>()
                .join(" ");
            if s.chars().count() > 100 {
                format!("{}…", s.chars().take(100).collect::<String>())
            } else {
                s
            }
        })
        .filter(|s| !s.is_empty());
    Some(match cmd {
        Some(c) => format!("process {pid}: {c}"),
        None => format!("process {pid}"),
    })
}

/// Checks and locks every output of a command before anything is computed (see the module
/// docs), and checks every input that exists ([`pdw_store::check_input`]: a regular file).
/// `inputs` that do not exist are left to their reader to report. The one claim of every
/// writer: the CLI's commands and the explorer's save call it with the files they will write
/// and the files they read; the returned [`Claim`] is held until the files are written.
pub fn claim(
    outputs: &[Output<'_>],
    inputs: &[Input<'_>],
    force: bool,
) -> Result<Claim, InputError> {
    check_inputs(inputs)?;
    let mut ids = identities(outputs, inputs)?;
    let leftover = check_being_written(outputs, &mut ids)?;
    check_overwrites_and_formats(outputs, &ids, force)?;
    lock_outputs(outputs, &ids, leftover)
}

/// Step 0 of [`claim`]: every input that exists is a regular file — a FIFO would block its
/// reader, a device such as /dev/zero never end (missing inputs are left to their reader to
/// report).
fn check_inputs(inputs: &[Input<'_>]) -> Result<(), InputError> {
    for i in inputs {
        if std::fs::metadata(i.path).is_ok() {
            pdw_store::check_input(i.path, None)
                .map_err(|e| InputError(format!("{}: {e}", i.flag)))?;
        }
    }
    Ok(())
}

/// Steps 1-2 of [`claim`]: each output's identity and whether it exists; refused when an
/// output is another output or an input.
fn identities(
    outputs: &[Output<'_>],
    inputs: &[Input<'_>],
) -> Result<Vec<(Identity, bool)>, InputError> {
    let mut ids: Vec<(Identity, bool)> = Vec::with_capacity(outputs.len());
    for o in outputs {
        let id = output_identity(o)?;
        if let Some((j, _)) = ids.iter().enumerate().find(|(_, p)| p.0 == id.0) {
            return Err(InputError(format!(
                "{} '{}' and {} '{}' are the same file: one would replace the other; give each \
                 output its own path (the HDF5 data ends in .h5, the picture in .png)",
                o.flag,
                o.path.display(),
                outputs[j].flag,
                outputs[j].path.display()
            )));
        }
        check_not_an_input(o, &id.0, inputs)?;
        ids.push(id);
    }
    Ok(ids)
}

/// Refuses output `o` (of identity `id`) when it is one of the `inputs`, even with --force.
fn check_not_an_input(
    o: &Output<'_>,
    id: &Identity,
    inputs: &[Input<'_>],
) -> Result<(), InputError> {
    for i in inputs {
        let Ok(m) = std::fs::metadata(i.path) else {
            continue;
        };
        if *id
            == (Identity::File {
                dev: m.dev(),
                ino: m.ino(),
            })
        {
            return Err(InputError(format!(
                "{}: '{}' is also an input ({} '{}', the same file); writing it would \
                 destroy the input, so it is refused even with --force",
                o.flag,
                o.path.display(),
                i.flag,
                i.path.display()
            )));
        }
    }
    Ok(())
}

/// A file being written is reported as such, whatever else holds (in the outputs' order). An
/// empty file where a continued output is expected is a placeholder left by a killed run (see
/// the module docs): claimed as a new output (marked not existing in `ids`). Which outputs are
/// such leftovers.
fn check_being_written(
    outputs: &[Output<'_>],
    ids: &mut [(Identity, bool)],
) -> Result<Vec<bool>, InputError> {
    let mut leftover = vec![false; outputs.len()];
    for (k, (o, (_, exists))) in outputs.iter().zip(ids.iter_mut()).enumerate() {
        if !*exists {
            continue;
        }
        if let Ok(f) = File::open(o.path) {
            lock(&f, o.path, o.flag)?;
        }
        if o.may_exist && std::fs::metadata(o.path).is_ok_and(|m| m.len() == 0) {
            *exists = false;
            leftover[k] = true;
        }
    }
    Ok(leftover)
}

/// The option that overwrites, as the front end of `flag` spells it: `--force` on the command
/// line (`--out`), `force=True` in Python (`out`).
fn force_flag(flag: &str) -> &'static str {
    if flag.starts_with("--") {
        "--force"
    } else {
        "force=True"
    }
}

/// Steps 3-4 of [`claim`]: an existing output is overwritten only with `force` (or where it
/// may exist), and every output's name ends in its format's extension.
fn check_overwrites_and_formats(
    outputs: &[Output<'_>],
    ids: &[(Identity, bool)],
    force: bool,
) -> Result<(), InputError> {
    for (o, (_, exists)) in outputs.iter().zip(ids) {
        if *exists && !force && !o.may_exist {
            let empty = std::fs::metadata(o.path).is_ok_and(|m| m.len() == 0);
            return Err(InputError(format!(
                "{}: '{}' exists{}; pass {} to overwrite it",
                o.flag,
                o.path.display(),
                if empty {
                    " (empty: perhaps left by an interrupted run)"
                } else {
                    ""
                },
                force_flag(o.flag)
            )));
        }
        if !o.format.matches(o.path) {
            return Err(InputError(format!(
                "{}: '{}' would hold {} but its name does not end in {}",
                o.flag,
                o.path.display(),
                o.format.name(),
                o.format
                    .extensions()
                    .iter()
                    .map(|e| format!(".{e}"))
                    .collect::<Vec<_>>()
                    .join(" or ")
            )));
        }
    }
    Ok(())
}

/// Steps 5-6 of [`claim`]: each output's directory takes new files, each output is opened (a
/// new one created as its placeholder) and locked; the stale partial files of killed writers
/// beside it are removed.
fn lock_outputs(
    outputs: &[Output<'_>],
    ids: &[(Identity, bool)],
    leftover: Vec<bool>,
) -> Result<Claim, InputError> {
    let mut claim = Claim { held: Vec::new() };
    for ((o, (_, exists)), leftover) in outputs.iter().zip(ids).zip(leftover) {
        probe(o)?;
        let (file, placeholder) = open_output(o, *exists, leftover)?;
        let held = Held {
            path: o.path.to_path_buf(),
            file: None,
            placeholder,
            existed: *exists,
        };
        // pushed before locking, so that a refusal removes this placeholder too
        claim.held.push(held);
        lock(&file, o.path, o.flag)?;
        if let Some(h) = claim.held.last_mut() {
            h.file = Some(file);
        }
        pdw_store::remove_stale_partials(o.path);
    }
    Ok(claim)
}

/// Output `o` opened for its lock: an existing file as it is; a leftover placeholder (`leftover`)
/// or a new file (created here) with its inode, the placeholder a refusal removes.
fn open_output(
    o: &Output<'_>,
    exists: bool,
    leftover: bool,
) -> Result<(File, Option<u64>), InputError> {
    Ok(if exists {
        (open_for_lock(o.path, o.flag)?, None)
    } else if leftover {
        let f = open_for_lock(o.path, o.flag)?;
        let ino = f.metadata().map(|m| m.ino()).ok();
        (f, ino)
    } else {
        let f = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(o.path)
            .map_err(|e| {
                InputError(format!(
                    "{}: cannot create '{}': {}",
                    o.flag,
                    o.path.display(),
                    kind_text(&e)
                ))
            })?;
        let ino = f.metadata().map(|m| m.ino()).ok();
        (f, ino)
    })
}

/// Creates and removes a file beside `o.path`: its directory takes new files (renaming a
/// finished file into place needs that as well).
fn probe(o: &Output<'_>) -> Result<(), InputError> {
    let dir = directory(o.path);
    let name = o.path.file_name().unwrap_or_default().to_string_lossy();
    let p = dir.join(format!(".{name}.probe-{}", std::process::id()));
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&p)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&p);
            Ok(())
        }
        Err(e) => Err(InputError(format!(
            "{}: cannot write '{}': its directory '{}' does not take new files: {}",
            o.flag,
            o.path.display(),
            dir.display(),
            kind_text(&e)
        ))),
    }
}

/// A value for a message or a table: as Rust prints it (the shortest text that reads back to
/// the same double) where that is short, `1.234568e308` style (seven significant digits) where
/// the magnitude is extreme (beyond 10^±6), which would otherwise print as a decimal of up to
/// 300 digits or a run of zeros.
pub fn number(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() || (1e-6..1e6).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:.6e}")
    }
}
