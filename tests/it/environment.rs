//! Image textures and environment lights: sampling the environment against its pdf
//! (chi-square), the kernel's lookups against the CPU's, a white-environment furnace, naive vs
//! nee and CPU vs GPU images (Welch z + Sidak, tests/it/common/stats.rs, family-wise 0.01), each
//! with a negative control, the syntax, bad image files, and kernels that leave images out.
//! `cargo test --test it environment:: -- --nocapture` prints the figures.
#![cfg_attr(not(feature = "gpu"), allow(unused))]

use crate::common;
use crate::common::chi_square::{self, Domain, Draw};

#[cfg(feature = "gpu")]
use common::gpu::{render_gpu, renderer};
use common::stats::compare;
use glam::{Vec2, Vec3};
use rt_gpu::assets::environment::Environment;
use rt_gpu::assets::image::Image;
use rt_gpu::cpu::environment;
#[cfg(feature = "gpu")]
use rt_gpu::gpu::Tuning;
use rt_gpu::scene::file::{load, parse_with, to_toml};
use rt_gpu::scene::flat::FlatScene;
use rt_gpu::scene::{Background, Material, Scene, Shape};
use std::f32::consts::PI;
use std::path::Path;
use std::sync::Arc;

/// A 16 x 8 environment: a sky brighter toward the top, a darker ground, and a sun texel.
fn sky_image(brighter_left: f32) -> Arc<Image> {
    let (w, h) = (16u32, 8u32);
    let mut texels = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let mut c = if y < h / 2 {
                Vec3::new(0.4, 0.6, 1.0) * (1.0 + (h / 2 - y) as f32 * 0.3)
            } else {
                Vec3::new(0.2, 0.15, 0.1)
            };
            if (x, y) == (5, 2) {
                c = Vec3::new(40.0, 36.0, 30.0);
            }
            if x < w / 2 {
                c *= brighter_left;
            }
            texels.extend(c.to_array());
        }
    }
    Image::from_linear("sky", w, h, texels).unwrap().shared()
}

/// (s, t) image coordinates of a world direction, as the renderer maps them.
fn image_coordinates(env: &Environment, dir: Vec3) -> (f32, f32) {
    let [c, s] = env.rotation;
    let local = Vec3::new(c * dir.x - s * dir.z, dir.y, s * dir.x + c * dir.z);
    (
        ((-local.z).atan2(local.x) + PI) / (2.0 * PI),
        local.y.clamp(-1.0, 1.0).acos() / PI,
    )
}

/// One cell per texel of an environment's image: the pdf integrated over each by a 4 x 4
/// midpoint rule in image coordinates (exact, as the pdf is constant over each quarter of a
/// texel), times the solid angle's sin(theta).
struct Texels<'a>(&'a Environment);

impl Domain for Texels<'_> {
    fn cells(&self) -> usize {
        (self.0.image.width * self.0.image.height) as usize
    }

    fn cell(&self, dir: Vec3) -> Option<usize> {
        let (w, h) = (self.0.image.width as usize, self.0.image.height as usize);
        let (s, t) = image_coordinates(self.0, dir);
        let x = ((s * w as f32) as usize).min(w - 1);
        let y = ((t * h as f32) as usize).min(h - 1);
        Some(y * w + x)
    }

    fn expected(&self, pdf: &dyn Fn(Vec3) -> f64) -> Vec<f64> {
        let env = self.0;
        let (w, h) = (env.image.width as usize, env.image.height as usize);
        let sub = 4;
        let mut expected = vec![0.0f64; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut mass = 0.0;
                for i in 0..sub {
                    for j in 0..sub {
                        let s = (x as f32 + (i as f32 + 0.5) / sub as f32) / w as f32;
                        let t = (y as f32 + (j as f32 + 0.5) / sub as f32) / h as f32;
                        let phi = 2.0 * PI * s - PI;
                        let local = Vec3::new(
                            (PI * t).sin() * phi.cos(),
                            (PI * t).cos(),
                            -(PI * t).sin() * phi.sin(),
                        );
                        let [c, sn] = env.rotation;
                        let dir = Vec3::new(
                            c * local.x + sn * local.z,
                            local.y,
                            -sn * local.x + c * local.z,
                        );
                        mass += pdf(dir) * 2.0 * (PI as f64).powi(2) * (PI * t).sin() as f64;
                    }
                }
                expected[y * w + x] = mass / (sub * sub * w * h) as f64;
            }
        }
        expected
    }
}

