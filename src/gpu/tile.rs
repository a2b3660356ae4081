//! One render's buffers and bind group on the device, and the dispatches over a tile of image
//! rows: its samples in slices, the pixels a BVH kernel left short, and the tile read into the
//! film. Batch renders (`renderer.rs`) use one per render; a live render (`live.rs`) keeps one
//! over the whole image.

use super::context::GpuError;
use super::dispatch::DispatchSizer;
use super::layout::whole_image_dispatch;
use super::renderer::{GpuRenderer, Kernel, SceneBindings, Timings};
use crate::film::{Film, PixelStats};
use crate::options::RenderOptions;
use crate::shared::exact_sum::{ExactSum, SUM_WORDS};
use crate::shared::layout::{
    ACCUM_BYTES_PER_PIXEL, ACCUM_COUNT, ACCUM_EVEN_SUM, ACCUM_INVALID, ACCUM_M2, ACCUM_M2_EXPONENT,
    ACCUM_ODD_SUM, ACCUM_WORDS, GpuDispatch, GpuParams, WORKGROUP_SIZE,
};
use glam::DVec3;
use rayon::prelude::*;
use std::io::Write;
use std::time::Instant;

/// One render's buffers and bind group, and the dispatches over a tile of image rows: its
/// samples in slices, the pixels a BVH kernel left short, and the tile read into the film.
pub(super) struct TileRenderer {
    renderer: GpuRenderer,
    pipeline: wgpu::ComputePipeline,
    /// The kernel keeps the odd samples' sum (stratified samplers).
    sobol: bool,
    pub(super) opts: RenderOptions,
    params_buffer: wgpu::Buffer,
    dispatch_buffer: wgpu::Buffer,
    pub(super) accum: wgpu::Buffer,
    /// Where the accumulator is copied to be read (as large as it): made once, not at every
    /// read (a mappable buffer of the whole image's sums each time).
    staging: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    pub(super) timer: Option<DispatchTimer>,
    trace: bool,
}

impl TileRenderer {
    pub(super) fn new(
        renderer: &GpuRenderer,
        kernel: &Kernel,
        opts: &RenderOptions,
        params: &GpuParams,
        scene_buffers: &SceneBindings,
        tile_rows: u32,
    ) -> Self {
        // Per-render params are uniform (lavapipe folds them into the kernel: one variant per
        // render); what changes every dispatch is in storage (folded, each new value compiled
        // and kept a variant).
        let params_buffer = renderer.buffer_with(
            "params",
            bytemuck::bytes_of(params),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let dispatch_buffer = renderer.buffer(
            "dispatch",
            std::mem::size_of::<GpuDispatch>() as u64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        let debug = renderer.buffer("unused", 16, wgpu::BufferUsages::STORAGE);
        let accum_size = tile_rows as u64 * opts.width as u64 * ACCUM_BYTES_PER_PIXEL;
        let accum = renderer.buffer(
            "accumulator",
            accum_size,
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
        );
        let staging = renderer.buffer(
            "accumulator read-back",
            accum_size,
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        );
        let bind_group = renderer.bind_group(
            kernel,
            [&params_buffer, &dispatch_buffer],
            scene_buffers,
            &accum,
            &debug,
        );
        TileRenderer {
            renderer: renderer.clone(),
            pipeline: kernel.pipeline.clone(),
            sobol: kernel.features.sobol,
            opts: *opts,
            params_buffer,
            dispatch_buffer,
            accum,
            staging,
            bind_group,
            timer: renderer
                .ctx
                .timestamps
                .then(|| DispatchTimer::new(renderer)),
            trace: std::env::var_os("RT_GPU_TRACE").is_some(),
        }
    }

    /// Drivers such as lavapipe compile a pipeline at its first dispatch: one empty dispatch
    /// (zero samples) first, so that compilation is not timed as, or inside, a slice.
    pub(super) fn warm_up(&self) -> Result<(), GpuError> {
        let ctx = &self.renderer.ctx;
        let mut dispatch = whole_image_dispatch(&self.opts);
        dispatch.tile_size = [self.opts.width, 1];
        ctx.queue
            .write_buffer(&self.dispatch_buffer, 0, bytemuck::bytes_of(&dispatch));
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            pass.dispatch_workgroups(self.opts.width.div_ceil(WORKGROUP_SIZE), 1, 1);
        }
        ctx.queue.submit([encoder.finish()]);
        ctx.wait()
    }

    /// Replaces the render's parameters (a live render's new camera); the accumulator is the
    /// caller's to clear.
    pub(super) fn write_params(&self, params: &GpuParams) {
        let ctx = &self.renderer.ctx;
        ctx.queue
            .write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(params));
    }

