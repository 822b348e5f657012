//! The declared formats, one table each (see [`super`]).

use super::{Format, Item, Quantity, Unit};

const H: &str = "header_digest";
const B: &str = "block_digest";

/// `/provenance`, `/@coordinates`: in every file (see [`crate::provenance`]).
pub const PROVENANCE: &[Item] = &[
    Item::attr(
        "@coordinates",
        "json",
        "state component → what it measures (the angle, from what, its sign)",
    )
    .only("files written since it was stored"),
    Item::group("provenance", "who made the file, how, from which build"),
    Item::attr(
        "provenance@crate_version",
        "str",
        "version of the pdw-sweep crates",
    ),
    Item::attr(
        "provenance@git_commit",
        "str",
        "commit built (`-dirty` with uncommitted changes, `unknown` outside git)",
    ),
    Item::attr("provenance@build_profile", "str", "`release` or `debug`"),
    Item::attr(
        "provenance@simd_path",
        "str",
        "instruction set the hot loops ran on (`baseline`, `avx2`, `avx512`)",
    ),
    Item::attr(
        "provenance@numerics",
        "str",
        "the numeric contract every path keeps",
    ),
    Item::attr("provenance@host", "str", "host name"),
    Item::attr("provenance@command", "str", "the command line"),
    Item::attr(
        "provenance@options",
        "json",
        "every numerical option of the run",
    ),
    Item::attr("provenance@created", "str", "RFC 3339 UTC"),
    Item::attr(
        "provenance@commands",
        "json",
        "every command line that wrote the file (a run and its `--resume` runs)",
    ),
    Item::attr(
        "provenance@model_spec",
        "str",
        "chain walkers: the resolved spec as TOML, parameters included",
    )
    .only("chain walkers"),
    Item::group("provenance/shards", "merged files: one group per shard").only("merged files"),
    Item::group(
        "provenance/shards/<n>",
        "a shard's provenance (the attributes above) and its `file`",
    )
    .only("merged files"),
    Item::attr(
        "provenance/shards/<n>@<attribute>",
        "str",
        "the shard's provenance attribute, and `file`",
    )
    .only("merged files"),
];