/// Chi-square p-value of 1 000 000 directions from `sample` against `environment::pdf` of
/// `env` (`common::chi_square`), over one cell per texel ([`Texels`]); the draws `sample`
/// declines are not counted.
fn chi_square_p(env: &Environment, sample: impl Fn(f32, f32) -> Option<(Vec3, f32)>) -> f64 {
    let texels = Texels(env);
    let expected = texels.expected(&|dir| environment::pdf(env, dir) as f64);
    let total: f64 = expected.iter().sum();
    assert!((total - 1.0).abs() < 2e-3, "the pdf integrates to {total}");
    let samples = 1_000_000u32;
    let tally = chi_square::tally(&texels, samples, |k| {
        let mut rng = rt_gpu::shared::sampler::Sampler::independent(k, 0, 17);
        let (u1, u2) = (rng.next_f32(), rng.next_f32());
        let Some((dir, pdf)) = sample(u1, u2) else {
            return Draw::Skipped;
        };
        assert!((dir.length() - 1.0).abs() < 1e-5 && pdf > 0.0);
        Draw::Direction(dir)
    });
    // Texels the pdf gives nothing (a compensated sky's below its mean: 77 of the test sky's
    // 128) get no directions but a rare one rounded across a texel's edge (none here).
    let stray: f64 = (tally.observed.iter().zip(&expected))
        .filter(|(_, e)| **e == 0.0)
        .map(|(o, _)| o)
        .sum();
    assert!(
        stray <= 1e-4 * samples as f64,
        "{stray} directions where the pdf is 0"
    );
    let (chi2, cells, p) = chi_square::test(&tally, &expected, samples);
    eprintln!("chi2 {chi2:.1} over {cells} cells, p = {p:.3e}");
    p
}

/// Environment sampling follows `environment::pdf`, the density MIS weighs it with (one test
/// at 0.001); and sampling from a sky whose left half is 3% brighter is rejected against the
/// true sky's pdf (negative control, at the same level).
#[test]
fn environment_sampling_follows_its_pdf() {
    let env = Environment::new(sky_image(1.0), 1.0, 30.0).unwrap();
    let p = chi_square_p(&env, |u1, u2| environment::sample(&env, u1, u2));
    assert!(p > 0.001, "directions do not follow the pdf (p = {p})");
    let wrong = Environment::new(sky_image(1.03), 1.0, 30.0).unwrap();
    let p = chi_square_p(&env, |u1, u2| environment::sample(&wrong, u1, u2));
    assert!(p < 0.001, "a 3% brighter half went undetected (p = {p})");
}

