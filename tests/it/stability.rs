//! Numerical stability on stiff and extreme cases, on both backends: exact-parallel, tangent and
//! edge rays, watertight boxes, scenes scaled over eight orders of magnitude and moved up to
//! 9.9e7 from the origin, extreme glass, energy conservation, tiny bright lights, extreme cameras and image
//! shapes, and long accumulations. Every image here is also checked for NaN and infinity.
//!
//! Image comparisons use the equivalence test of tests/it/common/stats.rs (family-wise alpha 0.01,
//! Sidak-corrected over every pixel, block and channel; its negative controls are in
//! tests/it/gpu_equivalence.rs and tests/it/nee.rs).
#![cfg_attr(not(feature = "gpu"), allow(unused))]

use crate::common;

#[cfg(feature = "gpu")]
use common::gpu::{render_gpu, renderer};
use common::stats::compare;
use common::{nee_opts, object, render_cpu, scene, triangulated};
use glam::Vec3;
use rt_gpu::cpu::intersect::intersect;
use rt_gpu::film::Film;
#[cfg(feature = "gpu")]
use rt_gpu::gpu::{GpuRenderer, Tuning};
use rt_gpu::render::RenderOptions;
use rt_gpu::scene::builtin::builtin;
use rt_gpu::scene::flat::FlatScene;
use rt_gpu::scene::{Background, Material, Scene, Shape, Transform};
use rt_gpu::shape::{DiskParams, QuadParams, SphereParams, SurfaceParams};
use rt_gpu::shared::ray::Ray;

fn assert_finite(name: &str, film: &Film) {
    assert_eq!(film.invalid_samples, 0, "{name}: NaN or infinite samples");
    assert!(
        film.pixels
            .iter()
            .all(|p| p.mean().is_finite() && p.m2.is_finite() && p.mean().min_element() >= 0.0),
        "{name}: a pixel is not finite and non-negative"
    );
}

#[cfg(feature = "gpu")]
/// CPU and GPU renders (independent seeds) are finite and statistically equal.
fn cpu_matches_gpu(name: &str, gpu: Option<&GpuRenderer>, scene: &Scene, opts: &RenderOptions) {
    let cpu = render_cpu(scene, opts);
    assert_finite(&format!("{name} (cpu)"), &cpu);
    if let Some(gpu) = gpu {
        let other = RenderOptions {
            seed: opts.seed + 100,
            ..*opts
        };
        let g = render_gpu(gpu, scene, &other, &Tuning::default());
        assert_finite(&format!("{name} (gpu)"), &g);
        let verdict = compare(&cpu, &g);
        eprintln!("{name}: cpu vs gpu {verdict:?}");
        assert!(verdict.passed(), "{name}: CPU and GPU differ: {verdict:?}");
    }
}

#[cfg(feature = "gpu")]
/// Closest hits of `rays` on both backends: (hit, point) per ray, CPU first.
fn trace_both(
    gpu: Option<&GpuRenderer>,
    flat: &FlatScene,
    rays: &[(Vec3, Vec3)],
) -> (Vec<Option<Vec3>>, Option<Vec<Option<Vec3>>>) {
    let cpu = rays
        .iter()
        .map(|&(origin, dir)| intersect(flat, &Ray { origin, dir }).map(|h| h.point))
        .collect();
    let gpu = gpu.map(|g| {
        g.trace_rays(flat, rays)
            .expect("trace kernel runs")
            .iter()
            .map(|b| (b.hit == 1).then(|| Vec3::from(b.point)))
            .collect()
    });
    (cpu, gpu)
}

fn unit_box(rotate_y_degrees: f32, translate: Vec3) -> Scene {
    let mut s = scene(
        Vec3::new(0.0, 0.0, 5.0),
        Vec3::ZERO,
        40.0,
        Background::Constant(Vec3::ONE),
        vec![Material::lambertian(Vec3::splat(0.5))],
        vec![object(
            Shape::Cuboid {
                min: Vec3::ZERO,
                max: Vec3::ONE,
            },
            0,
        )],
    );
    s.objects[0].transform = Transform {
        rotate_y_degrees,
        translate,
    };
    s
}