/// The basin file of `pdw-sweep basin` (and the explorer's saved window), `/` to `/metrics`.
const BASIN_ITEMS: &[Item] = &[
    Item::attr("@format", "str", "`pdw-sweep basin v1`"),
    Item::attr("@version", "str", "crate version that created the file"),
    Item::attr("@command", "str", "the command line that made the file").covered(H),
    Item::attr("@created", "str", "RFC 3339 UTC"),
    Item::attr("@model", "str", "model name").covered(H),
    Item::attr("@slope", "f64", "slope γ (rad)").covered(H),
    Item::attr("@params", "json", "model parameters").covered(H),
    Item::attr(
        "@model_resolved",
        "str",
        "the resolved model, one `key = value` line per quantity",
    )
    .covered(H),
    Item::attr("@integrator", "str", "integrator of the cells").covered(H),
    Item::attr(
        "@tolerances",
        "json",
        "rtol, atol, tol_gait, tol_recur, confirm, max_period, fixed_point_residual, \
         attractor_seeds, seed_strides, chaos_radius, chaos_sample, fixed",
    )
    .covered(H),
    Item::attr("@max_strides", "u32", "stride budget per cell").covered(H),
    Item::attr("@elapsed_s", "f64", "wall time of the computation (s)"),
    Item::attr(
        "@complete",
        "bool",
        "every row computed and the results written",
    ),
    Item::attr("@shard_index", "u64", "this shard's index")
        .covered(H)
        .only("shards"),
    Item::attr("@shard_count", "u64", "the number of shards")
        .covered(H)
        .only("shards"),
    Item::attr(
        "@header_digest",
        "u64",
        "FNV-1a over the run attributes, the grid axes' names and values, the state names, the \
         legend and the shard, checked by every reader; files without it read unverified",
    ),
    Item::group("slice", "the slice of the section the grid lies on"),
    Item::attr("slice@x", "str", "coordinate along x"),
    Item::attr("slice@y", "str", "coordinate along y"),
    Item::attr(
        "slice@fixed",
        "json",
        "name → {value, unit, source} of every coordinate held fixed",
    ),
    Item::attr(
        "slice@<coordinate>",
        "f64",
        "the value of each coordinate held fixed",
    ),
    Item::attr(
        "slice@on_fixed_point",
        "bool",
        "whether the gait lies on the slice",
    ),
    Item::attr("slice@z", "str", "the z coordinate of the drawn slice").only("3-D grids"),
    Item::attr("slice@z_index", "u64", "index of the drawn z-slice, from 0").only("3-D grids"),
    Item::attr("slice@z_value", "f64", "its z value").only("3-D grids"),
    Item::new(
        "slice/outcome",
        "u8",
        "[ny, nx]",
        Unit::One,
        "the z-slice the PNG draws, `/basin/outcome[z_index]`",
    )
    .only("3-D grids"),
    Item::attr("slice/outcome@description", "str", "what it is").only("3-D grids"),
    Item::group("grid", "the grid's axes"),
    Item::new(
        "grid/x",
        "f64",
        "[nx]",
        Unit::Axis(0),
        "grid abscissae; dimension scale of the last grid dimension",
    )
    .covered(H),
    Item::attr("grid/x@name", "str", "its section coordinate").covered(H),
    Item::new(
        "grid/y",
        "f64",
        "[ny]",
        Unit::Axis(1),
        "grid ordinates; dimension scale",
    )
    .covered(H),
    Item::attr("grid/y@name", "str", "its section coordinate").covered(H),
    Item::new(
        "grid/z",
        "f64",
        "[nz]",
        Unit::Axis(2),
        "z values; dimension scale of dimension 0",
    )
    .covered(H)
    .only("3-D grids"),
    Item::attr("grid/z@name", "str", "its section coordinate")
        .covered(H)
        .only("3-D grids"),
    Item::group("basin", "the cells"),
    Item::new(
        "basin/outcome",
        "u8",
        "[ny, nx] or [nz, ny, nx]",
        Unit::One,
        "outcome code of each cell (row = y index)",
    )
    .covered(B),
    Item::attr(
        "basin/outcome@legend",
        "json",
        "code → name, with 255 = `not_computed` (the fill value)",
    )
    .covered(H),
    Item::new(
        "basin/strides",
        "u16",
        "as outcome",
        Unit::One,
        "strides until classified",
    )
    .covered(B),
    Item::new(
        "basin/final",
        "f64",
        "[…, d]",
        Unit::Section,
        "section coordinates of each cell's last state",
    )
    .covered(B),
    Item::attr("basin/final@names", "json", "the d section coordinates").covered(H),
    Item::attr(
        "basin/final@description",
        "str",
        "what the last state is, by outcome",
    ),
    Item::new(
        "basin/rows_done",
        "u8",
        "[ny] or [nz·ny]",
        Unit::One,
        "1 once a row is on disk (what `--resume` skips)",
    ),
    Item::new(
        "basin/block_digest",
        "u64",
        "[nz·⌈ny/16⌉]",
        Unit::One,
        "per block of 16 rows: FNV-1a of its outcome, strides and final values as written",
    ),
    Item::attr(
        "basin/block_digest@description",
        "str",
        "what the digest covers",
    ),
    Item::group("attractors", "the attractors the cells were classified by").only("finished files"),
    Item::group(
        "attractors/<name>",
        "one attractor (gait, period-2, chaotic, …)",
    )
    .only("finished files"),
    Item::new(
        "attractors/<name>/section",
        "f64",
        "[k, d]",
        Unit::Section,
        "the orbit's k points in stride order (a chaotic attractor's sample)",
    )
    .only("finished files"),
    Item::new(
        "attractors/<name>/multipliers_re",
        "f64",
        "[m]",
        Unit::One,
        "real parts of the k-step map's multipliers (empty if chaotic)",
    )
    .only("finished files"),
    Item::new(
        "attractors/<name>/multipliers_im",
        "f64",
        "[m]",
        Unit::One,
        "imaginary parts",
    )
    .only("finished files"),
    Item::attr(
        "attractors/<name>@period_strides",
        "u32",
        "period k (0 if chaotic)",
    )
    .only("finished files"),
    Item::attr(
        "attractors/<name>@period_k",
        "u32",
        "the same, as older readers name it",
    )
    .only("finished files"),
    Item::attr(
        "attractors/<name>@period_time",
        "f64",
        "period in time (NaN if chaotic)",
    )
    .only("finished files"),
    Item::attr(
        "attractors/<name>@validity",
        "str",
        "`valid`, `invalid` or `not checked`",
    )
    .only("finished files"),
    Item::attr(
        "attractors/<name>@invalid_reasons",
        "str",
        "what fails, `; `-separated",
    )
    .only("invalid orbits"),
    Item::group("metrics", "the basin's measures").only("finished files"),
    Item::attr(
        "metrics@fractions",
        "json",
        "outcome name → fraction of cells",
    )
    .only("finished files"),
    Item::attr(
        "metrics@fraction_<name>",
        "f64",
        "the same, one attribute per outcome",
    )
    .only("finished files"),
    Item::attr(
        "metrics@basin_entropy",
        "f64",
        "basin entropy (Daza et al. 2016)",
    )
    .only("finished files"),
    Item::attr("metrics@boundary_entropy", "f64", "boundary basin entropy").only("finished files"),
    Item::attr("metrics@entropy_box", "u64", "box side in cells").only("finished files"),
];

