//! A hint to the CPU to bring one value into cache ahead of its use.
//!
//! The traversals evaluate front nodes whose geometry lies scattered over an array of
//! tens of megabytes (a 1M-triangle model has half a million nodes), so a frame's
//! evaluations are mostly cache misses taken one after another. The FIFO queues know
//! which nodes come next, so the passes ask for their geometry a few pops ahead and the
//! misses overlap. On targets without a prefetch instruction the hint does nothing.

/// How many entries ahead of the one being evaluated a pass prefetches: far enough to
/// cover a memory access with the evaluations between, near enough that the line is
/// still cached when its turn comes.
pub(crate) const DISTANCE: usize = 8;

/// Hints that `value` will be read soon. Never faults, never changes anything.
#[inline(always)]
pub(crate) fn prefetch<T>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // SAFETY: a prefetch is a hint with no architectural effect; the pointer comes
        // from a reference and is valid in any case.
        unsafe { _mm_prefetch::<_MM_HINT_T0>((value as *const T).cast::<i8>()) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}
