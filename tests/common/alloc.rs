//! A counting global allocator for the tests that watch the heap (tests/no_alloc.rs,
//! tests/memory.rs, tests/loads.rs): per thread, the number of allocations and the live and
//! peak bytes, so the harness's other threads are not counted. A `#[global_allocator]` must be
//! declared in the test crate itself: each such file declares
//! `#[global_allocator] static GLOBAL: common::alloc::Counting = common::alloc::Counting;`.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// The system allocator, counting this thread's allocations and heap.
pub struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
    static LIVE: Cell<usize> = const { Cell::new(0) };
    static PEAK: Cell<usize> = const { Cell::new(0) };
}

/// One allocation (`count`) of `delta` bytes more (or fewer) on this thread.
fn track(count: bool, delta: isize) {
    // `try_with`: the thread-locals may already be gone while a thread shuts down.
    if count {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
    }
    let _ = LIVE.try_with(|live| {
        let now = live.get().saturating_add_signed(delta);
        live.set(now);
        let _ = PEAK.try_with(|p| p.set(p.get().max(now)));
    });
}

/// Allocations (and reallocations) made by this thread so far.
pub fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

/// Bytes this thread holds now.
pub fn live_bytes() -> usize {
    LIVE.with(Cell::get)
}

/// The peak of [`live_bytes`] since the last [`reset_peak`].
pub fn peak_bytes() -> usize {
    PEAK.with(Cell::get)
}

/// Starts a new peak at the present heap.
pub fn reset_peak() {
    PEAK.with(|p| p.set(live_bytes()));
}

// SAFETY: every call is forwarded unchanged to the system allocator, which upholds
// `GlobalAlloc`'s contract; the counting touches thread-locals only and never allocates.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        track(true, layout.size() as isize);
        // SAFETY: the caller's `layout` contract is passed on as is.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        track(false, -(layout.size() as isize));
        // SAFETY: `ptr` came from `System` through this allocator, with this `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        track(true, new_size as isize - layout.size() as isize);
        // SAFETY: as for `dealloc`, with the caller's `new_size` contract passed on.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}
