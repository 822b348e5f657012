//! What makes a file self-describing: provenance (who made it, how, from which build), a
//! `units` attribute on every dataset, the slice a basin grid lies on, and HDF5 dimension
//! scales tying `/grid/x`, `/grid/y` to the dimensions of the grid datasets.
//!
//! # Provenance (`/provenance`, attributes)
//! `crate_version`, `git_commit` (read from git when the crate was built; `"unknown"` outside a
//! git checkout), `build_profile` (`release`/`debug`), `simd_path` (the instruction-set path
//! chosen at run time, from the caller), `numerics` (the numeric contract every path keeps), `host`, `command` (the command line), `options` (JSON: every numerical
//! option of the run — integrator, tolerances, continuation settings, orbit-diagram counts…),
//! `created` (RFC 3339 UTC) and `commands` (JSON list of every command line that wrote to the
//! file: a resumed basin lists the first run and each `--resume`). A merged basin keeps each
//! shard's provenance in `/provenance/shards/NNN` (with the shard's `file`).
//!
//! # Units
//! Every dataset gets a `units` attribute: a unit string (`"rad"`, `"rad/s"`, `"s"`,
//! `"sqrt(l/g)"`, `"1"` for counts, codes and dimensionless numbers), or, for a dataset whose
//! last axis runs over named components of different units, a JSON list of the units in that
//! order (e.g. `/basin/final`: `["rad","rad/s","rad/s"]`).
//!
//! # Slice (`/slice`, basin files)
//! A basin grid varies two section coordinates; every other one is held fixed. `/slice` has
//! attributes `x`, `y` (the axes' coordinate names), `fixed` (JSON object name → `{value,
//! unit, source}`, source `"fixed point"` when the value defaulted to the gait's or `"--set"`),
//! one `f64` attribute per fixed coordinate, and `on_fixed_point` (whether the gait lies on the
//! slice, i.e. every fixed coordinate equals the gait's).
//!
//! # Dimension scales
//! Written by hand to the HDF5 Dimension Scale specification (the high-level library H5DS is
//! not built by `hdf5-metno`'s `static` feature): the scale datasets get `CLASS =
//! "DIMENSION_SCALE"`, `NAME` and `REFERENCE_LIST` (compound `{dataset: object reference,
//! dimension: int}`), and each data dataset gets `DIMENSION_LIST` (one variable-length list of
//! object references per dimension). h5py's `ds.dims`, MATLAB's and netCDF-4 readers see them.

use std::ffi::{c_void, CString};
use std::path::Path;

use hdf5::{Dataset, File, Location};
use hdf5_sys::h5::hsize_t;
use hdf5_sys::h5i::hid_t;
use hdf5_sys::h5p::H5P_DEFAULT;
use hdf5_sys::h5r::{hobj_ref_t, H5R_type_t, H5Rcreate};
use hdf5_sys::{h5a, h5s, h5t};

use crate::h5util::{get_str, has_attr, open_unlocked, set_attr, set_str, At};
use crate::{time, Result, StoreError};

/// The git commit the crate was built from (`"unknown"` without git), with `-dirty` when the
/// work tree had uncommitted changes at build time.
pub const GIT_COMMIT: &str = env!("PDW_GIT_COMMIT");
/// The cargo profile of the build (`release`, `debug`).
pub const BUILD_PROFILE: &str = env!("PDW_BUILD_PROFILE");

/// Who made a file, how, and from which build.
#[derive(Clone, Debug, PartialEq)]
pub struct Provenance {
    pub crate_version: String,
    pub git_commit: String,
    pub build_profile: String,
    /// The instruction-set path the hot loops ran on (`baseline`, `avx2`, `avx512`).
    pub simd_path: String,
    /// The numeric contract every path keeps (`pdw_simd::NUMERICS`); files whose contract,
    /// crate version or commit differ may differ in the last bit, and `merge` refuses them.
    pub numerics: String,
    pub host: String,
    /// The command line.
    pub command: String,
    /// Every numerical option of the run, as a JSON object text.
    pub options: String,
    /// The resolved walker spec of a chain walker (its TOML text, parameters included:
    /// `WalkerSpec::to_toml`), so a reader rebuilds a user's own walker without its file;
    /// empty for the closed-form models (rebuilt by name) and files from before it existed.
    /// Written as the attribute `model_spec` when not empty.
    pub model_spec: String,
}

