//! Software prefetch of the data the next iterations of a loop will read.

/// Hints the processor to load the cache line of `x` (no effect on other targets).
#[inline(always)]
pub(super) fn prefetch<T>(x: &T) {
    prefetch_at((x as *const T).cast::<u8>());
}

/// Hints the processor to load the cache line at `p` (never dereferenced).
#[inline(always)]
pub(super) fn prefetch_at(p: *const u8) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is only a hint; it never faults, whatever the address.
    #[allow(unused_unsafe)]
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(p.cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}
