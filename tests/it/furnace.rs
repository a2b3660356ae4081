//! Furnace tests: scenes whose exact radiance is known in closed form.
//!
//! Both furnaces are noise-free in theory (every path carries the same radiance), so the
//! tolerance is 5 standard errors from the film's own measured variance plus a relative 1e-5
//! for f32 rounding; a bias (a lost bounce, a leak, a wrong albedo) fails it.

use crate::common;

use glam::{DVec3, Vec3};
use rt_gpu::cpu::intersect::hit_sphere;
use rt_gpu::film::PixelStats;
use rt_gpu::scene::flat::{FlatScene, Sphere};
use rt_gpu::scene::{Background, Material, Shape};
use rt_gpu::shared::ray::Ray;

fn assert_close(stats: &PixelStats, expected: DVec3, what: &str) {
    let tolerance = 5.0 * stats.variance_of_mean().map(f64::sqrt) + 1e-5 * expected.abs();
    let error = (stats.mean() - expected).abs();
    assert!(
        error.cmple(tolerance).all(),
        "{what}: mean {:?}, expected {expected:?}, tolerance {tolerance:?}",
        stats.mean()
    );
}

/// A lambertian sphere of albedo a under a constant background B: every first bounce escapes, so
/// wherever the sphere covers a whole pixel the image is exactly a * B (max depth >= 2).
#[test]
fn lambertian_sphere_under_constant_sky_shows_albedo_times_background() {
    let albedo = Vec3::new(0.5, 0.7, 0.9);
    let sky = Vec3::new(0.8, 1.0, 0.6);
    let scene = common::scene(
        Vec3::new(0.0, 0.0, 5.0),
        Vec3::ZERO,
        30.0,
        Background::Constant(sky),
        vec![Material::lambertian(albedo)],
        vec![common::object(Shape::sphere(Vec3::ZERO, 1.0), 0)],
    );
    let (w, h) = (24, 24);
    let flat = FlatScene::new(&scene, w, h).expect("valid");
    let sphere = Sphere {
        center: Vec3::ZERO,
        radius: 1.0,
        material: 0,
        light: 0,
    };
    // A pixel is covered when the rays through its four corners all hit (the silhouette is convex).
    let corner_hits = |x: u32, y: u32| {
        let cam = &flat.camera;
        let to_target = cam.to_upper_left + (x as f32 / w as f32) * cam.horizontal
            - (y as f32 / h as f32) * cam.vertical;
        let ray = Ray {
            origin: cam.origin,
            dir: to_target.normalize(),
        };
        hit_sphere(&sphere, &ray, 0.0, f32::INFINITY).is_some()
    };
    for max_depth in [2, 5] {
        let film = common::render_cpu(&scene, &common::opts(w, h, 16, max_depth, 3));
        let mut covered = 0;
        for y in 0..h {
            for x in 0..w {
                if corner_hits(x, y)
                    && corner_hits(x + 1, y)
                    && corner_hits(x, y + 1)
                    && corner_hits(x + 1, y + 1)
                {
                    covered += 1;
                    assert_close(
                        film.pixel(x, y),
                        (albedo * sky).as_dvec3(),
                        &format!("pixel ({x},{y})"),
                    );
                }
            }
        }
        assert!(covered > 150, "only {covered} pixels covered");
    }
}

/// The camera inside a closed lambertian sphere of albedo a that also emits Le: every segment
/// hits the sphere, so L = Le (1 + a + ... + a^(d-1)) = Le (1 - a^d) / (1 - a) at max depth d.
/// The background is bright so that any leak shows.
#[test]
fn closed_emitting_sphere_gives_the_geometric_series() {
    let albedo = Vec3::new(0.5, 0.8, 0.9);
    let emission = Vec3::new(1.0, 2.0, 0.5);
    let scene = common::scene(
        Vec3::new(0.1, 0.2, 0.0),
        Vec3::new(0.1, 0.2, -1.0),
        70.0,
        Background::Constant(Vec3::splat(100.0)),
        vec![Material::Lambertian(rt_gpu::material::Lambertian {
            albedo: albedo.into(),
            emission,
            normal_map: None,
        })],
        vec![common::object(Shape::sphere(Vec3::ZERO, 1.0), 0)],
    );
    for max_depth in [1, 3, 8] {
        let film = common::render_cpu(&scene, &common::opts(12, 10, 8, max_depth, 11));
        let a = albedo.as_dvec3();
        let expected =
            emission.as_dvec3() * (DVec3::ONE - a.powf(max_depth as f64)) / (DVec3::ONE - a);
        for (i, stats) in film.pixels.iter().enumerate() {
            assert_close(stats, expected, &format!("depth {max_depth}, pixel {i}"));
        }
        let mean_error = (film.image_mean() - expected).abs();
        assert!(
            mean_error
                .cmple(5.0 * film.image_mean_std_error() + 1e-5 * expected)
                .all(),
            "depth {max_depth}: image mean {:?} vs {expected:?}",
            film.image_mean()
        );
    }
}

