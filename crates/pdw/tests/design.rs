//! The design search's report: a best design on a face of its box is named.

use pdw::design::bound_warnings;
use pdw_limit::design::DesignSpace;

#[test]
fn a_best_design_on_a_bound_is_named_with_the_side() {
    let space = DesignSpace {
        names: vec!["hip_mass".into(), "a".into()],
        lo: vec![5.0, 0.3],
        hi: vec![15.0, 0.7],
    };
    // Inside the box: nothing to say.
    assert!(bound_warnings(&space, &[10.0, 0.5]).is_empty());
    // 1 % of the range (0.1 kg, 0.004 m) from a bound is on it; 2 % is not.
    let w = bound_warnings(&space, &[5.1, 0.5]);
    assert_eq!(w.len(), 1);
    assert!(
        w[0].contains("hip_mass = 5.1 at the lower bound 5"),
        "{}",
        w[0]
    );
    assert!(bound_warnings(&space, &[5.2, 0.5]).is_empty());
    let w = bound_warnings(&space, &[10.0, 0.7]);
    assert!(w[0].contains("a = 0.7 at the upper bound 0.7"), "{}", w[0]);
    assert_eq!(bound_warnings(&space, &[15.0, 0.3]).len(), 2);
}

/// A design whose cost is `f(p)` (a stand-in for a walker's evaluation: the search only sees
/// costs).
fn bowl_eval(p: &[f64], centre: &[f64]) -> pdw_limit::design::DesignEval {
    let mut e = pdw_limit::design::DesignEval::bad_model(p, String::new());
    e.status = pdw_limit::design::status::FEASIBLE;
    e.cost = p.iter().zip(centre).map(|(a, b)| (a - b).powi(2)).sum();
    e
}

fn bowl_options(budget: usize, init: usize) -> pdw_limit::design::DesignOptions {
    pdw_limit::design::DesignOptions {
        objective: pdw_limit::design::Objective::Margin,
        mu: 0.6,
        knee_margin: 0.0,
        min_margin: 0.0,
        budget,
        seed: 7,
        start: None,
        init,
        basin_grid: 3,
        basin_box: None,
        basin: pdw_limit::basin::BasinOptions::default(),
        newton_tol: 1e-10,
    }
}

#[test]
fn a_budget_smaller_than_the_simplex_ends_the_search_without_a_panic() {
    // seven free parameters need eight simplex vertices; budget 8 with 4 random designs
    // leaves 3 after the start and the random ones (the seed5 redesign's `--budget 8 --init 4`)
    let k = 7;
    let space = DesignSpace {
        names: (0..k).map(|i| format!("p{i}")).collect(),
        lo: vec![0.0; k],
        hi: vec![1.0; k],
    };
    let centre = vec![0.3; k];
    let mut eval = |p: &[f64], _: &[(String, Vec<f64>)]| bowl_eval(p, &centre);
    let h =
        pdw_limit::design::search(&space, &bowl_options(8, 4), &[], Vec::new(), &mut eval).unwrap();
    assert_eq!(
        h.len(),
        8,
        "every design of the budget is evaluated, no more"
    );
    // with budget to spare, Nelder–Mead on the quadratic bowl reaches its minimum (0 at the
    // centre) from the best of the random designs
    let mut eval = |p: &[f64], _: &[(String, Vec<f64>)]| bowl_eval(p, &centre[..2]);
    let space2 = DesignSpace {
        names: vec!["a".into(), "b".into()],
        lo: vec![0.0; 2],
        hi: vec![1.0; 2],
    };
    let h = pdw_limit::design::search(&space2, &bowl_options(150, 4), &[], Vec::new(), &mut eval)
        .unwrap();
    assert!(h.len() <= 150);
    let best = h.iter().map(|e| e.cost).fold(f64::INFINITY, f64::min);
    assert!(best < 1e-6, "best cost {best}");
}

use pdw_limit::design::{graded_cost, Grade, Shortfall, PROBE_STRIDES};

