//! The viewer's film and display pass, without a window: a render kept on the device gives the
//! batch render's film bit for bit, and the display pass draws the bytes the PNG encoder writes,
//! for kernel films, uploaded CPU films and sums placed exactly on the levels' thresholds.
#![cfg(feature = "gpu")]

use crate::common;

use common::gpu::renderer;
use rt_gpu::film::output::Transfer;
use rt_gpu::film::{Film, PixelStats};
use rt_gpu::gpu::display::{DisplayPass, accumulator_words, read_texture};
use rt_gpu::gpu::{GpuBackend, GpuContext};
use rt_gpu::options::SamplerKind;
use rt_gpu::render::{GpuChoice, Integrator, RenderBackend, RenderOptions};
use rt_gpu::scene::builtin::builtin;
use rt_gpu::scene::flat::FlatScene;
use rt_gpu::shared::exact_sum::ExactSum;
use wgpu::util::DeviceExt;

fn options(width: u32, height: u32, spp: u32) -> RenderOptions {
    RenderOptions {
        integrator: Integrator::Nee,
        sampler: SamplerKind::Sobol,
        roulette_depth: 3,
        ..RenderOptions::new(width, height, spp, 6)
    }
}

/// What the display pass draws of `accumulator` (a `width` x `height` film) into an 8-bit
/// image of the same size, as RGB bytes.
fn displayed(ctx: &GpuContext, accumulator: &wgpu::Buffer, width: u32, height: u32) -> Vec<u8> {
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let pass = DisplayPass::new(ctx, format, &Transfer::Srgb.levels()).expect("display pass");
    pass.set_film(ctx, width, height, 1);
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("window"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = texture.create_view(&Default::default());
    let group = pass.bind(ctx, accumulator);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    pass.draw(&mut encoder, &view, &group);
    ctx.queue.submit([encoder.finish()]);
    read_texture(ctx, &texture).expect("screenshot")
}

/// The PNG encoder's bytes of `film` (the same levels it writes).
fn encoded(film: &Film) -> Vec<u8> {
    let levels = Transfer::Srgb.levels();
    film.pixels.iter().flat_map(|p| levels.pixel(p)).collect()
}

/// The exact sum of `n` samples of `value` (by doubling).
fn times(value: f32, n: u64) -> ExactSum {
    let mut power = ExactSum::default();
    power.add_f32(value);
    let mut sum = ExactSum::default();
    let mut n = n;
    while n > 0 {
        if n & 1 == 1 {
            sum = sum.plus(&power);
        }
        power = power.plus(&power);
        n >>= 1;
    }
    sum
}

fn uploaded(ctx: &GpuContext, film: &Film) -> wgpu::Buffer {
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("film"),
            contents: bytemuck::cast_slice(&accumulator_words(film)),
            usage: wgpu::BufferUsages::STORAGE,
        })
}

/// A live render's samples added 1 + 2 + 5 at a time, and after a restart again, are the batch
/// render's film bit for bit, and the display pass shows exactly its PNG bytes: on the Cornell
/// box (held inlined) and on a scene of many spheres traced through a BVH (where lavapipe leaves pixels
/// short, and `complete` finishes them).
#[test]
fn a_live_render_is_the_batch_render_and_is_displayed_as_its_png() {
    let Some(_) = renderer() else { return };
    for (name, size) in [("cornell", (40, 30)), ("showcase", (24, 16))] {
        let scene = builtin(name).expect("built-in");
        let opts = options(size.0, size.1, 8);
        let flat = FlatScene::new(&scene, opts.width, opts.height).expect("valid");
        let features = GpuChoice::default().features(&flat, opts.integrator);
        let backend = GpuBackend::new(None, &flat, features, opts.integrator).expect("GPU backend");
        let batch = backend.render(&flat, &opts, &|_| {}).expect("renders").film;
        let mut live = backend.live(&flat, &opts).expect("live render");
        for round in 0..2 {
            if round == 1 {
                live.restart(&flat).expect("restarts");
                assert_eq!(live.spp(), 0);
            }
            // Slices as asked for, or what one dispatch may take if less.
            for count in [1, 2, 5, 5, 5, 5, 5] {
                if live.spp() < 8 {
                    live.add_samples(count.min(8 - live.spp()))
                        .expect("dispatch");
                }
            }
            assert_eq!(live.spp(), 8);
            let film = live.film().expect("reads back");
            assert!(
                film.pixels == batch.pixels,
                "{name}, round {round}: the live film differs from the batch render's"
            );
            let shown = displayed(
                backend.context(),
                live.accumulator(),
                opts.width,
                opts.height,
            );
            assert!(
                shown == encoded(&batch),
                "{name}: the display pass differs from the PNG bytes in {} of {} values",
                shown
                    .iter()
                    .zip(encoded(&batch))
                    .filter(|(a, b)| **a != *b)
                    .count(),
                shown.len()
            );
        }
    }
}

/// Pixels whose exact means sit on a level's threshold, or one smallest step of one sample
/// below it (where a rounded mean would say equal), at counts from 1 to 2^20: the display pass
/// decides every one as the PNG encoder does, on an uploaded film. A negative control: the
/// film with one sample's step removed is displayed differently.
#[test]
fn the_display_pass_decides_levels_on_exact_sums() {
    let Some(r) = renderer() else { return };
    let ctx = &r.ctx;
    let levels = Transfer::Srgb.levels();
    let mut pixels = Vec::new();
    for k in 1..256usize {
        let t = levels.thresholds[k];
        let step_below = f32::from_bits(t.to_bits() - 1);
        for n in [1u64, 3, 1000, 1 << 20] {
            let at = times(t, n);
            // One sample a step lower: the mean is below t by less than any f32 step.
            let below = times(t, n - 1).plus(&times(step_below, 1));
            pixels.push(PixelStats {
                n,
                sum: [at, below, ExactSum::default()],
                ..Default::default()
            });
        }
    }
    let width = 64;
    let height = pixels.len().div_ceil(width) as u32;
    pixels.resize(width * height as usize, PixelStats::default());
    let mut film = Film::new(width as u32, height);
    film.pixels = pixels;
    let expected = encoded(&film);
    let shown = displayed(ctx, &uploaded(ctx, &film), width as u32, height);
    let differ = shown.iter().zip(&expected).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "{differ} of {} values differ", shown.len());
    // Each pixel's red (at the threshold) and green (a step below) differ by one level.
    let levels_of = |c: usize| expected.chunks(3).take(255 * 4).map(move |p| p[c]);
    assert!(levels_of(0).zip(levels_of(1)).all(|(r, g)| r == g + 1));
}
