//! The setup of a basin of attraction, written once for `pdw-sweep basin`, `pdw-sweep basin
//! --over` and Python's `basin`: the grid's axes resolved against the model's section (as given,
//! or the default box around the gait), the period-one gait search, the engine's options and
//! the attractor discovery over the box.
//!
//! A front end parses its syntax into a [`BasinRequest`], finds the gaits ([`find_gaits`]),
//! chooses the centre of the grid ([`grid_centre`]) and the box ([`choose_box`]), and gets a
//! [`BasinPlan`]: the grid's cells, the section state off its axes and the options, from which
//! it discovers the attractors ([`BasinPlan::attractors`]) and classifies the cells
//! ([`pdw_limit::basin::classify_cells`]). Files, progress and messages are the front end's.
//! Every basin labels a box through this plan, so the three agree cell for cell.

use crate::gaits::{model_guesses, Failed, Found};
use crate::input::{AxisRange, InputError};
use crate::model::BuiltModel;
use pdw_hybrid::Options;
use pdw_limit::basin::{grid_cells, linspace, BasinOptions};
use pdw_limit::{Attractor, AttractorKind, AttractorSet, FixedPoint, LimitError};
use pdw_walkers::ModelInfo;

/// Residual tolerance of the Newton search for the period-one gaits a basin starts from (on
/// the fixed-point search's integrator, [`pdw_limit::gaits::default_integrator`]).
pub const GAIT_NEWTON_TOL: f64 = 1e-12;

/// The names a front end gives the axes in its messages (`--x`/`--y`/`--z`, or `x`/`y`/`z`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisFlags {
    pub x: &'static str,
    pub y: &'static str,
    pub z: &'static str,
}

/// Z-levels at which attractor discovery seeds a 3-D box: the lattice of the 2-D box is laid
/// at this many evenly spaced values of z (every z of the grid when it has no more).
pub const DISCOVERY_Z_LEVELS: usize = 5;

/// An axis of the grid: a section coordinate (by index) over an inclusive range.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// Index of the coordinate in the model's section.
    pub index: usize,
    /// Its name and bounds.
    pub range: AxisRange,
}

/// The stride budget `n` as the engine's count, if it is one: 1 to 65535 (strides are counted
/// in 16 bits).
fn stride_budget(n: u32) -> Option<u16> {
    u16::try_from(n).ok().filter(|&k| k >= 1)
}

/// The stride budget per cell, checked: 1 to 65535; the message names `what` (`max_strides`).
pub fn check_max_strides(n: u32, what: &str) -> Result<u16, InputError> {
    stride_budget(n)
        .ok_or_else(|| InputError(format!("{what}: {n} must be between 1 and {}", u16::MAX)))
}

/// `--max-strides N` as clap's value parser: a whole number from 1 to 65535.
pub fn parse_max_strides(s: &str) -> Result<u16, InputError> {
    let n: u32 = s.trim().parse().map_err(|_| {
        InputError(format!(
            "'{s}' is not a whole number of strides (1 to {})",
            u16::MAX
        ))
    })?;
    stride_budget(n).ok_or_else(|| InputError(format!("{n} must be between 1 and {}", u16::MAX)))
}

/// Refuses a model whose section has fewer than two coordinates: a basin `what` (`grid`,
/// `box`) spans two.
pub fn check_section(info: &ModelInfo, what: &str) -> Result<(), InputError> {
    if info.section_names.len() < 2 {
        return Err(InputError(format!(
            "model '{}' has one section coordinate ({}); a basin {what} needs two",
            info.name,
            info.section_names.join(", ")
        )));
    }
    Ok(())
}

/// The axis `given` (if any) resolved against the model's section coordinates; its range must
/// be finite and increasing. Messages name `flag`.
pub fn resolve_axis(
    info: &ModelInfo,
    given: Option<AxisRange>,
    flag: &str,
) -> Result<Option<Axis>, InputError> {
    let Some(range) = given else { return Ok(None) };
    let names = &info.section_names;
    let index = names.iter().position(|n| *n == range.name).ok_or_else(|| {
        InputError(format!(
            "{flag}: model '{}' has no section coordinate '{}'; its coordinates are {}",
            info.name,
            range.name,
            names.join(", ")
        ))
    })?;
    let (lo, hi) = (range.lo, range.hi);
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(InputError(format!(
            "{flag}: range {lo}:{hi} is empty or inverted; the first bound must be below the second"
        )));
    }
    Ok(Some(Axis { index, range }))
}

