//! The CPU reference renderer: the ground truth the GPU kernel is tested against. Plain f32 math
//! in the same order as the WGSL kernel, one counter-based random stream per sample, rayon over
//! image rows.

pub mod accel;
pub mod aov;
pub mod background;
pub mod camera;
pub mod environment;
pub mod four_quads;
pub mod four_spheres;
pub mod integrator;
pub mod intersect;
pub mod lanes;
pub mod lights;
pub mod medium;
pub mod ray_count;
pub mod traversal_stats;
pub mod triangle_blocks;

use crate::backend::{RenderBackend, Rendered};
use crate::film::{Film, PixelRun, PixelStats, is_valid_sample};
use crate::options::{Integrator, RenderOptions, SamplerKind};
use crate::scene::flat::FlatScene;
use crate::shared::sampler::Sampler;
use rayon::prelude::*;
use std::sync::Mutex;

/// The CPU reference as a [`RenderBackend`]: rayon over all cores.
pub struct CpuBackend {
    integrator: Integrator,
}

impl CpuBackend {
    pub fn new(integrator: Integrator) -> Self {
        CpuBackend { integrator }
    }
}

impl RenderBackend for CpuBackend {
    fn integrator(&self) -> Integrator {
        self.integrator
    }

    fn device(&self) -> String {
        format!("cpu ({} threads)", rayon::current_num_threads())
    }

    fn render(
        &self,
        scene: &FlatScene,
        opts: &RenderOptions,
        on_progress: &(dyn Fn(f64) + Sync),
    ) -> anyhow::Result<Rendered> {
        // Counted and reported under one lock: rows finish on many threads, and a count taken
        // apart from its report could reach the caller after a later one (a progress bar, or a
        // Python callback, sees the fraction go back).
        let rows = Mutex::new(0u32);
        let (film, rays) = render_counting_rays(scene, opts, &|| {
            let mut done = rows.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
            *done += 1;
            on_progress(*done as f64 / opts.height as f64);
        });
        Ok(Rendered {
            film,
            rays: Some(rays),
            gpu_seconds: None,
            longest_dispatch_seconds: None,
            host_seconds: None,
            device: self.device(),
        })
    }
}

/// Renders samples `opts.first_sample .. opts.first_sample + opts.spp` of every pixel.
/// `on_row` is called once per finished image row (for progress bars).
pub fn render(scene: &FlatScene, opts: &RenderOptions, on_row: &(dyn Fn() + Sync)) -> Film {
    render_counting_rays(scene, opts, on_row).0
}

/// [`render`], and how many rays it traced (camera, bounce and shadow rays).
pub fn render_counting_rays(
    scene: &FlatScene,
    opts: &RenderOptions,
    on_row: &(dyn Fn() + Sync),
) -> (Film, u64) {
    let width = opts.width as usize;
    let mut film = Film::new(opts.width, opts.height);
    let (invalid, rays) = film
        .pixels
        .par_chunks_mut(width)
        .enumerate()
        .map(|(y, row)| {
            let rays_before = ray_count::rays_traced();
            let mut invalid = 0;
            for (x, stats) in row.iter_mut().enumerate() {
                invalid += render_pixel(scene, opts, x as u32, y as u32, stats);
            }
            // Read before the caller's callback, which might trace rays of its own.
            let rays = ray_count::rays_traced().wrapping_sub(rays_before);
            on_row();
            (invalid, rays)
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    film.invalid_samples = invalid;
    film.stratified = opts.sampler == SamplerKind::Sobol;
    (film, rays)
}

/// Accumulates one pixel's samples; returns how many were invalid (non-finite or negative) and
/// counted as zero.
fn render_pixel(
    scene: &FlatScene,
    opts: &RenderOptions,
    x: u32,
    y: u32,
    stats: &mut PixelStats,
) -> u64 {
    let pixel = y * opts.width + x;
    let mut invalid = 0;
    let mut run = PixelRun::default();
    for sample in opts.first_sample..opts.first_sample + opts.spp {
        let mut sampler = Sampler::for_sample(opts.sampler, pixel, sample, opts.seed);
        let ray = camera::generate_ray(&scene.camera, opts, x, y, &mut sampler);
        let mut radiance = if opts.integrator.is_feature() {
            aov::feature(scene, ray, opts, &mut sampler)
        } else {
            integrator::radiance(scene, ray, opts, &mut sampler)
        };
        if !is_valid_sample(radiance) {
            invalid += 1;
            radiance = glam::Vec3::ZERO;
        }
        // Only stratified renders need their replicas' statistics (see film.rs).
        if opts.sampler == SamplerKind::Sobol {
            run.add_indexed(radiance, sample);
        } else {
            run.add(radiance);
        }
    }
    stats.merge(run.stats());
    invalid
}
