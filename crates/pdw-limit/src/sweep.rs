//! A one-parameter sweep on an output grid: the gait continued in a parameter from `A` to `B`
//! ([`continue_branch`], steps of at most one grid spacing), the period-2 branch switched onto at
//! the first period doubling ([`switch_period_doubling`]), then every branch put on the N evenly
//! spaced values `A, …, B` ([`branch_at_params`]) and each of those points measured: all K
//! orbit points, the K-stride period, the step length and the validity along each stride, the
//! multipliers of the K-stride map.
//!
//! This is the computation of the CLI's `fixedpoint --sweep NAME=A:B:N` and of Python's
//! `continuation`, which differ only in what they do with the result.

use crate::continuation::{
    branch_at_params, continue_branch, switch_period_doubling, BifurcationKind, Branch,
    BranchPoint, ContinuationOptions,
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
    /// `period-1`, `period-2`.
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

/// The sweep of `family` (the model at each parameter value) from the period-one gait at
/// `start` (its section state at `lo`) over `lo..hi` with `n` output values, continued with
/// `opts` (usually [`grid_options`], perhaps with another integrator). `name` is the
/// parameter's name in warnings. Points are corrected and measured on `pool`; the result does
/// not depend on its thread count.
#[allow(clippy::too_many_arguments)]
pub fn sweep<F, E>(
    family: &F,
    name: &str,
    start: &[f64],
    (lo, hi, n): (f64, f64, usize),
    opts: &ContinuationOptions,
    pool: &rayon::ThreadPool,
    progress: &dyn SweepProgress,
) -> Result<Sweep, LimitError>
where
    F: Fn(f64) -> Result<Box<dyn Walker>, E> + Sync,
    E: Display,
{
    use rayon::prelude::*;
    let n_units = n as u64;
    let mut warnings = Vec::new();
    progress.stage("period-1 branch", n_units, Some((lo, hi)));
    let main = continue_branch(family, start, lo, 1, opts)?;
    let mut continued = vec![("period-1".to_string(), main.clone())];
    if let Some(pd) = main
        .bifurcations
        .iter()
        .find(|b| b.kind == BifurcationKind::PeriodDoubling)
    {
        progress.stage("period-2 branch", n_units, Some((pd.param, hi)));
        match switch_period_doubling(family, pd, opts) {
            Ok(b2) => continued.push(("period-2".to_string(), b2)),
            Err(e) => warnings.push(format!("switching onto the period-2 branch failed: {e}")),
        }
    }
    let params = crate::basin::linspace(lo, hi, n);
    let mut branches = Vec::new();
    let mut grid_failures = 0usize;
    for (bname, b) in &continued {
        progress.stage(&format!("{bname} on the output grid"), 2, None);
        let sampled = branch_at_params(family, b, &params, opts, pool)?;
        progress.inc();
        let ok: Vec<BranchPoint> = sampled
            .into_iter()
            .filter_map(|sp| match sp.point {
                Ok(p) => Some(p),
                Err(e) => {
                    grid_failures += 1;
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
                Err(e) => {
                    grid_failures += 1;
                    warnings.push(format!(
                        "{bname} branch: a point could not be measured ({e}); it is left out"
                    ));
                }
            }
        }
        branches.push(GridBranch {
            name: bname.clone(),
            period_k: b.period_strides,
            points,
        });
    }
    Ok(Sweep {
        params,
        continued,
        branches,
        warnings,
        grid_failures,
    })
}