#[cfg(feature = "gpu")]
/// The kernel's environment (radiance, pdf, sampled direction and its pdf) equals the CPU's
/// at 20 000 random directions and number pairs, within what WGSL's trigonometry may differ:
/// atan2 (and acos) within 4096 ulp, sin and cos within 2^-11 absolute, moving image
/// coordinates by up to about 5e-4, which the sky's gradients turn into the bounds below;
/// where that moves a direction across a sampling cell's edge the pdf jumps (at most 0.5% of
/// directions). Against the sky 10% brighter, nearly every radiance differs (negative control).
#[test]
fn gpu_environment_matches_the_cpu() {
    const RADIANCE: f32 = 3e-2;
    const PDF: f32 = 1e-2;
    const DIRECTION: f32 = 2e-3;
    let Some(gpu) = renderer() else { return };
    let env = Environment::new(sky_image(1.0), 2.0, 30.0).unwrap();
    let brighter = Environment::new(sky_image(1.0), 2.2, 30.0).unwrap();
    let mut scene = common::furnace_scene();
    scene.background = Background::Environment(env.clone());
    let flat = FlatScene::new(&scene, 8, 8).expect("valid");
    let mut rng = rt_gpu::shared::rng::Rng::for_sample(0, 0, 3);
    let lookups: Vec<(Vec3, f32, f32)> = (0..20_000)
        .map(|_| {
            let dir = rt_gpu::shared::warp::unit_vector(rng.next_f32(), rng.next_f32());
            (dir, rng.next_f32(), rng.next_f32())
        })
        .collect();
    let found = gpu
        .look_up_environment(&flat, &lookups)
        .expect("lookups run");
    let relative = |a: f32, b: f32| (a - b).abs() / a.abs().max(b.abs()).max(1e-3);
    let relative3 = |a: Vec3, b: Vec3| {
        (a - b).abs().max_element() / a.abs().max_element().max(b.abs().max_element()).max(1e-3)
    };
    let (mut radiance_error, mut pdf_error, mut direction_error, mut sample_pdf_error) =
        (0.0f32, 0.0f32, 0.0f32, 0.0f32);
    let (mut pdfs_jump, mut differ_from_brighter) = (0, 0);
    for ((dir, u1, u2), g) in lookups.iter().zip(&found) {
        let radiance = environment::radiance(&env, *dir);
        radiance_error = radiance_error.max(relative3(radiance, g.radiance));
        differ_from_brighter +=
            (relative3(environment::radiance(&brighter, *dir), g.radiance) > RADIANCE) as usize;
        let pdf_difference = relative(environment::pdf(&env, *dir), g.pdf);
        if pdf_difference > PDF {
            pdfs_jump += 1; // across a cell's edge
        } else {
            pdf_error = pdf_error.max(pdf_difference);
        }
        match environment::sample(&env, *u1, *u2) {
            Some((sampled, pdf)) => {
                direction_error = direction_error.max((sampled - g.sampled).length());
                sample_pdf_error = sample_pdf_error.max(relative(pdf, g.sampled_pdf));
            }
            None => assert_eq!(g.sampled_pdf, 0.0),
        }
    }
    eprintln!(
        "worst relative differences: radiance {radiance_error:.1e}, pdf {pdf_error:.1e} ({pdfs_jump} of {} across a cell's edge), sampled direction {direction_error:.1e} (absolute), its pdf {sample_pdf_error:.1e}; radiance differing from the sky 10% brighter: {differ_from_brighter}",
        lookups.len()
    );
    assert!(
        radiance_error <= RADIANCE,
        "radiance differs by {radiance_error}"
    );
    assert!(
        pdf_error <= PDF && pdfs_jump * 200 <= lookups.len(),
        "pdfs differ: {pdfs_jump}"
    );
    assert!(
        direction_error <= DIRECTION,
        "sampled directions differ by {direction_error}"
    );
    assert!(
        sample_pdf_error <= PDF,
        "sampled pdfs differ by {sample_pdf_error}"
    );
    assert!(
        differ_from_brighter * 10 > lookups.len() * 9,
        "the negative control passed"
    );
}

