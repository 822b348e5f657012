//! The process-wide stop request (`pdw_hybrid::interrupt`): every layer that integrates ends
//! with `Interrupted` instead of a result, a call in progress stops within 1024 step attempts
//! of the request, and after `clear` the same calls give the same bits as before.
//!
//! The flag is global to the process, so this file is its own test binary with one test: no
//! other test can run beside it and see the request. The requests are made from inside the
//! computation (a flow evaluation, a progress callback), so the moment is the same on every
//! run: nothing here depends on timing.

use pdw_hybrid::StopReason;
use pdw_hybrid::{interrupt, GuardSpec, HybridError, HybridSystem, Integrator, Options, Scratch};
use pdw_limit::gaits;
use pdw_limit::StrideMap;
use std::sync::atomic::{AtomicUsize, Ordering};

/// ẋ = −x in three coordinates, no guards; the `trigger`-th flow evaluation requests a stop.
struct Decay {
    evals: AtomicUsize,
    trigger: usize,
}

pdw_hybrid::integrate_through_dyn!(Decay);
impl HybridSystem for Decay {
    fn dim(&self) -> usize {
        3
    }
    fn guards(&self, _mode: usize) -> &[GuardSpec] {
        &[]
    }
    fn flow(&self, _ws: &mut Scratch, _mode: usize, x: &[f64], dx: &mut [f64]) {
        if self.evals.fetch_add(1, Ordering::Relaxed) + 1 == self.trigger {
            interrupt::request();
        }
        for (d, v) in dx.iter_mut().zip(x) {
            *d = -v;
        }
    }
    fn guard(&self, _ws: &mut Scratch, _mode: usize, _k: usize, _x: &[f64]) -> f64 {
        unreachable!("no guards")
    }
    fn reset(&self, _ws: &mut Scratch, _m: usize, _k: usize, _x: &[f64], _o: &mut [f64]) -> usize {
        unreachable!("no guards")
    }
}

#[test]
fn a_stop_request_ends_every_layer_with_interrupted_and_clear_restores_the_same_bits() {
    assert!(!interrupt::requested(), "no request at the start");
    let w = pdw_walkers::build("compass", &[]).expect("compass preset");
    let guesses = gaits::model_guesses(w.as_ref());
    let (before, _) = gaits::search(w.as_ref(), &guesses, 1e-12).expect("search runs");
    assert!(
        !before.is_empty(),
        "the compass preset has a period-one gait"
    );
    let gait = before[0].fp.section.clone();
    let map = StrideMap::new(w.as_ref(), Options::dopri5(1e-10)).expect("map");
    let one = map.stride(&gait).expect("stride").next;
    let states: Vec<Vec<f64>> = (0..64)
        .map(|i| gait.iter().map(|g| g * (1.0 + 1e-3 * i as f64)).collect())
        .collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("pool");
    let all = map
        .strides_par(&states, 8, &pool, 8, &|_| {})
        .expect("strides");

    // 1. A long integration (budget 10^6 attempts over t ∈ [0, 10^4] at h ≤ 10^-3) stops
    //    within 1024 attempts of a request made by its 50th flow evaluation.
    let sys = Decay {
        evals: AtomicUsize::new(0),
        trigger: 50,
    };
    let mut opts = Options::dopri5(1e-10);
    opts.h_max = 1e-3;
    opts.max_steps = 1_000_000;
    let mut integ = Integrator::new(3, opts).expect("integrator");
    let (mut t, mut x) = (0.0, vec![1.0, 2.0, 3.0]);
    let stop = integ.integrate(
        &sys as &dyn pdw_hybrid::HybridSystem,
        0,
        &mut t,
        &mut x,
        1e4,
    );
    assert!(interrupt::requested());
    assert_eq!(
        stop,
        StopReason::MaxSteps,
        "an interrupt ends the call as a spent budget"
    );
    let attempts = integ.stats().accepted + integ.stats().rejected;
    assert!(
        (8..=1024 + 50).contains(&attempts),
        "stopped after {attempts} attempts; the request came at the 50th flow evaluation"
    );
    assert!(t < 1.1, "t = {t}: the call did not run on to its end time");

    // 2. With the request standing, every layer returns Interrupted at once.
    let e = map.stride(&gait).expect_err("a stride after a request");
    assert!(e.is_interrupted(), "{e}");
    let e = map
        .strides(&states, 8)
        .expect_err("a batch after a request");
    assert!(e.is_interrupted(), "{e}");
    let e = gaits::search(w.as_ref(), &guesses, 1e-12)
        .err()
        .expect("a gait search after a request");
    assert!(e.is_interrupted(), "{e}");
    let e = pdw_hybrid::run_scalar(
        &sys,
        &pdw_limit::stride::EventDriver {
            section_guard: (0, 0),
            start_mode: 0,
            t_max: 1.0,
        },
        &vec![1.0, 2.0, 3.0],
        &opts,
    )
    .expect_err("the scalar runner after a request");
    assert_eq!(e, HybridError::Interrupted);
    interrupt::clear();

    // 3. A request from inside a parallel batch (its first progress report) stops both workers:
    //    the call returns Interrupted, not a partial result.
    let reports = AtomicUsize::new(0);
    let r = map.strides_par(&states, 8, &pool, 8, &|_| {
        reports.fetch_add(1, Ordering::Relaxed);
        interrupt::request();
    });
    let e = r.expect_err("a batch interrupted in progress");
    assert!(e.is_interrupted(), "{e}");
    assert!(
        reports.load(Ordering::Relaxed) < 64 / 8,
        "it stopped before the end"
    );
    interrupt::clear();

    // 4. Cleared: the same calls give the same bits as before the requests.
    let (after, _) = gaits::search(w.as_ref(), &guesses, 1e-12).expect("search after clear");
    assert_eq!(after.len(), before.len());
    assert_eq!(after[0].fp.section, gait);
    assert_eq!(map.stride(&gait).expect("stride").next, one);
    let again = map
        .strides_par(&states, 8, &pool, 8, &|_| {})
        .expect("strides after clear");
    assert_eq!(again, all);
}
