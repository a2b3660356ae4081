//! Meshes placed more than once are instanced (`scene::flat::Instance`: stored once, a BVH of
//! their own, rays transformed into mesh coordinates): they are built once, and they give the
//! hits and images of the same meshes copied into the scene, on the CPU and on the GPU. Images
//! are compared by Welch z + Sidak at family-wise 0.01 (tests/it/common/stats.rs), each test with
//! a negative control (2% brighter white) that it detects. The shipped `scenes/knots.toml` is
//! instanced.
#![cfg_attr(not(feature = "gpu"), allow(unused))]

use crate::common;

#[cfg(feature = "gpu")]
use common::gpu::{render_gpu, renderer};
use common::stats::compare;
use glam::Vec3;
use rt_gpu::accel::Bvh;
use rt_gpu::cpu::intersect::intersect;
#[cfg(feature = "gpu")]
use rt_gpu::gpu::Tuning;
use rt_gpu::render::RenderOptions;
use rt_gpu::scene::builtin::builtin;
use rt_gpu::scene::flat::FlatScene;
use rt_gpu::scene::{Scene, Shape};
use rt_gpu::shared::primitive::PrimitiveRef;
use rt_gpu::shared::ray::Ray;

fn instanced_scene() -> Scene {
    common::with_instanced_meshes(builtin("cornell").expect("built-in"))
}

fn render_cpu_flat(flat: &FlatScene, opts: &RenderOptions) -> rt_gpu::film::Film {
    rt_gpu::cpu::render(flat, opts, &|| {})
}

/// The packed primitives in the leaves below node `root` of `bvh` (node 0: the top level, not
/// entering instances), each as often as a leaf holds it.
fn leaf_primitives(bvh: &Bvh, root: u32) -> Vec<u32> {
    let mut out = Vec::new();
    let mut stack = vec![root as usize];
    while let Some(i) = stack.pop() {
        let node = &bvh.nodes[i];
        if node.is_leaf() {
            out.extend(&bvh.primitives[node.offset as usize..][..node.count as usize]);
        } else {
            stack.extend([i + 1, node.offset as usize]);
        }
    }
    out
}

/// The triangles below node `root` of `bvh`, an instanced mesh's.
fn triangles_below(bvh: &Bvh, root: u32) -> Vec<u32> {
    let triangle = |p: u32| match PrimitiveRef::unpacked(p) {
        PrimitiveRef::Triangle(t) => t,
        other => panic!("an instance's BVH holds {other:?}"),
    };
    leaf_primitives(bvh, root)
        .into_iter()
        .map(triangle)
        .collect()
}

#[test]
fn a_mesh_placed_many_times_is_stored_and_built_once() {
    let scene = instanced_scene();
    let instanced = FlatScene::new(&scene, 8, 8).expect("flattens");
    let copied = FlatScene::with_instancing(&scene, 8, 8, false).expect("flattens");
    let mesh_sizes: Vec<usize> = scene
        .objects
        .iter()
        .filter_map(|o| match &o.shape {
            Shape::Mesh { mesh, .. } => Some(mesh.triangles.len()),
            _ => None,
        })
        .collect();
    let (block, ball) = (mesh_sizes[0], mesh_sizes[3]);
    assert_eq!(instanced.triangles.len(), block + ball);
    // Copied three times, less the slivers at the sphere's pole that placing collapses (the
    // instanced mesh keeps them: they are valid in its own coordinates).
    let copies = copied.triangles.len();
    assert!(
        copies <= 3 * (block + ball) && copies >= 3 * (block + ball - 16),
        "{copies}"
    );
    assert!(copied.instances.is_empty());
    assert_eq!(instanced.instances.len(), 6);
    assert_eq!(instanced.instanced_triangles, 0);
    assert_eq!(instanced.triangles.len(), block + ball);
    assert!(instanced.instance_depth > 0);
    // Each instance's BVH holds its mesh's triangles, each in exactly one leaf; the two meshes'
    // BVHs are shared by their three placements.
    let mut roots: Vec<u32> = instanced.instances.iter().map(|i| i.root).collect();
    roots.dedup();
    assert_eq!(roots.len(), 2, "{roots:?}");
    for (root, range) in roots.iter().zip([0..block, block..block + ball]) {
        let mut below = triangles_below(&instanced.bvh, *root);
        below.sort_unstable();
        let expected: Vec<u32> = range.map(|t| t as u32).collect();
        assert_eq!(below, expected);
    }
    // The top level holds the quads and the six instances; its bounds of an instance hold every
    // corner of its mesh, placed.
    let mut top = Vec::new();
    for &p in &leaf_primitives(&instanced.bvh, 0) {
        top.push(PrimitiveRef::unpacked(p));
    }
    let placed = instanced.shapes.len();
    assert_eq!(top.len(), placed + 6, "{top:?}");
    for instance in &instanced.instances {
        let range = if instance.root == roots[0] {
            0..block
        } else {
            block..block + ball
        };
        for t in &instanced.triangles[range] {
            for p in [t.p0, t.p1, t.p2].map(|p| instance.point_to_world(p)) {
                assert!(
                    instance.bounds[0].cmple(p).all() && instance.bounds[1].cmpge(p).all(),
                    "{p} outside {:?}",
                    instance.bounds
                );
            }
        }
    }
    // A mesh placed once, or with a different material each time, is copied.
    let smooth = common::with_smooth_spheres(builtin("cornell").expect("built-in"));
    assert!(
        FlatScene::new(&smooth, 8, 8)
            .expect("flattens")
            .instances
            .is_empty()
    );
}

