//! Where a batched run's time goes: tick counters per phase of the lockstep loop
//! ([`run_batch`](crate::run_batch), [`run_batch_par`](crate::run_batch_par)).
//!
//! Compiled in only with the crate feature `phase-timing`; without it every counter call is an
//! empty inline function and [`take`] returns zeros ([`ENABLED`] says which). A tick is one
//! count of the time-stamp counter on x86-64 (a constant rate, the same on every core of a
//! machine), a nanosecond elsewhere: compare phases by their shares, or scale the shares by a
//! wall-clock time measured around the run (as `profile batch` and `profile basin` do).
//!
//! Each thread adds to its own counters; a batch moves them to the process-wide totals when
//! its loop ends, and [`take`] reads and clears the totals. Reading the counter costs ~10 ns;
//! a timed build marks each phase of each lockstep iteration, each lane that stops and each
//! located event, and runs a few per cent slower than an untimed one.

/// Number of phases.
pub const N: usize = 8;

/// Names of the phases, in the order of [`PhaseTimes::ticks`].
pub const NAMES: [&str; N] = [
    "next step sizes, mode partition",
    "stages: stage sums and right-hand sides",
    "error norm",
    "guards at the step ends",
    "per-lane accept/reject, controller, commit",
    "event location (without the dense output)",
    "dense output of the event's step",
    "driver, resets and segment starts",
];

/// Whether this build counts (the `phase-timing` feature).
pub const ENABLED: bool = cfg!(feature = "phase-timing");

/// The totals of the phases since the last [`take`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhaseTimes {
    /// Ticks per phase (see [`NAMES`]); each phase excludes the ones nested in it.
    pub ticks: [u64; N],
    /// Accepted steps on which the event locator ran (a flagged guard).
    pub located: u64,
    /// Dense outputs built (a crossing seen on the step's samples).
    pub dense: u64,
}

// The phases, as indices of `NAMES` and of the raw slots. The per-lane pass is measured with
// the locator inside it, and the locator with the dense output inside it; `take` subtracts
// the nested phases.
pub(crate) const STEP_SIZES: usize = 0;
pub(crate) const STAGES: usize = 1;
pub(crate) const ERROR_NORM: usize = 2;
pub(crate) const GUARDS: usize = 3;
pub(crate) const PASS: usize = 4;
const LOCATE: usize = 5;
const DENSE: usize = 6;
pub(crate) const DRIVER: usize = 7;
const SLOTS: usize = N + 2;
const LOCATED: usize = N;
const DENSE_COUNT: usize = N + 1;

#[cfg(feature = "phase-timing")]
mod imp {
    use super::SLOTS;
    use std::cell::Cell;
    use std::sync::atomic::{AtomicU64, Ordering};

    static TOTAL: [AtomicU64; SLOTS] = [const { AtomicU64::new(0) }; SLOTS];

    thread_local! {
        static LOCAL: Cell<[u64; SLOTS]> = const { Cell::new([0; SLOTS]) };
    }

    #[inline(always)]
    pub fn now() -> u64 {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: RDTSC exists on every x86-64 processor and has no memory effects.
            unsafe { core::arch::x86_64::_rdtsc() }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            use std::sync::OnceLock;
            use std::time::Instant;
            static T0: OnceLock<Instant> = OnceLock::new();
            T0.get_or_init(Instant::now).elapsed().as_nanos() as u64
        }
    }

    #[inline(always)]
    pub fn add(slot: usize, v: u64) {
        LOCAL.with(|c| {
            let mut a = c.get();
            a[slot] += v;
            c.set(a);
        });
    }

    pub fn flush() {
        let a = LOCAL.with(|c| c.replace([0; SLOTS]));
        for (t, v) in TOTAL.iter().zip(a) {
            t.fetch_add(v, Ordering::Relaxed);
        }
    }

    pub fn take_raw() -> [u64; SLOTS] {
        std::array::from_fn(|i| TOTAL[i].swap(0, Ordering::Relaxed))
    }

    pub fn clear_local() {
        LOCAL.with(|c| c.set([0; SLOTS]));
    }
}

#[cfg(not(feature = "phase-timing"))]
mod imp {
    use super::SLOTS;
    #[inline(always)]
    pub fn now() -> u64 {
        0
    }
    #[inline(always)]
    pub fn add(_slot: usize, _v: u64) {}
    #[inline(always)]
    pub fn flush() {}
    pub fn take_raw() -> [u64; SLOTS] {
        [0; SLOTS]
    }
    pub fn clear_local() {}
}

/// The counter now (0 in an untimed build).
#[inline(always)]
pub(crate) fn now() -> u64 {
    imp::now()
}

/// Charge the time since `*t` to `phase` and restart the clock at now.
#[inline(always)]
pub(crate) fn lap(phase: usize, t: &mut u64) {
    if ENABLED {
        let n = imp::now();
        imp::add(phase, n.wrapping_sub(*t));
        *t = n;
    }
}

/// Charge one run of the event locator on a flagged step, `ticks` long (its dense output
/// included).
#[inline(always)]
pub(crate) fn charge_locate(ticks: u64) {
    if ENABLED {
        imp::add(LOCATE, ticks);
        imp::add(LOCATED, 1);
    }
}

/// Charge one dense output built by the locator, `ticks` long.
#[inline(always)]
pub(crate) fn charge_dense(ticks: u64) {
    if ENABLED {
        imp::add(DENSE, ticks);
        imp::add(DENSE_COUNT, 1);
    }
}

/// Move this thread's counters to the totals (end of a batch's loop).
#[inline(always)]
pub(crate) fn flush() {
    imp::flush()
}

/// Clear the totals and this thread's counters (the event locator also counts on a scalar
/// [`Integrator`](crate::Integrator)'s thread, and a batch run on this thread would move those
/// counts to the totals).
pub fn reset() {
    imp::clear_local();
    let _ = imp::take_raw();
}

/// Read and clear the totals of all threads.
pub fn take() -> PhaseTimes {
    let raw = imp::take_raw();
    let mut ticks = [0u64; N];
    ticks.copy_from_slice(&raw[..N]);
    ticks[PASS] = ticks[PASS].saturating_sub(ticks[LOCATE]);
    ticks[LOCATE] = ticks[LOCATE].saturating_sub(ticks[DENSE]);
    PhaseTimes {
        ticks,
        located: raw[LOCATED],
        dense: raw[DENSE_COUNT],
    }
}
