//! `pdw-sweep explore`: a local web server that serves one page over the basin files named on
//! its command line — the basin drawn at full resolution with the file's legend and units, a
//! clicked cell walked by the file's own model and integrator (the outcome shown is the basin
//! engine's label of that cell, equal to the file's), a dragged box recomputed by the basin
//! engine, and the window saved as a basin file. See docs/explore.md.
//!
//! Safety: the server binds the loopback address unless told otherwise explicitly
//! ([`Config::bind_explicit`]); files are addressed by their index in the list it was started
//! with (the page never sends a path); request bodies are capped ([`MAX_BODY`]); every error
//! is a JSON `{"error": …}` the page shows. The HTTP side runs on a tokio runtime of at most
//! two workers; computations run on one rayon pool ([`Config::threads`]) through
//! `spawn_blocking` and the refine worker ([`jobs`]).

pub mod design;
pub mod error;
pub mod grid;
pub mod jobs;
mod routes;
pub mod save;
pub mod source;
pub mod sweep;
pub mod walk;

pub use error::ApiError;

use source::{BasinSource, Rebuilt};
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

/// The default port of `pdw-sweep explore`.
pub const DEFAULT_PORT: u16 = 8737;
/// Largest request body accepted (bytes): every request is a small JSON object.
pub const MAX_BODY: usize = 16 * 1024;
/// Largest refined window (cells).
pub const MAX_WINDOW_CELLS: usize = 1_000_000;

/// How to start the server.
#[derive(Clone, Debug)]
pub struct Config {
    /// The files served, by index.
    pub files: Vec<PathBuf>,
    /// Address to bind; non-loopback only with `bind_explicit`.
    pub addr: IpAddr,
    /// Whether `addr` was given explicitly (`--bind`).
    pub bind_explicit: bool,
    /// Port; 0 picks a free one.
    pub port: u16,
    /// Where "save" writes.
    pub save_dir: PathBuf,
    /// Threads of the computing pool.
    pub threads: usize,
}

impl Config {
    /// Loopback on `port`, saving into the current directory, two threads.
    pub fn local(files: Vec<PathBuf>, port: u16) -> Config {
        Config {
            files,
            addr: IpAddr::V4(Ipv4Addr::LOCALHOST),
            bind_explicit: false,
            port,
            save_dir: PathBuf::from("."),
            threads: 2,
        }
    }
}

/// A served file: its path, and (read on first use) its contents and rebuilt run.
pub struct Entry {
    pub path: PathBuf,
    source: OnceLock<Result<Arc<BasinSource>, ApiError>>,
    rebuilt: OnceLock<Result<Arc<Rebuilt>, ApiError>>,
    sweep: OnceLock<Result<Arc<pdw_store::SweepData>, ApiError>>,
    design: OnceLock<Result<Arc<design::DesignFile>, ApiError>>,
}

impl Entry {
    /// The file read whole (once).
    pub fn source(&self) -> Result<Arc<BasinSource>, ApiError> {
        self.source
            .get_or_init(|| source::load(&self.path).map(Arc::new))
            .clone()
    }

    /// The file read as a sweep or continuation file (once).
    pub fn sweep(&self) -> Result<Arc<pdw_store::SweepData>, ApiError> {
        self.sweep
            .get_or_init(|| sweep::load(&self.path).map(Arc::new))
            .clone()
    }

    /// The file read as a design-search file (once).
    pub fn design(&self) -> Result<Arc<design::DesignFile>, ApiError> {
        self.design
            .get_or_init(|| design::load(&self.path).map(Arc::new))
            .clone()
    }

    /// The file's run rebuilt (once), checked to reproduce the file's grid and legend.
    pub fn rebuilt(&self, pool: &rayon::ThreadPool) -> Result<Arc<Rebuilt>, ApiError> {
        self.rebuilt
            .get_or_init(|| {
                let src = self.source()?;
                let r = source::rebuild(&src, &source::Window::default(), pool)?;
                source::check_same_run(&src, &r)?;
                Ok(Arc::new(r))
            })
            .clone()
    }
}

