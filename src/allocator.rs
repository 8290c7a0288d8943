//! A global allocator for programs built on the library: the system allocator with the
//! explicit memory limit of [`crate::memory::set_limit`] enforced, and out-of-memory turned
//! into one line on stderr and exit status 1 (instead of Rust's abort). A program installs
//! it with `#[global_allocator] static A: tptd::allocator::CappedAlloc = CappedAlloc;` and
//! may word the line itself ([`set_out_of_memory_message`]).
//!
//! Inside [`crate::memory::fallible`] a refused allocation returns null, so `try_reserve`
//! reports it; anywhere else the process removes its unfinished outputs
//! ([`crate::io::remove_pending_temporaries`]), prints the line and exits with status 1.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

use crate::memory::{explicit_limit, in_fallible_section, Bytes};

/// Bytes allocated through [`CappedAlloc`] and not yet freed (counted only under a limit).
static IN_USE: AtomicU64 = AtomicU64::new(0);

/// An allocation refused: what was asked for and the limit it would have exceeded.
#[derive(Clone, Copy, Debug)]
pub struct OutOfMemory {
    /// The bytes asked for.
    pub size: Bytes,
    /// The explicit limit (`None`: the system refused).
    pub limit: Option<Bytes>,
}

/// Writes the out-of-memory line (with its newline). It must not allocate anything large:
/// it writes into a buffer on the stack.
pub type OutOfMemoryMessage = fn(&mut dyn Write, OutOfMemory) -> std::io::Result<()>;

static MESSAGE: OnceLock<OutOfMemoryMessage> = OnceLock::new();

/// Sets the out-of-memory line (once; later calls change nothing). The default is
/// `out of memory: {size} more would exceed the memory limit of {limit}` or
/// `out of memory: the system refused {size}`.
pub fn set_out_of_memory_message(message: OutOfMemoryMessage) {
    let _ = MESSAGE.set(message);
}

/// The default out-of-memory line.
fn default_message(w: &mut dyn Write, m: OutOfMemory) -> std::io::Result<()> {
    match m.limit {
        Some(l) => writeln!(
            w,
            "out of memory: {} more would exceed the memory limit of {l}",
            m.size
        ),
        None => writeln!(w, "out of memory: the system refused {}", m.size),
    }
}

/// The system allocator under the process's explicit memory limit.
pub struct CappedAlloc;

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
    crate::io::remove_pending_temporaries();
    let mut buf = [0u8; 320];
    let mut cur = std::io::Cursor::new(&mut buf[..]);
    let m = OutOfMemory {
        size: Bytes(size as u64),
        limit: explicit_limit().map(Bytes),
    };
    let _ = MESSAGE.get().copied().unwrap_or(default_message)(&mut cur, m);
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
