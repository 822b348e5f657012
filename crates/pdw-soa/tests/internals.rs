//! pdw-soa's internals, run here rather than as unit tests so that the library is not compiled
//! a second time with `cfg(test)`: the dual numbers' rules (`dual`) and the stack buffer of the
//! dual-number impacts' faer scratch (`impact`).

mod dual {
    use pdw_soa::dual::*;
    use pdw_soa::spatial;

    #[test]
    fn product_quotient_and_trig_rules() {
        let x = Dual::<2>::variable(0.7, 0);
        let y = Dual::<2>::variable(-1.3, 1);
        let f = x * y / (x + Dual::cst(2.0)) - (-y);
        // f = x y / (x + 2) + y
        let (xv, yv) = (0.7, -1.3);
        assert!((f.v - (xv * yv / (xv + 2.0) + yv)).abs() < 1e-15);
        let dfdx = yv * 2.0 / ((xv + 2.0) * (xv + 2.0));
        let dfdy = xv / (xv + 2.0) + 1.0;
        assert!((f.d[0] - dfdx).abs() < 1e-15);
        assert!((f.d[1] - dfdy).abs() < 1e-15);
        let (s, c) = x.sin_cos();
        assert_eq!(s.v.to_bits(), spatial::sincos(0.7).0.to_bits());
        assert!((s.d[0] - 0.7f64.cos()).abs() < 1e-15 && s.d[1] == 0.0);
        assert!((c.d[0] + 0.7f64.sin()).abs() < 1e-15);
    }
}

mod impact {
    use faer::linalg::cholesky::llt;
    use faer::Par;
    use pdw_soa::derivatives::{FAER_SCRATCH, MAX_DOF};

    #[test]
    fn faer_scratch_fits_on_the_stack_buffer() {
        for n in 1..=MAX_DOF {
            let req =
                llt::factor::cholesky_in_place_scratch::<f64>(n, Par::Seq, Default::default())
                    .or(llt::solve::solve_in_place_scratch::<f64>(n, n, Par::Seq));
            assert!(
                req.size_bytes() + req.align_bytes() <= FAER_SCRATCH,
                "n = {n}"
            );
        }
    }
}
