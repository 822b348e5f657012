//! pdw-hybrid's internals, run here rather than as unit tests so that the library is not
//! compiled a second time with `cfg(test)`: the end-point test of event detection and its
//! directional refinement, the dense outputs and the affine guards' polynomials against the
//! general loops and the Illinois iteration (`event`), the Butcher tableaux against their
//! published nodes and order conditions (`tableau`), and a watched stop flag (`interrupt`).

mod event {
    use pdw_hybrid::engine::{tableau_of, Store};
    use pdw_hybrid::event::{
        bracket_tol, build_dense, clears_direction, crosses, dop853_dense_dyn, dop853_dense_fixed,
        gather_ends, guard_poly, hermite_basis, hermite_point, hull_and_margin, may_cross,
        nested_rows, nested_values, nested_with_derivative, refine, refine_linear, Dense,
        EventScratch, Interp, N_COLS as M, N_SAMPLES, POLY_ROWS,
    };
    use pdw_hybrid::{Crossing, GuardSpec, HybridSystem, Method, Scratch, Stats};

    /// The claim the event detection rests on: when `may_cross` clears a step, the cubic
    /// Hermite of the guard — which the interior samples evaluate for an affine guard — shows no
    /// crossing in either direction at the sample points, nor anywhere on a fine grid. Checked
    /// on 200 000 seeded random cubics (a plain LCG, no dependency), many of them near zero.
    #[test]
    fn a_cleared_step_has_no_crossing_on_the_guards_cubic() {
        let mut seed: u64 = 0x2545_f491_4f6c_dd1d;
        let mut uniform = move || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut cleared, mut flagged) = (0, 0);
        for _ in 0..200_000 {
            let scale = 10f64.powf(-6.0 * uniform());
            let g0 = scale * (2.0 * uniform() - 1.0);
            let g1 = scale * (2.0 * uniform() - 1.0);
            let r0 = 3.0 * (2.0 * uniform() - 1.0);
            let r1 = 3.0 * (2.0 * uniform() - 1.0);
            let h = 10f64.powf(-4.0 * uniform());
            if may_cross(g0, g1, r0, r1, h) {
                flagged += 1;
                continue;
            }
            cleared += 1;
            let p = |t: f64| hermite_point(hermite_basis(t), g0, g1, r0, r1, h);
            let values: Vec<f64> = (0..=1000).map(|i| p(i as f64 / 1000.0)).collect();
            assert!(
                values.iter().all(|&v| v < 0.0) || values.iter().all(|&v| v > 0.0),
                "cleared but the cubic reaches zero: g0 {g0}, g1 {g1}, r0 {r0}, r1 {r1}, h {h}"
            );
            let mut samples = [g0, 0.0, 0.0, 0.0, 0.0, g1];
            for (i, v) in samples.iter_mut().enumerate().take(M - 1).skip(1) {
                *v = p(i as f64 / (N_SAMPLES + 1) as f64);
            }
            for w in samples.windows(2) {
                assert!(!crosses(Crossing::Either, w[0], w[1]));
            }
        }
        // Both branches are exercised, and most far-from-zero steps are cleared.
        assert!(
            cleared > 20_000 && flagged > 20_000,
            "{cleared} cleared, {flagged} flagged"
        );
    }

    /// The claim of the directional test: when `clears_direction` clears a step that
    /// `may_cross` flags, its samples — the guard's cubic at θ = i/5, each moved by up to the
    /// margin m (rounding and a nonlinear guard's deviation), and the exact end values — show
    /// no crossing in that direction. Checked on 300 000 seeded random cubics, a third of them
    /// starting on the guard (g₀ = 0), for both directions; each of the three ways to clear
    /// must occur.
    #[test]
    fn a_step_cleared_by_direction_shows_no_crossing_in_that_direction() {
        let mut uniform = xorshift(0x9e37_79b9_7f4a_7c15);
        let (mut cleared, mut flagged) = (0, 0);
        let mut ways = [0usize; 3];
        for n in 0..300_000 {
            let scale = 10f64.powf(-6.0 * uniform());
            let g0 = if n % 3 == 0 {
                0.0
            } else {
                scale * (2.0 * uniform() - 1.0)
            };
            let g1 = scale * (2.0 * uniform() - 1.0);
            let r0 = 3.0 * (2.0 * uniform() - 1.0);
            let r1 = 3.0 * (2.0 * uniform() - 1.0);
            let h = 10f64.powf(-4.0 * uniform());
            if !may_cross(g0, g1, r0, r1, h) {
                continue;
            }
            for dir in [Crossing::Rising, Crossing::Falling] {
                if !clears_direction(dir, g0, g1, r0, r1, h) {
                    flagged += 1;
                    continue;
                }
                cleared += 1;
                let (_, _, m) = hull_and_margin(g0, g1, r0, r1, h);
                let p = |t: f64| hermite_point(hermite_basis(t), g0, g1, r0, r1, h);
                let mut samples = [g0, 0.0, 0.0, 0.0, 0.0, g1];
                for (i, v) in samples.iter_mut().enumerate().take(M - 1).skip(1) {
                    *v = p(i as f64 / (N_SAMPLES + 1) as f64) + 0.99 * m * (2.0 * uniform() - 1.0);
                }
                for w in samples.windows(2) {
                    assert!(
                        !crosses(dir, w[0], w[1]),
                        "{dir:?} cleared but the samples cross: g0 {g0}, g1 {g1}, r0 {r0}, \
                         r1 {r1}, h {h}: {samples:?}"
                    );
                }
                // Which way cleared it (for the coverage check below), in the sign of `dir`.
                let s = if let Crossing::Rising = dir {
                    1.0
                } else {
                    -1.0
                };
                let v: Vec<f64> = samples.iter().map(|v| s * v).collect();
                if v[1..].iter().all(|&x| x < 0.0) {
                    ways[0] += 1;
                } else if v.iter().all(|&x| x >= 0.0) {
                    ways[1] += 1;
                } else {
                    ways[2] += 1;
                }
            }
        }
        assert!(
            cleared > 20_000 && flagged > 20_000 && ways.iter().all(|&w| w > 1000),
            "{cleared} cleared, {flagged} flagged, ways {ways:?}"
        );
    }

    /// The steps the directional test is for: starting on the guard and moving away from its
    /// crossing side, crossing the other way; and the ones it must keep: a crossing in the
    /// guard's direction, a start on the guard moving into the crossing, non-finite values,
    /// `Either`.
    #[test]
    fn directional_clearing_cases() {
        use Crossing::{Either, Falling, Rising};
        // (g₀, g₁, ġ₀, ġ₁, h)
        let clears = |dir, [g0, g1, r0, r1, h]: [f64; 5]| clears_direction(dir, g0, g1, r0, r1, h);
        let up_from_zero = [0.0, 0.3, 1.0, 1.0, 0.3];
        let falling = [0.1, -0.1, -0.7, -0.7, 0.3];
        // A rising guard at 0 after a reset, moving up (away from a rising crossing), which the
        // hull test cannot clear; and moving down: no sample is ≥ 0 after the start.
        assert!(may_cross(0.0, 0.3, 1.0, 1.0, 0.3));
        assert!(clears(Rising, up_from_zero));
        assert!(clears(Rising, [0.0, -0.3, -1.0, -1.0, 0.3]));
        // A falling crossing clears a rising guard, not a falling one.
        assert!(clears(Rising, falling));
        assert!(!clears(Falling, falling));
        // Kept: a rising crossing; a dip below zero and back for a falling guard; `Either`;
        // a NaN or unknown rate.
        assert!(!clears(Rising, [-0.1, 0.1, 0.7, 0.7, 0.3]));
        assert!(!clears(Falling, [0.01, 0.01, -1.0, 1.0, 0.1]));
        assert!(!clears(Either, up_from_zero));
        assert!(!clears(Rising, [0.0, 0.3, f64::NAN, 1.0, 0.3]));
        assert!(!clears(Rising, [0.0, 0.3, f64::INFINITY, 1.0, 0.3]));
    }

    /// Steps the test cannot clear: an end on zero (a reset placed the state on the guard),
    /// a sign change between the ends, an unknown rate, NaN anywhere; and a guard far from zero
    /// is cleared.
    #[test]
    fn steps_that_must_be_sampled_are() {
        assert!(may_cross(0.0, -0.5, 1.0, 1.0, 0.1));
        assert!(may_cross(-0.1, 0.2, 1.0, 1.0, 0.1));
        assert!(may_cross(-0.5, -0.5, f64::INFINITY, 0.0, 0.1));
        assert!(may_cross(f64::NAN, -0.5, 0.0, 0.0, 0.1));
        assert!(may_cross(-0.5, -0.5, f64::NAN, 0.0, 0.1));
        assert!(may_cross(-0.5, -0.5, 0.0, 0.0, f64::NAN));
        // a dip between two negative ends: g0 = g1 = −0.01 with slopes that lift the middle
        // above zero (p(½) = −0.01 + h(r0 − r1)/8 = +0.015)
        assert!(may_cross(-0.01, -0.01, 1.0, -1.0, 0.1));
        assert!(!may_cross(-0.5, -0.4, 1.0, 1.0, 0.1));
        assert!(!may_cross(0.5, 0.4, -1.0, -1.0, 0.1));
    }

    /// A seeded xorshift generator of uniform values in [0, 1) (no dependency).
    fn xorshift(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// A nonlinear flow of any dimension for the dense-output build (no guards).
    struct Coupled(usize);

    pdw_hybrid::integrate_through_dyn!(Coupled);
    impl HybridSystem for Coupled {
        fn dim(&self) -> usize {
            self.0
        }
        fn guards(&self, _mode: usize) -> &[GuardSpec] {
            &[]
        }
        fn flow(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], dx: &mut [f64]) {
            let d = x.len();
            for j in 0..d {
                dx[j] = x[(j + 1) % d].sin() - 0.3 * x[j] * x[j];
            }
        }
        fn guard(&self, _ws: &mut Scratch, _mode: usize, _k: usize, _x: &[f64]) -> f64 {
            0.0
        }
        fn reset(
            &self,
            _: &mut Scratch,
            mode: usize,
            _: usize,
            x: &[f64],
            out: &mut [f64],
        ) -> usize {
            out.copy_from_slice(x);
            mode
        }
    }

    /// The DOP853 dense output of the shipped dimensions (compile-time rows) is the general
    /// loop's, bit for bit, on a strided lane of a batch store: coefficients, the three extra
    /// evaluations, and the interpolated states.
    #[test]
    fn dop853_dense_output_of_fixed_dimensions_is_the_general_loops() {
        let mut uniform = xorshift(0x2545_f491_4f6c_dd1du64);
        let tab = tableau_of(Method::Dop853);
        for d in [2, 4, 6, 8, 10, 12] {
            let sys = Coupled(d);
            let (lanes, l) = (5, 3);
            let mut st = Store::new(d, lanes, 0, tab);
            for v in
                st.k.iter_mut()
                    .chain(st.x.iter_mut())
                    .chain(st.xn.iter_mut())
            {
                *v = 2.0 * uniform() - 1.0;
            }
            let h = 0.01 + 0.1 * uniform();
            let run = |fixed: bool| {
                let mut sc = EventScratch::new(d, 0);
                gather_ends(&st, l, Method::Dop853, &mut sc);
                let mut stats = Stats::default();
                let interp = if fixed {
                    // the shipped dimensions, each with its compile-time rows
                    let (sc, stats) = (&mut sc, &mut stats);
                    match d {
                        2 => dop853_dense_fixed::<Coupled, 2>(&sys, 0, &st, l, h, sc, stats),
                        4 => dop853_dense_fixed::<Coupled, 4>(&sys, 0, &st, l, h, sc, stats),
                        6 => dop853_dense_fixed::<Coupled, 6>(&sys, 0, &st, l, h, sc, stats),
                        8 => dop853_dense_fixed::<Coupled, 8>(&sys, 0, &st, l, h, sc, stats),
                        10 => dop853_dense_fixed::<Coupled, 10>(&sys, 0, &st, l, h, sc, stats),
                        12 => dop853_dense_fixed::<Coupled, 12>(&sys, 0, &st, l, h, sc, stats),
                        _ => unreachable!("{d} is a shipped dimension"),
                    }
                } else {
                    dop853_dense_dyn(&sys, 0, &st, l, h, &mut sc, &mut stats)
                };
                let dense = Dense {
                    interp,
                    h,
                    x0: &sc.x0,
                    x1: &sc.x1,
                    f0: &sc.f0,
                    f1: &sc.f1,
                    cont: &sc.cont,
                };
                let mut states = vec![0.0; 3 * d];
                for (i, out) in states.chunks_exact_mut(d).enumerate() {
                    dense.eval(0.2 + 0.3 * i as f64, out);
                }
                (sc.cont[..8 * d].to_vec(), states, stats.rhs_evals)
            };
            let (fixed, dynamic) = (run(true), run(false));
            assert_eq!(fixed.2, 3);
            assert_eq!(fixed.2, dynamic.2);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fixed.0), bits(&dynamic.0), "coefficients, d = {d}");
            assert_eq!(bits(&fixed.1), bits(&dynamic.1), "states, d = {d}");
            assert!(
                fixed.0.iter().all(|v| v.is_finite()) && fixed.0[4 * d..].iter().any(|&v| v != 0.0)
            );
        }
    }

    /// The flow of [`Coupled`] with one affine guard `x₀ − c` (Either direction).
    struct Plane {
        d: usize,
        c: f64,
    }

    pdw_hybrid::integrate_through_dyn!(Plane);
    impl HybridSystem for Plane {
        fn dim(&self) -> usize {
            self.d
        }
        fn guards(&self, _mode: usize) -> &[GuardSpec] {
            &[]
        }
        fn flow(&self, ws: &mut Scratch, mode: usize, x: &[f64], dx: &mut [f64]) {
            Coupled(self.d).flow(ws, mode, x, dx)
        }
        fn guard(&self, _ws: &mut Scratch, _mode: usize, _k: usize, x: &[f64]) -> f64 {
            x[0] - self.c
        }
        fn guard_is_linear(&self, _mode: usize, _k: usize) -> bool {
            true
        }
        fn reset(
            &self,
            ws: &mut Scratch,
            mode: usize,
            k: usize,
            x: &[f64],
            o: &mut [f64],
        ) -> usize {
            Coupled(self.d).reset(ws, mode, k, x, o)
        }
    }

    /// The nested polynomial's value has the bits of [`Dense::eval`] on a one-component state
    /// (the same operations in the same order), and its derivative is the derivative: checked
    /// against a central difference of the value on random coefficients, for DOPRI5's five rows
    /// and DOP853's eight.
    #[test]
    fn nested_polynomial_is_the_dense_output_and_its_derivative() {
        let mut uniform = xorshift(0x9e37_79b9_7f4a_7c15u64);
        for (interp, rows) in [(Interp::Dopri5, 5), (Interp::Dop853, 8)] {
            for _ in 0..200 {
                let c: Vec<f64> = (0..8).map(|_| 2.0 * uniform() - 1.0).collect();
                let z = [0.0];
                let dense = Dense {
                    interp,
                    h: 0.1,
                    x0: &z,
                    x1: &z,
                    f0: &z,
                    f1: &z,
                    cont: &c,
                };
                let theta = uniform();
                let mut out = [0.0];
                dense.eval(theta, &mut out);
                let (v, dv) = nested_with_derivative(&c, rows, theta);
                assert_eq!(v.to_bits(), out[0].to_bits(), "{rows} rows at θ = {theta}");
                let four = nested_values(&c, rows, [theta, 0.2, 0.4, 0.8]);
                assert_eq!(four[0].to_bits(), v.to_bits());
                for (i, t) in [0.2, 0.4, 0.8].into_iter().enumerate() {
                    let one = nested_with_derivative(&c, rows, t).0;
                    assert_eq!(four[i + 1].to_bits(), one.to_bits());
                }
                let e = 1e-6;
                let fd = (nested_with_derivative(&c, rows, theta + e).0
                    - nested_with_derivative(&c, rows, theta - e).0)
                    / (2.0 * e);
                assert!(
                    (dv - fd).abs() <= 1e-8 * (1.0 + dv.abs()),
                    "{dv} against {fd}"
                );
            }
        }
    }

    /// The Newton iteration on an affine guard's polynomial finds the root the Illinois
    /// iteration finds on the states, to within the width of their brackets (a few 1e-15 of
    /// the step), and its state lies on the post-crossing side, for DOPRI5 and DOP853 dense
    /// outputs of a nonlinear flow, in dimensions 2 and 4, on random steps and random roots
    /// in both directions.
    #[test]
    fn newton_on_the_guard_polynomial_finds_the_illinois_root() {
        let mut uniform = xorshift(0x2545_f491_4f6c_dd1du64);
        let mut roots = 0;
        for method in [Method::Dopri5, Method::Dop853] {
            let tab = tableau_of(method);
            for d in [2, 4] {
                for _ in 0..300 {
                    let mut st = Store::new(d, 1, 1, tab);
                    for v in st.k.iter_mut().chain(st.x.iter_mut()) {
                        *v = 2.0 * uniform() - 1.0;
                    }
                    // A consistent step: x₁ from the stages with the method's weights b.
                    let h = 0.05 + 0.5 * uniform();
                    let last = tab.n_stages - 1;
                    for j in 0..d {
                        let mut s = 0.0;
                        for (q, &w) in tab.a[last].iter().enumerate() {
                            s += w * st.k[q * d + j];
                        }
                        st.xn[j] = st.x[j] + h * s;
                    }
                    let mut sc = EventScratch::new(d, 1);
                    gather_ends(&st, 0, method, &mut sc);
                    let mut stats = Stats::default();
                    let sys0 = Plane { d, c: 0.0 };
                    let interp = build_dense(&sys0, method, 0, &st, 0, h, &mut sc, &mut stats);
                    let dense = Dense {
                        interp,
                        h,
                        x0: &sc.x0,
                        x1: &sc.x1,
                        f0: &sc.f0,
                        f1: &sc.f1,
                        cont: &sc.cont,
                    };
                    // The guard's level: the first component at a random interior point.
                    let mut xs = vec![0.0; d];
                    dense.eval(0.05 + 0.9 * uniform(), &mut xs);
                    let sys = Plane { d, c: xs[0] };
                    let mut ws = Scratch::new();
                    let rows = nested_rows(interp);
                    let mut poly = [0.0; POLY_ROWS];
                    let zero = vec![0.0; d];
                    guard_poly(&sys, &mut ws, 0, 0, dense.cont, &zero, rows, &mut poly);
                    let g_at = |theta: f64, xr: &mut [f64], ws: &mut Scratch| {
                        if theta == 1.0 {
                            xr.copy_from_slice(dense.x1);
                        } else {
                            dense.eval(theta, xr);
                        }
                        sys.guard(ws, 0, 0, xr)
                    };
                    let mut xr = vec![0.0; d];
                    let gs: Vec<f64> = (0..M)
                        .map(|i| g_at(i as f64 / (M - 1) as f64, &mut xr, &mut ws))
                        .collect();
                    let Some(i) = (0..M - 1).find(|&i| crosses(Crossing::Either, gs[i], gs[i + 1]))
                    else {
                        continue;
                    };
                    let (ta, tb) = (i as f64 / (M - 1) as f64, (i + 1) as f64 / (M - 1) as f64);
                    let t_scale = 1.0 + h;
                    let tol = bracket_tol(t_scale, h);
                    let lo = (ta, gs[i]);
                    let hi = (tb, gs[i + 1]);
                    let mut xl = vec![0.0; d];
                    let newton = refine_linear(
                        &sys, &mut ws, 0, 0, &dense, &poly, rows, tol, lo, hi, &mut xl,
                    )
                    .expect("the polynomial's root");
                    let illinois = refine(&sys, &mut ws, 0, 0, &dense, t_scale, lo, hi, &mut xr);
                    assert!(
                        (newton - illinois).abs() <= 6.0 * tol,
                        "{method:?} d = {d}: Newton {newton}, Illinois {illinois}, tol {tol:e}"
                    );
                    assert!(newton > ta && newton <= tb);
                    let sig = if gs[i] < 0.0 { 1.0 } else { -1.0 };
                    assert!(sig * sys.guard(&mut ws, 0, 0, &xl) >= 0.0);
                    roots += 1;
                }
            }
        }
        assert!(roots > 600, "{roots} roots tested");
    }
}

