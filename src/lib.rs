//! rt-gpu: a physically based path tracer with a WGSL compute kernel (via wgpu) and a CPU
//! reference renderer computing the same estimator. See `docs/architecture.md`.

// `!(x > 0.0)` is deliberate throughout: unlike `x <= 0.0` it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod assets;
pub mod backend;
pub mod converge;
pub mod cpu;
pub mod denoise;
pub mod film;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod material;
pub mod options;
pub mod params;
pub mod placement;
pub mod render;
pub mod scene;
pub mod shape;
pub mod shared;
#[cfg(feature = "viewer")]
pub mod viewer;

thread_local! {
    static QUIET_PANICS: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs `f` with this thread's panics marked as expected: a loader that catches a panic in a
/// dependency (and turns it into an error naming the file) sets it so that the CLI's panic hook
/// does not also report it as a bug.
pub fn quiet_panics<T>(f: impl FnOnce() -> T) -> T {
    let before = QUIET_PANICS.with(|q| q.replace(true));
    struct Restore(bool);
    impl Drop for Restore {
        fn drop(&mut self) {
            QUIET_PANICS.with(|q| q.set(self.0));
        }
    }
    let _restore = Restore(before);
    f()
}

/// Runs `f`, a dependency's reader that may panic on input it should refuse, with its panic
/// quiet and caught: `None` if it panicked (nothing it built is kept, so unwind safety holds).
pub fn caught_quietly<T>(f: impl FnOnce() -> T) -> Option<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| quiet_panics(f))).ok()
}

/// Whether a panic on this thread now is one that [`quiet_panics`] expects.
pub fn panics_are_quiet() -> bool {
    QUIET_PANICS.with(|q| q.get())
}
