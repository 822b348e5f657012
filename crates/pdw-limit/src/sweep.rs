//! A one-parameter sweep on an output grid: the gait continued in a parameter over `A..B`
//! ([`continue_branch`], steps of at most one grid spacing), the period-doubling cascade
//! followed down to a period asked for ([`cascade`]: on each period-k branch, the period-2k
//! branch switched onto at its first period doubling by [`switch_period_doubling`]; by default
//! the period-2 branch only), then every branch put on the N evenly spaced values `A, …, B`
//! ([`branch_at_params`]) and each of those points measured: all K orbit points, the K-stride
//! period, the step length and the validity along each stride, the multipliers of the K-stride
//! map.
//!
//! The start gait may sit anywhere in the range ([`SweepSpec::from`]): from `A` the gait is
//! continued one way, to `B`; from a value inside, both ways — towards `A` and towards `B` — and
//! the two halves are joined into one branch ordered from `A` to `B`
//! ([`crate::continue_both_ways`]), so that the cascade below starts at the first period
//! doubling from `A` wherever the start was.
//!
//! This is the computation of the CLI's `fixedpoint --sweep NAME=A:B:N` (`--from`,
//! `--max-period`) and of Python's `continuation`, which differ only in what they do with the
//! result.

use crate::continuation::{
    branch_at_params, continue_both_ways, continue_branch, switch_period_doubling, BifurcationKind,
    Branch, BranchPoint, ContinuationOptions,
};
use crate::error::LimitError;
use crate::stride::StrideMap;
use crate::trajectory::Validity;
use pdw_model::Walker;
use std::fmt::Display;

/// The continuation settings of a sweep over `lo..hi` with `n` output values: steps of at most
/// one grid spacing (the first one too), a smallest step of 10⁻⁶ spacing, and at most 20
/// internal points per output value.
pub fn grid_options(lo: f64, hi: f64, n: usize) -> ContinuationOptions {
    let span = hi - lo;
    let step = span.abs() / (n.max(2) - 1) as f64;
    let mut opts = ContinuationOptions::new(lo.min(hi), lo.max(hi));
    opts.direction = span.signum();
    opts.ds_max = step;
    opts.ds_init = step;
    opts.ds_min = (step * 1e-6).min(opts.ds_min.max(1e-12));
    opts.max_points = 20 * n;
    opts
}

/// One point of a branch on the output grid, measured.
#[derive(Clone, Debug)]
pub struct MeasuredPoint {
    /// The point, corrected at its grid value (`orbit`: the K section points in stride order).
    pub point: BranchPoint,
    /// Step length of each of the K strides (the model's own, at heel strike; NaN if it has
    /// none).
    pub step_length: Vec<f64>,
    /// Validity along each of the K strides ([`Validity::along_step`]); `None` where the model
    /// reports no constraint forces.
    pub validity: Vec<Option<Validity>>,
}

impl MeasuredPoint {
    /// Mean speed: the K step lengths over the K-stride period.
    pub fn speed(&self) -> f64 {
        self.step_length.iter().sum::<f64>() / self.point.period
    }
}

/// A branch on the output grid.
#[derive(Clone, Debug)]
pub struct GridBranch {
    /// `period-1`, `period-2`, `period-4`, ….
    pub name: String,
    /// Strides per period.
    pub period_k: usize,
    /// Its points at the grid values it crosses, in the branch's order.
    pub points: Vec<MeasuredPoint>,
}

/// Everything a sweep computed.
#[derive(Clone, Debug)]
pub struct Sweep {
    /// The N output values.
    pub params: Vec<f64>,
    /// The continued branches (internal steps and located bifurcations), with their names.
    pub continued: Vec<(String, Branch)>,
    /// The same branches on the output grid, in the same order.
    pub branches: Vec<GridBranch>,
    /// What went wrong without stopping the sweep (a failed branch switch, a grid value whose
    /// correction or measurement failed and was left out), in order.
    pub warnings: Vec<String>,
    /// Grid points left out.
    pub grid_failures: usize,
}

/// Progress of a [`sweep`]: its stages (`range` = the parameter interval a continuation stage
/// covers, else `None`) and the units done within one. Both do nothing by default.
pub trait SweepProgress: Sync {
    fn stage(&self, _msg: &str, _len: u64, _range: Option<(f64, f64)>) {}
    fn inc(&self) {}
}