#[cfg(feature = "gpu")]
/// Rays exactly parallel to box faces (direction components +0 and -0), rays in a face's plane,
/// tangent to a sphere, and through box edges and corners: no NaN, no invented hits, and the
/// same answers on both backends.
#[test]
fn parallel_tangent_and_edge_rays() {
    let gpu = renderer();
    let mut s = unit_box(0.0, Vec3::ZERO);
    s.objects
        .push(object(Shape::sphere(Vec3::new(5.0, 0.0, 0.0), 1.0), 0));
    let flat = FlatScene::new(&s, 8, 8).expect("valid");
    let x = Vec3::X;
    let cases: Vec<(&str, Vec3, Vec3, Option<Vec3>)> = vec![
        // (what, origin, direction, expected hit point or None for a miss)
        (
            "+x, zeros +0",
            Vec3::new(-1.0, 0.5, 0.5),
            Vec3::new(1.0, 0.0, 0.0),
            Some(Vec3::new(0.0, 0.5, 0.5)),
        ),
        (
            "+x, zeros -0",
            Vec3::new(-1.0, 0.5, 0.5),
            Vec3::new(1.0, -0.0, -0.0),
            Some(Vec3::new(0.0, 0.5, 0.5)),
        ),
        (
            "-y, zeros -0",
            Vec3::new(0.5, 3.0, 0.5),
            Vec3::new(-0.0, -1.0, -0.0),
            Some(Vec3::new(0.5, 1.0, 0.5)),
        ),
        (
            "above the top face, parallel",
            Vec3::new(-1.0, 1.5, 0.5),
            x,
            None,
        ),
        (
            "beside the box, parallel",
            Vec3::new(2.0, 0.5, -0.25),
            -x,
            None,
        ),
        (
            "in the plane of the top face, above nothing",
            Vec3::new(3.0, 1.0, 0.5),
            x,
            None,
        ),
        (
            "tangent to the sphere, just outside",
            Vec3::new(5.0, 1.0001, -5.0),
            Vec3::Z,
            None,
        ),
        (
            "through the corner (1, 1, 1)",
            Vec3::new(2.0, 2.0, 2.0),
            -Vec3::ONE.normalize(),
            Some(Vec3::ONE),
        ),
        (
            "through the edge y = 1, z = 1",
            Vec3::new(0.5, 2.0, 2.0),
            Vec3::new(0.0, -1.0, -1.0).normalize(),
            Some(Vec3::new(0.5, 1.0, 1.0)),
        ),
    ];
    let rays: Vec<(Vec3, Vec3)> = cases.iter().map(|c| (c.1, c.2)).collect();
    let (cpu, gpu_hits) = trace_both(gpu.as_ref(), &flat, &rays);
    for (i, (what, _, _, expected)) in cases.iter().enumerate() {
        let backends = [Some(("cpu", &cpu)), gpu_hits.as_ref().map(|g| ("gpu", g))];
        for (backend, hits) in backends.into_iter().flatten() {
            match (expected, hits[i]) {
                (None, None) => {}
                (Some(e), Some(p)) => assert!(
                    p.is_finite() && (p - *e).length() < 1e-5,
                    "{backend}: {what}: hit {p}, expected {e}"
                ),
                (e, p) => panic!("{backend}: {what}: hit {p:?}, expected {e:?}"),
            }
        }
    }
    // Exactly tangent: a hit or a miss is fine, but a hit is on the sphere.
    let tangent = [(Vec3::new(5.0, 1.0, -5.0), Vec3::Z)];
    let (cpu, gpu_hits) = trace_both(gpu.as_ref(), &flat, &tangent);
    for p in cpu.iter().chain(gpu_hits.iter().flatten()).flatten() {
        assert!(
            ((*p - Vec3::new(5.0, 0.0, 0.0)).length() - 1.0).abs() < 1e-4,
            "{p}"
        );
    }
}

