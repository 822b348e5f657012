//! [`branch_at_params`]: a continued branch put on a requested parameter grid, checked against
//! closed-form fixed points and 2-cycles (maps run as hybrid systems whose stride map is exactly
//! the map), through a period doubling and around a fold.

use crate::continuation_maps as maps;

use maps::{logistic, saddle_node};
use pdw_limit::{
    branch_at_params, continue_branch, linspace, switch_period_doubling, BifurcationKind,
    ContinuationOptions,
};

fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
}

#[test]
fn logistic_branches_on_a_grid_are_the_closed_form_fixed_points_and_two_cycles() {
    let opts = ContinuationOptions::new(2.2, 3.4);
    let grid = linspace(2.2, 3.4, 13);
    let one = continue_branch(&logistic, &[1.0 - 1.0 / 2.2], 2.2, 1, &opts).unwrap();
    assert!(
        one.points.len() > grid.len(),
        "the continuation steps more finely"
    );
    let on = branch_at_params(&logistic, &one, &grid, &opts, &pool(2)).unwrap();
    // Exactly one point per grid value, in order, each at exactly that value.
    assert_eq!(
        on.iter().map(|p| p.index).collect::<Vec<_>>(),
        (0..13).collect::<Vec<_>>()
    );
    for sp in &on {
        let p = sp.point.as_ref().unwrap();
        assert_eq!(p.param, grid[sp.index]);
        // Fixed point 1 − 1/μ, multiplier 2 − μ.
        assert!(
            (p.section[0] - (1.0 - 1.0 / p.param)).abs() < 1e-10,
            "{p:?}"
        );
        assert!(
            (p.multipliers[0].re - (2.0 - p.param)).abs() < 1e-9,
            "{p:?}"
        );
        assert_eq!(p.orbit, vec![p.section.clone()]);
    }
    // The 2-cycle beyond μ = 3: both points, each a root of μ²x² − μ(μ+1)x + (μ+1) = 0, and
    // the map takes one to the other.
    let pd = one
        .bifurcations
        .iter()
        .find(|b| b.kind == BifurcationKind::PeriodDoubling)
        .unwrap();
    let two = switch_period_doubling(&logistic, pd, &opts).unwrap();
    let on2 = branch_at_params(&logistic, &two, &grid, &opts, &pool(1)).unwrap();
    // The switched branch starts a switching offset past μ = 3 (its first point is corrected
    // at ε = 10⁻³ from the period-1 point, where μ − 3 ~ ε²); grid values before it, here
    // μ = 3 itself where the 2-cycle degenerates onto the fixed point, are not on it.
    let start = two.points[0].param;
    assert!(start > pd.param && start - pd.param < 1e-4, "{start}");
    let beyond: Vec<usize> = (0..13).filter(|&i| grid[i] > start).collect();
    assert_eq!(beyond[0], 9);
    assert_eq!(on2.iter().map(|p| p.index).collect::<Vec<_>>(), beyond);
    for sp in &on2 {
        let p = sp.point.as_ref().unwrap();
        let mu = p.param;
        assert_eq!(p.orbit.len(), 2);
        for x in [p.orbit[0][0], p.orbit[1][0]] {
            assert!((mu * mu * x * x - mu * (mu + 1.0) * x + mu + 1.0).abs() < 1e-10);
        }
        let image = mu * p.orbit[0][0] * (1.0 - p.orbit[0][0]);
        assert!((image - p.orbit[1][0]).abs() < 1e-10);
        assert!((p.orbit[0][0] - p.orbit[1][0]).abs() > 1e-3);
    }
    // The same on one or two threads.
    let again = branch_at_params(&logistic, &two, &grid, &opts, &pool(2)).unwrap();
    assert_eq!(on2, again);
}

#[test]
fn a_branch_that_folds_gives_a_point_per_crossing() {
    // x ↦ x + μ − x²: fixed points ±√μ for μ > 0, fold at μ = 0. From +√0.25 down through the
    // fold and back up along −√μ every grid value in (0, 0.25] is crossed twice.
    let mut opts = ContinuationOptions::new(-0.1, 0.26);
    opts.direction = -1.0;
    let branch = continue_branch(&saddle_node, &[0.5], 0.25, 1, &opts).unwrap();
    let grid = linspace(0.01, 0.25, 7);
    let on = branch_at_params(&saddle_node, &branch, &grid, &opts, &pool(2)).unwrap();
    let idx: Vec<usize> = on.iter().map(|p| p.index).collect();
    assert_eq!(idx, vec![6, 5, 4, 3, 2, 1, 0, 0, 1, 2, 3, 4, 5, 6]);
    for (k, sp) in on.iter().enumerate() {
        let p = sp.point.as_ref().unwrap();
        let root = p.param.sqrt() * if k < 7 { 1.0 } else { -1.0 };
        assert!((p.section[0] - root).abs() < 1e-10, "{p:?} vs {root}");
        assert_eq!(p.stable, k < 7, "+√μ stable (λ = 1 − 2√μ), −√μ not");
    }
}
