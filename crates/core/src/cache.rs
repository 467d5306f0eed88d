//! Cache hints.

/// Asks for the cache line holding `x` (a hint: nothing on other targets).
#[inline(always)]
pub fn prefetch<T>(x: &T) {
    // SAFETY: a prefetch only hints the cache (it never faults nor reads into the
    // program), and SSE, which it needs, is part of every x86-64 target.
    #[cfg(target_arch = "x86_64")]
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(
            (x as *const T).cast::<i8>(),
        );
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}