#[cfg(feature = "gpu")]
/// Rays from inside closed boxes (axis-aligned, and rotated and moved far away) aimed at their
/// edges and corners, and a hair to either side, never escape: boxes of six quads, and the same
/// boxes as 12-triangle meshes (watertight triangles, through the BVH), whose every face
/// diagonal is an edge between two triangles too, copied into the scene or instanced (the rays
/// transformed into the mesh's coordinates).
#[test]
fn closed_boxes_are_watertight() {
    let gpu = renderer();
    let (quads, mesh, instanced) = (0, 1, 2);
    for (name, angle, offset, kind) in [
        ("axis-aligned", 0.0, Vec3::ZERO, quads),
        ("rotated 30 degrees", 30.0, Vec3::new(0.3, -0.2, 0.1), quads),
        ("rotated, 1e4 away", 37.0, Vec3::new(1e4, -2e4, 5e3), quads),
        ("mesh, axis-aligned", 0.0, Vec3::ZERO, mesh),
        (
            "mesh, rotated 30 degrees",
            30.0,
            Vec3::new(0.3, -0.2, 0.1),
            mesh,
        ),
        (
            "mesh, rotated, 1e4 away",
            37.0,
            Vec3::new(1e4, -2e4, 5e3),
            mesh,
        ),
        (
            "instanced mesh, rotated 30 degrees",
            30.0,
            Vec3::new(0.3, -0.2, 0.1),
            instanced,
        ),
        (
            "instanced mesh, rotated, 1e4 away",
            37.0,
            Vec3::new(1e4, -2e4, 5e3),
            instanced,
        ),
    ] {
        let s = unit_box(angle, offset);
        let mut s = if kind == quads { s } else { triangulated(&s) };
        if kind == instanced {
            // The same mesh placed a second time beside it: both become instances.
            let mut beside = s.objects[0].clone();
            beside.transform.translate += Vec3::new(3.0, 0.0, 0.0);
            s.objects.push(beside);
        }
        let mesh = kind != quads;
        let flat = FlatScene::new(&s, 8, 8).expect("valid");
        assert_eq!(flat.instances.len(), if kind == instanced { 2 } else { 0 });
        let t = s.objects[0].transform;
        let mut rays = Vec::new();
        let corners: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        let mut targets = corners.clone();
        // Points along every edge.
        for &a in &corners {
            for &b in &corners {
                if (a - b).length() == 1.0 && a.to_array() < b.to_array() {
                    for k in 0..=40 {
                        targets.push(a.lerp(b, k as f32 / 40.0));
                    }
                }
            }
        }
        // Points along the face diagonals: edges between a mesh's triangles.
        if mesh {
            for [q, u, v] in rt_gpu::scene::flat::box_faces(Vec3::ZERO, Vec3::ONE) {
                for k in 0..=40 {
                    targets.push(q + (u + v) * (k as f32 / 40.0));
                }
            }
        }
        let origins = [
            Vec3::splat(0.5),
            Vec3::new(0.2, 0.7, 0.4),
            Vec3::new(0.9, 0.1, 0.85),
        ];
        for &o in &origins {
            for &target in &targets {
                for nudge in [
                    Vec3::ZERO,
                    Vec3::splat(1e-7),
                    Vec3::splat(-1e-7),
                    Vec3::new(1e-7, -1e-7, 0.0),
                ] {
                    let origin = t.apply_point(o);
                    let dir = (t.apply_point(target + nudge) - origin).normalize();
                    rays.push((origin, dir));
                }
            }
        }
        let (cpu, gpu) = trace_both(gpu.as_ref(), &flat, &rays);
        let cpu_leaks = cpu.iter().filter(|h| h.is_none()).count();
        assert_eq!(
            cpu_leaks,
            0,
            "{name}: {cpu_leaks} of {} rays escape on the CPU",
            rays.len()
        );
        if let Some(gpu) = gpu {
            let leaks = gpu.iter().filter(|h| h.is_none()).count();
            assert_eq!(
                leaks,
                0,
                "{name}: {leaks} of {} rays escape on the GPU",
                rays.len()
            );
        }
    }
}

/// `scene` scaled by `s` about the origin, then moved by `offset`: the same picture.
fn scaled(scene: &Scene, s: f32, offset: Vec3) -> Scene {
    let mut out = scene.clone();
    for o in &mut out.objects {
        o.shape = match o.shape.clone() {
            Shape::Surface(SurfaceParams::Sphere(SphereParams { center, radius })) => {
                Shape::sphere(center * s, radius * s)
            }
            Shape::Surface(SurfaceParams::Quad(QuadParams { q, u, v })) => {
                Shape::quad(q * s, u * s, v * s)
            }
            Shape::Surface(SurfaceParams::Disk(d)) => {
                Shape::Surface(SurfaceParams::Disk(DiskParams {
                    center: d.center * s,
                    radius: d.radius * s,
                    ..d
                }))
            }
            Shape::Cuboid { min, max } => Shape::Cuboid {
                min: min * s,
                max: max * s,
            },
            Shape::Mesh { mesh, scale } => Shape::Mesh {
                mesh,
                scale: scale * s,
            },
        };
        o.transform.translate = o.transform.translate * s + offset;
    }
    out.camera.look_from = out.camera.look_from * s + offset;
    out.camera.look_at = out.camera.look_at * s + offset;
    out.camera.focus_distance = out.camera.focus_distance.map(|d| d * s);
    out.camera.aperture *= s;
    out
}

