//! The mean first-passage time (MFPT) on random terrain, written once for `pdw-sweep mfpt` (and
//! the Python package to come): the request's checks, the model at any slope, the walkers'
//! start (the stable period-one gait of the mean slope, just after a heel strike) and the Monte
//! Carlo run ([`pdw_limit::terrain`], which documents the convention and the estimator).

use crate::gaits::{model_guesses, no_gait_message, search};
use crate::input::{self, InputError};
use crate::model::BuiltModel;
use crate::output::{number, Format, Planned};
use pdw_hybrid::Options;
use pdw_limit::markov::{ChainResult, Frame, SectionBox};
use pdw_limit::mid_stance;
use pdw_limit::terrain::{
    self, Fate, MfptEstimate, SlopeTerrain, SlopeWalk, TerrainDist, TerrainKind,
};
use pdw_limit::LimitError;
use pdw_walkers::Walker;
use std::path::Path;

/// Residual tolerance of the gait the walkers start from.
pub const GAIT_TOL: f64 = 1e-12;

/// The largest magnitude a Box–Muller draw of [`terrain::standard_normal`] can reach:
/// `√(−2 ln u)` with `u ≥ 2⁻⁵⁴`, i.e. `√(108 ln 2)` ≈ 8.65 ([`TerrainDist::max_abs`] of the
/// other distributions).
pub const MAX_DRAW: f64 = terrain::MAX_NORMAL_DRAW;

/// The distributions `--dist` names (besides `file:PATH`).
pub const DISTS: &[&str] = &["normal", "uniform", "file:PATH"];

/// The terrains `--terrain` names.
pub const TERRAINS: &[&str] = &["slope", "step-down"];

/// A Monte Carlo MFPT run: the terrain, how many walkers, how many strides (heel strikes) at
/// most per walker, the integrator of the strides and whether they are integrated at all.
#[derive(Clone, Debug, PartialEq)]
pub struct MfptPlan {
    pub terrain: SlopeTerrain,
    pub walkers: usize,
    /// Strides at most per walker (the files' `max_steps`); a walker still walking then is
    /// censored.
    pub max_strides: usize,
    pub integrator: Options,
    pub stride_map: StrideMap,
}

/// How the Monte Carlo walkers' strides are computed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StrideMap {
    /// In closed form where the model has one ([`Walker::closed_stride`]: the rimless wheel),
    /// integrated otherwise.
    #[default]
    Auto,
    /// In closed form ([`terrain::monte_carlo_closed_form`]); refused for a model without one.
    ClosedForm,
    /// Integrated with [`MfptPlan::integrator`], in batched lockstep ([`terrain::monte_carlo`]).
    Integrated,
}

/// The stride maps `--stride-map` names.
pub const STRIDE_MAPS: &[&str] = &["auto", "closed-form", "integrated"];

impl StrideMap {
    /// The stride map as typed: `auto`, `closed-form` or `integrated`.
    pub fn parse(s: &str, flag: &str) -> Result<Self, InputError> {
        match s.trim() {
            "auto" => Ok(StrideMap::Auto),
            "closed-form" => Ok(StrideMap::ClosedForm),
            "integrated" => Ok(StrideMap::Integrated),
            t => Err(InputError(format!(
                "{flag}: '{t}' is not one of {}",
                STRIDE_MAPS.join(", ")
            ))),
        }
    }

    /// Whether the strides of `m` are taken in closed form; [`InputError`] for
    /// [`StrideMap::ClosedForm`] on a model without one.
    pub fn closed_form(self, m: &BuiltModel, flag: &str) -> Result<bool, InputError> {
        let has = m.walker.closed_stride().is_some();
        match self {
            StrideMap::Auto => Ok(has),
            StrideMap::Integrated => Ok(false),
            StrideMap::ClosedForm if has => Ok(true),
            StrideMap::ClosedForm => Err(InputError(format!(
                "{flag}: the model {} has no stride map in closed form (only the rimless \
                 wheel has); use auto or integrated",
                m.walker.name()
            ))),
        }
    }

    /// How the strides of `m` were computed, for reports and files: `closed form` or
    /// `integrated`.
    pub fn describe(self, m: &BuiltModel) -> &'static str {
        match self.closed_form(m, "") {
            Ok(true) => "closed form",
            _ => "integrated",
        }
    }
}

/// The names a front end gives the options in its messages.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MfptFlags {
    pub terrain: &'static str,
    pub sd: &'static str,
    pub mean: &'static str,
    pub walkers: &'static str,
    /// The stride limit's name ([`MfptPlan::max_strides`]: `--max-strides`, `max_strides`).
    pub max_steps: &'static str,
    pub dist: &'static str,
}

/// The default integrator: the basin's (DOP853 at 1e-9, [`pdw_limit::BasinOptions`]), the
/// per-stride speed and accuracy of a basin's cell.
pub fn default_integrator() -> Options {
    pdw_limit::BasinOptions::default_integrator()
}

/// The terrain's name checked: `slope` or `step-down` ([`TerrainKind`]).
pub fn check_terrain(name: &str, flags: &MfptFlags) -> Result<TerrainKind, InputError> {
    parse_terrain(name, flags.terrain)
}

/// The terrain kind named `name` (`slope` or `step-down`); anything else is refused naming
/// `flag`.
pub fn parse_terrain(name: &str, flag: &str) -> Result<TerrainKind, InputError> {
    if name == TerrainKind::Slope.name() {
        Ok(TerrainKind::Slope)
    } else if name == TerrainKind::StepDown.name() {
        Ok(TerrainKind::StepDown)
    } else {
        Err(InputError(format!(
            "{flag}: '{name}' is not one of {}",
            TERRAINS.join(", ")
        )))
    }
}

/// Every file `mfpt --out OUT` writes, in the order written: the HDF5 file, the MFPT picture
/// `OUT.png` and, over a parameter (`over`), the MFPT-against-GSN picture `OUT-gsn.png`. The
/// claim and the writers both take the paths from here.
pub fn output_files(out: &Path, over: bool) -> Vec<Planned> {
    let mut files = vec![
        Planned {
            flag: "--out",
            path: out.to_path_buf(),
            format: Format::Hdf5,
        },
        Planned {
            flag: "--out (its PNG)",
            path: out.with_extension("png"),
            format: Format::Png,
        },
    ];
    if over {
        let stem = out.file_stem().and_then(|s| s.to_str()).unwrap_or("mfpt");
        files.push(Planned {
            flag: "--out (its GSN PNG)",
            path: out.with_file_name(format!("{stem}-gsn.png")),
            format: Format::Png,
        });
    }
    files
}

/// The file `--dist file:PATH` reads, if it names one (an input of the run: never written).
pub fn dist_input(dist: &str) -> Option<&Path> {
    dist.trim()
        .strip_prefix("file:")
        .filter(|p| !p.is_empty())
        .map(Path::new)
}