/// Parameter overrides split into model parameters and section coordinates held fixed off the
/// grid's axes (an override named like a section coordinate, by index).
pub type SplitOverrides = (Vec<(String, f64)>, Vec<(usize, f64)>);

/// Splits `overrides` into model parameters and fixed section coordinates (see
/// [`SplitOverrides`]), each in the order given.
pub fn split_overrides(overrides: Vec<(String, f64)>, section_names: &[String]) -> SplitOverrides {
    let mut params = Vec::new();
    let mut fixed = Vec::new();
    for (n, v) in overrides {
        match section_names.iter().position(|s| *s == n) {
            Some(i) => fixed.push((i, v)),
            None => params.push((n, v)),
        }
    }
    (params, fixed)
}

/// What a basin is asked for, parsed and checked by the front end.
#[derive(Clone, Debug)]
pub struct BasinRequest {
    /// Cells along x and y.
    pub grid: (usize, usize),
    /// The axes given; the default box fills the others ([`default_axis`]).
    pub x: Option<Axis>,
    pub y: Option<Axis>,
    /// The third axis of a 3-D grid and its cells along it (`None`: a 2-D grid). It is never
    /// defaulted.
    pub z: Option<(Axis, usize)>,
    /// Section coordinates held fixed off the axes, by index.
    pub fixed: Vec<(usize, f64)>,
    /// Stride budget per cell.
    pub max_strides: u16,
    /// The cells' integrator.
    pub integrator: Options,
}

impl BasinRequest {
    /// Both axes given: the box does not depend on the gait.
    pub fn axes_given(&self) -> bool {
        self.x.is_some() && self.y.is_some()
    }

    /// The engine's options: the defaults of [`BasinOptions`] with this stride budget and
    /// integrator.
    pub fn options(&self) -> BasinOptions {
        BasinOptions {
            max_strides: self.max_strides,
            integrator: self.integrator,
            ..BasinOptions::default()
        }
    }
}

/// The period-one gaits found from the model's own guesses.
pub struct Gaits {
    pub found: Vec<Found>,
    pub failed: Vec<Failed>,
    /// Guesses tried.
    pub tried: usize,
}

impl Gaits {
    /// The selected gait (outcome code 0 of the grid): the first stable one found.
    pub fn stable(&self) -> Option<&FixedPoint> {
        self.found.iter().find(|f| f.fp.stable).map(|f| &f.fp)
    }

    /// The section state a grid centres on: the stable gait, else the first found.
    pub fn centre(&self) -> Option<&[f64]> {
        crate::gaits::selected(&self.found).map(|f| &f.fp.section[..])
    }
}

/// The period-one gaits of `m` by Newton from the model's guesses, to [`GAIT_NEWTON_TOL`].
pub fn find_gaits(m: &BuiltModel) -> Result<Gaits, LimitError> {
    let guesses = model_guesses(m.walker.as_ref());
    let (found, failed) = crate::gaits::search(m, &guesses, GAIT_NEWTON_TOL)?;
    Ok(Gaits {
        found,
        failed,
        tried: guesses.len(),
    })
}

/// The centre of a grid ([`pdw_limit::grid_centre`]): the gait of [`Gaits::centre`], else —
/// when both axes are given — the model's first guess; `None` when the default box needs a
/// gait and none was found.
pub fn grid_centre(m: &BuiltModel, gaits: &Gaits, axes_given: bool) -> Option<Vec<f64>> {
    pdw_limit::grid_centre(m.walker.as_ref(), &gaits.found, axes_given)
}

/// The default axis of coordinate `index` around `centre`: a half-width of 25 % of the
/// coordinate, at least 0.05. For the simplest walker at γ = 0.009 this gives
/// θ ∈ [0.150, 0.250], θ̇ ∈ [−0.250, −0.150].
pub fn default_axis(names: &[String], index: usize, centre: &[f64]) -> Axis {
    let c = centre[index];
    let half = (0.25 * c.abs()).max(0.05);
    Axis {
        index,
        range: AxisRange {
            name: names[index].clone(),
            lo: c - half,
            hi: c + half,
        },
    }
}