#[test]
fn the_graded_cost_is_the_documented_formula_at_hand_computed_designs() {
    // stable, invalid: 1 + 3 δ/(1 + δ) + 0.5 ρ, δ = d / 0.01 (the shortfall in per cent)
    assert_eq!(pdw_limit::design::SHORTFALL_UNIT, 0.01);
    assert!((graded_cost(Grade::Gait { rho: 0.5, d: 0.01 }) - 2.75).abs() < 1e-14);
    assert!(
        (graded_cost(Grade::Gait {
            rho: 0.8,
            d: 0.0025
        }) - 2.0)
            .abs()
            < 1e-14
    );
    // a per cent of shortfall outweighs any change of ρ below 1 (1.5 against at most 0.5)
    assert!(
        graded_cost(Grade::Gait { rho: 0.99, d: 0.01 })
            < graded_cost(Grade::Gait { rho: 0.0, d: 0.02 })
    );
    // unstable: 5 + 2 (1 − 1/ρ) + 2 δ/(1 + δ)
    assert!((graded_cost(Grade::Gait { rho: 2.0, d: 0.0 }) - 6.0).abs() < 1e-15);
    assert!((graded_cost(Grade::Gait { rho: 1.25, d: 0.03 }) - 6.9).abs() < 1e-14);
    // no gait: 9 + 0.5 (1 − n/N) + 0.5 q/(1 + q); nothing walked and no stride is the old 10
    let ng = |n, q| graded_cost(Grade::NoGait { n, of: 10, q });
    assert!((ng(5, 1.0) - 9.5).abs() < 1e-15);
    assert_eq!(ng(0, f64::INFINITY), 10.0);
    assert_eq!(ng(10, 0.0), 9.0);
    assert_eq!(graded_cost(Grade::BadModel), 11.0);
    // the shortfall from its quantities: margin 0.01 − (−0.03), friction (0.7 − 0.6)/0.6, knee
    // torque (0.1 − 0.05)/5, one discrete failure at 0.5
    let s = Shortfall::of((-0.03, 0.01), (0.7, 0.6), (0.05, 0.1, 5.0), 1);
    assert!((s.margin - 0.04).abs() < 1e-15);
    assert!((s.friction - 0.1 / 0.6).abs() < 1e-15);
    assert!((s.knee - 0.01).abs() < 1e-15);
    assert!((s.total() - (0.04 + 0.1 / 0.6 + 0.01 + 0.5)).abs() < 1e-15);
    // what is not measured or already met adds nothing
    let none = Shortfall::of((f64::NAN, 0.01), (0.3, 0.6), (f64::NAN, 0.1, 5.0), 0);
    assert_eq!(none.total(), 0.0);
    assert_eq!(
        Shortfall::of((0.2, 0.01), (0.6, 0.6), (3.0, 0.1, 5.0), 0).total(),
        0.0
    );
}

#[test]
fn the_graded_cost_is_monotone_in_each_quantity_and_its_bands_are_ordered() {
    let ds = [0.0, 1e-3, 0.01, 0.1, 0.5, 1.0, 3.0, 30.0, f64::INFINITY];
    let stable = [0.0, 0.3, 0.6, 0.9, 0.999];
    let unstable = [1.0, 1.001, 1.5, 3.0, 100.0];
    for w in ds.windows(2) {
        for &rho in stable.iter().chain(&unstable) {
            let (a, b) = (
                graded_cost(Grade::Gait { rho, d: w[0] }),
                graded_cost(Grade::Gait { rho, d: w[1] }),
            );
            assert!(
                a < b || (w[1].is_infinite() && a <= b),
                "d {w:?} at ρ {rho}: {a} {b}"
            );
        }
    }
    for rhos in [&stable[..], &unstable[..]] {
        for w in rhos.windows(2) {
            for &d in &ds {
                let (a, b) = (
                    graded_cost(Grade::Gait { rho: w[0], d }),
                    graded_cost(Grade::Gait { rho: w[1], d }),
                );
                assert!(a < b, "ρ {w:?} at d {d}: {a} {b}");
            }
        }
    }
    // every stable invalid design below every unstable one, every unstable one below (or at)
    // every design without a gait
    let worst_stable = graded_cost(Grade::Gait {
        rho: 0.999,
        d: f64::INFINITY,
    });
    let best_unstable = graded_cost(Grade::Gait { rho: 1.0, d: 0.0 });
    assert!(worst_stable < best_unstable);
    let worst_unstable = graded_cost(Grade::Gait { rho: 1e12, d: 1e12 });
    let best_no_gait = graded_cost(Grade::NoGait {
        n: PROBE_STRIDES,
        of: PROBE_STRIDES,
        q: 0.0,
    });
    assert!(worst_unstable <= best_no_gait);
    // more strides walked is better, a smaller stride-to-stride change is better
    let qs = [0.0, 1e-6, 1e-2, 1.0, 10.0, f64::INFINITY];
    for n in 0..PROBE_STRIDES {
        for &q in &qs {
            let at = |n| {
                graded_cost(Grade::NoGait {
                    n,
                    of: PROBE_STRIDES,
                    q,
                })
            };
            assert!(at(n + 1) < at(n), "n {n} q {q}");
        }
    }
    for w in qs.windows(2) {
        let at = |q| {
            graded_cost(Grade::NoGait {
                n: 3,
                of: PROBE_STRIDES,
                q,
            })
        };
        assert!(at(w[0]) < at(w[1]), "q {w:?}");
    }
}