#[cfg(feature = "gpu")]
/// A sphere of albedo 1 under a white environment of radiance 1 is invisible: every path
/// escapes after at most one bounce, naive paths carry exactly 1, and nee's weighted sum has
/// mean 1 (the whole-image mean within 4 standard errors, on both backends). Albedo 0.98 is
/// caught (negative control).
#[test]
fn a_white_environment_is_a_furnace() {
    let white = Image::from_linear("white", 8, 4, vec![1.0; 96])
        .unwrap()
        .shared();
    let scene_with = |albedo: f32| {
        common::scene(
            Vec3::new(0.0, 0.0, 3.0),
            Vec3::ZERO,
            40.0,
            Background::Environment(Environment::new(white.clone(), 1.0, 0.0).unwrap()),
            vec![Material::lambertian(Vec3::splat(albedo))],
            vec![common::object(Shape::sphere(Vec3::ZERO, 1.0), 0)],
        )
    };
    let gpu = renderer();
    let whole_image_z = |film: &rt_gpu::film::Film| {
        let (mut mean, mut var) = (0.0, 0.0);
        let n = (film.width * film.height) as f64;
        for y in 0..film.height {
            for x in 0..film.width {
                let p = film.pixel(x, y);
                mean += p.mean()[1] / n;
                var += film.variance_of_mean(p)[1] / (n * n);
            }
        }
        ((mean - 1.0) / var.sqrt().max(1e-12), mean)
    };
    for albedo in [1.0, 0.98] {
        let scene = scene_with(albedo);
        let naive = common::render_cpu(&scene, &common::opts(16, 16, 64, 8, 1));
        let nee = common::render_cpu(&scene, &common::nee_opts(16, 16, 256, 8, 2));
        let mut films = vec![("cpu nee", nee)];
        if let Some(gpu) = &gpu {
            films.push((
                "gpu nee",
                render_gpu(
                    gpu,
                    &scene,
                    &common::nee_opts(16, 16, 256, 8, 3),
                    &Tuning::default(),
                ),
            ));
            let gpu_naive = render_gpu(
                gpu,
                &scene,
                &common::opts(16, 16, 64, 8, 4),
                &Tuning::default(),
            );
            let worst = (0..16)
                .flat_map(|y| (0..16).map(move |x| (x, y)))
                .map(|(x, y)| (gpu_naive.pixel(x, y).mean()[1] - albedo as f64).abs())
                .fold(0.0, f64::max);
            eprintln!("albedo {albedo}: gpu naive worst pixel off by {worst:.2e}");
            if albedo == 1.0 {
                assert!(worst < 1e-5, "gpu naive: a pixel is off by {worst}");
            }
        }
        let worst = (0..16)
            .flat_map(|y| (0..16).map(move |x| (x, y)))
            .map(|(x, y)| (naive.pixel(x, y).mean()[1] - 1.0).abs())
            .fold(0.0, f64::max);
        eprintln!("albedo {albedo}: cpu naive worst pixel off 1 by {worst:.2e}");
        if albedo == 1.0 {
            assert!(worst < 1e-5, "cpu naive: a pixel is off by {worst}");
        }
        for (name, film) in &films {
            let (z, mean) = whole_image_z(film);
            eprintln!("albedo {albedo}, {name}: mean {mean:.5}, z = {z:.2}");
            if albedo == 1.0 {
                assert!(z.abs() < 4.0, "{name}: mean {mean}, z = {z}");
            } else {
                assert!(z.abs() > 4.0, "{name}: albedo 0.98 went undetected");
            }
        }
    }
}

/// The shipped scene (image textures on spheres and a quad, a solid checker, metal, glass,
/// under an environment with a sun), at a small size.
fn textured_scene() -> Scene {
    load(Path::new("scenes/textured.toml")).unwrap_or_else(|e| panic!("{e}"))
}

/// The textured scene under the 16 x 8 test sky, whose sun is 40 times the sky and spans a
/// texel: naive paths find it often enough that a pixel's sample variance measures its noise
/// (under the shipped sky's small sun, naive pixels that happen to miss it understate both).
fn textured_under_a_soft_sky() -> Scene {
    let mut scene = textured_scene();
    scene.background =
        Background::Environment(Environment::new(sky_image(1.0), 1.0, 60.0).unwrap());
    scene
}

fn with_strength(scene: &Scene, factor: f32) -> Scene {
    let mut out = scene.clone();
    if let Background::Environment(env) = &scene.background {
        out.background = Background::Environment(
            Environment::new(
                env.image.clone(),
                env.strength * factor,
                env.rotate_y_degrees,
            )
            .unwrap(),
        );
    }
    out
}

