//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod chi_square;
#[cfg(feature = "cli")]
pub mod cli;
pub mod gltf;
pub mod gltf_mutations;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod mutate;
pub mod stats;

use glam::Vec3;
use rt_gpu::film::Film;
use rt_gpu::render::{Integrator, RenderOptions};
use rt_gpu::scene::flat::FlatScene;
use rt_gpu::scene::{
    Background, Camera, Material, Object, RenderDefaults, Scene, Shape, Transform,
};

/// Options for the naive integrator (the estimator most tests pin down); nee tests override it.
pub fn opts(width: u32, height: u32, spp: u32, max_depth: u32, seed: u32) -> RenderOptions {
    RenderOptions {
        seed,
        integrator: Integrator::Naive,
        ..RenderOptions::new(width, height, spp, max_depth)
    }
}

/// `opts` with next-event estimation.
pub fn nee_opts(width: u32, height: u32, spp: u32, max_depth: u32, seed: u32) -> RenderOptions {
    RenderOptions {
        integrator: Integrator::Nee,
        ..opts(width, height, spp, max_depth, seed)
    }
}

pub fn render_cpu(scene: &Scene, opts: &RenderOptions) -> Film {
    let flat = FlatScene::new(scene, opts.width, opts.height).expect("valid scene");
    rt_gpu::cpu::render(&flat, opts, &|| {})
}

/// How far film `b` is from film `a`: the summed absolute difference of their pixels' means over
/// `a`'s summed light (0 for equal films).
pub fn relative_difference(a: &Film, b: &Film) -> f64 {
    let (mut off, mut total) = (0.0, 0.0);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        off += (p.mean() - q.mean()).abs().element_sum();
        total += p.mean().element_sum();
    }
    off / total
}

/// The one-line error of scene file `text` (as bad.toml), which must be refused.
pub fn scene_error(text: &str) -> String {
    match rt_gpu::scene::file::parse(text, "bad.toml", "bad") {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// A hit at the origin on a surface whose shading and geometric normal are `normal`, for
/// testing materials.
pub fn surface_hit(normal: Vec3, front_face: bool) -> rt_gpu::shared::ray::Hit {
    rt_gpu::shared::ray::Hit {
        t: 1.0,
        point: Vec3::ZERO,
        error: 0.0,
        normal,
        shading: normal,
        coat: normal,
        front_face,
        material: 0,
        primitive: rt_gpu::shared::primitive::PrimitiveRef::Shape {
            kind: rt_gpu::shape::Sphere::KIND,
            index: 0,
        },
        uv: glam::Vec2::ZERO,
        uv1: glam::Vec2::ZERO,
        color: Vec3::ONE,
    }
}

pub fn object(shape: Shape, material: u32) -> Object {
    Object {
        shape,
        material,
        transform: Transform::default(),
    }
}

/// A scene with the camera at `from` looking at `at` (up +y).
pub fn scene(
    from: Vec3,
    at: Vec3,
    vfov: f32,
    background: Background,
    materials: Vec<Material>,
    objects: Vec<Object>,
) -> Scene {
    Scene {
        name: "test".into(),
        camera: Camera {
            look_from: from,
            look_at: at,
            up: Vec3::Y,
            vfov_degrees: vfov,
            aperture: 0.0,
            focus_distance: None,
        },
        background,
        material_names: (0..materials.len()).map(|i| format!("m{i}")).collect(),
        materials,
        objects,
        punctual: Vec::new(),
        inputs: Vec::new(),
        defaults: RenderDefaults {
            width: 16,
            height: 16,
            max_depth: 4,
        },
    }
}

/// Two spheres, lambertian and fuzzy metal, under a constant background: a cheap scene with
/// real variance (metal absorption, silhouettes) and no light to find.
pub fn furnace_scene() -> Scene {
    scene(
        Vec3::new(0.0, 0.0, 3.0),
        Vec3::ZERO,
        50.0,
        Background::Constant(Vec3::new(0.9, 0.8, 0.7)),
        vec![
            Material::lambertian(Vec3::new(0.6, 0.5, 0.4)),
            Material::Metal(rt_gpu::material::Metal {
                albedo: Vec3::splat(0.9).into(),
                fuzz: 0.3,
            }),
        ],
        vec![
            object(Shape::sphere(Vec3::new(-0.6, 0.0, 0.0), 0.5), 0),
            object(Shape::sphere(Vec3::new(0.6, 0.0, 0.0), 0.5), 1),
        ],
    )
}

/// The built-in Cornell box with its white albedo 2% higher: the negative control the image
/// comparisons must detect.
pub fn cornell_white_2_percent_brighter() -> Scene {
    let mut scene = rt_gpu::scene::builtin::builtin("cornell").expect("built-in");
    let white = scene
        .material_names
        .iter()
        .position(|n| n == "white")
        .expect("cornell has white");
    scene.materials[white] = Material::lambertian(Vec3::splat(0.73 * 1.02));
    scene
}

/// The triangles of parallelograms `[q, u, v]`: two each, (q, q+u, q+u+v) and (q, q+u+v, q+v),
/// both counter-clockwise about u x v.
pub fn parallelogram_mesh(
    name: &str,
    faces: &[[Vec3; 3]],
) -> std::sync::Arc<rt_gpu::scene::mesh::Mesh> {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for &[q, u, v] in faces {
        let base = positions.len() as u32;
        positions.extend([q, q + u, q + u + v, q + v]);
        triangles.push([base, base + 1, base + 2]);
        triangles.push([base, base + 2, base + 3]);
    }
    rt_gpu::scene::mesh::Mesh::new(name, positions, triangles)
        .expect("a valid mesh")
        .shared()
}

/// A UV sphere of unit radius, `rings` x `segments` quads as two triangles each (counter-clockwise
/// from outside), every vertex with its radial normal: a smooth-shaded mesh.
pub fn smooth_sphere_mesh(rings: u32, segments: u32) -> std::sync::Arc<rt_gpu::scene::mesh::Mesh> {
    let vertex = |i: u32, j: u32| {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        let phi = 2.0 * std::f32::consts::PI * j as f32 / segments as f32;
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.cos(),
            -theta.sin() * phi.sin(),
        )
    };
    let positions: Vec<Vec3> = (0..=rings)
        .flat_map(|i| (0..segments).map(move |j| vertex(i, j)))
        .collect();
    let index = |i: u32, j: u32| i * segments + j % segments;
    let mut triangles = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let [a, b, c, d] = [
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            ];
            triangles.extend([[a, b, c], [a, c, d]]);
        }
    }
    let normals = triangles
        .iter()
        .map(|t: &[u32; 3]| Some(t.map(|v| positions[v as usize])))
        .collect();
    rt_gpu::scene::mesh::Mesh::with_normals("smooth sphere", positions, triangles, normals)
        .expect("a valid mesh")
        .shared()
}

