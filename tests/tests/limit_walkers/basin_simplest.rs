//! Basins of attraction of the simplest walker (Garcia et al. 1998) and of the compass gait:
//! physics claims and the engine's invariances (thread count, lanes, chunks, shards, scalar path).

use pdw_hybrid::{Options, Section};
use pdw_limit::{
    basin_metrics, classify_cells, classify_cells_scalar, continue_branch, find_fixed_point,
    grid_cells, legend, linspace, switch_period_doubling, BasinOptions, BasinProblem,
    BifurcationKind, CellResult, ContinuationOptions, NewtonOptions, Outcome, StrideMap,
};
use pdw_walkers::simplest::{Simplest, SimplestParams};
use pdw_walkers::Walker;

fn simplest(gamma: f64) -> Simplest {
    Simplest::new(SimplestParams {
        slope: gamma,
        ..Default::default()
    })
    .unwrap()
}

fn family(g: f64) -> Result<Box<Simplest>, pdw_walkers::WalkerError> {
    Simplest::new(SimplestParams {
        slope: g,
        ..Default::default()
    })
    .map(Box::new)
}

/// Period-one fixed point of the simplest walker at γ from a guess (tight tolerance).
fn fixed_point(m: &Simplest, guess: &[f64]) -> (Vec<f64>, bool) {
    let map = StrideMap::new(m, Options::dop853(1e-13)).unwrap();
    let fp = find_fixed_point(&map, guess, &NewtonOptions::default()).unwrap();
    (fp.section, fp.stable)
}

fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
}

/// The window around the stable gait at γ = 0.009, `n × n` cells.
fn window(n: usize) -> Vec<Vec<f64>> {
    grid_cells(
        &[0.0, 0.0],
        0,
        &linspace(0.15, 0.25, n),
        1,
        &linspace(-0.25, -0.15, n),
    )
}

#[test]
fn legend_codes_are_stable_and_name_gait_and_falls() {
    let l = legend();
    assert_eq!(l[0], (0, "gait"));
    assert_eq!(l[1], (1, "other"));
    assert_eq!(l[2], (2, "fall_forward"));
    assert_eq!(l[3], (3, "fall_backward"));
    assert_eq!(l[6], (6, "fall"));
    assert_eq!(l[7], (7, "timeout"));
    assert_eq!(l[8], (8, "nonfinite"));
    for (c, name) in l {
        assert_eq!(Outcome::from_code(c).unwrap().name(), name);
    }
    assert_eq!(Outcome::from_code(200), None);
}

#[test]
fn basin_at_0009_is_a_thin_band_containing_the_fixed_point() {
    let m = simplest(0.009);
    let (s, stable) = fixed_point(&m, &[0.2003, -0.1998]);
    assert!(stable);
    let fall = Outcome::of_fall;
    let prob = BasinProblem::new(&m, s.clone(), &fall);
    let opts = BasinOptions::default();
    let n = 61;
    let mut cells = window(n);
    cells.push(s.clone());
    let res = classify_cells(&prob, &cells, &opts, &pool(2), &|_| {}).unwrap();
    // The fixed point's own cell is `gait`, decided after `confirm` section states.
    let own = res.last().unwrap();
    assert_eq!(own.outcome(), Outcome::Gait);
    assert!(own.strides <= 2);
    let grid = &res[..n * n];
    let codes: Vec<u8> = grid.iter().map(|r| r.outcome).collect();
    let frac =
        |o: Outcome| codes.iter().filter(|&&c| c == o.code()).count() as f64 / (n * n) as f64;
    let g = frac(Outcome::Gait);
    // Thin band (Schwab & Wisse 2001): a small but positive part of the window; the rest falls.
    assert!(g > 0.01 && g < 0.2, "gait fraction {g}");
    assert!(frac(Outcome::FallForward) > 0.2 && frac(Outcome::FallBackward) > 0.2);
    assert_eq!(
        frac(Outcome::Timeout) + frac(Outcome::NonFinite) + frac(Outcome::Other),
        0.0
    );
    // Every gait cell ends within tol_gait of s*; every cell's strides are within the budget.
    for r in grid {
        assert!(r.strides <= opts.max_strides);
        if r.outcome() == Outcome::Gait {
            assert!(r
                .final_state
                .iter()
                .zip(&s)
                .all(|(a, b)| (a - b).abs() < opts.tol_gait));
        }
    }
    // The band is thin: in each column of fixed θ the gait cells span a narrow range of θ̇.
    let ys = linspace(-0.25, -0.15, n);
    let mut widest = 0.0f64;
    for j in 0..n {
        let rows: Vec<usize> = (0..n).filter(|&i| codes[i * n + j] == 0).collect();
        if let (Some(a), Some(b)) = (rows.first(), rows.last()) {
            widest = widest.max(ys[*b] - ys[*a]);
        }
    }
    assert!(widest < 0.05, "widest gait span in θ̇: {widest}");
    let metrics = basin_metrics(&codes, n, n, 5).unwrap();
    assert!(metrics.boundary_boxes > 0 && metrics.basin_entropy > 0.0);
    assert!(metrics.boundary_entropy >= metrics.basin_entropy);
}

