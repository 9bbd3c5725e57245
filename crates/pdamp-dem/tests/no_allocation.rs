//! The time step allocates no memory once the scratch buffers have grown (engineering rule:
//! no allocation per step). Counted with a global allocator over the steps of a shaken bed
//! that neither rebuild the neighbour list nor refresh the wall candidates (both may still
//! grow their lists, and a refresh reserves wall slots for new candidates).

mod common;
use common::*;

use std::alloc::{GlobalAlloc, Layout, System};

use std::sync::atomic::{AtomicU64, Ordering};

struct Counting;

static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);

// SAFETY: forwards to the system allocator, counting the calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// 1 500 spheres in a box shaken at 50 Hz, 2 mm amplitude (wall contacts, new and ending
/// pair contacts every step): after 2 000 steps of warm-up, the steps without a rebuild or
/// refresh allocate nothing, with one thread and with two, plain or deferred
/// ([`pdamp_dem::World::step_deferred`]). (Before: every step allocated.)
#[test]
fn velocity_verlet_steps_do_not_allocate() {
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut w = box_world(1500, 1e-3, 0.03, 0.04, hertz_mindlin(0.6, 0.4), 2e-6, false, 7);
            shake(&mut w, [0.0, 0.0, 1.0], 2e-3, 50.0);
            for _ in 0..2000 {
                w.step();
            }
            let (mut quiet, mut allocating) = (0, 0);
            for _ in 0..500 {
                let (builds, refreshes) =
                    (w.counters.neighbor_builds, w.wall_candidate_refreshes());
                let a0 = ALLOCATIONS.load(Ordering::Relaxed);
                // Half of the steps with the half kick deferred (the fused pass).
                if w.counters.steps.is_multiple_of(2) {
                    w.step_deferred();
                } else {
                    w.step();
                }
                let a = ALLOCATIONS.load(Ordering::Relaxed) - a0;
                if w.counters.neighbor_builds == builds && w.wall_candidate_refreshes() == refreshes {
                    quiet += 1;
                    if a > 0 {
                        allocating += 1;
                    }
                }
            }
            eprintln!(
                "{threads} thread(s): {quiet} steps without rebuild or refresh, {allocating} allocated"
            );
            assert!(quiet > 100, "too few steps without a rebuild or refresh: {quiet}");
            assert_eq!(allocating, 0, "{allocating} of {quiet} steps allocated ({threads} threads)");
        });
    }
}
