//! Continuation, bifurcation location and branch switching on maps whose bifurcations are known
//! in closed form (each map is run as a hybrid system whose stride map is exactly the map).

use crate::continuation_maps as maps;

use maps::{logistic, neimark_sacker, saddle_node, NS_OMEGA};
use pdw_limit::{
    continue_branch, period_doubling_cascade, switch_period_doubling, BifurcationKind, BranchEnd,
    ContinuationMethod, ContinuationOptions,
};

#[test]
fn logistic_period_doubling_located_at_mu_3_and_period_two_branch_doubles_at_one_plus_sqrt6() {
    let opts = ContinuationOptions::new(2.0, 3.52);
    let branch = continue_branch(&logistic, &[0.55], 2.5, 1, &opts).unwrap();
    // Every point is the closed-form fixed point 1 − 1/μ with multiplier 2 − μ, to the
    // accuracy the residual allows: |x − x*| ≤ ‖P(x) − x‖ / |1 − λ|.
    for p in &branch.points {
        let lambda = 2.0 - p.param;
        let dx = p.residual / (1.0 - lambda).abs() + 1e-15;
        assert!(
            (p.section[0] - (1.0 - 1.0 / p.param)).abs() <= 1.01 * dx,
            "{p:?}"
        );
        // (+1e-12: DL and DΠ inside the variational DP are Richardson differences, ~1e-13.)
        assert!(
            (p.multipliers[0].re - lambda).abs() <= 2.0 * p.param * dx + 1e-12,
            "{p:?}"
        );
    }
    let pd: Vec<_> = branch
        .bifurcations
        .iter()
        .filter(|b| b.kind == BifurcationKind::PeriodDoubling)
        .collect();
    assert_eq!(pd.len(), 1, "{:?}", branch.bifurcations);
    assert!((pd[0].param - 3.0).abs() < 1e-9, "PD at {}", pd[0].param);
    // Branch switching onto the 2-cycle, whose own period doubling is at μ = 1 + √6.
    let two = switch_period_doubling(&logistic, pd[0], &opts).unwrap();
    assert_eq!(two.period_strides, 2);
    let p2 = &two.points[two.points.len() / 2];
    let (a, b) = (p2.orbit[0][0], p2.orbit[1][0]);
    // The 2-cycle of the logistic map solves μ²x² − μ(μ+1)x + (μ+1) = 0.
    let mu = p2.param;
    for x in [a, b] {
        assert!((mu * mu * x * x - mu * (mu + 1.0) * x + mu + 1.0).abs() < 1e-10);
    }
    assert!((a - b).abs() > 1e-3);
    let pd2 = two
        .bifurcations
        .iter()
        .find(|b| b.kind == BifurcationKind::PeriodDoubling)
        .expect("period-2 branch doubles");
    let exact = 1.0 + 6f64.sqrt();
    assert!((pd2.param - exact).abs() < 1e-9, "{} vs {exact}", pd2.param);
}

#[test]
fn logistic_cascade_matches_the_feigenbaum_parameters() {
    // Published onsets of period 2^n: 3, 1 + √6, 3.5440903596, 3.5644072661 (e.g. Feigenbaum
    // 1978; values to 10 digits in many texts).
    let mut opts = ContinuationOptions::new(2.0, 3.569);
    opts.ds_max = 5e-3;
    let (pds, _) = period_doubling_cascade(&logistic, &[0.55], 2.5, 4, &opts).unwrap();
    let expect = [3.0, 1.0 + 6f64.sqrt(), 3.544_090_359_6, 3.564_407_266_1];
    assert_eq!(pds.len(), 4);
    for (b, e) in pds.iter().zip(expect) {
        assert!((b.param - e).abs() < 2e-9, "{} vs {e}", b.param);
    }
}