/// The box of section states a basin covers: two axes (three for a 3-D grid) and the cells
/// along each.
#[derive(Clone, Debug, PartialEq)]
pub struct BasinBox {
    pub x: Axis,
    pub y: Axis,
    pub nx: usize,
    pub ny: usize,
    /// The third axis of a 3-D grid.
    pub z: Option<Axis>,
    /// Cells along z: 1 for a 2-D grid.
    pub nz: usize,
}

impl BasinBox {
    /// The x values of the grid's columns (both bounds included).
    pub fn xs(&self) -> Vec<f64> {
        linspace(self.x.range.lo, self.x.range.hi, self.nx)
    }

    /// The y values of the grid's rows (both bounds included).
    pub fn ys(&self) -> Vec<f64> {
        linspace(self.y.range.lo, self.y.range.hi, self.ny)
    }

    /// The z values of a 3-D grid's slices (both bounds included); empty for a 2-D grid.
    pub fn zs(&self) -> Vec<f64> {
        self.z
            .as_ref()
            .map_or_else(Vec::new, |z| linspace(z.range.lo, z.range.hi, self.nz))
    }
}

/// The box of `req`: its axes, and the first two section coordinates around `centre` for those
/// not given ([`default_axis`]). Two axes on one coordinate are refused, as is a fixed
/// coordinate that is an axis (`what`: `grid` or `box`, for the message).
pub fn choose_box(
    req: &BasinRequest,
    names: &[String],
    centre: &[f64],
    flags: AxisFlags,
    what: &str,
) -> Result<BasinBox, InputError> {
    let x = req
        .x
        .clone()
        .unwrap_or_else(|| default_axis(names, 0, centre));
    let y = req
        .y
        .clone()
        .unwrap_or_else(|| default_axis(names, 1, centre));
    if x.index == y.index {
        return Err(InputError(format!(
            "{} and {} both name '{}'; choose two different coordinates",
            flags.x, flags.y, names[x.index]
        )));
    }
    let z = req.z.as_ref().map(|(z, _)| z.clone());
    if let Some(z) = &z {
        let other = [(&x, flags.x), (&y, flags.y)]
            .into_iter()
            .find(|(a, _)| a.index == z.index);
        if let Some((_, flag)) = other {
            return Err(InputError(format!(
                "{} names '{}', already the {flag} axis; choose a third coordinate",
                flags.z, names[z.index]
            )));
        }
    }
    let on_axis =
        |i: usize| i == x.index || i == y.index || z.as_ref().is_some_and(|z| z.index == i);
    if let Some((i, _)) = req.fixed.iter().find(|(i, _)| on_axis(*i)) {
        return Err(InputError(format!(
            "--set {}: that coordinate is an axis of the {what}",
            names[*i]
        )));
    }
    let (nx, ny) = req.grid;
    let nz = req.z.as_ref().map_or(1, |(_, n)| *n);
    Ok(BasinBox {
        x,
        y,
        nx,
        ny,
        z,
        nz,
    })
}

/// Everything a basin run computes from: the box and its grid values, the section state off
/// the axes, the gaits and the engine's options.
pub struct BasinPlan {
    pub bx: BasinBox,
    /// Column, row and slice values ([`BasinBox::xs`], [`BasinBox::ys`], [`BasinBox::zs`];
    /// `zs` empty for a 2-D grid).
    pub xs: Vec<f64>,
    pub ys: Vec<f64>,
    pub zs: Vec<f64>,
    /// The grid's centre ([`grid_centre`]).
    pub centre: Vec<f64>,
    /// Every cell's state off the two axes: the centre with the fixed coordinates applied.
    pub base: Vec<f64>,
    /// Section coordinates held fixed off the axes, by index.
    pub fixed: Vec<(usize, f64)>,
    pub gaits: Gaits,
    pub opts: BasinOptions,
}

impl BasinPlan {
    /// The plan of `req` on box `bx`, centred on `centre`, with the `gaits` found.
    pub fn new(req: &BasinRequest, bx: BasinBox, gaits: Gaits, centre: Vec<f64>) -> Self {
        let mut base = centre.clone();
        for (i, v) in &req.fixed {
            base[*i] = *v;
        }
        BasinPlan {
            xs: bx.xs(),
            ys: bx.ys(),
            zs: bx.zs(),
            bx,
            centre,
            base,
            fixed: req.fixed.clone(),
            gaits,
            opts: req.options(),
        }
    }