#[test]
fn labels_are_identical_for_any_thread_count_lane_count_chunk_and_shard_split() {
    let m = simplest(0.009);
    let (s, _) = fixed_point(&m, &[0.2003, -0.1998]);
    let fall = Outcome::of_fall;
    let prob = BasinProblem::new(&m, s, &fall);
    let cells = window(41);
    let base = BasinOptions::default();
    let reference = classify_cells(&prob, &cells, &base, &pool(1), &|_| {}).unwrap();
    for (threads, lanes, chunk) in [(2, 64, 1024), (2, 1, 7), (1, 7, 100), (2, 13, 1)] {
        let opts = BasinOptions {
            lanes,
            chunk,
            ..base
        };
        let r = classify_cells(&prob, &cells, &opts, &pool(threads), &|_| {}).unwrap();
        assert_eq!(
            r, reference,
            "threads {threads} lanes {lanes} chunk {chunk}"
        );
    }
    // Shards: rows computed separately (interleaved blocks) and reassembled.
    let nx = 41;
    let mut merged: Vec<Option<CellResult>> = vec![None; cells.len()];
    for shard in 0..3 {
        let rows: Vec<usize> = (0..41).filter(|i| (i / 4) % 3 == shard).collect();
        let part: Vec<Vec<f64>> = rows
            .iter()
            .flat_map(|&i| cells[i * nx..(i + 1) * nx].to_vec())
            .collect();
        let r = classify_cells(&prob, &part, &base, &pool(2), &|_| {}).unwrap();
        for (k, &i) in rows.iter().enumerate() {
            for j in 0..nx {
                merged[i * nx + j] = Some(r[k * nx + j].clone());
            }
        }
    }
    let merged: Vec<CellResult> = merged.into_iter().map(Option::unwrap).collect();
    assert_eq!(merged, reference);
}

#[test]
fn batched_equals_scalar_cell_for_cell_on_101x101_simplest() {
    let m = simplest(0.009);
    let (s, _) = fixed_point(&m, &[0.2003, -0.1998]);
    let fall = Outcome::of_fall;
    let prob = BasinProblem::new(&m, s, &fall);
    let cells = window(101);
    let opts = BasinOptions::default();
    let batched = classify_cells(&prob, &cells, &opts, &pool(2), &|_| {}).unwrap();
    let scalar = classify_cells_scalar(&prob, &cells, &opts).unwrap();
    assert_eq!(batched.len(), 101 * 101);
    for (k, (a, b)) in batched.iter().zip(&scalar).enumerate() {
        assert_eq!(a, b, "cell {k}");
    }
}

/// The default's warm restarts (`Options::warm_restart`: every stride after a cell's first
/// starts with the controller's last proposal) label the 101 × 101 window as cold restarts do —
/// outcome by outcome, all but 1 % of the gait cells' stride counts within one — with at least
/// 10 % fewer step attempts over the whole basin (the gait cells' strides are most of its
/// work). Measured: 679 gait cells, one of them 2 strides apart; 236 387 attempts warm against
/// 282 670 cold (0.84×), 23 538 rejections against 38 723.
#[test]
fn warm_restarts_label_the_basin_as_cold_ones_with_fewer_attempts() {
    let m = simplest(0.009);
    let (s, _) = fixed_point(&m, &[0.2003, -0.1998]);
    let fall = Outcome::of_fall;
    let prob = BasinProblem::new(&m, s, &fall);
    let cells = window(101);
    let run = |warm: bool| {
        let mut opts = BasinOptions::default();
        assert!(opts.integrator.warm_restart, "the basin's default");
        opts.integrator.warm_restart = warm;
        let driver = pdw_limit::BasinDriver::new(&prob, &opts).unwrap();
        let bo = pdw_hybrid::BatchOptions {
            lanes: opts.lanes,
            integrator: opts.integrator,
        };
        pdw_hybrid::run_batch_counted(prob.sys, &driver, &cells, &bo).unwrap()
    };
    let ((warm, sw), (cold, sc)) = (run(true), run(false));
    let gait = Outcome::Gait.code();
    let (mut n_gait, mut moved) = (0, 0);
    for (k, (w, c)) in warm.iter().zip(&cold).enumerate() {
        assert_eq!(w.outcome, c.outcome, "cell {k}");
        if w.outcome == gait {
            n_gait += 1;
            moved += usize::from(w.strides.abs_diff(c.strides) > 1);
        }
    }
    // A cell's stride count is the first stride within `tol_gait` of the gait: a cell on a long
    // transient may cross that line a stride or two apart.
    assert!(
        n_gait > 300 && moved * 100 <= n_gait,
        "{n_gait} gait cells, {moved} moved by > 1 stride"
    );
    let (aw, ac) = (sw.accepted + sw.rejected, sc.accepted + sc.rejected);
    assert!(
        (aw as f64) < 0.9 * ac as f64 && sw.rejected < sc.rejected,
        "attempts {aw} warm, {ac} cold; rejected {} warm, {} cold",
        sw.rejected,
        sc.rejected
    );
}

