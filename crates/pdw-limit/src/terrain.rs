//! Walking on random terrain: a random ground slope per step, its counter-based random numbers,
//! the walk of many walkers and the mean first-passage time (MFPT) of Byl & Tedrake
//! ("Metastable walking machines", IJRR 28(8), 2009).
//!
//! # Convention
//! Step `k` (k = 1, 2, …) ends when the swing foot lands on the line through the current stance
//! foot inclined by `s_k` (downhill positive, like every model's `slope`). During step `k` the
//! walker moves in the frame of that line: it is exactly the model at slope `s_k` (gravity
//! rotated). Between steps only the frame changes: the model's one absolute angle
//! ([`Walker::terrain_frame`]: index `a`, sign `σ`) becomes `x[a] + σ (s' − s)` when measured
//! from the normal of a line inclined `s'` instead of `s`; relative angles and every rate are
//! unchanged. The walk keeps the post-heel-strike state in the frame of the **mean** slope `s̄`,
//! so it is Markov in that state alone: a stride on line `s` is the shift into that line's
//! frame (`x[a] += σ (s − s̄)`), the model's stride at slope `s` from that full state (not on
//! the model's own section unless `s` equals the previous line's slope), and the shift back.
//! With `s = s̄` both shifts add an exact zero, so the terrain stride is the ordinary stride
//! bit for bit.
//!
//! # Round feet
//! A round foot rolls, so its contact point moves along the line it stands on, and a change of
//! line is not a rotation about it ([`Walker::terrain_frame`] is `None`). Such a model walks
//! random slopes on **tilted landing lines** ([`Walker::on_tilted_line`]): during step `k` the
//! stance foot rolls on the line it landed on (slope `s_{k−1}`), and the swing foot lands on
//! line `k`, which passes through the stance foot's contact point at the moment of that heel
//! strike and is inclined `Δ = s_k − s_{k−1}` against line `k−1`. The step is the model at
//! slope `s_{k−1}` in that line's frame, whose swing-foot guard measures the foot against the
//! tilted line and whose heel strike puts the new contact point on it; the frame shifts are
//! those of point feet (the absolute angle only: the rolling constraint fixes the contact's
//! rate, not where along the line it is). The ground the walk realises is a polyline with a
//! corner under each heel strike's stance contact point; it is the walk's ground as long as the
//! swing foot does not cross it before the heel strike, which the guard does not check
//! (neither does the point-foot walk). A stride then depends on the last line's slope as well
//! as on the next one, so the walk is Markov in `(state, s_{k−1})`: [`SlopeWalk::stride_from`]
//! takes both, the Monte Carlo walks one walker at a time ([`monte_carlo_scalar`]), and the
//! Markov chain on the post-heel-strike section is not built for it (its state would need the
//! last two slopes: the trailing foot stands on line `k−1`, the new stance foot on line `k`,
//! so the section's symmetric lift no longer holds). For point feet the tilted walk
//! ([`SlopeWalk::with_tilted_lines`]) is the rotated walk above in another frame.
//!
//! # Step heights
//! With [`TerrainKind::StepDown`] the ground of step `k` is a line parallel to the model's
//! slope, `h_k` below the stance foot along the slope normal (a step down positive, up
//! negative): the model at `step_down = h_k` (its module docs derive the guard and the impact
//! for the unsymmetric configuration). The dynamics see angles only and every foothold is
//! measured from the current stance foot, so nothing shifts between steps ([`SlopeWalk::shift`]
//! adds nothing); the state just after a heel strike onto `h_k` still remembers `h_k` (the
//! trailing foot is `h_k` above the new stance foot), which the Markov chain's layers carry as
//! they carry the last slope ([`crate::markov`]).
//!
//! # Random numbers
//! Counter-based: the slope of walker `i` at step `k` is a pure function of `(seed, i, k)`
//! ([`standard_normal`], [`standard_uniform`], [`pick`] for a list of values:
//! [`TerrainDist`]), so a walk is the same on any thread count or shard.

