//! The global allocator of `tptd-mesh`: the system allocator, with the explicit memory limit
//! of [`tptd::memory::set_limit`] enforced, and out-of-memory turned into the one-line error
//! every other failure gives (instead of Rust's abort).
//!
//! Inside [`tptd::memory::fallible`] a refused allocation returns null, so `try_reserve`
//! reports it; anywhere else the process removes its unfinished outputs, prints
//! `tptd-mesh: error: out of memory: …` and exits with status 1.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use tptd::memory::{explicit_limit, in_fallible_section, Bytes};

/// Bytes allocated through [`CappedAlloc`] and not yet freed (counted only under a limit).
static IN_USE: AtomicU64 = AtomicU64::new(0);

/// Whether the run lists critical points (`--critical`) instead of meshing: the
/// out-of-memory hint then says what helps there.
static CRITICAL: AtomicBool = AtomicBool::new(false);

/// Makes the out-of-memory hint the one of `--critical` runs.
pub(crate) fn set_critical_mode() {
    CRITICAL.store(true, Ordering::Relaxed);
}

/// The system allocator under the process's explicit memory limit.
pub(crate) struct CappedAlloc;

impl CappedAlloc {
    /// Counts `size` more bytes; false (counting nothing) when that exceeds the limit.
    fn take(size: usize) -> bool {
        let Some(limit) = explicit_limit() else {
            return true;
        };
        let size = size as u64;
        let before = IN_USE.fetch_add(size, Ordering::Relaxed);
        if before.saturating_add(size) > limit {
            IN_USE.fetch_sub(size, Ordering::Relaxed);
            return false;
        }
        true
    }

    fn give_back(size: usize) {
        if explicit_limit().is_some() {
            // Saturating: blocks allocated before the limit was set were never counted.
            let _ = IN_USE.fetch_update(Ordering::Relaxed, Ordering::Relaxed, |v| {
                Some(v.saturating_sub(size as u64))
            });
        }
    }

    /// The end of an allocation that failed: null in a fallible section, else the exit.
    fn failed(size: usize) -> *mut u8 {
        if in_fallible_section() {
            return std::ptr::null_mut();
        }
        out_of_memory(size)
    }
}

/// Removes the unfinished outputs, prints one line and exits with status 1. Allocates
/// nothing large (the message is formatted on the stack).
fn out_of_memory(size: usize) -> ! {
    tptd::io::remove_pending_temporaries();
    let mut buf = [0u8; 320];
    let mut cur = std::io::Cursor::new(&mut buf[..]);
    let critical = CRITICAL.load(Ordering::Relaxed);
    let size = Bytes(size as u64);
    let _ = match explicit_limit() {
        Some(l) => writeln!(
            cur,
            "tptd-mesh: error: out of memory: {size} more would exceed the memory limit of {}; \
             raise --memory-limit, {}",
            Bytes(l),
            if critical {
                "crop the volume or leave out --spectrum and --persistence"
            } else {
                "crop the volume or narrow the interval"
            }
        ),
        None => writeln!(
            cur,
            "tptd-mesh: error: out of memory: the system refused {size}; {}",
            if critical {
                "crop the volume or leave out --spectrum and --persistence"
            } else {
                "crop the volume, narrow the interval or use --no-analysis"
            }
        ),
    };
    let n = cur.position() as usize;
    let _ = std::io::stderr().write_all(&buf[..n]);
    std::process::exit(1)
}

// SAFETY: every method forwards to `System` with the caller's layout; the counting only
// decides whether to forward.
unsafe impl GlobalAlloc for CappedAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if !Self::take(layout.size()) {
            return Self::failed(layout.size());
        }
        let p = System.alloc(layout);
        if p.is_null() {
            Self::give_back(layout.size());
            return Self::failed(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if !Self::take(layout.size()) {
            return Self::failed(layout.size());
        }
        let p = System.alloc_zeroed(layout);
        if p.is_null() {
            Self::give_back(layout.size());
            return Self::failed(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout);
        Self::give_back(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let old = layout.size();
        if new_size > old && !Self::take(new_size - old) {
            return Self::failed(new_size);
        }
        let p = System.realloc(ptr, layout, new_size);
        if p.is_null() {
            if new_size > old {
                Self::give_back(new_size - old);
            }
            return Self::failed(new_size);
        }
        if new_size < old {
            Self::give_back(old - new_size);
        }
        p
    }
}
