//! Triangle meshes: OBJ and glTF loading (polygons, negative indices, node transforms and
//! selection, materials), one-line errors for bad files, and images: the Cornell box with its
//! quads and boxes as triangles renders as the quads do (Welch z + Sidak at family-wise 0.01,
//! tests/it/common/stats.rs), on the CPU and on the GPU against the CPU, each with a negative
//! control (2% brighter white walls) that the same test detects; vertex normals: read, placed
//! by the inverse transpose, shading on both backends alike.
#![cfg_attr(not(feature = "gpu"), allow(unused))]

use crate::common;

#[cfg(feature = "gpu")]
use common::gpu::{render_gpu, renderer};
use common::stats::compare;
use common::triangulated;
use glam::Vec3;
#[cfg(feature = "gpu")]
use rt_gpu::gpu::Tuning;
use rt_gpu::scene::Material;
use rt_gpu::scene::builtin::builtin;
use rt_gpu::scene::file::{load, parse_with, to_toml};
use rt_gpu::scene::flat::FlatScene;
use rt_gpu::scene::mesh;
use std::path::Path;

fn write(dir: &Path, name: &str, text: &[u8]) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).expect("writes");
    path
}

/// A scene file placing `mesh` (a TOML inline table) with `extra` keys.
fn scene_with(mesh: &str, extra: &str) -> String {
    format!(
        "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\nvfov = 40\n\n[materials]\nwhite = {{ type = \"lambertian\", albedo = [0.7, 0.7, 0.7] }}\n\n[[object]]\nmesh = {mesh}\n{extra}\n"
    )
}

#[test]
fn obj_polygons_negative_indices_and_missing_normals() {
    let dir = tempfile::tempdir().expect("temp dir");
    // A unit square as one polygon (two triangles), then a triangle by negative indices, with
    // texture coordinates and normals in the face syntax but no `vn` lines for some.
    let obj = b"# test\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1 4/1\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf -3 -2 -1\n";
    let path = write(dir.path(), "square.obj", obj);
    let parts = mesh::load(&path, "square.obj", None).expect("loads");
    assert_eq!(parts.len(), 1);
    let m = parts[0].clone();
    assert_eq!(m.positions.len(), 7);
    assert_eq!(m.triangles.len(), 3, "{:?}", m.triangles);
    // Counter-clockwise from +z: every triangle of the square faces +z, the last one too.
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        assert!((b - a).cross(c - a).z > 0.0, "{t:?}");
    }
    assert_eq!(m.triangles[2], [4, 5, 6]);
    // Placed through a scene file: scale, rotation and translation, relative to the file.
    let scene_path = write(
        dir.path(),
        "s.toml",
        scene_with(
            "{ file = \"square.obj\" }",
            "scale = [2, 3, 1]\ntranslate = [1, 0, 0]\nmaterial = \"white\"",
        )
        .as_bytes(),
    );
    let scene = load(&scene_path).expect("scene loads");
    let flat = FlatScene::new(&scene, 8, 8).expect("flattens");
    assert_eq!(flat.triangles.len(), 3);
    assert_eq!(flat.triangles[0].p1, Vec3::new(3.0, 0.0, 0.0));
    assert_eq!(flat.triangles[0].p2, Vec3::new(3.0, 3.0, 0.0));
    assert!(!flat.bvh.nodes.is_empty());
    // And written back, it reads the same.
    let text = to_toml(&scene);
    let loader = rt_gpu::assets::loader::Loader::new(dir.path());
    let again = parse_with(&loader, &text, "again.toml", "s").expect("written scene parses");
    assert_eq!(again.objects, scene.objects);
    // A mirroring scale keeps the front face on the same side of the surface.
    let mirrored = write(
        dir.path(),
        "m.toml",
        scene_with(
            "{ file = \"square.obj\" }",
            "scale = [-1, 1, 1]\nmaterial = \"white\"",
        )
        .as_bytes(),
    );
    let flat = FlatScene::new(&load(&mirrored).expect("loads"), 8, 8).expect("flattens");
    let t = flat.triangles[0];
    assert!((t.p1 - t.p0).cross(t.p2 - t.p0).z > 0.0);
}