#[test]
fn batched_equals_scalar_cell_for_cell_on_101x101_compass() {
    let m = pdw_walkers::presets::compass(&[]).unwrap();
    let guess = m.gait_guesses()[0].section.clone();
    let map = StrideMap::new(&m, Options::dop853(1e-12)).unwrap();
    let fp = find_fixed_point(&map, &guess, &NewtonOptions::default()).unwrap();
    let s = fp.section.clone();
    let fall = Outcome::of_fall;
    let prob = BasinProblem::new(&m, s.clone(), &fall);
    let cells = grid_cells(
        &s,
        0,
        &linspace(s[0] - 0.1, s[0] + 0.1, 101),
        1,
        &linspace(s[1] - 0.5, s[1] + 0.5, 101),
    );
    let opts = BasinOptions {
        max_strides: 40,
        ..Default::default()
    };
    let batched = classify_cells(&prob, &cells, &opts, &pool(2), &|_| {}).unwrap();
    let scalar = classify_cells_scalar(&prob, &cells, &opts).unwrap();
    for (k, (a, b)) in batched.iter().zip(&scalar).enumerate() {
        assert_eq!(a, b, "cell {k}");
    }
    // The grid contains the gait's own neighbourhood and some falls.
    let center = &batched[50 * 101 + 50];
    assert_eq!(center.outcome(), Outcome::Gait);
    assert!(batched.iter().any(|r| r.outcome().is_fall()));
    assert_eq!(m.section_dim(), 3);
}

#[test]
fn nonfinite_cells_are_an_outcome_not_a_panic() {
    let m = simplest(0.009);
    let (s, _) = fixed_point(&m, &[0.2003, -0.1998]);
    let fall = Outcome::of_fall;
    let prob = BasinProblem::new(&m, s.clone(), &fall);
    let cells = vec![
        vec![f64::NAN, -0.2],
        vec![0.2, f64::INFINITY],
        s.clone(),
        vec![1e300, -1e300],
    ];
    let opts = BasinOptions::default();
    let r = classify_cells(&prob, &cells, &opts, &pool(2), &|_| {}).unwrap();
    assert_eq!(r[0].outcome(), Outcome::NonFinite);
    assert_eq!(r[1].outcome(), Outcome::NonFinite);
    assert_eq!(r[0].strides, 0);
    assert_eq!(r[2].outcome(), Outcome::Gait);
    assert_ne!(r[3].outcome(), Outcome::Gait);
    // Same through the scalar path (compared bit for bit: NaN != NaN under `==`).
    let key = |c: &CellResult| {
        (
            c.outcome,
            c.strides,
            c.final_state
                .iter()
                .map(|v| v.to_bits())
                .collect::<Vec<_>>(),
        )
    };
    let scalar = classify_cells_scalar(&prob, &cells, &opts).unwrap();
    assert_eq!(
        r.iter().map(key).collect::<Vec<_>>(),
        scalar.iter().map(key).collect::<Vec<_>>()
    );
}