#[test]
fn pseudo_arclength_passes_the_saddle_node_fold_and_natural_continuation_reports_it() {
    let mut opts = ContinuationOptions::new(-0.1, 0.26);
    opts.direction = -1.0;
    let branch = continue_branch(&saddle_node, &[0.5], 0.25, 1, &opts).unwrap();
    let folds: Vec<_> = branch
        .bifurcations
        .iter()
        .filter(|b| b.kind == BifurcationKind::Fold)
        .collect();
    assert_eq!(folds.len(), 1, "{:?}", branch.bifurcations);
    assert!(
        folds[0].param.abs() < 1e-7,
        "fold at μ = {}",
        folds[0].param
    );
    // The fold from the branch's own points, independently of the test function that located
    // it. The fixed points of x ↦ x + μ − x² satisfy x + μ − x² = x, i.e. μ = x²: along the
    // branch (x decreasing from 0.5) μ falls to its minimum 0 at x = 0 and rises again, and the
    // multiplier d/dx (x + μ − x²) = 1 − 2x is below +1 before the turn (x > 0) and above it
    // after (x < 0).
    let pts = &branch.points;
    for p in pts {
        let x = p.section[0];
        assert!((p.param - x * x).abs() <= 1e-9, "μ − x² at {p:?}");
    }
    let turn = (0..pts.len())
        .min_by(|&a, &b| pts[a].param.total_cmp(&pts[b].param))
        .unwrap();
    assert!(
        turn > 0 && turn + 1 < pts.len(),
        "turn at {turn} of {}",
        pts.len()
    );
    assert!(pts[..=turn].windows(2).all(|w| w[1].param < w[0].param));
    assert!(pts[turn..].windows(2).all(|w| w[1].param > w[0].param));
    assert!(
        pts[turn].param.abs() < 1e-3,
        "turning point μ = {}",
        pts[turn].param
    );
    for p in &pts[..turn] {
        assert!(p.section[0] > 0.0 && p.multipliers[0].re < 1.0, "{p:?}");
    }
    for p in &pts[turn + 1..] {
        assert!(p.section[0] < 0.0 && p.multipliers[0].re > 1.0, "{p:?}");
    }
    // the located fold lies on the step across the turn, at a parameter no larger than either
    // neighbour's
    assert!(
        folds[0].index == turn || folds[0].index == turn + 1,
        "{:?}",
        folds[0]
    );
    assert!(folds[0].param <= pts[turn - 1].param.min(pts[turn + 1].param));
    // Past the fold: the other branch x = −√μ, unstable with multiplier 1 + 2√μ.
    let last = branch.points.last().unwrap();
    assert!(
        matches!(branch.end, BranchEnd::ParamBound { .. }),
        "{:?}",
        branch.end
    );
    assert!(last.section[0] < 0.0 && last.param > 0.25);
    assert!((last.section[0] + last.param.sqrt()).abs() < 1e-10);
    assert!(!last.stable);

    opts.method = ContinuationMethod::Natural;
    opts.ds_init = 1e-2;
    let nat = continue_branch(&saddle_node, &[0.5], 0.25, 1, &opts).unwrap();
    match nat.end {
        BranchEnd::FoldSuspected {
            param, multiplier, ..
        } => {
            assert!(param > 0.0 && param < 1e-3, "{param}");
            // The closed form, not the rule that named the end: the last point is a fixed point
            // of x ↦ x + μ − x² (x² = μ, to the corrector's residual) and its multiplier is that
            // map's derivative 1 − 2x there.
            let last = nat.points.last().unwrap();
            let x = last.section[0];
            assert_eq!(last.param, param);
            assert!(
                (x * x - param).abs() <= opts.newton_tol,
                "x² − μ = {}",
                x * x - param
            );
            assert!(
                (multiplier - (1.0 - 2.0 * x)).abs() < 1e-12,
                "multiplier {multiplier} against 1 − 2x = {}",
                1.0 - 2.0 * x
            );
        }
        ref e => panic!("expected FoldSuspected, got {e:?}"),
    }
    assert!(nat.points.iter().all(|p| p.section[0] > 0.0));
}

#[test]
fn neimark_sacker_of_the_normal_form_map_located_at_mu_0() {
    let opts = ContinuationOptions::new(-0.2, 0.2);
    let branch = continue_branch(&neimark_sacker, &[0.0, 0.0], -0.15, 1, &opts).unwrap();
    let ns: Vec<_> = branch
        .bifurcations
        .iter()
        .filter(|b| b.kind == BifurcationKind::NeimarkSacker)
        .collect();
    assert_eq!(ns.len(), 1, "{:?}", branch.bifurcations);
    assert!(ns[0].param.abs() < 1e-7, "NS at {}", ns[0].param);
    let m = ns[0].multipliers[0];
    assert!((m.modulus() - 1.0).abs() < 1e-7);
    assert!((m.im.atan2(m.re).abs() - NS_OMEGA).abs() < 1e-9);
    assert!(branch
        .bifurcations
        .iter()
        .all(|b| b.kind == BifurcationKind::NeimarkSacker));
}