#[cfg(feature = "gpu")]
/// The Cornell box (and the spheres scene, with its huge ground sphere) scaled by 1e-4, 1 and
/// 1e4, and moved 1e5 from the origin, renders the image of the unscaled scene up to noise on
/// both backends: ray origins leave surfaces by an offset that scales with their coordinates,
/// so there is no acne and no light leaks at box edges.
#[test]
fn cornell_box_renders_the_same_at_every_scale() {
    let gpu = renderer();
    for scene_name in ["cornell", "spheres"] {
        same_at_every_scale(gpu.as_ref(), scene_name);
    }
}

#[cfg(feature = "gpu")]
/// Moving far only for the Cornell box, whose coordinates are integers that f32 still holds
/// exactly 1e7 away (and, scaled by 8, 9.9e7 away, where f32 steps are 8): the spheres scene's
/// coordinates cannot even be written there. Rendering is camera-relative (FlatScene::origin),
/// so the far boxes keep the precision of the near one (before that, 1e7 away was ~17%
/// brighter).
fn same_at_every_scale(gpu: Option<&GpuRenderer>, scene_name: &str) {
    let original = builtin(scene_name).expect("built-in");
    let opts = nee_opts(16, 16, 4096, 10, 1);
    let reference = render_cpu(&original, &opts);
    let cases = [
        ("scale 1e-4", 1e-4, Vec3::ZERO),
        ("scale 1", 1.0, Vec3::ZERO),
        ("scale 1e4", 1e4, Vec3::ZERO),
        ("moved 1e5 away", 1.0, Vec3::new(1e5, 1e5, -1e5)),
        ("moved 1e7 away", 1.0, Vec3::new(1e7, 1e7, -1e7)),
        (
            "scaled 8, moved 9.9e7 away",
            8.0,
            Vec3::new(9.9e7, -9.9e7, 9.9e7),
        ),
    ];
    let count = if scene_name == "cornell" { 6 } else { 3 };
    for (name, s, offset) in cases.into_iter().take(count) {
        let moved = scaled(&original, s, offset);
        let mut films = vec![(
            "cpu",
            render_cpu(&moved, &RenderOptions { seed: 2, ..opts }),
        )];
        if let Some(g) = gpu {
            let film = render_gpu(
                g,
                &moved,
                &RenderOptions { seed: 3, ..opts },
                &Tuning::default(),
            );
            films.push(("gpu", film));
        }
        for (backend, film) in films {
            assert_finite(name, &film);
            let verdict = compare(&reference, &film);
            eprintln!("{scene_name} {name} ({backend}) vs unscaled: {verdict:?}");
            assert!(
                verdict.passed(),
                "{scene_name} {name} ({backend}) differs from the unscaled scene: {verdict:?}"
            );
        }
    }
}

fn with_glass_ior(scene: &Scene, ior: f32) -> Scene {
    let mut out = scene.clone();
    for m in &mut out.materials {
        if let Material::Dielectric(_) = m {
            *m = Material::Dielectric(rt_gpu::material::Dielectric::clear(ior));
        }
    }
    out
}

