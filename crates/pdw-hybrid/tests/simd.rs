//! pdw-simd's tests (pdw-simd has no test binary of its own; pdw-hybrid depends on it): the
//! path names and the same bits on every instruction-set path (`paths`), `powr` against libm
//! and its tables' bounds (`powr`), `sincos` and its column kernels against libm and each
//! other bit for bit (`trig`). The paths are process-wide: forcing one here changes nothing
//! in the other tests' results, every path giving the same bits.

mod paths {
    use pdw_simd::*;

    #[test]
    fn names_round_trip_and_baseline_is_always_available() {
        for p in SimdPath::ALL {
            assert_eq!(SimdPath::parse(p.name()), Some(p));
        }
        assert_eq!(SimdPath::parse("neon"), None);
        assert!(SimdPath::Baseline.available());
        assert_eq!(*available_paths().last().unwrap(), SimdPath::Baseline);
    }

    #[test]
    fn every_path_gives_the_same_bits_for_a_dot_product_and_sqrt() {
        // A reduction the compiler may vectorise differently per path; the order of the
        // additions is fixed by the source, so every path must round identically.
        let v: Vec<f64> = (0..1000).map(|i| (i as f64 * 0.37).sin() * 1e3).collect();
        let kernel = |v: &[f64]| {
            let mut acc = 0.0;
            for w in v.windows(3) {
                acc += w[0] * w[1] + w[2].abs().sqrt();
            }
            acc
        };
        let reference = kernel(&v);
        for p in available_paths() {
            set_path(p).unwrap();
            let got = dispatch(
                #[inline(always)]
                || kernel(&v),
            );
            assert_eq!(got.to_bits(), reference.to_bits(), "path {p}");
        }
    }

    #[test]
    fn unavailable_and_unknown_paths_are_refused_with_the_allowed_ones() {
        let e = SimdError::Unknown("sse9".into()).to_string();
        assert!(e.contains("baseline, avx2, avx512"), "{e}");
        for p in SimdPath::ALL {
            if !p.available() {
                let e = set_path(p).unwrap_err().to_string();
                assert!(e.contains("not supported"), "{e}");
            }
        }
    }
}

mod powr {
    use pdw_simd::powr::*;

    #[test]
    fn ln2_split_is_exact_in_its_high_part() {
        assert_eq!(LN2_HI.to_bits() & 0x1f_ffff, 0);
        assert!((LN2_HI + LN2_LO - LN2).abs() <= f64::EPSILON * LN2);
        assert!((LN2_LO - 1.908_214_929_270_587_7e-10).abs() < 1e-25);
    }

    #[test]
    fn agrees_with_libm_pow_over_the_range() {
        let mut worst: f64 = 0.0;
        for a in [0.2, 0.17, 0.04, 0.125, 1.0 / 3.0, 0.25, -0.2, 1.5] {
            let mut x = 1e-300_f64;
            while x < 1e300 {
                for f in [1.0, 1.234_567_89, 3.3, 7.77] {
                    let xv = x * f;
                    let (p, q) = (powr(xv, a), xv.powf(a));
                    if q.is_finite() && q > 1e-300 {
                        let scale = 4.0 * f64::EPSILON * (a * xv.ln()).abs().max(1.0);
                        worst = worst.max(((p - q) / q).abs() / scale);
                    }
                }
                x *= 10.0;
            }
        }
        assert!(
            worst <= 1.0,
            "worst relative error {worst} × 4ε·max(1, |a ln x|)"
        );
        // Near 1, where ln x is small: relative accuracy of the result holds too.
        for i in 1..2000 {
            let x = 1.0 + (i as f64 - 1000.0) * 1e-6;
            let (p, q) = (powr(x, 0.2), x.powf(0.2));
            assert!(((p - q) / q).abs() < 1e-15, "x = {x}: {p} vs {q}");
        }
    }

    /// The tables against libm (an independent evaluation): each entry within an ulp, every
    /// reduced argument `r = m·ĉᵢ − 1` inside the bound the log1p polynomial is built for, and
    /// the split of ln 2/64 exact in its high part.
    #[test]
    fn tables_and_reductions_hold_their_bounds() {
        let ulp = |v: f64| f64::EPSILON * v.abs();
        for i in 0..128 {
            let ic = f64::from_bits(INV_C[i]);
            let c = 1.0 + (i as f64 + 0.5) / 128.0;
            assert!((ic - 1.0 / c).abs() <= ulp(ic), "INV_C[{i}]");
            let lc = f64::from_bits(LN_C[i]);
            assert!((lc + ic.ln()).abs() <= ulp(lc) + 1e-300, "LN_C[{i}]");
            for m in [
                1.0 + i as f64 / 128.0,
                1.0 + (i as f64 + 1.0) / 128.0 - 1e-16,
            ] {
                assert!((m * ic - 1.0).abs() < 0.0039, "r at m = {m}");
            }
        }
        for (j, &b) in EXP2_J.iter().enumerate() {
            let v = f64::from_bits(b);
            assert!(
                (v - (j as f64 / 64.0).exp2()).abs() <= ulp(v),
                "EXP2_J[{j}]"
            );
        }
        assert_eq!(STEP_HI.to_bits() & 0x1f_ffff, 0);
        assert!((STEP_HI + STEP_LO - LN2 / 64.0).abs() <= f64::EPSILON * LN2 / 64.0);
        assert!((INV_STEP - 64.0 / LN2).abs() <= f64::EPSILON * INV_STEP);
    }

