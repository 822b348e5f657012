//! A curve of period doublings or folds of the period-one gait in two parameters
//! ([`pdw_limit::codim2`]): the stepped parameter takes N values A..B, the free one is solved
//! for at each. The plan ([`FollowPlan`]) holds the checked choices; the steps are
//!
//! 1. [`start_gait`]: the period-one gait at the stepped parameter's first value A and the
//!    model's value of the free parameter (Newton from the user's guess or the model's presets
//!    there; failing that, the gait at the model's own values continued in the stepped
//!    parameter to A);
//! 2. [`locate_start`]: one-parameter pseudo-arclength continuation of that gait in the free
//!    parameter (within its domain, up first, then down) to its first bifurcation of the kind
//!    followed, located there;
//! 3. [`curve`]: the two-parameter curve through it over the N values
//!    ([`pdw_limit::follow_curve`], a minimally augmented system);
//! 4. [`region_map`]: what the stride map does on a grid of the plane under the curve
//!    ([`pdw_limit::region_map`]).

use crate::input::{InputError, Sweep};
use crate::model::{build_with, BuiltModel, ModelChoice};
use pdw_hybrid::Options;
use pdw_limit::{
    continue_branch, find_fixed_point, follow_curve, BifurcationKind, Codim2Kind, Codim2Options,
    ContinuationOptions, Curve, CurveStart, LimitError, NewtonOptions, Region, RegionOptions,
    StrideMap,
};

/// Which gait the curve starts from when several are found at the start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GaitChoice {
    Stable,
    Unstable,
    /// The stable one if there is one, else the first found.
    Any,
}

impl GaitChoice {
    /// `stable`, `unstable` or `all` (the CLI's `--gait`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "stable" => Some(Self::Stable),
            "unstable" => Some(Self::Unstable),
            "all" => Some(Self::Any),
            _ => None,
        }
    }
}

/// A checked two-parameter curve run.
pub struct FollowPlan {
    /// The model and its overrides; the two parameters are set on top.
    pub model: ModelChoice,
    pub kind: Codim2Kind,
    /// The stepped parameter and its N values A..B.
    pub step: Sweep,
    /// The free parameter's name.
    pub free: String,
    /// Its domain: the curve ends where it leaves it.
    pub free_range: (f64, f64),
    /// The domain as given by the user (`None`: [`default_free_range`]); the region map's
    /// vertical range, else [`auto_range`].
    pub free_given: Option<(f64, f64)>,
    /// The model's own values of the free and the stepped parameter.
    pub free_own: f64,
    pub step_own: f64,
    /// The user's guess (section coordinates, checked against the model's section).
    pub guess: Option<Vec<f64>>,
    pub gait: GaitChoice,
    /// Newton tolerance of the gait search.
    pub tol: f64,
    pub integrator: Options,
}

impl FollowPlan {
    /// The model at stepped value `ps` and free value `pf`.
    pub fn model_at(&self, ps: f64, pf: f64) -> Result<BuiltModel, InputError> {
        build_with(
            &self.model,
            &[(self.step.name.clone(), ps), (self.free.clone(), pf)],
        )
    }

    /// Every corner of the plane (the ends of both ranges) makes a model; the error names the
    /// failing corner.
    pub fn check_corners(&self) -> Result<(), InputError> {
        let (s, (lo, hi)) = (&self.step, self.free_range);
        for (ps, pf) in [(s.lo, lo), (s.lo, hi), (s.hi, lo), (s.hi, hi)] {
            self.model_at(ps, pf).map_err(|e| {
                InputError(format!(
                    "{e} (at {} = {ps}, {} = {pf}: the corners of --sweep and --free must be \
                     valid parameter values)",
                    s.name, self.free
                ))
            })?;
        }
        Ok(())
    }
}

/// The free parameter's domain when none is given: a quarter to four times the model's
/// value `own` (a slope at most 1.2 rad); `None` when `own` is not positive.
pub fn default_free_range(name: &str, own: f64) -> Option<(f64, f64)> {
    if own <= 0.0 {
        return None;
    }
    let hi = 4.0 * own;
    let hi = if name == "slope" { hi.min(1.2) } else { hi };
    Some((0.25 * own, hi))
}

/// Why no gait was found to start from: the failed Newton runs at A and at the model's own
/// values (empty there when a gait exists but its continuation to A failed).
pub struct NoStartGait {
    pub at_start: String,
    pub at_own: String,
}

