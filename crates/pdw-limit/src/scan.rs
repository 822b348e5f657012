//! Every gait in a box of the section, found without a guess: a low-discrepancy sample of
//! starting states (Halton), and from each start
//!
//! 1. Newton on `P(s) − s` ([`find_fixed_point`]): the period-one gaits, stable and unstable,
//!    whose Newton basin holds a start;
//! 2. the stride map iterated [`ScanOptions::iterates`] strides: a start that falls is counted as
//!    a fall, by how its last stride ended ([`Scan::fell_by`]: the stride-end reasons of
//!    [`crate::StrideOutcome`], e.g. `stance knee buckled`; [`Scan::fates`] names every start's
//!    fate, so that a scan that finds nothing says why); one that settles — its last iterates repeat with a period `K ≤`
//!    [`ScanOptions::max_period`] to within [`SETTLED`] — is refined by Newton on `P^K − id`
//!    ([`find_periodic_orbit`]) to the attractor it reached (a stable gait for `K = 1`, a
//!    period-K orbit otherwise); one that does neither within the budget is "unsettled"
//!    (chaos, or a slow approach).
//!
//! Attractors with thin basins (the simplest walker's are famously thin) are often born where a
//! period-one gait lost its stability (a period doubling leaves the period-2 orbit next to the
//! now unstable gait). So each period-one gait with a real multiplier outside the unit circle
//! also seeds two starts, `s* ± 10⁻³ v` along that multiplier's eigenvector, iterated like the
//! others and reported apart ("near a gait").
//!
//! The fixed points are merged as [`crate::gaits::search`] merges them (relative 1e-8 in every
//! section coordinate), the orbits as cycles ([`same_orbit`]); each is reported with how many
//! starts reached it by Newton and by iteration. Starts run in parallel on the caller's pool;
//! each start's computation is serial and the merge follows the starts' order, so the result
//! is the same on any number of threads.
//!
//! What a scan cannot promise: a gait whose Newton basin misses every start, or an attractor
//! reached by no start, is not found — more starts (or a smaller box) find smaller basins; the
//! report says how many starts it used. Nor does it bound a start's cost: Newton from a start
//! where the stride map is far from any gait can spend its iterations on long variational
//! strides (measured: the compass gait's default box on a level floor, 256 starts, 40 s on one
//! core, of which one start took 30 s — 18 Newton iterations ending in a failed line search).
//! [`ScanOptions::newton_max_iters`] caps the iterations per start; a sweep that scans for its
//! start gait uses 12, which finds what the default 40 finds on every model the scan tests use.

use crate::continuation::real_eigenvector;
use crate::error::LimitError;
use crate::gaits::{default_integrator, rotate_to_canonical};
use crate::newton::{find_fixed_point, FixedPoint, NewtonOptions};
use crate::periodic::{find_periodic_orbit, same_orbit, PeriodicOrbit};
use crate::stride::{StrideMap, StrideOutcome};
use pdw_hybrid::{Integrator, Options};
use pdw_model::Walker;
use rayon::prelude::*;

/// Largest relative distance `|x_N − x_{N−K}| / (1 + |x_N|)` (every coordinate) at which the
/// iterates count as settled on a period-K cycle: well above the integrator's error, well below
/// the distances between the orbits of a period-doubling cascade that Newton then separates.
pub const SETTLED: f64 = 1e-6;

/// Shortest step (model length units; legs are O(1)) of a gait a scan reports. Newton's own
/// bound ([`crate::newton::MIN_STEP_LENGTH`], 10⁻⁶) is for a search that starts at a gait's
/// guess; a scan's starts also reach the numerically neutral "gaits" of a few micro-radians on
/// a level floor, where an impact loses a fraction ~θ⁴ of the energy — below the stride map's
/// 10⁻¹⁴ error for θ under ~10⁻³·⁵ — so a scan asks for steps of at least 10⁻³ of a leg.
pub const SCAN_MIN_STEP_LENGTH: f64 = 1e-3;

/// Longest cycle a scan recognises in the iterates by default ([`ScanOptions::max_period`]).
pub const MAX_PERIOD: usize = 8;

