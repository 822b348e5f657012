//! Command-line definitions (clap derive). The contract is docs/cli.md.

use clap::{Args, Parser, Subcommand};
use pdw::limit::design::Objective;
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(
    name = "pdw-sweep",
    version,
    about = "Find, measure and map the limit cycles of passive dynamic walkers",
    long_about = "Find, measure and map the limit cycles of passive dynamic walkers: fixed points of \
                  the stride map, Floquet multipliers, continuation in a parameter, and basins of \
                  attraction written to HDF5. Every command runs on a default (the simplest \
                  walker on slope 0.009 rad)."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// List the models, their parameters (units, defaults) and section coordinates.
    Models(ModelsArgs),
    /// Find period-one gaits (fixed points of the stride map) and their Floquet multipliers.
    Fixedpoint(FixedpointArgs),
    /// Compute a basin of attraction over a grid of section states and write HDF5 + PNG.
    Basin(BasinArgs),
    /// Join shard files of one basin run into one file.
    Merge(MergeArgs),
    /// Write an animated GIF of two strides of the gait found.
    Animate(AnimateArgs),
    /// Simulate N steps and write the time series (states, events, forces, energy) to HDF5 or CSV.
    Simulate(SimulateArgs),
    /// Mean first-passage time on random terrain (steps before a fall), by Monte Carlo.
    Mfpt(MfptArgs),
    /// Search free design parameters for the most robust physically valid gait (HDF5 + PNG).
    Design(DesignArgs),
    /// Explore basin files in the browser: click a cell to watch it walk, zoom to refine.
    Explore(ExploreArgs),
    /// One step of another slope or height from the gait: falls or recovers; or the largest
    /// such disturbance survived.
    Disturb(DisturbArgs),
}

/// `pdw-sweep explore`: the local basin explorer (docs/explore.md).
#[derive(Args, Debug)]
pub struct ExploreArgs {
    /// Basin files to serve (none: the default basin of `pdw-sweep basin`, computed first).
    pub files: Vec<PathBuf>,
    /// Port to listen on (0: any free port).
    #[arg(long, default_value_t = 8737)]
    pub port: u16,
    /// Address to listen on instead of the loopback 127.0.0.1 (anyone who can reach it can
    /// use the server).
    #[arg(long, value_name = "ADDR")]
    pub bind: Option<std::net::IpAddr>,
    /// Open the page in the browser (xdg-open).
    #[arg(long)]
    pub open: bool,
    /// Directory "save" writes refined windows into.
    #[arg(long, value_name = "DIR", default_value = ".")]
    pub save_dir: PathBuf,
    /// Threads of the computing pool.
    #[arg(long, default_value_t = 2, value_parser = crate::args::parse_threads)]
    pub threads: usize,
}

#[derive(Args, Debug)]
pub struct DisturbArgs {
    #[command(flatten)]
    pub model: ModelOpts,
    #[command(flatten)]
    pub integrator: IntegratorOpts,
    /// What step 1 changes: step-down (its foothold lies --once lower than nominal, a step down
    /// positive, model length units) or slope (its landing line is --once steeper, radians or
    /// 1deg).
    #[arg(long, default_value = "step-down")]
    pub terrain: String,
    /// The disturbance of step 1 (steps 2, 3, … are nominal).
    #[arg(long, allow_hyphen_values = true, required_unless_present = "largest")]
    pub once: Option<String>,
    /// Bisect for the largest disturbance survived, both ways (step down and up, or steeper
    /// and shallower).
    #[arg(long, conflicts_with = "once")]
    pub largest: bool,
    /// Strides walked after the disturbance that count as surviving it (old spelling: --steps).
    #[arg(long, alias = "steps", default_value_t = 200)]
    pub strides: usize,
    /// With --largest: the bisection's tolerance (the disturbance's unit).
    #[arg(long, default_value_t = 1e-5)]
    pub tol: f64,
    /// Print the report as one JSON object (the fields of Python's `disturb`).
    #[arg(long)]
    pub json: bool,
}