/// Step 1: the period-one gait at `(A, free_own)` (`m_a`), from the guesses there, else the
/// gait of `m_own` (the model's own values) continued in the stepped parameter to A.
pub fn start_gait(
    plan: &FollowPlan,
    m_a: &BuiltModel,
    m_own: &BuiltModel,
) -> Result<Result<Vec<f64>, NoStartGait>, LimitError> {
    let (direct, at_start) = pick_gait(plan, m_a)?;
    if let Some(s) = direct {
        return Ok(Ok(s));
    }
    let (own, at_own) = pick_gait(plan, m_own)?;
    match own.and_then(|s0| transfer_to_start(plan, m_a, &s0)) {
        Some(s) => Ok(Ok(s)),
        None => Ok(Err(NoStartGait { at_start, at_own })),
    }
}

/// The gait of the plan's choice found by Newton on `m`, with the failed guesses as text.
fn pick_gait(plan: &FollowPlan, m: &BuiltModel) -> Result<(Option<Vec<f64>>, String), LimitError> {
    let guesses = match &plan.guess {
        Some(g) => vec![("guess".to_string(), g.clone())],
        None => pdw_limit::gaits::model_guesses(m.walker.as_ref()),
    };
    let (found, failed) =
        crate::gaits::search_with(m, &guesses, plan.tol.max(1e-12), &plan.integrator)?;
    let f = match plan.gait {
        GaitChoice::Unstable => found.iter().find(|f| !f.fp.stable),
        GaitChoice::Stable => found.iter().find(|f| f.fp.stable),
        GaitChoice::Any => found.iter().find(|f| f.fp.stable).or_else(|| found.first()),
    };
    let why = failed
        .iter()
        .map(|(l, _, e)| format!("guess '{l}': {e}"))
        .collect::<Vec<_>>()
        .join("; ");
    Ok((f.map(|f| f.fp.section.clone()), why))
}

/// The gait `s0` at the model's own stepped value continued (natural parameter, no detection)
/// to A, and corrected there by Newton on `m_a`'s stride map.
fn transfer_to_start(plan: &FollowPlan, m_a: &BuiltModel, s0: &[f64]) -> Option<Vec<f64>> {
    let (name, own, a) = (&plan.step.name, plan.step_own, plan.step.lo);
    let others: Vec<(String, f64)> = m_a
        .params
        .iter()
        .filter(|(n, _)| n != name)
        .cloned()
        .collect();
    let fam = |ps: f64| {
        let mut ov = others.clone();
        ov.push((name.clone(), ps));
        build_with(&plan.model, &ov).map(|m| m.walker)
    };
    let mut c = ContinuationOptions::new(own.min(a), own.max(a));
    c.integrator = plan.integrator;
    c.detect = false;
    c.direction = (a - own).signum();
    let span = (a - own).abs().max(1e-12);
    c.ds_max = span / 20.0;
    c.ds_init = span / 200.0;
    c.ds_min = span * 1e-9;
    let br = continue_branch(&fam, s0, own, 1, &c).ok()?;
    let near = br
        .points
        .iter()
        .min_by(|p, q| (p.param - a).abs().total_cmp(&(q.param - a).abs()))?;
    let map = StrideMap::new(&*m_a.walker, plan.integrator).ok()?;
    let opts = NewtonOptions {
        tol: plan.tol.max(1e-12),
        ..NewtonOptions::default()
    };
    find_fixed_point(&map, &near.section, &opts)
        .ok()
        .map(|fp| fp.section)
}

/// The one-parameter continuation of step 2, as run: its options and either the bifurcation
/// found or how each direction ended (`up: …`, `down: …`).
pub struct StartSearch {
    pub options: ContinuationOptions,
    pub found: Result<pdw_limit::Bifurcation, Vec<String>>,
}

