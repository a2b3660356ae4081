//! The Rust structs uploaded to the GPU agree with their WGSL twins, and every kernel variant is
//! valid WGSL. Runs without a GPU: naga does the checking.

use rt_gpu::gpu::layout::{GpuFirstBounce, GpuLight, GpuMaterial, GpuParams, GpuQuad, GpuSphere};
use rt_gpu::gpu::shader::{Features, compose, validate};
use rt_gpu::render::Integrator;
use std::mem::{offset_of, size_of};
use wgpu::naga;

fn all_features() -> Features {
    Features {
        spheres: true,
        quads: true,
        lambertian: true,
        metal: true,
        dielectric: true,
        light: true,
        emissive: true,
        lens: true,
        sky: false,
        debug: true,
        nee: true,
        uniform_scene: false,
        scene_capacity: 1,
        inline_scene: false,
    }
}

/// A scene with a sphere and a box, for kernels that hold the scene as constants.
fn small_scene() -> rt_gpu::scene::flat::FlatScene {
    let scene = rt_gpu::scene::builtin::builtin("cornell").expect("built-in");
    rt_gpu::scene::flat::FlatScene::new(&scene, 8, 8).expect("valid")
}

/// A Rust struct's WGSL name, size, and field offsets in declaration order.
type Layout = (&'static str, usize, Vec<(&'static str, usize)>);

fn rust_layouts() -> Vec<Layout> {
    vec![
        (
            "Sphere",
            size_of::<GpuSphere>(),
            vec![
                ("center", offset_of!(GpuSphere, center)),
                ("radius", offset_of!(GpuSphere, radius)),
                ("material", offset_of!(GpuSphere, material)),
                ("light", offset_of!(GpuSphere, light)),
            ],
        ),
        (
            "Quad",
            size_of::<GpuQuad>(),
            vec![
                ("q", offset_of!(GpuQuad, q)),
                ("d", offset_of!(GpuQuad, d)),
                ("normal", offset_of!(GpuQuad, normal)),
                ("material", offset_of!(GpuQuad, material)),
                ("alpha_axis", offset_of!(GpuQuad, alpha_axis)),
                ("light", offset_of!(GpuQuad, light)),
                ("beta_axis", offset_of!(GpuQuad, beta_axis)),
                ("edge_tolerance", offset_of!(GpuQuad, edge_tolerance)),
            ],
        ),
        (
            "Light",
            size_of::<GpuLight>(),
            vec![
                ("position", offset_of!(GpuLight, position)),
                ("cdf", offset_of!(GpuLight, cdf)),
                ("u", offset_of!(GpuLight, u)),
                ("pick", offset_of!(GpuLight, pick)),
                ("v", offset_of!(GpuLight, v)),
                ("radius", offset_of!(GpuLight, radius)),
                ("normal", offset_of!(GpuLight, normal)),
                ("inv_area", offset_of!(GpuLight, inv_area)),
            ],
        ),
        (
            "Material",
            size_of::<GpuMaterial>(),
            vec![
                ("albedo", offset_of!(GpuMaterial, albedo)),
                ("kind", offset_of!(GpuMaterial, kind)),
                ("emission", offset_of!(GpuMaterial, emission)),
                ("param", offset_of!(GpuMaterial, param)),
            ],
        ),
        (
            "Params",
            size_of::<GpuParams>(),
            vec![
                ("origin", offset_of!(GpuParams, origin)),
                ("lens_radius", offset_of!(GpuParams, lens_radius)),
                ("to_upper_left", offset_of!(GpuParams, to_upper_left)),
                ("width", offset_of!(GpuParams, width)),
                ("horizontal", offset_of!(GpuParams, horizontal)),
                ("height", offset_of!(GpuParams, height)),
                ("vertical", offset_of!(GpuParams, vertical)),
                ("max_depth", offset_of!(GpuParams, max_depth)),
                ("right", offset_of!(GpuParams, right)),
                ("seed", offset_of!(GpuParams, seed)),
                ("up", offset_of!(GpuParams, up)),
                ("first_sample", offset_of!(GpuParams, first_sample)),
                ("background", offset_of!(GpuParams, background)),
                ("sample_count", offset_of!(GpuParams, sample_count)),
                ("tile_origin", offset_of!(GpuParams, tile_origin)),
                ("tile_size", offset_of!(GpuParams, tile_size)),
                ("sphere_count", offset_of!(GpuParams, sphere_count)),
                ("quad_count", offset_of!(GpuParams, quad_count)),
                ("samples_before", offset_of!(GpuParams, samples_before)),
                ("sky", offset_of!(GpuParams, sky)),
                ("light_count", offset_of!(GpuParams, light_count)),
                ("roulette_depth", offset_of!(GpuParams, roulette_depth)),
            ],
        ),
        (
            "FirstBounce",
            size_of::<GpuFirstBounce>(),
            vec![
                ("point", offset_of!(GpuFirstBounce, point)),
                ("primitive", offset_of!(GpuFirstBounce, primitive)),
                ("normal", offset_of!(GpuFirstBounce, normal)),
                ("hit", offset_of!(GpuFirstBounce, hit)),
                ("dir", offset_of!(GpuFirstBounce, dir)),
                ("scattered", offset_of!(GpuFirstBounce, scattered)),
            ],
        ),
    ]
}