/// Rays from the camera through a 200 x 200 grid and from inside the box in every direction of
/// a 100 x 100 grid: instanced meshes are hit where their copies are, at the same distance
/// (to 1e-4 of the box's size), with the same geometric and shading normals (to 1e-3) and
/// material. A ray grazing an edge may hit a neighbouring triangle or miss on one side: at
/// most 0.1% of rays may disagree.
#[test]
fn instanced_meshes_are_hit_where_their_copies_are() {
    let scene = instanced_scene();
    let instanced = FlatScene::new(&scene, 8, 8).expect("flattens");
    let copied = FlatScene::with_instancing(&scene, 8, 8, false).expect("flattens");
    let mut rays = camera_rays(&instanced);
    let inside = Vec3::new(278.0, 200.0, 150.0) - instanced.origin.as_vec3();
    for i in 0..100 {
        for j in 0..100 {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / 100.0;
            let phi = std::f32::consts::TAU * (j as f32 + 0.5) / 100.0;
            let r = (1.0 - z * z).sqrt();
            rays.push(Ray {
                origin: inside,
                dir: Vec3::new(r * phi.cos(), r * phi.sin(), z),
            });
        }
    }
    let (mut disagree, mut instance_hits) = (0, 0);
    for ray in &rays {
        let (a, b) = (intersect(&instanced, ray), intersect(&copied, ray));
        let same = match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                instance_hits += matches!(a.primitive, PrimitiveRef::Instance(_)) as u32;
                (a.t - b.t).abs() <= 0.0555
                    && (a.point - b.point).length() <= 0.0555
                    && (a.normal - b.normal).length() <= 1e-3
                    && (a.shading - b.shading).length() <= 1e-3
                    && a.front_face == b.front_face
                    && a.material == b.material
                    && matches!(a.primitive, PrimitiveRef::Instance(_))
                        == matches!(b.primitive, PrimitiveRef::Triangle(_))
            }
            _ => false,
        };
        disagree += !same as u32;
    }
    assert!(
        instance_hits > 2000,
        "only {instance_hits} rays hit an instance"
    );
    eprintln!(
        "{disagree} of {} rays disagree ({instance_hits} hit instances)",
        rays.len()
    );
    let allowed = rays.len() as u32 / 1000;
    assert!(
        disagree <= allowed,
        "{disagree} of {} rays disagree",
        rays.len()
    );
}

/// The instanced scene renders as the one with every placement copied (CPU, nee), and the
/// instanced one with 2% brighter white is caught.
#[test]
fn instanced_meshes_render_as_their_copies() {
    let scene = instanced_scene();
    let opts = |seed| common::nee_opts(32, 32, 1024, 6, seed);
    let copied = FlatScene::with_instancing(&scene, 32, 32, false).expect("flattens");
    let reference = render_cpu_flat(&copied, &opts(1));
    let film = common::render_cpu(&scene, &opts(2));
    let verdict = compare(&reference, &film);
    eprintln!("copied vs instanced: {verdict:?}");
    assert!(verdict.passed(), "{verdict:?}");
    let brighter = common::with_instanced_meshes(common::cornell_white_2_percent_brighter());
    let verdict = compare(&reference, &common::render_cpu(&brighter, &opts(2)));
    eprintln!("copied vs instanced with 2% brighter white: {verdict:?}");
    assert!(!verdict.passed(), "a 2% brighter white went undetected");
}

