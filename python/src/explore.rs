//! `explore`: the local basin explorer of `pdw-sweep explore` ([`pdw_explore`]) started on a
//! background thread, for a notebook.

use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Mutex;

use crate::errors::err;

/// The servers started from Python: they serve until the interpreter exits.
static SERVERS: Mutex<Vec<pdw_explore::Server>> = Mutex::new(Vec::new());

/// `explore(path, port=0, save_dir=".", threads=2)`: serves the basin file `path` (or a list
/// of files) on 127.0.0.1 — the page of `pdw-sweep explore` — on a background thread and
/// returns its URL with the session token (`http://127.0.0.1:PORT/?token=…`; `port=0`: any
/// free port; the URL has the real one). The server runs until the interpreter exits.
#[pyfunction]
#[pyo3(
    signature = (path, port=0, save_dir=PathBuf::from("."), threads=2),
    text_signature = "(path, port=0, save_dir='.', threads=2)"
)]
pub(crate) fn explore(
    path: &Bound<'_, PyAny>,
    port: u16,
    save_dir: PathBuf,
    threads: usize,
) -> PyResult<String> {
    let files: Vec<PathBuf> = match path.extract::<PathBuf>() {
        Ok(p) => vec![p],
        Err(_) => path
            .extract::<Vec<PathBuf>>()
            .map_err(|_| err("path: give a basin file's path or a list of paths"))?,
    };
    if let Some(missing) = files.iter().find(|p| !p.is_file()) {
        return Err(err(format!("path: '{}' is not a file", missing.display())));
    }
    let mut cfg = pdw_explore::Config::local(files, port);
    cfg.save_dir = save_dir;
    cfg.threads = threads;
    let server = pdw_explore::start(cfg).map_err(err)?;
    let url = server.url.clone();
    SERVERS
        .lock()
        .map_err(|_| err("explore: server list poisoned"))?
        .push(server);
    Ok(url)
}
