//! A process-wide request to stop: Ctrl-C or SIGTERM in the CLI, `KeyboardInterrupt` in Python.
//!
//! Computation polls one flag instead of threading a token through every layer. Once
//! [`request`] has been called:
//! - [`run_scalar_with`](crate::run_scalar_with), [`run_batch`](crate::run_batch) and
//!   [`run_batch_par`](crate::run_batch_par) return [`HybridError::Interrupted`](crate::HybridError::Interrupted) at their next
//!   integration call or lockstep step (every lane of a batch steps at least once per loop);
//! - an [`Integrator`](crate::Integrator) call in progress ends within 1024 step attempts as if
//!   its step budget had run out ([`StopReason::MaxSteps`](crate::StopReason::MaxSteps)), so a
//!   caller of the integrator itself must test [`requested`] before trusting that stop.
//!
//! Every later integration then stops at once, so gait searches, continuations and attractor
//! discovery unwind within milliseconds even where they turn a failed stride into "try the next
//! guess". Their results are meaningless after a request: a front end that polls the flag
//! discards them ([`requested`] after the call) and reports the interrupt. The flag stays set until
//! [`clear`] (the Python package clears it once its interrupted call has returned).
//!
//! A front end that runs several computations in one process (the explorer: a refine job beside
//! the walks of clicked cells) stops one of them without the others with [`watch`]: a flag of
//! its own that counts as a request on the threads that watch it, and only there.

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Asks every computation in the process to stop (safe from a signal handler: one atomic store).
pub fn request() {
    REQUESTED.store(true, Ordering::SeqCst);
}

/// Withdraws the request (for the next call, after the interrupted one has returned).
pub fn clear() {
    REQUESTED.store(false, Ordering::SeqCst);
}

thread_local! {
    static WATCHED: RefCell<Option<Arc<AtomicBool>>> = const { RefCell::new(None) };
}

/// Makes `flag` (set: stop) count as a request on this thread until the next `watch`
/// (`None`: none watched). Returns the flag watched before, to restore it. A computation that
/// spreads over a rayon pool watches on every thread of it
/// (`pool.broadcast(|_| watch(Some(flag.clone())))`).
pub fn watch(flag: Option<Arc<AtomicBool>>) -> Option<Arc<AtomicBool>> {
    WATCHED.with(|w| w.replace(flag))
}

/// Whether a stop has been requested: for the whole process ([`request`]) or by the flag this
/// thread watches ([`watch`]).
#[inline]
pub fn requested() -> bool {
    REQUESTED.load(Ordering::Relaxed)
        || WATCHED.with(|w| {
            w.borrow()
                .as_ref()
                .is_some_and(|f| f.load(Ordering::Relaxed))
        })
}