/// Two basins on the unit square: a wide local one at `A` (cost 0.5 at its bottom) and the
/// global one at `B` (cost 0).
const A: [f64; 2] = [0.2, 0.2];
const B: [f64; 2] = [0.8, 0.7];

fn two_basins(p: &[f64]) -> pdw_limit::design::DesignEval {
    let mut e = pdw_limit::design::DesignEval::bad_model(p, String::new());
    e.status = pdw_limit::design::status::FEASIBLE;
    let d2 = |c: &[f64; 2]| (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2);
    e.cost = (0.5 + 2.0 * d2(&A)).min(2.0 * d2(&B));
    e
}

fn square() -> DesignSpace {
    DesignSpace {
        names: vec!["a".into(), "b".into()],
        lo: vec![0.0; 2],
        hi: vec![1.0; 2],
    }
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

fn multi(
    budget: usize,
    starts: usize,
    history: Vec<pdw_limit::design::DesignEval>,
    threads: usize,
) -> Vec<pdw_limit::design::DesignEval> {
    let mut o = bowl_options(budget, 0);
    o.start = Some(A.to_vec());
    let eval = |_: u32, p: &[f64], _: &[(String, Vec<f64>)]| two_basins(p);
    pdw_limit::design::search_multi(&square(), &o, starts, &[], history, &eval, &pool(threads))
        .unwrap()
}

fn bits(h: &[pdw_limit::design::DesignEval]) -> Vec<(u32, Vec<u64>, u64)> {
    h.iter()
        .map(|e| {
            (
                e.run,
                e.params.iter().map(|v| v.to_bits()).collect(),
                e.cost.to_bits(),
            )
        })
        .collect()
}

#[test]
fn a_multi_start_finds_the_global_optimum_a_single_start_misses() {
    // one run from A stays in A's basin
    let one = multi(120, 1, Vec::new(), 1);
    let best1 = one.iter().map(|e| e.cost).fold(f64::INFINITY, f64::min);
    assert!(best1 > 0.49, "a single run from A left its basin: {best1}");
    // eight runs, seven from seeded random designs: the global minimum at B
    let many = multi(480, 8, Vec::new(), 2);
    assert!(many.len() <= 480);
    let b = many
        .iter()
        .min_by(|x, y| x.cost.total_cmp(&y.cost))
        .unwrap();
    // B's floor is 0, A's 0.49 or more: a cost this small is B's basin, converged as far as 60
    // Nelder–Mead evaluations per run go (|p − B| ~ 4e-4)
    assert!(b.cost < 1e-6, "best cost {}", b.cost);
    assert!((b.params[0] - B[0]).abs() < 1e-3 && (b.params[1] - B[1]).abs() < 1e-3);
    // run 0 is the single search itself (the same designs, in the same order)
    let mut o = bowl_options(60, 0);
    o.start = Some(A.to_vec());
    let mut eval = |p: &[f64], _: &[(String, Vec<f64>)]| two_basins(p);
    let single = pdw_limit::design::search(&square(), &o, &[], Vec::new(), &mut eval).unwrap();
    let run0: Vec<_> = many.iter().filter(|e| e.run == 0).cloned().collect();
    assert_eq!(bits(&single), bits(&run0));
}

#[test]
fn a_multi_start_is_the_same_on_one_and_two_threads_and_after_a_resume() {
    let full = multi(200, 5, Vec::new(), 1);
    assert_eq!(full.len(), 200);
    assert_eq!(bits(&full), bits(&multi(200, 5, Vec::new(), 2)));
    // a killed run's file: each run's first designs (a different number per run), stored in
    // the order the threads finished them (interleaved); resumed, the same search
    let prefixes: Vec<Vec<pdw_limit::design::DesignEval>> = (0..5u32)
        .map(|r| {
            let keep = [3usize, 17, 0, 40, 9][r as usize];
            full.iter()
                .filter(|e| e.run == r)
                .take(keep)
                .cloned()
                .collect()
        })
        .collect();
    let mut killed = Vec::new();
    for i in 0..40 {
        for p in prefixes.iter().rev() {
            if let Some(e) = p.get(i) {
                killed.push(e.clone());
            }
        }
    }
    assert_eq!(killed.len(), 3 + 17 + 40 + 9);
    assert_eq!(bits(&full), bits(&multi(200, 5, killed, 2)));
    // zero starts are refused
    let mut o = bowl_options(10, 0);
    o.start = None;
    let eval = |_: u32, p: &[f64], _: &[(String, Vec<f64>)]| two_basins(p);
    let e = pdw_limit::design::search_multi(&square(), &o, 0, &[], Vec::new(), &eval, &pool(1));
    assert!(e.is_err());
}

/// A stop-only design without a gait is graded by its latched twin: Hsu Chen's walker with
/// stops (its stance knee buckles at the knee strike) costs exactly what `models/kneed.toml`
/// — the same walker with ideal latches, evaluated on its own — costs, its gait invalid by the
/// pull its latches give; and the cost moves with the design (the flat 9.75 of a buckle before).
#[test]
fn a_stop_only_design_without_a_gait_costs_what_its_latched_twin_costs() {
    use pdw::design::{evaluate, DesignPlan};
    use pdw_limit::design::{status, DesignOptions, Objective};
    let kneed = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/kneed.toml"
    ))
    .unwrap();
    let stops_text = kneed.replace("hold = \"latch\"", "hold = \"stop\"");
    assert_ne!(stops_text, kneed);
    let stops = std::env::temp_dir().join(format!("kneed-stops-{}.toml", std::process::id()));
    std::fs::write(&stops, stops_text).unwrap();
    let plan = |model: &str| DesignPlan {
        model: pdw::ModelChoice {
            model: model.into(),
            slope: None,
            set: Vec::new(),
        },
        space: DesignSpace {
            names: vec!["hip_mass".into()],
            lo: vec![0.3],
            hi: vec![0.7],
        },
        options: DesignOptions {
            objective: Objective::Margin,
            mu: 0.8,
            knee_margin: 0.0,
            min_margin: 0.0,
            budget: 1,
            seed: 0,
            start: None,
            init: 0,
            basin_grid: 5,
            basin_box: None,
            basin: pdw_limit::basin::BasinOptions::default(),
            newton_tol: 1e-10,
        },
        starts: 1,
    };
    // each search's guesses are its own model's (the stops' section has `swing_knee_rate`)
    let guesses = |m: &str| {
        let base = pdw::build(m, &[]).unwrap();
        pdw_limit::gaits::model_guesses(base.walker.as_ref())
    };
    let (g_stops, g) = (guesses(stops.to_str().unwrap()), guesses("kneed"));
    assert_eq!(g_stops[0].1.len(), 4, "{g_stops:?}");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let (stops_plan, latched_plan) = (plan(stops.to_str().unwrap()), plan("kneed"));
    for hip in [0.5, 0.45] {
        let with_stops = evaluate(&stops_plan, &[hip], &g_stops, &pool);
        let latched = evaluate(&latched_plan, &[hip], &g, &pool);
        assert_eq!(with_stops.status, status::NO_GAIT, "{}", with_stops.reason);
        assert!(
            with_stops.fates.contains("stance knee buckled"),
            "{}",
            with_stops.fates
        );
        assert_eq!(latched.status, status::INVALID, "{}", latched.reason);
        assert_eq!(with_stops.cost, latched.cost, "hip_mass {hip}");
        assert!((1.0..4.5).contains(&with_stops.cost), "{}", with_stops.cost);
        assert!(
            with_stops
                .reason
                .contains("with ideal latches for its stops: invalid"),
            "{}",
            with_stops.reason
        );
    }
    let at = |hip: f64| evaluate(&stops_plan, &[hip], &g_stops, &pool).cost;
    assert_ne!(at(0.5), at(0.45), "the cost does not move with the design");
    let _ = std::fs::remove_file(&stops);
}
