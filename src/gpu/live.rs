//! A render that stays on the device, for the viewer: one accumulator over the whole image,
//! samples added to it a dispatch at a time, read in place by the display pass
//! (`display.rs`). The film comes back to the host only when asked for, and is then the film a
//! batch render of the same samples gives, bit for bit (the sums are exact, so how the samples
//! were split into dispatches does not show).

use super::context::GpuError;
use super::dispatch::Tuning;
use super::layout::base_params;
use super::renderer::{GpuRenderer, Kernel, Timings};
use super::tile::TileRenderer;
use crate::film::Film;
use crate::options::{RenderOptions, SamplerKind};
use crate::scene::flat::FlatScene;
use crate::shared::layout::GpuParams;
use std::sync::Arc;

pub struct LiveRender {
    renderer: GpuRenderer,
    kernel: Arc<Kernel>,
    tile: TileRenderer,
    /// The parameters the plan set for this scene (loop budget and costs), kept across cameras.
    params: GpuParams,
    max_slice: u32,
    /// Samples every pixel was asked for (a BVH kernel may have left some short: see
    /// `complete`).
    spp: u32,
}

impl LiveRender {
    /// An empty render of `scene` with `kernel` (compiled for it and `opts`); `opts.spp` is
    /// ignored: samples come with `add_samples`.
    pub fn new(
        renderer: &GpuRenderer,
        kernel: Arc<Kernel>,
        scene: &FlatScene,
        opts: &RenderOptions,
    ) -> Result<Self, GpuError> {
        let opts = RenderOptions {
            first_sample: 0,
            spp: 0,
            ..*opts
        };
        renderer.check_kernel(&kernel, scene, &opts)?;
        let pixels = opts.width as u64 * opts.height as u64;
        let most = renderer.max_tile_pixels();
        if pixels > most {
            return Err(GpuError::TooLarge(format!(
                "a {}x{} film does not fit one GPU storage binding ({most} pixels): make the window smaller",
                opts.width, opts.height
            )));
        }
        let plan = renderer.plan_dispatches(&kernel, scene, &opts, &Tuning::default())?;
        let buffers = renderer.scene_buffers(scene, &kernel.features)?;
        let tile = TileRenderer::new(
            renderer,
            &kernel,
            &opts,
            &plan.params,
            &buffers,
            opts.height,
        );
        tile.warm_up()?;
        tile.clear(opts.height);
        Ok(LiveRender {
            renderer: renderer.clone(),
            kernel,
            tile,
            params: plan.params,
            max_slice: plan.sizer.max_slice(),
            spp: 0,
        })
    }

    /// Starts again from no samples with `scene`'s camera: `scene` is the scene this render was
    /// made for, the camera moved (in the same recentring cell: the kernel is checked).
    pub fn restart(&mut self, scene: &FlatScene) -> Result<(), GpuError> {
        let opts = self.tile.opts;
        self.renderer.check_kernel(&self.kernel, scene, &opts)?;
        let params = GpuParams {
            sample_loop_cost: self.params.sample_loop_cost,
            traversal_weight: self.params.traversal_weight,
            loop_budget: self.params.loop_budget,
            ..base_params(scene, &opts)
        };
        self.tile.write_params(&params);
        self.params = params;
        self.tile.clear(opts.height);
        self.spp = 0;
        Ok(())
    }

    /// Adds up to `count` samples to every pixel (at most what one dispatch may take), in one
    /// dispatch over the whole image; returns the samples added and the dispatch's seconds.
    pub fn add_samples(&mut self, count: u32) -> Result<(u32, f64), GpuError> {
        let count = count.clamp(1, self.max_slice).min(u32::MAX - self.spp);
        let (seconds, _) = self
            .tile
            .dispatch(0, self.tile.opts.height, self.spp, count)?;
        self.spp += count;
        Ok((count, seconds))
    }

    /// Samples per pixel asked for so far.
    pub fn spp(&self) -> u32 {
        self.spp
    }

    pub fn width(&self) -> u32 {
        self.tile.opts.width
    }

    pub fn height(&self) -> u32 {
        self.tile.opts.height
    }

    /// The accumulator the display pass reads (the kernel's layout, `ACCUM_WORDS` per pixel).
    pub fn accumulator(&self) -> &wgpu::Buffer {
        &self.tile.accum
    }

    /// Brings every pixel to `spp()` samples: a dispatch can leave a pixel short (see
    /// `TileRenderer::finish_into`), and the next one continues it.
    pub fn complete(&mut self) -> Result<(), GpuError> {
        if self.spp == 0 {
            return Ok(()); // nothing to complete, nor to read back (the viewer asks every frame)
        }
        self.tile.opts.spp = self.spp;
        self.tile
            .finish_counts(self.tile.opts.height, self.max_slice)
    }

    /// The film of samples `0..spp()`, every pixel brought to them (see `complete`).
    pub fn film(&mut self) -> Result<Film, GpuError> {
        let opts = self.tile.opts;
        let mut film = Film::new(opts.width, opts.height);
        film.stratified = opts.sampler == SamplerKind::Sobol;
        if self.spp > 0 {
            self.tile.opts.spp = self.spp;
            let rows = self.tile.opts.height;
            self.tile
                .finish_into(&mut film, 0, rows, self.max_slice, &mut Timings::default())?;
        }
        Ok(film)
    }
}
