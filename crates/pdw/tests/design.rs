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