impl Provenance {
    /// This build's provenance for a run of `command` with `options` (a JSON object).
    pub fn new(command: &str, simd_path: &str, options: &serde_json::Value) -> Self {
        Self {
            crate_version: env!("CARGO_PKG_VERSION").to_string(),
            git_commit: GIT_COMMIT.to_string(),
            build_profile: BUILD_PROFILE.to_string(),
            simd_path: simd_path.to_string(),
            numerics: String::new(),
            host: hostname(),
            command: command.to_string(),
            options: options.to_string(),
            model_spec: String::new(),
        }
    }

    fn fields(&self) -> [(&'static str, &str); 8] {
        [
            ("crate_version", &self.crate_version),
            ("git_commit", &self.git_commit),
            ("build_profile", &self.build_profile),
            ("simd_path", &self.simd_path),
            ("numerics", &self.numerics),
            ("host", &self.host),
            ("command", &self.command),
            ("options", &self.options),
        ]
    }
}

/// The host name (`gethostname`), `"unknown"` if it cannot be read.
pub fn hostname() -> String {
    let mut buf = [0u8; 256];
    // SAFETY: the buffer is valid for its length; gethostname NUL-terminates on success (a
    // truncated name may not be, hence the search bounded by the buffer).
    let r = unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) };
    if r != 0 {
        return "unknown".into();
    }
    let n = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
    String::from_utf8_lossy(&buf[..n]).into_owned()
}

/// The slice a basin grid lies on.
#[derive(Clone, Debug, PartialEq)]
pub struct Slice {
    /// The coordinate along x and along y.
    pub x: String,
    pub y: String,
    /// Every other section coordinate: `(name, value, unit, source)`, source `"fixed point"`
    /// or `"--set"`.
    pub fixed: Vec<(String, f64, String, String)>,
    /// Whether the gait lies on the slice.
    pub on_fixed_point: bool,
}

