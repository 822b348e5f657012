//! The command line's [`Sink`]: a progress bar on stderr (hidden with `--quiet` or when stderr
//! is not a terminal), the run's lines above it, warnings as `warning: …` on stderr.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use pdw::pipeline::Sink;
use std::io::IsTerminal;
use std::sync::Mutex;

/// A progress bar per phase.
pub struct Bar {
    quiet: bool,
    bar: Mutex<Option<ProgressBar>>,
}

impl Bar {
    /// A sink that draws unless `quiet` (or stderr is not a terminal).
    pub fn new(quiet: bool) -> Self {
        Bar {
            quiet: quiet || !std::io::stderr().is_terminal(),
            bar: Mutex::new(None),
        }
    }

    fn with(&self, f: impl FnOnce(&ProgressBar)) {
        if let Ok(b) = self.bar.lock() {
            if let Some(pb) = b.as_ref() {
                f(pb);
            }
        }
    }
}

impl Sink for Bar {
    fn phase(&self, what: &str, total: u64, done: u64) {
        let pb = if self.quiet {
            ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden())
        } else {
            ProgressBar::new(total)
        };
        pb.set_style(
            ProgressStyle::with_template(&format!(
                "{{bar:40}} {{pos}}/{{len}} {what}  {{msg}}  eta {{eta}}"
            ))
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        pb.set_position(done.min(total));
        if let Ok(mut b) = self.bar.lock() {
            *b = Some(pb);
        }
    }

    fn advance(&self, n: u64) {
        self.with(|pb| pb.inc(n));
    }

    fn status(&self, text: &str) {
        self.with(|pb| pb.set_message(text.to_string()));
    }

    fn say(&self, text: &str) {
        let mut shown = false;
        self.with(|pb| {
            pb.println(text);
            shown = true;
        });
        if !shown {
            eprintln!("{text}");
        }
    }

    fn warn(&self, text: &str) {
        self.say(&format!("warning: {text}"));
    }

    fn finish(&self) {
        if let Ok(mut b) = self.bar.lock() {
            if let Some(pb) = b.take() {
                pb.finish_and_clear();
            }
        }
    }
}