use crate::ensemble::{monte_carlo_lockstep, Lockstep};
use crate::error::LimitError;
use crate::stride::{StrideMap, StrideOutcome, StrideStop};
use pdw_hybrid::{run_scalar_with, Integrator, Options, StopReason};
use pdw_model::{ClosedEnd, Ground, Walker};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Odd constant of the golden ratio (2⁶⁴/φ), the increment of SplitMix64.
const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// The output function of SplitMix64 (Steele, Lea & Flood, "Fast splittable pseudorandom
/// number generators", OOPSLA 2014; the variant of Stafford's "Mix13" constants): a bijection of
/// 64-bit words that changes about half the output bits for each input bit.
pub fn mix64(z: u64) -> u64 {
    let z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    let z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// 64 random bits for `(seed, walker, step, stream)`: each coordinate mixed in turn, each with
/// its own multiple of `GOLDEN` added so that swapping two coordinates changes the result.
pub fn counter_bits(seed: u64, walker: u64, step: u64, stream: u64) -> u64 {
    let mut h = mix64(seed.wrapping_add(GOLDEN));
    for (j, v) in [walker, step, stream].into_iter().enumerate() {
        h = mix64(h ^ v.wrapping_add(GOLDEN.wrapping_mul(j as u64 + 2)));
    }
    h
}

/// A uniform number in the open interval (0, 1) from the top 53 bits of [`counter_bits`]:
/// `(b + ½) 2⁻⁵³`, never 0 or 1 (so its logarithm is finite).
pub fn uniform(seed: u64, walker: u64, step: u64, stream: u64) -> f64 {
    let b = counter_bits(seed, walker, step, stream) >> 11;
    (b as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
}

/// A standard normal number for `(seed, walker, step)` by the Box–Muller transform (Box &
/// Muller, Ann. Math. Statist. 29, 1958): `√(−2 ln u₁) cos(2π u₂)` with `u₁`, `u₂` the
/// [`uniform`]s of streams 0 and 1.
pub fn standard_normal(seed: u64, walker: u64, step: u64) -> f64 {
    let u1 = uniform(seed, walker, step, 0);
    let u2 = uniform(seed, walker, step, 1);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// What the terrain draws per step: the landing line's slope, or the foothold's height below
/// the stance foot (module docs, "Step heights").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TerrainKind {
    /// A random slope per step (rad, downhill positive).
    #[default]
    Slope,
    /// A random step down per step (model length units, a step down positive).
    StepDown,
}

impl TerrainKind {
    /// The model parameter the terrain sets per step: `slope` or `step_down`.
    pub fn param(self) -> &'static str {
        match self {
            TerrainKind::Slope => "slope",
            TerrainKind::StepDown => "step_down",
        }
    }

    /// The terrain's name in commands and files: `slope` or `step-down`.
    pub fn name(self) -> &'static str {
        match self {
            TerrainKind::Slope => "slope",
            TerrainKind::StepDown => "step-down",
        }
    }
}

/// The distribution of the terrain's standardised draws `ξ_k` ([`SlopeTerrain`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub enum TerrainDist {
    /// Standard normal ([`standard_normal`]); the chain's quadrature is Gauss–Hermite.
    #[default]
    Normal,
    /// Uniform on `[−√3, √3]`: mean 0, variance 1, so `sd` stays the standard deviation
    /// ([`standard_uniform`]); the chain's quadrature is Gauss–Legendre.
    Uniform,
    /// The empirical distribution of a list of values (a file's): each step draws one of them
    /// with equal probability ([`pick`]), `sd` scales them as given.
    Values(ValuesDist),
}

/// A list of values to draw from and where it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct ValuesDist {
    /// Where the values came from (a file's path), for the record.
    pub source: String,
    /// The values, finite, at least one.
    pub values: std::sync::Arc<[f64]>,
}

impl TerrainDist {
    /// The empirical distribution of `values` from `source`; `Err` names why not (no value, a
    /// value that is not finite).
    pub fn values(source: &str, values: Vec<f64>) -> Result<Self, String> {
        if values.is_empty() {
            return Err(format!("{source}: holds no value"));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(format!(
                "{source}: value {} is {} (not finite)",
                i + 1,
                values[i]
            ));
        }
        Ok(TerrainDist::Values(ValuesDist {
            source: source.to_string(),
            values: values.into(),
        }))
    }

    /// The name in commands and files: `normal`, `uniform`, `file:PATH`.
    pub fn name(&self) -> String {
        match self {
            TerrainDist::Normal => "normal".into(),
            TerrainDist::Uniform => "uniform".into(),
            TerrainDist::Values(v) => format!("file:{}", v.source),
        }
    }

    /// The standardised draw `ξ` of walker `walker` at step `step`.
    pub fn draw(&self, seed: u64, walker: u64, step: u64) -> f64 {
        match self {
            TerrainDist::Normal => standard_normal(seed, walker, step),
            TerrainDist::Uniform => standard_uniform(seed, walker, step),
            TerrainDist::Values(v) => v.values[pick(seed, walker, step, v.values.len())],
        }
    }