/// Naive and nee (environment sampling with MIS) render the same image of the textured scene
/// under the soft sky; the sky 3% brighter is told apart (negative control).
#[test]
fn nee_and_naive_agree_under_an_environment() {
    let scene = textured_under_a_soft_sky();
    let naive = common::render_cpu(&scene, &common::opts(24, 14, 1024, 6, 1));
    let nee = common::render_cpu(&scene, &common::nee_opts(24, 14, 256, 6, 2));
    let verdict = compare(&naive, &nee);
    eprintln!("naive vs nee: {verdict:?}");
    assert!(verdict.passed(), "naive and nee differ: {verdict:?}");
    let brighter = common::render_cpu(
        &with_strength(&scene, 1.03),
        &common::nee_opts(24, 14, 256, 6, 2),
    );
    let verdict = compare(&naive, &brighter);
    eprintln!("naive vs nee 3% brighter: {verdict:?}");
    assert!(!verdict.passed(), "a 3% brighter sky went undetected");
}

#[cfg(feature = "gpu")]
/// CPU and GPU render the same image of the textured scene, naive under the soft sky and nee
/// under the shipped one; the sky 3% brighter is told apart (negative control).
#[test]
fn gpu_matches_cpu_under_an_environment() {
    let Some(gpu) = renderer() else { return };
    for (name, cpu_opts, gpu_opts) in [
        (
            "naive",
            common::opts(24, 14, 1024, 6, 1),
            common::opts(24, 14, 1024, 6, 2),
        ),
        (
            "nee",
            common::nee_opts(24, 14, 256, 6, 3),
            common::nee_opts(24, 14, 256, 6, 4),
        ),
    ] {
        let scene = if name == "nee" {
            textured_scene()
        } else {
            textured_under_a_soft_sky()
        };
        let cpu = common::render_cpu(&scene, &cpu_opts);
        let verdict = compare(
            &cpu,
            &render_gpu(&gpu, &scene, &gpu_opts, &Tuning::default()),
        );
        eprintln!("{name}: cpu vs gpu: {verdict:?}");
        assert!(verdict.passed(), "{name}: CPU and GPU differ: {verdict:?}");
        if name == "nee" {
            let brighter = render_gpu(
                &gpu,
                &with_strength(&scene, 1.03),
                &gpu_opts,
                &Tuning::default(),
            );
            let verdict = compare(&cpu, &brighter);
            eprintln!("{name}: cpu vs gpu 3% brighter: {verdict:?}");
            assert!(!verdict.passed(), "a 3% brighter sky went undetected");
        }
    }
}

