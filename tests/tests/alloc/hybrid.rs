//! The integration loops allocate nothing: the scalar integrator allocates only when it is built
//! (and when a system with more guards first shows up), a batch only when it starts — not per
//! step. Checked with a counting global allocator (the binary's counter, per thread).

use crate::allocs;
use crate::common::*;
use pdw_hybrid::{
    run_batch, BatchOptions, Control, Crossing, HybridSystem, Integrator, LaneDriver, Options,
    Scratch, StopReason,
};

#[test]
fn scalar_integration_does_not_allocate() {
    let osc = Oscillator::new(&[
        (0.0, Crossing::Falling, None),
        (0.5, Crossing::Rising, None),
    ]);
    for opts in [
        Options::dopri5(1e-10),
        Options::dop853(1e-12),
        Options::rk4(1e-3),
    ] {
        let mut integ = Integrator::new(2, opts).unwrap();
        let (mut t, mut x) = (0.0, [1.0, 0.0]);
        integ.integrate(&osc, 0, &mut t, &mut x, 100.0); // first call sizes the guard scratch
        let before = allocs();
        let mut events = 0;
        for _ in 0..20 {
            if let StopReason::Guard { .. } = integ.integrate(&osc, 0, &mut t, &mut x, 100.0) {
                events += 1;
            }
        }
        assert!(events == 20);
        assert_eq!(allocs() - before, 0, "{:?}", opts.method);
    }
}

/// A driver that allocates nothing itself.
struct Quiet;

impl<S: HybridSystem + ?Sized> LaneDriver<S> for Quiet {
    type Item = (f64, f64);
    type Output = f64;
    type Lane = u32;
    fn start(&self, _s: &S, it: &(f64, f64), _l: &mut u32, x: &mut [f64]) -> (usize, f64) {
        x[0] = it.0;
        x[1] = 0.0;
        (0, it.1)
    }
    #[allow(clippy::too_many_arguments)]
    fn on_stop(
        &self,
        s: &S,
        ws: &mut Scratch,
        _it: &(f64, f64),
        l: &mut u32,
        r: StopReason,
        m: usize,
        _t: f64,
        x: &mut [f64],
    ) -> Control {
        match r {
            StopReason::Guard { guard } => {
                *l += 1;
                let mut buf = [0.0; 2];
                let m2 = s.reset(ws, m, guard, x, &mut buf);
                x.copy_from_slice(&buf);
                Control::Continue {
                    mode: m2,
                    t_end: _it.1,
                }
            }
            _ => Control::Finish,
        }
    }
    fn finish(&self, _s: &S, _it: &(f64, f64), l: u32, t: f64, x: &[f64]) -> f64 {
        t + x[0] + l as f64
    }
}

#[test]
fn batch_allocations_do_not_grow_with_the_number_of_steps() {
    let sys = SoftBall {
        g: 9.81,
        k: 1000.0,
        c: 1e4,
    };
    let count = |t_end: f64| {
        let items: Vec<(f64, f64)> = (0..200).map(|i| (0.5 + 0.005 * i as f64, t_end)).collect();
        let bo = BatchOptions {
            lanes: 64,
            integrator: Options::dop853(1e-10),
        };
        let before = allocs();
        let out = run_batch(&sys, &Quiet, &items, &bo).unwrap();
        let n = allocs() - before;
        (n, out.len())
    };
    // Warm-up: the process-wide one-time initialisations (the SIMD path choice reads
    // `PDW_SIMD` once) are not per-run allocations.
    count(0.5);
    let (short, _) = count(0.5);
    let (long, _) = count(20.0);
    eprintln!("allocations per run_batch: short run {short}, 40× longer run {long}");
    assert_eq!(short, long);
}