/// A material library tobj cannot parse (it panics on a colour of two numbers) leaves the mesh
/// without materials, as a missing one does; the scene's material applies.
#[test]
fn a_malformed_material_library_reads_as_none() {
    let dir = tempfile::tempdir().expect("temp dir");
    write(dir.path(), "bad.mtl", b"newmtl m\nKd 1 2\n");
    let path = write(
        dir.path(),
        "t.obj",
        b"mtllib bad.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let parts = mesh::load(&path, "t.obj", None).expect("loads without materials");
    assert!(parts.iter().all(|p| p.material.is_none()));
}

#[test]
fn bad_mesh_files_are_one_line_errors_naming_file_and_line() {
    let dir = tempfile::tempdir().expect("temp dir");
    let cases: [(&str, &[u8], &str); 8] = [
        (
            "badv.obj",
            b"v 0 0 0\nv 1 0 0\nv 1 x 0\nf 1 2 3\n",
            "badv.obj:3: a vertex position",
        ),
        (
            "range.obj",
            b"v 0 0 0\nv 1 0 0\nv 1 1 0\n\nf 1 2 9\n",
            "range.obj:5: a face",
        ),
        // A far negative index, which tobj (parsing beside the check) trusts: the check is told.
        (
            "far.obj",
            b"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 -9223372036854775807\n",
            "far.obj:4: a face (f) names a vertex (v)",
        ),
        (
            "min.obj",
            b"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 -9223372036854775808\n",
            "min.obj:4: a face (f) names a vertex (v)",
        ),
        (
            "empty.obj",
            b"# nothing\nv 0 0 0\n",
            "empty.obj has no triangles",
        ),
        (
            "flat.obj",
            b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
            "flat.obj has no triangles",
        ),
        ("model.stl", b"solid x\n", "unknown format"),
        (
            "broken.gltf",
            b"{ \"asset\": ",
            "cannot read mesh broken.gltf",
        ),
    ];
    for (name, text, words) in cases {
        write(dir.path(), name, text);
        let scene_path = write(
            dir.path(),
            "s.toml",
            scene_with(&format!("{{ file = \"{name}\" }}"), "material = \"white\"").as_bytes(),
        );
        let error = format!("{:#}", load(&scene_path).expect_err(name));
        assert!(
            error.contains(words) && error.contains("s.toml:") && !error.contains('\n'),
            "{name}: {error}"
        );
    }
    let scene_path = write(
        dir.path(),
        "s.toml",
        scene_with("{ file = \"missing.obj\" }", "material = \"white\"").as_bytes(),
    );
    let error = format!("{:#}", load(&scene_path).expect_err("missing"));
    assert!(error.contains("cannot read mesh missing.obj"), "{error}");
    // An OBJ object needs a material; `scale` needs a mesh.
    write(dir.path(), "t.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let scene_path = write(
        dir.path(),
        "s.toml",
        scene_with("{ file = \"t.obj\" }", "").as_bytes(),
    );
    let error = format!("{:#}", load(&scene_path).expect_err("no material"));
    assert!(error.contains("material"), "{error}");
}

/// A glTF file: a parent node translating a scaled child, and a node placed by a matrix, with
/// an emissive material (KHR_materials_emissive_strength) and a metallic one.
fn write_gltf(dir: &Path) -> std::path::PathBuf {
    let mut bin: Vec<u8> = Vec::new();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for x in v {
            bin.extend(x.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 0] {
        bin.extend(i.to_le_bytes());
    }
    let doc = serde_json::json!({
      "extensionsUsed": ["KHR_materials_emissive_strength"],
      "bufferViews": [
        { "buffer": 0, "byteOffset": 0, "byteLength": 36 },
        { "buffer": 0, "byteOffset": 36, "byteLength": 6 }
      ],
      "accessors": [
        { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] },
        { "bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR" }
      ],
      "materials": [
        { "name": "Lamp", "emissiveFactor": [1, 0.5, 0.25], "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 4 } } },
        { "name": "Gold", "pbrMetallicRoughness": { "baseColorFactor": [0.9, 0.8, 0.1, 1], "metallicFactor": 1, "roughnessFactor": 0.2 } }
      ],
      "meshes": [
        { "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1, "material": 0 }] },
        { "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1, "material": 1 }] }
      ],
      "nodes": [
        { "name": "Parent", "translation": [10, 0, 0], "children": [1] },
        { "name": "Child", "scale": [2, 2, 2], "mesh": 0 },
        { "name": "Other", "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,5,0,1], "mesh": 1 }
      ],
      "scenes": [{ "nodes": [0, 2] }]
    });
    common::gltf::write_document(dir, "model", doc, &bin)
}

#[test]
fn gltf_node_transforms_selection_and_materials() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = write_gltf(dir.path());
    let parts = mesh::load(&path, "model.gltf", None).expect("loads");
    assert_eq!(parts.len(), 2, "one part per material");
    let lamp = parts
        .iter()
        .find(|p| p.material_name == "Lamp")
        .expect("lamp");
    let gold = parts
        .iter()
        .find(|p| p.material_name == "Gold")
        .expect("gold");
    assert_eq!(
        lamp.positions,
        vec![
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(12.0, 0.0, 0.0),
            Vec3::new(10.0, 2.0, 0.0)
        ]
    );
    assert_eq!(gold.positions[2], Vec3::new(0.0, 6.0, 0.0));
    match &lamp.material {
        Some(Material::Pbr(rt_gpu::material::Pbr {
            emission: Some(l), ..
        })) => {
            assert_eq!(l.strength, 4.0);
            assert!(!l.two_sided);
        }
        other => panic!("lamp: {other:?}"),
    }
    match &gold.material {
        Some(Material::Pbr(m)) => {
            assert_eq!(
                (m.metallic, m.roughness, m.ior, m.transmission),
                (1.0, 0.2, 1.5, 0.0)
            );
        }
        other => panic!("gold: {other:?}"),
    }
    // One node by name: its own transform and its children's, not its parents'.
    let child = mesh::load(&path, "model.gltf", Some("Child")).expect("loads");
    assert_eq!(child.len(), 1);
    assert_eq!(child[0].positions[1], Vec3::new(2.0, 0.0, 0.0));
    let parent = mesh::load(&path, "model.gltf", Some("Parent")).expect("loads");
    assert_eq!(parent[0].positions[1], Vec3::new(12.0, 0.0, 0.0));
    let error = mesh::load(&path, "model.gltf", Some("Nope")).expect_err("no such node");
    assert!(
        error.contains("no node named \"Nope\"") && error.contains("Child"),
        "{error}"
    );
    // In a scene without `material`: the file's materials join the scene, and the lamp is a
    // light (one-sided: the triangle emits toward +z).
    let scene_path = write(
        dir.path(),
        "s.toml",
        scene_with("{ file = \"model.gltf\" }", "").as_bytes(),
    );
    let scene = load(&scene_path).expect("scene loads");
    assert_eq!(scene.objects.len(), 2);
    assert!(scene.material_names.iter().any(|n| n == "model.gltf#Lamp"));
    let flat = FlatScene::new(&scene, 8, 8).expect("flattens");
    assert_eq!(flat.lights.len(), 1);
    // And written back (each part its own object), it reads the same.
    let loader = rt_gpu::assets::loader::Loader::new(dir.path());
    let again =
        parse_with(&loader, &to_toml(&scene), "again.toml", "s").expect("written scene parses");
    let named = |s: &rt_gpu::scene::Scene| -> Vec<_> {
        s.objects
            .iter()
            .map(|o| {
                (
                    o.shape.clone(),
                    s.materials[o.material as usize].clone(),
                    s.material_names[o.material as usize].clone(),
                )
            })
            .collect()
    };
    assert_eq!(named(&again), named(&scene));
}

/// The Cornell box as quads and as triangles: the same image on the CPU (nee: the light is two
/// emitting triangles, picked by area), and a 2% brighter white is caught.
#[test]
fn triangles_render_as_the_quads_they_replace() {
    let quads = builtin("cornell").expect("built-in");
    let triangles = triangulated(&quads);
    let opts = |seed| common::nee_opts(32, 32, 512, 6, seed);
    let reference = common::render_cpu(&quads, &opts(1));
    let film = common::render_cpu(&triangles, &opts(2));
    let verdict = compare(&reference, &film);
    eprintln!("quads vs triangles: {verdict:?}");
    assert!(verdict.passed(), "{verdict:?}");
    let brighter = triangulated(&common::cornell_white_2_percent_brighter());
    let verdict = compare(&reference, &common::render_cpu(&brighter, &opts(2)));
    eprintln!("quads vs triangles with 2% brighter white: {verdict:?}");
    assert!(!verdict.passed(), "a 2% brighter white went undetected");
}

#[cfg(feature = "gpu")]
/// CPU and GPU render the triangulated Cornell box (BVH, watertight triangles, emissive
/// triangles) alike, naive and nee; the GPU with 2% brighter white walls is caught.
#[test]
fn gpu_meshes_match_cpu_meshes() {
    let Some(gpu) = renderer() else { return };
    let scene = triangulated(&builtin("cornell").expect("built-in"));
    for nee in [false, true] {
        let opts = |seed| {
            if nee {
                common::nee_opts(32, 32, 512, 6, seed)
            } else {
                common::opts(32, 32, 1024, 6, seed)
            }
        };
        let cpu = common::render_cpu(&scene, &opts(1));
        let film = render_gpu(&gpu, &scene, &opts(2), &Tuning::default());
        let verdict = compare(&cpu, &film);
        eprintln!("nee {nee}: cpu vs gpu: {verdict:?}");
        assert!(verdict.passed(), "nee {nee}: {verdict:?}");
        if nee {
            let brighter = triangulated(&common::cornell_white_2_percent_brighter());
            let verdict = compare(
                &cpu,
                &render_gpu(&gpu, &brighter, &opts(2), &Tuning::default()),
            );
            eprintln!("gpu with 2% brighter white: {verdict:?}");
            assert!(!verdict.passed(), "a 2% brighter white went undetected");
        }
    }
}

#[cfg(feature = "gpu")]
/// The shipped mesh scene (an OBJ knot of 11 520 triangles in fuzzy metal, a glTF lamp whose
/// 320 emitting triangles join the light list beside the ceiling's quad, glass): CPU and GPU
/// agree with nee, and with white walls 2.7% brighter (albedo 0.75, not 0.73) the same test
/// tells them apart.
#[test]
fn the_shipped_mesh_scene_matches_on_both_backends() {
    let Some(gpu) = renderer() else { return };
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes.toml");
    let scene = load(&path).expect("loads");
    let flat = FlatScene::new(&scene, 8, 8).expect("flattens");
    assert_eq!(flat.triangles.len(), 11_520 + 24 + 320);
    assert_eq!(flat.lights.len(), 1 + 320);
    let opts = |seed| common::nee_opts(24, 24, 512, 6, seed);
    let cpu = common::render_cpu(&scene, &opts(1));
    let film = render_gpu(&gpu, &scene, &opts(2), &Tuning::default());
    let verdict = compare(&cpu, &film);
    eprintln!("meshes.toml cpu vs gpu: {verdict:?}");
    assert!(verdict.passed(), "{verdict:?}");
    let mut brighter = scene.clone();
    let white = brighter.material_names.iter().position(|n| n == "white");
    brighter.materials[white.expect("a white material")] = Material::lambertian(Vec3::splat(0.75));
    let verdict = compare(
        &cpu,
        &render_gpu(&gpu, &brighter, &opts(2), &Tuning::default()),
    );
    eprintln!("meshes.toml with 2.7% brighter white walls: {verdict:?}");
    assert!(!verdict.passed(), "2.7% brighter walls went undetected");
}

/// `common::smooth_sphere_mesh` as an OBJ file, each vertex with its radial normal
/// (`f v//vn`).
fn smooth_sphere_obj(rings: u32, segments: u32) -> String {
    let mesh = common::smooth_sphere_mesh(rings, segments);
    let mut text = String::from("# smooth sphere\n");
    for p in &mesh.positions {
        text += &format!("v {0} {1} {2}\nvn {0} {1} {2}\n", p.x, p.y, p.z);
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        text += &format!("f {a}//{a} {b}//{b} {c}//{c}\n");
    }
    text
}

/// Vertex normals shade: on a coarse sphere (12 x 24 facets) stretched by `scale = [2, 1, 1]`
/// and rotated, the interpolated normal at a hit is within 0.05 rad of the true ellipsoid's
/// normal there (inverse-transpose transform; 0.027 measured), while the flat facets' normals
/// are more than 0.15 rad off (0.26); the geometric normal still faces the ray and the shading normal is on its side. glTF
/// normals go through a non-uniform node scale by the inverse transpose too.
#[test]
fn vertex_normals_shade_and_transform() {
    use rt_gpu::cpu::intersect::intersect;
    use rt_gpu::shared::ray::Ray;
    let dir = tempfile::tempdir().expect("temp dir");
    write(
        dir.path(),
        "sphere.obj",
        smooth_sphere_obj(12, 24).as_bytes(),
    );
    let parts = mesh::load(&dir.path().join("sphere.obj"), "sphere.obj", None).expect("loads");
    assert_eq!(parts[0].normals.len(), parts[0].triangles.len());
    let scene_path = write(
        dir.path(),
        "s.toml",
        scene_with(
            "{ file = \"sphere.obj\" }",
            "scale = [2, 1, 1]\nrotate_y = 30\nmaterial = \"white\"",
        )
        .as_bytes(),
    );
    let flat = FlatScene::new(&load(&scene_path).expect("loads"), 8, 8).expect("flattens");
    assert_eq!(flat.triangle_normals.len(), flat.triangles.len());
    // The ellipsoid x'^2/4 + y^2 + z'^2 = 1 in its rotated frame (x', z'): its normal at p.
    let (sin, cos) = 30f32.to_radians().sin_cos();
    let to_local = |v: Vec3| Vec3::new(cos * v.x - sin * v.z, v.y, sin * v.x + cos * v.z);
    let to_world = |v: Vec3| Vec3::new(cos * v.x + sin * v.z, v.y, -sin * v.x + cos * v.z);
    let true_normal = |p: Vec3| {
        let l = to_local(p);
        to_world(Vec3::new(l.x / 4.0, l.y, l.z)).normalize()
    };
    let (mut worst_shading, mut worst_flat) = (0f32, 0f32);
    let mut state = 7u32;
    let mut next = || {
        state = state.wrapping_mul(747796405).wrapping_add(2891336453);
        (state >> 8) as f32 / (1 << 24) as f32
    };
    let camera = flat.camera.origin;
    for _ in 0..2000 {
        let target = Vec3::new(4.0 * next() - 2.0, 2.0 * next() - 1.0, 2.0 * next() - 1.0) * 0.9;
        let ray = Ray {
            origin: camera,
            dir: (target - camera).normalize(),
        };
        let Some(hit) = intersect(&flat, &ray) else {
            continue;
        };
        assert!(hit.normal.dot(ray.dir) < 0.0 && hit.shading.dot(hit.normal) > 0.0);
        let truth = true_normal(hit.point + flat.origin.as_vec3());
        worst_shading = worst_shading.max(hit.shading.dot(truth).clamp(-1.0, 1.0).acos());
        worst_flat = worst_flat.max(hit.normal.dot(truth).clamp(-1.0, 1.0).acos());
    }
    eprintln!("worst angle to the true normal: shading {worst_shading}, flat {worst_flat}");
    assert!(
        worst_shading < 0.05,
        "shading normal off by {worst_shading} rad"
    );
    assert!(
        worst_flat > 0.15,
        "the flat facets should be visibly off ({worst_flat} rad)"
    );

    // glTF: one triangle with normals, under a node scaled by [1, 1, 4].
    let mut bin: Vec<u8> = Vec::new();
    let h = std::f32::consts::FRAC_1_SQRT_2;
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        bin.extend(v.iter().flat_map(|x| x.to_le_bytes()));
    }
    for n in [[h, 0.0, h], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]] {
        bin.extend(n.iter().flat_map(|x| x.to_le_bytes()));
    }
    let doc = serde_json::json!({
      "bufferViews": [{ "buffer": 0, "byteOffset": 0, "byteLength": 36 }, { "buffer": 0, "byteOffset": 36, "byteLength": 36 }],
      "accessors": [
        { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] },
        { "bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3" }
      ],
      "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0, "NORMAL": 1 } }] }],
      "nodes": [{ "name": "Stretched", "scale": [1, 1, 4], "mesh": 0 }]
    });
    let path = common::gltf::write_document(dir.path(), "n", doc, &bin);
    let parts = mesh::load(&path, "n.gltf", None).expect("loads");
    let n = parts[0].normals[0];
    let expected = Vec3::new(1.0, 0.0, 0.25).normalize();
    assert!((n[0] - expected).length() < 1e-6, "{:?}", n[0]);
    assert!((n[1] - Vec3::Z).length() < 1e-6, "{:?}", n[1]);
}

#[cfg(feature = "gpu")]
/// CPU and GPU shade smooth meshes alike (`common::with_smooth_spheres`: lambertian, dielectric
/// and metal through interpolated normals), with nee; the GPU with 2% brighter white is caught.
/// The images cannot tell smooth from flat shading at this size (a GPU ignoring the normals
/// passed); `gpu_equivalence::first_bounces_match_the_cpu` compares the scattered directions.
#[test]
fn gpu_smooth_meshes_match_cpu() {
    let Some(gpu) = renderer() else { return };
    let scene = common::with_smooth_spheres(builtin("cornell").expect("built-in"));
    let flat = FlatScene::new(&scene, 8, 8).expect("flattens");
    assert!(!flat.triangle_normals.is_empty());
    // nee takes both the materials' sampled directions and their BSDFs toward lights.
    let opts = |seed| common::nee_opts(32, 32, 1024, 6, seed);
    let cpu = common::render_cpu(&scene, &opts(1));
    let film = render_gpu(&gpu, &scene, &opts(2), &Tuning::default());
    let verdict = compare(&cpu, &film);
    eprintln!("smooth meshes: cpu vs gpu: {verdict:?}");
    assert!(verdict.passed(), "{verdict:?}");
    let brighter = common::with_smooth_spheres(common::cornell_white_2_percent_brighter());
    let verdict = compare(
        &cpu,
        &render_gpu(&gpu, &brighter, &opts(2), &Tuning::default()),
    );
    eprintln!("smooth meshes, gpu with 2% brighter white: {verdict:?}");
    assert!(!verdict.passed(), "a 2% brighter white went undetected");
}

/// Five vertices in the z = 0 plane, drawn by a primitive of `mode` (glTF's number) with
/// `indices` (none: in order) beside a primitive of points, written as `name` in `dir`.
fn primitive_gltf(
    dir: &std::path::Path,
    name: &str,
    mode: u32,
    indices: &[u16],
) -> std::path::PathBuf {
    let mut bin = Vec::new();
    for p in [[0f32, 0.0], [0.0, 1.0], [1.0, 0.0], [1.0, 1.0], [2.0, 0.0]] {
        for c in [p[0], p[1], 0.0] {
            bin.extend(c.to_le_bytes());
        }
    }
    for i in indices {
        bin.extend(i.to_le_bytes());
    }
    let mut primitive = serde_json::json!({ "attributes": { "POSITION": 0 }, "mode": mode });
    let mut accessors = vec![
        serde_json::json!({ "bufferView": 0, "componentType": 5126, "count": 5,
        "type": "VEC3", "min": [0, 0, 0], "max": [2, 1, 0] }),
    ];
    let mut views = vec![serde_json::json!({ "buffer": 0, "byteOffset": 0, "byteLength": 60 })];
    if !indices.is_empty() {
        primitive["indices"] = 1.into();
        accessors.push(serde_json::json!({ "bufferView": 1, "componentType": 5123,
            "count": indices.len(), "type": "SCALAR" }));
        views.push(
            serde_json::json!({ "buffer": 0, "byteOffset": 60, "byteLength": 2 * indices.len() }),
        );
    }
    let points = serde_json::json!({ "attributes": { "POSITION": 0 }, "mode": 0 });
    let doc = serde_json::json!({
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [primitive, points] }],
        "bufferViews": views,
        "accessors": accessors,
    });
    common::gltf::write_document(dir, name, doc, &bin)
}