/// Step 2: the first bifurcation of the plan's kind on the branch of `gait` in the free
/// parameter at A, searched up and then down from the model's value.
pub fn locate_start(plan: &FollowPlan, gait: &[f64]) -> StartSearch {
    let (lo, hi) = plan.free_range;
    let fam = |pf: f64| plan.model_at(plan.step.lo, pf).map(|m| m.walker);
    let mut copts = ContinuationOptions::new(lo, hi);
    copts.integrator = plan.integrator;
    copts.stop_at = Some(match plan.kind {
        Codim2Kind::PeriodDoubling => BifurcationKind::PeriodDoubling,
        Codim2Kind::Fold => BifurcationKind::Fold,
    });
    copts.ds_max = (hi - lo) / 100.0;
    copts.ds_init = copts.ds_max / 10.0;
    copts.ds_min = (hi - lo) * 1e-9;
    copts.max_points = 5000;
    copts.locate_tol = 1e-10 * plan.free_own.abs().max(1.0);
    let mut ends = Vec::new();
    for dir in [1.0, -1.0] {
        copts.direction = dir;
        let name = if dir > 0.0 { "up" } else { "down" };
        match continue_branch(&fam, gait, plan.free_own, 1, &copts) {
            Ok(br) => {
                let stop = copts.stop_at;
                if let Some(b) = br.bifurcations.iter().find(|b| Some(b.kind) == stop) {
                    return StartSearch {
                        found: Ok(b.clone()),
                        options: copts,
                    };
                }
                ends.push(format!("{name}: {}", br.end));
            }
            Err(e) => ends.push(format!("{name}: {e}")),
        }
    }
    StartSearch {
        options: copts,
        found: Err(ends),
    }
}

/// Step 3: the curve through `bif` over the N stepped values, with its options.
pub fn curve(
    plan: &FollowPlan,
    bif: &pdw_limit::Bifurcation,
) -> Result<(Codim2Options, Curve), LimitError> {
    let steps = pdw_limit::basin::linspace(plan.step.lo, plan.step.hi, plan.step.n);
    let (lo, hi) = plan.free_range;
    let mut o2 = Codim2Options::new(lo, hi);
    o2.integrator = plan.integrator;
    o2.newton_tol = plan.tol.max(1e-11);
    let fam = |ps: f64, pf: f64| plan.model_at(ps, pf).map(|m| m.walker);
    let c = follow_curve(
        &fam,
        plan.kind,
        &CurveStart::from_bifurcation(bif),
        &steps,
        &o2,
    )?;
    Ok((o2, c))
}

/// The free-parameter range of the map when the user gives none: the curve's range, widened
/// by a quarter of its width or a fifth of its middle value (whichever is larger) on each
/// side, within the domain `lo..hi`.
pub fn auto_range(c: &Curve, lo: f64, hi: f64) -> (f64, f64) {
    let (a, b) = c
        .points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(x, y), p| {
            (x.min(p.p_free), y.max(p.p_free))
        });
    let pad = (0.25 * (b - a)).max(0.2 * (0.5 * (a + b)).abs());
    ((a - pad).max(lo), (b + pad).min(hi))
}

/// The region map of step 4: the grid's stepped and free values and each cell's region
/// (`region[i][j]` at `step[i]`, `free[j]`).
pub struct RegionGrid {
    pub step: Vec<f64>,
    pub free: Vec<f64>,
    pub region: Vec<Vec<Region>>,
}

/// Step 4: the region map on `nx × ny` cells over the stepped range and the free range
/// (the user's, else [`auto_range`]), every column starting from the curve's gait at the
/// nearest curve point. `progress` is told of every finished column of each of its two
/// passes. The curve must have points.
pub fn region_map(
    plan: &FollowPlan,
    curve: &Curve,
    (nx, ny): (usize, usize),
    ropts: &RegionOptions,
    pool: &rayon::ThreadPool,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<RegionGrid, LimitError> {
    let (lo, hi) = plan.free_range;
    let (f0, f1) = plan.free_given.unwrap_or_else(|| auto_range(curve, lo, hi));
    let step = pdw_limit::basin::linspace(plan.step.lo, plan.step.hi, nx);
    let free = pdw_limit::basin::linspace(f0, f1, ny);
    let hints: Vec<(Vec<f64>, f64)> = step
        .iter()
        .map(|&ps| {
            let p = curve
                .points
                .iter()
                .min_by(|p, q| (p.p_step - ps).abs().total_cmp(&(q.p_step - ps).abs()))
                .expect("the curve has points");
            (p.section.clone(), p.p_free)
        })
        .collect();
    let fam = |ps: f64, pf: f64| plan.model_at(ps, pf).map(|m| m.walker);
    let region = pdw_limit::region_map(&fam, &step, &free, &hints, ropts, pool, progress)?;
    Ok(RegionGrid { step, free, region })
}

/// The long name of a curve's kind in messages and titles.
pub fn kind_long(k: Codim2Kind) -> &'static str {
    match k {
        Codim2Kind::PeriodDoubling => "period-doubling",
        Codim2Kind::Fold => "fold",
    }
}

