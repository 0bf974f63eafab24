//! A counting global allocator: live bytes, the peak since a reset, and the
//! largest single request, so that the harness can hold each load to a
//! memory bound.
//!
//! A binary that wants the counts installs it:
//!
//! ```text
//! #[global_allocator]
//! static ALLOC: ballpass_fuzz::alloc::Counting = ballpass_fuzz::alloc::Counting;
//! ```
//!
//! Requests above [`HARD_CAP`] are refused (null), which aborts the process
//! with "memory allocation of N bytes failed" instead of letting a runaway
//! loader take the machine's memory: that is a failure the run reports by
//! dying, reproducible from its seed.

#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

/// Largest single allocation served, bytes.
pub const HARD_CAP: usize = 2 << 30;

static CURRENT: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static LARGEST: AtomicUsize = AtomicUsize::new(0);

/// The counting allocator (the system allocator underneath).
pub struct Counting;

fn grew(size: usize) {
    let now = CURRENT.fetch_add(size, Relaxed) + size;
    PEAK.fetch_max(now, Relaxed);
    LARGEST.fetch_max(size, Relaxed);
}

// SAFETY: every method forwards to `System` with the caller's layout and
// pointer unchanged (the `GlobalAlloc` contract is `System`'s), and only
// updates atomic counters besides; refusing a request by returning null is
// allowed by that contract.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if layout.size() > HARD_CAP {
            LARGEST.fetch_max(layout.size(), Relaxed);
            return std::ptr::null_mut();
        }
        // SAFETY: the caller upholds `alloc`'s contract for `layout`.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if layout.size() > HARD_CAP {
            LARGEST.fetch_max(layout.size(), Relaxed);
            return std::ptr::null_mut();
        }
        // SAFETY: as `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by this allocator (so by `System`)
        // with `layout`, as the caller guarantees.
        unsafe { System.dealloc(ptr, layout) };
        CURRENT.fetch_sub(layout.size(), Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size > HARD_CAP {
            LARGEST.fetch_max(new_size, Relaxed);
            return std::ptr::null_mut();
        }
        // SAFETY: as `dealloc` for `ptr` and `layout`; `new_size` is the
        // caller's, checked by it.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            CURRENT.fetch_sub(layout.size(), Relaxed);
            grew(new_size);
        }
        p
    }
}

/// Memory counts between [`reset`] and now.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Usage {
    /// Highest live bytes above the live bytes at the reset.
    pub peak_bytes: usize,
    /// Largest single request, bytes.
    pub largest_bytes: usize,
}

/// Starts a new measurement: the peak from now, the largest request from now.
pub fn reset() {
    PEAK.store(CURRENT.load(Relaxed), Relaxed);
    LARGEST.store(0, Relaxed);
}

/// Live bytes now.
pub fn current() -> usize {
    CURRENT.load(Relaxed)
}

/// What happened since [`reset`], the live bytes at the reset being `base`.
pub fn usage(base: usize) -> Usage {
    Usage {
        peak_bytes: PEAK.load(Relaxed).saturating_sub(base),
        largest_bytes: LARGEST.load(Relaxed),
    }
}