#[cfg(feature = "gpu")]
/// A glass sphere of ior 1.0 bends nothing and reflects nothing: the Cornell box renders as if it
/// were not there, on both backends.
#[test]
fn glass_of_index_one_vanishes() {
    let gpu = renderer();
    let cornell = builtin("cornell").expect("built-in");
    let mut without = cornell.clone();
    without
        .objects
        .retain(|o| !matches!(o.shape, Shape::Surface(SurfaceParams::Sphere(_))));
    assert_eq!(without.objects.len() + 1, cornell.objects.len());
    let invisible = with_glass_ior(&cornell, 1.0);
    let opts = nee_opts(16, 16, 4096, 10, 1);
    let reference = render_cpu(&without, &opts);
    let mut films = vec![(
        "cpu",
        render_cpu(&invisible, &RenderOptions { seed: 2, ..opts }),
    )];
    if let Some(g) = &gpu {
        let film = render_gpu(
            g,
            &invisible,
            &RenderOptions { seed: 3, ..opts },
            &Tuning::default(),
        );
        films.push(("gpu", film));
    }
    for (backend, film) in films {
        assert_finite("ior 1", &film);
        let verdict = compare(&reference, &film);
        eprintln!("ior 1 ({backend}) vs no sphere: {verdict:?}");
        assert!(
            verdict.passed(),
            "ior 1 sphere visible on {backend}: {verdict:?}"
        );
    }
}

#[cfg(feature = "gpu")]
/// Glass of ior 1.0001 (nearly invisible), 2.42 (diamond) and 10 (almost a mirror, strong total
/// internal reflection); a camera inside a glass sphere; a hollow air bubble inside glass: finite,
/// and the same on both backends.
#[test]
fn extreme_glass_is_finite_and_agrees() {
    let gpu = renderer();
    let spheres = builtin("spheres").expect("built-in");
    let opts = nee_opts(24, 24, 256, 10, 1);
    for ior in [1.0001, 2.42, 10.0] {
        cpu_matches_gpu(
            &format!("ior {ior}"),
            gpu.as_ref(),
            &with_glass_ior(&spheres, ior),
            &opts,
        );
    }
    let materials = vec![
        Material::Dielectric(rt_gpu::material::Dielectric::clear(1.5)),
        Material::lambertian(Vec3::new(0.8, 0.3, 0.2)),
    ];
    let sphere =
        |center: Vec3, radius: f32, material: u32| object(Shape::sphere(center, radius), material);
    let inside = scene(
        Vec3::ZERO,
        Vec3::new(0.0, 0.0, -1.0),
        70.0,
        Background::Sky,
        materials.clone(),
        vec![
            sphere(Vec3::ZERO, 2.0, 0),
            sphere(Vec3::new(0.0, 0.0, -4.0), 1.0, 1),
        ],
    );
    cpu_matches_gpu("camera inside glass", gpu.as_ref(), &inside, &opts);
    let bubble = scene(
        Vec3::new(0.0, 0.0, 4.0),
        Vec3::ZERO,
        35.0,
        Background::Sky,
        materials,
        vec![
            sphere(Vec3::ZERO, 1.0, 0),
            sphere(Vec3::new(0.2, 0.1, 0.0), -0.5, 0),
            sphere(Vec3::new(0.0, -101.0, 0.0), 100.0, 1),
        ],
    );
    cpu_matches_gpu("air bubble in glass", gpu.as_ref(), &bubble, &opts);
}

