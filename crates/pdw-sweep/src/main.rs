//! `pdw-sweep`: the command-line front end. Thin by design: parse, call the libraries, report.
//! Every user error prints a message naming the bad value and exits with code 2.

mod args;
mod cli;
mod commands;

/// Writes `text` to stdout; a closed pipe (`| head`) ends the output quietly instead of panicking.
pub fn out(text: &str) {
    use std::io::Write;
    let mut o = std::io::stdout().lock();
    if o.write_all(text.as_bytes())
        .and_then(|_| o.flush())
        .is_err()
    {
        std::process::exit(0);
    }
}

/// `println!` through [`out`].
#[macro_export]
macro_rules! outln {
    () => { $crate::out("\n") };
    ($($t:tt)*) => { $crate::out(&format!("{}\n", format_args!($($t)*))) };
}

/// The error and its causes, each told once: a cause whose text the message already holds
/// (HDF5's and the operating system's errors are embedded by the store's messages) is not
/// repeated.
fn message(e: &anyhow::Error) -> String {
    let mut msg = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !msg.contains(&c) {
            msg.push_str(": ");
            msg.push_str(&c);
        }
    }
    msg
}

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    // A file-size limit (`ulimit -f`) makes the kernel send SIGXFSZ on the write that would
    // pass it, which kills the process without a word and with its file half written. Ignored,
    // that write fails with EFBIG instead: the writer reports it (exit 2) and leaves the file as
    // of its last flush, resumable, as after a full disk.
    // SAFETY: signal(2) with a valid signal number and SIG_IGN, before any thread is started.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
    let cli = cli::Cli::parse();
    match commands::run(cli) {
        Ok(code) => code,
        Err(e) => {
            if let Some(input) = e.downcast_ref::<args::InputError>() {
                eprintln!("error: {input}");
            } else {
                eprintln!("error: {}", message(&e));
            }
            ExitCode::from(2)
        }
    }
}
