//! Walkers that come to a stand: the basin labels a walk that dies out towards standing still
//! a fall (`Outcome::Fall`), never an attractor (`other`) or a `timeout` that discovery could
//! take for a chaotic attractor; recurrences are judged relative to the state's scale.
//! Synthetic stride maps (`continuation_maps::MapSystem`: the stride map is a given map exactly)
//! make every decay known in closed form.

use crate::continuation_maps::MapSystem;
use pdw_limit::{
    classify_cells, classify_cells_scalar, decay_exponent, stands_still, walk_dies_out,
    BasinOptions, BasinProblem, CellResult, Outcome, STANDSTILL_WINDOW,
};

/// `STANDSTILL_WINDOW + 1` values of `f(k)`, k = 0, 1, ….
fn window(f: impl Fn(f64) -> f64) -> Vec<f64> {
    (0..=STANDSTILL_WINDOW).map(|k| f(k as f64)).collect()
}

/// The decay exponent against closed-form decays: the geometric decay (m = 1), the exact
/// solutions `a(k) = (a₀^{1−m} + (m−1) c k)^{1/(1−m)}` of `da/dk = −c a^m` for m = 2, 3, the
/// level-floor walker's discrete law `a ↦ a − 24 a³` (m = 3, the constant fitted to the simplest
/// walker on a level floor), and approaches to an orbit of scale `L`, `a_k = L(1 + u λ^{k−16})`
/// (u the newest excess), whose exponent grows without bound as the walker settles.
#[test]
fn decay_exponent_of_closed_form_decays() {
    let m = |a: &[f64]| decay_exponent(a).unwrap();
    assert!((m(&window(|k| 0.3 * 0.97f64.powf(k))) - 1.0).abs() < 1e-12);
    assert!((m(&window(|k| 2e-6 * 0.9999f64.powf(k))) - 1.0).abs() < 1e-6);
    let power = |a0: f64, c: f64, p: f64| {
        window(move |k| (a0.powf(1.0 - p) + (p - 1.0) * c * k).powf(1.0 / (1.0 - p)))
    };
    assert!((m(&power(0.01, 1.0, 2.0)) - 2.0).abs() < 1e-3);
    assert!((m(&power(0.0046, 24.0, 3.0)) - 3.0).abs() < 1e-4);
    assert!((m(&power(0.05, 24.0, 3.0)) - 3.0).abs() < 0.05);
    let mut level = vec![0.0046];
    for _ in 0..STANDSTILL_WINDOW {
        let a: f64 = *level.last().unwrap();
        level.push(a - 24.0 * a.powi(3));
    }
    assert!((m(&level) - 3.0).abs() < 0.01);
    // a constant decrement (the scale would reach zero in finite time): below 1
    assert!(m(&window(|k| 1e-6 - 1e-10 * k)).abs() < 1e-6);
    // approaches to an orbit: at least 5, and 20 for a slow approach already close
    let settle = |lam: f64, u: f64| window(move |k| 0.2 * (1.0 + u * lam.powf(k - 16.0)));
    assert!(m(&settle(0.999, 0.05)) > 20.0);
    assert!(m(&settle(0.9, 0.1)) > 5.0);
    assert!(m(&settle(0.999, 0.2)) > 5.0);
    // not a decay at every stride: no exponent
    assert_eq!(decay_exponent(&window(|_| 0.2)), None);
    assert_eq!(decay_exponent(&window(|k| 0.2 + 1e-6 * k)), None);
    assert_eq!(
        decay_exponent(&window(|k| 0.2 + 0.01 * (-0.9f64).powf(k))),
        None
    );
    assert_eq!(decay_exponent(&[0.3, 0.2, 0.1, 0.05]), None);
    assert_eq!(decay_exponent(&[0.3, 0.2]), None);
    assert_eq!(decay_exponent(&[0.3, f64::NAN, 0.1]), None);
    assert_eq!(decay_exponent(&[0.3, 0.1, 0.0]), Some(f64::NEG_INFINITY));
}