#[cfg(feature = "gpu")]
/// CPU and GPU render the instanced scene alike (nee); the GPU with 2% brighter white is caught.
#[test]
fn gpu_instances_match_cpu() {
    let Some(gpu) = renderer() else { return };
    let scene = instanced_scene();
    let opts = |seed| common::nee_opts(32, 32, 1024, 6, seed);
    let cpu = common::render_cpu(&scene, &opts(1));
    let film = render_gpu(&gpu, &scene, &opts(2), &Tuning::default());
    let verdict = compare(&cpu, &film);
    eprintln!("instances: cpu vs gpu: {verdict:?}");
    assert!(verdict.passed(), "{verdict:?}");
    let brighter = common::with_instanced_meshes(common::cornell_white_2_percent_brighter());
    let verdict = compare(
        &cpu,
        &render_gpu(&gpu, &brighter, &opts(2), &Tuning::default()),
    );
    eprintln!("instances, gpu with 2% brighter white: {verdict:?}");
    assert!(!verdict.passed(), "a 2% brighter white went undetected");
}

/// The shipped `scenes/knots.toml` places one OBJ knot 27 times with one material: 27
/// instances of one stored mesh.
#[test]
fn the_shipped_knots_scene_is_instanced() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/knots.toml");
    let scene = rt_gpu::scene::file::load(&path).expect("loads");
    let flat = FlatScene::new(&scene, 8, 8).expect("flattens");
    assert_eq!(flat.instances.len(), 27);
    assert_eq!(flat.triangles.len(), 11_520);
    assert_eq!(flat.placed_triangles(), 27 * 11_520);
}

/// `scenes/blender/bumpy.glb`'s cube under its normal map, placed four times: as it is, turned
/// and scaled unevenly, mirrored, and turned and scaled down; the map's strength `map_scale`.
fn normal_mapped_scene(dir: &std::path::Path, map_scale: f32) -> Scene {
    let blender = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/blender");
    let material = format!(
        r#"{{ type = "lambertian", albedo = [0.8, 0.8, 0.8], normal_map = {{ image = "{blender}/bumpy-normals.png", scale = {map_scale} }} }}"#
    );
    bumpy_cubes(dir, &material, &format!("bumpy-{map_scale}"))
}

/// The cubes of [`normal_mapped_scene`] of `material` (a scene file's material table entry);
/// `name` names the scene file.
fn bumpy_cubes(dir: &std::path::Path, material: &str, name: &str) -> Scene {
    let blender = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/blender");
    let cube = format!(
        "mesh = {{ file = \"{blender}/bumpy.glb\", node = \"Cube\" }}\nmaterial = \"bumpy\""
    );
    let text = format!(
        r#"[render]
background = [0.3, 0.3, 0.3]

[camera]
look_from = [0, 4, 9]
look_at = [0, 0, 0]
vfov = 45

[materials]
bumpy = {material}

[[object]]
{cube}

[[object]]
{cube}
rotate_y = 30
scale = [1, 0.5, 2]
translate = [3.5, 0, 0]

[[object]]
{cube}
scale = [-1, 1, 1]
translate = [-3.5, 0, 0]

[[object]]
{cube}
rotate_y = -50
scale = 0.7
translate = [0, 0, 3]

[[light]]
directional = {{ direction = [-0.612, -0.707, 0.354], irradiance = [3, 3, 3] }}
"#
    );
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).expect("writes");
    rt_gpu::scene::file::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// Issue 61: a normal-mapped mesh placed many times is instanced (each placement was copied
