//! One design evaluated: the compass preset is feasible and costs its objective; each
//! constraint, tightened past the design's own value, makes it infeasible with a cost above every
//! feasible one and a reason naming the constraint. (This used the seed5_walking design until
//! validity was located on the dense solution and impacts were checked: its stance knee buckles at
//! the knee strike, and with the knee latched its swing foot is 12.5 mm below the slope from
//! 0.416 s to 0.595 s and its trailing knee's stop pulls at heel strike, −0.092 N m s.)

use pdw_limit::basin::BasinOptions;
use pdw_limit::design::{evaluate_design, status, DesignOptions, Objective};
use pdw_walkers::{ChainWalker, Walker, WalkerSpec};

fn walker() -> Box<dyn Walker> {
    pdw_walkers::build("compass", &[]).unwrap()
}

/// seed5_walking with its stance knee latched (both ways), as `hold = "latch"` in its spec.
fn seed5_walking_latched() -> ChainWalker {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/seed5_walking.toml");
    let mut spec = WalkerSpec::from_file(std::path::Path::new(path)).unwrap();
    spec.knees[0].hold = Some("latch".into());
    ChainWalker::from_spec(spec).unwrap()
}

fn opts(objective: Objective) -> DesignOptions {
    DesignOptions {
        objective,
        mu: 0.6,
        knee_margin: 0.1,
        min_margin: 0.0,
        budget: 1,
        seed: 0,
        start: None,
        init: 0,
        basin_grid: 5,
        basin_box: Some([0.02, 0.08]),
        basin: BasinOptions {
            max_strides: 30,
            ..BasinOptions::default()
        },
        newton_tol: 1e-10,
    }
}

#[test]
fn constraints_and_objectives_of_one_design() {
    let w = walker();
    let w = w.as_ref();
    let guesses = pdw_limit::gaits::model_guesses(w);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let p = [0.0];
    let m = evaluate_design(&p, w, &guesses, &opts(Objective::Margin), &pool);
    assert_eq!(m.status, status::FEASIBLE, "{}", m.reason);
    assert!((m.cost - m.rho).abs() == 0.0 && m.rho < 0.6);
    assert!(m.max_friction <= 0.6 && m.min_normal_force > 0.0);
    assert!(m.min_knee_torque.is_nan(), "no knees");
    assert!(m.min_relative_margin > 0.0 && m.min_relative_margin < 1.0);
    // the basin objective: minus the gait's fraction of the box (the gait's own cell counts)
    let b = evaluate_design(&p, w, &guesses, &opts(Objective::Basin), &pool);
    assert_eq!(b.status, status::FEASIBLE);
    assert!(b.basin_fraction >= 1.0 / 25.0 && b.basin_fraction <= 1.0);
    assert!((b.cost - (-b.basin_fraction + 1e-3 * b.rho)).abs() < 1e-15);
    // a relative margin above the design's smallest
    let mut o = opts(Objective::Margin);
    o.min_margin = m.min_relative_margin + 0.01;
    let r = evaluate_design(&p, w, &guesses, &o, &pool);
    assert_eq!(r.status, status::INVALID);
    assert!(r.reason.contains("min margin"), "{}", r.reason);
    assert!(r.cost > 1.0 && r.cost < 5.0);
    // a friction bound below what the gait needs
    let mut o = opts(Objective::Margin);
    o.mu = m.max_friction - 0.01;
    let f = evaluate_design(&p, w, &guesses, &o, &pool);
    assert_eq!(f.status, status::INVALID);
    assert!(f.reason.contains("friction"), "{}", f.reason);
    assert!(f.cost > 1.0 && f.cost < 5.0);
    // no guess near a gait: no gait, the cost above every invalid one
    let far = vec![("far".to_string(), vec![1.2, 3.0, -3.0])];
    let n = evaluate_design(&p, w, &far, &opts(Objective::Margin), &pool);
    assert_eq!(n.status, status::NO_GAIT);
    assert_eq!(n.cost, 10.0);
    // a walker with knees: seed5_walking latched is stable but its swing foot dips below the
    // slope and its trailing knee's stop pulls at heel strike; a knee margin above its
    // smallest lock torque is named too
    let s5 = seed5_walking_latched();
    let g5 = pdw_limit::gaits::model_guesses(&s5);
    let mut o = opts(Objective::Margin);
    o.knee_margin = 10.0;
    let k = evaluate_design(&p, &s5, &g5, &o, &pool);
    assert_eq!(k.status, status::INVALID, "{}", k.reason);
    for why in [
        "swing foot below the slope",
        "heel_strike:trailing_knee",
        "knee torque",
    ] {
        assert!(k.reason.contains(why), "{why}: {}", k.reason);
    }
    assert!(k.cost > 1.0 && k.cost < 5.0 && k.min_relative_margin < 0.0);
}

/// The compass with `hip_mass` set (the preset's other values).
fn compass_with(hip_mass: f64) -> Box<dyn Walker> {
    pdw_walkers::build("compass", &[("hip_mass", hip_mass)]).unwrap()
}

#[test]
fn the_default_basin_box_scales_with_the_gait_and_tells_designs_apart() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    // the front ends' defaults: 15 × 15 cells, 40 strides, the box scaled to the gait
    let o = DesignOptions {
        basin_grid: 15,
        basin_box: None,
        basin: BasinOptions {
            max_strides: 40,
            ..BasinOptions::default()
        },
        ..opts(Objective::Basin)
    };
    let mut fractions = Vec::new();
    for hip_mass in [10.0, 4.0, 7.0, 16.0] {
        let w = compass_with(hip_mass);
        let g = pdw_limit::gaits::model_guesses(w.as_ref());
        let e = evaluate_design(&[hip_mass], w.as_ref(), &g, &o, &pool);
        assert_eq!(
            e.status,
            status::FEASIBLE,
            "hip mass {hip_mass}: {}",
            e.reason
        );
        // the box recorded is the rule's: half widths 0.15·|stance|, 0.15·|stance_rate|
        let want = [
            pdw_limit::design::BASIN_BOX_SCALE * e.section[0].abs(),
            pdw_limit::design::BASIN_BOX_SCALE * e.section[1].abs(),
        ];
        assert_eq!(e.basin_box, want);
        assert!(
            e.basin_fraction <= 0.95,
            "hip mass {hip_mass}: fraction {} fills the box",
            e.basin_fraction
        );
        fractions.push(e.basin_fraction);
    }
    // the preset's design lands well inside (0.2, 0.8): the measure is not saturated
    assert!(
        fractions[0] > 0.2 && fractions[0] < 0.8,
        "preset fraction {}",
        fractions[0]
    );
    // designs that differ get different fractions
    assert!(
        fractions
            .windows(2)
            .any(|w| (w[0] - w[1]).abs() >= 1.0 / 225.0),
        "{fractions:?}"
    );
    // an explicit box is used as given
    let fixed = DesignOptions {
        basin_box: Some([0.02, 0.08]),
        ..o.clone()
    };
    let w = compass_with(10.0);
    let g = pdw_limit::gaits::model_guesses(w.as_ref());
    let e = evaluate_design(&[10.0], w.as_ref(), &g, &fixed, &pool);
    assert_eq!(e.basin_box, [0.02, 0.08]);
}
