//! Sampling a compass-gait stride allocates nothing per sample: the model's forces, flags and
//! energy run in one reused scratch, so a walk's allocations grow only with the doublings of the
//! recorded series (logarithmic in the sample count), not with the samples.

use crate::allocs;
use pdw_limit::trajectory::{initial_state, simulate, TrajectoryOptions};

#[test]
fn trajectory_samples_allocate_nothing_per_sample() {
    let w = pdw_walkers::registry::build("compass", &[]).expect("the compass preset builds");
    let guess = &w.gait_guesses()[0].section;
    let x0 = initial_state(w.as_ref(), guess).expect("the guess lifts to a state");
    let run = |dt: f64| {
        let mut o = TrajectoryOptions::new(1);
        o.dt_out = Some(dt);
        let before = allocs();
        let tr = simulate(w.as_ref(), &x0, &o).expect("the stride simulates");
        let used = allocs() - before;
        assert!(tr.forces.is_some() && tr.flags.is_some() && tr.energy.is_some());
        (used, tr.len())
    };
    let (a1, n1) = run(1e-3);
    let (a2, n2) = run(1e-3 / 8.0);
    assert!(n1 > 500 && n2 >= 7 * n1, "samples {n1}, {n2}");
    // eight times the samples: each recorded series (time, state, mode, step, energy, four force
    // series, flags) doubles its buffer three more times, ~30 allocations; one allocation per
    // sample would add thousands
    assert!(
        a2 <= a1 + 40,
        "{a1} allocations for {n1} samples, {a2} for {n2}: more than the series' growth"
    );
}
