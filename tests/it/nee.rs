//! Next-event estimation with multiple importance sampling: it converges to the same image as
//! the naive integrator (the original project's estimator), on both backends, and its light
//! sampling draws directions with exactly the pdf it reports.
//!
//! Image comparisons use the equivalence test of tests/it/common/stats.rs (family-wise alpha 0.01,
//! Sidak-corrected over every pixel, block and channel); each assertion below is one such test.
#![cfg_attr(not(feature = "gpu"), allow(unused))]

use crate::common;
use crate::common::chi_square::{self, Domain, Draw};

#[cfg(feature = "gpu")]
use common::gpu::{render_gpu, renderer};
use common::stats::compare;
use common::{nee_opts, object, opts, render_cpu};
use glam::Vec3;
use rt_gpu::cpu::intersect::{hit_quad, hit_sphere, hit_triangle};
use rt_gpu::cpu::lights;
#[cfg(feature = "gpu")]
use rt_gpu::gpu::Tuning;
use rt_gpu::render::RenderOptions;
use rt_gpu::scene::builtin::builtin;
use rt_gpu::scene::flat::{Light, LightShape, Quad, Sphere, Triangle};
use rt_gpu::scene::{Material, Scene, Shape};
use rt_gpu::shape::disk::hit_disk;
use rt_gpu::shape::{Disk, SurfaceShape};
use rt_gpu::shared::ray::Ray;

fn add_material(scene: &mut Scene, name: &str, material: Material) -> u32 {
    scene.materials.push(material);
    scene.material_names.push(name.into());
    scene.materials.len() as u32 - 1
}

/// The Cornell box with a second, one-sided sphere light hanging under the ceiling: two lights
/// of different power (the pick) and a sphere light (cone sampling). Large and dim, so that
/// naive paths find it often enough for a fair variance estimate.
fn cornell_with_sphere_light() -> Scene {
    let mut scene = builtin("cornell").expect("built-in");
    let glow = add_material(
        &mut scene,
        "glow",
        Material::Light(rt_gpu::material::Light {
            radiance: Vec3::new(2.0, 1.5, 1.0).into(),
            strength: 1.0,
            two_sided: false,
            alpha: None,
        }),
    );
    scene.objects.push(object(
        Shape::sphere(Vec3::new(150.0, 400.0, 380.0), 70.0),
        glow,
    ));
    scene
}

/// The `spheres` scene (sky, glass, metal, lambertian) lit also by an overhead quad light and a
/// small emissive-lambertian sphere: light sampling through and around specular surfaces.
fn spheres_with_lights() -> Scene {
    let mut scene = builtin("spheres").expect("built-in");
    let lamp = add_material(
        &mut scene,
        "lamp",
        Material::Light(rt_gpu::material::Light {
            radiance: Vec3::splat(6.0).into(),
            strength: 1.0,
            two_sided: false,
            alpha: None,
        }),
    );
    let ember = add_material(
        &mut scene,
        "ember",
        Material::Lambertian(rt_gpu::material::Lambertian {
            albedo: Vec3::splat(0.5).into(),
            emission: Vec3::new(8.0, 2.0, 1.0),
            normal_map: None,
        }),
    );
    // Facing down: u x v = -y.
    scene.objects.push(object(
        Shape::quad(
            Vec3::new(-1.0, 3.0, -2.0),
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(2.0, 0.0, 0.0),
        ),
        lamp,
    ));
    scene.objects.push(object(
        Shape::sphere(Vec3::new(0.7, -0.35, -0.6), 0.15),
        ember,
    ));
    scene
}

fn cornell(seed: u32, nee: bool) -> RenderOptions {
    // As in the GPU test: 16x16 at 20 000 spp resolves a 2% change in the whole-image mean.
    if nee {
        nee_opts(16, 16, 20_000, 10, seed)
    } else {
        opts(16, 16, 20_000, 10, seed)
    }
}

fn small(seed: u32, nee: bool, spp: u32) -> RenderOptions {
    if nee {
        nee_opts(24, 24, spp, 8, seed)
    } else {
        opts(24, 24, spp, 8, seed)
    }
}

