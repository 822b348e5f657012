//! Input errors and the parsers of the compact value syntaxes the front ends accept
//! ([docs/cli.md](../../../docs/cli.md): slopes in rad, `3deg` or `3°`, `NAME=VALUE`, `NAME=A:B`,
//! `NXxNY`, `NAME=A:B:N`, `I/N`, `X1,X2,..`).
//!
//! Every parser returns a message that names the bad value and says what is allowed; the CLI
//! prints it and exits with code 2, Python raises it as a `ValueError`.

use std::fmt;

/// A user-input error: the message is printed as is, exit code 2.
#[derive(Debug, Clone, PartialEq)]
pub struct InputError(pub String);

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for InputError {}

fn err<T>(msg: String) -> Result<T, InputError> {
    Err(InputError(msg))
}

/// A finite float, with a message naming `what` on failure.
pub fn parse_f64(s: &str, what: &str) -> Result<f64, InputError> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => err(format!("{what}: '{s}' is not a finite number")),
        Err(_) => err(format!("{what}: '{s}' is not a number")),
    }
}

/// A slope in radians, or with an angle unit: `3deg`, `3°`, ` 3 deg`, `0.05rad` (the units of
/// spec files, [`pdw_walkers::units`]: degrees are converted as `v · π / 180`, so `3deg` is
/// 0.05235987755982988, the compass preset's 3°); must lie in (−π/2, π/2).
pub fn parse_slope(s: &str) -> Result<f64, InputError> {
    parse_slope_for(s, "--slope")
}

/// [`parse_slope`] with the messages naming `flag` (e.g. `--set slope`, `--sweep slope`).
pub fn parse_slope_for(s: &str, flag: &str) -> Result<f64, InputError> {
    const FORMS: &str = "give radians (0.05, 0.05rad) or degrees (3deg, 3°)";
    let (number, unit) = pdw_walkers::units::split_quantity(s);
    let v = match number.parse::<f64>() {
        Ok(v) if v.is_finite() => v,
        _ => return err(format!("{flag}: '{s}' is not a number; {FORMS}")),
    };
    let v = if unit.is_empty() {
        v
    } else {
        use pdw_walkers::units::{convert, Dimension, UnitSystem};
        match convert(v, unit, flag, Dimension::ANGLE, UnitSystem::Si) {
            Ok(rad) => rad,
            Err(why) => {
                return err(format!(
                    "{flag}: '{s}' has the unit `{unit}`, not an angle ({why}); {FORMS}"
                ))
            }
        }
    };
    if v.abs() >= std::f64::consts::FRAC_PI_2 {
        return err(format!(
            "{flag}: '{s}' is outside (-pi/2, pi/2) rad; {FORMS}"
        ));
    }
    Ok(v)
}

/// `NAME=VALUE` (for `--set`), the value a plain number or a slope in any angle unit.
pub fn parse_assignment(s: &str) -> Result<(String, f64), InputError> {
    let (name, v, unit) = parse_assignment_with_unit(s)?;
    match unit {
        None => Ok((name, v)),
        Some(u) => err(format!(
            "--set {name}: '{s}' has a unit (`{u}`), which only the model can convert"
        )),
    }
}

/// `NAME=VALUE[unit]` (for `--set`): the name, the number and its unit when one is written
/// (`hip_mass=5kg`, `a=50 cm`). A slope is converted and checked here ([`parse_slope_for`]);
/// any other unit is converted by the model, which knows its parameter's quantity
/// ([`pdw_walkers::ModelInfo::value_in_unit`]).
pub fn parse_assignment_with_unit(s: &str) -> Result<(String, f64, Option<String>), InputError> {
    let Some((name, value)) = s.split_once('=') else {
        return err(format!("--set: '{s}' is not of the form NAME=VALUE"));
    };
    let name = name.trim();
    if name.is_empty() {
        return err(format!("--set: '{s}' has an empty parameter name"));
    }
    if name == "slope" {
        return Ok((
            name.to_string(),
            parse_slope_for(value, "--set slope")?,
            None,
        ));
    }
    let (number, unit) = pdw_walkers::units::split_quantity(value);
    if unit.is_empty() {
        return Ok((
            name.to_string(),
            parse_f64(value, &format!("--set {name}"))?,
            None,
        ));
    }
    let v = parse_f64(number, &format!("--set {name}"))?;
    Ok((name.to_string(), v, Some(unit.to_string())))
}