#[test]
fn past_the_first_period_doubling_cells_reach_the_period_two_gait_not_the_unstable_one() {
    // At γ = 0.016 the period-one gait is unstable (a multiplier below −1) and a stable
    // period-two gait exists (Garcia 1998). Cells near the period-one gait must be labelled
    // `other` with period 2 — by recurrence, and as the known attractor when it is given.
    let gamma = 0.016;
    let m = simplest(gamma);
    let (s1, stable) = fixed_point(&m, &[0.245, -0.238]);
    assert!(!stable);
    let fall = Outcome::of_fall;
    let mut prob = BasinProblem::new(&m, s1.clone(), &fall);
    // An even grid, so that s* itself is not a cell (see the chaotic-regime test).
    let d = 2e-3;
    let cells = grid_cells(
        &s1,
        0,
        &linspace(s1[0] - d, s1[0] + d, 8),
        1,
        &linspace(s1[1] - d, s1[1] + d, 8),
    );
    let opts = BasinOptions {
        max_strides: 400,
        ..Default::default()
    };
    let r = classify_cells(&prob, &cells, &opts, &pool(2), &|_| {}).unwrap();
    let others: Vec<&CellResult> = r.iter().filter(|c| c.outcome() == Outcome::Other).collect();
    assert!(others.len() > cells.len() / 2, "{r:?}");
    let odd: Vec<_> = others
        .iter()
        .filter(|c| !(c.period == 2 && c.attractor == u8::MAX))
        .collect();
    assert!(odd.is_empty(), "{odd:?}");
    assert!(r.iter().all(|c| c.outcome() != Outcome::Gait));
    // The period-2 orbit from branch switching at the located period doubling.
    let mut co = ContinuationOptions::new(0.009, gamma);
    co.stop_at = Some(BifurcationKind::PeriodDoubling);
    let b1 = continue_branch(&family, &[0.2003, -0.1998], 0.009, 1, &co).unwrap();
    let pd = b1
        .bifurcations
        .iter()
        .find(|b| b.kind == BifurcationKind::PeriodDoubling)
        .unwrap();
    let mut co2 = ContinuationOptions::new(0.009, gamma + 1e-4);
    co2.ds_max = 2e-3;
    let b2 = switch_period_doubling(&family, pd, &co2).unwrap();
    // The point of the period-2 branch closest to γ, corrected there by a fixed-point solve of P².
    let near = b2
        .points
        .iter()
        .min_by(|a, b| (a.param - gamma).abs().total_cmp(&(b.param - gamma).abs()))
        .unwrap();
    let pb = continue_branch(&family, &near.section, near.param, 2, &{
        let mut o =
            ContinuationOptions::new(near.param.min(gamma) - 1e-9, near.param.max(gamma) + 1e-9);
        o.method = pdw_limit::ContinuationMethod::Natural;
        o.direction = if gamma > near.param { 1.0 } else { -1.0 };
        o.ds_init = (gamma - near.param).abs().max(1e-9);
        o.ds_max = o.ds_init;
        o.ds_min = o.ds_init.min(1e-9);
        o.max_points = 2;
        o.detect = false;
        o
    })
    .unwrap();
    let p2 = pb.points.last().unwrap();
    assert!((p2.param - gamma).abs() < 1e-12, "{}", p2.param);
    assert!(p2.stable);
    prob.others.push(p2.orbit.clone());
    let r2 = classify_cells(&prob, &cells, &opts, &pool(2), &|_| {}).unwrap();
    for (a, b) in r.iter().zip(&r2) {
        if a.outcome() == Outcome::Other {
            assert_eq!(b.outcome(), Outcome::Other);
            assert_eq!((b.period, b.attractor), (2, 0));
            assert!(b.strides <= a.strides + 1);
        }
    }
}

#[test]
fn in_the_chaotic_regime_no_cell_is_labelled_gait() {
    // γ = 0.0189 lies past the accumulation of the cascade (γ∞ ≈ 0.01829): the period-one
    // gait is unstable and walking trajectories wander on a chaotic attractor (Garcia 1998).
    let gamma = 0.0189;
    let m = simplest(gamma);
    let (s1, stable) = fixed_point(&m, &[0.26, -0.25]);
    assert!(!stable);
    let fall = Outcome::of_fall;
    let prob = BasinProblem::new(&m, s1.clone(), &fall);
    // An even grid: s* itself is not a cell (a trajectory started exactly on the unstable gait
    // stays within tol_gait of it for many strides — that cell *is* the gait).
    let d = 5e-3;
    let cells = grid_cells(
        &s1,
        0,
        &linspace(s1[0] - d, s1[0] + d, 10),
        1,
        &linspace(s1[1] - d, s1[1] + d, 10),
    );
    let r = classify_cells(&prob, &cells, &BasinOptions::default(), &pool(2), &|_| {}).unwrap();
    assert!(r.iter().all(|c| c.outcome() != Outcome::Gait), "{r:?}");
    // Some cells keep walking for the whole budget without settling on any orbit of period ≤ 8.
    assert!(r.iter().any(|c| c.outcome() == Outcome::Timeout));
}

