//! Basin cells whose verdict hinges on a guard window narrower than a fifth of an integration
//! step (a swing foot that grazes the ground, a knee that reaches straight and swings back):
//! before the event detection probed the extremum of a flagged guard's cubic, the basin's
//! default integrator missed these events and gave another verdict than a fixed step of
//! 0.0005 (the reference: too small a step to miss them). On the 101 × 101 default basins of
//! compass, kneed and seed5, 79 cells changed with the probe; 74 now equal the fine reference in
//! outcome and strides (5 kneed cells in outcome only), none did before. Three of them here.

use pdw_hybrid::Options;
use pdw_limit::{classify_cells, grid_cells, BasinOptions, BasinProblem, Outcome};

/// `(outcome, strides)` of the cell `(stance, stance_rate) = (x, y)` of `name`'s default basin
/// (the other coordinates the stable gait's), with the basin's default integrator and with a
/// fixed step of 0.0005.
fn verdicts(name: &str, x: f64, y: f64) -> [(u8, u16); 2] {
    let m = pdw::build(name, &[]).unwrap();
    let (_, section) = pdw::mfpt::start(&m).unwrap();
    let cells = grid_cells(&section, 0, &[x], 1, &[y]);
    let fall = Outcome::of_fall;
    let problem = BasinProblem::new(m.walker.as_ref(), section.clone(), &fall);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let default = BasinOptions::default();
    let fine = BasinOptions {
        integrator: Options::rk4(0.0005),
        ..default
    };
    [default, fine].map(|o| {
        let c = &classify_cells(&problem, &cells, &o, &pool, &|_| {}).unwrap()[0];
        (c.outcome, c.strides)
    })
}

#[test]
fn the_basins_verdict_on_narrow_windows_is_the_fine_steps() {
    for (name, x, y, expected) in [
        // the knee reaches straight for a moment: it locks, the walker completes two strides
        // (the window missed: it fell forward in its first); its fall is the swing foot
        // striking before the knee locked, fall_knee_bent (10)
        ("kneed", 0.2982318253167276, -1.0147548079887536, (10, 2)),
        // falls back after one stride (the window missed: labelled the gait after 32)
        ("seed5", 0.2484689706421825, -0.6421357244661431, (3, 1)),
        // one more stride before it falls forward
        ("compass", 0.3387858506235275, -1.360017569405087, (2, 2)),
    ] {
        let [default, fine] = verdicts(name, x, y);
        assert_eq!(fine, expected, "{name}: the fine reference");
        assert_eq!(
            default, fine,
            "{name}: the default integrator against the fine step"
        );
    }
}