/// Options shared by every command that builds a model.
#[derive(Args, Debug, Clone)]
pub struct ModelOpts {
    /// Model name (see `pdw-sweep models`) or a walker spec file (`.toml`, e.g. one written by
    /// `pdw-sweep models --spec compass > my.toml`).
    #[arg(long, default_value = "simplest")]
    pub model: String,
    /// Slope in radians, or with an angle unit (3deg, 3°, 0.05rad). Default: the model's preset.
    #[arg(long)]
    pub slope: Option<String>,
    /// Override a model parameter, NAME=VALUE (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
}

/// The integrator of the stride map, shared by `fixedpoint`, `basin` and `simulate`. Every
/// field is optional: the command's default (DOP853 at its documented tolerance) fills the rest.
#[derive(Args, Debug, Clone, Default)]
pub struct IntegratorOpts {
    /// Integration method: dopri5 (Dormand–Prince 5(4)), dop853 (Dormand–Prince 8(5,3)) or rk4
    /// (classical, fixed step; give --rk4-step). Default: dop853.
    #[arg(long, value_parser = ["dopri5", "dop853", "rk4"])]
    pub integrator: Option<String>,
    /// Relative tolerance of dopri5/dop853 (0 or from 2.2e-15). Default: the command's
    /// (fixedpoint 1e-14, basin 1e-9, simulate 1e-10).
    #[arg(long)]
    pub rtol: Option<f64>,
    /// Absolute tolerance of dopri5/dop853 (> 0, units of the state). Default: --rtol if given,
    /// else the command's.
    #[arg(long)]
    pub atol: Option<f64>,
    /// Step of --integrator rk4 (model time units, > 0).
    #[arg(long, value_name = "H")]
    pub rk4_step: Option<f64>,
    /// Start every segment with the starting-step heuristic, also one that continues a cell's
    /// run after an impact (basin commands otherwise start it with the step the controller
    /// proposed at the impact: faster, results different at the tolerance's level). Other
    /// commands restart cold already.
    #[arg(long)]
    pub cold_restarts: bool,
    /// Step-size controller of dopri5: pi (the code dopri5's, β = 0.04; the default) or
    /// elementary (β = 0, h·0.9·err^(−1/5), as MATLAB's ode45). dop853's is elementary either way.
    #[arg(long, value_parser = ["pi", "elementary"])]
    pub controller: Option<String>,
}

#[derive(Args, Debug)]
pub struct ModelsArgs {
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Print a chain-walker preset's spec file (compass, kneed, seed5), to edit and pass back
    /// with `--model FILE.toml`.
    #[arg(long, value_name = "NAME")]
    pub spec: Option<String>,
}

