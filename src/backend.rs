//! The interface every rendering backend implements (the CPU reference in `cpu/`, the WGSL
//! kernel in `gpu/`); [`crate::render::Session`] picks one.

use crate::film::Film;
use crate::options::{Integrator, RenderOptions};
use crate::scene::flat::FlatScene;

/// What a render produced.
pub struct Rendered {
    pub film: Film,
    /// Rays traced (camera, bounce and shadow rays), where the backend counts them (the CPU).
    pub rays: Option<u64>,
    /// Device time from timestamp queries, where available.
    pub gpu_seconds: Option<f64>,
    /// The longest single GPU dispatch (device time if known, else wall time).
    pub longest_dispatch_seconds: Option<f64>,
    /// The GPU's host share of the film, wall time (`gpu::Timings::host_seconds`).
    pub host_seconds: Option<f64>,
    /// What rendered it: "cpu (N threads)" or the adapter's name.
    pub device: String,
}

/// A device made ready (device opened, kernel compiled) to render one flat scene many times
/// with one integrator (the GPU's kernel is built for one).
pub trait RenderBackend {
    /// The integrator this backend was made ready for.
    fn integrator(&self) -> Integrator;
    /// What renders: "cpu (N threads)" or the adapter's name.
    fn device(&self) -> String;
    /// Renders `scene` (the one the backend was made ready for) with `opts`, whose integrator
    /// is this backend's; `on_progress` gets the fraction done.
    fn render(
        &self,
        scene: &FlatScene,
        opts: &RenderOptions,
        on_progress: &(dyn Fn(f64) + Sync),
    ) -> anyhow::Result<Rendered>;
}
