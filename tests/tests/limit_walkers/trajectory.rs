//! Trajectories as physics claims: energy is conserved by the flow between impacts; a walk
//! started on a gait repeats step after step.

use pdw_limit::gaits;
use pdw_limit::trajectory::{self, TrajectoryOptions};

fn stable_gait(model: &str) -> (Box<dyn pdw_walkers::Walker>, pdw_limit::FixedPoint) {
    let w = pdw_walkers::build(model, &[]).unwrap();
    let (found, _) = gaits::search(w.as_ref(), &gaits::model_guesses(w.as_ref()), 1e-12).unwrap();
    let fp = found.into_iter().find(|f| f.fp.stable).unwrap().fp;
    (w, fp)
}

#[test]
fn energy_conserved_between_impacts_compass() {
    let (w, fp) = stable_gait("compass");
    let tr = trajectory::simulate(w.as_ref(), &fp.state, &TrajectoryOptions::new(3)).unwrap();
    assert!(tr.outcome.is_ok() && tr.steps_done == 3);
    let e = tr
        .energy
        .as_ref()
        .expect("the compass gait defines its energy");
    // Samples between two events: same step index, same mode, and not the post-impact copy.
    for step in 0..3u32 {
        let idx: Vec<usize> = (0..tr.len()).filter(|&i| tr.step[i] == step).collect();
        assert!(idx.len() > 5);
        let (lo, hi) = idx
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &i| {
                (a.min(e[i]), b.max(e[i]))
            });
        // DOP853 at 1e-10 on angles and rates of order 1: the energy (≈150 J) drifts by far
        // less than 1e-8 relative over a step.
        assert!(
            (hi - lo) <= 1e-8 * lo.abs(),
            "step {step}: energy varies by {} J over {} samples",
            hi - lo,
            idx.len()
        );
    }
}

#[test]
fn gait_trajectory_is_periodic_over_steps() {
    for model in ["simplest", "compass", "kneed"] {
        let (w, fp) = stable_gait(model);
        let tr = trajectory::simulate(w.as_ref(), &fp.state, &TrajectoryOptions::new(3)).unwrap();
        assert!(tr.outcome.is_ok(), "{model}: {:?}", tr.outcome);
        let ds = fp.section.len();
        // Section after every step equals the fixed point.
        for k in 0..3 {
            for (a, b) in tr.section[k * ds..(k + 1) * ds].iter().zip(&fp.section) {
                assert!((a - b).abs() < 1e-8, "{model} step {k}: {a} vs {b}");
            }
        }
        // Step-ending events every period T.
        let ends: Vec<f64> = tr
            .events
            .iter()
            .filter(|e| e.ends_step)
            .map(|e| e.t)
            .collect();
        assert_eq!(ends.len(), 3);
        for (k, t) in ends.iter().enumerate() {
            let want = (k + 1) as f64 * fp.metrics.period;
            assert!(
                (t - want).abs() < 1e-8 * want,
                "{model}: event {k} at {t}, expected {want}"
            );
        }
        // The pre-impact states of successive heel strikes repeat.
        let pre: Vec<&Vec<f64>> = tr
            .events
            .iter()
            .filter(|e| e.ends_step)
            .map(|e| &e.pre)
            .collect();
        for k in 1..3 {
            for (a, b) in pre[k].iter().zip(pre[0]) {
                assert!((a - b).abs() < 1e-8, "{model}: heel strike {k}: {a} vs {b}");
            }
        }
    }
}

#[test]
fn output_grid_samples_at_multiples_of_dt_and_a_fall_ends_the_walk() {
    let w = pdw_walkers::build("simplest", &[]).unwrap();
    let x0 = trajectory::initial_state(w.as_ref(), &[0.2003109, -0.1998325]).unwrap();
    let opts = TrajectoryOptions {
        dt_out: Some(0.25),
        ..TrajectoryOptions::new(2)
    };
    let tr = trajectory::simulate(w.as_ref(), &x0, &opts).unwrap();
    assert!(tr.outcome.is_ok());
    for (k, t) in tr.t.iter().enumerate() {
        assert_eq!(*t, k as f64 * 0.25);
    }
    // Leaning back with little speed: the walker falls backward in the first step.
    let x0 = trajectory::initial_state(w.as_ref(), &[0.3, -0.1]).unwrap();
    let tr = trajectory::simulate(w.as_ref(), &x0, &TrajectoryOptions::new(5)).unwrap();
    assert_eq!(tr.steps_done, 0);
    assert!(matches!(tr.outcome, pdw_limit::StrideOutcome::Fall { .. }));
    assert!(tr.events.last().unwrap().fall);
    // Bad input is an error naming the value.
    let e = trajectory::initial_state(w.as_ref(), &[0.1, 0.2, 0.3]).unwrap_err();
    assert!(e.to_string().contains("3 values given"));
    let e = trajectory::simulate(w.as_ref(), &x0, &TrajectoryOptions::new(0)).unwrap_err();
    assert!(e.to_string().contains("steps"));
}