impl Slice {
    /// `"hip_rate = 0.715 rad/s (fixed point)"`, one entry per fixed coordinate, for titles.
    pub fn describe(&self) -> String {
        self.fixed
            .iter()
            .map(|(n, v, u, s)| format!("{n} = {} {u} ({s})", short(*v)))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// `v` with 5 decimals, trailing zeros dropped (`0.6`, `0.05236`), for titles.
pub fn short(v: f64) -> String {
    let t = format!("{v:.5}");
    if t.contains('.') {
        t.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        t
    }
}

/// A dimension scale to attach: `scale` (a 1-D dataset path) to dimension `dim` of `data`.
#[derive(Clone, Debug, PartialEq)]
pub struct ScaleAttach {
    pub data: String,
    pub dim: usize,
    pub scale: String,
}

/// Everything [`annotate_file`] writes.
pub struct Annotations<'a> {
    pub provenance: Option<&'a Provenance>,
    /// The unit of a dataset, by its path (`"basin/final"`); `None` leaves it without one
    /// (the tests require every dataset to have one).
    pub units: &'a dyn Fn(&str) -> Option<String>,
    pub slice: Option<&'a Slice>,
    pub scales: &'a [ScaleAttach],
    /// The root attribute `coordinates`: what each state component of the model means (JSON
    /// object, state name → meaning); `None` leaves the file's own.
    pub coordinates: Option<&'a str>,
}

/// Opens `path` for writing and annotates it (see [`annotate_file`]).
pub fn annotate(path: &Path, a: &Annotations<'_>) -> Result<()> {
    let f = open_unlocked(path, true, "opening for annotation")?;
    annotate_file(path, &f, a)?;
    f.flush().at(path, "flushing")?;
    f.close().at(path, "closing")
}

/// Writes provenance, units on every dataset `units` knows (datasets not yet in the file are
/// skipped; a later call adds theirs), the slice and the dimension scales into the open `file`.
pub fn annotate_file(path: &Path, file: &File, a: &Annotations<'_>) -> Result<()> {
    if let Some(p) = a.provenance {
        write_provenance(path, file, p)?;
    }
    for ds in dataset_paths(path, file)? {
        if let Some(u) = (a.units)(&ds) {
            let d = file.dataset(&ds).at(path, "opening a dataset")?;
            set_str(path, &d, "units", &u)?;
        }
    }
    if let Some(s) = a.slice {
        write_slice(path, file, s)?;
    }
    if !a.scales.is_empty() {
        attach_scales(path, file, a.scales)?;
    }
    if let Some(c) = a.coordinates {
        set_str(path, file, "coordinates", c)?;
    }
    Ok(())
}

/// Every dataset of the file, as paths without the leading `/`, in name order.
pub fn dataset_paths(path: &Path, file: &File) -> Result<Vec<String>> {
    fn walk(path: &Path, g: &hdf5::Group, prefix: &str, out: &mut Vec<String>) -> Result<()> {
        for name in g.member_names().at(path, "listing a group")? {
            let full = if prefix.is_empty() {
                name.clone()
            } else {
                format!("{prefix}/{name}")
            };
            if let Ok(sub) = g.group(&name) {
                walk(path, &sub, &full, out)?;
            } else if g.dataset(&name).is_ok() {
                out.push(full);
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    walk(path, file, "", &mut out)?;
    Ok(out)
}

/// The group `name` of `parent`, created when it is missing (`what` names the step in the error).
fn group_at(path: &Path, parent: &hdf5::Group, name: &str, what: &str) -> Result<hdf5::Group> {
    match parent.group(name) {
        Ok(g) => Ok(g),
        Err(_) => parent.create_group(name).at(path, what),
    }
}

/// `/provenance`: the attributes of `p`, `created`, and `commands` extended by this command.
pub fn write_provenance(path: &Path, file: &File, p: &Provenance) -> Result<()> {
    let g = group_at(path, file, "provenance", "creating /provenance")?;
    let mut commands: Vec<String> = if has_attr(&g, "commands") {
        serde_json::from_str(&get_str(path, "pdw-sweep file", &g, "commands")?).unwrap_or_default()
    } else {
        Vec::new()
    };
    if commands.last() != Some(&p.command) {
        commands.push(p.command.clone());
    }
    for (k, v) in p.fields() {
        set_str(path, &g, k, v)?;
    }
    if !p.model_spec.is_empty() {
        set_str(path, &g, "model_spec", &p.model_spec)?;
    }
    if !has_attr(&g, "created") {
        set_str(path, &g, "created", &time::now_rfc3339())?;
    }
    set_str(
        path,
        &g,
        "commands",
        &serde_json::to_string(&commands).unwrap_or_default(),
    )
}

/// Carries the history in `/provenance` of `src` — `commands` and `created` — into `dst`, a
/// file rebuilt from it (a resumed basin): the next [`write_provenance`] on `dst` extends the
/// command list instead of starting a new one. A `src` without provenance carries nothing.
pub fn carry_history(src_path: &Path, src: &File, dst_path: &Path, dst: &File) -> Result<()> {
    let Ok(sg) = src.group("provenance") else {
        return Ok(());
    };
    let g = group_at(dst_path, dst, "provenance", "creating /provenance")?;
    for k in ["commands", "created"] {
        if has_attr(&sg, k) {
            let v = get_str(src_path, "pdw-sweep file", &sg, k)?;
            set_str(dst_path, &g, k, &v)?;
        }
    }
    Ok(())
}

/// Reads `/provenance` of an open file (`None` for files written before it existed).
pub fn read_provenance(path: &Path, file: &File) -> Result<Option<Provenance>> {
    let Ok(g) = file.group("provenance") else {
        return Ok(None);
    };
    read_provenance_at(path, &g).map(Some)
}

fn read_provenance_at(path: &Path, g: &Location) -> Result<Provenance> {
    let r = |k: &str| get_str(path, "pdw-sweep file", g, k);
    Ok(Provenance {
        crate_version: r("crate_version")?,
        git_commit: r("git_commit")?,
        build_profile: r("build_profile")?,
        simd_path: r("simd_path")?,
        // Files from before the attribute existed: unknown contract.
        numerics: r("numerics").unwrap_or_default(),
        host: r("host")?,
        command: r("command")?,
        options: r("options")?,
        // Files from before the attribute existed, and closed-form models: none.
        model_spec: r("model_spec").unwrap_or_default(),
    })
}

/// Copies each shard's provenance into `/provenance/shards/NNN` of the merged `file` (with the
/// shard's `file` name); a shard without one keeps at least its root `command`.
pub fn copy_shard_provenance(path: &Path, file: &File, shards: &[&Path]) -> Result<()> {
    let g = group_at(path, file, "provenance", "creating /provenance")?;
    let sg = group_at(path, &g, "shards", "creating /provenance/shards")?;
    for (i, sp) in shards.iter().enumerate() {
        let sf = open_unlocked(sp, false, "opening a shard")?;
        let name = format!("{i:03}");
        let dst = group_at(path, &sg, &name, "creating a shard entry")?;
        set_str(path, &dst, "file", &sp.display().to_string())?;
        match read_provenance(sp, &sf)? {
            Some(p) => {
                for (k, v) in p.fields() {
                    set_str(path, &dst, k, v)?;
                }
            }
            None => {
                let c = get_str(sp, "pdw-sweep basin", &sf, "command").unwrap_or_default();
                set_str(path, &dst, "command", &c)?;
            }
        }
        if let Ok(sgp) = sf.group("provenance") {
            if has_attr(&sgp, "commands") {
                let c = get_str(sp, "pdw-sweep file", &sgp, "commands")?;
                set_str(path, &dst, "commands", &c)?;
            }
        }
    }
    Ok(())
}

/// Copies the `units` attribute of every dataset of `src` onto the dataset of the same path in
/// `file`, the root `coordinates` and `/slice` (a merged basin describes itself as its shards
/// did).
pub fn copy_units_and_slice(path: &Path, file: &File, src: &Path) -> Result<()> {
    let sf = open_unlocked(src, false, "opening a shard")?;
    for ds in dataset_paths(src, &sf)? {
        let (Ok(s), Ok(d)) = (sf.dataset(&ds), file.dataset(&ds)) else {
            continue;
        };
        if has_attr(&s, "units") {
            let u = get_str(src, "pdw-sweep file", &s, "units")?;
            set_str(path, &d, "units", &u)?;
        }
    }
    if has_attr(&sf, "coordinates") {
        let c = get_str(src, "pdw-sweep file", &sf, "coordinates")?;
        set_str(path, file, "coordinates", &c)?;
    }
    if let Ok(sl) = sf.group("slice") {
        let dst = group_at(path, file, "slice", "creating /slice")?;
        for name in sl.attr_names().at(src, "listing /slice")? {
            let a = sl.attr(&name).at(src, "reading /slice")?;
            // bool first: HDF5 converts its enum to f64, not the other way.
            if let Ok(v) = a.read_scalar::<bool>() {
                set_attr(path, &dst, &name, &v)?;
            } else if let Ok(v) = a.read_scalar::<f64>() {
                set_attr(path, &dst, &name, &v)?;
            } else {
                let v = get_str(src, "pdw-sweep basin", &sl, &name)?;
                set_str(path, &dst, &name, &v)?;
            }
        }
    }
    Ok(())
}

/// `/slice` (see the module docs).
pub fn write_slice(path: &Path, file: &File, s: &Slice) -> Result<()> {
    let g = group_at(path, file, "slice", "creating /slice")?;
    set_str(path, &g, "x", &s.x)?;
    set_str(path, &g, "y", &s.y)?;
    let fixed: serde_json::Map<String, serde_json::Value> = s
        .fixed
        .iter()
        .map(|(n, v, u, src)| {
            (
                n.clone(),
                serde_json::json!({"value": v, "unit": u, "source": src}),
            )
        })
        .collect();
    set_str(
        path,
        &g,
        "fixed",
        &serde_json::Value::Object(fixed).to_string(),
    )?;
    for (n, v, _, _) in &s.fixed {
        set_attr(path, &g, n, v)?;
    }
    set_attr(path, &g, "on_fixed_point", &s.on_fixed_point)
}

fn h5_err(path: &Path, what: &str) -> StoreError {
    StoreError::invalid(
        "dimension scales",
        format!("{}: {what} failed", path.display()),
    )
}

fn cstr(s: &str) -> CString {
    CString::new(s).unwrap_or_default()
}

/// Deletes attribute `name` of object `id` if it exists.
///
/// # Safety
/// `id` must be an open HDF5 object identifier; the caller holds HDF5's lock.
unsafe fn delete_attr(id: hid_t, name: &str) {
    let c = cstr(name);
    if h5a::H5Aexists(id, c.as_ptr()) > 0 {
        h5a::H5Adelete(id, c.as_ptr());
    }
}

/// Writes attribute `name` of type `t` and dataspace `space` from `buf`, replacing one of the
/// same name; closes nothing of the caller's.
///
/// # Safety
/// `id`, `t`, `space` must be open identifiers and `buf` must hold data of `t` for every
/// element of `space`; the caller holds HDF5's lock.
unsafe fn write_raw_attr(
    id: hid_t,
    name: &str,
    t: hid_t,
    space: hid_t,
    buf: *const c_void,
) -> bool {
    delete_attr(id, name);
    let c = cstr(name);
    let a = h5a::H5Acreate2(id, c.as_ptr(), t, space, H5P_DEFAULT, H5P_DEFAULT);
    if a < 0 {
        return false;
    }
    let ok = h5a::H5Awrite(a, t, buf) >= 0;
    h5a::H5Aclose(a);
    ok
}

/// A fixed-length, NUL-terminated ASCII string attribute (the type H5DS uses for `CLASS`).
///
/// # Safety
/// As [`write_raw_attr`].
unsafe fn write_fixed_str(id: hid_t, name: &str, value: &str) -> bool {
    let v = cstr(value);
    let bytes = v.as_bytes_with_nul();
    let t = h5t::H5Tcopy(*h5t::H5T_C_S1);
    h5t::H5Tset_size(t, bytes.len());
    h5t::H5Tset_strpad(t, h5t::H5T_STR_NULLTERM);
    let sp = h5s::H5Screate(h5s::H5S_class_t::H5S_SCALAR);
    let ok = write_raw_attr(id, name, t, sp, bytes.as_ptr().cast());
    h5s::H5Sclose(sp);
    h5t::H5Tclose(t);
    ok
}

/// Attaches every scale of `scales` to its data dataset's dimension, to the Dimension Scale
/// specification (attributes `CLASS`, `NAME`, `REFERENCE_LIST`, `DIMENSION_LIST`). Each call
/// rewrites those attributes whole for the datasets it names.
pub fn attach_scales(path: &Path, file: &File, scales: &[ScaleAttach]) -> Result<()> {
    let open = |p: &str| -> Result<Dataset> { file.dataset(p).at(path, "opening a dataset") };
    let fid = file.id();
    // Scales: CLASS, NAME, REFERENCE_LIST.
    let mut scale_names: Vec<&str> = scales.iter().map(|s| s.scale.as_str()).collect();
    scale_names.sort();
    scale_names.dedup();
    for sc in &scale_names {
        let ds = open(sc)?;
        let entries: Vec<RefEntry> = scales
            .iter()
            .filter(|s| s.scale == *sc)
            .map(|s| {
                Ok(RefEntry {
                    dataset: object_ref(path, fid, &s.data)?,
                    dimension: s.dim as i32,
                })
            })
            .collect::<Result<_>>()?;
        // The dimension's name: the scale's coordinate (its `name` attribute, e.g. "theta"),
        // else its dataset name.
        let coord = if has_attr(&ds, "name") {
            get_str(path, "pdw-sweep file", &ds, "name").ok()
        } else {
            None
        };
        let name = coord
            .as_deref()
            .unwrap_or_else(|| sc.rsplit('/').next().unwrap_or(sc));
        if !write_scale_attrs(&ds, name, &entries) {
            return Err(h5_err(path, &format!("making /{sc} a dimension scale")));
        }
    }
    // Data: DIMENSION_LIST, one list of scale references per dimension.
    let mut datas: Vec<&str> = scales.iter().map(|s| s.data.as_str()).collect();
    datas.sort();
    datas.dedup();
    for d in datas {
        let ds = open(d)?;
        let rank = ds.ndim();
        let mut lists: Vec<Vec<hobj_ref_t>> = vec![Vec::new(); rank];
        for s in scales.iter().filter(|s| s.data == d) {
            if s.dim >= rank {
                return Err(StoreError::invalid(
                    "dimension scales",
                    format!("/{d} has {rank} dimensions, no dimension {}", s.dim),
                ));
            }
            lists[s.dim].push(object_ref(path, fid, &s.scale)?);
        }
        if !write_dimension_list(&ds, &mut lists) {
            return Err(h5_err(path, &format!("attaching scales to /{d}")));
        }
    }
    Ok(())
}

/// One entry of a dimension scale's `REFERENCE_LIST`: a dataset the scale is attached to and
/// the dimension (the C layout of the compound type H5DS writes).
#[repr(C)]
struct RefEntry {
    dataset: hobj_ref_t,
    dimension: i32,
}

/// An object reference to the dataset `/p` of the open file `fid`.
fn object_ref(path: &Path, fid: hid_t, p: &str) -> Result<hobj_ref_t> {
    let c = cstr(&format!("/{p}"));
    let mut r: hobj_ref_t = 0;
    // SAFETY: `r` is a valid hobj_ref_t buffer; `fid` is the open file.
    let e = unsafe {
        H5Rcreate(
            (&mut r as *mut hobj_ref_t).cast(),
            fid,
            c.as_ptr(),
            H5R_type_t::H5R_OBJECT1,
            -1,
        )
    };
    if e < 0 {
        return Err(h5_err(path, &format!("a reference to /{p}")));
    }
    Ok(r)
}

/// Makes `ds` a dimension scale: `CLASS` = `DIMENSION_SCALE`, `NAME` = `name`, and
/// `REFERENCE_LIST` = `entries` (the datasets and dimensions it is attached to). False if HDF5
/// refused a write.
fn write_scale_attrs(ds: &Dataset, name: &str, entries: &[RefEntry]) -> bool {
    hdf5::sync::sync(|| {
        // SAFETY: identifiers opened here and closed before leaving; the compound type
        // matches `RefEntry`'s C layout; HDF5's lock is held by `sync`.
        unsafe {
            let id = ds.id();
            let mut ok = write_fixed_str(id, "CLASS", "DIMENSION_SCALE");
            ok &= write_fixed_str(id, "NAME", name);
            let t = h5t::H5Tcreate(
                h5t::H5T_class_t::H5T_COMPOUND,
                std::mem::size_of::<RefEntry>(),
            );
            let f1 = cstr("dataset");
            let f2 = cstr("dimension");
            h5t::H5Tinsert(
                t,
                f1.as_ptr(),
                std::mem::offset_of!(RefEntry, dataset),
                *h5t::H5T_STD_REF_OBJ,
            );
            h5t::H5Tinsert(
                t,
                f2.as_ptr(),
                std::mem::offset_of!(RefEntry, dimension),
                *h5t::H5T_NATIVE_INT,
            );
            let n = [entries.len() as hsize_t];
            let sp = h5s::H5Screate_simple(1, n.as_ptr(), std::ptr::null());
            ok &= write_raw_attr(id, "REFERENCE_LIST", t, sp, entries.as_ptr().cast());
            h5s::H5Sclose(sp);
            h5t::H5Tclose(t);
            ok
        }
    })
}

/// Writes the data dataset `ds`'s `DIMENSION_LIST`: for each of its dimensions, the list of
/// references to the scales attached to it (`lists`, one per dimension). False if HDF5 refused
/// the write.
fn write_dimension_list(ds: &Dataset, lists: &mut [Vec<hobj_ref_t>]) -> bool {
    let rank = lists.len();
    let mut vl: Vec<h5t::hvl_t> = lists
        .iter_mut()
        .map(|l| h5t::hvl_t {
            len: l.len(),
            p: if l.is_empty() {
                std::ptr::null_mut()
            } else {
                l.as_mut_ptr().cast()
            },
        })
        .collect();
    hdf5::sync::sync(|| {
        // SAFETY: `vl` points into `lists`, alive for the call; identifiers are closed
        // before leaving; HDF5's lock is held by `sync`.
        unsafe {
            let t = h5t::H5Tvlen_create(*h5t::H5T_STD_REF_OBJ);
            let n = [rank as hsize_t];
            let sp = h5s::H5Screate_simple(1, n.as_ptr(), std::ptr::null());
            let ok = write_raw_attr(ds.id(), "DIMENSION_LIST", t, sp, vl.as_mut_ptr().cast());
            h5s::H5Sclose(sp);
            h5t::H5Tclose(t);
            ok
        }
    })
}

/// Annotates a merged basin file: its own provenance (the merge command), each shard's in
/// `/provenance/shards/NNN`, the units and slice of the first shard, and the grid's dimension
/// scales.
pub fn annotate_merged(out: &Path, shards: &[&Path], p: &Provenance) -> Result<()> {
    let f = open_unlocked(out, true, "opening for annotation")?;
    write_provenance(out, &f, p)?;
    copy_shard_provenance(out, &f, shards)?;
    if let Some(first) = shards.first() {
        copy_units_and_slice(out, &f, first)?;
    }
    let scales = if f.link_exists("grid/z") {
        basin_scales_3d()
    } else {
        basin_scales()
    };
    attach_scales(out, &f, &scales)?;
    f.flush().at(out, "flushing")?;
    f.close().at(out, "closing")
}

/// The dimension scales of a basin file: `/grid/y` on dimension 0 and `/grid/x` on dimension
/// 1 of `/basin/outcome`, `/basin/strides` and `/basin/final`.
pub fn basin_scales() -> Vec<ScaleAttach> {
    ["basin/outcome", "basin/strides", "basin/final"]
        .iter()
        .flat_map(|d| {
            [
                ScaleAttach {
                    data: d.to_string(),
                    dim: 0,
                    scale: "grid/y".into(),
                },
                ScaleAttach {
                    data: d.to_string(),
                    dim: 1,
                    scale: "grid/x".into(),
                },
            ]
        })
        .collect()
}

/// The dimension scales of a 3-D basin file: `/grid/z`, `/grid/y` and `/grid/x` on dimensions
/// 0, 1 and 2 of `/basin/outcome`, `/basin/strides` and `/basin/final`.
pub fn basin_scales_3d() -> Vec<ScaleAttach> {
    ["basin/outcome", "basin/strides", "basin/final"]
        .iter()
        .flat_map(|d| {
            ["grid/z", "grid/y", "grid/x"]
                .iter()
                .enumerate()
                .map(|(dim, s)| ScaleAttach {
                    data: d.to_string(),
                    dim,
                    scale: s.to_string(),
                })
        })
        .collect()
}

/// The z-slice of a 3-D basin the picture draws, written into `/slice`: attributes `z` (the
/// coordinate), `z_index` (the slice, from 0) and `z_value`, and the dataset `outcome`, u8
/// `[ny, nx]`, equal to `/basin/outcome[z_index]`.
pub fn write_slice_view(
    path: &Path,
    z_name: &str,
    z_index: usize,
    z_value: f64,
    outcome: ndarray::ArrayView2<'_, u8>,
) -> Result<()> {
    let f = open_unlocked(path, true, "opening for the slice")?;
    let g = group_at(path, &f, "slice", "creating /slice")?;
    set_str(path, &g, "z", z_name)?;
    set_attr(path, &g, "z_index", &(z_index as u64))?;
    set_attr(path, &g, "z_value", &z_value)?;
    if g.link_exists("outcome") {
        g.unlink("outcome").at(path, "replacing /slice/outcome")?;
    }
    let ds = g
        .new_dataset_builder()
        .with_data(&outcome.as_standard_layout())
        .create("outcome")
        .at(path, "writing /slice/outcome")?;
    set_str(path, &ds, "units", "1")?;
    set_str(
        path,
        &ds,
        "description",
        "the z-slice /basin/outcome[z_index] the picture draws (legend as /basin/outcome)",
    )?;
    drop(ds);
    f.flush().at(path, "flushing")?;
    f.close().at(path, "closing")
}

/// The z-slice recorded by [`write_slice_view`]: `(z, z_index, z_value)`, `None` for a 2-D
/// basin.
pub fn read_slice_view(path: &Path) -> Result<Option<(String, usize, f64)>> {
    let f = open_unlocked(path, false, "opening")?;
    let Ok(g) = f.group("slice") else {
        return Ok(None);
    };
    if !has_attr(&g, "z_index") {
        return Ok(None);
    }
    let kind = "pdw-sweep basin";
    Ok(Some((
        get_str(path, kind, &g, "z")?,
        crate::h5util::get_attr::<u64>(path, kind, &g, "z_index")? as usize,
        crate::h5util::get_attr::<f64>(path, kind, &g, "z_value")?,
    )))
}

/// The slice of a basin file (`None` for files written before `/slice` existed).
pub fn read_slice(path: &Path) -> Result<Option<Slice>> {
    let f = open_unlocked(path, false, "opening")?;
    let Ok(g) = f.group("slice") else {
        return Ok(None);
    };
    let r = |k: &str| get_str(path, "pdw-sweep basin", &g, k);
    let fixed: serde_json::Map<String, serde_json::Value> =
        serde_json::from_str(&r("fixed")?).unwrap_or_default();
    let on = g
        .attr("on_fixed_point")
        .and_then(|a| a.read_scalar::<bool>())
        .at(path, "reading /slice")?;
    Ok(Some(Slice {
        x: r("x")?,
        y: r("y")?,
        fixed: fixed
            .into_iter()
            .map(|(n, v)| {
                (
                    n,
                    v["value"].as_f64().unwrap_or(f64::NAN),
                    v["unit"].as_str().unwrap_or_default().to_string(),
                    v["source"].as_str().unwrap_or_default().to_string(),
                )
            })
            .collect(),
        on_fixed_point: on,
    }))
}

/// The `units` attribute of dataset `ds` of the file at `path` (`None` without one).
pub fn read_units(path: &Path, ds: &str) -> Result<Option<String>> {
    let f = open_unlocked(path, false, "opening")?;
    let d = f.dataset(ds).at(path, "opening a dataset")?;
    if has_attr(&d, "units") {
        get_str(path, "pdw-sweep file", &d, "units").map(Some)
    } else {
        Ok(None)
    }
}

/// The provenance of each shard file (`None` where a file has none).
pub fn shard_provenance(shards: &[&Path]) -> Result<Vec<Option<Provenance>>> {
    shards
        .iter()
        .map(|p| {
            let f = crate::h5util::open_file(p, false)?;
            read_provenance(p, &f)
        })
        .collect()
}

/// The resolved walker spec a file records (`/provenance/model_spec`, [`Provenance::model_spec`]):
/// `None` for a closed-form model, a file without provenance or one from before it existed.
pub fn read_model_spec(path: &Path) -> Result<Option<String>> {
    let f = crate::h5util::open_file(path, false)?;
    Ok(read_provenance(path, &f)?
        .map(|p| p.model_spec)
        .filter(|s| !s.is_empty()))
}

/// What a file says about its own run beyond its header: its `/provenance` (`None` in files
/// written before it existed) and its root `coordinates` attribute (state name → meaning, a
/// JSON object text; `None` without one).
pub fn read_run_description(path: &Path) -> Result<(Option<Provenance>, Option<String>)> {
    let f = crate::h5util::open_file(path, false)?;
    let prov = read_provenance(path, &f)?;
    let coords = if has_attr(&f, "coordinates") {
        Some(get_str(path, "pdw-sweep file", &f, "coordinates")?)
    } else {
        None
    };
    Ok((prov, coords))
}
