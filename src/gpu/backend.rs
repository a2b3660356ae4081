//! The WGSL kernel as a [`RenderBackend`]: a device opened and a kernel compiled once.

use super::{Features, GpuContext, GpuRenderer, Kernel, Tuning};
use crate::backend::{RenderBackend, Rendered};
use crate::options::{Integrator, RenderOptions};
use crate::scene::flat::FlatScene;

pub struct GpuBackend {
    renderer: GpuRenderer,
    kernel: Kernel,
    integrator: Integrator,
}

impl GpuBackend {
    /// Opens the adapter whose name contains `adapter` (or the best one) and compiles the
    /// kernel with `features` for `scene`.
    pub fn new(
        adapter: Option<&str>,
        scene: &FlatScene,
        features: Features,
        integrator: Integrator,
    ) -> anyhow::Result<Self> {
        let renderer = GpuRenderer::new(GpuContext::new(adapter)?);
        let kernel = renderer.kernel(scene, features, "render")?;
        Ok(GpuBackend {
            renderer,
            kernel,
            integrator,
        })
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
        let (film, timings) =
            self.renderer
                .render(&self.kernel, scene, opts, &Tuning::default(), on_progress)?;
        Ok(Rendered {
            film,
            gpu_seconds: timings.gpu_seconds,
            longest_dispatch_seconds: Some(timings.longest_dispatch_seconds),
            device: self.device(),
        })
    }
}
