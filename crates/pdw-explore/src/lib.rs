//! `pdw-sweep explore`: a local web server that serves one page over the basin files named on
//! its command line — the basin drawn at full resolution with the file's legend and units, a
//! clicked cell walked by the file's own model and integrator (the outcome shown is the basin
//! engine's label of that cell, equal to the file's), a dragged box recomputed by the basin
//! engine, and the window saved as a basin file. See docs/explore.md.
//!
//! Safety: the server binds the loopback address unless told otherwise explicitly
//! ([`Config::bind_explicit`]); it answers only its own page ([`guard`]: the session token in
//! the printed URL, the Host and Origin checked, JSON-only POSTs); files are addressed by their
//! index in the list it was started with (the page never sends a path); request bodies are
//! capped ([`MAX_BODY`]) and must arrive in time, like request heads; connections are bounded
//! ([`Config::max_connections`]), so are the large responses prepared at once ([`heavy`]) and
//! the finished windows kept ([`jobs::CACHE_BYTES`]); every error is a JSON `{"error": …}` the
//! page shows. The HTTP side runs on a tokio runtime of at most two workers; walks run on one
//! rayon pool ([`Config::threads`]) through `spawn_blocking`, windows on the refine worker's
//! own pool ([`jobs`]), so that walks never wait behind a window.

pub mod design;
pub mod error;
pub mod grid;
pub mod guard;
pub mod heavy;
pub mod jobs;
pub mod private_dir;
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
    /// Most connections open at once; a connection beyond is closed at once (file
    /// descriptors stay for the files).
    pub max_connections: usize,
    /// Time limits of a request's head and body.
    pub limits: guard::Limits,
    /// Large responses prepared at once, and how many more may wait ([`heavy`]).
    pub heavy: (usize, usize),
    /// Bytes of finished windows the refine cache keeps ([`jobs::CACHE_BYTES`]).
    pub cache_bytes: usize,
}

/// [`Config::max_connections`] by default.
pub const MAX_CONNECTIONS: usize = 128;
/// [`guard::Limits`] by default: 10 s for a request head, 10 s for a body.
pub const LIMITS: guard::Limits = guard::Limits {
    header_timeout: std::time::Duration::from_secs(10),
    body_timeout: std::time::Duration::from_secs(10),
};

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
            max_connections: MAX_CONNECTIONS,
            limits: LIMITS,
            heavy: heavy::DEFAULT,
            cache_bytes: jobs::CACHE_BYTES,
        }
    }
}

