//! The Rust structs uploaded to the GPU agree with their WGSL twins, and every kernel variant is
//! valid WGSL. Runs without a GPU: naga does the checking.
#![cfg(feature = "gpu")]

use rt_gpu::gpu::shader::{Features, compose, validate};
use rt_gpu::render::Integrator;
use wgpu::naga;

/// No switch on; arrays sized for small scenes.
fn no_features() -> Features {
    let mut features = Features::of(&small_scene());
    for (name, _) in features.flags() {
        features.set(name, false).expect("a known switch");
    }
    features.scene_capacity = 32;
    features
}

fn all_features() -> Features {
    let mut features = no_features();
    for (name, _) in features.flags() {
        features.set(name, true).expect("a known switch");
    }
    for off in ["SKY", "UNIFORM_SCENE", "INLINE_SCENE"] {
        features.set(off, false).expect("a known switch");
    }
    features
}

/// A scene with a sphere and a box, for kernels that hold the scene as constants.
fn small_scene() -> rt_gpu::scene::flat::FlatScene {
    let scene = rt_gpu::scene::builtin::builtin("cornell").expect("built-in");
    rt_gpu::scene::flat::FlatScene::new(&scene, 8, 8).expect("valid")
}

#[test]
fn rust_structs_match_wgsl_sizes_and_offsets() {
    let source = compose(&all_features(), &small_scene()).expect("composes");
    let (module, _) = validate(&source).unwrap_or_else(|e| panic!("{e}"));
    // The declarations are generated from the Rust structs; naga lays them out independently.
    let mut layouts = rt_gpu::shared::layout::shared_layouts();
    assert_eq!(layouts.len(), 8);
    layouts.extend(rt_gpu::shape::layouts());
    assert_eq!(layouts.len(), 8 + rt_gpu::shape::KINDS.len());
    for layout in layouts {
        assert_layout_matches(&module, layout);
    }
}

/// Switch i (in the order of `Features::flags`) on where bit i is set.
fn features_from_bits(bits: u64) -> Features {
    let mut features = no_features();
    for (i, (name, _)) in no_features().flags().into_iter().enumerate() {
        features
            .set(name, bits & (1u64 << i) != 0)
            .expect("a known switch");
    }
    features
}

/// How many switches the kernel has: material kinds and their extra features among them.
fn feature_count() -> u32 {
    no_features().flags().len() as u32
}

fn assert_validates(bits: u64) {
    let features = features_from_bits(bits);
    let source = compose(&features, &small_scene()).expect("composes");
    if let Err(e) = validate(&source) {
        panic!("{features:?}: {e}");
    }
}

/// Rows of switches (as bits) in which every pair of features takes every pair of values
/// (on/off, on/on, ...) at least once: a greedy covering array, deterministic.
fn pairwise_covering(features: u32) -> Vec<u64> {
    let mut uncovered: Vec<(u32, u32, u32)> = Vec::new(); // (i, j, values of i and j as 2 bits)
    for i in 0..features {
        for j in i + 1..features {
            for values in 0..4 {
                uncovered.push((i, j, values));
            }
        }
    }
    let covers = |row: u64, &(i, j, values): &(u32, u32, u32)| {
        (((row >> i) & 1) | (((row >> j) & 1) << 1)) as u32 == values
    };
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut rows = Vec::new();
    while !uncovered.is_empty() {
        let mut best = (0, 0);
        for _ in 0..64 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let row = state & ((1u64 << features) - 1);
            let count = uncovered.iter().filter(|p| covers(row, p)).count();
            if count > best.1 {
                best = (row, count);
            }
        }
        rows.push(best.0);
        uncovered.retain(|p| !covers(best.0, p));
    }
    rows
}

/// Kernel variants compose into valid WGSL: none and all features, every feature alone and
/// every feature left out, and a pairwise covering set (every two features in every on/off
/// combination): about 75 kernels, where all combinations are 2^35 and double with each new
/// feature. The full set: `cargo test --test it gpu_layout -- --ignored`.
#[test]
fn kernel_variants_validate() {
    let count = feature_count();
    let all = (1u64 << count) - 1;
    let mut rows = vec![0, all];
    for i in 0..count {
        rows.push(1u64 << i);
        rows.push(all & !(1u64 << i));
    }
    let pairwise = pairwise_covering(count);
    assert!(pairwise.len() <= 24, "{} rows", pairwise.len());
    rows.extend(pairwise);
    for bits in rows {
        assert_validates(bits);
    }
}

/// Every combination of features (2^35 kernels) composes into valid WGSL.
#[test]
#[ignore = "slow: 2^35 kernels; the pairwise set above runs by default"]
fn every_kernel_variant_validates() {
    for bits in 0u64..1 << feature_count() {
        assert_validates(bits);
    }
}