/// The terrain distribution as typed: `normal`, `uniform` or `file:PATH` ([`TerrainDist`];
/// a file is read by [`read_values`]).
pub fn parse_dist(s: &str, flags: &MfptFlags) -> Result<TerrainDist, InputError> {
    match s.trim() {
        "normal" => Ok(TerrainDist::Normal),
        "uniform" => Ok(TerrainDist::Uniform),
        t => match t.strip_prefix("file:") {
            Some(path) if !path.is_empty() => read_values(path, flags),
            _ => Err(InputError(format!(
                "{}: '{s}' is not one of {}",
                flags.dist,
                DISTS.join(", ")
            ))),
        },
    }
}

/// The values of a distribution file: one number per line, blank lines and everything after
/// a `#` ignored; at least one value, every value finite.
pub fn read_values(path: &str, flags: &MfptFlags) -> Result<TerrainDist, InputError> {
    let text = pdw_store::read_text_input(Path::new(path), pdw_store::MAX_TEXT_INPUT)
        .map_err(|e| InputError(format!("{}: {e}", flags.dist)))?;
    let mut values = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let v = line.split('#').next().unwrap_or("").trim();
        if v.is_empty() {
            continue;
        }
        match v.parse::<f64>() {
            Ok(x) if x.is_finite() => values.push(x),
            _ => {
                return Err(InputError(format!(
                    "{}: '{path}' line {}: '{v}' is not a finite number (one value per line, \
                     '#' starts a comment)",
                    flags.dist,
                    i + 1
                )))
            }
        }
    }
    TerrainDist::values(path, values).map_err(|e| InputError(format!("{}: {e}", flags.dist)))
}

/// The slope's standard deviation as typed (radians, or `1deg`): finite and ≥ 0.
pub fn parse_sd(s: &str, flags: &MfptFlags) -> Result<f64, InputError> {
    let v = input::parse_slope_for(s, flags.sd)?;
    if v < 0.0 {
        return Err(InputError(format!(
            "{}: '{s}' must be >= 0 (a standard deviation)",
            flags.sd
        )));
    }
    Ok(v)
}

/// A step height's standard deviation as typed: a plain number in the model's length unit,
/// finite and ≥ 0.
pub fn parse_height_sd(s: &str, flags: &MfptFlags) -> Result<f64, InputError> {
    let v = parse_height(s, flags.sd)?;
    if v < 0.0 {
        return Err(InputError(format!(
            "{}: '{s}' must be >= 0 (a standard deviation)",
            flags.sd
        )));
    }
    Ok(v)
}

/// A step height as typed: a plain finite number in the model's length unit.
pub fn parse_height(s: &str, flag: &str) -> Result<f64, InputError> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| {
            InputError(format!(
                "{flag}: '{s}' is not a height (a plain number in the model's length unit; a \
                 step down positive)"
            ))
        })
}

/// `--sd A:B:N`: `N ≥ 2` standard deviations evenly spaced from `A` to `B` (each end in radians
/// or with a unit, as [`parse_sd`] takes it; `0 ≤ A < B`); a plain `--sd` is one value.
pub fn parse_sd_values(s: &str, flags: &MfptFlags) -> Result<Vec<f64>, InputError> {
    parse_sd_values_for(s, TerrainKind::Slope, flags)
}

/// [`parse_sd_values`] for terrain `kind`: step heights' ends are plain lengths
/// ([`parse_height_sd`]).
pub fn parse_sd_values_for(
    s: &str,
    kind: TerrainKind,
    flags: &MfptFlags,
) -> Result<Vec<f64>, InputError> {
    let one = |v: &str| match kind {
        TerrainKind::Slope => parse_sd(v, flags),
        TerrainKind::StepDown => parse_height_sd(v, flags),
    };
    let parts: Vec<&str> = s.split(':').collect();
    match parts.as_slice() {
        [v] => Ok(vec![one(v)?]),
        [a, b, n] => {
            let (lo, hi) = (one(a)?, one(b)?);
            let n: usize = n.trim().parse().ok().filter(|&n| n >= 2).ok_or_else(|| {
                InputError(format!(
                    "{}: '{s}': the count '{n}' must be an integer >= 2",
                    flags.sd
                ))
            })?;
            if lo >= hi {
                return Err(InputError(format!(
                    "{}: '{s}': the first value must be below the last",
                    flags.sd
                )));
            }
            Ok((0..n)
                .map(|i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
                .collect())
        }
        _ => Err(InputError(format!(
            "{}: '{s}' is neither a standard deviation (1deg) nor a range A:B:N (0.5deg:3deg:11)",
            flags.sd
        ))),
    }
}

/// Refuses zero walkers or strides, and a terrain whose slopes could leave (−π/2, π/2) (the mean
/// plus [`MAX_DRAW`] standard deviations).
pub fn check_plan(plan: &MfptPlan, flags: &MfptFlags) -> Result<(), InputError> {
    for (v, flag) in [
        (plan.walkers, flags.walkers),
        (plan.max_strides, flags.max_steps),
    ] {
        if v == 0 {
            return Err(InputError(format!("{flag}: 0 must be an integer >= 1")));
        }
    }
    let t = &plan.terrain;
    let reach = t.dist.max_abs();
    if t.kind == TerrainKind::Slope && t.mean.abs() + reach * t.sd >= std::f64::consts::FRAC_PI_2 {
        return Err(InputError(format!(
            "{} {} rad with {} {} rad: slopes up to {} standard deviations from the mean \
             are drawn ({} {}) and must stay within (-pi/2, pi/2) rad",
            flags.sd,
            number(t.sd),
            flags.mean,
            number(t.mean),
            number(reach),
            flags.dist,
            t.dist.name()
        )));
    }
    Ok(())
}

/// Refuses a model that cannot walk on terrain of kind `kind`: on random slopes a model
/// without a frame change or a tilted landing line ([`Walker::on_tilted_line`]: round feet
/// walk one walker at a time), a model without a `step_down` parameter on step heights.
pub fn check_model_for(m: &BuiltModel, kind: TerrainKind) -> Result<(), InputError> {
    match kind {
        TerrainKind::Slope if tilted(m) => Ok(()),
        TerrainKind::Slope => check_model(m),
        TerrainKind::StepDown if m.params.iter().any(|p| p.0 == "step_down") => Ok(()),
        TerrainKind::StepDown => Err(InputError(format!(
            "model '{}' cannot walk on random step heights yet: it has no step_down parameter \
             (the built-in models and every walker spec have one)",
            m.info.name
        ))),
    }
}

/// Refuses a step-height terrain whose draws (up to [`MAX_DRAW`] standard deviations from the
/// mean) the model does not take, with the model's reason (e.g. a step beyond a spoke's reach).
pub fn check_heights(m: &BuiltModel, plan: &MfptPlan, flags: &MfptFlags) -> Result<(), InputError> {
    let t = &plan.terrain;
    if t.kind != TerrainKind::StepDown {
        return Ok(());
    }
    let at = model_at_param(m, "step_down");
    let reach = t.dist.max_abs();
    for h in [t.mean - reach * t.sd, t.mean + reach * t.sd] {
        if let Err(e) = at(h) {
            return Err(InputError(format!(
                "{} {} with a mean step down of {}: step heights up to {} standard \
                 deviations from the mean are drawn, and the model refuses {}: {}",
                flags.sd,
                number(t.sd),
                number(t.mean),
                number(reach),
                number(h),
                limit_message(&e)
            )));
        }
    }
    Ok(())
}

/// A model error's message without the parameter value the limit error adds.
fn limit_message(e: &LimitError) -> String {
    match e {
        LimitError::Model { message, .. } => message.clone(),
        other => other.to_string(),
    }
}

/// Whether `m` walks random slopes on tilted landing lines ([`Walker::on_tilted_line`]; round
/// feet): its stride depends on the last line's slope too, so it has the Monte Carlo walk and
/// the single disturbance but no Markov chain on its section and no gait sensitivity norm.
pub fn tilted(m: &BuiltModel) -> bool {
    m.walker.terrain_frame().is_none()
        && pdw_limit::terrain::tilted_frame(m.walker.as_ref()).is_some()
}

/// Refuses a model whose stride on random slopes is not a function of the landing slope alone
/// (round feet), for what needs one: the gait sensitivity norm, `--over`, the Markov chain.
pub fn check_model(m: &BuiltModel) -> Result<(), InputError> {
    if m.walker.terrain_frame().is_some() {
        return Ok(());
    }
    Err(InputError(format!(
        "model '{}' has no stride of one landing slope: with round feet the stance foot rolls on \
         the last line while the swing foot lands on the next, so a stride depends on both \
         slopes; its Monte Carlo walk and single disturbances run (pdw-sweep mfpt without \
         --chain or --over), the Markov chain and the gait sensitivity norm on random slopes \
         need point feet (foot_radius=0)",
        m.info.name
    )))
}

/// Refuses the Markov chain where its states do not hold the walk's: round feet on random
/// slopes ([`check_model`]); `flag` names the request.
pub fn check_chain_terrain(
    m: &BuiltModel,
    kind: TerrainKind,
    flag: &str,
) -> Result<(), InputError> {
    match kind {
        TerrainKind::Slope => check_model(m).map_err(|e| InputError(format!("{flag}: {}", e.0))),
        TerrainKind::StepDown => Ok(()),
    }
}

/// The model of `m` at any slope: its parameter values with only `slope` replaced, built by
/// the registry (a model error names the slope).
pub fn model_at(m: &BuiltModel) -> impl Fn(f64) -> Result<Box<dyn Walker>, LimitError> + Sync + '_ {
    model_at_param(m, "slope")
}