    /// The largest `|ξ|` a draw can take: [`MAX_NORMAL_DRAW`], `√3`, the largest `|value|`.
    pub fn max_abs(&self) -> f64 {
        match self {
            TerrainDist::Normal => MAX_NORMAL_DRAW,
            TerrainDist::Uniform => 3f64.sqrt(),
            TerrainDist::Values(v) => v.values.iter().fold(0.0, |m, x| m.max(x.abs())),
        }
    }

    /// An `n`-point quadrature `(ξ_l, w_l)` of the distribution (weights summing to 1): the
    /// Gauss–Hermite rule for the normal, Gauss–Legendre for the uniform
    /// ([`crate::markov::gauss_hermite`], [`crate::markov::gauss_legendre`]), and for values
    /// their empirical distribution ([`empirical_nodes`]).
    pub fn quadrature(&self, n: usize) -> (Vec<f64>, Vec<f64>) {
        match self {
            TerrainDist::Normal => crate::markov::gauss_hermite(n),
            TerrainDist::Uniform => crate::markov::gauss_legendre(n),
            TerrainDist::Values(v) => empirical_nodes(&v.values, n),
        }
    }
}

/// The largest magnitude a Box–Muller draw of [`standard_normal`] can reach: `√(−2 ln u)` with
/// `u ≥ 2⁻⁵⁴`, i.e. `√(108 ln 2)` ≈ 8.65.
pub const MAX_NORMAL_DRAW: f64 = 8.66;

/// A uniform number of mean 0 and variance 1 for `(seed, walker, step)`: `√3 (2u − 1)` with
/// `u` the [`uniform`] of stream 0, in the open interval `(−√3, √3)`.
pub fn standard_uniform(seed: u64, walker: u64, step: u64) -> f64 {
    3f64.sqrt() * (2.0 * uniform(seed, walker, step, 0) - 1.0)
}

/// An index in `0 … n−1` for `(seed, walker, step)`, each with probability `n⁻¹ (1 ± n 2⁻⁶⁴)`:
/// the high word of the 128-bit product of [`counter_bits`] (stream 0) and `n` (Lemire, "Fast
/// random integer generation in an interval", ACM TOMACS 29(1), 2019, without its rejection).
pub fn pick(seed: u64, walker: u64, step: u64, n: usize) -> usize {
    let b = counter_bits(seed, walker, step, 0) as u128;
    ((b * n as u128) >> 64) as usize
}

/// The chain's quadrature of the empirical distribution of `values` with at most `n` nodes:
/// its distinct values weighted by their frequencies when there are at most `n` of them; else
/// the sorted values cut into `n` bins of (nearly) equal count, bin `j` holding the values of
/// sorted positions `⌊j m / n⌋ … ⌊(j+1) m / n⌋ − 1` (m values), each bin represented by its
/// mean and weighted by its share of the values (the mean of the distribution is kept
/// exactly; its spread within a bin is lost).
pub fn empirical_nodes(values: &[f64], n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let m = v.len() as f64;
    let mut distinct: Vec<(f64, usize)> = Vec::new();
    for &x in &v {
        match distinct.last_mut() {
            Some(last) if last.0 == x => last.1 += 1,
            _ => distinct.push((x, 1)),
        }
    }
    if distinct.len() <= n {
        return distinct.iter().map(|&(x, c)| (x, c as f64 / m)).unzip();
    }
    (0..n)
        .map(|j| {
            let bin = &v[j * v.len() / n..(j + 1) * v.len() / n];
            let mean = bin.iter().sum::<f64>() / bin.len() as f64;
            (mean, bin.len() as f64 / m)
        })
        .unzip()
}

/// Ground slopes (or step heights, [`TerrainKind`]) drawn per step: `s_k = mean + sd ξ_k`,
/// `ξ_k` independent draws of `dist` ([`TerrainDist::draw`] of `(seed, walker, k)`; standard
/// normals by default).
#[derive(Clone, Debug, PartialEq)]
pub struct SlopeTerrain {
    /// Mean slope `s̄` (rad), or mean step down `h̄`.
    pub mean: f64,
    /// Standard deviation `σ` of the slope (rad, ≥ 0), or of the step down.
    pub sd: f64,
    /// Seed of the counter-based generator.
    pub seed: u64,
    /// What is drawn.
    pub kind: TerrainKind,
    /// The distribution of the standardised draws `ξ_k`.
    pub dist: TerrainDist,
}

impl SlopeTerrain {
    /// The slope of the line walker `walker` lands on at the end of step `step` (1, 2, …) (or
    /// the step down of its foothold).
    pub fn slope(&self, walker: u64, step: u64) -> f64 {
        self.mean + self.sd * self.dist.draw(self.seed, walker, step)
    }
}