/// No progress reported.
pub struct Silent;
impl SweepProgress for Silent {}

/// Step length and validity along each stride of `p`'s orbit, on `integrator`.
fn measure(
    w: &dyn Walker,
    p: &BranchPoint,
    integrator: pdw_hybrid::Options,
) -> Result<(Vec<f64>, Vec<Option<Validity>>), String> {
    let step = |x: &[f64]| w.step_length(x);
    let map = StrideMap::new(w, integrator)
        .map_err(|e| e.to_string())?
        .with_step_length(&step);
    let mut lengths = Vec::with_capacity(p.orbit.len());
    let mut validity = Vec::with_capacity(p.orbit.len());
    for s in &p.orbit {
        let st = map.stride(s).map_err(|e| e.to_string())?;
        if !st.outcome.is_ok() {
            return Err(format!("the stride from {s:?} ended: {}", st.outcome));
        }
        lengths.push(st.step_length.unwrap_or(f64::NAN));
        validity.push(Validity::along_step(w, &map.lift(s)));
    }
    Ok((lengths, validity))
}

/// What a sweep covers: the N output values `lo..hi`, the parameter value the start gait is at,
/// and the longest period followed down the cascade.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweepSpec {
    pub lo: f64,
    pub hi: f64,
    /// Number of output values (at least 2).
    pub n: usize,
    /// The parameter value of the start gait, within `[lo, hi]`: `lo` continues one way, to
    /// `hi`; any other value both ways, towards `lo` and towards `hi`.
    pub from: f64,
    /// The longest period (strides) followed: 1, 2, 4, …, 64. On each period-k branch (k <
    /// `max_period`), the first period doubling along the branch is switched onto the
    /// period-2k branch.
    pub max_period: usize,
}

impl SweepSpec {
    /// `lo..hi` with `n` values from the gait at `lo`, down to the period-2 branch.
    pub fn new(lo: f64, hi: f64, n: usize) -> Self {
        Self {
            lo,
            hi,
            n,
            from: lo,
            max_period: 2,
        }
    }

    /// `from` inside the range and `max_period` a power of two up to 64.
    pub fn validate(&self) -> Result<(), LimitError> {
        let (a, b) = (self.lo.min(self.hi), self.lo.max(self.hi));
        if !(self.from.is_finite() && a <= self.from && self.from <= b) {
            return Err(LimitError::InvalidOption {
                name: "from",
                value: self.from,
                allowed: "the start value must lie within the swept range",
            });
        }
        if !(self.max_period.is_power_of_two() && self.max_period <= MAX_CASCADE_PERIOD) {
            return Err(LimitError::InvalidOption {
                name: "max_period",
                value: self.max_period as f64,
                allowed: "a power of two from 1 to 64 strides",
            });
        }
        Ok(())
    }
}

/// The longest period a sweep follows down a period-doubling cascade.
pub const MAX_CASCADE_PERIOD: usize = 64;

/// The sweep of `family` (the model at each parameter value) from the period-one gait at
/// `start` (its section state at `spec.from`) over `spec.lo..spec.hi` with `spec.n` output
/// values, continued with `opts` (usually [`grid_options`], perhaps with another integrator)
/// and followed down the period-doubling cascade to `spec.max_period` ([`cascade`]). `name` is
/// the parameter's name in warnings. Points are corrected and measured on `pool`; the result
/// does not depend on its thread count.
pub fn sweep<F, E>(
    family: &F,
    name: &str,
    start: &[f64],
    spec: &SweepSpec,
    opts: &ContinuationOptions,
    pool: &rayon::ThreadPool,
    progress: &dyn SweepProgress,
) -> Result<Sweep, LimitError>
where
    F: Fn(f64) -> Result<Box<dyn Walker>, E> + Sync,
    E: Display,
{
    spec.validate()?;
    let (lo, hi, n) = (spec.lo, spec.hi, spec.n);
    let mut warnings = Vec::new();
    progress.stage("period-1 branch", n as u64, Some((lo, hi)));
    let main = if spec.from == lo {
        continue_branch(family, start, lo, 1, opts)?
    } else {
        continue_both_ways(family, start, spec.from, 1, opts)?
    };
    let mut continued = vec![("period-1".to_string(), main)];
    cascade(family, &mut continued, &mut warnings, spec, opts, progress);
    let params = crate::basin::linspace(lo, hi, n);
    let mut branches = Vec::new();
    let mut grid_failures = 0usize;
    for (bname, b) in &continued {
        let (gb, failures) = on_grid(family, (name, bname), b, &params, opts, pool, progress)?;
        grid_failures += failures.len();
        warnings.extend(failures);
        branches.push(gb);
    }
    Ok(Sweep {
        params,
        continued,
        branches,
        warnings,
        grid_failures,
    })
}