/// The model of `m` with parameter `param` (`slope`, `step_down`) set to any value.
pub fn model_at_param<'a>(
    m: &'a BuiltModel,
    param: &str,
) -> impl Fn(f64) -> Result<Box<dyn Walker>, LimitError> + Sync + 'a {
    let values: Vec<f64> = m.params.iter().map(|p| p.1).collect();
    let index = m.params.iter().position(|p| p.0 == param);
    move |s| {
        let mut v = values.clone();
        if let Some(i) = index {
            v[i] = s;
        }
        m.info.build_from(&v).map_err(|e| LimitError::Model {
            param: s,
            message: e.to_string(),
        })
    }
}

/// The walkers' first state: the stable period-one gait of `m` (built at the mean slope) from
/// its own guesses, as the full state just after a heel strike, with its section coordinates.
pub fn start(m: &BuiltModel) -> Result<(Vec<f64>, Vec<f64>), InputError> {
    let guesses = model_guesses(m.walker.as_ref());
    let (found, failed) = search(m, &guesses, GAIT_TOL).map_err(|e| InputError(e.to_string()))?;
    match found.iter().find(|f| f.fp.stable) {
        Some(g) => Ok((g.fp.state.clone(), g.fp.section.clone())),
        None => Err(InputError(format!(
            "{}; the walkers start from the stable gait of the mean slope",
            no_gait_message(m, "stable", guesses.len(), &failed)
        ))),
    }
}

/// The walk of `plan`'s terrain for the model at any value of its terrain parameter.
pub fn walk_of<'a>(
    at: &'a (dyn Fn(f64) -> Result<Box<dyn Walker>, LimitError> + Sync),
    plan: &MfptPlan,
) -> Result<SlopeWalk<'a>, LimitError> {
    SlopeWalk::with_kind(at, plan.terrain.kind, plan.terrain.mean, plan.integrator)
}

/// The Monte Carlo run: every walker from `x0` on its own terrain, and the estimate.
pub fn run(
    m: &BuiltModel,
    plan: &MfptPlan,
    x0: &[f64],
    pool: &rayon::ThreadPool,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<(Vec<Fate>, MfptEstimate), LimitError> {
    let at = model_at_param(m, plan.terrain.kind.param());
    let walk = walk_of(&at, plan)?;
    let closed = plan
        .stride_map
        .closed_form(m, "stride map")
        .map_err(|e| LimitError::Model {
            param: plan.terrain.mean,
            message: e.0,
        })?;
    let mc = if closed {
        terrain::monte_carlo_closed_form
    } else {
        terrain::monte_carlo
    };
    let fates = mc(
        &walk,
        &plan.terrain,
        x0,
        plan.walkers,
        plan.max_strides,
        pool,
        progress,
    )?;
    let est = terrain::estimate(&fates, plan.max_strides);
    Ok((fates, est))
}

/// A Markov-chain MFPT ([`pdw_limit::markov`]): Gauss–Hermite nodes of the slope, mesh nodes
/// per section axis, and the box (`None`: the box the Monte Carlo walkers visit, padded).
#[derive(Clone, Debug, PartialEq)]
pub struct ChainPlan {
    pub nodes: usize,
    pub mesh: usize,
    pub bounds: Option<(Vec<f64>, Vec<f64>)>,
    pub section: ChainSection,
    pub layout: ChainMesh,
}

/// Where the chain's nodes lie.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ChainMesh {
    /// A regular grid over the box the walkers visit ([`pdw_limit::markov::Mesh`]).
    #[default]
    Grid,
    /// The visited states thinned to the grid's spacing, closed under the chain's own landings
    /// ([`pdw_limit::cloud`]); mid-stance section only.
    Cloud,
}

impl ChainMesh {
    /// The names `--chain-mesh` takes.
    pub const NAMES: &'static [&'static str] = &["grid", "cloud"];

    /// The layout's name in commands and files.
    pub fn name(self) -> &'static str {
        match self {
            ChainMesh::Grid => "grid",
            ChainMesh::Cloud => "cloud",
        }
    }
}

