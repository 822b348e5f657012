//! Every command as a plan, a run and a report — the shape each front end adapts.
//!
//! - **Input**: the command's typed inputs, as the user gave them (a model choice, option values,
//!   the words a value was typed in). A front end fills it from its own syntax and nothing else.
//! - **Plan** (`plan(&Input, Spelling)`): no I/O but reading the model's spec file. It validates
//!   every input, naming the option as the front end spells it ([`Spelling`]), builds the model,
//!   gives dimensions to units, checks the integrator against the model
//!   ([`crate::integrator::check_integrator`]), lists the files the run writes and states what it
//!   will cost ([`Preview`]).
//! - **Run** (`Plan::run(&dyn Sink)`): interruptible (the process-wide request of
//!   [`pdw_hybrid::interrupt`]), reports progress and warnings through one [`Sink`], and returns
//!   the report value.
//! - **Report**: one serialisable type per command ([`Report`]). The CLI prints its
//!   [`Report::text`] or, with `--json`, its [`Report::json`]; Python returns the same JSON
//!   object as a dict ([`Report::json`] converted), so the fields have the same names in every
//!   front end.

use serde::Serialize;
use std::path::PathBuf;

/// How a front end names an option in its messages: `--max-strides` on the command line,
/// `max_strides` in Python. Options are named once, in snake case, and spelled by this.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Spelling {
    /// `--kebab-case`.
    Cli,
    /// `snake_case`, a keyword argument.
    Python,
}

impl Spelling {
    /// The option `name` (snake case) as this front end spells it.
    pub fn flag(self, name: &str) -> String {
        match self {
            Spelling::Cli => format!("--{}", name.replace('_', "-")),
            Spelling::Python => name.to_string(),
        }
    }
}

/// What a plan states before anything is computed: the files the run writes (derived pictures
/// included), the warnings its inputs call for and the peak memory it expects.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Preview {
    /// Every file the run writes.
    pub outputs: Vec<PathBuf>,
    /// Warnings about the inputs (an integrator too coarse for the stride, …).
    pub warnings: Vec<String>,
    /// The run's estimated peak memory in bytes, the figure its plan checked against the
    /// memory available ([`crate::memory::check_memory`]); `None` where the run's memory does
    /// not grow with its inputs beyond a few MiB.
    pub memory_bytes: Option<u64>,
}

/// Where a run reports its progress and its warnings. Every method has a silent default.
pub trait Sink: Sync {
    /// A phase of `total` units of work (strides, walkers, designs) starts, `done` of them
    /// done already (a continued run).
    fn phase(&self, _what: &str, _total: u64, _done: u64) {}
    /// `n` more units of the current phase are done.
    fn advance(&self, _n: u64) {}
    /// The phase's status in a few words ("best cost 0.41").
    fn status(&self, _text: &str) {}
    /// A line for the user about the run ("continuing design.h5: 12 designs stored").
    fn say(&self, _text: &str) {}
    /// A warning, told as soon as it is known (it is also in the report).
    fn warn(&self, _text: &str) {}
    /// The current phase is over.
    fn finish(&self) {}
}

/// The sink that shows nothing (tests, quiet runs, Python).
pub struct Silent;

impl Sink for Silent {}

/// A command's result: printed by the CLI, returned by Python, written by neither by hand.
pub trait Report: Serialize {
    /// The lines the CLI prints (each ends in a newline).
    fn text(&self) -> String;

    /// The report as one JSON object: the CLI's `--json` and Python's dict.
    fn json(&self) -> serde_json::Value {
        // The reports hold numbers, strings, options and vectors under string keys: serde_json
        // cannot fail on them (a non-finite number becomes null).
        serde_json::to_value(self).unwrap_or_else(|e| serde_json::json!({ "error": e.to_string() }))
    }
}

/// Why a plan or a run stopped: a bad input (the CLI's exit 2 with the message), or the
/// engine's own error (an interrupt, an integrator failure).
#[derive(Debug)]
pub enum CommandError {
    Input(crate::InputError),
    Limit(pdw_limit::LimitError),
}

impl std::fmt::Display for CommandError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CommandError::Input(e) => e.fmt(f),
            CommandError::Limit(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for CommandError {}

impl From<crate::InputError> for CommandError {
    fn from(e: crate::InputError) -> Self {
        CommandError::Input(e)
    }
}

impl From<pdw_limit::LimitError> for CommandError {
    fn from(e: pdw_limit::LimitError) -> Self {
        CommandError::Limit(e)
    }
}
