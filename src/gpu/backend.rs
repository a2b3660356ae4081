//! The WGSL kernel as a [`RenderBackend`]: a device opened once, and a kernel compiled for each
//! sampler the renders ask for (the first one's up front).

use super::{Features, GpuContext, GpuRenderer, Kernel, LiveRender, Tuning};
use crate::backend::{RenderBackend, Rendered};
use crate::options::{Integrator, RenderOptions, SamplerKind};
use crate::scene::flat::FlatScene;
use std::sync::{Arc, Mutex};

pub struct GpuBackend {
    renderer: GpuRenderer,
    /// The scene's features for this backend's integrator, before the sampler is chosen.
    features: Features,
    kernels: Mutex<Vec<Arc<Kernel>>>,
    integrator: Integrator,
}

impl GpuBackend {
    /// Opens the adapter whose name contains `adapter` (or the best one) and compiles the
    /// kernel with `features` for `scene` and the default sampler.
    pub fn new(
        adapter: Option<&str>,
        scene: &FlatScene,
        features: Features,
        integrator: Integrator,
    ) -> anyhow::Result<Self> {
        Self::with_context(GpuContext::new(adapter)?, scene, features, integrator)
    }

    /// As [`GpuBackend::new`], on a device already open (the viewer's, which shows its
    /// window).
    pub fn with_context(
        ctx: GpuContext,
        scene: &FlatScene,
        features: Features,
        integrator: Integrator,
    ) -> anyhow::Result<Self> {
        let backend = GpuBackend {
            renderer: GpuRenderer::new(ctx),
            features,
            kernels: Mutex::new(Vec::new()),
            integrator,
        };
        backend.kernel(scene, SamplerKind::default())?;
        Ok(backend)
    }

    /// The kernel for `sampler`, compiled the first time it is asked for.
    fn kernel(&self, scene: &FlatScene, sampler: SamplerKind) -> anyhow::Result<Arc<Kernel>> {
        // As the device builds it (a software adapter's counts its loops): what the cache holds.
        let features = self.renderer.for_device(Features {
            sobol: sampler == SamplerKind::Sobol,
            ..self.features
        });
        let mut kernels = self.kernels.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(k) = kernels.iter().find(|k| k.features == features) {
            return Ok(k.clone());
        }
        let kernel = Arc::new(self.renderer.kernel(scene, features, "render")?);
        kernels.push(kernel.clone());
        Ok(kernel)
    }
}

impl GpuBackend {
    /// How many kernels it has compiled: one per sampler asked for, however many renders.
    pub fn compiled_kernels(&self) -> usize {
        self.kernels.lock().unwrap_or_else(|e| e.into_inner()).len()
    }

    /// A render of `scene` with `opts` that stays on the device (see [`LiveRender`]).
    pub fn live(&self, scene: &FlatScene, opts: &RenderOptions) -> anyhow::Result<LiveRender> {
        let kernel = self.kernel(scene, opts.sampler)?;
        Ok(LiveRender::new(&self.renderer, kernel, scene, opts)?)
    }

    /// The device this backend renders on.
    pub fn context(&self) -> &GpuContext {
        &self.renderer.ctx
    }
}

impl RenderBackend for GpuBackend {
    fn integrator(&self) -> Integrator {
        self.integrator
    }

    fn device(&self) -> String {
        self.renderer.ctx.info.name.clone()
    }

    fn render(
        &self,
        scene: &FlatScene,
        opts: &RenderOptions,
        on_progress: &(dyn Fn(f64) + Sync),
    ) -> anyhow::Result<Rendered> {
        let kernel = self.kernel(scene, opts.sampler)?;
        let (film, timings) =
            self.renderer
                .render(&kernel, scene, opts, &Tuning::default(), on_progress)?;
        Ok(Rendered {
            film,
            rays: None,
            gpu_seconds: timings.gpu_seconds,
            longest_dispatch_seconds: Some(timings.longest_dispatch_seconds),
            host_seconds: Some(timings.host_seconds),
            device: self.device(),
        })
    }
}