/// Issue 62: triangle strips and fans are drawn as the triangle lists they stand for (only
/// lists were drawn: MeshPrimitiveModes showed 1 of its 3 triangle meshes), indexed or not,
/// with one winding (glTF 2.0, 3.7.2.1); a primitive of points is named in a note.
#[test]
fn triangle_strips_and_fans_are_their_lists() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let triangles = |path: &std::path::Path| -> Vec<[glam::Vec3; 3]> {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let parts = rt_gpu::scene::mesh::load(path, &name, None).expect("loads");
        assert_eq!(parts.len(), 1);
        let mesh = parts[0].clone();
        mesh.triangles
            .iter()
            .map(|t| t.map(|i| mesh.positions[i as usize]))
            .collect()
    };
    let strip_list = triangles(&primitive_gltf(
        d,
        "strip-list",
        4,
        &[0, 1, 2, 1, 3, 2, 2, 3, 4],
    ));
    assert_eq!(strip_list.len(), 3);
    assert_eq!(triangles(&primitive_gltf(d, "strip", 5, &[])), strip_list);
    assert_eq!(
        triangles(&primitive_gltf(d, "strip-indexed", 5, &[0, 1, 2, 3, 4])),
        strip_list
    );
    let fan_list = triangles(&primitive_gltf(
        d,
        "fan-list",
        4,
        &[1, 2, 0, 2, 3, 0, 3, 4, 0],
    ));
    assert_eq!(triangles(&primitive_gltf(d, "fan", 6, &[])), fan_list);
    // One winding: every strip triangle faces the way the first does (the zigzag's -z).
    for [a, b, c] in &strip_list {
        assert!((*b - *a).cross(*c - *a).z < 0.0, "{strip_list:?}");
    }
    let (_, notes) =
        rt_gpu::scene::gltf_scene::load(&d.join("strip.gltf"), "strip.gltf", None).expect("loads");
    assert!(
        notes
            .iter()
            .any(|n| n.contains("not rendered: 1 primitive of points or lines")),
        "{notes:?}"
    );
    // Too short a strip is named.
    let err =
        rt_gpu::scene::mesh::load(&primitive_gltf(d, "short", 5, &[0, 1]), "short.gltf", None)
            .expect_err("two indices");
    assert!(err.contains("strip or fan of 2 indices"), "{err}");
}