/// The absolute angle `(index, sign)` of a model that walks random slopes on tilted landing
/// lines ([`Walker::on_tilted_line`], module docs "Round feet"); `None` for one that has none.
pub fn tilted_frame(model: &dyn Walker) -> Option<(usize, f64)> {
    let tilts = model.on_tilted_line(0.0).is_some_and(|r| r.is_ok());
    model.absolute_angle().filter(|_| tilts)
}

/// The model at a given slope (the same model with only its slope changed).
pub type ModelAt<'a> = &'a (dyn Fn(f64) -> Result<Box<dyn Walker>, LimitError> + Sync);

/// One stride on terrain: how it ended and the state after it, in the mean slope's frame.
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainStride {
    pub outcome: StrideOutcome,
    /// The full state just after the heel strike (or at the stop), in the mean slope's frame.
    pub post: Vec<f64>,
}

/// The stride on terrain of a model (module docs, "Convention").
pub struct SlopeWalk<'a> {
    model_at: ModelAt<'a>,
    kind: TerrainKind,
    mean: f64,
    absolute: usize,
    sign: f64,
    /// the stride depends on the last line too ([`Walker::on_tilted_line`]; module docs,
    /// "Round feet")
    tilted: bool,
    integrator: Options,
    /// Told the number of strides each batched call of a chain has finished since it last
    /// told ([`SlopeWalk::with_progress`]).
    progress: Option<&'a (dyn Fn(usize) + Sync)>,
    /// The Markov chains take their strides in closed form where the model has one
    /// ([`SlopeWalk::with_closed_form`]).
    closed_form: bool,
}

impl<'a> SlopeWalk<'a> {
    /// The walk of the model `model_at` gives around mean slope `mean`, integrated with
    /// `integrator`; [`LimitError::Model`] when the model has no terrain frame
    /// ([`Walker::terrain_frame`]).
    pub fn new(model_at: ModelAt<'a>, mean: f64, integrator: Options) -> Result<Self, LimitError> {
        Self::with_kind(model_at, TerrainKind::Slope, mean, integrator)
    }

    /// The walk on terrain of kind `kind`: `model_at` sets the model's [`TerrainKind::param`]
    /// (mean `mean`).
    pub fn with_kind(
        model_at: ModelAt<'a>,
        kind: TerrainKind,
        mean: f64,
        integrator: Options,
    ) -> Result<Self, LimitError> {
        integrator.validate()?;
        let model = model_at(mean)?;
        let frame = model.terrain_frame();
        // step heights shift nothing; a slope needs the model's absolute angle, and a model
        // whose change of line is not a rotation lands on a tilted line (round feet)
        let (absolute, sign, tilted) = match (kind, frame, tilted_frame(model.as_ref())) {
            (TerrainKind::StepDown, f, _) => {
                let (a, s) = f.unwrap_or((0, 0.0));
                (a, s, false)
            }
            (TerrainKind::Slope, Some((a, s)), _) => (a, s, false),
            (TerrainKind::Slope, None, Some((a, s))) => (a, s, true),
            (TerrainKind::Slope, None, None) => {
                return Err(LimitError::Model {
                    param: mean,
                    message: "the model does not walk on random slopes".into(),
                })
            }
        };
        Ok(Self {
            model_at,
            kind,
            mean,
            absolute,
            sign,
            tilted,
            integrator,
            progress: None,
            closed_form: false,
        })
    }

    /// Whether a stride depends on the slope of the line the stance foot stands on as well as
    /// on the landing line's (round feet on random slopes, module docs "Round feet"): then only
    /// [`SlopeWalk::stride_from`] walks it.
    pub fn tilted(&self) -> bool {
        self.tilted
    }

    /// The walk on random slopes by tilted landing lines (module docs, "Round feet") for any
    /// model that has them ([`Walker::on_tilted_line`]), also one whose change of line is a
    /// rotation (point feet: the two walks are the same walk in two frames, which the tests
    /// compare). [`LimitError::Model`] for a model without tilted landing lines.
    pub fn with_tilted_lines(
        model_at: ModelAt<'a>,
        mean: f64,
        integrator: Options,
    ) -> Result<Self, LimitError> {
        integrator.validate()?;
        let Some((absolute, sign)) = tilted_frame(model_at(mean)?.as_ref()) else {
            return Err(LimitError::Model {
                param: mean,
                message: "the model has no tilted landing line".into(),
            });
        };
        Ok(Self {
            model_at,
            kind: TerrainKind::Slope,
            mean,
            absolute,
            sign,
            tilted: true,
            integrator,
            progress: None,
            closed_form: false,
        })
    }