#[test]
fn basin_entropy_of_a_straight_two_basin_boundary_is_ln2_over_the_boundary_boxes() {
    // 10 × 10 grid, columns 0–4 code 0, 5–9 code 3: the boundary runs between the boxes
    // (columns 0–4 and 5–9), so no box is mixed.
    let nx = 10;
    let mut codes = vec![0u8; 100];
    for i in 0..10 {
        for j in 5..10 {
            codes[i * nx + j] = 3;
        }
    }
    let m = basin_metrics(&codes, 10, 10, 5).unwrap();
    assert_eq!((m.boxes, m.boundary_boxes), (4, 0));
    assert_eq!(m.basin_entropy, 0.0);
    // Columns 0–2 code 0, 3–9 code 3: the two left boxes hold p = (3/5, 2/5), the right ones
    // are pure; S_bb = −(0.6 ln 0.6 + 0.4 ln 0.4), S_b = S_bb · 2/4.
    for i in 0..10 {
        for j in 0..10 {
            codes[i * nx + j] = if j < 3 { 0 } else { 3 };
        }
    }
    let m = basin_metrics(&codes, 10, 10, 5).unwrap();
    let s = -(0.6f64 * 0.6f64.ln() + 0.4 * 0.4f64.ln());
    assert_eq!(m.boundary_boxes, 2);
    assert!((m.boundary_entropy - s).abs() < 1e-15);
    assert!((m.basin_entropy - s / 2.0).abs() < 1e-15);
    let f: Vec<f64> = m
        .fractions
        .iter()
        .filter(|f| f.2 > 0.0)
        .map(|f| f.2)
        .collect();
    assert_eq!(f, vec![0.3, 0.7]);
}

/// The basin and the stride map read a stride's end alike (one vocabulary, [`pdw_limit::End`]):
/// a cell whose first stride does not reach the heel strike ends with the code of that
/// stride's end, and a stride time budget too short for any stride makes every stride
/// `fall_no_heel_strike` (5) in both — never the basin's `timeout` (7, a cell not classified
/// within its stride budget).
#[test]
fn basin_and_stride_map_give_one_end_for_one_state() {
    let m = simplest(0.009);
    let (s, _) = fixed_point(&m, &[0.2003, -0.1998]);
    let fall = Outcome::of_fall;
    let opts = BasinOptions::default();
    let map = StrideMap::new(&m, opts.integrator).unwrap();
    // a wide window: falls in the first stride (both ways) beside strides that land
    let cells = grid_cells(
        &[0.0, 0.0],
        0,
        &linspace(0.02, 0.6, 15),
        1,
        &linspace(-0.9, 0.3, 15),
    );
    let res = classify_cells(
        &BasinProblem::new(&m, s.clone(), &fall),
        &cells,
        &opts,
        &pool(2),
        &|_| {},
    )
    .unwrap();
    let strides = map.strides(&cells, 16).unwrap();
    let mut first_stride_ends = Vec::new();
    for ((c, r), st) in cells.iter().zip(&res).zip(&strides) {
        if st.outcome.is_ok() {
            assert!(
                r.strides >= 1,
                "{c:?}: the stride landed, the cell says {r:?}"
            );
            continue;
        }
        assert_eq!(r.strides, 0, "{c:?}");
        assert_eq!(
            r.outcome,
            st.outcome.end().code(),
            "{c:?}: the basin says {}, the stride map {} ({})",
            r.outcome().name(),
            st.outcome.end().name(),
            st.outcome
        );
        first_stride_ends.push(st.outcome.end());
    }
    assert!(
        first_stride_ends
            .iter()
            .any(|e| e.is_fall() && *e != Outcome::FallNoHeelStrike),
        "no cell fell in its first stride: {first_stride_ends:?}"
    );
    // A stride time budget of 0.3, far below the gait's period (3.8): no stride reaches its
    // heel strike.
    let short = Simplest::new(SimplestParams {
        slope: 0.009,
        max_stride_time: 0.3,
        ..Default::default()
    })
    .unwrap();
    let cells = window(5);
    let res = classify_cells_scalar(&BasinProblem::new(&short, s, &fall), &cells, &opts).unwrap();
    let map = StrideMap::new(&short, opts.integrator).unwrap();
    for (c, r) in cells.iter().zip(&res) {
        let st = map.stride(c).unwrap();
        assert_eq!(st.outcome, pdw_limit::StrideOutcome::NoHeelStrike, "{c:?}");
        assert_eq!(st.outcome.end(), Outcome::FallNoHeelStrike);
        assert_eq!(r.outcome, 5, "{c:?}: {}", r.outcome().name());
        assert_eq!(r.outcome().name(), "fall_no_heel_strike");
    }
}