/// The specialised kernel leaves out what the scene does not use.
#[test]
fn kernels_leave_out_unused_code() {
    let flat = |name: &str| {
        let scene = rt_gpu::scene::builtin::builtin(name).expect("built-in");
        rt_gpu::scene::flat::FlatScene::new(&scene, 8, 8).expect("valid")
    };
    let kernel = |name: &str| compose(&Features::of(&flat(name)), &flat(name)).expect("composes");
    let empty = kernel("cornell-empty");
    assert!(
        !empty.contains("fn consider_sphere"),
        "sphere code in a scene without spheres"
    );
    assert!(
        !empty.contains("fn fresnel("),
        "dielectric code in a scene without glass"
    );
    assert!(
        !empty.contains("fn metal_sample"),
        "metal code in a scene without metal"
    );
    assert!(
        !empty.contains("fn ggx_d") && !empty.contains("fn conductor_sample"),
        "microfacet code in a scene without a rough conductor"
    );
    // Small scenes are constants in the kernel: one test per primitive, no buffer loop.
    assert_eq!(
        empty.matches("    consider_quad_at(quad_distance_").count(),
        6
    );
    assert_eq!(empty.matches("fn quad_distance_").count(), 6);
    // Constant zero terms left out: the back wall (normal +z) meets a ray at a distance found
    // from z components alone.
    assert!(empty.contains("let t = (to_corner.z) /"));
    assert!(!empty.contains("quads[i]"));
    // With nee, shadow rays keep only distances and indices of the six, then test the one
    // emitting quad (the light) in full.
    let empty_nee = {
        let scene = flat("cornell-empty");
        let features = Features::of(&scene).with_integrator(&scene, Integrator::Nee);
        compose(&features, &scene).expect("composes")
    };
    assert_eq!(
        empty_nee
            .matches("    consider_first(quad_distance_")
            .count(),
        6
    );
    assert_eq!(
        empty_nee
            .matches("    consider_quad_at(quad_distance_")
            .count(),
        6 + 1
    );
    let spheres = kernel("spheres");
    assert!(
        !spheres.contains("fn consider_quad"),
        "quad code in a scene without quads"
    );
    assert_eq!(spheres.matches("    consider_sphere(Sphere(").count(), 4);
    assert!(spheres.contains("fresnel") && spheres.contains("fn metal_sample"));
    // A scene too large to inline goes through its BVH; no triangle code without triangles.
    let showcase = kernel("showcase");
    assert!(showcase.contains("fn traverse") && showcase.contains("spheres[index]"));
    assert!(!showcase.contains("fn inline_scene") && !showcase.contains("fn triangle_hit"));
    // Shading normals only for meshes that have them.
    let placed = |mesh: std::sync::Arc<rt_gpu::scene::mesh::Mesh>, placements| {
        let mut scene = rt_gpu::scene::builtin::builtin("cornell").expect("built-in");
        for k in 0..placements {
            scene.objects.push(rt_gpu::scene::Object {
                shape: rt_gpu::scene::Shape::Mesh {
                    mesh: mesh.clone(),
                    scale: glam::Vec3::splat(50.0),
                },
                material: 0,
                transform: rt_gpu::scene::Transform {
                    rotate_y_degrees: 0.0,
                    translate: glam::Vec3::splat(200.0 + 60.0 * k as f32),
                },
            });
        }
        let flat = rt_gpu::scene::flat::FlatScene::new(&scene, 8, 8).expect("valid");
        compose(&Features::of(&flat), &flat).expect("composes")
    };
    let flat_mesh = rt_gpu::scene::mesh::Mesh::new(
        "tetrahedron",
        vec![
            glam::Vec3::ZERO,
            glam::Vec3::X,
            glam::Vec3::Y,
            glam::Vec3::Z,
        ],
        vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    )
    .expect("valid")
    .shared();
    let mesh_scene = |mesh| placed(mesh, 1);
    let flat_kernel = mesh_scene(flat_mesh.clone());
    assert!(flat_kernel.contains("fn triangle_hit") && !flat_kernel.contains("triangle_normals"));
    // Instances (a mesh placed more than once) only where there are some.
    let instance_code = [
        "fn consider_instanced_triangle",
        "var instance = NO_INSTANCE",
        "instances[",
    ];
    let leaked: Vec<&&str> = instance_code
        .iter()
        .filter(|code| flat_kernel.contains(*code))
        .collect();
    assert!(leaked.is_empty(), "{leaked:?}");
    let instanced_kernel = placed(flat_mesh.clone(), 2);
    assert!(
        instance_code
            .iter()
            .all(|code| instanced_kernel.contains(code))
    );
    let smooth = rt_gpu::scene::mesh::Mesh::with_normals(
        "smooth tetrahedron",
        flat_mesh.positions.clone(),
        flat_mesh.triangles.clone(),
        vec![Some([glam::Vec3::ONE; 3]); 4],
    )
    .expect("valid")
    .shared();
    assert!(mesh_scene(smooth).contains("fn shading_normal"));
    // Nor BVH code in a scene without one.
    let cornell = kernel("cornell");
    assert!(!cornell.contains("fn traverse") && !cornell.contains("fn triangle_hit"));
    // Light sampling only for nee, and only where there is a light.
    let with = |name: &str, integrator| {
        let f = flat(name);
        compose(&Features::of(&f).with_integrator(&f, integrator), &f).expect("composes")
    };
    assert!(with("cornell", Integrator::Nee).contains("fn sample_light"));
    assert!(!with("cornell", Integrator::Naive).contains("fn sample_light"));
    assert!(!with("spheres", Integrator::Nee).contains("fn sample_light"));
}