/// An inclusive coordinate range `NAME=A:B` with A < B (for `--x`, `--y`).
#[derive(Debug, Clone, PartialEq)]
pub struct AxisRange {
    pub name: String,
    pub lo: f64,
    pub hi: f64,
}

pub fn parse_axis(s: &str, flag: &str) -> Result<AxisRange, InputError> {
    let Some((name, range)) = s.split_once('=') else {
        return err(format!(
            "{flag}: '{s}' is not of the form NAME=A:B (e.g. theta=0.15:0.25)"
        ));
    };
    let Some((a, b)) = range.split_once(':') else {
        return err(format!("{flag}: range '{range}' is not of the form A:B"));
    };
    let lo = parse_f64(a, flag)?;
    let hi = parse_f64(b, flag)?;
    if lo >= hi {
        return err(format!(
            "{flag}: range {lo}:{hi} is empty or inverted; the first bound must be below the second"
        ));
    }
    if !(hi - lo).is_finite() {
        return err(format!(
            "{flag}: range '{range}' is too wide to divide into grid points (its width \
             overflows a double); keep |B - A| below about 1e308"
        ));
    }
    Ok(AxisRange {
        name: name.trim().to_string(),
        lo,
        hi,
    })
}

/// A grid size `NXxNY` given to `flag`, each at least 1 and the product at most 10⁹.
pub fn parse_grid_for(flag: &str, s: &str) -> Result<(usize, usize), InputError> {
    let lower = s.trim().to_ascii_lowercase();
    let Some((a, b)) = lower.split_once('x') else {
        return err(format!(
            "{flag}: '{s}' is not of the form NXxNY (e.g. 401x401)"
        ));
    };
    let parse = |t: &str| -> Result<usize, InputError> {
        match t.parse::<usize>() {
            Ok(n) if n >= 1 => Ok(n),
            _ => err(format!("{flag}: '{t}' in '{s}' is not a positive integer")),
        }
    };
    let (nx, ny) = (parse(a)?, parse(b)?);
    if nx.saturating_mul(ny) > 1_000_000_000 {
        return err(format!("{flag}: {nx}x{ny} has more than 10^9 cells"));
    }
    Ok((nx, ny))
}

/// A grid of two or three dimensions, `NXxNY` or `NXxNYxNZ` of the option `flag`: each a
/// positive integer, at most 10⁹ cells in all.
pub fn parse_grid_dims(flag: &str, s: &str) -> Result<Vec<usize>, InputError> {
    let lower = s.trim().to_ascii_lowercase();
    let parts: Vec<&str> = lower.split('x').collect();
    if !(2..=3).contains(&parts.len()) {
        return err(format!(
            "{flag}: '{s}' is not of the form NXxNY or NXxNYxNZ (e.g. 401x401, 41x41x21)"
        ));
    }
    let dims = parts
        .iter()
        .map(|t| match t.parse::<usize>() {
            Ok(n) if n >= 1 => Ok(n),
            _ => err(format!("{flag}: '{t}' in '{s}' is not a positive integer")),
        })
        .collect::<Result<Vec<usize>, InputError>>()?;
    let cells = dims.iter().fold(1usize, |a, &n| a.saturating_mul(n));
    if cells > 1_000_000_000 {
        return err(format!("{flag}: {s} has more than 10^9 cells"));
    }
    Ok(dims)
}

/// [`parse_grid_for`] of `--grid`.
pub fn parse_grid(s: &str) -> Result<(usize, usize), InputError> {
    parse_grid_for("--grid", s)
}

/// Most points of a `--sweep` (each is a continuation step and an orbit-diagram column of
/// 364 strides; 10⁵ points take about an hour).
pub const MAX_SWEEP_POINTS: usize = 100_000;

/// A parameter sweep `NAME=A:B:N` (2 ≤ N ≤ [`MAX_SWEEP_POINTS`] points, inclusive).
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    pub name: String,
    pub lo: f64,
    pub hi: f64,
    pub n: usize,
}