/// How a front end names the curve's inputs in its messages: the flags (`--sweep`, `--free`,
/// `--follow`; Python's `sweep`, `free`, `kind`) and how a range of the free parameter and a
/// value of a parameter are given.
pub struct FollowFlags {
    pub kind: &'static str,
    pub sweep: &'static str,
    pub free: &'static str,
    /// How to give parameter `name` a range, e.g. `--free slope=LO:HI`.
    pub free_range_hint: fn(&str) -> String,
    /// How to set parameter `name` to a value, e.g. `--set slope=VALUE or --slope`.
    pub set_hint: fn(&str) -> String,
}

/// The curve's kind by name: `pd` (period doubling) or `fold`.
pub fn parse_kind(kind: &str, flag: &str) -> Result<Codim2Kind, InputError> {
    match kind {
        "pd" => Ok(Codim2Kind::PeriodDoubling),
        "fold" => Ok(Codim2Kind::Fold),
        "ns" => Err(InputError(format!(
            "{flag} ns: not supported: Neimark-Sacker curves (a complex pair of multipliers on \
             the unit circle) are not implemented; {flag} takes pd or fold"
        ))),
        other => Err(InputError(format!(
            "{flag}: '{other}' is not one of pd (period doubling), fold"
        ))),
    }
}

/// The free parameter of a curve: its name and its domain (if given).
#[derive(Clone, Debug, PartialEq)]
pub struct Free {
    pub name: String,
    pub range: Option<(f64, f64)>,
}

/// `NAME` or `NAME=LO:HI` (a slope in any angle unit, e.g. `slope=2deg:8deg`).
pub fn parse_free(s: &str, flag: &str) -> Result<Free, InputError> {
    let Some((name, range)) = s.split_once('=') else {
        let name = s.trim();
        if name.is_empty() {
            return Err(InputError(format!("{flag}: empty parameter name")));
        }
        return Ok(Free {
            name: name.to_string(),
            range: None,
        });
    };
    let name = name.trim().to_string();
    let Some((lo, hi)) = range.split_once(':') else {
        return Err(InputError(format!(
            "{flag}: '{s}' is not of the form NAME or NAME=LO:HI (e.g. slope=2deg:8deg)"
        )));
    };
    let conv = |t: &str| {
        if name == "slope" {
            crate::input::parse_slope_for(t, &format!("{flag} slope"))
        } else {
            crate::input::parse_f64(t, &format!("{flag} {name}"))
        }
    };
    let (lo, hi) = (conv(lo)?, conv(hi)?);
    if lo >= hi {
        return Err(InputError(format!(
            "{flag}: range {lo}:{hi} is empty or inverted; LO must be below HI"
        )));
    }
    Ok(Free {
        name,
        range: Some((lo, hi)),
    })
}

fn value_of(m: &BuiltModel, name: &str) -> Option<f64> {
    m.params.iter().find(|(n, _)| n == name).map(|p| p.1)
}