// Negative numbers are values, not flags: `--slope -0.009`, `--guess -0.2,0.2`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
#[command(group(clap::ArgGroup::new("pooled").args(["sweep", "search"]).multiple(true)))]
pub struct FixedpointArgs {
    #[command(flatten)]
    pub model: ModelOpts,
    #[command(flatten)]
    pub integrator: IntegratorOpts,
    /// Which gaits to report: stable, unstable or all.
    #[arg(long, default_value = "all", value_parser = parse_gait)]
    pub gait: String,
    /// Initial guess in section coordinates, comma separated.
    #[arg(long, allow_hyphen_values = true)]
    pub guess: Option<String>,
    /// Tolerance on the fixed-point residual ‖P(x) − x‖, relative to the gait's scale
    /// (max |x|, at most 1); between 1e-15 and 1e-3.
    #[arg(long, default_value_t = 1e-12, value_parser = parse_tol)]
    pub tol: f64,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// With --json, for period-one gaits: each gait's linear stability data under `linear` —
    /// the stride-map Jacobian DP (variational equations), its eigenvalues and unit
    /// eigenvectors, the saltation matrix of every impact along the stride, and the
    /// finite-time Lyapunov exponents of the stride map over 100 strides (docs/cli.md).
    #[arg(long, requires = "json", conflicts_with_all = ["search", "sweep", "follow", "period"])]
    pub jacobian: bool,
    /// For period-one gaits: the gait sensitivity norm (Hobbelen & Wisse 2007) of each stable
    /// gait against the slope of the next landing line (random terrain), with each
    /// indicator's norm; an unstable gait's is infinite (docs/cli.md, "Walking on rough
    /// ground").
    #[arg(long, conflicts_with_all = ["search", "sweep", "follow", "period"])]
    pub gsn: bool,
    /// With --gsn: the gait indicators, comma separated, of step-time, step-length, speed.
    #[arg(
        long,
        value_name = "LIST",
        default_value = "step-time,step-length",
        requires = "gsn"
    )]
    pub indicators: String,
    /// Find every gait without a guess: Newton from N starting states spread over a box of the
    /// section (a Halton sample; N defaults to 256), and the stride map iterated from each to
    /// see where it goes (a stable gait, a period-K orbit up to K = 8, a fall). Lists every
    /// period-one gait, stable and unstable, and every period-K orbit with how many starts
    /// reached it. Runs by itself when the model's guesses find no gait.
    #[arg(
        long,
        value_name = "N",
        num_args = 0..=1,
        default_missing_value = "256",
        value_parser = parse_starts,
        conflicts_with_all = ["guess", "sweep", "follow", "period"]
    )]
    pub search: Option<usize>,
    /// With --search: the range of a section coordinate, NAME=LO:HI (repeatable), in place of
    /// the model's own box for that coordinate (see `pdw-sweep models`).
    #[arg(long = "search-box", value_name = "NAME=LO:HI", requires = "search", value_parser = parse_search_box)]
    pub search_box: Vec<pdw::input::AxisRange>,
    /// Period K of the orbits sought, in strides (1..=64): fixed points of the K-stride map
    /// P^K, found by Newton from the guesses, from where the map takes them after a few hundred
    /// strides, and from the period-doubling predictor at the period-one gaits.
    #[arg(long, default_value_t = 1, value_parser = parse_period)]
    pub period: usize,
    /// Continue the gait in a parameter: NAME=A:B:N (e.g. slope=0.001:0.019:400). The output
    /// holds exactly N points per branch, at the N evenly spaced values A, A + (B−A)/(N−1), …, B
    /// (on each branch where it exists; a branch that folds back has a point per crossing),
    /// each corrected at that value; the continuation takes whatever internal steps it needs
    /// (at most (B−A)/(N−1) in arclength) and does not store them. Bifurcations are located
    /// to 1e-10 and stored separately. Also an orbit diagram at the same N values.
    #[arg(long)]
    pub sweep: Option<String>,
    /// With --sweep: follow the period-doubling cascade down to period P strides (a power of
    /// two, 1 to 64): on each period-k branch, the period-2k branch is switched onto at its
    /// first period doubling and continued, until period P (branches period-1, period-2,
    /// period-4, …). Default 2: the period-2 branch only.
    #[arg(long, value_name = "P", default_value_t = 2, value_parser = parse_max_period, requires = "sweep")]
    pub max_period: usize,
    /// With --sweep NAME=A:B:N: find the gait to start from at NAME = MU (within A..B) and
    /// continue it both ways, towards A and towards B, into one branch. Without it the gait
    /// is found at A — from the guesses, else by a scan of the section — or, when A has none,
    /// at the grid values inward from A (the middle, then the quarter points).
    #[arg(long = "from", value_name = "MU", requires = "sweep", value_parser = parse_from)]
    pub from: Option<f64>,
    /// HDF5 output of a sweep (default bif.h5), or of --follow KIND (default KIND.h5: pd.h5,
    /// fold.h5).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// PNG bifurcation diagram of a sweep.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Overwrite existing output files.
    #[arg(long)]
    pub force: bool,
    // ---- sweep output (with --sweep; --json then prints the sweep as one JSON object)
    /// With --sweep: also write the branches as CSV, one row per orbit point of every branch
    /// point (columns: docs/cli.md, "Sweep output and basin stability").
    #[arg(long, value_name = "FILE", requires = "sweep")]
    pub csv: Option<PathBuf>,
    /// With --sweep: worker threads (rayon pool) for the points on the output grid, their
    /// measurements and the orbit diagram (with --follow: the region map); results are
    /// identical for any count. Default 2.
    #[arg(long, value_parser = crate::args::parse_threads, requires = "pooled")]
    pub threads: Option<usize>,
    /// With --sweep (or --follow): no progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Follow a bifurcation of the period-one gait in two parameters: pd (period doubling) or
    /// fold. Needs --sweep NAME=A:B:N (the stepped parameter; N curve points) and --free NAME
    /// (the parameter solved for). Writes the curve to --out, the two-parameter diagram to
    /// --png (if given), and prints a table or, with --json, the curve.
    #[arg(long, value_name = "pd|fold")]
    pub follow: Option<String>,
    /// The free parameter of --follow: NAME, or NAME=LO:HI to bound it (the curve ends where it
    /// leaves LO:HI; also the vertical range of --png). Default bounds: a quarter to four times
    /// the model's value.
    #[arg(long, value_name = "NAME[=LO:HI]")]
    pub free: Option<String>,
    /// Cells of the --follow region map drawn under the curve in --png, NXxNY (columns along
    /// the --sweep parameter, rows along --free).
    #[arg(long, value_name = "NXxNY", requires = "png")]
    pub map_grid: Option<String>,
}

