//! Per-thread counters of traced rays, so benchmarks can report integrator rays/s without a shared
//! atomic on the hot path. Each worker thread counts into its own cell; `take` drains the calling
//! thread's counts (benchmarks call it on every worker, e.g. with rayon's `broadcast`).

use std::cell::Cell;

thread_local! {
    static CLOSEST: Cell<u64> = const { Cell::new(0) };
    static SHADOW: Cell<u64> = const { Cell::new(0) };
}

#[inline]
pub(crate) fn count_closest() {
    CLOSEST.with(|c| c.set(c.get() + 1));
}

#[inline]
pub(crate) fn count_shadow() {
    SHADOW.with(|c| c.set(c.get() + 1));
}

/// (closest-hit rays, shadow rays) traced on this thread since the last call; resets them.
pub fn take() -> (u64, u64) {
    (
        CLOSEST.with(|c| c.replace(0)),
        SHADOW.with(|c| c.replace(0)),
    )
}