/// Every material's scattering, for incoming directions from head-on to 1e-7 from grazing, on
/// both faces: throughput finite and in [0, 1], directions finite unit vectors; glass at grazing
/// incidence from inside reflects totally.
#[test]
fn scattering_keeps_throughput_finite_and_non_negative() {
    use rt_gpu::shared::ray::Hit;
    let materials = [
        Material::lambertian(Vec3::ONE),
        Material::Metal(rt_gpu::material::Metal {
            albedo: Vec3::ONE.into(),
            fuzz: 0.0,
        }),
        Material::Metal(rt_gpu::material::Metal {
            albedo: Vec3::ONE.into(),
            fuzz: 0.5,
        }),
        Material::Metal(rt_gpu::material::Metal {
            albedo: Vec3::ONE.into(),
            fuzz: 1.0,
        }),
        Material::Dielectric(rt_gpu::material::Dielectric::clear(1.0)),
        Material::Dielectric(rt_gpu::material::Dielectric::clear(1.0001)),
        Material::Dielectric(rt_gpu::material::Dielectric::clear(1.5)),
        Material::Dielectric(rt_gpu::material::Dielectric::clear(2.42)),
        Material::Dielectric(rt_gpu::material::Dielectric::clear(10.0)),
        Material::Conductor(rt_gpu::material::Conductor::metal("Au", 0.0).expect("known")),
        Material::Conductor(rt_gpu::material::Conductor::metal("Au", 0.005).expect("known")),
        Material::Conductor(rt_gpu::material::Conductor::metal("Au", 0.01).expect("known")),
        Material::Conductor(rt_gpu::material::Conductor::metal("Au", 0.3).expect("known")),
        Material::Conductor(rt_gpu::material::Conductor::metal("Au", 1.0).expect("known")),
    ];
    let normal = Vec3::new(0.3, 0.8, -0.52).normalize();
    let (t, _) = rt_gpu::shared::warp::basis(normal);
    let mut checked = 0;
    for m in &materials {
        for front_face in [true, false] {
            for cos in [1.0f32, 0.5, 1e-2, 1e-4, 1e-7, 0.0] {
                let sin = (1.0 - cos * cos).max(0.0).sqrt();
                let dir_in = (-cos * normal + sin * t).normalize();
                let hit = Hit {
                    point: Vec3::new(1e4, -3.0, 0.25),
                    ..common::surface_hit(normal, front_face)
                };
                for k in 0..200 {
                    let mut rng = rt_gpu::shared::sampler::Sampler::independent(k, 0, 5);
                    if let Some(s) = m.sample(-dir_in, &hit, &mut rng) {
                        let (attenuation, dir) = (s.weight, s.wi);
                        assert!(s.pdf.is_finite() && s.pdf >= 0.0, "{m:?}: pdf {}", s.pdf);
                        assert!(
                            attenuation.is_finite()
                                && attenuation.min_element() >= 0.0
                                && attenuation.max_element() <= 1.0,
                            "{m:?}: throughput {attenuation}"
                        );
                        assert!(
                            dir.is_finite() && (dir.length() - 1.0).abs() < 1e-5,
                            "{m:?}: direction {dir}"
                        );
                        checked += 1;
                    }
                }
            }
        }
    }
    assert!(checked > 10_000);
    // Total internal reflection: from inside glass (back face) at grazing incidence.
    let hit = common::surface_hit(Vec3::Y, false);
    let dir_in = Vec3::new(1.0, -1e-3, 0.0).normalize();
    for k in 0..100 {
        let mut rng = rt_gpu::shared::sampler::Sampler::independent(k, 0, 6);
        let dir = (Material::Dielectric(rt_gpu::material::Dielectric::clear(1.5)))
            .sample(-dir_in, &hit, &mut rng)
            .expect("glass always scatters")
            .wi;
        assert!(
            dir.y > 0.0,
            "grazing light inside glass must reflect back in: {dir}"
        );
    }
}

#[cfg(feature = "gpu")]
/// Closed furnaces never gain energy. Inside a closed sphere that is lambertian with albedo 1 and
/// emits E, every path segment adds exactly E: naive samples are exactly depth * E, and nee's
/// means are depth * E within their noise. Inside a closed mirror-like metal sphere (albedo 1,
/// fuzz 0.3) around a small emitter, no pixel exceeds depth * E.
#[test]
fn closed_furnaces_never_gain_energy() {
    let gpu = renderer();
    let e = 0.25;
    let depth = 6;
    let white_glow = Material::Lambertian(rt_gpu::material::Lambertian {
        albedo: Vec3::ONE.into(),
        emission: Vec3::splat(e),
        normal_map: None,
    });
    let sphere =
        |center: Vec3, radius: f32, material: u32| object(Shape::sphere(center, radius), material);
    let furnace = scene(
        Vec3::ZERO,
        Vec3::new(0.0, 0.0, -1.0),
        90.0,
        Background::Constant(Vec3::ZERO),
        vec![white_glow.clone()],
        vec![sphere(Vec3::ZERO, 1.0, 0)],
    );
    let mirror = scene(
        Vec3::new(0.0, 0.0, 0.5),
        Vec3::new(0.0, 0.0, -1.0),
        90.0,
        Background::Constant(Vec3::ZERO),
        vec![
            white_glow.clone(),
            Material::Metal(rt_gpu::material::Metal {
                albedo: Vec3::ONE.into(),
                fuzz: 0.3,
            }),
        ],
        vec![sphere(Vec3::ZERO, 0.2, 0), sphere(Vec3::ZERO, 2.0, 1)],
    );
    let limit = depth as f64 * e as f64;
    for integrator_opts in [
        common::opts(8, 8, 256, depth, 1),
        nee_opts(8, 8, 256, depth, 1),
    ] {
        let mut films = vec![(
            "cpu",
            render_cpu(&furnace, &integrator_opts),
            render_cpu(&mirror, &integrator_opts),
        )];
        if let Some(g) = &gpu {
            films.push((
                "gpu",
                render_gpu(g, &furnace, &integrator_opts, &Tuning::default()),
                render_gpu(g, &mirror, &integrator_opts, &Tuning::default()),
            ));
        }
        let what = format!("{:?}", integrator_opts.integrator);
        for (backend, closed, mirrored) in films {
            assert_finite(&what, &closed);
            assert_finite(&what, &mirrored);
            for p in &closed.pixels {
                let sigma = p.variance_of_mean().max_element().sqrt();
                for c in 0..3 {
                    assert!(
                        (p.mean()[c] - limit).abs() <= 1e-5 * limit + 5.0 * sigma,
                        "{backend} {what}: furnace pixel {} vs {limit}",
                        p.mean()[c]
                    );
                }
            }
            for p in &mirrored.pixels {
                assert!(
                    p.mean().max_element() <= limit * (1.0 + 1e-5),
                    "{backend} {what}: mirror furnace pixel {:?} exceeds {limit}",
                    p.mean()
                );
            }
        }
    }
}

