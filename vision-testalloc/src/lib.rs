//! Tests only: a global allocator that tracks the peak of live heap bytes, so a test can show
//! that some work's memory is bounded (issues 17 and 26). A test binary installs it with
//!
//! ```ignore
//! #[global_allocator]
//! static GLOBAL: vision_testalloc::PeakAlloc = vision_testalloc::PeakAlloc;
//! ```
//!
//! and measures with [`peak_during`]. Without it installed, [`peak_during`] reports 0.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};

/// The system allocator, counting the bytes live and their peak.
pub struct PeakAlloc;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
/// One measurement at a time: two measured tests on parallel threads would count each other.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

// SAFETY: forwards every call to the system allocator unchanged; only tracks sizes.
unsafe impl GlobalAlloc for PeakAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let live = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
        PEAK.fetch_max(live, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

/// Runs `work` and returns its result with the peak of heap bytes live during it beyond those
/// live when it started, bytes. Measurements in one binary run one after another; allocations
/// of unmeasured tests running at the same time still count, so a binary that measures should
/// measure in every test (or hold one test).
pub fn peak_during<R>(work: impl FnOnce() -> R) -> (R, usize) {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(PoisonError::into_inner);
    let before = LIVE.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
    let result = work();
    (result, PEAK.load(Ordering::Relaxed).saturating_sub(before))
}

/// Runs `work` while no measurement runs: for an unmeasured test in a binary that measures,
/// whose allocations would otherwise count in another test's peak.
pub fn alone<R>(work: impl FnOnce() -> R) -> R {
    peak_during(work).0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[global_allocator]
    static GLOBAL: PeakAlloc = PeakAlloc;

    #[test]
    fn a_held_allocation_counts_and_a_freed_one_still_sets_the_peak() {
        let (kept, peak) = peak_during(|| {
            drop(vec![0u8; 1 << 20]);
            vec![0u8; 1 << 10]
        });
        assert_eq!(kept.len(), 1 << 10);
        assert!(peak >= 1 << 20, "{peak}");
        assert!(peak < 1 << 21, "{peak}");
    }
}
