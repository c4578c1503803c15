//! Hints that a record will soon be read, so that its cache miss overlaps the work
//! before the read instead of stalling it.
//!
//! A prefetch never changes what a program computes: it moves no data the program can
//! see, never faults, and may be ignored by the processor. On targets without a stable
//! prefetch instruction it does nothing.

/// Asks for the cache line holding `item`'s first byte and the one holding its last
/// to be brought towards the core. Returns at once; the read it prepares still happens
/// where the caller makes it.
#[inline(always)]
pub fn prefetch<T>(item: &T) {
    let first = std::ptr::from_ref(item).cast::<u8>();
    line(first);
    if std::mem::size_of::<T>() > 1 {
        line(first.wrapping_add(std::mem::size_of::<T>() - 1));
    }
}

/// Prefetches the cache line holding the byte at `at`.
#[inline(always)]
fn line(at: *const u8) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `prefetcht0` is a hint: it reads nothing the program sees and never
    // faults, whatever the address (here always inside or at the end of a live
    // reference), and SSE, which provides it, is part of every x86-64 processor.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(at.cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = at;
}