impl FixedpointArgs {
    /// `--out`, else `bif.h5` for a sweep and `KIND.h5` for `--follow KIND`.
    pub fn out_path(&self) -> PathBuf {
        self.out.clone().unwrap_or_else(|| match &self.follow {
            Some(kind) => format!("{kind}.h5").into(),
            None => "bif.h5".into(),
        })
    }
}

#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct BasinArgs {
    #[command(flatten)]
    pub model: ModelOpts,
    #[command(flatten)]
    pub integrator: IntegratorOpts,
    /// Grid size NXxNY, or NXxNYxNZ with --z. Default: 401x401; 41x41 with --over.
    #[arg(long)]
    pub grid: Option<String>,
    /// Horizontal axis: NAME=A:B (inclusive). Default: the model's first section coordinate
    /// around the fixed point.
    #[arg(long)]
    pub x: Option<String>,
    /// Vertical axis: NAME=A:B (inclusive).
    #[arg(long)]
    pub y: Option<String>,
    /// Third axis, NAME=A:B (inclusive): a 3-D grid over a section coordinate other than --x
    /// and --y (--grid then gives NXxNYxNZ). The file holds [nz, ny, nx] datasets; the picture
    /// draws one z-slice (--slice).
    #[arg(long, conflicts_with = "over")]
    pub z: Option<String>,
    /// With --z: the z-slice the picture draws, NAME=VALUE (NAME the --z coordinate or `z`):
    /// the slice nearest VALUE, which must lie in the --z range. Default: the middle slice
    /// (always, for shards and their merge).
    #[arg(
        long,
        requires = "z",
        conflicts_with = "shard",
        value_name = "NAME=VALUE"
    )]
    pub slice: Option<String>,
    /// Stride budget per cell, 1 to 65535. A stride here is one step: heel strike to the next
    /// heel strike (one application of the stride map), not biomechanics' two steps.
    #[arg(long, default_value_t = 100, value_parser = pdw::basin::parse_max_strides)]
    pub max_strides: u16,
    /// HDF5 output file. Default: basin.h5; basin_stability.h5 with --over.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// PNG heatmap (default: the output path with .png).
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Worker threads (rayon pool).
    #[arg(long, default_value_t = 2, value_parser = crate::args::parse_threads)]
    pub threads: usize,
    /// Continue an interrupted run in --out (blocks damaged on disk are recomputed; a
    /// complete file is left as it is, exit 0).
    #[arg(long)]
    pub resume: bool,
    /// Overwrite an existing --out.
    #[arg(long)]
    pub force: bool,
    /// Compute only shard I of N (rows split deterministically).
    #[arg(long)]
    pub shard: Option<String>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    // ---- basin stability over a parameter (--over)
    /// Basin stability over a model parameter, NAME=A:B:N (e.g. slope=0.009:0.019:6): at each
    /// of the N evenly spaced values, the same box of section states (--x/--y, else the
    /// default box around the gait at A) is classified by attractor, and the fraction reaching
    /// each attractor (Menck et al. 2013), falling, or neither is written to --out (HDF5) and
    /// drawn as a stacked chart (--png). One small file written whole: no --resume or --shard.
    #[arg(long, value_name = "NAME=A:B:N", conflicts_with_all = ["resume", "shard"])]
    pub over: Option<String>,
    /// With --over: print the fractions as one JSON object (a plain basin writes its grid to
    /// --out and --png only).
    #[arg(long, requires = "over")]
    pub json: bool,
}

