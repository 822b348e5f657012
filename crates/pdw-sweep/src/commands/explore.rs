//! `pdw-sweep explore`: the local basin explorer ([`pdw_explore`], docs/explore.md). With no
//! file it first computes the default basin of `pdw-sweep basin` into a temporary folder.

use crate::cli::{Cli, Command, ExploreArgs};
use clap::Parser;
use std::net::{IpAddr, Ipv4Addr};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};

/// Set once the server listens: Ctrl-C then ends the process (before, it stops the default
/// basin's computation as in `basin`).
static SERVING: AtomicBool = AtomicBool::new(false);

pub fn run(a: &ExploreArgs) -> anyhow::Result<ExitCode> {
    let _ = ctrlc::set_handler(|| {
        if SERVING.load(Ordering::SeqCst) {
            std::process::exit(0);
        }
        pdw_hybrid::interrupt::request();
    });
    let addr = a.bind.unwrap_or(IpAddr::V4(Ipv4Addr::LOCALHOST));
    if !addr.is_loopback() {
        eprintln!(
            "warning: listening on {addr}: anyone who can reach this address can use the \
             explorer (it computes on request and writes into --save-dir)"
        );
    }
    let (files, _tmp) = if a.files.is_empty() {
        default_basin()?
    } else {
        (a.files.clone(), None)
    };
    let cfg = pdw_explore::Config {
        files,
        addr,
        bind_explicit: a.bind.is_some(),
        port: a.port,
        save_dir: a.save_dir.clone(),
        threads: a.threads,
    };
    let server = pdw_explore::start(cfg).map_err(crate::args::InputError)?;
    SERVING.store(true, Ordering::SeqCst);
    crate::outln!("explorer at {} (Ctrl-C stops it)", server.url);
    if a.open {
        open_browser(&server.url);
    }
    server.wait();
    Ok(ExitCode::SUCCESS)
}

/// The default basin (`pdw-sweep basin` with no option) computed into a temporary folder,
/// removed when the explorer stops.
fn default_basin() -> anyhow::Result<(Vec<PathBuf>, Option<TempDir>)> {
    let dir = TempDir::new()?;
    let out = dir.0.join("basin.h5");
    let png = dir.0.join("basin.png");
    eprintln!("no file given: computing the default basin first");
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
    Ok((vec![out], Some(dir)))
}

/// A folder removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new() -> std::io::Result<TempDir> {
        let d = std::env::temp_dir().join(format!("pdw-explore-{}", std::process::id()));
        std::fs::create_dir_all(&d)?;
        Ok(TempDir(d))
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
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