/// The primes whose radical inverses give the Halton coordinates (one per section coordinate).
const HALTON_BASES: [u64; 12] = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37];

/// A box of section states: `lo[j] < hi[j]` for every coordinate.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanBox {
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
}

/// Options of a scan.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanOptions {
    /// Starting states (the first `starts` points of the Halton sequence, skipping its origin).
    pub starts: usize,
    /// Newton's residual tolerance (the fixed points and orbits are found to it).
    pub tol: f64,
    /// Strides each start is iterated to see where it settles.
    pub iterates: usize,
    /// Longest cycle recognised in the iterates.
    pub max_period: usize,
    /// The stride map's integrator (default: [`default_integrator`] of `tol`).
    pub integrator: Options,
    /// Newton iterations per start (default: [`NewtonOptions::default`]'s 40). A lower cap
    /// bounds what a start far from every gait can cost (see the module docs) and may lose a
    /// gait whose Newton path from every start is long.
    pub newton_max_iters: u64,
}

impl ScanOptions {
    /// `starts` starts, residual tolerance `tol`, 200 iterates, cycles up to [`MAX_PERIOD`],
    /// Newton's default iteration budget.
    pub fn new(starts: usize, tol: f64) -> Self {
        Self {
            starts,
            tol,
            iterates: 200,
            max_period: MAX_PERIOD,
            integrator: default_integrator(tol),
            newton_max_iters: NewtonOptions::default().max_iters,
        }
    }
}

/// A period-one gait the scan found.
pub struct ScanGait {
    pub fp: FixedPoint,
    /// Starts from which Newton converged to it.
    pub newton_starts: usize,
    /// Starts whose iterates settled on it (zero for an unstable gait).
    pub attracted_starts: usize,
    /// Starts seeded next to the unstable gaits whose iterates settled on it.
    pub near_gaits: usize,
}

/// A period-K orbit (`K ≥ 2`) the iterates settled on.
pub struct ScanOrbit {
    pub orbit: PeriodicOrbit,
    /// Starts whose iterates settled on it.
    pub attracted_starts: usize,
    /// Starts seeded next to the unstable gaits whose iterates settled on it.
    pub near_gaits: usize,
}

/// What a scan found, and what became of the starts that found nothing.
pub struct Scan {
    /// The box scanned and the number of starts.
    pub scan_box: ScanBox,
    pub starts: usize,
    /// Period-one gaits, in the order of the first start that found each.
    pub gaits: Vec<ScanGait>,
    /// Period-K orbits, `K ≥ 2`, in the same order.
    pub orbits: Vec<ScanOrbit>,
    /// Starts whose iterates fell.
    pub fell: usize,
    /// The starts that fell by how their last stride ended (the words of
    /// [`crate::StrideOutcome`], e.g. `stance knee buckled`, `fell forward`), most first.
    pub fell_by: Vec<(String, usize)>,
    /// Starts whose iterates neither fell nor settled within the budget.
    pub unsettled: usize,
    /// Starts seeded next to the unstable gaits (two per gait with a real multiplier outside
    /// the unit circle).
    pub near_gait_starts: usize,
}

/// A start's fate where the stride map itself failed (not a stride's end).
pub const STRIDE_MAP_FAILED: &str = "the stride map failed";

/// Fate of the starts that neither fell nor settled, in [`Scan::fates`].
pub const UNSETTLED: &str = "neither fell nor settled";

/// Fate of the starts that settled on a gait or an orbit, in [`Scan::fates`].
pub const SETTLED_FATE: &str = "settled on a gait or orbit";

impl Scan {
    /// What became of the (non-seeded) starts, by fate, most first: the falls by how their
    /// stride ended ([`Scan::fell_by`]), [`UNSETTLED`], [`SETTLED_FATE`]; the counts add up to
    /// [`Scan::starts`].
    pub fn fates(&self) -> Vec<(String, usize)> {
        let mut v = self.fell_by.clone();
        let settled = self.starts - self.fell - self.unsettled;
        for (what, n) in [(UNSETTLED, self.unsettled), (SETTLED_FATE, settled)] {
            if n > 0 {
                v.push((what.to_string(), n));
            }
        }
        by_count(v)
    }
}