    /// Empties the accumulator of the next tile's `rows` rows (the buffer holds the tallest
    /// tile: lavapipe clears with the CPU, and a whole buffer for each short tile cost seconds).
    pub(super) fn clear(&self, rows: u32) {
        let ctx = &self.renderer.ctx;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&self.accum, 0, Some(self.tile_bytes(rows)));
        ctx.queue.submit([encoder.finish()]);
    }

    /// The tile's `opts.spp` samples per pixel in slices sized by `sizer` from each dispatch's
    /// measured time; returns their GPU seconds.
    pub(super) fn sample(
        &self,
        y0: u32,
        rows: u32,
        sizer: &mut DispatchSizer,
        timings: &mut Timings,
        on_progress: &dyn Fn(f64),
    ) -> Result<f64, GpuError> {
        let (opts, width) = (&self.opts, self.opts.width);
        let tile_pixels = rows as u64 * width as u64;
        let mut slice = sizer.first_slice();
        let mut gpu_seconds = 0.0;
        let mut done = 0;
        while done < opts.spp {
            let count = slice.min(opts.spp - done);
            let (seconds, gpu) = self.dispatch(y0, rows, done, count)?;
            gpu_seconds += gpu;
            timings.dispatches += 1;
            timings.longest_dispatch_seconds = timings.longest_dispatch_seconds.max(seconds);
            done += count;
            on_progress(
                (y0 as f64 + rows as f64 * done as f64 / opts.spp as f64) / opts.height as f64,
            );
            if self.trace {
                // RT_GPU_TRACE=1: one line per dispatch, for tuning the sizing.
                let _ = writeln!(
                    std::io::stderr().lock(),
                    "tile y0 {y0} rows {rows} count {count} seconds {seconds:.4}"
                );
            }
            slice = sizer.record(count, tile_pixels, seconds);
        }
        Ok(gpu_seconds)
    }

    /// Reads the tile's pixels into `film` from row `y0`. A dispatch can leave a pixel short of
    /// its samples: a BVH kernel's when its traversals near the loop budget, any kernel's after
    /// a sample that fits none of its summing windows (shaders/film.wgsl). Each dispatch gives
    /// every pixel at least one sample; this dispatches again, at most `max_slice` samples a
    /// pixel each time, until every pixel of the tile has them all, reading the tile each time
    /// (its sample counts are read as its sums are converted: one pass over it). Returns the
    /// GPU seconds of those dispatches; `timings.host_seconds` gains the reads'.
    pub(super) fn finish_into(
        &self,
        film: &mut Film,
        y0: u32,
        rows: u32,
        max_slice: u32,
        timings: &mut Timings,
    ) -> Result<f64, GpuError> {
        self.finish(y0, rows, max_slice, timings, |bytes| {
            self.read_into(film, y0, bytes)
        })
    }

    /// [`Self::finish_into`] without a film: only the tile's sample counts are read.
    pub(super) fn finish_counts(&self, rows: u32, max_slice: u32) -> Result<(), GpuError> {
        let spp = self.opts.spp;
        let short = |bytes: &[u8]| {
            let words: &[u32] = bytemuck::cast_slice(bytes);
            let counts = words.par_chunks_exact(ACCUM_WORDS as usize);
            counts.filter(|px| px[ACCUM_COUNT as usize] != spp).count() as u64
        };
        self.finish(0, rows, max_slice, &mut Timings::default(), short)
            .map(|_| ())
    }

    /// Reads the tile with `read` (which returns how many pixels are short) and dispatches
    /// again until none is; see [`Self::finish_into`].
    fn finish(
        &self,
        y0: u32,
        rows: u32,
        max_slice: u32,
        timings: &mut Timings,
        mut read: impl FnMut(&[u8]) -> u64,
    ) -> Result<f64, GpuError> {
        let spp = self.opts.spp;
        let mut gpu_seconds = 0.0;
        let mut short = 0;
        for attempt in 0..=spp {
            let start = Instant::now();
            short = self.with_tile(rows, &mut read)?;
            timings.host_seconds += start.elapsed().as_secs_f64();
            if short == 0 || attempt == spp {
                break;
            }
            if self.trace {
                let _ = writeln!(
                    std::io::stderr().lock(),
                    "tile y0 {y0}: {short} pixels short of {spp} samples, dispatching again"
                );
            }
            let slice = max_slice.clamp(1, spp);
            let (seconds, gpu) = self.dispatch(y0, rows, spp - slice, slice)?;
            gpu_seconds += gpu;
            timings.dispatches += 1;
            timings.longest_dispatch_seconds = timings.longest_dispatch_seconds.max(seconds);
        }
        if short > 0 {
            return Err(GpuError::Runtime(format!(
                "the device ended the kernel early: {short} pixel{} of the tile at row {y0} did not get their {spp} samples",
                if short == 1 { "" } else { "s" }
            )));
        }
        Ok(gpu_seconds)
    }

    /// One dispatch over the tile's `rows` rows from `y0`, until each pixel holds
    /// `samples_before + count` samples; its seconds (GPU time where known, else wall time) and
    /// its GPU seconds.
    pub(super) fn dispatch(
        &self,
        y0: u32,
        rows: u32,
        samples_before: u32,
        count: u32,
    ) -> Result<(f64, f64), GpuError> {
        let ctx = &self.renderer.ctx;
        let width = self.opts.width;
        // Each pixel takes samples first_sample + (its count so far) onward, so a pixel the
        // kernel left short (see shaders/accel.wgsl) continues where it stopped.
        let dispatch = GpuDispatch {
            tile_origin: [0, y0],
            tile_size: [width, rows],
            first_sample: self.opts.first_sample,
            samples_before,
            sample_count: count,
            ..whole_image_dispatch(&self.opts)
        };
        ctx.queue
            .write_buffer(&self.dispatch_buffer, 0, bytemuck::bytes_of(&dispatch));
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("render"),
                timestamp_writes: self.timer.as_ref().map(|t| t.writes()),
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            pass.dispatch_workgroups(
                width.div_ceil(WORKGROUP_SIZE),
                rows.div_ceil(WORKGROUP_SIZE),
                1,
            );
        }
        if let Some(t) = &self.timer {
            t.resolve(&mut encoder);
        }
        let start = Instant::now();
        ctx.queue.submit([encoder.finish()]);
        ctx.wait()?;
        let wall = start.elapsed().as_secs_f64();
        let gpu = match &self.timer {
            Some(t) => t.read(&self.renderer)?,
            None => 0.0,
        };
        Ok((if gpu > 0.0 { gpu } else { wall }, gpu))
    }

    /// Bytes of the accumulator of `rows` rows.
    fn tile_bytes(&self, rows: u32) -> u64 {
        rows as u64 * self.opts.width as u64 * ACCUM_BYTES_PER_PIXEL
    }

    /// Copies the accumulator of the tile's `rows` rows to the staging buffer and hands it to
    /// `f` as bytes where it is mapped.
    fn with_tile<R>(&self, rows: u32, f: impl FnOnce(&[u8]) -> R) -> Result<R, GpuError> {
        let ctx = &self.renderer.ctx;
        let size = self.tile_bytes(rows);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&self.accum, 0, &self.staging, 0, size);
        ctx.queue.submit([encoder.finish()]);
        ctx.with_mapped(&self.staging, size, "GPU memory", f)
    }

    /// Puts the tile's pixels, `bytes` as `with_tile` gives them, into `film` from row `y0`,
    /// on all cores (a million pixels' exact sums are a fraction of a second on one). Returns
    /// how many pixels are short of `opts.spp` samples; their statistics are then partial, and
    /// the film's count of invalid samples is left as it was.
    fn read_into(&self, film: &mut Film, y0: u32, bytes: &[u8]) -> u64 {
        let opts = &self.opts;
        let words: &[u32] = bytemuck::cast_slice(bytes);
        // The kernel keeps the odd samples' sum only for stratified renders.
        let odd_n = if self.sobol {
            (opts.first_sample as u64 + opts.spp as u64) / 2 - opts.first_sample as u64 / 2
        } else {
            0
        };
        let first = y0 as usize * opts.width as usize;
        let pixels = &mut film.pixels[first..first + words.len() / ACCUM_WORDS as usize];
        let (short, invalid) = pixels
            .par_iter_mut()
            .zip(words.par_chunks_exact(ACCUM_WORDS as usize))
            .map(|(pixel, px)| {
                *pixel = pixel_stats(px, opts.spp, odd_n);
                let short = (px[ACCUM_COUNT as usize] != opts.spp) as u64;
                (short, px[ACCUM_INVALID as usize] as u64)
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        if short == 0 {
            film.invalid_samples += invalid;
        }
        short
    }
}

/// A pixel's statistics from its accumulator words.
fn pixel_stats(px: &[u32], spp: u32, odd_n: u64) -> PixelStats {
    let f = |w: u32| f32::from_bits(w) as f64;
    let even_sum = fixed_sums(&px[ACCUM_EVEN_SUM as usize..]);
    let odd_sum = fixed_sums(&px[ACCUM_ODD_SUM as usize..]);
    PixelStats {
        n: spp as u64,
        sum: std::array::from_fn(|c| even_sum[c].plus(&odd_sum[c])),
        // The kernel's M2 is f32 of samples scaled by 1 / scale: a spread too wide even for
        // that reads as the largest f32, not as an infinity.
        m2: DVec3::from_array(std::array::from_fn(|c| {
            let m2 = f(px[ACCUM_M2 as usize + c]);
            let m2 = if m2.is_finite() {
                m2.max(0.0)
            } else {
                f32::MAX as f64
            };
            let exponent = (px[ACCUM_M2_EXPONENT as usize] >> (8 * c)) & 0xff;
            let scale = m2_scale(exponent);
            m2 * scale * scale
        })),
        odd_n,
        odd_sum,
    }
}

/// Timestamp queries around one compute pass.
pub(super) struct DispatchTimer {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    period_ns: f64,
}

impl DispatchTimer {
    fn new(r: &GpuRenderer) -> Self {
        DispatchTimer {
            queries: r.ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("dispatch time"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            }),
            resolved: r.buffer(
                "timestamps",
                16,
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            period_ns: r.ctx.queue.get_timestamp_period() as f64,
        }
    }

    fn writes(&self) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: Some(1),
        }
    }

    fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.queries, 0..2, &self.resolved, 0);
    }

    fn read(&self, r: &GpuRenderer) -> Result<f64, GpuError> {
        let bytes = r.read_back(&self.resolved, 16)?;
        let stamps: &[u64] = bytemuck::cast_slice(&bytes);
        Ok(stamps[1].saturating_sub(stamps[0]) as f64 * self.period_ns * 1e-9)
    }
}