/// with its tangents: a 20 k-triangle OBJ placed 500 times took 8.3 s and 2.7 GB), its tangents
/// placed at each hit as flattening places a copy's. Rays from the camera through a 200 x 200
/// grid meet the instances where they meet the copies, with the same shading normals (to
/// 1e-3), under placements that turn, scale unevenly and mirror; at most 0.1% of rays (grazing
/// an edge) may disagree. Negative control: without the map's bending (strength 0) the shading
/// normals differ from the copies' for most rays that hit.
#[test]
fn normal_mapped_meshes_are_instanced_and_shaded_as_their_copies() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = normal_mapped_scene(dir.path(), 1.0);
    let instanced = FlatScene::new(&scene, 8, 8).expect("flattens");
    let copied = FlatScene::with_instancing(&scene, 8, 8, false).expect("flattens");
    let unbent = FlatScene::new(&normal_mapped_scene(dir.path(), 0.0), 8, 8).expect("flattens");
    assert_eq!(instanced.instances.len(), 4);
    assert_eq!(4 * instanced.triangles.len(), copied.triangles.len());
    let (mut disagree, mut hits, mut bent) = (0, 0, 0);
    for ray in camera_rays(&instanced) {
        let (a, b) = (intersect(&instanced, &ray), intersect(&copied, &ray));
        let same = match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                hits += 1;
                let flat = intersect(&unbent, &ray).expect("the same surface");
                bent += ((flat.shading - b.shading).length() > 1e-3) as u32;
                (a.shading - b.shading).length() <= 1e-3
                    && (a.normal - b.normal).length() <= 1e-3
                    && (a.point - b.point).length() <= 1e-3
            }
            _ => false,
        };
        disagree += !same as u32;
    }
    eprintln!("{disagree} of 40000 rays disagree; {hits} hit, {bent} bent by the map");
    assert!(hits > 3_000, "{hits}");
    assert!(disagree <= 40, "{disagree} rays disagree");
    assert!(
        bent > hits / 2,
        "only {bent} of {hits} hits are bent by the map"
    );
}

/// The instanced normal-mapped scene renders as its copies on the CPU, and as the CPU on the
/// GPU (nee, 32x32 at 512 spp; Welch z + Sidak at family-wise 0.01); negative control: the
/// map's strength 1 -> 0.8 on the GPU is told apart.
#[test]
fn normal_mapped_instances_render_as_their_copies() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = normal_mapped_scene(dir.path(), 1.0);
    let opts = |seed| common::nee_opts(32, 32, 512, 6, seed);
    let copied = FlatScene::with_instancing(&scene, 32, 32, false).expect("flattens");
    let reference = render_cpu_flat(&copied, &opts(1));
    let film = common::render_cpu(&scene, &opts(2));
    let verdict = compare(&reference, &film);
    eprintln!("normal-mapped, copied vs instanced: {verdict:?}");
    assert!(verdict.passed(), "{verdict:?}");
    #[cfg(feature = "gpu")]
    {
        let Some(gpu) = renderer() else { return };
        let verdict = compare(
            &film,
            &render_gpu(&gpu, &scene, &opts(3), &Tuning::default()),
        );
        eprintln!("normal-mapped instances, cpu vs gpu: {verdict:?}");
        assert!(verdict.passed(), "{verdict:?}");
        let weaker = normal_mapped_scene(dir.path(), 0.8);
        let verdict = compare(
            &film,
            &render_gpu(&gpu, &weaker, &opts(3), &Tuning::default()),
        );
        eprintln!("normal-mapped instances, the map's strength 0.8 on the gpu: {verdict:?}");
        assert!(!verdict.passed(), "a weaker map went undetected");
    }
}