    /// The selected gait ([`Gaits::stable`]).
    pub fn gait(&self) -> Option<&FixedPoint> {
        self.gaits.stable()
    }

    /// Every attractor reached from the box ([`pdw_limit::box_attractors`]), each periodic one
    /// checked for physical validity ([`AttractorSet::check_validity`]), and the number of
    /// seeds tried.
    pub fn attractors(
        &self,
        m: &BuiltModel,
        pool: &rayon::ThreadPool,
    ) -> Result<(AttractorSet, usize), LimitError> {
        let (x, y) = (&self.bx.x, &self.bx.y);
        let levels = self.discovery_levels();
        let (mut set, seeds) = pdw_limit::box_attractors(
            m.walker.as_ref(),
            &self.gaits.found,
            self.gait(),
            &self.fixed,
            &self.base,
            (x.index, (x.range.lo, x.range.hi)),
            (y.index, (y.range.lo, y.range.hi)),
            self.bx.z.as_ref().map(|z| (z.index, &levels[..])),
            &self.opts,
            pool,
        )?;
        set.check_validity(m.walker.as_ref());
        Ok((set, seeds))
    }

    /// The z values a 3-D box's attractor discovery seeds at ([`DISCOVERY_Z_LEVELS`] evenly
    /// spaced over z, or every z of the grid); empty for a 2-D box.
    pub fn discovery_levels(&self) -> Vec<f64> {
        match &self.bx.z {
            Some(z) => linspace(z.range.lo, z.range.hi, self.bx.nz.min(DISCOVERY_Z_LEVELS)),
            None => Vec::new(),
        }
    }

    /// The start states of the cells of the grid's rows `rows`, row by row: row `k·ny + i` is
    /// `(z[k], y[i])` on a 3-D grid, row `i` is `y[i]` on a 2-D one.
    pub fn row_cells(&self, rows: &[usize]) -> Vec<Vec<f64>> {
        let ny = self.bx.ny;
        let mut cells = Vec::with_capacity(rows.len() * self.bx.nx);
        for &r in rows {
            let mut base = self.base.clone();
            if let Some(z) = &self.bx.z {
                base[z.index] = self.zs[r / ny];
            }
            let y = [self.ys[r % ny]];
            cells.extend(grid_cells(
                &base,
                self.bx.x.index,
                &self.xs,
                self.bx.y.index,
                &y,
            ));
        }
        cells
    }

    /// The start states of the cells of the rows at `row_ys`, row by row.
    pub fn cells(&self, row_ys: &[f64]) -> Vec<Vec<f64>> {
        grid_cells(
            &self.base,
            self.bx.x.index,
            &self.xs,
            self.bx.y.index,
            row_ys,
        )
    }

    /// How far the gait is from a fixed point of the cells' stride map, when more than a tenth
    /// of the gait tolerance: the gait was found on an accurate map, and cells that converge to
    /// a point the classifier does not recognise come out `other` or `timeout`.
    pub fn gait_drift(&self, m: &BuiltModel) -> Result<Option<f64>, LimitError> {
        let Some(fp) = self.gait() else {
            return Ok(None);
        };
        crate::integrator::gait_drift(m, self.opts.integrator, &fp.section, self.opts.tol_gait)
    }
}

/// A periodic attractor that converges too slowly for the stride budget.
#[derive(Clone, Copy, Debug)]
pub struct SlowAttractor<'a> {
    pub attractor: &'a Attractor,
    /// |λ| of its slowest multiplier (per `period_k` strides).
    pub modulus: f64,
    /// Strides a cell near it needs.
    pub strides: f64,
}