#[test]
fn rust_structs_match_wgsl_sizes_and_offsets() {
    let source = compose(&all_features(), &small_scene()).expect("composes");
    let (module, _) = validate(&source).unwrap_or_else(|e| panic!("{e}"));
    for (name, rust_size, rust_fields) in rust_layouts() {
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
        let wgsl_fields: Vec<(String, usize)> = members
            .iter()
            .map(|m| (m.name.clone().unwrap_or_default(), m.offset as usize))
            .collect();
        let rust_fields: Vec<(String, usize)> = rust_fields
            .into_iter()
            .map(|(n, o)| (n.to_string(), o))
            .collect();
        assert_eq!(wgsl_fields, rust_fields, "fields of {name}");
    }
}

/// Every combination of features (2^13 kernels) composes into valid WGSL.
#[test]
fn every_kernel_variant_validates() {
    let scene = small_scene();
    for bits in 0u32..1 << 13 {
        let on = |i: u32| bits & (1 << i) != 0;
        let features = Features {
            spheres: on(0),
            quads: on(1),
            lambertian: on(2),
            metal: on(3),
            dielectric: on(4),
            light: on(5),
            emissive: on(6),
            lens: on(7),
            sky: on(8),
            debug: on(9),
            uniform_scene: on(10),
            scene_capacity: 32,
            inline_scene: on(11),
            nee: on(12),
        };
        let source = compose(&features, &scene).expect("composes");
        if let Err(e) = validate(&source) {
            panic!("{features:?}: {e}");
        }
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
        !empty.contains("fresnel"),
        "dielectric code in a scene without glass"
    );
    assert!(
        !empty.contains("MAT_METAL {"),
        "metal code in a scene without metal"
    );
    // Small scenes are constants in the kernel: one test per primitive, no buffer loop.
    assert_eq!(empty.matches("    consider_quad(Quad(").count(), 6);
    assert!(!empty.contains("quads[i]"));
    let spheres = kernel("spheres");
    assert!(
        !spheres.contains("fn consider_quad"),
        "quad code in a scene without quads"
    );
    assert_eq!(spheres.matches("    consider_sphere(Sphere(").count(), 4);
    assert!(spheres.contains("fresnel") && spheres.contains("MAT_METAL {"));
    // A scene too large to inline loops over its buffers.
    let showcase = kernel("showcase");
    assert!(showcase.contains("spheres[i]") && showcase.contains("quads[i]"));
    assert!(!showcase.contains("fn inline_scene"));
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
