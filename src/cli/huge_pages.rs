//! The command line's allocator: the system's, asking Linux to back large allocations with
//! transparent huge pages (2 MiB) where the system leaves that to each program
//! (`/sys/kernel/mm/transparent_hugepage/enabled` set to `madvise`, a common default), as
//! Embree's allocator does for its BVHs. Loading a million-triangle mesh fills a few hundred
//! megabytes of fresh arrays (the file, its triangles, the BVH and its blocks), and taking them
//! in 4 KiB at a time cost more than any single stage of the load (docs/benchmarks.md).
//!
//! This code runs before `main` (the Rust runtime allocates), so before `main`'s check of the
//! CPU: that check runs earlier still, when the binary is loaded (`host_cpu.c`).

use std::alloc::{GlobalAlloc, Layout, System};

/// Allocations from this size on ask for huge pages: below it few whole huge pages fit.
const LARGE: usize = 4 << 20;
/// The granularity of the advice: the kernel's base page.
const PAGE: usize = 4096;

pub struct HugePages;

// SAFETY: every call is the system allocator's; the advice changes how the kernel backs the
// pages, never their contents or ownership.
unsafe impl GlobalAlloc for HugePages {
    #[inline]
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        advise(p, layout.size());
        p
    }

    #[inline]
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        advise(p, layout.size());
        p
    }

    #[inline]
    unsafe fn dealloc(&self, p: *mut u8, layout: Layout) {
        unsafe { System.dealloc(p, layout) }
    }

    #[inline]
    unsafe fn realloc(&self, p: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let q = unsafe { System.realloc(p, layout, new_size) };
        advise(q, new_size);
        q
    }
}

/// Asks for huge pages over the pages holding a large allocation at `p` of `size` bytes: from
/// the page of its start to the end of its usable size, so that an allocation the C library
/// maps on its own is advised as one whole mapping. (Advising only the whole huge pages inside
/// split such a mapping in three, and `realloc` could then no longer grow it in place with
/// `mremap`, but copied it.) Pages of a neighbour in the same page are advised too, which is
/// harmless: the advice never changes contents. Pages already touched keep their size until
/// the kernel's khugepaged gathers them.
#[inline]
fn advise(p: *mut u8, size: usize) {
    if size < LARGE || p.is_null() {
        return;
    }
    // SAFETY: `p` is a live allocation of the C library's malloc family (the system
    // allocator's, whatever the alignment), which `malloc_usable_size` accepts.
    let usable = unsafe { libc::malloc_usable_size(p.cast()) };
    let Some((start, len)) = pages_holding(p as usize, usable.max(size)) else {
        return;
    };
    // SAFETY: the range is mapped (the allocation's pages); MADV_HUGEPAGE is advice, which
    // the kernel may refuse (THP unsupported), and then nothing changes. errno is the
    // caller's, kept as it was.
    unsafe {
        let errno = libc::__errno_location();
        let saved = *errno;
        libc::madvise(start as *mut libc::c_void, len, libc::MADV_HUGEPAGE);
        *errno = saved;
    }
}