/// `plan` with its nodes laid out as `name` says ([`ChainMesh::NAMES`]), or an error naming
/// `flag`: a name not in the list, or a cloud on the section just after heel strike (its
/// layers would need one cloud per terrain node; the cloud is built for the mid-stance
/// section).
pub fn check_layout(plan: ChainPlan, name: &str, flag: &str) -> Result<ChainPlan, InputError> {
    let layout = match name.trim() {
        "grid" => ChainMesh::Grid,
        "cloud" => ChainMesh::Cloud,
        t => {
            return Err(InputError(format!(
                "{flag}: '{t}' is not one of {}",
                ChainMesh::NAMES.join(", ")
            )))
        }
    };
    if layout == ChainMesh::Cloud && plan.section != ChainSection::MidStance {
        return Err(InputError(format!(
            "{flag}: a cloud is built on the mid-stance section only; add the section \
             mid-stance, or use the grid"
        )));
    }
    Ok(ChainPlan { layout, ..plan })
}

/// The section the chain's states lie on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ChainSection {
    /// Just after a heel strike, one layer of the mesh per terrain node (the state remembers
    /// the line it landed on; [`pdw_limit::markov`]).
    #[default]
    Landing,
    /// At mid-stance, the stance leg vertical: one mesh, no layers
    /// ([`pdw_limit::mid_stance`]); one-mode models only.
    MidStance,
}

impl ChainSection {
    /// The names `--chain-section` takes.
    pub const NAMES: &'static [&'static str] = &["landing", "mid-stance"];

    /// The section's name in commands and files.
    pub fn name(self) -> &'static str {
        match self {
            ChainSection::Landing => "landing",
            ChainSection::MidStance => "mid-stance",
        }
    }

    /// The section named `s` ([`ChainSection::NAMES`]), or an error naming `flag`.
    pub fn parse(s: &str, flag: &str) -> Result<Self, InputError> {
        match s.trim() {
            "landing" => Ok(ChainSection::Landing),
            "mid-stance" => Ok(ChainSection::MidStance),
            t => Err(InputError(format!(
                "{flag}: '{t}' is not one of {}",
                Self::NAMES.join(", ")
            ))),
        }
    }
}

/// Walkers and steps of the Monte Carlo pass that finds the visited box, and its padding (a
/// fraction of each side's range).
pub const BOX_WALKERS: usize = 200;
pub const BOX_STEPS: usize = 200;
pub const BOX_PAD: f64 = 0.1;

/// The section states the walkers of `plan` visit (the first [`BOX_WALKERS`] walkers, at most
/// [`BOX_STEPS`] steps each) and the start's section state.
pub fn visited_points(
    m: &BuiltModel,
    plan: &MfptPlan,
    x0: &[f64],
    pool: &rayon::ThreadPool,
    progress: &Progress,
) -> Result<(Vec<Vec<f64>>, Vec<f64>), LimitError> {
    let at = model_at_param(m, plan.terrain.kind.param());
    let walk = walk_of(&at, plan)?.with_progress(progress);
    let pts = terrain::visited(&walk, &plan.terrain, x0, BOX_WALKERS, BOX_STEPS, pool)?;
    let mut s0 = vec![0.0; m.info.section_names.len()];
    m.walker.project(x0, &mut s0);
    Ok((pts, s0))
}

/// The box (section coordinates) the walkers of `plan` visit ([`visited_points`]), padded by
/// [`BOX_PAD`] of its range on each side.
pub fn visited_box(
    m: &BuiltModel,
    plan: &MfptPlan,
    x0: &[f64],
    pool: &rayon::ThreadPool,
) -> Result<(Vec<f64>, Vec<f64>), LimitError> {
    let (pts, s0) = visited_points(m, plan, x0, pool, &|_| {})?;
    Ok(padded(Frame::identity(s0.len()).bounds(&pts, &s0)))
}

/// The walkers' principal frame ([`Frame::principal`] of the points [`visited_points`]
/// returns) and the box they fill in it, padded by [`BOX_PAD`] of its range on each side.
pub fn visited_frame(
    m: &BuiltModel,
    plan: &MfptPlan,
    x0: &[f64],
    pool: &rayon::ThreadPool,
    progress: &Progress,
) -> Result<(Frame, SectionBox), LimitError> {
    let (mut pts, s0) = visited_points(m, plan, x0, pool, progress)?;
    pts.push(s0.clone());
    let frame = Frame::principal(&pts, s0.len());
    let bounds = padded(frame.bounds(&pts, &frame.to_frame(&s0)));
    Ok((frame, bounds))
}

/// The walkers' principal frame and padded box on the mid-stance section
/// ([`pdw_limit::mid_stance::visited`]: the first [`BOX_WALKERS`] walkers, at most
/// [`BOX_STEPS`] transitions each, from the start's first mid-stance).
pub fn mid_stance_frame(
    m: &BuiltModel,
    plan: &MfptPlan,
    x0: &[f64],
    pool: &rayon::ThreadPool,
    progress: &Progress,
) -> Result<(Frame, SectionBox), LimitError> {
    let (_, frame, bounds) =
        mid_stance_points(m, plan, x0, (BOX_WALKERS, BOX_STEPS), pool, progress)?;
    Ok((frame, bounds))
}

/// The mid-stance states of the first `walkers` walkers of `plan` (at most `steps` transitions
/// each, from the start's first mid-stance, which comes first), their principal frame and
/// their box in it, padded by [`BOX_PAD`].
pub fn mid_stance_points(
    m: &BuiltModel,
    plan: &MfptPlan,
    x0: &[f64],
    (walkers, steps): (usize, usize),
    pool: &rayon::ThreadPool,
    progress: &Progress,
) -> Result<(Vec<Vec<f64>>, Frame, SectionBox), LimitError> {
    let at = model_at_param(m, plan.terrain.kind.param());
    let walk = walk_of(&at, plan)?.with_progress(progress);
    let sense = mid_stance::sweep_sense(walk.model(walk.mean())?.as_ref(), walk.kind(), x0)?;
    let pts = mid_stance::visited(&walk, &plan.terrain, x0, sense, walkers, steps, pool)?;
    let Some(first) = pts.first() else {
        return Err(LimitError::Model {
            param: plan.terrain.mean,
            message: "the start falls before its first mid-stance".into(),
        });
    };
    let frame = Frame::principal(&pts, first.len());
    let bounds = padded(frame.bounds(&pts, &frame.to_frame(first)));
    Ok((pts, frame, bounds))
}

/// `(lo, hi)` padded by [`BOX_PAD`] of its range on each side.
fn padded((mut lo, mut hi): SectionBox) -> SectionBox {
    for (l, h) in lo.iter_mut().zip(hi.iter_mut()) {
        let pad = BOX_PAD * (*h - *l).max(1e-9);
        *l -= pad;
        *h += pad;
    }
    (lo, hi)
}

/// Told how many more strides a chain's maps and walks have run, as they run (a progress bar;
/// called from the pool's threads): [`pdw_limit::terrain::SlopeWalk::with_progress`].
pub type Progress<'a> = dyn Fn(usize) + Sync + 'a;

