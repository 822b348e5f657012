//! `pdw-sweep explore`: the local basin explorer ([`pdw_explore`], docs/explore.md). With no
//! file it first computes the default basin of `pdw-sweep basin` into a private temporary
//! directory ([`PrivateDir`]), removed when the explorer stops, by Ctrl-C or SIGTERM too.

use crate::cli::{Cli, Command, ExploreArgs};
use clap::Parser;
use pdw_explore::private_dir::PrivateDir;
use std::net::{IpAddr, Ipv4Addr};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// Set once the server listens: Ctrl-C then ends the process (before, it stops the default
/// basin's computation as in `basin`).
static SERVING: AtomicBool = AtomicBool::new(false);
/// The default basin's private directory, removed by the signal handler before it exits.
static TEMP: Mutex<Option<PrivateDir>> = Mutex::new(None);

pub fn run(a: &ExploreArgs) -> anyhow::Result<ExitCode> {
    let _ = ctrlc::set_handler(|| {
        if SERVING.load(Ordering::SeqCst) {
            if let Ok(mut t) = TEMP.lock() {
                drop(t.take());
            }
            std::process::exit(0);
        }
        pdw::hybrid::interrupt::request();
    });
    pdw_explore::check_save_dir(&a.save_dir).map_err(crate::args::InputError)?;
    let addr = a.bind.unwrap_or(IpAddr::V4(Ipv4Addr::LOCALHOST));
    if !addr.is_loopback() {
        eprintln!(
            "warning: listening on {addr}: anyone who can reach this address can use the \
             explorer (it computes on request and writes into --save-dir)"
        );
    }
    let files = if a.files.is_empty() {
        default_basin()?
    } else {
        a.files.clone()
    };
    let cfg = pdw_explore::Config {
        files,
        addr,
        bind_explicit: a.bind.is_some(),
        port: a.port,
        save_dir: a.save_dir.clone(),
        threads: a.threads,
        ..pdw_explore::Config::local(Vec::new(), a.port)
    };
    let server = pdw_explore::start(cfg);
    let server = match server {
        Ok(s) => s,
        Err(e) => {
            drop(TEMP.lock().ok().and_then(|mut t| t.take()));
            return Err(crate::args::InputError(e).into());
        }
    };
    SERVING.store(true, Ordering::SeqCst);
    crate::outln!("explorer at {} (Ctrl-C stops it)", server.url);
    if a.open {
        open_browser(&server.url);
    }
    server.wait();
    drop(TEMP.lock().ok().and_then(|mut t| t.take()));
    Ok(ExitCode::SUCCESS)
}

/// The default basin (`pdw-sweep basin` with no option) computed into a private temporary
/// directory, kept in [`TEMP`] until the explorer stops (an interrupted or failed computation
/// removes it at once).
fn default_basin() -> anyhow::Result<Vec<PathBuf>> {
    let dir = PrivateDir::new("pdw-explore-").map_err(crate::args::InputError)?;
    let out = dir.path().join("basin.h5");
    let png = dir.path().join("basin.png");
    eprintln!(
        "no file given: computing the default basin first (into {}, removed on exit)",
        dir.path().display()
    );
    let args = ["pdw-sweep", "basin", "--quiet", "--out"];
    let mut argv: Vec<String> = args.iter().map(|s| s.to_string()).collect();
    argv.extend([
        out.display().to_string(),
        "--png".into(),
        png.display().to_string(),
    ]);
    let Command::Basin(b) = Cli::try_parse_from(&argv)?.command else {
        unreachable!("parsed as basin")
    };
    let code = super::basin::run(&b)?;
    if code != ExitCode::SUCCESS {
        anyhow::bail!("the default basin could not be computed");
    }
    *TEMP
        .lock()
        .map_err(|_| anyhow::anyhow!("the temporary directory's lock"))? = Some(dir);
    Ok(vec![out])
}

/// Opens `url` with xdg-open if there is one; else says where the page is.
fn open_browser(url: &str) {
    let opened = std::process::Command::new("xdg-open")
        .arg(url)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .is_ok();
    if !opened {
        eprintln!("no xdg-open here: open {url} in a browser");
    }
}
