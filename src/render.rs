//! What a render is asked to do, and the backends that do it.

use crate::film::Film;
use crate::scene::flat::FlatScene;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel in this render.
    pub spp: u32,
    /// Index of the first sample: a render continuing an earlier one of `n` samples starts at `n`.
    pub first_sample: u32,
    pub seed: u32,
    /// The number of path segments.
    pub max_depth: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Backend {
    /// The WGSL compute kernel through wgpu (any Vulkan, Metal or DX12 device, or Mesa lavapipe).
    Gpu,
    /// The CPU reference renderer (rayon over all cores).
    Cpu,
}

impl Backend {
    pub fn name(self) -> &'static str {
        match self {
            Backend::Gpu => "gpu",
            Backend::Cpu => "cpu",
        }
    }
}

/// Renders on `backend`; `on_progress` is called with fractions of the work done.
pub fn render(
    backend: Backend,
    scene: &FlatScene,
    opts: &RenderOptions,
    on_row: &(dyn Fn() + Sync),
) -> anyhow::Result<Film> {
    match backend {
        Backend::Cpu => Ok(crate::cpu::render(scene, opts, on_row)),
        Backend::Gpu => anyhow::bail!("the GPU backend is not built yet: use --backend cpu"),
    }
}
