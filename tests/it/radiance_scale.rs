//! The film sums every finite sample exactly (src/shared/exact_sum.rs), whatever the scene's radiance
//! scale: the Cornell box with its light scaled from 1e-12 to 1e30 renders the shipped image
//! times that scale on both backends, and its films resume and merge bit-identically.
//!
//! Image comparisons use the equivalence test of tests/it/common/stats.rs (family-wise alpha 0.01,
//! Sidak-corrected over every pixel, block and channel of one comparison; each scale and backend
//! is its own comparison, as in tests/it/stability.rs). The negative control: the light 2% dimmer
//! at a scale of 1e-12 is detected.
#![cfg_attr(not(feature = "gpu"), allow(unused))]

use crate::common;

#[cfg(feature = "gpu")]
use common::gpu::{render_gpu, renderer};
use common::stats::compare_scaled;
use common::{nee_opts, render_cpu};
use rt_gpu::assets::texture::Texture;
use rt_gpu::film::Film;
#[cfg(feature = "gpu")]
use rt_gpu::gpu::{GpuRenderer, Tuning};
#[cfg(feature = "gpu")]
use rt_gpu::render::RenderOptions;
use rt_gpu::scene::builtin::builtin;
use rt_gpu::scene::{Material, Scene};

/// The Cornell box with its light's radiance times `scale`.
fn cornell_lit(scale: f32) -> Scene {
    let mut scene = builtin("cornell").expect("built-in");
    for m in &mut scene.materials {
        if let Material::Light(light) = m {
            let Texture::Colour(c) = light.radiance else {
                panic!("the Cornell box's light is a colour");
            };
            light.radiance = Texture::Colour(c * scale);
        }
    }
    scene
}

fn finite(name: &str, film: &Film) {
    assert_eq!(film.invalid_samples, 0, "{name}: invalid samples");
    assert!(
        film.pixels
            .iter()
            .all(|p| p.mean().is_finite() && p.mean().min_element() >= 0.0),
        "{name}: a pixel is not finite and non-negative"
    );
}

#[cfg(feature = "gpu")]
fn render(backend: &str, gpu: Option<&GpuRenderer>, scene: &Scene, opts: &RenderOptions) -> Film {
    match (backend, gpu) {
        ("gpu", Some(g)) => render_gpu(g, scene, opts, &Tuning::default()),
        _ => render_cpu(scene, opts),
    }
}

#[cfg(feature = "gpu")]
#[test]
fn the_cornell_box_renders_alike_at_any_radiance_scale() {
    let gpu = renderer();
    let opts = nee_opts(32, 32, 1024, 5, 1);
    let reference = render_cpu(&cornell_lit(1.0), &opts);
    let backends: &[&str] = if gpu.is_some() {
        &["cpu", "gpu"]
    } else {
        &["cpu"]
    };
    for scale in [1e-12f32, 1e-6, 1e6, 1e12, 1e30] {
        let scene = cornell_lit(scale);
        for (i, &backend) in backends.iter().enumerate() {
            let other = RenderOptions {
                seed: 2 + i as u32,
                ..opts
            };
            let film = render(backend, gpu.as_ref(), &scene, &other);
            let name = format!("light x {scale:e} ({backend})");
            finite(&name, &film);
            let verdict = compare_scaled(&reference, scale as f64, &film);
            eprintln!("{name} vs the shipped image x {scale:e}: {verdict:?}");
            assert!(verdict.passed(), "{name}: {verdict:?}");
        }
    }
    // Negative control: 2% less light at 1e-12 is seen.
    let dimmer = render_cpu(&cornell_lit(0.98e-12), &RenderOptions { seed: 9, ..opts });
    let verdict = compare_scaled(&reference, 1e-12, &dimmer);
    eprintln!("control: light x 0.98e-12 vs the shipped image x 1e-12: {verdict:?}");
    assert!(!verdict.passed(), "a 2% dimmer light went unnoticed");
}