#[test]
fn a_broken_shader_is_a_clear_error() {
    let err = validate("fn main() -> f32 { return 1u; }").expect_err("invalid");
    assert!(err.contains("WGSL"), "{err}");
    assert!(!err.contains('\n'));
}

/// The display pass's struct, generated into shaders/display.wgsl, as naga lays it out there.
#[test]
fn the_display_struct_matches_its_wgsl() {
    let source = rt_gpu::gpu::display::display_source();
    let (module, _) = validate(&source).unwrap_or_else(|e| panic!("{e}"));
    assert_layout_matches(&module, rt_gpu::shared::layout::display_layout());
}

/// naga's size and field offsets of the struct `layout` names in `module` are Rust's.
fn assert_layout_matches(module: &naga::Module, layout: rt_gpu::shared::layout::StructLayout) {
    let (name, rust_size, rust_fields) = layout;
    let ty = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("WGSL has no struct {name}"))
        .1;
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("{name} is not a struct");
    };
    assert_eq!(*span as usize, rust_size, "size of {name}");
    let wgsl: Vec<(String, usize)> = members
        .iter()
        .map(|m| (m.name.clone().unwrap_or_default(), m.offset as usize))
        .collect();
    let rust: Vec<(String, usize)> = rust_fields
        .into_iter()
        .map(|(n, o)| (n.to_string(), o))
        .collect();
    assert_eq!(wgsl, rust, "fields of {name}");
}

/// Every line of a composed kernel that says where it comes from (`shader::source_of`) is that
/// line of that `.wgsl` file, in kernels of every switch and of shipped scenes; and an error
/// planted on one such line is reported at its file and line, not only at the kernel's line.
#[test]
fn composed_kernels_name_the_wgsl_file_and_line_of_each_line() {
    use rt_gpu::gpu::shader::source_of;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let scenes = ["cornell", "showcase", "textured", "materials", "meshes"].map(|name| {
        let path = root.join(format!("scenes/{name}.toml"));
        let scene = rt_gpu::scene::file::load(&path).expect("loads");
        rt_gpu::scene::flat::FlatScene::new(&scene, 8, 8).expect("valid")
    });
    let mut kernels: Vec<String> = (scenes.iter())
        .map(|f| {
            compose(&Features::of(f).with_integrator(f, Integrator::Nee), f).expect("composes")
        })
        .collect();
    kernels.push(compose(&all_features(), &small_scene()).expect("composes"));
    let mut checked = 0;
    for kernel in &kernels {
        for (index, text) in kernel.lines().enumerate() {
            // The kernel's first line names its features, above every part; headers and marks
            // are the composer's own, as are the blank lines between parts.
            if index == 0
                || text.is_empty()
                || text.starts_with("// ---- ")
                || text.starts_with("//# ")
            {
                continue;
            }
            let Some(place) = source_of(kernel, index + 1) else {
                panic!("line {}: no source", index + 1)
            };
            let Some((file, line)) = place.split_once(".wgsl:") else {
                continue; // a generated part
            };
            let line: usize = line.parse().expect("a line number");
            let source = std::fs::read_to_string(root.join(format!("{file}.wgsl"))).expect("reads");
            assert_eq!(source.lines().nth(line - 1), Some(text), "{place}");
            checked += 1;
        }
    }
    assert!(checked > 5000, "{checked} lines checked");
    // An error planted on a line of shaders/integrator.wgsl.
    let kernel = &kernels[1];
    let (index, _) = (kernel.lines().enumerate())
        .find(|(i, text)| {
            text.trim_start().starts_with("let ")
                && source_of(kernel, i + 1)
                    .is_some_and(|p| p.starts_with("shaders/integrator.wgsl:"))
        })
        .expect("a let in the integrator");
    let place = source_of(kernel, index + 1).expect("a place");
    let broken: Vec<&str> = (kernel.lines().enumerate())
        .map(|(i, text)| {
            if i == index {
                "let planted_error: f32 = 1u;"
            } else {
                text
            }
        })
        .collect();
    let err = validate(&broken.join("\n")).expect_err("invalid");
    assert!(err.starts_with(&format!("{place}: ")), "{place}: {err}");
}
