//! The declared formats of the files that follow one or two parameters: the bifurcation curve
//! of `fixedpoint --follow`, the basin stability of `basin --over`, the MFPT curve of
//! `mfpt --sd A:B:N` and the MFPT over a parameter of `mfpt --over` (see [`super`]).

use super::tables::{PROVENANCE, RUN};
use super::{Format, Item, Quantity, Unit};

const CURVE_ITEMS: &[Item] = &[
    Item::attr("@format", "str", "`pdw-sweep curve v1`"),
    Item::attr("@kind", "str", "`pd` (period doubling) or `fold`"),
    Item::attr(
        "@step_parameter",
        "str",
        "the parameter stepped along the curve",
    ),
    Item::attr("@free_parameter", "str", "the parameter solved for"),
    Item::attr("@section_names", "json", "the d section coordinates"),
    Item::attr("@state_names", "json", "the D state components"),
    Item::attr(
        "@complete",
        "u8",
        "1 if every requested point was reached, else 0",
    ),
    Item::attr("@end", "str", "how the curve ended, in words"),
    Item::group("curve", "the points of the curve"),
    Item::new(
        "curve/p_step",
        "f64",
        "[n]",
        Unit::Parameter,
        "the stepped parameter at each point",
    ),
    Item::new(
        "curve/p_free",
        "f64",
        "[n]",
        Unit::FreeParameter,
        "the free parameter solved for",
    ),
    Item::new(
        "curve/section",
        "f64",
        "[n, d]",
        Unit::Section,
        "section state of the critical period-one gait",
    ),
    Item::new(
        "curve/state",
        "f64",
        "[n, D]",
        Unit::State,
        "its full post-heel-strike state",
    ),
    Item::new(
        "curve/multipliers_re",
        "f64",
        "[n, d]",
        Unit::One,
        "real parts of the Floquet multipliers (decreasing modulus)",
    ),
    Item::new(
        "curve/multipliers_im",
        "f64",
        "[n, d]",
        Unit::One,
        "their imaginary parts",
    ),
    Item::new(
        "curve/critical",
        "f64",
        "[n]",
        Unit::One,
        "the real multiplier at −1 (pd) or +1 (fold)",
    ),
    Item::new(
        "curve/period",
        "f64",
        "[n]",
        Unit::Model(Quantity::Time),
        "stride duration",
    ),
    Item::new(
        "curve/residual",
        "f64",
        "[n]",
        Unit::MaxOverSection("curve/section"),
        "‖P(x) − x‖∞ re-computed with a fresh stride",
    ),
    Item::group("map", "the region map drawn under the curve").only("`--map-grid`"),
    Item::new(
        "map/step",
        "f64",
        "[nx]",
        Unit::Parameter,
        "stepped-parameter values (columns)",
    )
    .only("`--map-grid`"),
    Item::new(
        "map/free",
        "f64",
        "[ny]",
        Unit::FreeParameter,
        "free-parameter values (rows)",
    )
    .only("`--map-grid`"),
    Item::new(
        "map/region",
        "u8",
        "[ny, nx]",
        Unit::One,
        "region code of each cell (row j = free[j], column i = step[i])",
    )
    .only("`--map-grid`"),
    Item::attr("map/region@legend", "json", "region code → name").only("`--map-grid`"),
];

/// The curve file of `pdw-sweep fixedpoint --follow pd|fold` (`format = "pdw-sweep curve v1"`).
pub const CURVE: Format = Format {
    name: "curve",
    format: crate::curve::CURVE_FORMAT,
    parts: &[CURVE_ITEMS, RUN, PROVENANCE],
};

const STABILITY_ITEMS: &[Item] = &[
    Item::attr("@format", "str", "`pdw-sweep basin-stability v1`"),
    Item::attr("@parameter", "str", "the parameter varied"),
    Item::attr(
        "@box",
        "json",
        "the two axes with their ranges and cell counts, the fixed coordinates, and where the \
         box came from",
    ),
    Item::attr(
        "@max_strides",
        "u64",
        "strides a cell may walk before it is a timeout",
    ),
    Item::attr("@elapsed_s", "f64", "wall time (s)"),
    Item::attr(
        "@setting_<name>",
        "json",
        "one entry of the run's settings (the integrator, the basin options)",
    ),
    Item::new(
        "parameter",
        "f64",
        "[N]",
        Unit::Parameter,
        "the parameter values",
    ),
    Item::new(
        "fractions",
        "f64",
        "[N, C]",
        Unit::One,
        "fraction of the box per column; each row sums to 1",
    ),
    Item::attr(
        "fractions@columns",
        "json",
        "the C column names: the attractors met at any value, then `fall`, `timeout`, `other`",
    ),
    Item::attr(
        "fractions@kinds",
        "json",
        "each column's kind: `attractor`, `fall`, `timeout` or `other`",
    ),
    Item::new(
        "outcome_fractions",
        "f64",
        "[N, 13]",
        Unit::One,
        "the fixed basin outcomes (by code) before attractors are told apart",
    ),
    Item::attr(
        "outcome_fractions@columns",
        "json",
        "the outcome names, by code",
    ),
    Item::group("values", "one group per parameter value"),
    Item::group("values/<NNN>", "the attractors found at value NNN"),
    Item::attr("values/<NNN>@parameter", "f64", "the parameter value"),
    Item::attr(
        "values/<NNN>@attractors",
        "json",
        "one object per attractor: name, period_strides (0 = chaotic), period_time, points, \
         multipliers, validity, invalid_reasons",
    ),
];

/// The basin-stability file of `pdw-sweep basin --over` (`format = "pdw-sweep
/// basin-stability v1"`).
pub const STABILITY: Format = Format {
    name: "stability",
    format: crate::stability::STABILITY_FORMAT,
    parts: &[STABILITY_ITEMS, RUN, PROVENANCE],
};