/// The basin file (`format = "pdw-sweep basin v1"`).
pub const BASIN: Format = Format {
    name: "basin",
    format: crate::basin::BASIN_FORMAT,
    parts: &[BASIN_ITEMS, PROVENANCE],
};

const SWEEP_ITEMS: &[Item] = &[
    Item::attr("@format", "str", "`pdw-sweep sweep v2`"),
    Item::attr("@parameter", "str", "the parameter swept"),
    Item::attr("@section_names", "json", "the d section coordinates"),
    Item::attr("@elapsed_s", "f64", "wall time of the computation (s)"),
    Item::attr(
        "@setting_<name>",
        "json",
        "one per setting of the run (continuation, grid, integrator, threads, tolerances)",
    ),
    Item::group("branches", "one group per branch"),
    Item::group("branches/<n>", "a branch (000, 001, …)"),
    Item::attr("branches/<n>@name", "str", "e.g. `period-1`"),
    Item::attr(
        "branches/<n>@period_strides",
        "u32",
        "its period K in strides",
    ),
    Item::new(
        "branches/<n>/parameter",
        "f64",
        "[n]",
        Unit::Parameter,
        "the parameter at each point",
    ),
    Item::new(
        "branches/<n>/section",
        "f64",
        "[n, d]",
        Unit::Section,
        "the orbit's first section point",
    ),
    Item::new(
        "branches/<n>/multipliers_re",
        "f64",
        "[n, m]",
        Unit::One,
        "real parts of the K-stride map's multipliers, by decreasing modulus",
    ),
    Item::new(
        "branches/<n>/multipliers_im",
        "f64",
        "[n, m]",
        Unit::One,
        "imaginary parts",
    ),
    Item::new(
        "branches/<n>/stable",
        "u8",
        "[n]",
        Unit::One,
        "1 = all multipliers inside the unit circle",
    ),
    Item::new(
        "branches/<n>/orbit",
        "f64",
        "[n, K, d]",
        Unit::Section,
        "the K section points in stride order",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/period",
        "f64",
        "[n]",
        Unit::Model(Quantity::Time),
        "the K strides' time",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/step_length",
        "f64",
        "[n, K]",
        Unit::Model(Quantity::Length),
        "per stride (NaN if the model reports none)",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/speed",
        "f64",
        "[n]",
        Unit::Model(Quantity::Speed),
        "K step lengths / period",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/validity_checked",
        "u8",
        "[n, K]",
        Unit::One,
        "per stride, 1 = yes",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/valid",
        "u8",
        "[n, K]",
        Unit::One,
        "per stride, 1 = yes",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/normal_force_negative",
        "u8",
        "[n, K]",
        Unit::One,
        "per stride, 1 = yes",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/knee_unlocks",
        "u8",
        "[n, K]",
        Unit::One,
        "per stride, 1 = yes",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/swing_foot_scuffs",
        "u8",
        "[n, K]",
        Unit::One,
        "per stride, 1 = yes",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/impact_violation",
        "u8",
        "[n, K]",
        Unit::One,
        "per stride, 1 = yes",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/min_normal_force",
        "f64",
        "[n, K]",
        Unit::Model(Quantity::Force),
        "per stride (NaN where not defined)",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/max_friction_required",
        "f64",
        "[n, K]",
        Unit::One,
        "friction coefficient needed, per stride",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/min_knee_torque",
        "f64",
        "[n, K]",
        Unit::Model(Quantity::Torque),
        "smallest knee-lock torque, per stride",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/min_clearance",
        "f64",
        "[n, K]",
        Unit::Model(Quantity::Length),
        "smallest swing-foot clearance, per stride",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/scuff_depth",
        "f64",
        "[n, K]",
        Unit::Model(Quantity::Length),
        "deepest scuff, per stride",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/min_impact_margin",
        "f64",
        "[n, K]",
        Unit::Fixed("model units of the binding impact entry"),
        "smallest impact margin, per stride",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/min_relative_margin",
        "f64",
        "[n, K]",
        Unit::One,
        "smallest relative margin of the validity criteria, per stride",
    )
    .only("measured branches"),
    Item::new(
        "branches/<n>/binding_criterion",
        "u8",
        "[n, K]",
        Unit::One,
        "the binding criterion, per stride",
    )
    .only("measured branches"),
    Item::attr(
        "branches/<n>/binding_criterion@legend",
        "json",
        "code → criterion name",
    )
    .only("measured branches"),
    Item::group("bifurcations", "one group per detected bifurcation"),
    Item::group("bifurcations/<n>", "a bifurcation (000, 001, …)").only("detected bifurcations"),
    Item::attr(
        "bifurcations/<n>@kind",
        "str",
        "`period-doubling`, `fold`, `neimark-sacker`, …",
    )
    .only("detected bifurcations"),
    Item::attr("bifurcations/<n>@parameter", "f64", "where").only("detected bifurcations"),
    Item::attr("bifurcations/<n>@branch", "u64", "on which branch (index)")
        .only("detected bifurcations"),
    Item::new(
        "bifurcations/<n>/section",
        "f64",
        "[d]",
        Unit::Section,
        "the section point",
    )
    .only("detected bifurcations"),
    Item::group("orbit", "the brute-force orbit diagram").only("an orbit diagram"),
    Item::attr(
        "orbit@coordinate",
        "str",
        "the section coordinate sampled (the first)",
    )
    .only("an orbit diagram"),
    Item::new(
        "orbit/parameter",
        "f64",
        "[n]",
        Unit::Parameter,
        "parameter values",
    )
    .only("an orbit diagram"),
    Item::new(
        "orbit/points",
        "f64",
        "[n, s]",
        Unit::SectionCoordinate(0),
        "s section samples after transients (NaN where the walker fell)",
    )
    .only("an orbit diagram"),
];