/// nee and naive converge to the same image (CPU), on the Cornell box, the empty Cornell box,
/// spheres with lights, a scene with a sphere light, and one with disks (a disk lamp).
#[test]
fn nee_and_naive_agree() {
    let cases = [
        (
            "cornell",
            builtin("cornell").expect("built-in"),
            cornell(1, false),
            cornell(2, true),
        ),
        (
            "cornell-empty",
            builtin("cornell-empty").expect("built-in"),
            small(1, false, 8192),
            small(2, true, 1024),
        ),
        (
            "spheres+lights",
            spheres_with_lights(),
            small(1, false, 8192),
            small(2, true, 1024),
        ),
        (
            "cornell+sphere light",
            cornell_with_sphere_light(),
            small(1, false, 8192),
            small(2, true, 1024),
        ),
        (
            "cornell+disks",
            common::cornell_with_disks(),
            small(1, false, 8192),
            small(2, true, 1024),
        ),
    ];
    for (name, scene, naive, nee) in cases {
        let a = render_cpu(&scene, &naive);
        let b = render_cpu(&scene, &nee);
        assert_eq!(a.invalid_samples + b.invalid_samples, 0, "{name}");
        let verdict = compare(&a, &b);
        eprintln!("{name}: naive vs nee: {verdict:?}");
        assert!(
            verdict.passed(),
            "{name}: naive and nee differ: {verdict:?}"
        );
    }
}

/// Negative control: the same test catches nee rendering the Cornell box with a 2% brighter
/// light, and with the light emitting from both faces (a one-sided-light bug nee could have:
/// the light's back faces the ceiling, so only light sampling would see it).
#[test]
fn nee_comparison_detects_small_real_differences() {
    let scene = builtin("cornell").expect("built-in");
    let naive = render_cpu(&scene, &cornell(1, false));
    let light = scene
        .material_names
        .iter()
        .position(|n| n == "light")
        .expect("light");
    for (label, radiance, two_sided) in [
        ("light +2%", 15.0 * 1.02, false),
        ("two-sided light", 15.0, true),
    ] {
        let mut changed = scene.clone();
        changed.materials[light] = Material::Light(rt_gpu::material::Light {
            radiance: Vec3::splat(radiance).into(),
            strength: 1.0,
            two_sided,
            alpha: None,
        });
        let verdict = compare(&naive, &render_cpu(&changed, &cornell(2, true)));
        eprintln!("{label}: {verdict:?}");
        assert!(!verdict.passed(), "{label} went undetected: {verdict:?}");
    }
}

/// Russian roulette is unbiased: nee with roulette from the second segment matches naive.
#[test]
fn russian_roulette_keeps_the_image() {
    let scene = builtin("cornell").expect("built-in");
    let naive = render_cpu(&scene, &cornell(1, false));
    let roulette = RenderOptions {
        roulette_depth: 2,
        ..cornell(3, true)
    };
    let verdict = compare(&naive, &render_cpu(&scene, &roulette));
    eprintln!("roulette: {verdict:?}");
    assert!(verdict.passed(), "roulette changes the image: {verdict:?}");
}

#[cfg(feature = "gpu")]
/// The GPU kernel's nee (with and without roulette) matches the CPU's.
#[test]
fn gpu_nee_matches_cpu_nee() {
    let Some(gpu) = renderer() else { return };
    let cases = [
        (
            "cornell",
            builtin("cornell").expect("built-in"),
            cornell(1, true),
            0,
        ),
        (
            "spheres+lights",
            spheres_with_lights(),
            small(1, true, 1024),
            0,
        ),
        (
            "cornell+sphere light",
            cornell_with_sphere_light(),
            small(1, true, 1024),
            3,
        ),
        (
            "cornell+disks",
            common::cornell_with_disks(),
            small(1, true, 1024),
            0,
        ),
    ];
    for (name, scene, cpu_opts, roulette_depth) in cases {
        let cpu_opts = RenderOptions {
            roulette_depth,
            ..cpu_opts
        };
        let gpu_opts = RenderOptions {
            seed: cpu_opts.seed + 1,
            ..cpu_opts
        };
        let cpu = render_cpu(&scene, &cpu_opts);
        let gpu_film = render_gpu(&gpu, &scene, &gpu_opts, &Tuning::default());
        assert_eq!(gpu_film.invalid_samples, 0, "{name}");
        let verdict = compare(&cpu, &gpu_film);
        eprintln!("{name}: cpu nee vs gpu nee: {verdict:?}");
        assert!(
            verdict.passed(),
            "{name}: CPU and GPU nee differ: {verdict:?}"
        );
    }
}