/// What every request sees.
pub struct AppState {
    pub entries: Vec<Entry>,
    pub pool: Arc<rayon::ThreadPool>,
    pub jobs: Arc<jobs::Jobs>,
    pub save_dir: PathBuf,
}

impl AppState {
    /// File `i`, or a 404 naming how many there are.
    pub fn entry(&self, i: usize) -> Result<&Entry, ApiError> {
        self.entries.get(i).ok_or_else(|| {
            ApiError::not_found(format!(
                "no file {i}: the server serves {} file(s), numbered from 0",
                self.entries.len()
            ))
        })
    }
}

/// A running server: its URL and state; dropping it stops it.
pub struct Server {
    pub addr: SocketAddr,
    pub url: String,
    pub state: Arc<AppState>,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Server {
    /// Blocks until the server stops.
    pub fn wait(mut self) {
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Refuses a non-loopback address that was not given explicitly.
pub fn check_bind(addr: IpAddr, explicit: bool) -> Result<(), String> {
    if addr.is_loopback() || explicit {
        Ok(())
    } else {
        Err(format!(
            "refusing to listen on {addr}: the explorer binds the loopback address unless \
             --bind ADDR is given explicitly"
        ))
    }
}

/// Starts the server on a thread of its own; returns once it listens.
pub fn start(cfg: Config) -> Result<Server, String> {
    check_bind(cfg.addr, cfg.bind_explicit)?;
    let threads = pdw::input::check_threads(cfg.threads, "threads").map_err(|e| e.0)?;
    let listener = std::net::TcpListener::bind(SocketAddr::new(cfg.addr, cfg.port))
        .map_err(|e| format!("cannot listen on {}:{}: {e}", cfg.addr, cfg.port))?;
    listener.set_nonblocking(true).map_err(|e| e.to_string())?;
    let addr = listener.local_addr().map_err(|e| e.to_string())?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| e.to_string())?;
    let pool = Arc::new(pool);
    let state = Arc::new(AppState {
        entries: cfg
            .files
            .iter()
            .map(|p| Entry {
                path: p.clone(),
                source: OnceLock::new(),
                rebuilt: OnceLock::new(),
                sweep: OnceLock::new(),
                design: OnceLock::new(),
            })
            .collect(),
        jobs: jobs::Jobs::start(pool.clone()),
        pool,
        save_dir: cfg.save_dir.clone(),
    });
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .max_blocking_threads(8)
        .enable_all()
        .build()
        .map_err(|e| e.to_string())?;
    let (tx, rx) = tokio::sync::oneshot::channel::<()>();
    let app = routes::router(state.clone());
    let thread = std::thread::Builder::new()
        .name("pdw-explore".into())
        .spawn(move || {
            rt.block_on(async move {
                let Ok(l) = tokio::net::TcpListener::from_std(listener) else {
                    return;
                };
                let _ = axum::serve(l, app)
                    .with_graceful_shutdown(async {
                        let _ = rx.await;
                    })
                    .await;
            });
        })
        .map_err(|e| e.to_string())?;
    warm_up(&state);
    let host = match addr.ip() {
        IpAddr::V6(a) => format!("[{a}]"),
        IpAddr::V4(a) => a.to_string(),
    };
    Ok(Server {
        addr,
        url: format!("http://{host}:{}/", addr.port()),
        state,
        stop: Some(tx),
        thread: Some(thread),
    })
}

/// Reads the files and rebuilds their runs in the background, so that the first click walks
/// at once.
fn warm_up(state: &Arc<AppState>) {
    let s = state.clone();
    let _ = std::thread::Builder::new()
        .name("pdw-explore-warm".into())
        .spawn(move || {
            for e in &s.entries {
                let _ = e.rebuilt(&s.pool);
            }
        });
}