/// `NAME=A:B:N` of the option `opt` (e.g. `--sweep`, `--over`); see [`parse_sweep`].
pub fn parse_range_count(s: &str, opt: &str) -> Result<Sweep, InputError> {
    let Some((name, rest)) = s.split_once('=') else {
        return err(format!(
            "{opt}: '{s}' is not of the form NAME=A:B:N (e.g. slope=0.001:0.019:400)"
        ));
    };
    let parts: Vec<&str> = rest.split(':').collect();
    if parts.len() != 3 {
        return err(format!("{opt}: '{rest}' is not of the form A:B:N"));
    }
    let name = name.trim().to_string();
    let flag = format!("{opt} {name}");
    let conv = |t: &str| {
        if name == "slope" {
            parse_slope_for(t, &flag)
        } else {
            parse_f64(t, &flag)
        }
    };
    let lo = conv(parts[0])?;
    let hi = conv(parts[1])?;
    let n = match parts[2].trim().parse::<usize>() {
        Ok(n) if (2..=MAX_SWEEP_POINTS).contains(&n) => n,
        _ => {
            return err(format!(
                "{opt}: point count '{}' must be an integer from 2 to {MAX_SWEEP_POINTS}",
                parts[2]
            ))
        }
    };
    if lo == hi {
        return err(format!("{opt}: range {lo}:{hi} is empty"));
    }
    if !(hi - lo).is_finite() {
        return err(format!(
            "{opt}: range '{rest}' is too wide (its width overflows a double)"
        ));
    }
    Ok(Sweep { name, lo, hi, n })
}

/// `--sweep NAME=A:B:N`: N evenly spaced values from A to B inclusive.
pub fn parse_sweep(s: &str) -> Result<Sweep, InputError> {
    parse_range_count(s, "--sweep")
}

/// A shard `I/N` with 0 ≤ I < N.
pub fn parse_shard(s: &str) -> Result<(usize, usize), InputError> {
    let Some((a, b)) = s.split_once('/') else {
        return err(format!("--shard: '{s}' is not of the form I/N (e.g. 0/4)"));
    };
    let (i, n) = match (a.trim().parse::<usize>(), b.trim().parse::<usize>()) {
        (Ok(i), Ok(n)) => (i, n),
        _ => {
            return err(format!(
                "--shard: '{s}' needs two non-negative integers I/N"
            ))
        }
    };
    if n == 0 || i >= n {
        return err(format!("--shard: '{s}' needs 0 <= I < N"));
    }
    Ok((i, n))
}

/// A comma-separated initial guess `X1,X2,..`.
pub fn parse_guess(s: &str) -> Result<Vec<f64>, InputError> {
    s.split(',').map(|t| parse_f64(t, "--guess")).collect()
}

/// The most worker threads a run accepts.
pub const MAX_THREADS: usize = 1024;

/// A worker-thread count, checked: 1 to [`MAX_THREADS`]; the message names `what` (`--threads`,
/// `threads`).
pub fn check_threads(n: usize, what: &str) -> Result<usize, InputError> {
    if (1..=MAX_THREADS).contains(&n) {
        Ok(n)
    } else {
        err(format!("{what}: {n} must be between 1 and {MAX_THREADS}"))
    }
}

/// `--threads N` as clap's value parser: a whole number from 1 to [`MAX_THREADS`].
pub fn parse_threads(s: &str) -> Result<usize, InputError> {
    let n: usize = s.trim().parse().map_err(|_| {
        InputError(format!(
            "'{s}' is not a whole number of threads (1 to {MAX_THREADS})"
        ))
    })?;
    if (1..=MAX_THREADS).contains(&n) {
        Ok(n)
    } else {
        err(format!("{n} must be between 1 and {MAX_THREADS}"))
    }
}

/// The deepest period of a sweep's period-doubling cascade: a power of two from 1 to 64
/// ([`pdw_limit::sweep::MAX_CASCADE_PERIOD`]); messages name `what` (e.g. `--max-period`).
pub fn check_max_period(p: usize, what: &str) -> Result<usize, InputError> {
    let most = pdw_limit::sweep::MAX_CASCADE_PERIOD;
    if p.is_power_of_two() && p <= most {
        Ok(p)
    } else {
        err(format!(
            "{what}: {p} is not a power of two from 1 to {most} (1, 2, 4, 8, 16, 32 or 64)"
        ))
    }
}

/// The value a sweep starts at, inside its range `sw` (either end included); messages name
/// `what` (e.g. `--from`).
pub fn check_from(mu: f64, sw: &Sweep, what: &str) -> Result<f64, InputError> {
    let (a, b) = (sw.lo.min(sw.hi), sw.lo.max(sw.hi));
    if mu.is_finite() && a <= mu && mu <= b {
        Ok(mu)
    } else {
        err(format!(
            "{what}: {mu} is outside the swept range {}:{} of '{}'",
            sw.lo, sw.hi, sw.name
        ))
    }
}