#[cfg(feature = "gpu")]
/// A tiny, very bright light (area 1e-6, radiance 1e8) one unit above a lambertian floor: finite
/// images whose mean matches the closed form, (albedo / pi) L A h^2 / d^4 averaged over the floor
/// each pixel sees, within 4 standard errors (plus 0.2% for the quadrature); and a quad light seen
/// exactly edge-on, finite and equal on both backends.
#[test]
fn tiny_bright_lights_and_edge_on_lights() {
    let gpu = renderer();
    let (albedo, radiance, side, height) = (0.5f32, 1e8f32, 1e-3f32, 1.0f32);
    let lit_floor = scene(
        Vec3::new(0.0, 3.0, 0.0),
        Vec3::ZERO,
        60.0,
        Background::Constant(Vec3::ZERO),
        vec![
            Material::lambertian(Vec3::splat(albedo)),
            Material::Light(rt_gpu::material::Light {
                radiance: Vec3::splat(radiance).into(),
                strength: 1.0,
                two_sided: false,
                alpha: None,
            }),
        ],
        vec![
            object(
                Shape::quad(
                    Vec3::new(-2.0, 0.0, -2.0),
                    Vec3::new(0.0, 0.0, 4.0),
                    Vec3::new(4.0, 0.0, 0.0),
                ),
                0,
            ),
            // Facing down: u x v = -y.
            object(
                Shape::quad(
                    Vec3::new(-side / 2.0, height, -side / 2.0),
                    Vec3::new(side, 0.0, 0.0),
                    Vec3::new(0.0, 0.0, side),
                ),
                1,
            ),
        ],
    );
    let mut lit_floor = lit_floor;
    lit_floor.camera.up = Vec3::new(0.0, 0.0, -1.0);
    let opts = nee_opts(16, 16, 256, 4, 1);
    // The closed form, averaged over a 64x64 grid per pixel of where camera rays meet the floor.
    let flat = FlatScene::new(&lit_floor, opts.width, opts.height).expect("valid");
    let cam = flat.camera;
    let n = 64 * opts.width;
    let mut expected = 0.0f64;
    for j in 0..n {
        for i in 0..n {
            let s = (i as f32 + 0.5) / n as f32;
            let t = (j as f32 + 0.5) / n as f32;
            let dir = (cam.to_upper_left + s * cam.horizontal - t * cam.vertical).normalize();
            let p = cam.origin + dir * (-cam.origin.y / dir.y);
            let d2 = (p.x * p.x + p.z * p.z + height * height) as f64;
            expected += (albedo / std::f32::consts::PI) as f64
                * radiance as f64
                * (side * side) as f64
                * (height * height) as f64
                / (d2 * d2);
        }
    }
    expected /= (n * n) as f64;
    let mut films = vec![("cpu", render_cpu(&lit_floor, &opts))];
    if let Some(g) = &gpu {
        films.push(("gpu", render_gpu(g, &lit_floor, &opts, &Tuning::default())));
    }
    for (backend, film) in films {
        assert_finite("tiny light", &film);
        let pixels = film.pixels.len() as f64;
        let mean = film.pixels.iter().map(|p| p.mean().x).sum::<f64>() / pixels;
        let sigma = (film
            .pixels
            .iter()
            .map(|p| p.variance_of_mean().x)
            .sum::<f64>())
        .sqrt()
            / pixels;
        eprintln!(
            "tiny light ({backend}): mean {mean:.5} vs closed form {expected:.5} (sigma {sigma:.1e})"
        );
        assert!(
            (mean - expected).abs() <= 4.0 * sigma + 2e-3 * expected,
            "{backend}: tiny light mean {mean} vs closed form {expected} (sigma {sigma})"
        );
    }

    // The camera in the plane of a quad light: rays along the plane never hit it.
    let mut edge_on = builtin("cornell").expect("built-in");
    edge_on.camera.look_from = Vec3::new(278.0, 554.0, -800.0);
    edge_on.camera.look_at = Vec3::new(278.0, 554.0, 0.0);
    cpu_matches_gpu(
        "edge-on light",
        gpu.as_ref(),
        &edge_on,
        &nee_opts(16, 16, 1024, 10, 4),
    );
}