/// The sweep file of `pdw-sweep fixedpoint --sweep` (`format = "pdw-sweep sweep v2"`).
pub const SWEEP: Format = Format {
    name: "sweep",
    format: crate::sweep::SWEEP_FORMAT,
    parts: &[SWEEP_ITEMS, RUN, PROVENANCE],
};

/// The root attributes every file but the basin and design files starts with.
pub(super) const RUN: &[Item] = &[
    Item::attr("@version", "str", "crate version that created the file"),
    Item::attr("@command", "str", "the command line that made the file"),
    Item::attr("@created", "str", "RFC 3339 UTC"),
    Item::attr("@model", "str", "model name"),
    Item::attr("@params", "json", "model parameters"),
];

const MFPT_ITEMS: &[Item] = &[
    Item::attr("@format", "str", "`pdw-sweep mfpt v1`"),
    Item::group("mfpt", "the estimate and the settings it came from"),
    Item::attr("mfpt@method", "str", "`monte carlo`"),
    Item::attr("mfpt@terrain", "str", "`slope` or `step-down`"),
    Item::attr(
        "mfpt@distribution",
        "str",
        "the distribution of the standardised draws, in words",
    ),
    Item::attr(
        "mfpt@terrain_unit",
        "str",
        "unit of `mean` and `sd`: `rad`, or the model's length unit",
    ),
    Item::attr(
        "mfpt@estimator",
        "str",
        "how `mfpt` and `stderr` were estimated, in words",
    ),
    Item::attr("mfpt@seed", "u64", "seed of the terrain draws"),
    Item::attr("mfpt@walkers", "u64", "walkers started"),
    Item::attr(
        "mfpt@max_steps",
        "u64",
        "heel strikes a walker may complete",
    ),
    Item::attr("mfpt@falls", "u64", "walkers that fell"),
    Item::attr("mfpt@censored", "u64", "walkers still walking at max_steps"),
    Item::attr(
        "mfpt@total_steps",
        "u64",
        "heel strikes completed by all walkers",
    ),
    Item::attr("mfpt@mean", "f64", "mean of the terrain (in terrain_unit)"),
    Item::attr("mfpt@sd", "f64", "its standard deviation (in terrain_unit)"),
    Item::attr("mfpt@mfpt", "f64", "mean first-passage time (steps)"),
    Item::attr("mfpt@stderr", "f64", "its standard error"),
    Item::attr(
        "mfpt@restricted_mean",
        "f64",
        "mean of min(steps, max_steps)",
    ),
    Item::attr("mfpt@restricted_stderr", "f64", "its standard error"),
    Item::attr("mfpt@elapsed_s", "f64", "wall time (s)"),
    Item::attr(
        "mfpt@chain_<name>",
        "f64",
        "the Markov chain's numbers (`quadrature_*` among them)",
    )
    .only("`--chain`"),
    Item::new(
        "mfpt/survival",
        "f64",
        "[K + 1]",
        Unit::One,
        "fraction of walkers that completed at least k steps, k = 0 … K (chunked, shuffled and \
         deflated beyond 65 536 values)",
    ),
    Item::new(
        "mfpt/failures",
        "u64",
        "[kinds]",
        Unit::One,
        "falls per kind",
    ),
    Item::attr("mfpt/failures@kinds", "json", "the fall kinds, in order"),
    Item::new(
        "mfpt/start",
        "f64",
        "[d]",
        Unit::Section,
        "the section state the walkers start from",
    ),
    Item::attr("mfpt/start@names", "json", "the section coordinates"),
];

