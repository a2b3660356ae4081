//! The backends that render: a [`RenderBackend`] per device, made ready once (a [`Session`])
//! for many renders. What a render is asked to do is in [`crate::options`]; a whole render, from
//! a request to its written outputs, is [`request`] (passes in [`progressive`], checkpoints in
//! [`checkpoint`]).

pub mod checkpoint;
pub mod progressive;
pub mod request;

pub use crate::backend::{RenderBackend, Rendered};
use crate::cpu::CpuBackend;
#[cfg(feature = "gpu")]
use crate::gpu::{Features, GpuBackend};
pub use crate::options::{Backend, Integrator, RenderOptions};
use crate::scene::flat::FlatScene;

/// GPU choices.
#[derive(Clone, Debug, Default)]
pub struct GpuChoice {
    /// Part of an adapter's name (see `rt-gpu devices`); `None` picks the best available.
    pub adapter: Option<String>,
    /// Run the everything-enabled kernel instead of the one specialised to the scene.
    pub everything: bool,
}

#[cfg(feature = "gpu")]
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

/// What `--backend auto` renders on, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct AutoBackend {
    pub backend: Backend,
    pub reason: String,
}

/// What `--backend auto` asks of the machine: the adapter wgpu would open, if any. Looking
/// starts the Vulkan loader and its drivers and needs no scene, so the CLI looks while the
/// scene loads.
pub struct AdapterLook {
    #[cfg(feature = "gpu")]
    info: Option<wgpu::AdapterInfo>,
    /// The vec4fs of images its kernel holds (`gpu::renderer::image_capacity`).
    #[cfg(feature = "gpu")]
    image_capacity: u64,
}

/// Looks for the adapter `gpu` names (the best available without a name).
pub fn look_for_adapter(gpu: &GpuChoice) -> AdapterLook {
    #[cfg(feature = "gpu")]
    {
        match crate::gpu::context::adapter_limits(gpu.adapter.as_deref()) {
            Ok((info, limits)) => AdapterLook {
                info: Some(info),
                image_capacity: crate::gpu::renderer::image_capacity(&limits),
            },
            Err(_) => AdapterLook {
                info: None,
                image_capacity: 0,
            },
        }
    }
    #[cfg(not(feature = "gpu"))]
    {
        let _ = gpu;
        AdapterLook {}
    }
}

/// `--backend auto`: a hardware GPU runs the kernel. On a software adapter (lavapipe,
/// SwiftShader, WARP: wgpu's `DeviceType::Cpu`, the CPU's own cores) the kernel runs only a
/// scene it holds inlined as constants, where it was measured faster than the CPU backend on
/// the same cores; a scene traced through its BVH goes to the CPU backend, faster there
/// (docs/benchmarks.md, 2026-12-02). With no adapter, or no `gpu` feature, the CPU backend.
pub fn auto_backend(gpu: &GpuChoice, scene: &FlatScene) -> AutoBackend {
    auto_backend_seeing(&look_for_adapter(gpu), gpu, scene)
}

/// [`auto_backend`] with the adapter already looked for (by [`look_for_adapter`] with `gpu`).
pub fn auto_backend_seeing(look: &AdapterLook, gpu: &GpuChoice, scene: &FlatScene) -> AutoBackend {
    let cpu = |reason: String| AutoBackend {
        backend: Backend::Cpu,
        reason,
    };
    #[cfg(feature = "gpu")]
    {
        let Some(info) = &look.info else {
            return cpu("no GPU adapter (`rt-gpu devices` lists what wgpu sees)".into());
        };
        let gpu_backend = |reason: String| AutoBackend {
            backend: Backend::Gpu,
            reason,
        };
        let images = crate::gpu::layout::ImageArray::plan(scene).bytes() / 16;
        if images > look.image_capacity {
            return cpu(format!(
                "the scene's images take {} MB, more than the adapter's largest texture holds ({} MB)",
                (images * 16) >> 20,
                (look.image_capacity * 16) >> 20
            ));
        }
        if info.device_type != wgpu::DeviceType::Cpu {
            return gpu_backend("a GPU".into());
        }
        if gpu.features(scene, Integrator::Naive).inline_scene {
            gpu_backend(
                "a software adapter, and the kernel holds this scene inlined: faster than the CPU backend".into(),
            )
        } else {
            cpu("a software adapter, and this scene is traced through a BVH: the CPU backend is faster".into())
        }
    }
    #[cfg(not(feature = "gpu"))]
    {
        let _ = (look, gpu, scene);
        cpu("built without the gpu feature".into())
    }
}

/// What `--backend gpu` asks of each image a scene loads (`assets::image::with_device_check`):
/// that the adapter `gpu` names holds it. Adapters are asked only for an image larger than any
/// holds (wgpu's default limits: 8192 rows), so other scenes never wait for the drivers.
#[cfg(feature = "gpu")]
pub fn image_check(gpu: &GpuChoice) -> crate::assets::image::DeviceCheck {
    let gpu = gpu.clone();
    let look = std::sync::OnceLock::new();
    std::sync::Arc::new(move |texels: u64| {
        if texels <= crate::gpu::renderer::image_capacity(&wgpu::Limits::default()) {
            return Ok(());
        }
        let look: &AdapterLook = look.get_or_init(|| look_for_adapter(&gpu));
        match &look.info {
            Some(info) if texels > look.image_capacity => Err(format!(
                "more than {}'s largest texture holds ({} texels): use a smaller image, or --backend cpu",
                info.name, look.image_capacity
            )),
            _ => Ok(()),
        }
    })
}

/// A backend made ready once (device opened, kernel compiled) for many renders of one scene.
/// The GPU's kernel is built for one integrator, so a session is too.
pub struct Session(Box<dyn RenderBackend>);

impl Session {
    pub fn new(
        backend: Backend,
        gpu: &GpuChoice,
        scene: &FlatScene,
        integrator: Integrator,
    ) -> anyhow::Result<Self> {
        Ok(Session(match backend {
            Backend::Cpu => Box::new(CpuBackend::new(integrator)),
            #[cfg(feature = "gpu")]
            Backend::Gpu => Box::new(GpuBackend::new(
                gpu.adapter.as_deref(),
                scene,
                gpu.features(scene, integrator),
                integrator,
            )?),
            #[cfg(not(feature = "gpu"))]
            Backend::Gpu => {
                let _ = (gpu, scene);
                anyhow::bail!("this rt-gpu was built without the gpu feature: use --backend cpu")
            }
        }))
    }

    pub fn integrator(&self) -> Integrator {
        self.0.integrator()
    }

    /// What renders: "cpu (N threads)" or the adapter's name.
    pub fn device(&self) -> String {
        self.0.device()
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
        self.0.render(scene, opts, on_progress)
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
