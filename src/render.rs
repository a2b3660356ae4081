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
    pub integrator: Integrator,
    /// Russian roulette from this many segments on (0: off). Unbiased: a path survives with the
    /// probability of its largest throughput component (at most 0.95) and is reweighted.
    pub roulette_depth: u32,
}

impl RenderOptions {
    /// `width` x `height` at `spp` samples, seed 0, the default integrator, no roulette.
    pub fn new(width: u32, height: u32, spp: u32, max_depth: u32) -> Self {
        RenderOptions {
            width,
            height,
            spp,
            first_sample: 0,
            seed: 0,
            max_depth,
            integrator: Integrator::default(),
            roulette_depth: 0,
        }
    }
}

/// How a path finds light.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Integrator {
    /// Paths find light only by hitting it (the original project's estimator).
    Naive,
    /// Next-event estimation: each diffuse hit also samples a light with a shadow ray, combined
    /// with BSDF sampling by multiple importance sampling (power heuristic).
    #[default]
    Nee,
}

impl Integrator {
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Naive => "naive",
            Integrator::Nee => "nee",
        }
    }
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
    /// The kernel features this choice runs `scene` with under `integrator`.
    pub fn features(&self, scene: &FlatScene, integrator: Integrator) -> Features {
        let features = if self.everything {
            Features::everything(scene)
        } else {
            Features::of(scene)
        };
        features.with_integrator(scene, integrator)
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
/// The GPU's kernel is built for one integrator, so a session is too.
pub enum Session {
    Cpu {
        integrator: Integrator,
    },
    Gpu {
        renderer: Box<GpuRenderer>,
        kernel: Box<Kernel>,
        integrator: Integrator,
    },
}

impl Session {
    pub fn new(
        backend: Backend,
        gpu: &GpuChoice,
        scene: &FlatScene,
        integrator: Integrator,
    ) -> anyhow::Result<Self> {
        Ok(match backend {
            Backend::Cpu => Session::Cpu { integrator },
            Backend::Gpu => {
                let renderer = GpuRenderer::new(GpuContext::new(gpu.adapter.as_deref())?);
                let features = gpu.features(scene, integrator);
                let kernel = renderer.kernel(scene, features, "render")?;
                Session::Gpu {
                    renderer: Box::new(renderer),
                    kernel: Box::new(kernel),
                    integrator,
                }
            }
        })
    }

    pub fn integrator(&self) -> Integrator {
        match self {
            Session::Cpu { integrator } | Session::Gpu { integrator, .. } => *integrator,
        }
    }

    /// What renders: "cpu (N threads)" or the adapter's name.
    pub fn device(&self) -> String {
        match self {
            Session::Cpu { .. } => format!("cpu ({} threads)", rayon::current_num_threads()),
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
        if opts.integrator != self.integrator() {
            anyhow::bail!(
                "this session was built for the {} integrator, not {}",
                self.integrator().name(),
                opts.integrator.name()
            );
        }
        match self {
            Session::Cpu { .. } => {
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
            Session::Gpu {
                renderer, kernel, ..
            } => {
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
    Session::new(backend, gpu, scene, opts.integrator)?.render(scene, opts, on_progress)
}