/// Which synthetic orbits die out: every decay towards zero above, not the approaches to an
/// orbit (unless still far above it, the documented limit: u = 0.5 at λ = 0.999).
#[test]
fn a_synthetic_decaying_orbit_dies_out_and_an_approach_to_a_gait_does_not() {
    assert!(walk_dies_out(&window(|k| 0.3 * 0.97f64.powf(k))));
    assert!(walk_dies_out(&window(
        |k| (0.0046f64.powi(-2) + 48.0 * k).powf(-0.5)
    )));
    assert!(walk_dies_out(&window(|k| 1e-6 - 1e-10 * k)));
    assert!(walk_dies_out(&[0.3, 0.1, 0.0]));
    let settle = |lam: f64, u: f64| window(move |k| 0.2 * (1.0 + u * lam.powf(k - 16.0)));
    assert!(!walk_dies_out(&settle(0.999, 0.05)));
    assert!(!walk_dies_out(&settle(0.99, 0.2)));
    assert!(!walk_dies_out(&settle(0.9, 0.1)));
    assert!(walk_dies_out(&settle(0.999, 0.5)));
    assert!(!walk_dies_out(&window(|_| 0.2)));
    // stands_still reads the newest states: at standing (within tol_gait of s = 0) at once,
    // else the decay of the scales ‖s‖∞ over the window
    let hist = |a: Vec<f64>| -> Vec<Vec<f64>> { a.iter().map(|v| vec![*v, -1.05 * v]).collect() };
    assert!(stands_still(&[vec![4e-7, -9e-7]], 1e-6));
    assert!(!stands_still(&[vec![4e-7, -2e-6]], 1e-6));
    assert!(!stands_still(&[], 1e-6));
    let dying = hist(window(|k| 0.3 * 0.97f64.powf(k)));
    assert!(stands_still(&dying, 1e-6));
    assert!(!stands_still(&dying[1..], 1e-6), "shorter than the window");
    let mut longer = hist(vec![5.0, 4.0]);
    longer.extend(dying.iter().cloned());
    assert!(stands_still(&longer, 1e-6), "only the newest window counts");
    assert!(!stands_still(&hist(settle(0.999, 0.05)), 1e-6));
}

/// `s ↦ s (1 − μ ‖s‖²₂)`: the level-floor walker's cubic decay towards standing still.
fn cubic(s: &[f64], mu: f64, o: &mut [f64]) {
    let r2 = s[0] * s[0] + s[1] * s[1];
    o[0] = s[0] * (1.0 - mu * r2);
    o[1] = s[1] * (1.0 - mu * r2);
}

/// `s ↦ (1 − μ) s`: a geometric decay.
fn geometric(s: &[f64], mu: f64, o: &mut [f64]) {
    o[0] = (1.0 - mu) * s[0];
    o[1] = (1.0 - mu) * s[1];
}

/// `s ↦ L + μ (s − L)`, `L = (0.2, −0.2)`: a gait of scale 0.2 with the double multiplier μ.
fn settle(s: &[f64], mu: f64, o: &mut [f64]) {
    o[0] = 0.2 + mu * (s[0] - 0.2);
    o[1] = -0.2 + mu * (s[1] + 0.2);
}

/// `s ↦ s`: every state a fixed point.
fn identity(s: &[f64], _mu: f64, o: &mut [f64]) {
    o.copy_from_slice(&s[..2]);
}

fn no_jac(_s: &[f64], _mu: f64, o: &mut [f64]) {
    o.fill(f64::NAN);
}

fn system(f: fn(&[f64], f64, &mut [f64]), mu: f64) -> MapSystem {
    MapSystem {
        n: 2,
        mu,
        f,
        jac: no_jac,
    }
}