/// Down the period-doubling cascade: while the last branch of `continued` has period k <
/// `spec.max_period` and a located period doubling, switch at its first one along the branch
/// ([`switch_period_doubling`]) onto the period-2k branch, named `period-2k`. A failed switch
/// ends the cascade with a warning.
pub fn cascade<F, E>(
    family: &F,
    continued: &mut Vec<(String, Branch)>,
    warnings: &mut Vec<String>,
    spec: &SweepSpec,
    opts: &ContinuationOptions,
    progress: &dyn SweepProgress,
) where
    F: Fn(f64) -> Result<Box<dyn Walker>, E> + Sync,
    E: Display,
{
    while let Some((_, last)) = continued.last() {
        let k2 = 2 * last.period_strides;
        if k2 > spec.max_period {
            break;
        }
        let Some(pd) = last
            .bifurcations
            .iter()
            .find(|b| b.kind == BifurcationKind::PeriodDoubling)
        else {
            break;
        };
        progress.stage(
            &format!("period-{k2} branch"),
            spec.n as u64,
            Some((pd.param, spec.hi)),
        );
        match switch_period_doubling(family, pd, opts) {
            Ok(b) => continued.push((format!("period-{k2}"), b)),
            Err(e) => {
                warnings.push(format!("switching onto the period-{k2} branch failed: {e}"));
                break;
            }
        }
    }
}

/// Branch `b` (named `names.1`; `names.0` is the parameter's name) on the output values
/// `params` ([`branch_at_params`]), every point measured; with a warning per point left out.
fn on_grid<F, E>(
    family: &F,
    (name, bname): (&str, &str),
    b: &Branch,
    params: &[f64],
    opts: &ContinuationOptions,
    pool: &rayon::ThreadPool,
    progress: &dyn SweepProgress,
) -> Result<(GridBranch, Vec<String>), LimitError>
where
    F: Fn(f64) -> Result<Box<dyn Walker>, E> + Sync,
    E: Display,
{
    use rayon::prelude::*;
    let mut warnings = Vec::new();
    progress.stage(&format!("{bname} on the output grid"), 2, None);
    let sampled = branch_at_params(family, b, params, opts, pool)?;
    progress.inc();
    let ok: Vec<BranchPoint> = sampled
        .into_iter()
        .filter_map(|sp| match sp.point {
            Ok(p) => Some(p),
            Err(e) => {
                warnings.push(format!(
                    "{bname} branch at {name} = {}: {e}; the point is left out",
                    params[sp.index]
                ));
                None
            }
        })
        .collect();
    progress.stage(
        &format!("measuring the {bname} points"),
        ok.len() as u64,
        None,
    );
    let measured: Vec<Result<MeasuredPoint, String>> = pool.install(|| {
        ok.into_par_iter()
            .map(|p| {
                let r = family(p.param)
                    .map_err(|e| e.to_string())
                    .and_then(|w| measure(w.as_ref(), &p, opts.integrator));
                progress.inc();
                r.map(|(step_length, validity)| MeasuredPoint {
                    point: p,
                    step_length,
                    validity,
                })
            })
            .collect()
    });
    let mut points = Vec::with_capacity(measured.len());
    for r in measured {
        match r {
            Ok(v) => points.push(v),
            Err(e) => warnings.push(format!(
                "{bname} branch: a point could not be measured ({e}); it is left out"
            )),
        }
    }
    let gb = GridBranch {
        name: bname.to_string(),
        period_k: b.period_strides,
        points,
    };
    Ok((gb, warnings))
}