    /// The walk with `progress` told how many more strides the Markov chains' batched maps
    /// ([`crate::markov`], [`crate::mid_stance`]) and their walks of visited states have run,
    /// as they run (a front end's progress bar; calls come from the pool's threads).
    pub fn with_progress(mut self, progress: &'a (dyn Fn(usize) + Sync)) -> Self {
        self.progress = Some(progress);
        self
    }

    /// The walk whose Markov chain on the landing section ([`crate::markov`]) takes each stride
    /// in closed form where the model has one ([`Walker::closed_stride`], the rimless wheel),
    /// as the Monte Carlo walkers of [`monte_carlo_closed_form`] do: the same strides, no
    /// tolerance, and no integration. A start the closed form does not cover is integrated.
    /// Off by default (every stride integrated with [`SlopeWalk::options`]).
    pub fn with_closed_form(mut self, on: bool) -> Self {
        self.closed_form = on;
        self
    }

    /// Whether the chains take their strides in closed form where the model has one
    /// ([`SlopeWalk::with_closed_form`]).
    pub fn closed_form(&self) -> bool {
        self.closed_form
    }

    /// `strides` more strides run ([`SlopeWalk::with_progress`]).
    pub fn report(&self, strides: usize) {
        if let Some(p) = self.progress {
            p(strides);
        }
    }

    /// A progress callback for one call of [`pdw_hybrid::run_batch_par`] (which tells the
    /// call's items done so far, from any thread, not necessarily in order) that reports the
    /// increments to [`SlopeWalk::report`].
    pub(crate) fn batch_progress(&self) -> impl Fn(usize) + Sync + '_ {
        let told = std::sync::atomic::AtomicUsize::new(0);
        move |done: usize| {
            let before = told.fetch_max(done, std::sync::atomic::Ordering::Relaxed);
            if done > before {
                self.report(done - before);
            }
        }
    }

    /// The mean slope `s̄`.
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// A state in the frame of line `from` carried to the frame of line `to`; nothing for step
    /// heights (module docs, "Step heights").
    pub fn shift(&self, x: &mut [f64], from: f64, to: f64) {
        if self.kind == TerrainKind::Slope {
            x[self.absolute] += self.sign * (to - from);
        }
    }

    /// What the terrain draws.
    pub fn kind(&self) -> TerrainKind {
        self.kind
    }

    /// One stride landing on a line inclined `slope`, from the post-heel-strike full state `x`
    /// in the mean slope's frame, with a caller-owned integrator (for the model's state
    /// dimension and this walk's options).
    pub fn stride(
        &self,
        integ: &mut Integrator,
        x: &[f64],
        slope: f64,
    ) -> Result<TerrainStride, LimitError> {
        if self.tilted {
            return Err(LimitError::Model {
                param: slope,
                message: "this model's stride on random slopes depends on the last line's slope \
                          too (round feet): it walks one walker at a time (stride_from), and has \
                          no Markov chain on its post-heel-strike section"
                    .into(),
            });
        }
        let w = (self.model_at)(slope)?;
        self.stride_in(integ, w.as_ref(), x, slope)
    }

    /// The stride of model `w`, whose frame is that of the line inclined `frame`, from `x` in
    /// the mean slope's frame, its end shifted back to it.
    fn stride_in(
        &self,
        integ: &mut Integrator,
        w: &dyn Walker,
        x: &[f64],
        frame: f64,
    ) -> Result<TerrainStride, LimitError> {
        let map = StrideMap::new(w, self.integrator)?;
        let mut x0 = x.to_vec();
        self.shift(&mut x0, self.mean, frame);
        let end = run_scalar_with(integ, map.system(), &map.driver(), &x0)?;
        let mut post = end.post;
        self.shift(&mut post, frame, self.mean);
        Ok(TerrainStride {
            outcome: end.outcome,
            post,
        })
    }

    /// One stride from the post-heel-strike full state `x` (mean slope's frame) of a walker
    /// standing on a line inclined `last`, landing on a line inclined `slope`. For a walk that
    /// is not [`SlopeWalk::tilted`] this is [`SlopeWalk::stride`] (`last` does not matter).
    /// Tilted (module docs, "Round feet"): the model at slope `last` landing on a line inclined
    /// `slope − last` against it ([`Walker::on_tilted_line`]), between the shifts into and out
    /// of `last`'s frame.
    pub fn stride_from(
        &self,
        integ: &mut Integrator,
        x: &[f64],
        last: f64,
        slope: f64,
    ) -> Result<TerrainStride, LimitError> {
        if !self.tilted {
            return self.stride(integ, x, slope);
        }
        let refused = |message: String| LimitError::Model {
            param: slope,
            message,
        };
        let w = (self.model_at)(last)?
            .on_tilted_line(slope - last)
            .ok_or_else(|| refused("the model has no tilted landing line".into()))?
            .map_err(refused)?;
        self.stride_in(integ, w.as_ref(), x, last)
    }

    /// A fresh integrator for this walk.
    pub fn integrator(&self, dim: usize) -> Result<Integrator, LimitError> {
        Ok(Integrator::new(dim, self.integrator)?)
    }

    /// The integrator options of the strides.
    pub fn options(&self) -> Options {
        self.integrator
    }

    /// The model at slope `slope`.
    pub fn model(&self, slope: f64) -> Result<Box<dyn Walker>, LimitError> {
        (self.model_at)(slope)
    }
}