/// The cells through the batched engine and the scalar reference (identical), default basin
/// options with `max_strides`.
fn classify(sys: &MapSystem, gait: Vec<f64>, cells: &[Vec<f64>], max: u16) -> Vec<CellResult> {
    let fall = Outcome::of_fall;
    let prob = BasinProblem::new(sys, gait, &fall);
    let opts = BasinOptions {
        max_strides: max,
        lanes: 4,
        chunk: 4,
        ..Default::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let a = classify_cells(&prob, cells, &opts, &pool, &|_| {}).unwrap();
    let b = classify_cells_scalar(&prob, cells, &opts).unwrap();
    assert_eq!(a, b);
    a
}

/// A walk that dies out is a fall at the end of its budget — the level floor's cubic law
/// (from the scales the simplest walker has after 100 and 1000 strides on a level floor, and
/// from 0.05), a geometric decay — and so is a recurrence at a state within the gait
/// tolerance of standing (every state of `s ↦ s` is a fixed point). Before, these were
/// `timeout` (then `chaotic` when discovery sampled one) or, where a stride moved the state by
/// less than an absolute 10⁻¹⁰, `other`.
#[test]
fn a_synthetic_walk_that_dies_out_is_a_fall_not_an_attractor() {
    let sys = system(cubic, 12.0);
    let cells = vec![
        vec![0.0139, -0.0145],
        vec![0.0046, -0.0048],
        vec![0.05, -0.052],
    ];
    for max in [100, 1000] {
        for (c, s) in classify(&sys, Vec::new(), &cells, max).iter().zip(&cells) {
            assert_eq!(c.outcome(), Outcome::Fall, "{c:?}");
            assert_eq!(c.strides, max);
            assert!(c.final_state[0] > 0.0 && c.final_state[0] < s[0], "{c:?}");
        }
    }
    // a geometric decay of 10⁻⁷ per stride from the scale 10⁻⁴: each stride moves the state
    // by 10⁻¹¹ (a recurrence for an absolute 10⁻¹⁰), 10⁻⁷ of its scale
    let sys = system(geometric, 1e-7);
    for c in classify(&sys, Vec::new(), &[vec![1e-4, -1e-4]], 100) {
        assert_eq!(c.outcome(), Outcome::Fall, "{c:?}");
        assert_eq!(c.strides, 100);
    }
    // exact recurrence near standing, and away from it
    let sys = system(identity, 0.0);
    let r = classify(
        &sys,
        Vec::new(),
        &[vec![5e-7, -9e-7], vec![0.3, -0.3], vec![3e-6, -3e-6]],
        100,
    );
    assert_eq!(r[0].outcome(), Outcome::Fall, "{:?}", r[0]);
    assert_eq!(r[1].outcome(), Outcome::Other, "{:?}", r[1]);
    assert_eq!(r[1].period, 1);
    assert_eq!(r[2].outcome(), Outcome::Other, "{:?}", r[2]);
    assert!(r[0].strides <= 2 && r[1].strides <= 2);
}

/// Gaits are labelled as before: a contracting gait is `gait` when given and `other` (period 1)
/// by recurrence when not; a slow approach (double multiplier 0.999, 5 % above the gait) that
/// runs out of strides stays `timeout`, not a fall.
#[test]
fn converging_walks_keep_their_labels() {
    let fast = system(settle, 0.5);
    let cells = vec![vec![0.25, -0.25], vec![0.15, -0.19]];
    for c in classify(&fast, vec![0.2, -0.2], &cells, 100) {
        assert_eq!(c.outcome(), Outcome::Gait, "{c:?}");
    }
    for c in classify(&fast, Vec::new(), &cells, 100) {
        assert_eq!(c.outcome(), Outcome::Other, "{c:?}");
        assert_eq!(c.period, 1);
    }
    let slow = system(settle, 0.999);
    for c in classify(&slow, Vec::new(), &[vec![0.21, -0.21]], 100) {
        assert_eq!(c.outcome(), Outcome::Timeout, "{c:?}");
    }
}