/// Adds `material` to `scene` as `name`; returns its index.
pub fn add_material(scene: &mut Scene, name: &str, material: Material) -> u32 {
    scene.materials.push(material);
    scene.material_names.push(name.into());
    scene.materials.len() as u32 - 1
}

/// Adds a brushed brass metal (fuzz 0.2) as "metal"; returns its index.
pub fn add_brushed_metal(scene: &mut Scene) -> u32 {
    let metal = rt_gpu::material::Metal {
        albedo: Vec3::new(0.8, 0.6, 0.3).into(),
        fuzz: 0.2,
    };
    add_material(scene, "metal", Material::Metal(metal))
}

/// `scene` (the Cornell box's materials) with three smooth sphere meshes of 8 x 16 facets: a
/// white ellipsoid, glass and brushed metal, so that lambertian, dielectric and metal shade
/// through interpolated normals.
pub fn with_smooth_spheres(mut scene: Scene) -> Scene {
    use rt_gpu::scene::{Shape, Transform};
    let mesh = smooth_sphere_mesh(8, 16);
    let white = scene.material_names.iter().position(|n| n == "white");
    let glass = add_material(
        &mut scene,
        "glass",
        Material::Dielectric(rt_gpu::material::Dielectric::clear(1.5)),
    );
    let metal = add_brushed_metal(&mut scene);
    for (scale, translate, material) in [
        (
            Vec3::new(120.0, 60.0, 60.0),
            Vec3::new(180.0, 60.0, 180.0),
            white.expect("white") as u32,
        ),
        (Vec3::splat(80.0), Vec3::new(380.0, 80.0, 300.0), glass),
        (Vec3::splat(70.0), Vec3::new(270.0, 330.0, 350.0), metal),
    ] {
        scene.objects.push(Object {
            shape: Shape::Mesh {
                mesh: mesh.clone(),
                scale,
            },
            material,
            transform: Transform {
                translate,
                rotate_y_degrees: 20.0,
            },
        });
    }
    scene
}