/// The terrain nodes `(s_l, w_l)` (slopes or step heights) of an `n`-point quadrature of
/// `plan`'s terrain distribution ([`TerrainDist::quadrature`]: Gauss–Hermite for normals,
/// Gauss–Legendre for uniforms, a list's empirical distribution).
pub fn terrain_nodes(plan: &MfptPlan, n: usize) -> Vec<(f64, f64)> {
    let t = &plan.terrain;
    let (z, w) = t.dist.quadrature(n);
    z.iter()
        .zip(&w)
        .map(|(z, w)| (t.mean + t.sd * z, *w))
        .collect()
}

/// Nodes per axis of the coarse meshes of [`chain_box`] (by section dimension) and its passes.
pub const HULL_MESH: [usize; 3] = [40, 10, 5];
pub const HULL_PASSES: usize = 4;

/// The chain's box and how it was chosen.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainBox {
    /// The frame the mesh is regular in: the walkers' principal axes ([`visited_frame`]).
    pub frame: Frame,
    /// The mesh's box, in `frame`'s coordinates.
    pub bounds: SectionBox,
    /// Widening passes of [`pdw_limit::markov::landing_hull`] (0: the walkers' box kept).
    pub passes: usize,
    /// Share of the absorption that was landings outside the walkers' box (on the coarse
    /// mesh), the reason to widen it.
    pub out_share: f64,
}

/// The share of absorption above which the walkers' box is widened ([`chain_box`]): box exits
/// below it bias the MFPT by less than the mesh-refinement tolerance [`REFINEMENT_MAX`], while
/// widening costs resolution — the widened box holds the landings of every node, also of the
/// nodes about to fall, which fling far (the compass at 3°, σ = 0.2°: 1.0 % box exits on the
/// walkers' box; widened 4 passes, the chain gave 8.4 / 28 steps at mesh 12 / 24 against
/// 45 / 93 unwidened and the walkers' 137).
pub const OUT_SHARE_MAX: f64 = REFINEMENT_MAX;

/// The chain's box: the box the walkers visit along their principal axes ([`visited_frame`]:
/// the states walkers visit often lie along an oblique band, see
/// [`pdw_limit::section_frame`]); where more than
/// [`OUT_SHARE_MAX`] of the chain's absorption on it is landings outside it (the rare falls of
/// a small σ start far outside the box a short run visits), that box widened by
/// [`pdw_limit::markov::landing_hull`] until it holds the landings of its own nodes on every
/// slope node. Not widened otherwise: a wider box is a coarser mesh.
pub fn chain_box(
    m: &BuiltModel,
    plan: &MfptPlan,
    chain: &ChainPlan,
    x0: &[f64],
    pool: &rayon::ThreadPool,
    progress: &Progress,
) -> Result<ChainBox, LimitError> {
    let (frame, visited) = match chain.section {
        ChainSection::Landing => visited_frame(m, plan, x0, pool, progress)?,
        ChainSection::MidStance => mid_stance_frame(m, plan, x0, pool, progress)?,
    };
    let r = chain_in(m, plan, chain, &frame, &visited, x0, pool, progress)?;
    let absorbed = r.out_of_mesh + r.fall_per_step;
    let out_share = if absorbed > 0.0 {
        r.out_of_mesh / absorbed
    } else {
        0.0
    };
    if out_share <= OUT_SHARE_MAX {
        return Ok(ChainBox {
            frame,
            bounds: visited,
            passes: 0,
            out_share,
        });
    }
    let at = model_at_param(m, plan.terrain.kind.param());
    let walk = walk_of(&at, plan)?.with_progress(progress);
    let d = visited.0.len();
    let per_axis = HULL_MESH[d.clamp(1, 3) - 1];
    let slopes = terrain_nodes(plan, chain.nodes);
    let (bounds, passes) = match chain.section {
        ChainSection::Landing => pdw_limit::markov::landing_hull(
            &walk,
            &slopes,
            &frame,
            visited,
            per_axis,
            HULL_PASSES,
            pool,
        )?,
        ChainSection::MidStance => {
            let sense =
                mid_stance::sweep_sense(walk.model(walk.mean())?.as_ref(), walk.kind(), x0)?;
            pdw_limit::markov::widen_box(&frame, visited, per_axis, HULL_PASSES, &|mesh| {
                mid_stance::landings(&walk, &slopes, mesh, sense, pool)
            })?
        }
    };
    Ok(ChainBox {
        frame,
        bounds,
        passes,
        out_share,
    })
}

/// The chain's MFPT from `x0` on `chain`'s mesh over `bounds` (section coordinates).
pub fn chain(
    m: &BuiltModel,
    plan: &MfptPlan,
    chain: &ChainPlan,
    bounds: &(Vec<f64>, Vec<f64>),
    x0: &[f64],
    pool: &rayon::ThreadPool,
) -> Result<pdw_limit::markov::ChainResult, LimitError> {
    let frame = Frame::identity(bounds.0.len());
    chain_in(m, plan, chain, &frame, bounds, x0, pool, &|_| {})
}

/// The chain's MFPT from `x0` on `chain`'s mesh over `bounds`, a box of `frame`'s coordinates;
/// `progress` told the strides as they run ([`Progress`]).
#[allow(clippy::too_many_arguments)]
pub fn chain_in(
    m: &BuiltModel,
    plan: &MfptPlan,
    chain: &ChainPlan,
    frame: &Frame,
    bounds: &SectionBox,
    x0: &[f64],
    pool: &rayon::ThreadPool,
    progress: &Progress,
) -> Result<pdw_limit::markov::ChainResult, LimitError> {
    use pdw_limit::markov;
    let at = model_at_param(m, plan.terrain.kind.param());
    // the chain's strides as the walkers': in closed form where `--stride-map` takes them so
    let closed = plan
        .stride_map
        .closed_form(m, "stride map")
        .unwrap_or(false);
    let walk = walk_of(&at, plan)?
        .with_progress(progress)
        .with_closed_form(closed);
    let slopes = terrain_nodes(plan, chain.nodes);
    let mesh = markov::Mesh {
        lo: bounds.0.clone(),
        hi: bounds.1.clone(),
        n: chain.mesh,
        frame: frame.clone(),
    };
    let tr = match chain.section {
        ChainSection::Landing => markov::transitions(&walk, &slopes, &mesh, x0, pool)?,
        ChainSection::MidStance => {
            let sense =
                mid_stance::sweep_sense(walk.model(walk.mean())?.as_ref(), walk.kind(), x0)?;
            mid_stance::transitions(&walk, &slopes, &mesh, x0, sense, pool)?
        }
    };
    // the solve's products run on the pool
    Ok(pool.install(|| markov::solve_chain(&tr)))
}

/// Relative change of the chain's MFPT between two meshes above which [`refinement_warning`]
/// warns.
pub const REFINEMENT_MAX: f64 = 0.1;