/// The cubes of [`normal_mapped_scene`] in a red pbr under a clear coat (roughness 0.3), with
/// the cube's normal map at strength `base` on the base and `coat` on the coat (0: none).
fn coated_cubes(dir: &std::path::Path, base: f32, coat: f32) -> Scene {
    let blender = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/blender");
    let map =
        |scale: f32| format!(r#"{{ image = "{blender}/bumpy-normals.png", scale = {scale} }}"#);
    let mut material = String::from(
        r#"{ type = "pbr", base_color = [0.6, 0.1, 0.1], metallic = 0, roughness = 0.5, clearcoat = { factor = 1, roughness = 0.3 }"#,
    );
    if base != 0.0 {
        material += &format!(", normal_map = {}", map(base));
    }
    if coat != 0.0 {
        material += &format!(", clearcoat_normal_map = {}", map(coat));
    }
    material += " }";
    bumpy_cubes(dir, &material, &format!("coated-{base}-{coat}"))
}

/// Issue 63: a clear coat shades with a normal of its own (`Hit::coat`), as glTF draws it. Rays
/// from the camera through a 200 x 200 grid onto the instanced cubes: over a normal-mapped base
/// the coat's normal is the unmapped one (glTF draws a coat without clearcoatNormalTexture
/// unmapped) and the base's the mapped one; with the map on the coat instead, the other way
/// round, the coat's bent where its mirror would send the view below the surface
/// (`valid_reflection`; to 1e-4, against the lambertian cubes with the map at strength 0 and
/// 1). Negative control: the map bends most hits' normals.
#[test]
fn a_clear_coat_shades_with_its_own_normal_map() {
    let dir = tempfile::tempdir().expect("temp dir");
    let flat = |scene: &Scene| FlatScene::new(scene, 8, 8).expect("flattens");
    let unbent = flat(&normal_mapped_scene(dir.path(), 0.0));
    let bent = flat(&normal_mapped_scene(dir.path(), 1.0));
    let base_mapped = flat(&coated_cubes(dir.path(), 1.0, 0.0));
    let coat_mapped = flat(&coated_cubes(dir.path(), 0.0, 1.0));
    assert_eq!(coat_mapped.instances.len(), 4);
    use rt_gpu::assets::normal_map::valid_reflection;
    let (mut hits, mut differ, mut wrong) = (0, 0, 0);
    for ray in camera_rays(&unbent) {
        let hit = |scene: &FlatScene| intersect(scene, &ray);
        let (Some(u), Some(b), Some(on_base), Some(on_coat)) = (
            hit(&unbent),
            hit(&bent),
            hit(&base_mapped),
            hit(&coat_mapped),
        ) else {
            continue;
        };
        hits += 1;
        let near = |a: Vec3, b: Vec3| (a - b).length() <= 1e-4;
        differ += !near(u.shading, b.shading) as u32;
        let right = near(on_base.shading, b.shading)
            && near(on_base.coat, u.shading)
            && near(on_coat.shading, u.shading)
            && near(
                on_coat.coat,
                valid_reflection(b.normal, -ray.dir, b.shading),
            );
        wrong += !right as u32;
    }
    eprintln!("{hits} hits, {differ} bent by the map, {wrong} wrong");
    assert!(hits > 3_000, "{hits}");
    assert!(differ > hits / 2, "only {differ} of {hits} hits are bent");
    assert_eq!(wrong, 0);
}

/// The coated cubes with the map on the base (strength 1) and, reversed, on the coat (-1):
/// the kernel renders them as the CPU does (nee, 32x32 at 512 spp; Welch z + Sidak at
/// family-wise 0.01: worst block z 1.7 against 4.67); negative control: the coat's map at half
/// strength (-0.5) on the GPU is told apart (z 7.7; at -0.8, 5.7). On the CPU, the coat's map
/// changes the picture: without it the same test fails (z 51).
#[test]
fn a_clear_coats_normal_map_renders_alike_on_both_backends() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = coated_cubes(dir.path(), 1.0, -1.0);
    let opts = |seed| common::nee_opts(32, 32, 512, 6, seed);
    let film = common::render_cpu(&scene, &opts(1));
    assert_eq!(film.invalid_samples, 0);
    let unmapped = common::render_cpu(&coated_cubes(dir.path(), 1.0, 0.0), &opts(2));
    let verdict = compare(&film, &unmapped);
    eprintln!("coat map against none: {verdict:?}");
    assert!(!verdict.passed(), "the coat's map changes nothing");
    #[cfg(feature = "gpu")]
    {
        let Some(gpu) = renderer() else { return };
        let verdict = compare(
            &film,
            &render_gpu(&gpu, &scene, &opts(3), &Tuning::default()),
        );
        eprintln!("coat map, cpu vs gpu: {verdict:?}");
        assert!(verdict.passed(), "{verdict:?}");
        let weaker = coated_cubes(dir.path(), 1.0, -0.5);
        let verdict = compare(
            &film,
            &render_gpu(&gpu, &weaker, &opts(3), &Tuning::default()),
        );
        eprintln!("coat map -0.5 on the gpu: {verdict:?}");
        assert!(!verdict.passed(), "the weaker coat map went undetected");
    }
}

/// Rays from `scene`'s camera through the centres of a 200 x 200 grid over the image.
fn camera_rays(scene: &FlatScene) -> Vec<Ray> {
    let camera = &scene.camera;
    let mut rays = Vec::with_capacity(200 * 200);
    for y in 0..200 {
        for x in 0..200 {
            let (s, t) = ((x as f32 + 0.5) / 200.0, (y as f32 + 0.5) / 200.0);
            let dir = camera.to_upper_left + s * camera.horizontal - t * camera.vertical;
            rays.push(Ray {
                origin: camera.origin,
                dir: dir.normalize(),
            });
        }
    }
    rays
}