#[cfg(feature = "gpu")]
/// Renders of samples 0..5 and 5..13 (a resumed render, or two shards) merge into exactly the
/// sums of one render of 0..13, at every scale and on both backends, also through film files.
#[test]
fn films_of_any_radiance_scale_resume_and_merge_bit_identically() {
    let gpu = renderer();
    let backends: &[&str] = if gpu.is_some() {
        &["cpu", "gpu"]
    } else {
        &["cpu"]
    };
    let whole = nee_opts(12, 8, 13, 10, 4);
    let dir = tempfile::tempdir().expect("tempdir");
    for scale in [1e-12f32, 1e-6, 1e6, 1e12, 1e30] {
        let scene = cornell_lit(scale);
        for &backend in backends {
            let all = render(backend, gpu.as_ref(), &scene, &whole);
            let first = RenderOptions { spp: 5, ..whole };
            let rest = RenderOptions {
                spp: 8,
                first_sample: 5,
                ..whole
            };
            let mut merged = render(backend, gpu.as_ref(), &scene, &first);
            // The first part goes through a film file, as a checkpoint does.
            let meta = rt_gpu::film::file::FilmMeta {
                identity: "scene=0 size=12x8".to_string(),
                samples: std::iter::once(0..5).collect(),
                device: backend.to_string(),
            };
            let path = dir.path().join("part.exr");
            std::fs::write(
                &path,
                rt_gpu::film::file::encode(&merged, Some(&meta)).expect("encodes"),
            )
            .expect("writes");
            let (read, _) = rt_gpu::film::file::read(&path).expect("reads");
            assert_eq!(
                read.pixels, merged.pixels,
                "{backend} x {scale:e}: film file"
            );
            merged = read;
            merged.merge(&render(backend, gpu.as_ref(), &scene, &rest));
            for (a, b) in all.pixels.iter().zip(&merged.pixels) {
                assert_eq!(
                    (a.n, a.sum, a.odd_n, a.odd_sum),
                    (b.n, b.sum, b.odd_n, b.odd_sum),
                    "{backend} x {scale:e}"
                );
                assert_eq!(a.mean(), b.mean());
            }
            assert_eq!(all.mean_rgb(), merged.mean_rgb());
        }
    }
}

#[cfg(feature = "gpu")]
/// An environment whose one sun texel is 1e30 (and a light image as bright) loads and lights
/// the scene on both backends: before the film summed every finite sample, such a texel
/// blacked the image out.
#[test]
fn a_sun_of_1e30_lights_the_scene() {
    let gpu = renderer();
    let dir = tempfile::tempdir().expect("tempdir");
    let (w, h) = (16u32, 8u32);
    let mut texels = vec![0.25f32; (w * h * 3) as usize];
    let sun = ((2 * w + 5) * 3) as usize; // row 2: high in the sky
    texels[sun..sun + 3].copy_from_slice(&[1e30, 1e30, 1e30]);
    let sky = image::Rgb32FImage::from_raw(w, h, texels).expect("image");
    sky.save(dir.path().join("sun.exr"))
        .expect("writes the sky");
    let text = r#"
[render]
background = { image = "sun.exr", strength = 1.0 }

[camera]
look_from = [0, 1, 4]
look_at = [0, 0.5, 0]
vfov = 40

[materials]
white = { type = "lambertian", albedo = [0.7, 0.7, 0.7] }

[[object]]
quad = { q = [-4, 0, 4], u = [8, 0, 0], v = [0, 0, -8] }
material = "white"

[[object]]
sphere = { center = [0, 0.5, 0], radius = 0.5 }
material = "white"
"#;
    let path = dir.path().join("sun.toml");
    std::fs::write(&path, text).expect("writes the scene");
    let scene = rt_gpu::scene::file::load(&path).expect("loads");
    let opts = nee_opts(12, 8, 256, 4, 1);
    let backends: &[&str] = if gpu.is_some() {
        &["cpu", "gpu"]
    } else {
        &["cpu"]
    };
    let mut films = Vec::new();
    for (i, &backend) in backends.iter().enumerate() {
        let seeded = RenderOptions {
            seed: 1 + i as u32,
            ..opts
        };
        let film = render(backend, gpu.as_ref(), &scene, &seeded);
        finite(&format!("sun of 1e30 ({backend})"), &film);
        let mean = film.image_mean();
        eprintln!("sun of 1e30 ({backend}): image mean {mean:?}");
        // Lit floor pixels carry the sun's light: far above anything the dim sky gives.
        assert!(mean.min_element() > 1e20, "{backend}: image mean {mean:?}");
        films.push(film);
    }
    // Their spreads agree too: a pixel whose first samples saw only the sky and later ones
    // the sun keeps its variance on the GPU (its M2's scale rises with the samples).
    if let [cpu, gpu] = &films[..] {
        let verdict = common::stats::compare(cpu, gpu);
        eprintln!("sun of 1e30, cpu vs gpu: {verdict:?}");
        assert!(verdict.passed(), "{verdict:?}");
    }
}