impl BasinArgs {
    /// The HDF5 output: --out, or the mode's default.
    pub fn out_path(&self) -> PathBuf {
        self.out.clone().unwrap_or_else(|| {
            if self.over.is_some() {
                "basin_stability.h5".into()
            } else {
                "basin.h5".into()
            }
        })
    }
}

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// Shard files.
    #[arg(required = true)]
    pub shards: Vec<PathBuf>,
    /// Merged output file.
    #[arg(long)]
    pub out: PathBuf,
    /// PNG heatmap (default: the output path with .png).
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Overwrite an existing --out and --png.
    #[arg(long)]
    pub force: bool,
}

#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct AnimateArgs {
    #[command(flatten)]
    pub model: ModelOpts,
    /// Strides of the gait shown, 1 to 1000.
    #[arg(long = "strides", alias = "steps", default_value_t = pdw::animate::STRIDES, value_parser = parse_anim_strides)]
    pub strides: usize,
    /// Frames per second, 0.5 to 50 (the GIF's delay is round(100/F) centiseconds). One second
    /// of the GIF is one model time unit: real time for models in seconds. Default: 16.7 (a
    /// 60 ms delay).
    #[arg(long, value_parser = parse_fps)]
    pub fps: Option<f64>,
    /// Picture size WIDTHxHEIGHT in pixels (width 64 to 4096, height 110 to 4096).
    #[arg(long, default_value = "640x400", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Animate a trajectory file written by `simulate` (HDF5) instead of a gait: its model is
    /// rebuilt from the file, --model/--slope/--set/--strides are not used.
    #[arg(long, value_name = "TRAJ.h5", conflicts_with_all = ["model", "slope", "set", "strides"])]
    pub from: Option<PathBuf>,
    /// Output GIF.
    #[arg(long, default_value = "gait.gif")]
    pub out: PathBuf,
    /// Overwrite an existing --out.
    #[arg(long)]
    pub force: bool,
}

// Negative numbers are values, not flags: `--mean -0.01`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct MfptArgs {
    #[command(flatten)]
    pub model: ModelOpts,
    #[command(flatten)]
    pub integrator: IntegratorOpts,
    /// The terrain: slope (a random ground slope per step, normal around --mean with --sd), or
    /// step-down (a random foothold height per step: the next foothold lies h below the stance
    /// foot, a step down positive, normal around --mean with --sd, model length units).
    #[arg(long, default_value = "slope")]
    pub terrain: String,
    /// Standard deviation of the slope, radians or with a unit (1deg, 0.5°), or of the step
    /// down (a plain length); or a range A:B:N (0.3deg:0.7deg:5) for the MFPT against it (a
    /// table, HDF5 and a PNG on a log axis).
    #[arg(long)]
    pub sd: String,
    /// Distribution of the standardised draws ξ (slope or step down = mean + sd ξ): normal,
    /// uniform (on [−√3, √3], variance 1, so --sd stays the standard deviation) or file:PATH
    /// (a text file of ξ values, one per line, '#' comments; each step draws one with equal
    /// probability).
    #[arg(long, default_value = "normal")]
    pub dist: String,
    /// Mean slope, radians or with a unit (3deg) (not with --slope); with --terrain step-down
    /// the mean step down (a plain length). Default: the model's slope (--slope or its preset),
    /// or its step_down (0).
    #[arg(long)]
    pub mean: Option<String>,
    /// How the walkers' strides are computed: auto (in closed form where the model has one —
    /// the rimless wheel, from conservation of energy and angular momentum — integrated
    /// otherwise), closed-form, or integrated (the integrator options, in batched lockstep).
    #[arg(long, default_value = "auto")]
    pub stride_map: String,
    /// Number of walkers.
    #[arg(long, default_value_t = 10000)]
    pub walkers: usize,
    /// Strides (heel strikes) at most per walker; a walker still walking then is censored (not a
    /// fall).
    #[arg(long = "max-strides", alias = "max-steps", default_value_t = 1000)]
    pub max_strides: usize,
    /// Seed of the terrain's random numbers (walker i, step k and the seed give the slope).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads (rayon pool); results are identical for any count.
    #[arg(long, default_value_t = 2, value_parser = crate::args::parse_threads)]
    pub threads: usize,
    /// Output file (HDF5, with a PNG of the survival curve next to it). Default: none.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Overwrite an existing --out.
    #[arg(long)]
    pub force: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Also compute the MFPT as a Markov chain on a mesh of the section (Byl & Tedrake 2009),
    /// at --mesh and twice --mesh nodes per section axis (models with up to 3 section
    /// coordinates).
    #[arg(long)]
    pub chain: bool,
    /// With --chain: mesh nodes per section axis (the finer mesh has twice as many). Default:
    /// 200 for one section coordinate, 60 for two, 12 for three (24 at mid-stance).
    #[arg(long, requires = "chain")]
    pub mesh: Option<usize>,
    /// With --chain: Gauss–Hermite nodes of the slope distribution.
    #[arg(long, default_value_t = 11, requires = "chain")]
    pub nodes: usize,
    /// With --chain: the section the chain's states lie on: `landing` (just after heel strike,
    /// one mesh layer per terrain node) or `mid-stance` (the stance leg vertical — on step
    /// heights the legs together, where the next height starts to matter — no layers: the
    /// compass gait's chain at a fraction of the strides; one-mode models only).
    #[arg(long, default_value = "landing", requires = "chain")]
    pub chain_section: String,
    /// With --chain: where the chain's nodes lie: `grid` (a regular grid over the box the
    /// walkers visit) or `cloud` (the states the walkers visit, thinned to the grid's spacing
    /// and closed under their own landings: the nodes follow a thin visited set; mid-stance
    /// section only).
    #[arg(long, default_value = "grid", requires = "chain")]
    pub chain_mesh: String,
    /// The MFPT over a model parameter, PARAM=A:B:N: at each of the N values the stable gait,
    /// its MFPT (the same walkers and seed at every value) and its gait sensitivity norm; a
    /// table, and with --out the file, OUT.png (MFPT against the parameter) and OUT-gsn.png
    /// (MFPT against the GSN).
    #[arg(long, value_name = "PARAM=A:B:N")]
    pub over: Option<String>,
}

