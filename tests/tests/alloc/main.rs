//! Allocation counts of the hot paths, in one test binary with one counting global allocator:
//! the scalar and batched integrators ([`hybrid`]), the chain walker's right-hand sides, Jacobians,
//! guards and resets ([`chain_walker`]) and a recorded stride's samples ([`trajectory`]).
//!
//! The counter is per thread: each test counts the allocations of the thread it runs on, so the
//! tests may run side by side, and a count measures only the code the test calls on its own
//! thread (the measured calls here run on the calling thread).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

#[path = "../../../crates/pdw-hybrid/tests/common/mod.rs"]
mod common;

#[path = "../../../crates/pdw-walkers/tests/chain_common/mod.rs"]
mod chain_common;

mod chain_walker;
mod hybrid;
mod trajectory;

struct Counting;

thread_local! {
    /// Allocations made by this thread.
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        // `try_with`: the thread-local may already be gone while a thread is being torn down
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made so far by the calling thread.
pub fn allocs() -> usize {
    ALLOCS.with(|c| c.get())
}
