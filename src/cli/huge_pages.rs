//! The command line's allocator: the system's, asking Linux to back large allocations with
//! transparent huge pages (2 MiB) where the system leaves that to each program
//! (`/sys/kernel/mm/transparent_hugepage/enabled` set to `madvise`, a common default), as
//! Embree's allocator does for its BVHs. Loading a million-triangle mesh fills a few hundred
//! megabytes of fresh arrays (the file, its triangles, the BVH and its blocks), and on 4 KiB
//! pages the faults taking them in were a sixth of the load's time (docs/benchmarks.md,
//! 2026-12-05, eleventh session).

use std::alloc::{GlobalAlloc, Layout, System};

/// Allocations from this size on ask for huge pages: below it few whole huge pages fit.
const LARGE: usize = 4 << 20;
/// The size (and alignment) of a transparent huge page on x86-64 and most of arm64.
const HUGE_PAGE: usize = 2 << 20;

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

/// Asks for huge pages over the whole ones within a large allocation at `p` of `size` bytes.
/// Only pages not yet touched are affected: a fresh allocation's, or a grown one's new part.
#[inline]
fn advise(p: *mut u8, size: usize) {
    if size < LARGE || p.is_null() {
        return;
    }
    if let Some((start, len)) = whole_huge_pages(p as usize, size) {
        // SAFETY: the range lies within the allocation just made; MADV_HUGEPAGE is advice,
        // which the kernel may refuse (THP disabled or unsupported), and then nothing changes.
        unsafe {
            libc::madvise(start as *mut libc::c_void, len, libc::MADV_HUGEPAGE);
        }
    }
}

/// The huge pages wholly inside `[address, address + size)`: their start and length.
fn whole_huge_pages(address: usize, size: usize) -> Option<(usize, usize)> {
    let start = address.checked_next_multiple_of(HUGE_PAGE)?;
    let end = address.checked_add(size)? / HUGE_PAGE * HUGE_PAGE;
    (end > start).then(|| (start, end - start))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn advice_covers_the_whole_huge_pages_inside_an_allocation_only() {
        let mb = 1 << 20;
        // Aligned at both ends: all of it.
        assert_eq!(whole_huge_pages(4 * mb, 8 * mb), Some((4 * mb, 8 * mb)));
        // A page header's offset: the aligned interior.
        assert_eq!(
            whole_huge_pages(4 * mb + 16, 8 * mb),
            Some((6 * mb, 6 * mb))
        );
        // Less than one whole huge page inside.
        assert_eq!(whole_huge_pages(mb, 3 * mb - 1), None);
        assert_eq!(whole_huge_pages(usize::MAX - mb, 4 * mb), None);
    }

    /// The allocator gives what the system's does: contents kept through growth, zeroed
    /// memory zero, on both sides of the size that asks for huge pages.
    #[test]
    fn allocations_behave_as_the_systems() {
        let a = HugePages;
        for size in [64, LARGE - 1, LARGE, 3 * LARGE + 5] {
            let layout = Layout::from_size_align(size, 64).unwrap();
            // SAFETY: the layouts are of non-zero size; every pointer is checked, written and
            // read within its size, and freed with its layout.
            unsafe {
                let z = a.alloc_zeroed(layout);
                assert!(!z.is_null());
                assert!(std::slice::from_raw_parts(z, size).iter().all(|&b| b == 0));
                a.dealloc(z, layout);
                let p = a.alloc(layout);
                assert!(!p.is_null());
                for i in (0..size).step_by(4093) {
                    *p.add(i) = (i % 251) as u8;
                }
                let grown = a.realloc(p, layout, 2 * size + LARGE);
                assert!(!grown.is_null());
                for i in (0..size).step_by(4093) {
                    assert_eq!(*grown.add(i), (i % 251) as u8);
                }
                let grown_layout = Layout::from_size_align(2 * size + LARGE, 64).unwrap();
                a.dealloc(grown, grown_layout);
            }
        }
    }
}
