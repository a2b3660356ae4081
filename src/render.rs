//! What a render is asked to do, and the backends that do it.

use crate::film::Film;
use crate::gpu::{Features, GpuContext, GpuRenderer, Kernel, Tuning};
use crate::scene::flat::FlatScene;
use std::sync::atomic::{AtomicU32, Ordering};

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

/// GPU choices.
#[derive(Clone, Debug, Default)]
pub struct GpuChoice {
    /// Part of an adapter's name (see `rt-gpu devices`); `None` picks the best available.
    pub adapter: Option<String>,
    /// Run the everything-enabled kernel instead of the one specialised to the scene.
    pub everything: bool,
}

impl GpuChoice {
    /// The kernel features this choice runs `scene` with.
    pub fn features(&self, scene: &FlatScene) -> Features {
        if self.everything {
            Features::everything(scene)
        } else {
            Features::of(scene)
        }
    }
}

pub struct Rendered {
    pub film: Film,
    /// Device time from timestamp queries, where available.
    pub gpu_seconds: Option<f64>,
    /// The longest single GPU dispatch (device time if known, else wall time).
    pub longest_dispatch_seconds: Option<f64>,
    /// What rendered it: "cpu (N threads)" or the adapter's name.
    pub device: String,
}

/// A backend made ready once (device opened, kernel compiled) for many renders of one scene.
pub enum Session {
    Cpu,
    Gpu {
        renderer: Box<GpuRenderer>,
        kernel: Box<Kernel>,
    },
}

impl Session {
    pub fn new(backend: Backend, gpu: &GpuChoice, scene: &FlatScene) -> anyhow::Result<Self> {
        Ok(match backend {
            Backend::Cpu => Session::Cpu,
            Backend::Gpu => {
                let renderer = GpuRenderer::new(GpuContext::new(gpu.adapter.as_deref())?);
                let features = gpu.features(scene);
                let kernel = renderer.kernel(scene, features, "render")?;
                Session::Gpu {
                    renderer: Box::new(renderer),
                    kernel: Box::new(kernel),
                }
            }
        })
    }

    /// What renders: "cpu (N threads)" or the adapter's name.
    pub fn device(&self) -> String {
        match self {
            Session::Cpu => format!("cpu ({} threads)", rayon::current_num_threads()),
            Session::Gpu { renderer, .. } => renderer.ctx.info.name.clone(),
        }
    }

    /// Renders `scene` (the one the session was made for); `on_progress` gets the fraction done.
    pub fn render(
        &self,
        scene: &FlatScene,
        opts: &RenderOptions,
        on_progress: &(dyn Fn(f64) + Sync),
    ) -> anyhow::Result<Rendered> {
        match self {
            Session::Cpu => {
                let rows = AtomicU32::new(0);
                let film = crate::cpu::render(scene, opts, &|| {
                    let done = rows.fetch_add(1, Ordering::Relaxed) + 1;
                    on_progress(done as f64 / opts.height as f64);
                });
                Ok(Rendered {
                    film,
                    gpu_seconds: None,
                    longest_dispatch_seconds: None,
                    device: self.device(),
                })
            }
            Session::Gpu { renderer, kernel } => {
                let (film, timings) =
                    renderer.render(kernel, scene, opts, &Tuning::default(), on_progress)?;
                Ok(Rendered {
                    film,
                    gpu_seconds: timings.gpu_seconds,
                    longest_dispatch_seconds: Some(timings.longest_dispatch_seconds),
                    device: self.device(),
                })
            }
        }
    }
}

/// Renders on `backend`; `on_progress` is called with the fraction of work done.
pub fn render(
    backend: Backend,
    gpu: &GpuChoice,
    scene: &FlatScene,
    opts: &RenderOptions,
    on_progress: &(dyn Fn(f64) + Sync),
) -> anyhow::Result<Rendered> {
    Session::new(backend, gpu, scene)?.render(scene, opts, on_progress)
}