/// Issue 62: what a glTF file holds and rt-gpu does not render is named in one note (it was
/// dropped silently): here a second set of vertex colours, a third UV set, an extension it does
/// not read and a primitive of points (a morph target of weight 0 is read, and not named).
#[test]
fn what_a_gltf_file_holds_and_is_not_rendered_is_named_in_one_note() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let path = primitive_gltf(d, "extras", 4, &[0, 1, 2]);
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("reads")).expect("json");
    let primitive = &mut doc["meshes"][0]["primitives"][0];
    primitive["attributes"]["COLOR_1"] = 0.into();
    primitive["attributes"]["TEXCOORD_2"] = 2.into();
    primitive["targets"] = serde_json::json!([{ "POSITION": 0 }]);
    doc["accessors"].as_array_mut().expect("accessors").push(
        serde_json::json!({ "bufferView": 0, "componentType": 5126, "count": 5, "type": "VEC2" }),
    );
    doc["extensionsUsed"] = serde_json::json!(["EXT_unknown_to_rt_gpu", "KHR_materials_ior"]);
    std::fs::write(&path, doc.to_string()).expect("writes");
    let (_, notes) = rt_gpu::scene::gltf_scene::load(&path, "extras.gltf", None).expect("loads");
    assert_eq!(notes.len(), 1, "{notes:?}");
    for named in [
        "1 primitive of points or lines",
        "COLOR_1",
        "TEXCOORD_2",
        "extension EXT_unknown_to_rt_gpu",
    ] {
        assert!(notes[0].contains(named), "{named}: {}", notes[0]);
    }
    assert!(!notes[0].contains("KHR_materials_ior"), "{}", notes[0]);
    assert!(!notes[0].contains("morph"), "{}", notes[0]);
}