/// How one walker's walk ended: the heel strikes completed and, for a fall, how the stride
/// that did not reach the next heel strike ended (`None`: still walking at the step limit,
/// censored).
#[derive(Clone, Debug, PartialEq)]
pub struct Fate {
    pub steps: usize,
    pub end: Option<StrideOutcome>,
}

/// Walker `i` walks from `x0` (mean-slope frame, just after a heel strike) on `terrain` for at
/// most `max_steps` strides.
pub fn walk_one(
    walk: &SlopeWalk,
    terrain: &SlopeTerrain,
    x0: &[f64],
    i: u64,
    max_steps: usize,
) -> Result<Fate, LimitError> {
    let mut integ = walk.integrator(x0.len())?;
    let mut x = x0.to_vec();
    // the walker starts just after a heel strike on a line of the mean slope
    let mut last = walk.mean();
    for k in 0..max_steps {
        let slope = terrain.slope(i, k as u64 + 1);
        let st = walk.stride_from(&mut integ, &x, last, slope)?;
        if !st.outcome.is_ok() {
            return Ok(Fate {
                steps: k,
                end: Some(st.outcome),
            });
        }
        x = st.post;
        last = slope;
    }
    Ok(Fate {
        steps: max_steps,
        end: None,
    })
}

/// `walkers` walkers (0, 1, …) from `x0` on `pool`, in walker order; identical for any thread
/// count, lane count and chunk size (each walker's slopes are its own counter-based draws).
/// Both terrains run in batched lockstep ([`crate::ensemble`], lanes and chunks of
/// [`Lockstep::for_pool`]); step heights on a model without [`Walker::step_height`], and random
/// slopes on tilted landing lines ([`SlopeWalk::tilted`]: round feet, whose flow depends on the
/// line the stance foot rolls on), run one walker at a time ([`monte_carlo_scalar`]).
/// `progress` gets the number of walkers done.
pub fn monte_carlo(
    walk: &SlopeWalk,
    terrain: &SlopeTerrain,
    x0: &[f64],
    walkers: usize,
    max_steps: usize,
    pool: &rayon::ThreadPool,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Vec<Fate>, LimitError> {
    let steps = terrain.kind == TerrainKind::StepDown || walk.kind() == TerrainKind::StepDown;
    if walk.tilted() || steps && walk.model(walk.mean())?.step_height().is_none() {
        return monte_carlo_scalar(walk, terrain, x0, walkers, max_steps, pool, progress);
    }
    let batch = Lockstep::for_pool(walkers, pool.current_num_threads());
    monte_carlo_lockstep(walk, terrain, x0, walkers, max_steps, pool, batch, progress)
}

/// The scalar walk: each walker on one thread with its own integrator, each stride
/// [`SlopeWalk::stride`] (the model at the line's slope or step height, the shifts of the
/// module docs) — the reference of the lockstep walk. Identical for any thread
/// count; `progress` gets the number of walkers done.
pub fn monte_carlo_scalar(
    walk: &SlopeWalk,
    terrain: &SlopeTerrain,
    x0: &[f64],
    walkers: usize,
    max_steps: usize,
    pool: &rayon::ThreadPool,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Vec<Fate>, LimitError> {
    let done = AtomicUsize::new(0);
    pool.install(|| {
        (0..walkers)
            .into_par_iter()
            .map(|i| {
                let f = walk_one(walk, terrain, x0, i as u64, max_steps);
                progress(done.fetch_add(1, Ordering::Relaxed) + 1);
                f
            })
            .collect()
    })
}

/// The walk in closed form ([`Walker::closed_stride`]): each walker one stride after another
/// on one thread, each stride the model's [`pdw_model::ClosedStride::stride_on`] on the ground of its
/// draw, between the shifts of [`SlopeWalk::stride`] (module docs, "Convention"); a stride
/// whose start the closed form does not cover ([`ClosedEnd::Outside`]) is integrated
/// ([`SlopeWalk::stride`]). No tolerance, so it differs from the integrated walks only where
/// a stride lands within their tolerance of a fall (or creeps past the stride time budget,
/// [`pdw_model::ClosedStride`]). Walkers in walker order, identical for any thread count; `progress`
/// gets the number of walkers done. [`LimitError::Model`] when the model has no closed form,
/// or for a step height outside the model's range (as [`monte_carlo`]).
pub fn monte_carlo_closed_form(
    walk: &SlopeWalk,
    terrain: &SlopeTerrain,
    x0: &[f64],
    walkers: usize,
    max_steps: usize,
    pool: &rayon::ThreadPool,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Vec<Fate>, LimitError> {
    let model = walk.model(walk.mean())?;
    let no_form = || LimitError::Model {
        param: walk.mean(),
        message: format!(
            "the model {} has no stride map in closed form (integrate its strides)",
            model.name()
        ),
    };
    let closed = model.closed_stride().ok_or_else(no_form)?;
    crate::ensemble::check_walk(walk, terrain, x0, model.as_ref())?;
    let guards = model.guards(model.section_mode());
    let done = AtomicUsize::new(0);
    pool.install(|| {
        (0..walkers)
            .into_par_iter()
            // one walker per task: walkers' lengths are geometric, and a long one left at the
            // end of a chunk of short ones would keep the other thread idle
            .with_max_len(1)
            .map(|i| {
                let mut x = x0.to_vec();
                let (mut y, mut out) = (x.clone(), x.clone());
                let mut integ = None;
                let mut fate = Fate {
                    steps: max_steps,
                    end: None,
                };
                for k in 0..max_steps {
                    let s = terrain.slope(i as u64, k as u64 + 1);
                    let ground = match walk.kind() {
                        TerrainKind::Slope => Ground::Slope(s),
                        TerrainKind::StepDown => Ground::StepDown(s),
                    };
                    y.copy_from_slice(&x);
                    walk.shift(&mut y, walk.mean(), s);
                    let end = match closed.stride_on(ground, &y, &mut out) {
                        ClosedEnd::Landed => {
                            walk.shift(&mut out, s, walk.mean());
                            std::mem::swap(&mut x, &mut out);
                            continue;
                        }
                        ClosedEnd::Terminal { guard } => {
                            match StrideStop::of(StopReason::Guard { guard }, guards) {
                                StrideStop::End(o) => o,
                                // a closed form naming a reset guard is a model's bug:
                                // reported as the stride that did not end, not hidden
                                StrideStop::Reset { .. } => StrideOutcome::TooManyEvents,
                            }
                        }
                        ClosedEnd::Outside => {
                            let integ = match &mut integ {
                                Some(g) => g,
                                None => integ.insert(walk.integrator(x.len())?),
                            };
                            let st = walk.stride(integ, &x, s)?;
                            if st.outcome.is_ok() {
                                x = st.post;
                                continue;
                            }
                            st.outcome
                        }
                    };
                    fate = Fate {
                        steps: k,
                        end: Some(end),
                    };
                    break;
                }
                progress(done.fetch_add(1, Ordering::Relaxed) + 1);
                Ok(fate)
            })
            .collect()
    })
}

/// The Monte Carlo estimate of the mean first-passage time and what it rests on.
#[derive(Clone, Debug, PartialEq)]
pub struct MfptEstimate {
    pub walkers: usize,
    pub falls: usize,
    /// Walkers still walking at the step limit.
    pub censored: usize,
    /// Heel strikes completed by all walkers together, `S`.
    pub total_steps: u64,
    /// `S / F` (F falls): the maximum-likelihood MFPT for a constant fall probability per step
    /// (geometric first-passage time, the metastable regime); infinite without a fall.
    pub mfpt: f64,
    /// Its standard error from the Fisher information, `√(S (S + F)) / F^{3/2}`.
    pub stderr: f64,
    /// The survival-based (restricted) mean: `Σ_{k=1}^{K} S(k)` = the mean of `min(T, K)`, K the
    /// step limit; equals the MFPT when no walker is censored.
    pub restricted_mean: f64,
    /// Its standard error, the sample standard deviation of `min(T, K)` over `√N`.
    pub restricted_stderr: f64,
    /// `survival[k]`: the fraction of walkers that completed at least `k` heel strikes, for
    /// k = 0 … the most heel strikes any walker completed (at most K); 0 beyond. Sized by what
    /// the walkers did, not by the step limit, which may be far larger than any walk.
    pub survival: Vec<f64>,
    /// Falls by kind (the outcome's name), sorted by name.
    pub failures: Vec<(String, usize)>,
}

/// The estimate from the walkers' fates (`max_steps` the step limit K).
///
/// With `F` falls among `N` walkers that completed `S` heel strikes in all, a constant fall
/// probability `p` per stride has the censored geometric likelihood `p^F (1 − p)^S`, maximal at
/// `p̂ = F/(S + F)`; the MFPT (heel strikes before the fall) `(1 − p)/p` has the MLE `S/F`, and
/// the observed information `(S + F)³/(F S)` gives the delta-method standard error
/// `√(S (S + F)) / F^{3/2}` (≈ MFPT/√F).
pub fn estimate(fates: &[Fate], max_steps: usize) -> MfptEstimate {
    let n = fates.len();
    let falls = fates.iter().filter(|f| f.end.is_some()).count();
    let s: u64 = fates.iter().map(|f| f.steps as u64).sum();
    let (sf, ff) = (s as f64, falls as f64);
    let (mfpt, stderr) = if falls == 0 {
        (f64::INFINITY, f64::INFINITY)
    } else {
        (sf / ff, (sf * (sf + ff)).sqrt() / ff.powf(1.5))
    };
    // The curve ends at the longest walk, not at the step limit: a limit of 10^12 steps that
    // no walker comes near costs nothing (survival is 0 beyond the longest walk).
    let longest = fates
        .iter()
        .map(|f| f.steps.min(max_steps))
        .max()
        .unwrap_or(0);
    let mut alive = vec![0usize; longest + 2];
    for f in fates {
        alive[f.steps.min(max_steps) + 1] += 1;
    }
    // survival[k] = #(T ≥ k) / N: counts of T = j summed from the top
    let mut survival = vec![0.0; longest + 1];
    let mut acc = 0usize;
    for k in (0..=longest).rev() {
        acc += alive[k + 1];
        survival[k] = acc as f64 / n.max(1) as f64;
    }
    let (rm, rse) = mean_and_stderr(fates.iter().map(|f| f.steps.min(max_steps) as f64));
    MfptEstimate {
        walkers: n,
        falls,
        censored: n - falls,
        total_steps: s,
        mfpt,
        stderr,
        restricted_mean: rm,
        restricted_stderr: rse,
        survival,
        failures: failure_counts(fates),
    }
}

/// Sample mean and its standard error (sample standard deviation over √n).
fn mean_and_stderr(v: impl Iterator<Item = f64> + Clone) -> (f64, f64) {
    let n = v.clone().count() as f64;
    if n == 0.0 {
        return (f64::NAN, f64::NAN);
    }
    let mean = v.clone().sum::<f64>() / n;
    let var = v.map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, (var / n).sqrt())
}

/// Falls counted by the outcome's name.
fn failure_counts(fates: &[Fate]) -> Vec<(String, usize)> {
    let mut m: BTreeMap<String, usize> = BTreeMap::new();
    for o in fates.iter().filter_map(|f| f.end) {
        *m.entry(o.to_string()).or_default() += 1;
    }
    m.into_iter().collect()
}

/// The section states (in the frame of the line each was reached on) of every heel strike of
/// `walkers` walkers from `x0`, at most `max_steps` each: the set a Markov chain's mesh must
/// cover ([`crate::markov`]). Projected with the mean slope's model (a section projection does
/// not depend on the slope).
pub fn visited(
    walk: &SlopeWalk,
    terrain: &SlopeTerrain,
    x0: &[f64],
    walkers: usize,
    max_steps: usize,
    pool: &rayon::ThreadPool,
) -> Result<Vec<Vec<f64>>, LimitError> {
    let base = walk.model(walk.mean())?;
    let per: Vec<Vec<Vec<f64>>> = pool.install(|| {
        (0..walkers)
            .into_par_iter()
            .map(|i| {
                let mut integ = walk.integrator(x0.len())?;
                let mut x = x0.to_vec();
                let mut out = Vec::new();
                for k in 0..max_steps {
                    let s = terrain.slope(i as u64, k as u64 + 1);
                    let st = walk.stride(&mut integ, &x, s)?;
                    walk.report(1);
                    if !st.outcome.is_ok() {
                        break;
                    }
                    let mut y = st.post.clone();
                    walk.shift(&mut y, walk.mean(), s);
                    let mut sec = vec![0.0; base.section_dim()];
                    base.project(&y, &mut sec);
                    out.push(sec);
                    x = st.post;
                }
                Ok(out)
            })
            .collect::<Result<_, LimitError>>()
    })?;
    Ok(per.into_iter().flatten().collect())
}