/// Where a steep normal map bends the shading normal (60 degrees), a lossless surface under a
/// uniform sky still renders 1 at every pixel: normal-mapped surfaces are microsurfaces (`material::microsurface`, Schüssler et al. 2017) that
/// neither lose light below the surface nor go black where the view is below the shading
/// normal. Naive paths on lossless materials weigh exactly 1 (or 0 where one is lost), so their
/// bound is a plain 1% at every pixel (the issue asks 2%). With next-event estimation against a
/// uniform environment light (the split of the BSDF between MIS and sampling alone must add
/// up), samples vary: the image mean within 4 standard errors (4 such tests; Sidak at 0.01
/// would allow 3.0) and each pixel within 1% + 5 of its standard errors. The control, albedo
/// 0.98, must break each bound. Both backends.
#[test]
fn normal_maps_keep_a_lossless_surface_lossless() {
    use rt_gpu::assets::environment::Environment;
    use rt_gpu::assets::image::Image;
    use rt_gpu::assets::normal_map::NormalMap;
    use rt_gpu::scene::Scene;
    #[cfg(feature = "gpu")]
    let gpu = common::gpu::renderer();
    // A 4 x 4 map of normals tilted 60 degrees toward 16 azimuths.
    let texels = (0..16)
        .flat_map(|i| {
            let (phi, theta) = (
                i as f32 * 2.0 * std::f32::consts::PI / 16.0,
                60f32.to_radians(),
            );
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            (0.5 * (n + Vec3::ONE)).to_array()
        })
        .collect();
    let steep = NormalMap {
        image: Image::from_linear("steep normals", 4, 4, texels)
            .expect("valid")
            .shared(),
        scale: 1.0,
    };
    let white = Image::from_linear("white", 8, 4, vec![1.0; 96])
        .expect("valid")
        .shared();
    let bumpy = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/blender/bumpy.glb");
    let (bumpy, _) = rt_gpu::scene::gltf_scene::load(&bumpy, "bumpy.glb", None).expect("loads");
    let scenes = |albedo: f32| -> Vec<(&'static str, Scene)> {
        let lambertian = Material::Lambertian(rt_gpu::material::Lambertian {
            albedo: Vec3::splat(albedo).into(),
            emission: Vec3::ZERO,
            normal_map: Some(steep.clone()),
        });
        let mut mirror = rt_gpu::material::Pbr::new(Vec3::splat(albedo).into(), 1.0, 0.0, 1.5, 0.0);
        mirror.normal_map = Some(steep.clone());
        let mut out = Vec::new();
        for (what, material) in [
            ("lambertian", lambertian),
            ("mirror", Material::Pbr(mirror)),
        ] {
            let mut scene = bumpy.clone();
            scene.background = Background::Constant(Vec3::ONE);
            scene.punctual.clear(); // its sun
            scene
                .materials
                .iter_mut()
                .for_each(|m| *m = material.clone());
            out.push((
                if what == "mirror" {
                    "mapped mirror"
                } else {
                    "mapped lambertian"
                },
                scene,
            ));
        }
        out
    };
    let worst_of = |film: &rt_gpu::film::Film| {
        film.pixels
            .iter()
            .map(|p| (p.mean() - DVec3::ONE).abs().max_element())
            .fold(0.0, f64::max)
    };
    for albedo in [1.0, 0.98] {
        for (what, scene) in scenes(albedo) {
            let environment = Scene {
                background: Background::Environment(
                    Environment::new(white.clone(), 1.0, 0.0).unwrap(),
                ),
                ..scene.clone()
            };
            let mut opts = common::opts(32, 24, 16, 64, 5);
            opts.roulette_depth = 0;
            let mut nee = common::nee_opts(32, 24, 16, 64, 6);
            nee.roulette_depth = 0;
            #[allow(unused_mut)]
            let mut films = vec![
                ("cpu naive", common::render_cpu(&scene, &opts)),
                ("cpu nee", common::render_cpu(&environment, &nee)),
            ];
            #[cfg(feature = "gpu")]
            if let Some(gpu) = &gpu {
                let tuning = rt_gpu::gpu::Tuning::default();
                films.push((
                    "gpu naive",
                    common::gpu::render_gpu(gpu, &scene, &opts, &tuning),
                ));
                films.push((
                    "gpu nee",
                    common::gpu::render_gpu(gpu, &environment, &nee, &tuning),
                ));
            }
            for (how, film) in films {
                let worst = worst_of(&film);
                let (mean, error) = (film.image_mean()[1], film.image_mean_std_error()[1]);
                let z = (mean - 1.0) / error.max(1e-12);
                eprintln!(
                    "{what}, albedo {albedo}, {how}: worst pixel off by {worst:.2e}, image mean {mean:.5} +- {error:.5}"
                );
                let noisy = how.ends_with("nee");
                let off = |p: &rt_gpu::film::PixelStats| {
                    let slack = if noisy {
                        5.0 * film.variance_of_mean(p)[1].sqrt()
                    } else {
                        0.0
                    };
                    (p.mean()[1] - 1.0).abs() > 0.01 + slack
                };
                if albedo == 1.0 {
                    assert!(z.abs() < 4.0, "{what}, {how}: image mean {mean} +- {error}");
                    let bad = film.pixels.iter().filter(|p| off(p)).count();
                    assert!(
                        bad == 0,
                        "{what}, {how}: {bad} pixels off (worst by {worst})"
                    );
                } else if noisy {
                    assert!(
                        z.abs() > 4.0,
                        "{what}, {how}: the 2% control passed ({mean} +- {error})"
                    );
                } else {
                    assert!(
                        worst > 0.01,
                        "{what}, {how}: the 2% control passed ({worst})"
                    );
                }
            }
        }
    }
}