    /// The controller's range, densely: error norms 1e−12 … 1e12 at the exponents DOPRI5 and
    /// DOP853 use (±α, ±α/2, β), within 4ε·max(1, |a ln x|) of libm.
    #[test]
    fn controller_arguments_densely() {
        let mut worst: f64 = 0.0;
        let mut x = 1e-12_f64;
        while x < 1e12 {
            for a in [-0.085, -0.1, 0.17, 0.2, 0.04, -0.0625, 0.125, 1.0 / 5.0] {
                let (p, q) = (powr(x, a), x.powf(a));
                let scale = 4.0 * f64::EPSILON * (a * x.ln()).abs().max(1.0);
                worst = worst.max(((p - q) / q).abs() / scale);
            }
            x *= 1.000_37;
        }
        eprintln!("worst relative error {worst:.3} × 4ε·max(1, |a ln x|)");
        assert!(worst <= 1.0, "worst {worst}");
    }

    #[test]
    fn subnormals_edges_and_invalid_inputs() {
        let x = 5e-320_f64;
        let scale = 4.0 * f64::EPSILON * (0.2 * x.ln()).abs();
        assert!(((powr(x, 0.2) - x.powf(0.2)) / x.powf(0.2)).abs() < scale);
        assert_eq!(powr(0.0, 0.2), 0.0);
        assert_eq!(powr(0.0, 0.0), 1.0);
        assert_eq!(powr(0.0, -0.2), f64::INFINITY);
        assert_eq!(powr(f64::INFINITY, 0.2), f64::INFINITY);
        assert_eq!(powr(f64::INFINITY, -0.2), 0.0);
        assert!(powr(f64::NAN, 0.2).is_nan());
        assert!(powr(-1.0, 0.2).is_nan());
        assert_eq!(powr(1.0, 0.2), 1.0);
        assert_eq!(powr(2.0, 1.0), 2.0);
        assert_eq!(powr(1e300, 2.0), f64::INFINITY);
        assert_eq!(powr(1e-300, 2.0), 0.0);
    }
}

mod trig {
    use pdw_simd::trig::*;

    /// Distance in units in the last place between two finite doubles of the same sign region.
    fn ulps(a: f64, b: f64) -> u64 {
        let key = |v: f64| {
            let b = v.to_bits() as i64;
            if b < 0 {
                i64::MIN - b
            } else {
                b
            }
        };
        key(a).abs_diff(key(b))
    }

    #[test]
    fn within_two_ulp_of_libm_and_mostly_equal_over_the_reduced_range() {
        // glibc's sin/cos are within 1 ulp of the exact value; we measure our distance to them.
        let mut hist = [0u64; 4];
        let n = 2_000_000;
        for k in 0..=n {
            let x = -REDUCED_RANGE + 2.0 * REDUCED_RANGE * (k as f64 / n as f64);
            let (s, c) = sincos(x);
            let (sl, cl) = x.sin_cos();
            // Near a zero of sin/cos an ulp is relative to a tiny value: compare absolutely
            // there (the bound is the reduction's error, ~ε·ulp(x)).
            for (a, b) in [(s, sl), (c, cl)] {
                if b.abs() > 1e-6 {
                    hist[(ulps(a, b) as usize).min(3)] += 1;
                } else {
                    assert!(
                        (a - b).abs() < 1e-22 + 1e-22 * x.abs(),
                        "x = {x}: {a} vs {b}"
                    );
                }
            }
        }
        let total: u64 = hist.iter().sum();
        eprintln!(
            "ulp distance to libm: 0: {}, 1: {}, 2: {}, >2: {}",
            hist[0], hist[1], hist[2], hist[3]
        );
        assert_eq!(hist[3], 0, "{hist:?}");
        assert!(
            hist[2] * 10_000 < total,
            "more than 1e-4 of values 2 ulp away: {hist:?}"
        );
        assert!(
            hist[0] * 10 > 8 * total,
            "fewer than 80 % equal to libm: {hist:?}"
        );
        // Small and moderate arguments densely.
        for k in 0..200_000 {
            let x = (k as f64 - 100_000.0) * 1e-4;
            let (s, c) = sincos(x);
            let (sl, cl) = x.sin_cos();
            assert!(ulps(s, sl) <= 2 || (s - sl).abs() < 1e-300, "sin {x}");
            assert!(ulps(c, cl) <= 2, "cos {x}");
        }
    }

