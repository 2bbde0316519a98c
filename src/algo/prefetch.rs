//! A cache hint for the inner optimiser's minibatch draws.
//!
//! A minibatch draws its examples uniformly from an aggregated dataset that outgrows the caches
//! within a few DAgger rounds; each example read in the supervised pass would then be a cache
//! miss on that pass's dependency chain. Asking for every drawn example's cache lines when the
//! batch is formed lets the loads overlap. A prefetch reads nothing the program sees, so results
//! are unchanged; on targets other than x86-64 it does nothing. The crate denies `unsafe_code`
//! except here and in the interval product's call of its AVX2 route (`scalar::interval_product`).

/// Hint that `x`'s first and last bytes will be read soon (no effect on any value).
#[inline(always)]
pub(crate) fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let first = (x as *const T).cast::<i8>();
        let last = first.wrapping_add(size_of::<T>().saturating_sub(1));
        #[allow(unsafe_code)]
        // SAFETY: a prefetch never faults and has no architectural effect; both addresses lie
        // within `x`, a live reference.
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(first);
            _mm_prefetch::<_MM_HINT_T0>(last);
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}