#[cfg(feature = "gpu")]
/// The GPU's nee images do not depend on dispatch slicing either.
#[test]
fn gpu_nee_does_not_depend_on_slicing() {
    let Some(gpu) = renderer() else { return };
    let scene = cornell_with_sphere_light();
    let opts = RenderOptions {
        roulette_depth: 3,
        ..nee_opts(12, 10, 32, 10, 5)
    };
    let sliced = |samples_per_dispatch| {
        let tuning = Tuning {
            samples_per_dispatch,
            max_tile_pixels: None,
        };
        render_gpu(&gpu, &scene, &opts, &tuning)
    };
    assert!(sliced(Some(1)) == sliced(Some(32)));
}

/// A tilted quad light seen obliquely from `X` (its pdf varies strongly across it).
fn tilted_quad() -> Quad {
    Quad::new(
        Vec3::new(-0.5, 1.0, -0.8),
        Vec3::new(1.2, 0.3, 0.0),
        Vec3::new(0.2, 0.4, 1.0),
        0,
    )
}

const X: Vec3 = Vec3::new(0.3, -0.2, 0.1);

/// Where a ray meets a light under test, if it does.
type LightHit = Box<dyn Fn(&Ray) -> Option<f32>>;

/// A light under test: itself, where rays from `X` meet it, and what bounds the cone of
/// directions toward it (its centre, and its rim's points or, for a sphere, its cone).
struct TestLight {
    light: Light,
    hit: LightHit,
    centre: Vec3,
    rim: Vec<Vec3>,
    /// Whether `p` lies on the light's surface.
    on_light: Box<dyn Fn(Vec3) -> bool>,
}

/// `shape` of primitive kind `kind` as the flat scene makes it a light.
fn shape_light<S: SurfaceShape + 'static>(shape: S, kind: u32) -> Light {
    let (_, light) = shape.as_light();
    Light {
        shape: LightShape::Surface { kind, light },
        cdf: 1.0,
        pick: 1.0,
    }
}

fn quad_light(quad: Quad) -> TestLight {
    TestLight {
        light: shape_light(quad, Quad::KIND),
        hit: Box::new(move |ray| hit_quad(&quad, ray, 0.0, f32::INFINITY)),
        centre: quad.q + 0.5 * (quad.u + quad.v),
        rim: vec![
            quad.q,
            quad.q + quad.u,
            quad.q + quad.v,
            quad.q + quad.u + quad.v,
        ],
        on_light: Box::new(move |p| (p - quad.q).dot(quad.normal).abs() < 1e-5),
    }
}

/// Half of `quad`: the triangle (q, q + u, q + v).
fn triangle_light(quad: Quad) -> TestLight {
    let triangle = Triangle {
        p0: quad.q,
        p1: quad.q + quad.u,
        p2: quad.q + quad.v,
        material: 0,
        light: 1,
    };
    TestLight {
        light: Light {
            shape: LightShape::Triangle {
                corner: quad.q,
                u: quad.u,
                v: quad.v,
                normal: quad.normal,
                inv_area: 2.0 / quad.u.cross(quad.v).length(),
            },
            cdf: 1.0,
            pick: 1.0,
        },
        hit: Box::new(move |ray| {
            hit_triangle(&triangle, ray, 0.0, f32::INFINITY).map(|(t, _, _)| t)
        }),
        centre: quad.q + (quad.u + quad.v) / 3.0,
        rim: vec![quad.q, quad.q + quad.u, quad.q + quad.v],
        on_light: Box::new(move |p| (p - quad.q).dot(quad.normal).abs() < 1e-5),
    }
}