/// A triangle placed by node 0 with EXT_mesh_gpu_instancing (required) at `instances` (each a
/// translation, rotation quaternion and scale), the node itself moved by [0, 0, 5].
fn instanced_gltf(
    dir: &std::path::Path,
    name: &str,
    instances: &[([f32; 3], [f32; 4], [f32; 3])],
) -> std::path::PathBuf {
    let mut bin = Vec::new();
    for p in [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]] {
        p.iter().for_each(|c| bin.extend(c.to_le_bytes()));
    }
    let mut views = vec![serde_json::json!({ "buffer": 0, "byteOffset": 0, "byteLength": 36 })];
    let mut accessors = vec![
        serde_json::json!({ "bufferView": 0, "componentType": 5126, "count": 3,
        "type": "VEC3", "min": [0, 0, 0], "max": [1, 2, 0] }),
    ];
    for (k, ty) in [(0, "VEC3"), (1, "VEC4"), (2, "VEC3")] {
        let start = bin.len();
        for instance in instances {
            let values: &[f32] = match k {
                0 => &instance.0,
                1 => &instance.1,
                _ => &instance.2,
            };
            values.iter().for_each(|c| bin.extend(c.to_le_bytes()));
        }
        views.push(serde_json::json!({ "buffer": 0, "byteOffset": start, "byteLength": bin.len() - start }));
        accessors.push(
            serde_json::json!({ "bufferView": views.len() - 1, "componentType": 5126,
            "count": instances.len(), "type": ty }),
        );
    }
    let doc = serde_json::json!({
        "extensionsUsed": ["EXT_mesh_gpu_instancing"],
        "extensionsRequired": ["EXT_mesh_gpu_instancing"],
        "nodes": [{ "mesh": 0, "translation": [0, 0, 5], "extensions": { "EXT_mesh_gpu_instancing":
            { "attributes": { "TRANSLATION": 1, "ROTATION": 2, "SCALE": 3 } } } }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 } }] }],
        "bufferViews": views,
        "accessors": accessors,
    });
    common::gltf::write_document(dir, name, doc, &bin)
}