/// The MFPT file of `pdw-sweep mfpt` (`format = "pdw-sweep mfpt v1"`).
pub const MFPT: Format = Format {
    name: "mfpt",
    format: crate::mfpt::MFPT_FORMAT,
    parts: &[MFPT_ITEMS, RUN, PROVENANCE],
};

const DESIGN_ITEMS: &[Item] = &[
    Item::attr("@format", "str", "`pdw-sweep design v1`"),
    Item::attr("@version", "str", "crate version that created the file"),
    Item::attr("@created", "str", "RFC 3339 UTC"),
    Item::attr(
        "@settings",
        "json",
        "model, fixed parameters, free parameters and bounds, objective, constraints, seed (a \
         rerun must match it to continue)",
    ),
    Item::attr("@free_names", "json", "the k free parameters"),
    Item::attr(
        "@status_names",
        "json",
        "names of the status codes, by code",
    ),
    Item::new(
        "params",
        "f64",
        "[N, k]",
        Unit::FreeParameters,
        "the free parameters of each design, in evaluation order",
    ),
    Item::new(
        "section",
        "f64",
        "[N, 3]",
        Unit::Section,
        "the gait's (stance, stance_rate, hip_rate), NaN without a gait",
    ),
    Item::new(
        "status",
        "u8",
        "[N]",
        Unit::One,
        "status code (`status_names`)",
    ),
    Item::new(
        "reasons",
        "u8",
        "[bytes]",
        Unit::One,
        "per design, why it failed (UTF-8 JSON list of strings)",
    ),
    Item::new(
        "bindings",
        "u8",
        "[bytes]",
        Unit::One,
        "per design, the binding validity criterion (UTF-8 JSON list)",
    ),
    Item::new(
        "fates",
        "u8",
        "[bytes]",
        Unit::One,
        "per design, how a gait search that found nothing ended (UTF-8 JSON list)",
    ),
    Item::new(
        "cost",
        "f64",
        "[N]",
        Unit::One,
        "the minimised cost (NaN where not measured, as every measure below)",
    ),
    Item::new(
        "basin_fraction",
        "f64",
        "[N]",
        Unit::One,
        "basin fraction (objective `basin`, feasible designs)",
    ),
    Item::new(
        "rho",
        "f64",
        "[N]",
        Unit::One,
        "largest multiplier modulus of the gait",
    ),
    Item::new(
        "min_normal_force",
        "f64",
        "[N]",
        Unit::Model(Quantity::Force),
        "smallest normal force",
    ),
    Item::new(
        "max_friction",
        "f64",
        "[N]",
        Unit::One,
        "largest friction coefficient needed",
    ),
    Item::new(
        "min_knee_torque",
        "f64",
        "[N]",
        Unit::Model(Quantity::Torque),
        "smallest knee-lock torque",
    ),
    Item::new(
        "period",
        "f64",
        "[N]",
        Unit::Model(Quantity::Time),
        "period of the gait",
    ),
    Item::new(
        "step_length",
        "f64",
        "[N]",
        Unit::Model(Quantity::Length),
        "step length of the gait",
    ),
    Item::new(
        "min_relative_margin",
        "f64",
        "[N]",
        Unit::One,
        "smallest relative margin of the validity criteria (the binding one's)",
    ),
    Item::new(
        "basin_box_stance",
        "f64",
        "[N]",
        Unit::SectionCoordinate(0),
        "half width of the basin box the fraction was measured in, along stance",
    ),
    Item::new(
        "basin_box_stance_rate",
        "f64",
        "[N]",
        Unit::SectionCoordinate(1),
        "the same along stance_rate",
    ),
    Item::new(
        "shortfall",
        "f64",
        "[N]",
        Unit::One,
        "the shortfall d of the graded cost",
    ),
    Item::new(
        "strides_survived",
        "f64",
        "[N]",
        Unit::One,
        "without a gait: the most strides any guess walked",
    ),
    Item::new(
        "probe_residual",
        "f64",
        "[N]",
        Unit::One,
        "without a gait: the smallest relative stride-to-stride change met",
    ),
    Item::new(
        "run",
        "f64",
        "[N]",
        Unit::One,
        "the search run that evaluated it (0 for a single run)",
    ),
];

