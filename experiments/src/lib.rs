//! Shared helpers of the experiment binaries (`src/bin/<name>.rs`): output folders, timing,
//! CSV and Markdown tables; and [`seed5_pi`], the seed thesis' own constraint handling (PI
//! knee latch, compliant ground), a comparison model of the `economy` experiment.
//!
//! Every experiment writes into `experiments/results/<name>/`: PNG charts (drawn with
//! `pdw-store`'s plots), the data as CSV (or HDF5 where `pdw-store` has a schema), and a
//! `README.md` holding the numbers and the exact command that reproduced them.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub mod seed5_pi;

/// `experiments/results/<name>/`, created if missing.
pub fn results_dir(name: &str) -> anyhow::Result<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("results")
        .join(name);
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}

/// The command that reproduces experiment `name` (for its `README.md`).
pub fn command(name: &str) -> String {
    format!("cargo run --release -p pdw-experiments --bin {name}")
}

/// Runs `f` repeatedly until at least `min_total` seconds (and at least once) have passed;
/// returns the last result and the mean wall time per call (s).
pub fn time_mean<T>(min_total: f64, mut f: impl FnMut() -> T) -> (T, f64) {
    let t0 = Instant::now();
    let mut n = 0u32;
    loop {
        let r = f();
        n += 1;
        let el = t0.elapsed().as_secs_f64();
        if el >= min_total {
            return (r, el / f64::from(n));
        }
    }
}

/// Wall time of one call of `f` (s).
pub fn time_once<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t0 = Instant::now();
    let r = f();
    (r, t0.elapsed().as_secs_f64())
}

/// A Markdown table built row by row.
pub struct Table {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    /// Table with column titles `header`.
    pub fn new(header: &[&str]) -> Self {
        Self {
            header: header.iter().map(|s| s.to_string()).collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row (one cell per column).
    pub fn row(&mut self, cells: Vec<String>) {
        self.rows.push(cells);
    }

    /// The table as Markdown.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "| {} |", self.header.join(" | "));
        let _ = writeln!(
            s,
            "|{}",
            self.header.iter().map(|_| "---|").collect::<String>()
        );
        for r in &self.rows {
            let _ = writeln!(s, "| {} |", r.join(" | "));
        }
        s
    }

    /// The table as CSV (cells must not contain commas).
    pub fn csv(&self) -> String {
        let mut s = self.header.join(",");
        s.push('\n');
        for r in &self.rows {
            s.push_str(&r.join(","));
            s.push('\n');
        }
        s
    }
}

/// Writes `text` to `dir/file` and says so on stderr.
pub fn write_text(dir: &Path, file: &str, text: &str) -> anyhow::Result<()> {
    let p = dir.join(file);
    std::fs::write(&p, text)?;
    eprintln!("wrote {}", p.display());
    Ok(())
}

/// `x` in short scientific notation (`1.23e-9`); `—` for non-finite values.
pub fn sci(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.2e}")
    } else {
        "—".to_string()
    }
}

/// Least-squares line through `pts`: `(a, b)` of `y = a + b·x`.
pub fn fit_line(pts: &[(f64, f64)]) -> (f64, f64) {
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|&(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = pts.iter().map(|&(x, _)| (x - mx) * (x - mx)).sum();
    let b = sxy / sxx;
    (my - b * mx, b)
}

/// Largest absolute componentwise difference of two equally long vectors.
pub fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Largest distance between matched multipliers: each multiplier of `a` is matched to the
/// nearest unused one of `b` (sorting by modulus alone can swap the members of a conjugate pair
/// or two multipliers of nearly equal modulus). `∞` if the counts differ.
pub fn multiplier_error(a: &[pdw_limit::Multiplier], b: &[pdw_limit::Multiplier]) -> f64 {
    if a.len() != b.len() {
        return f64::INFINITY;
    }
    let mut used = vec![false; b.len()];
    let mut worst: f64 = 0.0;
    for x in a {
        let mut best = (f64::INFINITY, usize::MAX);
        for (j, y) in b.iter().enumerate() {
            let d = (x.re - y.re).hypot(x.im - y.im);
            if !used[j] && d < best.0 {
                best = (d, j);
            }
        }
        if best.1 == usize::MAX {
            return f64::INFINITY;
        }
        used[best.1] = true;
        worst = worst.max(best.0);
    }
    worst
}

/// Multipliers as `a±bi` text, e.g. `-0.19±0.55i, 0.46`.
pub fn fmt_multipliers(m: &[pdw_limit::Multiplier], digits: usize) -> String {
    m.iter()
        .filter(|l| l.im >= 0.0)
        .map(|l| {
            if l.im > 0.0 {
                format!("{:.*}±{:.*}i", digits, l.re, digits, l.im)
            } else {
                format!("{:.*}", digits, l.re)
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}
