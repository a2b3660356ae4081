//! Opening the GPU in tests. CI sets RT_GPU_REQUIRE_GPU=1 (it installs lavapipe), so a missing
//! adapter fails there; elsewhere GPU tests are skipped with a note.

use rt_gpu::film::Film;
use rt_gpu::gpu::{Features, GpuContext, GpuRenderer, Tuning};
use rt_gpu::render::RenderOptions;
use rt_gpu::scene::Scene;
use rt_gpu::scene::flat::FlatScene;

pub fn renderer() -> Option<GpuRenderer> {
    match GpuContext::new(None) {
        Ok(ctx) => Some(GpuRenderer::new(ctx)),
        Err(e) if std::env::var_os("RT_GPU_REQUIRE_GPU").is_some() => {
            panic!("RT_GPU_REQUIRE_GPU is set but the GPU is unavailable: {e}")
        }
        Err(e) => {
            eprintln!("skipping GPU test: {e}");
            None
        }
    }
}

pub fn render_gpu(r: &GpuRenderer, scene: &Scene, opts: &RenderOptions, tuning: &Tuning) -> Film {
    render_gpu_with(r, scene, opts, tuning, Features::of)
}

/// Renders with the kernel `features` picks for the flattened scene (and `opts.integrator`).
pub fn render_gpu_with(
    r: &GpuRenderer,
    scene: &Scene,
    opts: &RenderOptions,
    tuning: &Tuning,
    features: fn(&FlatScene) -> Features,
) -> Film {
    let flat = FlatScene::new(scene, opts.width, opts.height).expect("valid scene");
    let features = features(&flat).for_render(&flat, opts);
    let kernel = r
        .kernel(&flat, features, "render")
        .expect("kernel compiles");
    r.render(&kernel, &flat, opts, tuning, &|_| {})
        .expect("renders")
        .0
}