/// Issue 62: EXT_mesh_gpu_instancing places a node's mesh once per instance, each by its
/// translation, rotation and scale and then the node's transform (only one triangle was drawn,
/// silently; a file requiring the extension was refused); bad instancing is one line.
#[test]
fn gpu_instancing_places_a_mesh_per_instance() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let quarter = std::f32::consts::FRAC_1_SQRT_2;
    let path = instanced_gltf(
        d,
        "three",
        &[
            ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], [1.0, 1.0, 1.0]),
            (
                [10.0, 0.0, 0.0],
                [0.0, 0.0, quarter, quarter],
                [1.0, 1.0, 1.0],
            ),
            ([0.0, 10.0, 0.0], [0.0, 0.0, 0.0, 1.0], [2.0, 3.0, 1.0]),
        ],
    );
    let parts = rt_gpu::scene::mesh::load(&path, "three.gltf", None).expect("loads");
    let mesh = parts[0].clone();
    let placed: Vec<[glam::Vec3; 3]> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize]))
        .collect();
    let v = glam::Vec3::new;
    let expected = [
        [v(0.0, 0.0, 5.0), v(1.0, 0.0, 5.0), v(0.0, 2.0, 5.0)],
        // A quarter turn about z: x -> y, y -> -x.
        [v(10.0, 0.0, 5.0), v(10.0, 1.0, 5.0), v(8.0, 0.0, 5.0)],
        [v(0.0, 10.0, 5.0), v(2.0, 10.0, 5.0), v(0.0, 16.0, 5.0)],
    ];
    assert_eq!(placed.len(), 3, "{placed:?}");
    for (got, want) in placed.iter().zip(expected) {
        for (a, b) in got.iter().zip(want) {
            assert!((*a - b).length() < 1e-5, "{placed:?}");
        }
    }
    let (_, notes) = rt_gpu::scene::gltf_scene::load(&path, "three.gltf", None).expect("loads");
    assert!(notes.is_empty(), "{notes:?}");
    // A rotation of length 2 is refused, naming the instance.
    let bad = instanced_gltf(d, "bad", &[([0.0; 3], [0.0, 0.0, 0.0, 2.0], [1.0; 3])]);
    let err = rt_gpu::scene::mesh::load(&bad, "bad.gltf", None).expect_err("not a unit quaternion");
    assert!(
        err.contains("instance 0's ROTATION") && err.contains("unit quaternion"),
        "{err}"
    );
    assert!(!err.contains('\n'), "{err}");
    // Bad accessors are named before anything is read; a count that would place more triangles
    // than rt-gpu takes is refused at once.
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("reads")).expect("json");
    let edited = |name: &str, edit: &dyn Fn(&mut serde_json::Value)| {
        let mut doc = doc.clone();
        edit(&mut doc);
        let path = d.join(format!("{name}.gltf"));
        std::fs::write(&path, doc.to_string()).expect("writes");
        let start = std::time::Instant::now();
        let err = rt_gpu::scene::mesh::load(&path, name, None).expect_err(name);
        assert!(
            start.elapsed().as_secs_f64() < 1.0,
            "{name}: {:?}",
            start.elapsed()
        );
        assert!(!err.contains('\n'), "{err}");
        err
    };
    let err = edited("vec3-rotation", &|doc| {
        doc["accessors"][2]["type"] = "VEC3".into()
    });
    assert!(err.contains("ROTATION (accessor 2) is VEC3"), "{err}");
    let err = edited("counts", &|doc| doc["accessors"][3]["count"] = 2.into());
    assert!(err.contains("counts differ"), "{err}");
    // Only TRANSLATION, `count` of them, sparse without a view: one stored value (view 1) at
    // index 0 (view 0's first word).
    let sparse_translations = |doc: &mut serde_json::Value, count: u64| {
        let attributes =
            &mut doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"];
        *attributes = serde_json::json!({ "TRANSLATION": 1 });
        doc["accessors"][1] = serde_json::json!({ "componentType": 5126, "count": count,
            "type": "VEC3", "sparse": { "count": 1, "indices": { "bufferView": 0, "componentType": 5125 },
            "values": { "bufferView": 1 } } });
    };
    let err = edited("many", &|doc| sparse_translations(doc, 300_000_000));
    assert!(err.contains("EXT_mesh_gpu_instancing"), "{err}");
    // A mesh of points draws nothing, but each instance would still be a pass over it.
    let err = edited("points", &|doc| {
        doc["meshes"][0]["primitives"][0]["mode"] = 0.into();
        sparse_translations(doc, 200_000_000);
    });
    assert!(err.contains("EXT_mesh_gpu_instancing"), "{err}");
}