#[cfg(feature = "gpu")]
/// The kernel's image-texture lookups equal the CPU's at 20 000 random UVs to 1e-5 (bilinear
/// filtering, wrapping); the CPU's lookup a texel away differs in more than 10% of them
/// (negative control: much of the tiles is flat).
#[test]
fn gpu_image_lookups_match_the_cpu() {
    let Some(gpu) = renderer() else { return };
    let flat = FlatScene::new(&textured_scene(), 8, 8).expect("valid");
    let textured: Vec<(u32, rt_gpu::assets::texture::Texture)> = flat
        .materials
        .iter()
        .enumerate()
        .filter_map(|(i, m)| match m {
            Material::Lambertian(l)
                if matches!(l.albedo, rt_gpu::assets::texture::Texture::Image(_)) =>
            {
                Some((i as u32, l.albedo.clone()))
            }
            _ => None,
        })
        .collect();
    assert_eq!(textured.len(), 2);
    let mut rng = rt_gpu::shared::rng::Rng::for_sample(0, 0, 8);
    let lookups: Vec<(u32, Vec3, Vec2)> = (0..20_000)
        .map(|k| {
            // UVs a little beyond [0, 1] too: the image wraps.
            let uv = Vec2::new(rng.next_f32(), rng.next_f32()) * 1.2 - 0.1;
            (textured[k % 2].0, Vec3::ZERO, uv)
        })
        .collect();
    let found = gpu.look_up_albedo(&flat, &lookups).expect("lookups run");
    let (mut worst, mut shifted_differ) = (0.0f32, 0);
    for ((material, _, uv), g) in lookups.iter().zip(found) {
        let (_, texture) = textured.iter().find(|(m, _)| m == material).unwrap();
        let hit = |uv: Vec2| rt_gpu::shared::ray::Hit {
            t: 1.0,
            point: Vec3::ZERO,
            error: 0.0,
            normal: Vec3::Y,
            shading: Vec3::Y,
            coat: Vec3::Y,
            front_face: true,
            material: *material,
            primitive: rt_gpu::shared::primitive::PrimitiveRef::Shape {
                kind: rt_gpu::shape::Quad::KIND,
                index: 0,
            },
            uv,
            uv1: uv,
            color: Vec3::ONE,
        };
        let cpu = rt_gpu::material::texture::value(texture, &hit(*uv));
        worst = worst.max((cpu - g).abs().max_element());
        let texel = Vec2::new(1.0 / 128.0, 1.0 / 128.0);
        let moved = rt_gpu::material::texture::value(texture, &hit(*uv + texel));
        shifted_differ += ((moved - g).abs().max_element() > 1e-5) as usize;
    }
    eprintln!("worst difference {worst:.2e}; a texel away: {shifted_differ} of 20000 differ");
    assert!(worst <= 1e-5, "lookups differ by {worst}");
    assert!(shifted_differ > 2_000, "the negative control passed");
}

#[cfg(feature = "gpu")]
/// The syntax round-trips (paths as written, relative to the scene file); the kernel holds
/// image and environment code only for scenes that use them.
#[test]
fn image_syntax_round_trips_and_kernels_leave_images_out() {
    use rt_gpu::gpu::Features;
    use rt_gpu::gpu::shader::compose;
    let scene = textured_scene();
    let loader = rt_gpu::assets::loader::Loader::new(Path::new("scenes"));
    let again = parse_with(&loader, &to_toml(&scene), "again.toml", "textured")
        .expect("exported scene parses");
    assert_eq!(scene.materials, again.materials);
    assert_eq!(scene.background, again.background);
    let cornell = rt_gpu::scene::builtin::builtin("cornell").expect("built-in");
    for (name, scene, images) in [("cornell", cornell, false), ("textured", scene, true)] {
        let flat = FlatScene::new(&scene, 8, 8).expect("valid");
        let features = Features::of(&flat);
        let source = compose(&features, &flat).expect("composes");
        assert_eq!(
            features.has_material(rt_gpu::material::MaterialFeature::ImageTexture),
            images,
            "{name}"
        );
        assert_eq!(features.environment, images, "{name}");
        assert_eq!(source.contains("fn bilinear("), images, "{name}");
        assert_eq!(source.contains("fn environment_sample("), images, "{name}");
    }
}