/// The attributes and datasets an MFPT curve and an MFPT over a parameter share, under the
/// group `$g` (`curve` or `over`).
macro_rules! series_items {
    ($g:literal) => {
        &[
            Item::attr(concat!($g, "@terrain"), "str", "`slope` or `step-down`"),
            Item::attr(
                concat!($g, "@distribution"),
                "str",
                "the distribution of the standardised draws, in words",
            ),
            Item::attr(concat!($g, "@seed"), "u64", "seed of the terrain draws"),
            Item::attr(concat!($g, "@walkers"), "u64", "walkers started per value"),
            Item::attr(
                concat!($g, "@max_steps"),
                "u64",
                "heel strikes a walker may complete",
            ),
            Item::attr(
                concat!($g, "@estimator"),
                "str",
                "how `mfpt` and `stderr` were estimated, in words",
            ),
            Item::attr(
                concat!($g, "@chain_mesh_coarse"),
                "u64",
                "the Markov chain's coarse mesh (0 without the chain)",
            ),
            Item::attr(
                concat!($g, "@chain_mesh_fine"),
                "u64",
                "its fine mesh (0 without the chain)",
            ),
            Item::new(
                concat!($g, "/mfpt"),
                "f64",
                "[N]",
                Unit::Fixed("steps"),
                "mean first-passage time (strides)",
            ),
            Item::new(
                concat!($g, "/stderr"),
                "f64",
                "[N]",
                Unit::Fixed("steps"),
                "its standard error",
            ),
            Item::new(
                concat!($g, "/restricted_mean"),
                "f64",
                "[N]",
                Unit::Fixed("steps"),
                "mean of min(strides, max_steps)",
            ),
            Item::new(
                concat!($g, "/chain_mfpt_coarse"),
                "f64",
                "[N]",
                Unit::Fixed("steps"),
                "the chain's MFPT on the coarse mesh (NaN where it did not run)",
            ),
            Item::new(
                concat!($g, "/chain_mfpt_fine"),
                "f64",
                "[N]",
                Unit::Fixed("steps"),
                "the same on the fine mesh",
            ),
            Item::new(
                concat!($g, "/falls"),
                "u64",
                "[N]",
                Unit::Fixed("walkers"),
                "walkers that fell",
            ),
            Item::new(
                concat!($g, "/censored"),
                "u64",
                "[N]",
                Unit::Fixed("walkers"),
                "walkers still walking at max_steps",
            ),
            Item::new(
                concat!($g, "/total_steps"),
                "u64",
                "[N]",
                Unit::Fixed("steps"),
                "heel strikes completed by all walkers",
            ),
        ]
    };
}

const MFPT_CURVE_SHARED: &[Item] = series_items!("curve");

const MFPT_CURVE_ITEMS: &[Item] = &[
    Item::attr("@format", "str", "`pdw-sweep mfpt curve v1`"),
    Item::group(
        "curve",
        "the MFPT at each standard deviation σ, one Monte Carlo run each",
    ),
    Item::attr(
        "curve@terrain_unit",
        "str",
        "unit of `mean` and `sd`: `rad`, or the model's length unit",
    ),
    Item::attr("curve@mean", "f64", "mean of the terrain (in terrain_unit)"),
    Item::new(
        "curve/sd",
        "f64",
        "[N]",
        Unit::Terrain,
        "the standard deviations (terrain_unit)",
    ),
];

/// The MFPT curve file of `pdw-sweep mfpt --sd A:B:N` (`format = "pdw-sweep mfpt curve v1"`).
pub const MFPT_CURVE: Format = Format {
    name: "mfpt_curve",
    format: crate::mfpt::MFPT_CURVE_FORMAT,
    parts: &[MFPT_CURVE_ITEMS, MFPT_CURVE_SHARED, RUN, PROVENANCE],
};

const MFPT_OVER_SHARED: &[Item] = series_items!("over");

const MFPT_OVER_ITEMS: &[Item] = &[
    Item::attr("@format", "str", "`pdw-sweep mfpt over v1`"),
    Item::group(
        "over",
        "the MFPT and the gait sensitivity norm at each value of the parameter",
    ),
    Item::attr("over@param", "str", "the parameter's name"),
    Item::attr("over@sd", "f64", "standard deviation of the slope (rad)"),
    Item::attr(
        "over@indicators",
        "str",
        "the gait indicators of the norm, comma separated",
    ),
    Item::attr(
        "over@spearman",
        "f64",
        "rank correlation of GSN and MFPT over the values with both (NaN with fewer than 2)",
    ),
    Item::new(
        "over/values",
        "f64",
        "[N]",
        Unit::Parameter,
        "the parameter's values",
    ),
    Item::new(
        "over/mean",
        "f64",
        "[N]",
        Unit::Fixed("rad"),
        "the mean slope at each value",
    ),
    Item::new(
        "over/stable",
        "u64",
        "[N]",
        Unit::One,
        "1 where the model has a stable period-one gait, else 0 (every other column is NaN or 0 \
         there)",
    ),
    Item::new(
        "over/gsn",
        "f64",
        "[N]",
        Unit::Fixed("indicator units per rad"),
        "gait sensitivity norm of the stable gait (Hobbelen & Wisse 2007)",
    ),
];

/// The file of `pdw-sweep mfpt --over PARAM=A:B:N` (`format = "pdw-sweep mfpt over v1"`).
pub const MFPT_OVER: Format = Format {
    name: "mfpt_over",
    format: crate::mfpt_over::MFPT_OVER_FORMAT,
    parts: &[MFPT_OVER_ITEMS, MFPT_OVER_SHARED, RUN, PROVENANCE],
};