#[cfg(feature = "gpu")]
/// Fields of view of 0.01 and 179 degrees, and 1x4096 and 4096x1 images: finite and equal on
/// both backends. A camera with no direction, or with `up` along it, is a clear error.
#[test]
fn extreme_cameras_and_image_shapes() {
    let gpu = renderer();
    let cornell = builtin("cornell").expect("built-in");
    for fov in [0.01, 179.0] {
        let mut s = cornell.clone();
        s.camera.vfov_degrees = fov;
        cpu_matches_gpu(
            &format!("fov {fov}"),
            gpu.as_ref(),
            &s,
            &nee_opts(16, 16, 512, 10, 2),
        );
    }
    for (w, h) in [(1, 4096), (4096, 1)] {
        cpu_matches_gpu(
            &format!("{w}x{h}"),
            gpu.as_ref(),
            &cornell,
            &nee_opts(w, h, 32, 10, 3),
        );
    }
    let mut blind = cornell.clone();
    blind.camera.look_at = blind.camera.look_from;
    let err = FlatScene::new(&blind, 8, 8).expect_err("no direction");
    assert!(
        err.to_string().contains("look_from equals look_at"),
        "{err}"
    );
    let mut tilted = cornell.clone();
    tilted.camera.up = Vec3::new(0.0, 0.0, 2.0);
    let err = FlatScene::new(&tilted, 8, 8).expect_err("up along the view");
    assert!(err.to_string().contains("parallel"), "{err}");
}

#[cfg(feature = "gpu")]
/// A million samples per pixel accumulate on the GPU as accurately as in the CPU's f64 film.
/// The scene is smooth in its random numbers (a lambertian sphere filling the view under a sky,
/// max depth 2), so each sample agrees between backends to ~1e-6 relative and nearly all of that
/// averages out; what remains is accumulation error. The kernel sums samples exactly
/// (film.wgsl), so none is left but the samples' own differences; the bound is one f32 unit in
/// the last place, 2^-23 ~ 1.2e-7 relative (an uncompensated f32 mean would drift about
/// sqrt(1e6) ulps, ~1e-4).
#[test]
fn a_million_samples_accumulate_accurately() {
    let Some(gpu) = renderer() else { return };
    let sky_sphere = scene(
        Vec3::new(0.0, 0.0, 3.0),
        Vec3::ZERO,
        5.0,
        Background::Sky,
        vec![Material::lambertian(Vec3::new(0.7, 0.6, 0.5))],
        vec![object(Shape::sphere(Vec3::ZERO, 1.0), 0)],
    );
    let opts = common::opts(2, 2, 1_000_000, 2, 4);
    let cpu = render_cpu(&sky_sphere, &opts);
    let g = render_gpu(&gpu, &sky_sphere, &opts, &Tuning::default());
    assert_finite("1e6 spp", &g);
    for (c, g) in cpu.pixels.iter().zip(&g.pixels) {
        let relative = ((c.mean() - g.mean()).abs() / c.mean()).max_element();
        eprintln!("1e6 spp: GPU vs CPU mean, largest relative difference {relative:.2e}");
        assert!(
            relative < 1.2e-7,
            "GPU mean {:?} vs CPU {:?}: {relative:e}",
            g.mean(),
            c.mean()
        );
    }
}