/// `fates` sorted by count, largest first, equal counts by name (a stable order for reports
/// and files).
pub fn by_count(mut fates: Vec<(String, usize)>) -> Vec<(String, usize)> {
    fates.sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
    fates
}

/// `N starts: n₁ fate₁, n₂ fate₂, …` (e.g. `256 starts: 201 stance knee buckled, 40 fell
/// forward, 15 neither fell nor settled`).
pub fn fates_text(starts: usize, fates: &[(String, usize)]) -> String {
    let parts: Vec<String> = fates.iter().map(|(f, n)| format!("{n} {f}")).collect();
    format!("{starts} starts: {}", parts.join(", "))
}

/// Offset of the starts seeded next to an unstable gait, along its unstable eigenvector.
pub const NEAR_GAIT_OFFSET: f64 = 1e-3;

/// Where the iterates of one start went.
enum Fate {
    /// The stride that ended otherwise than at the section, in words.
    Fell(String),
    Unsettled,
    Gait(FixedPoint),
    Orbit(PeriodicOrbit),
}

/// The `i`-th point (`i ≥ 1`) of the Halton sequence in `dim` coordinates, in the unit cube:
/// coordinate `j` is the radical inverse of `i` in the `j`-th prime base (Halton 1960).
pub fn halton(i: u64, dim: usize) -> Vec<f64> {
    HALTON_BASES[..dim]
        .iter()
        .map(|&b| {
            let (mut n, mut f, mut r) = (i, 1.0, 0.0);
            while n > 0 {
                f /= b as f64;
                r += f * (n % b) as f64;
                n /= b;
            }
            r
        })
        .collect()
}

/// The first `n` Halton points (indices 1 to n) mapped into `b`.
pub fn starts_in(b: &ScanBox, n: usize) -> Vec<Vec<f64>> {
    (1..=n as u64)
        .map(|i| {
            halton(i, b.lo.len())
                .iter()
                .zip(b.lo.iter().zip(&b.hi))
                .map(|(u, (lo, hi))| lo + u * (hi - lo))
                .collect()
        })
        .collect()
}

/// Checks the box against the model's section and the options.
fn check(w: &dyn Walker, b: &ScanBox, opts: &ScanOptions) -> Result<(), LimitError> {
    let ds = w.section_dim();
    if b.lo.len() != ds || b.hi.len() != ds {
        return Err(LimitError::SectionDim {
            expected: ds,
            got: if b.lo.len() != ds {
                b.lo.len()
            } else {
                b.hi.len()
            },
        });
    }
    if ds > HALTON_BASES.len() {
        return Err(LimitError::InvalidOption {
            name: "scan box",
            value: ds as f64,
            allowed: "a scan samples at most 12 section coordinates",
        });
    }
    if !b
        .lo
        .iter()
        .zip(&b.hi)
        .all(|(lo, hi)| lo.is_finite() && hi.is_finite() && lo < hi)
    {
        return Err(LimitError::InvalidOption {
            name: "scan box",
            value: f64::NAN,
            allowed:
                "every coordinate's range must be finite with its low bound below its high one",
        });
    }
    let checks = [
        (
            "starts",
            opts.starts as f64,
            opts.starts >= 1,
            "at least 1 start",
        ),
        (
            "max_period",
            opts.max_period as f64,
            (1..=64).contains(&opts.max_period),
            "a period from 1 to 64 strides",
        ),
        (
            "newton_max_iters",
            opts.newton_max_iters as f64,
            opts.newton_max_iters >= 1,
            "at least 1 Newton iteration",
        ),
        (
            "iterates",
            opts.iterates as f64,
            opts.iterates > opts.max_period,
            "more iterates than the longest period recognised",
        ),
    ];
    for (name, value, ok, allowed) in checks {
        if !ok {
            return Err(LimitError::InvalidOption {
                name,
                value,
                allowed,
            });
        }
    }
    Ok(())
}