/// Emitters in vertical stripes, `per_pixel` to a pixel of a `width` x 8 image, of the
/// `radiances` in turn (a stripe of `None` is black), seen directly.
#[cfg(feature = "gpu")]
fn stripes(width: u32, per_pixel: u32, radiances: &[Option<&str>]) -> Scene {
    let mut text = format!(
        "[render]\nwidth = {width}\nheight = 8\nmax_depth = 1\nbackground = [0, 0, 0]\n\
         [camera]\nlook_from = [0, 0, -10]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\n\
         vfov = 11.42\n[materials]\nblack = {{ type = \"lambertian\", albedo = [0, 0, 0] }}\n"
    );
    for (i, r) in radiances.iter().enumerate() {
        if let Some(r) = r {
            text += &format!("light{i} = {{ type = \"light\", radiance = {r} }}\n");
        }
    }
    // The view is 2 units high, so a pixel is 0.25 wide; the stripes overhang both sides.
    let stripe = 0.25 / per_pixel as f32;
    let count = (width + 2) * per_pixel;
    for k in 0..count {
        let i = k as usize % radiances.len();
        let material = match radiances[i] {
            Some(_) => format!("light{i}"),
            None => "black".to_string(),
        };
        let x = -(width as f32 + 2.0) * 0.125 + k as f32 * stripe;
        text += &format!(
            "[[object]]\nquad = {{ q = [{x}, -1.5, 0], u = [0, 3, 0], v = [{stripe}, 0, 0] }}\n\
             material = \"{material}\"\n"
        );
    }
    rt_gpu::scene::file::parse(&text, "stripes.toml", "stripes").expect("parses")
}

#[cfg(feature = "gpu")]
/// The kernel's exact sums do not depend on how many samples one dispatch takes: a dispatch of
/// one sample adds each to the sum on its own, longer ones gather them in windows first
/// (film.wgsl). Each pixel's samples come from stripes between 1e-30 and 1e30, so windows both
/// carry between their words and meet samples that fit none; in the second scene a pixel's
/// samples are 1e-12 and 3.99 (2^-40 and the top bit of a word), 2048 to a dispatch, so a window's
/// fourth word overflows into its fifth. Both samplers (the independent one keeps no odd sums).
#[test]
fn the_kernels_sums_are_exact_whatever_the_samples_per_dispatch() {
    let Some(gpu) = renderer() else { return };
    let wide_range = stripes(
        16,
        3,
        &[
            Some("[1e-30, 1, 3e9]"),
            Some("[1, 3e9, 1e20]"),
            Some("[3e9, 1e20, 1e30]"),
            Some("[1e20, 1e30, 1e-30]"),
            Some("[1e30, 1e-30, 1e-10]"),
            Some("[1e-10, 0.3, 1]"),
            None,
        ],
    );
    let top_bits = stripes(
        4,
        2,
        &[Some("[1e-12, 1e-12, 1e-12]"), Some("[3.99, 3.99, 3.99]")],
    );
    for (name, scene, spp) in [
        ("wide range", wide_range, 512),
        ("top bits", top_bits, 2048),
    ] {
        for sampler in [
            rt_gpu::options::SamplerKind::Sobol,
            rt_gpu::options::SamplerKind::Independent,
        ] {
            let width = scene.defaults.width;
            let opts = RenderOptions {
                sampler,
                ..nee_opts(width, 8, spp, 1, 3)
            };
            let tuning = |samples_per_dispatch| Tuning {
                samples_per_dispatch,
                ..Tuning::default()
            };
            let single = render_gpu(&gpu, &scene, &opts, &tuning(Some(1)));
            finite(name, &single);
            for per_dispatch in [None, Some(5), Some(spp)] {
                let film = render_gpu(&gpu, &scene, &opts, &tuning(per_dispatch));
                for (i, (a, b)) in single.pixels.iter().zip(&film.pixels).enumerate() {
                    assert_eq!(
                        (a.n, a.sum, a.odd_n, a.odd_sum),
                        (b.n, b.sum, b.odd_n, b.odd_sum),
                        "{name}, {sampler:?}, {per_dispatch:?} samples a dispatch: pixel {i}"
                    );
                }
            }
            // The CPU's film of the same samples has the same sums, but for the odd ray that a
            // last bit sends across a stripe's edge on one backend only.
            let cpu = render_cpu(&scene, &opts);
            let same = cpu
                .pixels
                .iter()
                .zip(&single.pixels)
                .filter(|(a, b)| (a.sum, a.odd_sum) == (b.sum, b.odd_sum))
                .count();
            let all = cpu.pixels.len();
            eprintln!("{name}, {sampler:?}: {same} of {all} pixels sum as the CPU's to the bit");
            assert!(
                4 * same >= 3 * all,
                "{name}, {sampler:?}: {same} of {all} as the CPU's"
            );
        }
    }
}
