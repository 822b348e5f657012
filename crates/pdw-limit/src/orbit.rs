//! Brute-force orbit diagrams: for each parameter value μ_i, iterate the stride map from a start
//! state for `transient` strides and record the next `record` section states (the classic
//! bifurcation picture of a cascade and of chaos).
//!
//! # Parallelisation
//! The model differs between parameter values, and the batched engine runs lanes of *one*
//! model, so the lanes of one batch cannot hold different μ. Parameter values are therefore
//! distributed over the caller's rayon pool in fixed, contiguous chunks of `chunk` values; within
//! a chunk the values are processed in order, each by scalar strides through one reused
//! [`Integrator`] (a stride of a low-dimensional walker is a few µs, and the strides of one μ
//! are sequential anyway). Results are identical for any thread count because the chunks do
//! not depend on it.
//!
//! # Start states
//! [`OrbitStart::Fixed`]: every μ starts from the same state. [`OrbitStart::PerParam`]: one
//! start state per μ (e.g. a continued fixed point). [`OrbitStart::FollowPrevious`]: within a
//! chunk, μ_i starts from the last state of μ_{i−1} (if it did not fall), the first μ of each
//! chunk from the given state — a cheap way to stay on an attractor as μ moves, still
//! deterministic because the chunks are fixed.
//!
//! # Period detection
//! The smallest `p ≤ max_period` with `‖r_j − r_{j−p}‖∞ < tol_period` for every recorded
//! `j ≥ p` is reported as the orbit's period (`None` when no such p: quasi-periodic, chaotic, or
//! not yet converged).

use crate::error::LimitError;
use crate::family::ModelFamily;
use crate::stride::{StrideMap, StrideOutcome};
use pdw_hybrid::{Integrator, Options, Section};
use rayon::prelude::*;
use std::fmt::Display;

/// Where each parameter value's iteration starts.
#[derive(Clone, Debug, PartialEq)]
pub enum OrbitStart {
    /// The same section state for every μ.
    Fixed(Vec<f64>),
    /// One section state per μ (same length as the parameter list).
    PerParam(Vec<Vec<f64>>),
    /// The previous μ's last state within a chunk; the given state at each chunk start and
    /// after a fall.
    FollowPrevious(Vec<f64>),
}

/// Options of [`orbit_diagram`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitOptions {
    pub integrator: Options,
    /// Strides discarded before recording.
    pub transient: usize,
    /// Strides recorded.
    pub record: usize,
    /// Parameter values per parallel task (fixed; results do not depend on the thread count).
    pub chunk: usize,
    /// Largest period looked for.
    pub max_period: usize,
    /// Tolerance of the period detection.
    pub tol_period: f64,
}

impl Default for OrbitOptions {
    /// DOP853 at 1e-10, 500 transient strides, 100 recorded, chunks of 8 values, periods ≤ 64
    /// detected to 1e-7.
    fn default() -> Self {
        Self {
            integrator: Options::dop853(1e-10),
            transient: 500,
            record: 100,
            chunk: 8,
            max_period: 64,
            tol_period: 1e-7,
        }
    }
}

/// The iteration at one parameter value.
#[derive(Clone, Debug, PartialEq)]
pub struct OrbitColumn {
    pub param: f64,
    /// Recorded section states (fewer than `record` if the walker fell).
    pub points: Vec<Vec<f64>>,
    /// `None` if every stride completed; otherwise the failed stride's index (0-based, counting
    /// transient strides) and how it ended.
    pub fall: Option<(usize, StrideOutcome)>,
    /// Detected period of the recorded orbit.
    pub period: Option<usize>,
}

fn detect_period(points: &[Vec<f64>], max_p: usize, tol: f64) -> Option<usize> {
    (1..=max_p.min(points.len().saturating_sub(1))).find(|&p| {
        (p..points.len()).all(|j| {
            points[j]
                .iter()
                .zip(&points[j - p])
                .all(|(a, b)| (a - b).abs() < tol)
        })
    })
}