#[derive(Args, Debug)]
pub struct SimulateArgs {
    #[command(flatten)]
    pub model: ModelOpts,
    #[command(flatten)]
    pub integrator: IntegratorOpts,
    /// Initial state just after a heel strike: section coordinates or the full state, comma
    /// separated (see `pdw-sweep models`). Default: the stable gait.
    #[arg(long, value_name = "X1,X2,..")]
    pub state: Option<String>,
    /// Start on the model's stable or unstable gait (found as `fixedpoint` finds it).
    #[arg(long, value_parser = ["stable", "unstable"], conflicts_with = "state")]
    pub gait: Option<String>,
    /// Strides to simulate, heel strike to heel strike (old spelling: --steps).
    #[arg(long, alias = "steps", default_value_t = 10)]
    pub strides: usize,
    /// Output time step (model time units), or `steps`: a sample at every accepted integrator
    /// step and both sides of every event. Default: 100 samples per step from a gait (its
    /// period / 100), T/50 from --state (T = sqrt(L/g)), and both sides of every event.
    #[arg(long, value_name = "H|steps", value_parser = parse_dt_out)]
    pub dt_out: Option<pdw::simulate::DtOut>,
    /// Output file: .h5/.hdf5 (HDF5) or .csv.
    #[arg(long, default_value = "traj.h5")]
    pub out: PathBuf,
    /// Overwrite an existing --out.
    #[arg(long)]
    pub force: bool,
    /// Print the report as one JSON object (the fields of Python's `simulate` besides the
    /// arrays).
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct DesignArgs {
    #[command(flatten)]
    pub model: ModelOpts,
    /// Free design parameter and its bounds, NAME=LO:HI (repeatable; any model parameter).
    #[arg(long = "free", value_name = "NAME=LO:HI")]
    pub free: Vec<String>,
    /// What a feasible design is scored by: basin (fraction of a box of section states around
    /// the gait that reaches it; larger is better) or margin (largest |multiplier|; smaller).
    #[arg(long, default_value = "basin", value_parser = parse_objective)]
    pub objective: Objective,
    /// Designs evaluated in all (a rerun on the same --out counts the stored ones).
    #[arg(long, default_value_t = 60, value_parser = parse_budget)]
    pub budget: usize,
    /// Seed of the initial random designs (--init).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Seeded random designs evaluated after the model's own values (the start), before
    /// Nelder-Mead starts from the best design so far.
    #[arg(long, default_value_t = 0)]
    pub init: usize,
    /// Local runs of the multi-start: run 0 from the model's own values (with --init), the
    /// others each from a seeded random design; --budget is shared out evenly and the runs
    /// run in parallel on --threads.
    #[arg(long, default_value_t = 1, value_parser = parse_design_starts)]
    pub starts: usize,
    /// Largest friction coefficient the ground supplies.
    #[arg(long, default_value_t = 0.6, value_parser = parse_mu)]
    pub mu: f64,
    /// Smallest knee-lock torque (N m) a passive knee stop must be left with along the stride.
    #[arg(long, default_value_t = 0.1, value_parser = parse_knee_margin)]
    pub knee_margin: f64,
    /// Smallest margin every validity criterion must keep, relative to its natural scale
    /// (forces / m g, torques / m g l, clearance / l, impulses / m sqrt(g l)); 0 = sign tests.
    #[arg(long, default_value_t = 0.0, value_parser = parse_min_margin)]
    pub min_margin: f64,
    /// Basin cells per side (objective basin).
    #[arg(long, default_value_t = 15, value_parser = parse_basin_grid)]
    pub basin_grid: usize,
    /// Half widths of the basin box around the gait: DSTANCE,DSTANCE_RATE (rad, rad/s).
    /// Default: scaled to each design's gait, 0.15 x (|stance|, |stance_rate|).
    #[arg(long, value_parser = parse_basin_box)]
    pub basin_box: Option<[f64; 2]>,
    /// Stride budget per basin cell.
    #[arg(long, default_value_t = 40, value_parser = parse_max_strides)]
    pub max_strides: u16,
    /// HDF5 file of every evaluated design (a rerun with the same settings continues it).
    #[arg(long, default_value = "design.h5")]
    pub out: PathBuf,
    /// PNG of the search (default: the output path with .png).
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Worker threads: the multi-start's runs (--starts) and the basin engine.
    #[arg(long, default_value_t = 2, value_parser = crate::args::parse_threads)]
    pub threads: usize,
    /// Start over: replace an existing --out.
    #[arg(long)]
    pub force: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Print the report as one JSON object (the fields of Python's `design` besides its arrays).
    #[arg(long)]
    pub json: bool,
}

// ---- value checks clap runs while parsing (a bad value exits with code 2 before anything runs;
// clap's message wraps the text here, which names the flag and the value)

/// Smallest `fixedpoint --tol`: below it the residual is integrator round-off.
pub const MIN_TOL: f64 = 1e-15;
/// Largest `fixedpoint --tol`: a looser relative tolerance accepts a preset guess as the gait
/// after zero iterations (the presets are within ~1e-2 of the gaits).
pub const MAX_TOL: f64 = 1e-3;

fn number(s: &str) -> Result<f64, String> {
    s.parse::<f64>().map_err(|e| e.to_string())
}

/// `fixedpoint --tol`: within [`MIN_TOL`, `MAX_TOL`].
fn parse_tol(s: &str) -> Result<f64, String> {
    let t = number(s)?;
    if (MIN_TOL..=MAX_TOL).contains(&t) {
        Ok(t)
    } else {
        Err(format!(
            "--tol: {t} is outside [{MIN_TOL:e}, {MAX_TOL:e}]; the residual tolerance is relative \
             to the gait's scale, and a looser one would accept the initial guess as a gait"
        ))
    }
}

/// `simulate --dt-out`: a positive time step or `steps`.
fn parse_dt_out(s: &str) -> Result<pdw::simulate::DtOut, String> {
    pdw::simulate::DtOut::parse(s, "--dt-out").map_err(|e| e.0)
}

/// `fixedpoint --gait`: stable, unstable or all.
fn parse_gait(s: &str) -> Result<String, String> {
    if matches!(s, "stable" | "unstable" | "all") {
        Ok(s.to_string())
    } else {
        Err(format!("--gait: '{s}' is not one of stable, unstable, all"))
    }
}

/// `fixedpoint --period`: 1 to 64 strides.
/// `--search N`: 1 to 1 000 000 starting states.
fn parse_starts(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if (1..=1_000_000).contains(&n) => Ok(n),
        _ => Err(format!("'{s}' is not a number of starts from 1 to 1000000")),
    }
}

/// `--search-box NAME=LO:HI`.
fn parse_search_box(s: &str) -> Result<pdw::input::AxisRange, String> {
    pdw::input::parse_axis(s, "--search-box").map_err(|e| e.0)
}

fn parse_period(s: &str) -> Result<usize, String> {
    let k = s.parse::<usize>().map_err(|e| e.to_string())?;
    if (1..=64).contains(&k) {
        Ok(k)
    } else {
        Err(format!("--period: {k} must be between 1 and 64 strides"))
    }
}

/// `--max-period P`: a power of two from 1 to 64.
fn parse_max_period(s: &str) -> Result<usize, String> {
    let p = s
        .trim()
        .parse::<usize>()
        .map_err(|_| format!("--max-period: '{s}' is not a whole number"))?;
    pdw::input::check_max_period(p, "--max-period").map_err(|e| e.to_string())
}

/// `--from MU`: a finite number (checked against the range once the sweep is parsed).
fn parse_from(s: &str) -> Result<f64, String> {
    pdw::input::parse_f64(s, "--from").map_err(|e| e.to_string())
}

/// `design --objective`: basin or margin.
fn parse_objective(s: &str) -> Result<Objective, String> {
    pdw::design::parse_objective(s, "--objective").map_err(|e| e.0)
}

/// `design --mu`: a finite friction coefficient > 0.
fn parse_mu(s: &str) -> Result<f64, String> {
    pdw::design::check_mu(number(s)?, "--mu").map_err(|e| e.0)
}

/// `design --knee-margin`: a finite torque ≥ 0.
fn parse_knee_margin(s: &str) -> Result<f64, String> {
    pdw::design::check_knee_margin(number(s)?, "--knee-margin").map_err(|e| e.0)
}

/// `design --min-margin`: a finite relative margin ≥ 0.
fn parse_min_margin(s: &str) -> Result<f64, String> {
    pdw::design::check_min_margin(number(s)?, "--min-margin").map_err(|e| e.0)
}

fn integer(s: &str) -> Result<i64, String> {
    s.parse::<i64>().map_err(|e| e.to_string())
}

/// `design --budget`: 1 to 100000 designs.
fn parse_budget(s: &str) -> Result<usize, String> {
    pdw::design::check_budget(integer(s)?, "--budget").map_err(|e| e.0)
}

/// `design --starts`: 1 to 10000 local runs.
fn parse_design_starts(s: &str) -> Result<usize, String> {
    pdw::design::check_starts(integer(s)?, "--starts").map_err(|e| e.0)
}

/// `design --basin-grid`: 1 to 200 cells per side.
fn parse_basin_grid(s: &str) -> Result<usize, String> {
    pdw::design::check_basin_grid(integer(s)?, "--basin-grid").map_err(|e| e.0)
}

/// `design --max-strides`: 1 to 10000 strides per basin cell.
fn parse_max_strides(s: &str) -> Result<u16, String> {
    pdw::design::check_max_strides(integer(s)?, "--max-strides").map_err(|e| e.0)
}

/// `design --basin-box`: two positive half widths `DSTANCE,DSTANCE_RATE`.
fn parse_basin_box(s: &str) -> Result<[f64; 2], String> {
    let v = crate::args::parse_guess(s).map_err(|e| e.to_string())?;
    pdw::design::check_basin_box(&v, s, "--basin-box").map_err(|e| e.0)
}

/// `animate --strides`: 1 to 1000 strides.
fn parse_anim_strides(s: &str) -> Result<usize, String> {
    pdw::animate::check_strides(integer(s)?, "--strides").map_err(|e| e.0)
}

/// `animate --fps`: 0.5 to 50 frames per second.
fn parse_fps(s: &str) -> Result<f64, String> {
    pdw::animate::check_fps(number(s)?, "--fps").map_err(|e| e.0)
}

/// `animate --size`: WIDTHxHEIGHT pixels.
fn parse_size(s: &str) -> Result<(u32, u32), String> {
    pdw::animate::parse_size(s, "--size").map_err(|e| e.0)
}