/// Scans the box `b` of `w`'s section (see the module docs) on `pool`.
pub fn scan(
    w: &dyn Walker,
    b: &ScanBox,
    opts: &ScanOptions,
    pool: &rayon::ThreadPool,
) -> Result<Scan, LimitError> {
    check(w, b, opts)?;
    opts.integrator.validate()?;
    let starts = starts_in(b, opts.starts);
    let newton = NewtonOptions {
        tol: opts.tol,
        min_step_length: SCAN_MIN_STEP_LENGTH,
        max_iters: opts.newton_max_iters,
        ..NewtonOptions::default()
    };
    let per_start: Vec<Result<(Option<FixedPoint>, Fate), LimitError>> = pool.install(|| {
        starts
            .par_iter()
            .map(|s| one_start(w, s, opts, &newton))
            .collect()
    });
    let mut out = Scan {
        scan_box: b.clone(),
        starts: starts.len(),
        gaits: Vec::new(),
        orbits: Vec::new(),
        fell: 0,
        fell_by: Vec::new(),
        unsettled: 0,
        near_gait_starts: 0,
    };
    let mut fell_by: Vec<(String, usize)> = Vec::new();
    for r in per_start {
        let (fp, fate) = r?;
        if let Some(fp) = fp {
            gait_entry(&mut out.gaits, fp).newton_starts += 1;
        }
        match fate {
            Fate::Fell(why) => {
                out.fell += 1;
                match fell_by.iter_mut().find(|f| f.0 == why) {
                    Some(f) => f.1 += 1,
                    None => fell_by.push((why, 1)),
                }
            }
            Fate::Unsettled => out.unsettled += 1,
            settled => settle_into(&mut out, settled, false),
        }
    }
    out.fell_by = by_count(fell_by);
    let seeds = near_gait_starts(&out.gaits);
    out.near_gait_starts = seeds.len();
    let fates: Vec<Result<Fate, LimitError>> = pool.install(|| {
        seeds
            .par_iter()
            .map(|s| {
                let step = |x: &[f64]| w.step_length(x);
                let map = StrideMap::new(w, opts.integrator)?.with_step_length(&step);
                settle(&map, s, opts, &newton)
            })
            .collect()
    });
    for f in fates {
        settle_into(&mut out, f?, true);
    }
    Ok(out)
}

/// Counts a start that settled (`near`: one seeded next to a gait) on its gait or orbit.
fn settle_into(out: &mut Scan, fate: Fate, near: bool) {
    let (attracted, near_gaits) = match fate {
        Fate::Fell(_) | Fate::Unsettled => return,
        Fate::Gait(fp) => {
            let g = gait_entry(&mut out.gaits, fp);
            (&mut g.attracted_starts, &mut g.near_gaits)
        }
        Fate::Orbit(orbit) => {
            let i = match out
                .orbits
                .iter()
                .position(|o| same_orbit(&o.orbit.orbit, &orbit.orbit))
            {
                Some(i) => i,
                None => {
                    out.orbits.push(ScanOrbit {
                        orbit,
                        attracted_starts: 0,
                        near_gaits: 0,
                    });
                    out.orbits.len() - 1
                }
            };
            let o = &mut out.orbits[i];
            (&mut o.attracted_starts, &mut o.near_gaits)
        }
    };
    if near {
        *near_gaits += 1;
    } else {
        *attracted += 1;
    }
}

/// Two starts `s* ± NEAR_GAIT_OFFSET · v` for every gait with a real multiplier outside the
/// unit circle (`v` its unit eigenvector; the multiplier of largest modulus among them).
fn near_gait_starts(gaits: &[ScanGait]) -> Vec<Vec<f64>> {
    let mut seeds = Vec::new();
    for g in gaits {
        let fp = &g.fp;
        let n = fp.section.len();
        let Some(l) = fp
            .multipliers
            .iter()
            .filter(|m| m.im == 0.0 && m.re.abs() > 1.0)
            .max_by(|a, b| a.re.abs().total_cmp(&b.re.abs()))
        else {
            continue;
        };
        let Some(v) = real_eigenvector(&fp.dp, n, l.re) else {
            continue;
        };
        for sign in [1.0, -1.0] {
            seeds.push(
                fp.section
                    .iter()
                    .zip(&v)
                    .map(|(a, b)| a + sign * NEAR_GAIT_OFFSET * b)
                    .collect(),
            );
        }
    }
    seeds
}

