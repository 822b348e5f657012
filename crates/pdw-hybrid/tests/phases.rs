//! The phase counters (`pdw_hybrid::phases`), in a test binary of their own: CI builds it a
//! second time with the `phase-timing` feature (`cargo test --release --workspace --features
//! pdw-hybrid/phase-timing --test phases`), which recompiles only this crate and this small file
//! (`--workspace` keeps every dependency's features those of the test build).

use pdw_hybrid::{
    phases, run_batch, BatchOptions, Control, HybridSystem, LaneDriver, Options, Scratch,
    StopReason,
};

// The bouncing ball of the other test files (`common::Ball`; the module allows dead code).
mod common;
use common::Ball;

const BALL: Ball = Ball { g: 9.81, e: 0.8 };

/// Bounces three times from the height given as the item, then finishes; outputs the bounces.
struct ThreeBounces;

impl LaneDriver<Ball> for ThreeBounces {
    type Item = f64;
    type Output = u32;
    type Lane = u32;

    fn start(&self, _sys: &Ball, item: &f64, _lane: &mut u32, x: &mut [f64]) -> (usize, f64) {
        x[0] = *item;
        x[1] = 0.0;
        (0, 20.0)
    }

    fn on_stop(
        &self,
        sys: &Ball,
        ws: &mut Scratch,
        _item: &f64,
        lane: &mut u32,
        stop: StopReason,
        mode: usize,
        _t: f64,
        x: &mut [f64],
    ) -> Control {
        match stop {
            StopReason::Guard { guard } if *lane < 2 => {
                let mut xp = [0.0; 2];
                let m = sys.reset(ws, mode, guard, x, &mut xp);
                x.copy_from_slice(&xp);
                *lane += 1;
                Control::Continue {
                    mode: m,
                    t_end: 20.0,
                }
            }
            StopReason::Guard { .. } => {
                *lane += 1;
                Control::Finish
            }
            _ => Control::Finish,
        }
    }

    fn finish(&self, _sys: &Ball, _item: &f64, lane: u32, _t: f64, _x: &[f64]) -> u32 {
        lane
    }
}

/// The phase counters count a batched run when the crate is built with `phase-timing`, and
/// cost nothing and report zeros otherwise. Every reset is an event the locator found on a step
/// whose dense output it built, so each counted event is at least one located step and one
/// dense output.
#[test]
fn phase_counters_count_a_batched_run_when_enabled() {
    let items: Vec<f64> = (0..64).map(|i| 0.5 + 0.02 * i as f64).collect();
    let bo = BatchOptions {
        lanes: 16,
        integrator: Options::dop853(1e-10),
    };
    phases::reset();
    let out = run_batch(&BALL, &ThreeBounces, &items, &bo).unwrap();
    let p = phases::take();
    let events: u64 = out.iter().map(|&o| u64::from(o)).sum();
    assert_eq!(events, 3 * 64, "every item bounced three times");
    if phases::ENABLED {
        assert!(p.ticks.iter().all(|&t| t > 0), "{p:?}");
        assert!(p.located >= events && p.dense >= events, "{p:?}");
    } else {
        assert_eq!(p, phases::PhaseTimes::default());
    }
}
