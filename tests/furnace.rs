//! Furnace tests: scenes whose exact radiance is known in closed form.
//!
//! Both furnaces are noise-free in theory (every path carries the same radiance), so the
//! tolerance is 5 standard errors from the film's own measured variance plus a relative 1e-5
//! for f32 rounding; a bias (a lost bounce, a leak, a wrong albedo) fails it.

mod common;

use glam::{DVec3, Vec3};
use rt_gpu::cpu::shapes::hit_sphere;
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