// The published nodes carry their 30 digits; the compiler rounds them to the nearest f64.
#[allow(clippy::excessive_precision)]
mod tableau {
    use pdw_hybrid::tableau::*;

    /// Published nodes c of DOP853 (Hairer–Wanner's table), stages 1..12 then 14..16.
    const DOP853_C: [f64; 12] = [
        0.0,
        0.526001519587677318785587544488e-01,
        0.789002279381515978178381316732e-01,
        0.118350341907227396726757197510e+00,
        0.281649658092772603273242802490e+00,
        0.333333333333333333333333333333e+00,
        0.25e+00,
        0.307692307692307692307692307692e+00,
        0.651282051282051282051282051282e+00,
        0.6e+00,
        0.857142857142857142857142857142e+00,
        1.0,
    ];

    fn row_sum(r: &[f64]) -> f64 {
        r.iter().sum()
    }

    #[test]
    fn stage_rows_sum_to_the_published_nodes() {
        let dopri5_c = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
        for (q, &c) in dopri5_c.iter().enumerate().skip(1) {
            assert!((row_sum(DOPRI5.a[q]) - c).abs() < 1e-15, "DOPRI5 row {q}");
        }
        for (q, &c) in DOP853_C.iter().enumerate().skip(1) {
            assert!((row_sum(DOP853.a[q]) - c).abs() < 1e-14, "DOP853 row {q}");
        }
        for (r, c) in [0.1, 0.2, 7.0 / 9.0].iter().enumerate() {
            assert!(
                (row_sum(DOP853_DENSE_A[r]) - c).abs() < 1e-14,
                "DOP853 dense row {r}"
            );
        }
        let rk4_c = [0.0, 0.5, 0.5, 1.0, 1.0];
        for (q, &c) in rk4_c.iter().enumerate().skip(1) {
            assert!((row_sum(RK4.a[q]) - c).abs() < 1e-15, "RK4 row {q}");
        }
    }

