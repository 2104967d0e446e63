//! The per-step path allocates nothing: a counting global allocator watches `Simulation::step`
//! on every built-in scene (this test binary holds only this test, so no other thread
//! allocates while it counts).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn steps_do_not_allocate() {
    for name in viscobar::scene::builtin_names() {
        let (_, scene) = viscobar::scene::load(name, &[]).unwrap();
        let mut sim = viscobar::Simulation::new(&scene).unwrap();
        sim.step().unwrap(); // warm-up outside the count
        let before = ALLOCATIONS.load(Ordering::SeqCst);
        for _ in 0..100 {
            sim.step().unwrap();
        }
        let allocations = ALLOCATIONS.load(Ordering::SeqCst) - before;
        assert_eq!(
            allocations, 0,
            "{name}: {allocations} allocations in 100 steps"
        );
    }
}