    #[test]
    fn the_small_argument_path_equals_the_full_reduction_bit_for_bit() {
        let mut xs: Vec<f64> = (0..=400_000)
            .map(|k| (k as f64 - 200_000.0) / 200_000.0 * SMALL)
            .collect();
        xs.extend([
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            -1e-300,
            SMALL.next_down(),
            -SMALL.next_down(),
        ]);
        for &x in &xs {
            let (s, c) = sincos(x);
            let (sf, cf) = kernel(x);
            assert_eq!(
                (s.to_bits(), c.to_bits()),
                (sf.to_bits(), cf.to_bits()),
                "x = {x}"
            );
        }
        // A lane above SMALL sends all lanes through the reduction: still the same bits.
        let (s2, c2) = sincos_lanes([0.3, 2.5]);
        assert_eq!(
            (s2[0].to_bits(), c2[0].to_bits()),
            (sincos(0.3).0.to_bits(), sincos(0.3).1.to_bits())
        );
        assert_eq!(
            (s2[1].to_bits(), c2[1].to_bits()),
            (kernel(2.5).0.to_bits(), kernel(2.5).1.to_bits())
        );
    }

    #[test]
    fn the_column_kernels_equal_the_one_value_routine_bit_for_bit() {
        let bits = |v: (f64, f64)| (v.0.to_bits(), v.1.to_bits());
        for k in 0..=200_000 {
            let x = (k as f64 - 100_000.0) / 100_000.0 * SMALL.next_down();
            assert_eq!(bits(sincos_small(x)), bits(sincos(x)), "{x}");
            assert_eq!(sin_small(x).to_bits(), sincos(x).0.to_bits(), "{x}");
            let y = (k as f64 - 100_000.0) / 100_000.0 * REDUCED_RANGE;
            assert_eq!(bits(sincos_reduced_range(y)), bits(sincos(y)), "{y}");
        }
        for x in [0.0, -0.0, f64::MIN_POSITIVE, -1e-300, 5e-324] {
            assert_eq!(bits(sincos_small(x)), bits(sincos(x)), "{x}");
            assert_eq!(sin_small(x).to_bits(), sincos(x).0.to_bits(), "{x}");
            assert_eq!(bits(sincos_reduced_range(x)), bits(sincos(x)), "{x}");
        }
        for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let (s, c) = sincos_reduced_range(v);
            assert!(s.is_nan() && c.is_nan(), "{v}");
        }
    }

    #[test]
    fn quadrants_signs_and_special_values() {
        for k in -8..=8 {
            let x = k as f64 * std::f64::consts::FRAC_PI_2;
            let (s, c) = sincos(x);
            let (sl, cl) = x.sin_cos();
            assert!((s - sl).abs() < 1e-15 && (c - cl).abs() < 1e-15, "k = {k}");
        }
        let (s, c) = sincos(-0.0);
        assert!(s == 0.0 && s.is_sign_negative() && c == 1.0);
        for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let (s, c) = sincos(v);
            assert!(s.is_nan() && c.is_nan(), "{v}");
        }
        // Beyond the reduced range: libm's values.
        for x in [1.0e4, 1.0e6, -3.3e9, 1.0e300] {
            assert_eq!(sincos(x), x.sin_cos());
        }
    }

    #[test]
    fn lanes_and_slices_equal_the_one_value_routine_bit_for_bit() {
        let xs: Vec<f64> = (0..37).map(|i| (i as f64 - 18.0) * 0.731 + 1e-3).collect();
        let mut s = vec![0.0; xs.len()];
        let mut c = vec![0.0; xs.len()];
        sincos_slice(&xs, &mut s, &mut c);
        for (i, &x) in xs.iter().enumerate() {
            let (a, b) = sincos(x);
            assert_eq!((a.to_bits(), b.to_bits()), (s[i].to_bits(), c[i].to_bits()));
        }
        let four = [xs[0], xs[5], 2.0e3, xs[9]];
        let (s4, c4) = sincos_lanes(four);
        for i in 0..4 {
            assert_eq!(sincos(four[i]).0.to_bits(), s4[i].to_bits());
            assert_eq!(sincos(four[i]).1.to_bits(), c4[i].to_bits());
        }
        // And on every instruction-set path.
        for p in pdw_simd::available_paths() {
            pdw_simd::set_path(p).unwrap();
            let mut s2 = vec![0.0; xs.len()];
            let mut c2 = vec![0.0; xs.len()];
            pdw_simd::dispatch(
                #[inline(always)]
                || sincos_slice(&xs, &mut s2, &mut c2),
            );
            assert_eq!(s2, s, "path {p}");
            assert_eq!(c2, c, "path {p}");
        }
    }
}