fn sphere_light() -> TestLight {
    let sphere = Sphere {
        center: Vec3::new(1.0, 2.0, -1.5),
        radius: 0.6,
        material: 0,
        light: 1,
    };
    TestLight {
        light: shape_light(sphere, Sphere::KIND),
        hit: Box::new(move |ray| hit_sphere(&sphere, ray, 0.0, f32::INFINITY)),
        centre: sphere.center,
        rim: Vec::new(),
        on_light: Box::new(move |p| ((p - sphere.center).length() - sphere.radius).abs() < 1e-5),
    }
}

/// A tilted disk seen obliquely from `X`.
fn disk_light() -> TestLight {
    let disk = Disk::new(Vec3::new(0.2, 1.2, -0.4), Vec3::new(0.3, -1.0, 0.5), 0.7, 0);
    let rim = (0..256)
        .map(|i| {
            let angle = i as f32 / 256.0 * std::f32::consts::TAU;
            disk.center + disk.radius * (angle.cos() * disk.tangent + angle.sin() * disk.bitangent)
        })
        .collect();
    TestLight {
        light: shape_light(disk, Disk::KIND),
        hit: Box::new(move |ray| hit_disk(&disk, ray, 0.0, f32::INFINITY)),
        centre: disk.center,
        rim,
        on_light: Box::new(move |p| {
            (p - disk.center).dot(disk.normal).abs() < 1e-5
                && (p - disk.center).length() < disk.radius * (1.0 + 1e-5)
        }),
    }
}