/// A quad whose positions are UNSIGNED_BYTE (0 or 2, the node scaling them by 0.5), normals
/// normalized BYTE (0, 0, 127) and texture coordinates normalized UNSIGNED_SHORT: what
/// KHR_mesh_quantization allows, `used` or not.
fn quantized_gltf(dir: &std::path::Path, name: &str, used: bool) -> std::path::PathBuf {
    let mut bin: Vec<u8> = Vec::new();
    for [x, y] in [[0u8, 0], [2, 0], [2, 2], [0, 2]] {
        bin.extend([x, y, 0, 0]); // padded to 4 bytes
    }
    for _ in 0..4 {
        bin.extend([0u8, 0, 127, 0]);
    }
    for [u, v] in [[0u16, 65535], [65535, 65535], [65535, 0], [0, 0]] {
        bin.extend(u.to_le_bytes());
        bin.extend(v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    let extensions = if used {
        serde_json::json!(["KHR_mesh_quantization"])
    } else {
        serde_json::json!([])
    };
    let doc = serde_json::json!({
        "extensionsUsed": extensions,
        "extensionsRequired": extensions,
        "nodes": [{ "mesh": 0, "scale": [0.5, 0.5, 0.5] }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 }, "indices": 3 }] }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 16, "byteStride": 4 },
            { "buffer": 0, "byteOffset": 16, "byteLength": 16, "byteStride": 4 },
            { "buffer": 0, "byteOffset": 32, "byteLength": 16 },
            { "buffer": 0, "byteOffset": 48, "byteLength": 12 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5121, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [2, 2, 0] },
            { "bufferView": 1, "componentType": 5120, "normalized": true, "count": 4, "type": "VEC3" },
            { "bufferView": 2, "componentType": 5123, "normalized": true, "count": 4, "type": "VEC2" },
            { "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR" }
        ],
    });
    common::gltf::write_document(dir, name, doc, &bin)
}