/// The design file of `pdw-sweep design` (`format = "pdw-sweep design v1"`).
pub const DESIGN: Format = Format {
    name: "design",
    format: crate::design::DESIGN_FORMAT,
    parts: &[DESIGN_ITEMS, PROVENANCE],
};

const TRAJECTORY_ITEMS: &[Item] = &[
    Item::attr("@format", "str", "`pdw-sweep trajectory v1`"),
    Item::attr("@slope", "str", "slope γ (rad), as text"),
    Item::attr("@integrator", "str", "integrator of the walk"),
    Item::attr("@steps", "str", "steps asked for"),
    Item::attr("@steps_done", "str", "steps completed"),
    Item::attr("@outcome", "str", "how the walk ended (`ok`, a fall…)"),
    Item::attr("@start", "str", "the start state and where it came from"),
    Item::attr("@state_names", "json", "the state components"),
    Item::attr(
        "@dt_out",
        "str",
        "the sample spacing, or every accepted step and event",
    ),
    Item::attr("@dt_out_source", "str", "where the spacing came from"),
    Item::attr(
        "@flags_legend",
        "json",
        "bit → what the `flags` column flags",
    ),
    Item::attr("@mode_legend", "json", "mode code → name"),
    Item::attr(
        "@point_names",
        "json",
        "the named points of `pos_<point>` (`[]` for round feet)",
    ),
    Item::attr(
        "@positions_frame",
        "str",
        "the frame of the positions, or why there are none",
    ),
    Item::group("events", "the events along the walk"),
    Item::new("events/t", "f64", "[m]", Unit::Own, "event times"),
    Item::new(
        "events/kind",
        "u8",
        "[m]",
        Unit::One,
        "event kind (`legend`)",
    ),
    Item::attr(
        "events/kind@legend",
        "json",
        "code → name (`heel_strike`, a fall…)",
    ),
    Item::new(
        "events/step",
        "u32",
        "[m]",
        Unit::One,
        "step during which it happened, from 0",
    ),
    Item::new(
        "events/mode_before",
        "u32",
        "[m]",
        Unit::One,
        "mode before the event",
    ),
    Item::new(
        "events/mode_after",
        "u32",
        "[m]",
        Unit::One,
        "mode after it",
    ),
    Item::new(
        "events/pre",
        "f64",
        "[m, d]",
        Unit::State,
        "state just before the event",
    ),
    Item::new(
        "events/post",
        "f64",
        "[m, d]",
        Unit::State,
        "state just after it",
    ),
];

/// The trajectory's columns: last, since `<column>` matches any name at the root.
const TRAJECTORY_COLUMNS: &[Item] = &[
    Item::attr(
        "<column>@components",
        "json",
        "the k component names of a 2-D column",
    ),
    Item::new(
        "<column>",
        "f64 or u32",
        "[n] or [n, k]",
        Unit::Own,
        "one dataset per column at the root, row = sample: `t`, each state component, `mode`, \
         `step`, forces, `flags`, `energy`, `energy_fixed_frame`, `pos_<point>` and `com` [n, 2]",
    ),
];

/// The trajectory file of `pdw-sweep simulate` (`format = "pdw-sweep trajectory v1"`). Its
/// columns carry their own units, written with them; [`Format::units`] gives the events'.
pub const TRAJECTORY: Format = Format {
    name: "trajectory",
    format: crate::trajectory::TRAJECTORY_FORMAT,
    parts: &[TRAJECTORY_ITEMS, RUN, PROVENANCE, TRAJECTORY_COLUMNS],
};