/// `|fine − coarse| / max(fine, coarse)` of the two meshes' MFPTs (0 where both are 0, 1
/// where one is not finite).
pub fn refinement_change(coarse: &ChainResult, fine: &ChainResult) -> f64 {
    let (a, b) = (coarse.mfpt, fine.mfpt);
    if !(a.is_finite() && b.is_finite()) {
        return 1.0;
    }
    let top = a.abs().max(b.abs());
    if top == 0.0 {
        0.0
    } else {
        (a - b).abs() / top
    }
}

/// A warning when the chain's MFPT changes by more than [`REFINEMENT_MAX`] from the mesh of
/// `n` nodes per axis to the finer one: the mesh does not resolve where the walkers fall (a
/// basin thinner than the mesh spacing hands probability to falling nodes by interpolation),
/// and the chain's number is not an answer.
pub fn refinement_warning(coarse: &ChainResult, fine: &ChainResult, n: usize) -> Option<String> {
    let c = refinement_change(coarse, fine);
    (c > REFINEMENT_MAX).then(|| {
        format!(
            "WARNING: the chain's MFPT changed by {:.0} % from mesh {n} to mesh {} ({:.4e} to \
             {:.4e}): not converged in the mesh — the mesh does not resolve where the walkers \
             fall, and neither number is the MFPT; refine --mesh until two meshes agree, or use \
             the Monte Carlo",
            100.0 * c,
            2 * n,
            coarse.mfpt,
            fine.mfpt
        )
    })
}

/// A warning when the chain's MFPT on its finer mesh (`fine`; `coarse` on the mesh half as
/// fine) and the walkers' restricted mean (none censored) disagree by more than 3 of the
/// walkers' standard errors plus what the mesh refinement moved the chain: the chain then
/// carries a discretisation error its own refinement does not show — the terrain quadrature's
/// (the simplest walker on step heights, docs/cli.md) or a mesh too coarse — and the walkers
/// are the reference. `nodes_flag` names the quadrature's option in the caller's words. `None`
/// where they agree, a walker was censored (the restricted mean is then not the MFPT), or an
/// MFPT is not finite.
pub fn agreement_warning(
    coarse: f64,
    fine: f64,
    est: &MfptEstimate,
    nodes_flag: &str,
) -> Option<String> {
    if est.censored > 0 || !(coarse.is_finite() && fine.is_finite()) {
        return None;
    }
    let (mc, se) = (est.restricted_mean, est.restricted_stderr);
    let allowed = 3.0 * se + (fine - coarse).abs();
    ((fine - mc).abs() > allowed).then(|| {
        format!(
            "WARNING: the chain's MFPT {fine:.4} (finer mesh) and the walkers' {mc:.4} ± {se:.4} \
             differ by {:.1} standard errors, more than the mesh refinement moved the chain \
             ({:.4}): a discretisation error of the terrain quadrature ({nodes_flag}) or of the \
             mesh; where both run the walkers are the reference",
            (fine - mc).abs() / se.max(f64::MIN_POSITIVE),
            (fine - coarse).abs()
        )
    })
}

/// [`agreement_warning`] of a chain's MFPTs as an MFPT file keeps them, by name (`mfpt_coarse`,
/// `mfpt_fine`); `None` without them (no chain was run).
pub fn chain_agreement_warning(
    chain: &[(String, f64)],
    est: &MfptEstimate,
    nodes_flag: &str,
) -> Option<String> {
    let get = |k: &str| chain.iter().find(|(n, _)| n == k).map(|(_, v)| *v);
    agreement_warning(get("mfpt_coarse")?, get("mfpt_fine")?, est, nodes_flag)
}

/// The terrain distribution in words, for reports and files: its name, and for a list of
/// values how many there are, their mean and standard deviation.
pub fn dist_words(d: &TerrainDist) -> String {
    match d {
        TerrainDist::Normal => "normal".into(),
        TerrainDist::Uniform => "uniform on [-sqrt 3, sqrt 3] (variance 1)".into(),
        TerrainDist::Values(v) => {
            let n = v.values.len() as f64;
            let mean = v.values.iter().sum::<f64>() / n;
            let var = v.values.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
            // six decimals, or six significant digits where that would be a long decimal
            let six = |x: f64| {
                if x.abs() >= 1e6 {
                    format!("{x:.6e}")
                } else {
                    format!("{x:.6}")
                }
            };
            format!(
                "{} ({} values, mean {}, sd {}; each step draws one with equal probability, \
                 scaled by sd)",
                d.name(),
                v.values.len(),
                six(mean),
                six(var.sqrt())
            )
        }
    }
}

/// The name of the chain's quadrature of `d` ([`TerrainDist::quadrature`]).
pub fn quadrature_name(d: &TerrainDist) -> &'static str {
    match d {
        TerrainDist::Normal => "Gauss-Hermite",
        TerrainDist::Uniform => "Gauss-Legendre",
        TerrainDist::Values(_) => "empirical",
    }
}

/// The names a front end gives the chain's options in its messages.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChainFlags {
    pub chain: &'static str,
    pub mesh: &'static str,
    pub nodes: &'static str,
    pub section: &'static str,
}

/// A warning when a terrain node of the chain's rule (`nodes` of `plan`'s distribution) sits at a
/// step height of exactly 0: there the model is level ground, whose heel-strike rule is the step
/// model's limit from below only, and a walker's map can change sharply for the smallest steps
/// down — the simplest walker's chain gives 11.80 with 11 nodes against 11.21 with 12 (its
/// walkers 10.73 ± 0.11, experiments/cli-measurements.md). `None` on slopes, with no node at 0, or without spread.
pub fn zero_height_node_warning(plan: &MfptPlan, nodes: usize, flag: &str) -> Option<String> {
    let t = &plan.terrain;
    if t.kind != TerrainKind::StepDown || t.sd <= 0.0 {
        return None;
    }
    let at_zero = terrain_nodes(plan, nodes)
        .iter()
        .any(|(v, w)| *v == 0.0 && *w > 0.0);
    at_zero.then(|| {
        format!(
            "WARNING: {flag} {nodes} puts a node of the terrain's rule at a step height of exactly \
             0, where the model is level ground (the step model's limit from below only); a \
             walker whose map changes sharply for the smallest steps down gets a biased chain \
             there (the simplest walker: 11.80 with 11 nodes against 11.21 with 12) — prefer \
             an even {flag} on step heights of mean 0"
        )
    })
}

/// Default quadrature nodes of the chain.
pub const DEFAULT_NODES: usize = 11;

/// Most quadrature nodes a chain takes: twice the 40 that converge the rimless wheel's chain
/// at σ = 0.5° (within 0.4 % of 80 at mesh 200), so that [`quadrature_check`]'s advice to
/// double them can be followed.
pub const MAX_NODES: usize = 80;