/// The pages holding `[address, address + size)`: the start of the first and the length up to
/// the end of the last.
fn pages_holding(address: usize, size: usize) -> Option<(usize, usize)> {
    let start = address / PAGE * PAGE;
    let end = address.checked_add(size)?.checked_next_multiple_of(PAGE)?;
    (end > start).then(|| (start, end - start))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn advice_covers_the_pages_holding_an_allocation() {
        let mb = 1 << 20;
        // Page-aligned at both ends: itself.
        assert_eq!(pages_holding(4 * mb, 8 * mb), Some((4 * mb, 8 * mb)));
        // A C library's mapped chunk: its 16-byte header in the first page.
        assert_eq!(
            pages_holding(4 * mb + 16, 8 * mb - 16),
            Some((4 * mb, 8 * mb))
        );
        // Ending inside a page: that page too.
        assert_eq!(
            pages_holding(4 * mb + 16, 8 * mb),
            Some((4 * mb, 8 * mb + PAGE))
        );
        assert_eq!(pages_holding(usize::MAX - mb, 4 * mb), None);
    }

    /// The mapping holding `address` in this process (/proc/self/smaps): its range and flags.
    fn mapping_of(address: usize) -> Option<(usize, usize, String)> {
        let smaps = std::fs::read_to_string("/proc/self/smaps").ok()?;
        let mut found: Option<(usize, usize)> = None;
        for line in smaps.lines() {
            let range = line
                .split_whitespace()
                .next()
                .and_then(|r| r.split_once('-'));
            let parsed = range.and_then(|(a, b)| {
                Some((
                    usize::from_str_radix(a, 16).ok()?,
                    usize::from_str_radix(b, 16).ok()?,
                ))
            });
            if let Some((a, b)) = parsed {
                found = (a <= address && address < b).then_some((a, b));
            } else if let (Some((a, b)), Some(flags)) = (found, line.strip_prefix("VmFlags:")) {
                return Some((a, b, flags.to_string()));
            }
        }
        None
    }

    /// A large allocation as every `Vec` makes one (malloc's alignment), and the same grown:
    /// advised for huge pages where the kernel has them, over one mapping holding the whole
    /// allocation (which `realloc` can then grow in place).
    #[test]
    fn large_allocations_are_advised_as_whole_mappings() {
        if !std::path::Path::new("/sys/kernel/mm/transparent_hugepage").exists() {
            eprintln!("no transparent huge pages in this kernel: nothing to check");
            return;
        }
        let a = HugePages;
        let layout = Layout::from_size_align(8 << 20, 8).unwrap();
        // SAFETY: a non-zero layout; each pointer is checked, written within its size, and
        // freed with its layout.
        unsafe {
            let p = a.alloc(layout);
            assert!(!p.is_null());
            p.write_bytes(1, layout.size());
            let check = |p: *mut u8, size: usize| {
                let usable = libc::malloc_usable_size(p.cast());
                let (start, end, flags) = mapping_of(p as usize).expect("a mapping holds it");
                assert!(flags.split_whitespace().any(|f| f == "hg"), "flags {flags}");
                assert!(start <= p as usize / PAGE * PAGE, "{start:x} {p:?}");
                assert!(
                    end >= p as usize + usable.max(size),
                    "{end:x} {p:?} {usable}"
                );
            };
            check(p, layout.size());
            let grown = a.realloc(p, layout, 16 << 20);
            assert!(!grown.is_null());
            assert_eq!(*grown.add((8 << 20) - 1), 1);
            check(grown, 16 << 20);
            a.dealloc(grown, Layout::from_size_align(16 << 20, 8).unwrap());
        }
    }

    /// The allocator gives what the system's does: contents kept through growth, zeroed
    /// memory zero, on both sides of the size that asks for huge pages, at malloc's alignment
    /// and beyond it.
    #[test]
    fn allocations_behave_as_the_systems() {
        let a = HugePages;
        for align in [8, 16, 64, 8192] {
            for size in [64, LARGE - 1, LARGE, 3 * LARGE + 5] {
                let layout = Layout::from_size_align(size, align).unwrap();
                // SAFETY: the layouts are of non-zero size; every pointer is checked, written
                // and read within its size, and freed with its layout.
                unsafe {
                    let z = a.alloc_zeroed(layout);
                    assert!(!z.is_null() && (z as usize).is_multiple_of(align));
                    assert!(std::slice::from_raw_parts(z, size).iter().all(|&b| b == 0));
                    a.dealloc(z, layout);
                    let p = a.alloc(layout);
                    assert!(!p.is_null() && (p as usize).is_multiple_of(align));
                    for i in (0..size).step_by(4093) {
                        *p.add(i) = (i % 251) as u8;
                    }
                    let grown = a.realloc(p, layout, 2 * size + LARGE);
                    assert!(!grown.is_null() && (grown as usize).is_multiple_of(align));
                    for i in (0..size).step_by(4093) {
                        assert_eq!(*grown.add(i), (i % 251) as u8);
                    }
                    let grown_layout = Layout::from_size_align(2 * size + LARGE, align).unwrap();
                    let shrunk = a.realloc(grown, grown_layout, size);
                    assert!(!shrunk.is_null() && (shrunk as usize).is_multiple_of(align));
                    for i in (0..size).step_by(4093) {
                        assert_eq!(*shrunk.add(i), (i % 251) as u8);
                    }
                    a.dealloc(shrunk, layout);
                }
            }
        }
    }
}