/// Bad image files are one-line errors naming the file and the scene file's line.
#[test]
fn bad_images_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, bytes: &[u8]| std::fs::write(dir.path().join(name), bytes).unwrap();
    write("garbage.png", b"this is not a PNG at all");
    write("notes.txt", b"hello");
    write(
        "truncated.png",
        &std::fs::read("scenes/textures/tiles.png").unwrap()[..200],
    );
    let bright = image::Rgb32FImage::from_raw(2, 1, vec![2.0, 0.5, 0.5, 0.1, 0.1, 0.1]).unwrap();
    bright.save(dir.path().join("bright.exr")).unwrap();
    let nan = image::Rgb32FImage::from_raw(2, 1, vec![f32::NAN, 0.5, 0.5, 0.1, 0.1, 0.1]).unwrap();
    nan.save(dir.path().join("nan.exr")).unwrap();
    let camera = "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\nvfov = 40\n";
    let object = "\n[[object]]\nsphere = { center = [0, 0, 0], radius = 1 }\nmaterial = \"m\"\n";
    for (albedo, background, words) in [
        ("{ image = \"missing.png\" }", None, "missing.png"),
        ("{ image = \"garbage.png\" }", None, "garbage.png"),
        ("{ image = \"notes.txt\" }", None, "notes.txt"),
        ("{ image = \"truncated.png\" }", None, "truncated.png"),
        (
            "{ image = \"bright.exr\" }",
            None,
            "an albedo must lie in [0, 1]",
        ),
        (
            "[0.5, 0.5, 0.5]",
            Some("{ image = \"nan.exr\" }"),
            "nan.exr",
        ),
        (
            "[0.5, 0.5, 0.5]",
            Some("{ image = \"missing.hdr\" }"),
            "missing.hdr",
        ),
        (
            "[0.5, 0.5, 0.5]",
            Some("{ image = \"bright.exr\", strength = -1 }"),
            "strength",
        ),
        (
            "[0.5, 0.5, 0.5]",
            Some("{ image = \"bright.exr\", size = 2 }"),
            "unknown field `size`",
        ),
    ] {
        let render =
            background.map_or(String::new(), |b| format!("[render]\nbackground = {b}\n\n"));
        let text = format!(
            "{render}{camera}\n[materials]\nm = {{ type = \"lambertian\", albedo = {albedo} }}\n{object}"
        );
        let path = dir.path().join("scene.toml");
        std::fs::write(&path, &text).unwrap();
        let err = load(&path).expect_err(&text).to_string();
        eprintln!("{err}");
        assert!(err.contains(words), "{err}");
        assert!(err.contains("scene.toml:"), "{err}");
        assert!(!err.contains('\n'), "{err}");
    }
}

/// Every format the docs name loads: 8-bit PNG and JPEG and 16-bit PNG decoded from sRGB,
/// OpenEXR and Radiance HDR as linear values (a 2x1 image: mid-grey and black).
#[test]
fn every_supported_format_loads() {
    let dir = tempfile::tempdir().unwrap();
    let grey = 0.5f32;
    // 128 of 255, and 32896 of 65535, are 128 / 255 decoded from sRGB.
    let linear_grey = rt_gpu::assets::image::srgb_to_linear(128.0 / 255.0);
    let eight = image::RgbImage::from_raw(2, 1, vec![128, 128, 128, 0, 0, 0]).unwrap();
    let sixteen = image::ImageBuffer::<image::Rgb<u16>, _>::from_raw(
        2,
        1,
        vec![32896u16, 32896, 32896, 0, 0, 0],
    )
    .unwrap();
    let float = image::Rgb32FImage::from_raw(2, 1, vec![grey, grey, grey, 0.0, 0.0, 0.0]).unwrap();
    eight.save(dir.path().join("a.png")).unwrap();
    eight.save(dir.path().join("a.jpg")).unwrap();
    sixteen.save(dir.path().join("b.png")).unwrap();
    float.save(dir.path().join("c.exr")).unwrap();
    float.save(dir.path().join("c.hdr")).unwrap();
    for (name, expected, tolerance) in [
        ("a.png", linear_grey, 1e-6),
        ("a.jpg", linear_grey, 0.02),
        ("b.png", linear_grey, 1e-6),
        ("c.exr", grey, 1e-6),
        ("c.hdr", grey, 1e-2),
    ] {
        let image = rt_gpu::assets::image::load(&dir.path().join(name), name)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((image.width, image.height), (2, 1), "{name}");
        let first = image.texel(0, 0);
        assert!(
            (first - Vec3::splat(expected)).abs().max_element() <= tolerance,
            "{name}: {first} (expected {expected})"
        );
        assert!(image.texel(1, 0).max_element() <= 0.02, "{name}");
    }
}