/// Every kind of area light.
fn test_lights() -> [(&'static str, TestLight); 4] {
    [
        ("quad", quad_light(tilted_quad())),
        ("triangle", triangle_light(tilted_quad())),
        ("sphere", sphere_light()),
        ("disk", disk_light()),
    ]
}

/// Equal-solid-angle cells about `axis` out to 1 - cos theta = `c_max`: `n_theta` rings of
/// 1 - cos theta by `n_phi` sectors, each cell's integral a midpoint rule of `sub` x `sub`
/// points.
struct Cone {
    axis: Vec3,
    t: Vec3,
    b: Vec3,
    c_max: f64,
}

const N_THETA: usize = 24;
const N_PHI: usize = 24;
const SUB: usize = 24;

impl Cone {
    fn direction(&self, a: f64, phi: f64) -> Vec3 {
        let sin = (a * (2.0 - a)).max(0.0).sqrt();
        ((1.0 - a) as f32) * self.axis
            + (sin * phi.cos()) as f32 * self.t
            + (sin * phi.sin()) as f32 * self.b
    }
}

impl Domain for Cone {
    fn cells(&self) -> usize {
        N_THETA * N_PHI
    }

    fn cell(&self, dir: Vec3) -> Option<usize> {
        use std::f64::consts::PI;
        let a = (1.0 - self.axis.dot(dir) as f64).max(0.0); // rounding at the axis
        let phi = (dir.dot(self.b) as f64).atan2(dir.dot(self.t) as f64);
        let i = (a / self.c_max * N_THETA as f64).floor();
        if !(0.0..N_THETA as f64).contains(&i) {
            return None;
        }
        let j = (((phi + PI) / (2.0 * PI) * N_PHI as f64).floor() as usize).min(N_PHI - 1);
        Some(i as usize * N_PHI + j)
    }

    fn expected(&self, pdf: &dyn Fn(Vec3) -> f64) -> Vec<f64> {
        use std::f64::consts::PI;
        let cell_solid_angle = self.c_max * 2.0 * PI / (N_THETA * N_PHI) as f64;
        let mut expected = vec![0.0f64; N_THETA * N_PHI];
        for i in 0..N_THETA {
            for j in 0..N_PHI {
                let mut sum = 0.0;
                for si in 0..SUB {
                    for sj in 0..SUB {
                        let a = (i as f64 + (si as f64 + 0.5) / SUB as f64) / N_THETA as f64
                            * self.c_max;
                        let phi = -PI
                            + (j as f64 + (sj as f64 + 0.5) / SUB as f64) / N_PHI as f64 * 2.0 * PI;
                        sum += pdf(self.direction(a, phi));
                    }
                }
                expected[i * N_PHI + j] = sum / (SUB * SUB) as f64 * cell_solid_angle;
            }
        }
        expected
    }
}

/// Pearson's chi-square p-value of 1 000 000 directions from `sample` against `lights::pdf` for
/// `light` seen from `X` (`common::chi_square`), over a [`Cone`] of cells around the light (out
/// to 1.2 times its extent), cells expected below 5 pooled. Also checks that the pdf
/// integrates to 1 and that every direction lands in the cone.
fn chi_square_p(name: &str, test: &TestLight, sample: impl Fn(f32, f32) -> Vec3) -> f64 {
    let light = &test.light;
    let reaches = |dir: Vec3| -> Option<Vec3> {
        let ray = Ray { origin: X, dir };
        (test.hit)(&ray).map(|t| ray.at(t))
    };
    let pdf = |dir: Vec3| reaches(dir).map_or(0.0, |p| lights::pdf(light, X, p, dir)) as f64;
    let axis = (test.centre - X).normalize();
    let (t, b) = rt_gpu::shared::warp::basis(axis);
    let c_max = 1.2
        * match light.shape {
            LightShape::Surface { light: l, .. } if test.rim.is_empty() => {
                lights::sphere_cone(l.position, l.size, X)
                    .expect("outside")
                    .1 as f64
            }
            _ => test
                .rim
                .iter()
                .map(|&c| 1.0 - axis.dot((c - X).normalize()) as f64)
                .fold(0.0, f64::max),
        };
    let cone = Cone { axis, t, b, c_max };
    let expected = cone.expected(&pdf);
    let total: f64 = expected.iter().sum();
    assert!(
        (total - 1.0).abs() < 3e-3,
        "{name}: the pdf integrates to {total}"
    );
    let samples = 1_000_000u32;
    let tally = chi_square::tally(&cone, samples, |k| {
        let mut rng = rt_gpu::shared::sampler::Sampler::independent(k, 0, 77);
        Draw::Direction(sample(rng.next_f32(), rng.next_f32()))
    });
    assert!(
        tally.outside.is_empty(),
        "{name}: {:?} are outside the light's cone",
        &tally.outside[..tally.outside.len().min(3)]
    );
    let (chi2, cells, p) = chi_square::test(&tally, &expected, samples);
    eprintln!("{name}: chi2 {chi2:.1} over {cells} cells, p = {p:.3e}");
    p
}

/// Light-sampled directions follow the pdf that MIS weighs them with: a chi-square test per
/// light kind (quad, triangle, sphere, disk), each at significance 0.001 (Bonferroni: 0.004
/// for the four).
/// The pdf each sample reports must equal `lights::pdf` of its direction, and its point must be
/// on the light along that direction.
#[test]
fn light_sampling_directions_follow_their_pdf() {
    for (name, test) in test_lights() {
        let light = &test.light;
        let p = chi_square_p(name, &test, |u1, u2| {
            let s = lights::sample(light, X, u1, u2).expect("samples");
            // The point it reports is on the light, along the direction.
            assert!(
                (test.on_light)(s.point),
                "{name}: {} is not on the light",
                s.point
            );
            assert!(
                (s.point - X).normalize().dot(s.dir) > 1.0 - 1e-6,
                "{name}: point off the ray"
            );
            let expected = lights::pdf(light, X, s.point, s.dir);
            assert!(
                (s.pdf - expected).abs() <= 1e-3 * s.pdf,
                "{name}: sample says pdf {}, lights::pdf says {expected}",
                s.pdf
            );
            s.dir
        });
        assert!(
            p > 0.001,
            "{name}: directions do not follow the pdf (p = {p})"
        );
    }
}

/// Negative control: the chi-square test rejects a sampler 2% off in its first coordinate
/// (u1 -> u1^1.02) for every light kind.
#[test]
fn light_sampling_test_detects_a_slightly_wrong_warp() {
    for (name, test) in test_lights() {
        let p = chi_square_p(name, &test, |u1, u2| {
            lights::sample(&test.light, X, u1.powf(1.02), u2)
                .expect("samples")
                .dir
        });
        assert!(p < 0.001, "{name}: a wrong warp went undetected (p = {p})");
    }
}