/// The periodic attractors of `set` whose cells need more than `max_strides` strides: a
/// perturbation of 1e-2 shrinks below the engine's 1e-6 gait tolerance after
/// K·ln(1e-4)/ln|λ| strides at the slowest multiplier λ of the K-stride map. Near a
/// bifurcation (|λ| → 1) cells that do converge are labelled `timeout`.
pub fn slow_attractors(set: &AttractorSet, max_strides: u16) -> Vec<SlowAttractor<'_>> {
    set.attractors
        .iter()
        .filter(|at| at.kind == AttractorKind::Periodic)
        .filter_map(|at| {
            let modulus = at.multipliers.first()?.modulus();
            let strides = (at.period_k as f64 * (1e-4f64).ln() / modulus.ln()).ceil();
            (modulus < 1.0 && strides > f64::from(max_strides)).then_some(SlowAttractor {
                attractor: at,
                modulus,
                strides,
            })
        })
        .collect()
}

/// An attractor in a basin file's plain form (as `pdw-sweep basin` and the explorer's saved
/// windows store it): `period_strides` 0 and no multipliers for a chaotic one, whose `section` is
/// a sample of points on it.
pub fn store_attractor(a: &Attractor) -> pdw_store::Attractor {
    use pdw_limit::OrbitValidity;
    use pdw_store::OrbitCheck;
    pdw_store::Attractor {
        name: a.name.clone(),
        period_strides: a.period_k as u32,
        period_time: a.period_time,
        section: a.points.clone(),
        multipliers: a.multipliers.iter().map(|l| (l.re, l.im)).collect(),
        validity: match &a.validity {
            OrbitValidity::Unchecked => OrbitCheck::Unchecked,
            OrbitValidity::Valid => OrbitCheck::Valid,
            OrbitValidity::Invalid(r) => {
                OrbitCheck::Invalid(r.iter().map(|s| s.to_string()).collect())
            }
        },
    }
}

/// The grid a basin file covers: its axes' coordinates and values (a CLI run's box, or an
/// explorer's window).
pub struct FileGrid {
    pub x: (String, Vec<f64>),
    pub y: (String, Vec<f64>),
    pub z: Option<pdw_store::ZAxis>,
}

/// The basin file's header of a run on `m` under `plan`, the attractors `set` found from
/// `seeds` seeds, on `grid`: the one header of every basin file, whichever front end writes it
/// (`pdw-sweep basin`, the explorer's saved window), so that all carry the same fields.
/// `model` is the model's name, `command` what made the file, `shard` the shard it holds.
pub fn file_header(
    (command, model): (String, String),
    m: &BuiltModel,
    plan: &BasinPlan,
    (set, seeds): (&AttractorSet, usize),
    grid: FileGrid,
    shard: Option<pdw_store::ShardSpec>,
) -> pdw_store::BasinHeader {
    let (opts, names) = (&plan.opts, &m.info.section_names);
    let disc = pdw_limit::attractors::DiscoveryOptions::default();
    let fixed: std::collections::BTreeMap<String, f64> = plan
        .fixed
        .iter()
        .map(|(i, v)| (names[*i].clone(), *v))
        .collect();
    pdw_store::BasinHeader {
        command,
        model,
        slope: m.slope(),
        params: m.params_json().to_string(),
        model_resolved: m.walker.fingerprint(),
        integrator: crate::integrator_text(&opts.integrator),
        tolerances: serde_json::json!({
            "rtol": opts.integrator.rtol, "atol": opts.integrator.atol,
            "tol_gait": opts.tol_gait, "tol_recur": opts.tol_recur,
            "confirm": opts.confirm, "max_period": opts.max_period,
            "fixed_point_residual": plan.gait().map(|fp| fp.residual),
            "attractor_seeds": seeds, "seed_strides": disc.seed_strides,
            "chaos_radius": disc.chaos_radius, "chaos_sample": disc.cloud_points,
            "fixed": fixed,
        })
        .to_string(),
        max_strides: u32::from(opts.max_strides),
        x_name: grid.x.0,
        x: grid.x.1,
        y_name: grid.y.0,
        y: grid.y.1,
        z: grid.z,
        state_names: names.clone(),
        legend: set.legend(),
        shard,
    }
}

/// The units of a basin file of `m` whose grid runs along the section coordinates `axes`
/// (x, y and, for a 3-D grid, z): what [`pdw_store::format::BASIN`]'s unit rules resolve
/// against.
pub fn file_units(m: &BuiltModel, axes: &[usize]) -> pdw_store::format::UnitContext {
    pdw_store::format::UnitContext {
        section: crate::model::section_units(m),
        axes: axes.to_vec(),
        ..Default::default()
    }
}