/// A served file: its path, and (read on first use) its contents and rebuilt run.
pub struct Entry {
    pub path: PathBuf,
    source: OnceLock<Result<Arc<BasinSource>, ApiError>>,
    rebuilt: OnceLock<Result<Arc<Rebuilt>, ApiError>>,
    sweep: OnceLock<Result<Arc<pdw::store::SweepData>, ApiError>>,
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
    pub fn sweep(&self) -> Result<Arc<pdw::store::SweepData>, ApiError> {
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
    /// The gate of large responses.
    pub heavy: heavy::Heavy,
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
    /// The page's URL with the session token (`http://127.0.0.1:8737/?token=…`).
    pub url: String,
    /// The session token every API request needs ([`guard`]).
    pub token: String,
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

/// Refuses a save directory that is missing, not a directory or not writable, naming it.
pub fn check_save_dir(dir: &std::path::Path) -> Result<(), String> {
    let shown = dir.display();
    let md = std::fs::metadata(dir)
        .map_err(|e| format!("--save-dir '{shown}': {e}; give an existing, writable directory"))?;
    if !md.is_dir() {
        return Err(format!(
            "--save-dir '{shown}' is not a directory; give an existing, writable directory"
        ));
    }
    let probe =
        tempfile_probe(dir).map_err(|e| format!("--save-dir '{shown}' is not writable: {e}"))?;
    let _ = std::fs::remove_file(probe);
    Ok(())
}

/// A probe file created (new, never an existing path) in `dir`.
fn tempfile_probe(dir: &std::path::Path) -> std::io::Result<PathBuf> {
    let name = format!(
        ".pdw-explore-probe-{}",
        guard::hex(&guard::random_bytes(8).map_err(std::io::Error::other)?)
    );
    let p = dir.join(name);
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&p)?;
    Ok(p)
}

/// Starts the server on a thread of its own; returns once it listens.
pub fn start(cfg: Config) -> Result<Server, String> {
    check_bind(cfg.addr, cfg.bind_explicit)?;
    check_save_dir(&cfg.save_dir)?;
    let threads = pdw::input::check_threads(cfg.threads, "threads").map_err(|e| e.0)?;
    let token = guard::Token::random()?;
    let listener = std::net::TcpListener::bind(SocketAddr::new(cfg.addr, cfg.port))
        .map_err(|e| format!("cannot listen on {}:{}: {e}", cfg.addr, cfg.port))?;
    listener.set_nonblocking(true).map_err(|e| e.to_string())?;
    let addr = listener.local_addr().map_err(|e| e.to_string())?;
    let pool = |name: &'static str| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(move |i| format!("{name}-{i}"))
    };
    let walk_pool = Arc::new(
        pool("pdw-explore-walk")
            .build()
            .map_err(|e| e.to_string())?,
    );
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
        jobs: jobs::Jobs::start(pool("pdw-explore-refine"), cfg.cache_bytes)?,
        pool: walk_pool,
        save_dir: cfg.save_dir.clone(),
        heavy: heavy::Heavy::new(cfg.heavy.0, cfg.heavy.1),
    });
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .max_blocking_threads(8)
        .enable_all()
        .build()
        .map_err(|e| e.to_string())?;
    let (tx, rx) = tokio::sync::oneshot::channel::<()>();
    let guard = Arc::new(guard::Guard::new(token.clone(), addr, cfg.limits));
    let app = routes::router(state.clone(), guard);
    let (max_conn, header_timeout) = (cfg.max_connections.max(1), cfg.limits.header_timeout);
    let thread = std::thread::Builder::new()
        .name("pdw-explore".into())
        .spawn(move || {
            rt.block_on(async move {
                let Ok(l) = tokio::net::TcpListener::from_std(listener) else {
                    return;
                };
                serve(l, app, max_conn, header_timeout, rx).await;
            });
        })
        .map_err(|e| e.to_string())?;
    warm_up(&state);
    Ok(Server {
        addr,
        url: format!(
            "http://{}:{}/?token={}",
            guard::ip_text(addr.ip()),
            addr.port(),
            token.as_str()
        ),
        token: token.as_str().to_string(),
        state,
        stop: Some(tx),
        thread: Some(thread),
    })
}

/// Accepts connections until `stop`: at most `max_conn` at once (one more is closed at once),
/// each served by hyper's HTTP/1 with a deadline on every request head.
async fn serve(
    l: tokio::net::TcpListener,
    app: axum::Router,
    max_conn: usize,
    header_timeout: std::time::Duration,
    mut stop: tokio::sync::oneshot::Receiver<()>,
) {
    let slots = Arc::new(tokio::sync::Semaphore::new(max_conn));
    loop {
        let tcp = tokio::select! {
            _ = &mut stop => return,
            r = l.accept() => match r {
                Ok((tcp, _)) => tcp,
                // out of file descriptors, or a connection reset before it was accepted
                Err(_) => {
                    tokio::task::yield_now().await;
                    continue;
                }
            },
        };
        let Ok(slot) = slots.clone().try_acquire_owned() else {
            drop(tcp);
            continue;
        };
        let svc = hyper_util::service::TowerToHyperService::new(app.clone());
        tokio::spawn(async move {
            let _slot = slot;
            let conn = hyper::server::conn::http1::Builder::new()
                .timer(hyper_util::rt::TokioTimer::new())
                .header_read_timeout(header_timeout)
                .serve_connection(hyper_util::rt::TokioIo::new(tcp), svc);
            let _ = conn.await;
        });
    }
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
