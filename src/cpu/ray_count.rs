//! Rays traced on this thread, for `rt-gpu bench`'s rays per second. A thread-local counter:
//! an atomic shared by all threads would bounce its cache line between cores at every ray.

use std::cell::Cell;

thread_local! {
    static RAYS: Cell<u64> = const { Cell::new(0) };
}

/// Counts one ray traced on this thread.
#[inline]
pub fn count_ray() {
    RAYS.with(|r| r.set(r.get().wrapping_add(1)));
}

/// Rays traced on this thread so far: read before and after a piece of work, the difference
/// is its rays.
pub fn rays_traced() -> u64 {
    RAYS.with(Cell::get)
}