    /// Quadrature order conditions Σ b_i c_i^(m−1) = 1/m for m = 1..p (HNW I, §II.2).
    #[test]
    fn weights_satisfy_the_quadrature_order_conditions() {
        let dopri5_c: [f64; 6] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0];
        let b5 = DOPRI5.a[6];
        for m in 1..=5 {
            let s: f64 = b5
                .iter()
                .zip(&dopri5_c)
                .map(|(b, c)| b * c.powi(m - 1))
                .sum();
            assert!((s - 1.0 / m as f64).abs() < 1e-15, "DOPRI5 m = {m}: {s}");
        }
        for m in 1..=8 {
            let s: f64 = DOP853_B
                .iter()
                .zip(&DOP853_C)
                .map(|(b, c)| b * c.powi(m - 1))
                .sum();
            assert!((s - 1.0 / m as f64).abs() < 1e-14, "DOP853 m = {m}: {s}");
        }
        // Error weights are differences of two consistent weight vectors: they sum to 0.
        assert!(DOPRI5_E.iter().sum::<f64>().abs() < 1e-16);
        assert!(DOP853_ER.iter().sum::<f64>().abs() < 1e-14);
        assert!((DOP853_BHH.iter().sum::<f64>() - 1.0).abs() < 1e-15);
    }
}

mod interrupt {
    use pdw_hybrid::interrupt::*;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    /// A watched flag is a request on the watching thread only, and unwatching restores it.
    #[test]
    fn a_watched_flag_stops_only_its_threads() {
        let flag = Arc::new(AtomicBool::new(false));
        assert!(watch(Some(flag.clone())).is_none());
        assert!(!requested());
        flag.store(true, Ordering::SeqCst);
        assert!(requested());
        let other = std::thread::spawn(requested).join().unwrap();
        assert!(!other, "another thread saw this thread's flag");
        assert!(watch(None).is_some());
        assert!(!requested());
    }
}