/// The entry of `fp` among `gaits` (merged as [`crate::gaits::search`] merges), added if new.
fn gait_entry(gaits: &mut Vec<ScanGait>, fp: FixedPoint) -> &mut ScanGait {
    let same = |a: &FixedPoint| {
        a.section
            .iter()
            .zip(&fp.section)
            .all(|(x, y)| (x - y).abs() <= 1e-8 * (1.0 + x.abs()))
    };
    let i = match gaits.iter().position(|g| same(&g.fp)) {
        Some(i) => i,
        None => {
            gaits.push(ScanGait {
                fp,
                newton_starts: 0,
                attracted_starts: 0,
                near_gaits: 0,
            });
            gaits.len() - 1
        }
    };
    &mut gaits[i]
}

/// Newton from `s`, then where the iterates from `s` go. Failures of Newton are the scan's
/// expected outcome for most starts and are not errors; an interrupt is.
fn one_start(
    w: &dyn Walker,
    s: &[f64],
    opts: &ScanOptions,
    newton: &NewtonOptions,
) -> Result<(Option<FixedPoint>, Fate), LimitError> {
    let step = |x: &[f64]| w.step_length(x);
    let map = StrideMap::new(w, opts.integrator)?.with_step_length(&step);
    let fp = match find_fixed_point(&map, s, newton) {
        Ok(fp) => Some(fp),
        Err(e) if e.is_interrupted() => return Err(e),
        Err(_) => None,
    };
    Ok((fp, settle(&map, s, opts, newton)?))
}

/// Iterates the map from `s` and refines the cycle the iterates settle on, if any.
fn settle(
    map: &StrideMap<'_>,
    s: &[f64],
    opts: &ScanOptions,
    newton: &NewtonOptions,
) -> Result<Fate, LimitError> {
    let mut integ = Integrator::new(map.system().dim(), opts.integrator)?;
    let kmax = opts.max_period;
    // the last kmax + 1 iterates, oldest first
    let mut tail: Vec<Vec<f64>> = vec![s.to_vec()];
    for _ in 0..opts.iterates {
        if pdw_hybrid::interrupt::requested() {
            return Err(LimitError::interrupted());
        }
        let x = tail.last().expect("the tail holds the start");
        let st = match map.stride_with(&mut integ, x) {
            Ok(st) => st,
            Err(e) if e.is_interrupted() => return Err(e),
            Err(_) => return Ok(Fate::Fell(STRIDE_MAP_FAILED.into())),
        };
        if !st.outcome.is_ok() {
            return Ok(Fate::Fell(st.outcome.to_string()));
        }
        if !st.next.iter().all(|v| v.is_finite()) {
            return Ok(Fate::Fell(StrideOutcome::NonFinite.to_string()));
        }
        if tail.len() > kmax {
            tail.remove(0);
        }
        tail.push(st.next);
    }
    let last = tail.last().expect("the tail holds the start");
    let Some(k) = (1..=kmax).find(|&k| {
        tail.len() > k
            && tail[tail.len() - 1 - k]
                .iter()
                .zip(last)
                .all(|(a, b)| (a - b).abs() <= SETTLED * (1.0 + b.abs()))
    }) else {
        return Ok(Fate::Unsettled);
    };
    if k == 1 {
        return Ok(match find_fixed_point(map, last, newton) {
            Ok(fp) => Fate::Gait(fp),
            Err(e) if e.is_interrupted() => return Err(e),
            Err(_) => Fate::Unsettled,
        });
    }
    match find_periodic_orbit(map, last, k, newton) {
        Ok(mut orbit) => {
            rotate_to_canonical(map, &mut orbit, newton)?;
            Ok(Fate::Orbit(orbit))
        }
        Err(e) if e.is_interrupted() => Err(e),
        Err(_) => Ok(Fate::Unsettled),
    }
}
