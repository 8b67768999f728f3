//! Work split over threads with the bits of one thread: mutable slices that
//! threads share by taking disjoint ranges of them, and a loop over work
//! items that runs on rayon's pool (with the `parallel` feature) or in order.
//! Each item computes what it would on one thread; only sums of integers
//! cross items, so the result never depends on the thread count.

use std::marker::PhantomData;
use std::ops::Range;

/// A mutable slice shared by threads that each take a disjoint range of it.
pub(crate) struct Disjoint<'a, T> {
    ptr: *mut T,
    len: usize,
    _slice: PhantomData<&'a mut [T]>,
}

impl<T> Clone for Disjoint<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for Disjoint<'_, T> {}

// SAFETY: a `Disjoint` hands out its elements only through `range`, whose
// callers promise that the ranges in use at once do not overlap; each
// element is then reached from one thread at a time, as through `&mut [T]`.
unsafe impl<T: Send> Send for Disjoint<'_, T> {}
// SAFETY: as above.
unsafe impl<T: Send> Sync for Disjoint<'_, T> {}

impl<'a, T> Disjoint<'a, T> {
    /// Shares `slice` (borrowed mutably for as long as the `Disjoint` lives).
    pub(crate) fn new(slice: &'a mut [T]) -> Self {
        Disjoint {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
            _slice: PhantomData,
        }
    }

    /// The elements `range` (panics when it is not within the slice).
    ///
    /// # Safety
    /// No other slice taken from this `Disjoint` that overlaps `range` may
    /// be in use while the returned one is.
    pub(crate) unsafe fn range(self, range: Range<usize>) -> &'a mut [T] {
        assert!(
            range.start <= range.end && range.end <= self.len,
            "a range within the slice"
        );
        // SAFETY: in bounds (asserted); exclusive by the caller's promise;
        // alive for 'a, for which the slice is borrowed.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(range.start), range.len()) }
    }
}

/// Runs `f` on every item and sums what it returns: on the threads of
/// rayon's current pool when `threads` (and the `parallel` feature), else in
/// order on this thread.
pub(crate) fn sum_over<I: Sync>(
    items: &[I],
    threads: bool,
    f: impl Fn(&I) -> u32 + Sync + Send,
) -> u32 {
    #[cfg(feature = "parallel")]
    if threads && items.len() > 1 {
        use rayon::prelude::*;
        return items.par_iter().map(f).sum();
    }
    let _ = threads;
    items.iter().map(f).sum()
}

/// Runs `f` on `0..count` and sums what it returns, as [`sum_over`].
pub(crate) fn sum_over_count(
    count: usize,
    threads: bool,
    f: impl Fn(usize) -> u32 + Sync + Send,
) -> u32 {
    #[cfg(feature = "parallel")]
    if threads && count > 1 {
        use rayon::prelude::*;
        return (0..count).into_par_iter().map(f).sum();
    }
    let _ = threads;
    (0..count).map(f).sum()
}