/// Issue 62: KHR_mesh_quantization's integer attributes read as the extension defines them
/// (the extension, required, was refused): positions as their values (the node dequantizes),
/// normalized normals and texture coordinates divided by 127 and 65535. Without the extension
/// such attributes stay refused in one line.
#[test]
fn quantized_attributes_read_as_the_extension_defines() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = quantized_gltf(dir.path(), "quantized", true);
    let parts = rt_gpu::scene::mesh::load(&path, "quantized.gltf", None).expect("loads");
    let mesh = parts[0].clone();
    let corners: Vec<Vec3> = mesh.triangles[0]
        .map(|i| mesh.positions[i as usize])
        .to_vec();
    assert_eq!(
        corners,
        [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0)
        ]
    );
    for n in mesh.normals.iter().flatten() {
        assert!((*n - Vec3::Z).length() < 1e-6, "{n}");
    }
    let uvs = mesh.uvs[0];
    // glTF's v runs down the image; rt-gpu's up.
    assert_eq!(uvs[1], glam::Vec2::new(1.0, 0.0), "{uvs:?}");
    assert_eq!(uvs[2], glam::Vec2::new(1.0, 1.0), "{uvs:?}");
    let plain = quantized_gltf(dir.path(), "plain", false);
    let err = rt_gpu::scene::mesh::load(&plain, "plain.gltf", None).expect_err("not FLOAT");
    assert!(err.contains("POSITION (accessor 0) is VEC3 of U8"), "{err}");
    assert!(!err.contains('\n'), "{err}");
}