/// The chain's plan for `m` on `section`, checked: `mesh` nodes per axis (default by the
/// section's dimension: 200, 60, 12 just after heel strike; 200, 60, 24 at mid-stance, which
/// has no layers; at least 2), `nodes` quadrature nodes (2 … [`MAX_NODES`], default [`DEFAULT_NODES`]);
/// refused for a section of more than 3 coordinates, and at mid-stance for a model without it
/// ([`pdw_limit::mid_stance::unsupported`]).
pub fn check_chain(
    m: &BuiltModel,
    mesh: Option<usize>,
    nodes: Option<usize>,
    section: ChainSection,
    flags: &ChainFlags,
) -> Result<ChainPlan, InputError> {
    let d = match section {
        ChainSection::Landing => m.info.section_names.len(),
        ChainSection::MidStance => {
            if let Some(why) = pdw_limit::mid_stance::unsupported(m.walker.as_ref()) {
                return Err(InputError(format!("{}: {why}", flags.section)));
            }
            m.walker.dim() - 1
        }
    };
    let default = match (d, section) {
        (1, _) => 200,
        (2, _) => 60,
        (3, ChainSection::Landing) => 12,
        (3, ChainSection::MidStance) => 24,
        _ => {
            return Err(InputError(format!(
                "{}: model '{}' has {d} coordinates on the {} section; the mesh is built for at \
                 most 3",
                flags.chain,
                m.info.name,
                section.name()
            )))
        }
    };
    let mesh = mesh.unwrap_or(default);
    if mesh < 2 {
        return Err(InputError(format!(
            "{}: {mesh} must be at least 2",
            flags.mesh
        )));
    }
    let nodes = nodes.unwrap_or(DEFAULT_NODES);
    if !(2..=MAX_NODES).contains(&nodes) {
        return Err(InputError(format!(
            "{}: {nodes} must be between 2 and {MAX_NODES} (one node is the mean terrain alone: \
             deterministic ground, on which the chain sees no fall and has no MFPT)",
            flags.nodes
        )));
    }
    Ok(ChainPlan {
        nodes,
        mesh,
        bounds: None,
        section,
        layout: ChainMesh::Grid,
    })
}

/// Fixed allowance of an MFPT run beyond what scales with its request: the model, the thread
/// pool's batches of lanes, the visited box's walkers ([`BOX_WALKERS`] × [`BOX_STEPS`]) and
/// HDF5's buffers.
const MFPT_BASE_BYTES: u64 = 96 << 20;

/// Estimated peak memory (bytes) of the Monte Carlo walkers of `plan`: every walker's fate is
/// kept until the estimate is made; the lanes in flight are a fixed batch per thread. The
/// survival curve is sized by the longest walk ([`terrain::estimate`]), not by the stride limit,
/// so `max_strides` does not enter.
pub fn walkers_memory(plan: &MfptPlan) -> u64 {
    crate::memory::bytes(plan.walkers as u64, std::mem::size_of::<Fate>() as u64)
        .saturating_add(MFPT_BASE_BYTES)
}

/// The chain's states on its finer mesh (twice `chain.mesh` nodes per axis, the larger of the
/// two chains it solves) with `d` section coordinates: one layer of the mesh per terrain node on
/// the landing section, one mesh at mid-stance; saturating.
pub fn chain_states(chain: &ChainPlan, d: usize) -> u64 {
    let fine = (2 * chain.mesh as u64).saturating_pow(d as u32);
    let layers = match chain.section {
        ChainSection::Landing => chain.nodes as u64,
        ChainSection::MidStance => 1,
    };
    fine.saturating_mul(layers).saturating_add(1)
}

/// Estimated peak memory (bytes) of the Markov chain of `chain` for a model with `dim` state
/// components and `d` section coordinates ([`chain_states`] states): per state its start state,
/// its transition row (up to one landing per terrain node on each of the 2^d nodes of a cell,
/// 16 bytes each), its fall and exit probabilities and the solver's vectors.
pub fn chain_memory(chain: &ChainPlan, d: usize, dim: usize) -> u64 {
    let per_state = 160 + 8 * dim as u64 + 16 * chain.nodes as u64 * (1u64 << d.min(16));
    crate::memory::bytes(chain_states(chain, d), per_state).saturating_add(MFPT_BASE_BYTES)
}

/// Refuses, before any walker walks, an MFPT run whose walkers ([`walkers_memory`]) or chain
/// ([`chain_memory`]) would not fit in memory ([`crate::memory::check_memory`]), naming the
/// option, the estimate and the limit. The walkers' fates are released before the chain
/// runs, so the larger of the two counts.
pub fn check_memory(
    m: &BuiltModel,
    plan: &MfptPlan,
    chain: Option<&ChainPlan>,
    flags: &MfptFlags,
    mesh_flag: &str,
) -> Result<(), InputError> {
    crate::memory::check_memory(
        walkers_memory(plan),
        &format!("{} {}", flags.walkers, plan.walkers),
        "use fewer walkers (the standard error falls as 1/sqrt(walkers))",
    )?;
    if let Some(c) = chain {
        let d = match c.section {
            ChainSection::Landing => m.info.section_names.len(),
            ChainSection::MidStance => m.walker.dim() - 1,
        };
        crate::memory::check_memory(
            chain_memory(c, d, m.walker.dim()),
            &format!(
                "{mesh_flag} {} ({} states on the finer mesh of {} nodes per axis, {} \
                 coordinates{})",
                c.mesh,
                chain_states(c, d),
                2 * c.mesh,
                d,
                match c.section {
                    ChainSection::Landing => format!(", {} terrain nodes", c.nodes),
                    ChainSection::MidStance => String::new(),
                }
            ),
            "use a smaller mesh (the finer mesh has twice its nodes per axis)",
        )?;
    }
    Ok(())
}

/// The chain at `chain.mesh` and at twice as many nodes per axis over one box ([`chain_box`]),
/// with the relative change between them and its warning ([`refinement_warning`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ChainPair {
    pub chain_box: ChainBox,
    /// The coarse mesh's and the fine mesh's results.
    pub results: [ChainResult; 2],
    pub change: f64,
    pub warning: Option<String>,
    /// On a cloud ([`ChainMesh::Cloud`]): the coarse and the fine cloud's closure.
    pub clouds: Option<[CloudStats; 2]>,
    /// On a grid: the coarse mesh's chain checked against twice the terrain's nodes
    /// ([`quadrature_check`]).
    pub quadrature: Option<QuadratureCheck>,
}

/// Relative change of the chain's MFPT between its terrain quadrature and one of twice as many
/// nodes above which [`quadrature_check`] warns: 0.5 %.
pub const QUADRATURE_MAX: f64 = 0.005;

/// The chain's terrain quadrature checked against one of twice as many nodes, on the same mesh
/// and box ([`quadrature_check`]).
#[derive(Clone, Debug, PartialEq)]
pub struct QuadratureCheck {
    /// The doubled quadrature's nodes and the mesh both chains were built on.
    pub nodes: usize,
    pub mesh: usize,
    /// The chain's MFPT with the doubled quadrature.
    pub mfpt: f64,
    /// `|doubled − base| / max` ([`refinement_change`]).
    pub change: f64,
    /// Above [`QUADRATURE_MAX`]: the quadrature is not converged, and the warning names the
    /// `--nodes` that is.
    pub warning: Option<String>,
}