fn unknown(m: &BuiltModel, flag: &str, name: &str) -> InputError {
    InputError(format!(
        "{flag}: model '{}' has no parameter '{name}'; its parameters are {}",
        m.info.name,
        m.params
            .iter()
            .map(|(n, _)| n.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    ))
}

/// The free parameter's domain: the range given, else [`default_free_range`] around the
/// model's value `free_own`, which must lie inside (the one-parameter search starts there).
pub fn free_domain(
    free: &Free,
    free_own: f64,
    flags: &FollowFlags,
) -> Result<(f64, f64), InputError> {
    let (lo, hi) = match free.range {
        Some(r) => r,
        None => default_free_range(&free.name, free_own).ok_or_else(|| {
            InputError(format!(
                "{} {}: the model's value {free_own} is not positive, so there is no default \
                 range; give one: {}",
                flags.free,
                free.name,
                (flags.free_range_hint)(&free.name)
            ))
        })?,
    };
    if !(lo..=hi).contains(&free_own) {
        return Err(InputError(format!(
            "{} {}={lo}:{hi}: the model's value {free_own} (where the one-parameter search \
             starts) lies outside; set it inside with {}",
            flags.free,
            free.name,
            (flags.set_hint)(&free.name)
        )));
    }
    Ok((lo, hi))
}

/// The plan of a curve of `kind` with `step` stepped and `free` solved for, from `model` at
/// its own values (returned too): both parameters exist and differ, the free domain holds the
/// model's value. The guess is unset and the integrator DOP853 at 1e-13; a front end sets
/// either before [`start_model`].
#[allow(clippy::too_many_arguments)]
pub fn plan(
    model: ModelChoice,
    kind: Codim2Kind,
    step: Sweep,
    free: &Free,
    gait: GaitChoice,
    tol: f64,
    flags: &FollowFlags,
) -> Result<(FollowPlan, BuiltModel), InputError> {
    if free.name == step.name {
        return Err(InputError(format!(
            "{} {} and {} {}: the same parameter; the curve needs two different parameters \
             (one stepped, one solved for)",
            flags.free, free.name, flags.sweep, step.name
        )));
    }
    let m_own = crate::model::build_model(&model)?;
    let step_own =
        value_of(&m_own, &step.name).ok_or_else(|| unknown(&m_own, flags.sweep, &step.name))?;
    let free_own =
        value_of(&m_own, &free.name).ok_or_else(|| unknown(&m_own, flags.free, &free.name))?;
    let (lo, hi) = free_domain(free, free_own, flags)?;
    let plan = FollowPlan {
        model,
        kind,
        step,
        free: free.name.clone(),
        free_range: (lo, hi),
        free_given: free.range,
        free_own,
        step_own,
        guess: None,
        gait,
        tol,
        integrator: Options::dop853(1e-13),
    };
    Ok((plan, m_own))
}

/// The checks made before computing: every corner of the plane is a model
/// ([`FollowPlan::check_corners`]), the user's guess (`flag` names it) fits the section at the
/// start, which becomes the plan's guess; returns the model at `(A, free_own)`.
pub fn start_model(
    plan: &mut FollowPlan,
    guess: Option<Vec<f64>>,
    flag: &str,
) -> Result<BuiltModel, InputError> {
    plan.check_corners()?;
    let m_a = plan.model_at(plan.step.lo, plan.free_own)?;
    if guess.is_some() {
        let g = crate::gaits::guesses(&m_a, guess, flag)?;
        plan.guess = g.into_iter().next().map(|(_, v)| v);
    }
    Ok(m_a)
}

/// Why no gait was found to start the curve from, in words.
pub fn no_gait_message(plan: &FollowPlan, m_a: &BuiltModel, why: &NoStartGait) -> String {
    let (name, a_val) = (&plan.step.name, plan.step.lo);
    format!(
        "no period-one gait of model '{}' at {name} = {a_val} to start from (Newton there: {}; \
         at the model's own {name} = {}: {})",
        m_a.info.name,
        why.at_start,
        plan.step_own,
        if why.at_own.is_empty() {
            "a gait exists but its continuation to A failed"
        } else {
            why.at_own.as_str()
        }
    )
}

/// Why no bifurcation of the plan's kind was found on the start gait's branch, in words
/// (`ends`: how each direction of [`locate_start`] ended).
pub fn no_bifurcation_message(plan: &FollowPlan, ends: &[String]) -> String {
    let (lo, hi) = plan.free_range;
    format!(
        "no {} of the period-one gait on {} in [{lo}, {hi}] at {} = {} (the branch from {} = {} \
         ended {})",
        kind_long(plan.kind),
        plan.free,
        plan.step.name,
        plan.step.lo,
        plan.free,
        plan.free_own,
        ends.join("; ")
    )
}

/// How a lost curve ended, in words (`None` for a complete one); the points reached are kept.
pub fn lost_message(plan: &FollowPlan, curve: &Curve) -> Option<String> {
    let pdw_limit::CurveEnd::Lost {
        last,
        tried,
        reason,
    } = &curve.end
    else {
        return None;
    };
    Some(format!(
        "the {} curve was lost {} (the step to {} = {tried} failed even at 1/256 of the \
         spacing): {reason}",
        kind_long(plan.kind),
        match last {
            Some(l) => format!("after {} = {l}", plan.step.name),
            None => format!("at its start, {} = {}", plan.step.name, plan.step.lo),
        },
        plan.step.name,
    ))
}
