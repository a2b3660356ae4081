//! The film the viewer shows, on either backend: the kernel's accumulator kept on the device
//! (a [`LiveRender`]), or the CPU reference's film, rendered a pass at a time and uploaded in
//! the accumulator's layout. Both are the batch renderers' own code, driven a frame at a time.

use crate::backend::RenderBackend;
use crate::cpu::CpuBackend;
use crate::film::Film;
use crate::gpu::display::accumulator_words;
use crate::gpu::{Features, GpuBackend, GpuContext, LiveRender};
use crate::options::RenderOptions;
use crate::scene::flat::FlatScene;
use crate::shared::layout::ACCUM_BYTES_PER_PIXEL;
use std::time::Instant;

pub enum LiveFilm {
    Gpu {
        // Boxed: the kernel's state is far larger than the CPU film's handles.
        backend: Box<GpuBackend>,
        live: Box<LiveRender>,
        /// Samples per dispatch, sized from the last one's time.
        slice: u32,
    },
    Cpu {
        backend: CpuBackend,
        /// Where the film is uploaded each pass.
        queue: wgpu::Queue,
        opts: RenderOptions,
        film: Film,
        upload: wgpu::Buffer,
        /// Samples per pass, sized from the last one's time.
        slice: u32,
    },
}

impl LiveFilm {
    /// An empty film of `scene` with `opts` (`opts.spp` is ignored), on the kernel (`gpu`:
    /// its features) or the CPU backend, shown through `ctx`'s device.
    pub fn new(
        ctx: &GpuContext,
        gpu: Option<Features>,
        scene: &FlatScene,
        opts: &RenderOptions,
    ) -> anyhow::Result<Self> {
        Ok(match gpu {
            Some(features) => {
                let backend =
                    GpuBackend::with_context(ctx.clone(), scene, features, opts.integrator)?;
                let live = backend.live(scene, opts)?;
                LiveFilm::Gpu {
                    backend: Box::new(backend),
                    live: Box::new(live),
                    slice: 1,
                }
            }
            None => {
                let size = opts.width as u64 * opts.height as u64 * ACCUM_BYTES_PER_PIXEL;
                let upload = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("cpu film"),
                    size,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                let mut film = Film::new(opts.width, opts.height);
                film.stratified = opts.sampler == crate::options::SamplerKind::Sobol;
                LiveFilm::Cpu {
                    backend: CpuBackend::new(opts.integrator),
                    queue: ctx.queue.clone(),
                    opts: RenderOptions {
                        first_sample: 0,
                        spp: 0,
                        ..*opts
                    },
                    film,
                    upload,
                    slice: 1,
                }
            }
        })
    }

    /// Starts again from no samples with `scene`'s camera (the scene this film was made for).
    pub fn restart(&mut self, scene: &FlatScene) -> anyhow::Result<()> {
        match self {
            LiveFilm::Gpu { live, slice, .. } => {
                live.restart(scene)?;
                *slice = 1;
            }
            LiveFilm::Cpu {
                film, opts, slice, ..
            } => {
                let stratified = film.stratified;
                *film = Film::new(opts.width, opts.height);
                film.stratified = stratified;
                opts.spp = 0;
                *slice = 1;
            }
        }
        Ok(())
    }

    /// Samples per pixel so far.
    pub fn spp(&self) -> u32 {
        match self {
            LiveFilm::Gpu { live, .. } => live.spp(),
            LiveFilm::Cpu { opts, .. } => opts.spp,
        }
    }

    /// Renders for about `seconds` (at least one dispatch or pass), never past `most` spp;
    /// returns the samples per pixel added.
    pub fn advance(&mut self, scene: &FlatScene, seconds: f64, most: u32) -> anyhow::Result<u32> {
        let start = Instant::now();
        let before = self.spp();
        let left = |spp: u32| most.saturating_sub(spp);
        match self {
            LiveFilm::Gpu { live, slice, .. } => {
                while left(live.spp()) > 0 {
                    let (added, took) = live.add_samples((*slice).min(left(live.spp())))?;
                    *slice = next_slice(added, took, seconds);
                    if start.elapsed().as_secs_f64() >= seconds {
                        break;
                    }
                }
            }
            LiveFilm::Cpu {
                backend,
                queue,
                opts,
                film,
                upload,
                slice,
            } => {
                if left(opts.spp) > 0 {
                    let count = (*slice).min(left(opts.spp));
                    let pass = RenderOptions {
                        first_sample: opts.spp,
                        spp: count,
                        ..*opts
                    };
                    let rendered = backend.render(scene, &pass, &|_| {})?;
                    film.merge(&rendered.film);
                    opts.spp += count;
                    *slice = next_slice(count, start.elapsed().as_secs_f64(), seconds);
                    queue.write_buffer(upload, 0, bytemuck::cast_slice(&accumulator_words(film)));
                }
            }
        }
        Ok(self.spp() - before)
    }

    /// The accumulator the display pass reads.
    pub fn accumulator(&self) -> &wgpu::Buffer {
        match self {
            LiveFilm::Gpu { live, .. } => live.accumulator(),
            LiveFilm::Cpu { upload, .. } => upload,
        }
    }

    /// Every pixel brought to `spp()` samples (a BVH kernel's short pixels finished), so that
    /// what is shown is exactly the film of `spp()` samples.
    pub fn complete(&mut self) -> anyhow::Result<()> {
        if let LiveFilm::Gpu { live, .. } = self {
            live.complete()?;
        }
        Ok(())
    }

    /// The film so far (read back from the device for the kernel's).
    pub fn film(&mut self) -> anyhow::Result<Film> {
        Ok(match self {
            LiveFilm::Gpu { live, .. } => live.film()?,
            LiveFilm::Cpu { film, .. } => film.clone(),
        })
    }

    /// What renders: the adapter's name, or "cpu (N threads)".
    pub fn device(&self) -> String {
        match self {
            LiveFilm::Gpu { backend, .. } => backend.device(),
            LiveFilm::Cpu { backend, .. } => backend.device(),
        }
    }
}

/// Samples for the next slice: what fits `seconds` at the rate `added` samples in `took`
/// seconds showed, growing at most fourfold a step (the first dispatches include warm-up).
fn next_slice(added: u32, took: f64, seconds: f64) -> u32 {
    let rate = added as f64 / took.max(1e-6);
    ((rate * seconds) as u32).clamp(1, added.saturating_mul(4).max(1))
}