/// `scene` (the Cornell box's materials) with two meshes placed three times each with one
/// material, so that both are instanced: a box (12 flat triangles) in white, once mirrored and
/// once stretched, and a smooth sphere (8 x 16 facets, vertex normals) in brushed metal, once
/// squashed.
pub fn with_instanced_meshes(mut scene: Scene) -> Scene {
    use rt_gpu::scene::{Shape, Transform};
    let white = scene.material_names.iter().position(|n| n == "white");
    let white = white.expect("white") as u32;
    let metal = add_brushed_metal(&mut scene);
    let block = parallelogram_mesh(
        "block",
        &rt_gpu::scene::flat::box_faces(Vec3::ZERO, Vec3::ONE),
    );
    let ball = smooth_sphere_mesh(8, 16);
    let placements = [
        (
            block.clone(),
            Vec3::splat(80.0),
            Vec3::new(60.0, 0.0, 300.0),
            15.0,
            white,
        ),
        (
            block.clone(),
            Vec3::new(-70.0, 120.0, 70.0),
            Vec3::new(480.0, 0.0, 380.0),
            -20.0,
            white,
        ),
        (
            block,
            Vec3::new(100.0, 40.0, 60.0),
            Vec3::new(250.0, 0.0, 80.0),
            40.0,
            white,
        ),
        (
            ball.clone(),
            Vec3::splat(45.0),
            Vec3::new(150.0, 300.0, 250.0),
            0.0,
            metal,
        ),
        (
            ball.clone(),
            Vec3::new(70.0, 40.0, 50.0),
            Vec3::new(400.0, 250.0, 200.0),
            30.0,
            metal,
        ),
        (
            ball,
            Vec3::splat(35.0),
            Vec3::new(300.0, 450.0, 300.0),
            -10.0,
            metal,
        ),
    ];
    for (mesh, scale, translate, rotate_y_degrees, material) in placements {
        scene.objects.push(Object {
            shape: Shape::Mesh { mesh, scale },
            material,
            transform: Transform {
                translate,
                rotate_y_degrees,
            },
        });
    }
    scene
}

/// `scene` with every quad and box made of triangles (two per parallelogram): the same surfaces.
pub fn triangulated(scene: &Scene) -> Scene {
    let mut out = scene.clone();
    for o in &mut out.objects {
        let faces: Vec<[Vec3; 3]> = match o.shape {
            Shape::Surface(rt_gpu::shape::SurfaceParams::Quad(rt_gpu::shape::QuadParams {
                q,
                u,
                v,
            })) => vec![[q, u, v]],
            Shape::Cuboid { min, max } => rt_gpu::scene::flat::box_faces(min, max).to_vec(),
            _ => continue,
        };
        o.shape = Shape::Mesh {
            mesh: parallelogram_mesh("triangulated", &faces),
            scale: Vec3::ONE,
        };
    }
    out
}

/// `scenes/disks.toml`: the Cornell box with a tilted one-sided disk lamp under its ceiling
/// (light-sampled uniformly on its area) and a tilted disk of a UV checker standing in it (its
/// polar texture coordinates), both seen from front and back.
pub fn cornell_with_disks() -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/disks.toml");
    rt_gpu::scene::file::load(&path).expect("scenes/disks.toml")
}

/// `scene` renders the same estimator every way: naive against nee on the CPU, the GPU against
/// the CPU with nee (Welch z + Sidak at family-wise 0.01, tests/it/common/stats.rs; 24x18 at
/// 4 096 and 2 048 spp); and the negative control `changed` on the GPU is told apart. Returns
/// the CPU's nee film.
pub fn renders_alike_every_way(
    label: &str,
    scene: &Scene,
    changed: impl FnOnce() -> Scene,
) -> rt_gpu::film::Film {
    use crate::common::stats::compare;
    let naive = render_cpu(scene, &opts(24, 18, 4096, 5, 1));
    let nee = render_cpu(scene, &nee_opts(24, 18, 2048, 5, 2));
    let verdict = compare(&naive, &nee);
    eprintln!("{label}, naive vs nee: {verdict:?}");
    assert!(verdict.passed(), "{label}: {verdict:?}");
    #[cfg(feature = "gpu")]
    {
        use crate::common::gpu::{render_gpu, renderer};
        let Some(gpu) = renderer() else { return nee };
        let tuning = rt_gpu::gpu::Tuning::default();
        let opts = nee_opts(24, 18, 2048, 5, 3);
        let verdict = compare(&nee, &render_gpu(&gpu, scene, &opts, &tuning));
        eprintln!("{label}, cpu vs gpu: {verdict:?}");
        assert!(verdict.passed(), "{label}: {verdict:?}");
        let verdict = compare(&nee, &render_gpu(&gpu, &changed(), &opts, &tuning));
        eprintln!("{label}, the negative control on the gpu: {verdict:?}");
        assert!(
            !verdict.passed(),
            "{label}: the negative control went undetected"
        );
    }
    #[cfg(not(feature = "gpu"))]
    let _ = changed;
    nee
}