/// The chain of `chain` on its coarse mesh over `cb` with twice `chain.nodes` terrain nodes,
/// against `base`, the same chain with `chain.nodes`: a quadrature too coarse for the terrain
/// (the rimless wheel at σ = 0.5°: 11 nodes give 116.1 steps where 22 and 40 give 118.6 and
/// 118.4) shows as a change above [`QUADRATURE_MAX`], which warns and names the option
/// (`nodes_flag`) with the doubled count. The box is the base chain's; landings of the extra
/// nodes outside it are absorbed as out of the mesh, as the base chain's are.
#[allow(clippy::too_many_arguments)]
pub fn quadrature_check(
    m: &BuiltModel,
    plan: &MfptPlan,
    chain: &ChainPlan,
    cb: &ChainBox,
    base: &ChainResult,
    x0: &[f64],
    pool: &rayon::ThreadPool,
    progress: &Progress,
    nodes_flag: &str,
) -> Result<QuadratureCheck, LimitError> {
    let doubled = ChainPlan {
        nodes: 2 * chain.nodes,
        ..chain.clone()
    };
    let r = chain_in(m, plan, &doubled, &cb.frame, &cb.bounds, x0, pool, progress)?;
    let change = refinement_change(base, &r);
    let warning = (change > QUADRATURE_MAX).then(|| {
        format!(
            "WARNING: the chain's MFPT changed by {:.1} % from {nodes_flag} {} to {nodes_flag} {} \
             ({:.4} to {:.4} at mesh {}): the terrain's quadrature is not converged; give \
             {nodes_flag} {} or more",
            100.0 * change,
            chain.nodes,
            doubled.nodes,
            base.mfpt,
            r.mfpt,
            chain.mesh,
            doubled.nodes
        )
    });
    Ok(QuadratureCheck {
        nodes: doubled.nodes,
        mesh: chain.mesh,
        mfpt: r.mfpt,
        change,
        warning,
    })
}

/// How a cloud of the chain was built ([`pdw_limit::mid_stance::cloud_transitions`]).
#[derive(Clone, Debug, PartialEq)]
pub struct CloudStats {
    /// Nodes per axis of the grid whose spacing the cloud has, and that spacing (standard
    /// deviations of the visited states).
    pub mesh: usize,
    pub cell: f64,
    /// The visited states thinned, the nodes after the closure, and its passes that added
    /// nodes.
    pub seeds: usize,
    pub nodes: usize,
    pub passes: usize,
    /// Seconds to build and solve this cloud's chain (the visited states' walk not included).
    pub secs: f64,
}

/// Walkers and transitions of the Monte Carlo pass whose mid-stance states seed a cloud.
pub const CLOUD_WALKERS: usize = 200;
pub const CLOUD_STEPS: usize = 500;
/// Closure passes of a cloud at most.
pub const CLOUD_PASSES: usize = 8;

/// The chain on two clouds of the mid-stance section: the states the first [`CLOUD_WALKERS`]
/// walkers visit (at most [`CLOUD_STEPS`] transitions each) thinned to the spacing of a grid
/// of `chain.mesh` and of twice as many nodes per axis, each closed under its landings in at
/// most [`CLOUD_PASSES`] passes ([`pdw_limit::mid_stance::cloud_transitions`]). The pair's box
/// is the visited states' principal frame and padded box, for the report.
pub fn cloud_pair(
    m: &BuiltModel,
    plan: &MfptPlan,
    chain: &ChainPlan,
    x0: &[f64],
    pool: &rayon::ThreadPool,
    progress: &Progress,
) -> Result<ChainPair, LimitError> {
    let at = model_at_param(m, plan.terrain.kind.param());
    let walk = walk_of(&at, plan)?.with_progress(progress);
    let sense = mid_stance::sweep_sense(walk.model(walk.mean())?.as_ref(), walk.kind(), x0)?;
    let (pts, frame, bounds) =
        mid_stance_points(m, plan, x0, (CLOUD_WALKERS, CLOUD_STEPS), pool, progress)?;
    let slopes = terrain_nodes(plan, chain.nodes);
    // the fine cloud's starts that the coarse one mapped are taken from it (bit for bit)
    let mut cache = mid_stance::LandingCache::recording();
    let mut run = |n: usize| -> Result<(ChainResult, CloudStats), LimitError> {
        let t0 = std::time::Instant::now();
        let mut cloud = pdw_limit::cloud::Cloud::thinned(&pts, n)?;
        let cc = mid_stance::cloud_transitions_cached(
            &walk,
            &slopes,
            &mut cloud,
            x0,
            sense,
            CLOUD_PASSES,
            pool,
            &mut cache,
        )?;
        cache.record = false;
        let r = pool.install(|| pdw_limit::markov::solve_chain(&cc.transitions));
        let stats = CloudStats {
            mesh: n,
            cell: cloud.cell(),
            seeds: cc.seeds,
            nodes: cc.nodes,
            passes: cc.passes,
            secs: t0.elapsed().as_secs_f64(),
        };
        Ok((r, stats))
    };
    let (coarse, c0) = run(chain.mesh)?;
    let (fine, c1) = run(2 * chain.mesh)?;
    let results = [coarse, fine];
    let change = refinement_change(&results[0], &results[1]);
    let warning = refinement_warning(&results[0], &results[1], chain.mesh);
    Ok(ChainPair {
        chain_box: ChainBox {
            frame,
            bounds,
            passes: 0,
            out_share: 0.0,
        },
        results,
        change,
        warning,
        clouds: Some([c0, c1]),
        quadrature: None,
    })
}

/// The chain of `chain` at its mesh and twice as fine, from `x0`, and on a grid its quadrature
/// checked ([`ChainPair`]; the quadrature's option named `nodes`, as in Python).
pub fn chain_pair(
    m: &BuiltModel,
    plan: &MfptPlan,
    chain: &ChainPlan,
    x0: &[f64],
    pool: &rayon::ThreadPool,
    progress: &Progress,
) -> Result<ChainPair, LimitError> {
    if chain.layout == ChainMesh::Cloud {
        return cloud_pair(m, plan, chain, x0, pool, progress);
    }
    let cb = chain_box(m, plan, chain, x0, pool, progress)?;
    let at = |n: usize| {
        let c = ChainPlan {
            mesh: n,
            ..chain.clone()
        };
        chain_in(m, plan, &c, &cb.frame, &cb.bounds, x0, pool, progress)
    };
    let results = [at(chain.mesh)?, at(2 * chain.mesh)?];
    let change = refinement_change(&results[0], &results[1]);
    let warning = refinement_warning(&results[0], &results[1], chain.mesh);
    let quadrature = quadrature_check(
        m,
        plan,
        chain,
        &cb,
        &results[0],
        x0,
        pool,
        progress,
        "nodes",
    )?;
    Ok(ChainPair {
        chain_box: cb,
        results,
        change,
        warning,
        clouds: None,
        quadrature: Some(quadrature),
    })
}