/// Orbit diagram over `params` (see the module docs). `family(μ)` builds the model.
pub fn orbit_diagram<S, E, F>(
    family: &F,
    params: &[f64],
    start: &OrbitStart,
    opts: &OrbitOptions,
    pool: &rayon::ThreadPool,
) -> Result<Vec<OrbitColumn>, LimitError>
where
    S: Section + ?Sized,
    E: Display,
    F: Fn(f64) -> Result<Box<S>, E> + Sync,
{
    diagram_erased(family, params, start, opts, pool)
}

/// [`orbit_diagram`] on the erased family.
pub(crate) fn diagram_erased<'m>(
    family: &(dyn ModelFamily<'m> + Sync),
    params: &[f64],
    start: &OrbitStart,
    opts: &OrbitOptions,
    pool: &rayon::ThreadPool,
) -> Result<Vec<OrbitColumn>, LimitError> {
    opts.integrator.validate()?;
    if opts.chunk == 0 {
        return Err(LimitError::InvalidOption {
            name: "chunk",
            value: 0.0,
            allowed: "must be >= 1",
        });
    }
    if let OrbitStart::PerParam(v) = start {
        if v.len() != params.len() {
            return Err(LimitError::InvalidOption {
                name: "start",
                value: v.len() as f64,
                allowed: "PerParam needs one start state per parameter value",
            });
        }
    }
    let chunks: Vec<(usize, &[f64])> = params
        .chunks(opts.chunk)
        .enumerate()
        .map(|(i, c)| (i * opts.chunk, c))
        .collect();
    let parts: Vec<Result<Vec<OrbitColumn>, LimitError>> = pool.install(|| {
        chunks
            .par_iter()
            .map(|&(offset, mus)| {
                let mut out = Vec::with_capacity(mus.len());
                let mut carry: Option<Vec<f64>> = None;
                for (i, &mu) in mus.iter().enumerate() {
                    let s0 = match start {
                        OrbitStart::Fixed(s) => s.clone(),
                        OrbitStart::PerParam(v) => v[offset + i].clone(),
                        OrbitStart::FollowPrevious(s) => carry.take().unwrap_or_else(|| s.clone()),
                    };
                    let col = column(family, mu, &s0, opts)?;
                    if col.fall.is_none() {
                        carry = col.points.last().cloned();
                    }
                    out.push(col);
                }
                Ok(out)
            })
            .collect()
    });
    let mut all = Vec::with_capacity(params.len());
    for p in parts {
        all.extend(p?);
    }
    Ok(all)
}

fn column(
    family: &dyn ModelFamily<'_>,
    mu: f64,
    s0: &[f64],
    opts: &OrbitOptions,
) -> Result<OrbitColumn, LimitError> {
    let built = family
        .build(mu)
        .map_err(|message| LimitError::Model { param: mu, message })?;
    let model = built.section();
    let map = StrideMap::new(model, opts.integrator)?;
    let mut integ = Integrator::new(model.dim(), opts.integrator)?;
    let mut s = s0.to_vec();
    let mut points = Vec::with_capacity(opts.record);
    let mut fall = None;
    for k in 0..opts.transient + opts.record {
        let st = map.stride_with(&mut integ, &s)?;
        if !st.outcome.is_ok() || !st.next.iter().all(|v| v.is_finite()) {
            let outcome = if st.outcome.is_ok() {
                StrideOutcome::NonFinite
            } else {
                st.outcome
            };
            fall = Some((k, outcome));
            break;
        }
        s = st.next;
        if k >= opts.transient {
            points.push(s.clone());
        }
    }
    let period = if fall.is_none() {
        detect_period(&points, opts.max_period, opts.tol_period)
    } else {
        None
    };
    Ok(OrbitColumn {
        param: mu,
        points,
        fall,
        period,
    })
}