/// What the kernel divided a pixel channel's samples by for its mean and M2: the power of two of
/// the exponent bits `exponent` it keeps (1 before there is one). Twin of `inverse_m2_scale` in
/// shaders/kernel.wgsl.
fn m2_scale(exponent: u32) -> f64 {
    match exponent {
        0 => 1.0,
        // 2^(e - 127), built from its exponent bits (the same value powi gives, without the
        // multiplications: this runs three times a pixel on every read-back).
        e => f64::from_bits(((e.clamp(1, 253) as i64 - 127 + 1023) as u64) << 52),
    }
}

/// Per channel, an exact sum from its words (word-major: all channels' w0, then w1...).
fn fixed_sums(words: &[u32]) -> [ExactSum; 3] {
    // As an array, so that the words are gathered without a bounds check each.
    let Some(words) = words.first_chunk::<{ 3 * SUM_WORDS }>() else {
        return [ExactSum::ZERO; 3];
    };
    std::array::from_fn(|c| ExactSum::from_word_array(&std::array::from_fn(|w| words[3 * w + c])))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scale built from exponent bits is powi's, for every exponent the kernel may write.
    #[test]
    fn m2_scales_are_powers_of_two() {
        for e in 0..=255u32 {
            let expected = if e == 0 {
                1.0
            } else {
                2f64.powi(e.clamp(1, 253) as i32 - 127)
            };
            assert_eq!(m2_scale(e).to_bits(), expected.to_bits(), "{e}");
        }
    }

    /// The sums gathered from an array are those `ExactSum::from_words` reads.
    #[test]
    fn fixed_sums_read_the_words_channel_by_channel() {
        let words: Vec<u32> = (0..3 * SUM_WORDS as u32)
            .map(|i| i.wrapping_mul(0x9e37_79b9).rotate_left(i))
            .collect();
        let sums = fixed_sums(&words);
        for (c, sum) in sums.iter().enumerate() {
            let expected = ExactSum::from_words((0..SUM_WORDS).map(|w| words[3 * w + c]));
            assert_eq!(*sum, expected, "channel {c}");
        }
    }
}
