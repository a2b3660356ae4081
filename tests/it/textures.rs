//! Textured albedos: the scene-file syntax and its errors, CPU and GPU images of a textured
//! scene (Welch z + Sidak, tests/it/common/stats.rs, family-wise 0.01) with a negative control,
//! and kernels that leave texture code out of scenes without textures.
#![cfg_attr(not(feature = "gpu"), allow(unused))]

use crate::common;

#[cfg(feature = "gpu")]
use common::gpu::{render_gpu, renderer};
use common::stats::compare;
use glam::Vec3;
#[cfg(feature = "gpu")]
use rt_gpu::gpu::Tuning;
use rt_gpu::scene::Scene;
use rt_gpu::scene::file::{parse, to_toml};
use rt_gpu::scene::flat::FlatScene;

const TEXTURED: &str = r#"
[render]
background = [0.9, 0.9, 1.0]

[camera]
look_from = [0, 1.5, 4]
look_at = [0, 0.4, 0]
vfov = 45

[materials]
floor = { type = "lambertian", albedo = { uv_checker = { scale = 8, even = [0.9, 0.9, 0.9], odd = [0.2, 0.3, 0.1] } } }
solid = { type = "lambertian", albedo = { checker = { scale = 0.25, even = [0.8, 0.1, 0.1], odd = [0.9, 0.9, 0.2] } } }
globe = { type = "lambertian", albedo = { uv_checker = { scale = 6, even = [0.1, 0.2, 0.8], odd = [0.9, 0.9, 0.9] } } }
brass = { type = "metal", albedo = { checker = { scale = 0.3, even = [0.8, 0.6, 0.2], odd = [0.5, 0.5, 0.5] } }, fuzz = 0.3 }

[[object]]
quad = { q = [-3, 0, 3], u = [6, 0, 0], v = [0, 0, -6] }
material = "floor"

[[object]]
sphere = { center = [-1.1, 0.5, 0], radius = 0.5 }
material = "solid"

[[object]]
sphere = { center = [0, 0.5, 0], radius = 0.5 }
material = "globe"

[[object]]
box = { min = [0.7, 0, -0.4], max = [1.5, 0.8, 0.4] }
rotate_y = 20
material = "brass"
"#;

fn textured() -> Scene {
    parse(TEXTURED, "textured.toml", "textured").unwrap_or_else(|e| panic!("{e}"))
}

/// The syntax reads and writes back to the same scene; bad textures are one-line errors.
#[test]
fn texture_syntax_round_trips_and_errors_are_one_line() {
    let scene = textured();
    let again = parse(&to_toml(&scene), "again.toml", "textured").expect("exported scene parses");
    assert_eq!(scene.materials, again.materials);
    for (albedo, words) in [
        (
            "{ checker = { scale = 0, even = [1, 1, 1], odd = [0, 0, 0] } }",
            "checker scale must be in (0",
        ),
        (
            "{ checker = { scale = 1, even = [1, 2, 1], odd = [0, 0, 0] } }",
            "[0, 1]",
        ),
        (
            "{ checker = { scale = 1, even = [1, 1, 1] } }",
            "missing field `odd`",
        ),
        ("{ marble = { scale = 1 } }", "unknown field `marble`"),
        (
            "{ checker = { scale = 1, even = [1, 1, 1], odd = [0, 0, 0], size = 2 } }",
            "unknown field `size`",
        ),
        ("\"red\"", "a colour [r, g, b]"),
    ] {
        let text = format!(
            "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\nvfov = 40\n\n[materials]\nm = {{ type = \"lambertian\", albedo = {albedo} }}\n\n[[object]]\nsphere = {{ center = [0, 0, 0], radius = 1 }}\nmaterial = \"m\"\n"
        );
        let error = parse(&text, "m.toml", "m")
            .map(|_| ())
            .expect_err(albedo)
            .to_string();
        assert!(
            error.starts_with("m.toml:") && error.contains(words) && !error.contains('\n'),
            "{albedo}: {error}"
        );
    }
}

#[cfg(feature = "gpu")]
/// CPU and GPU render the textured scene alike (solid and UV checkers on spheres, a quad and a
/// box, lambertian and metal); the same test catches the GPU with one checker colour 3%
/// brighter.
#[test]
fn gpu_textures_match_cpu_textures() {
    let Some(gpu) = renderer() else { return };
    let scene = textured();
    let opts = |seed| common::opts(32, 24, 2000, 6, seed);
    let cpu = common::render_cpu(&scene, &opts(1));
    let gpu_film = render_gpu(&gpu, &scene, &opts(2), &Tuning::default());
    let verdict = compare(&cpu, &gpu_film);
    eprintln!("cpu vs gpu: {verdict:?}");
    assert!(verdict.passed(), "CPU and GPU textures differ: {verdict:?}");
    let brighter = parse(
        &TEXTURED.replace("odd = [0.2, 0.3, 0.1]", "odd = [0.206, 0.309, 0.103]"),
        "brighter.toml",
        "textured",
    )
    .expect("parses");
    let verdict = compare(
        &cpu,
        &render_gpu(&gpu, &brighter, &opts(2), &Tuning::default()),
    );
    eprintln!("floor's odd squares 3% brighter: {verdict:?}");
    assert!(!verdict.passed(), "a 3% brighter checker went undetected");
}

#[cfg(feature = "gpu")]
/// Only scenes with textures get texture code, and only the kind they use.
#[test]
fn only_textured_scenes_get_texture_code() {
    use rt_gpu::gpu::Features;
    use rt_gpu::gpu::shader::compose;
    let solid_only = TEXTURED.replace("uv_checker", "checker");
    for (name, scene, solid, uv) in [
        (
            "cornell",
            rt_gpu::scene::builtin::builtin("cornell").expect("built-in"),
            false,
            false,
        ),
        ("textured", textured(), true, true),
        (
            "solid only",
            parse(&solid_only, "s.toml", "s").expect("parses"),
            true,
            false,
        ),
    ] {
        let flat = FlatScene::new(&scene, 8, 8).expect("valid");
        let features = Features::of(&flat);
        let source = compose(&features, &flat).expect("composes");
        assert_eq!(
            features.has_material(rt_gpu::material::MaterialFeature::Checker),
            solid,
            "{name}"
        );
        assert_eq!(
            features.has_material(rt_gpu::material::MaterialFeature::UvChecker),
            uv,
            "{name}"
        );
        assert_eq!(source.contains("fn parity("), solid || uv, "{name}");
        assert_eq!(source.contains("fn sphere_uv("), uv, "{name}");
        assert_eq!(flat.uv_textures, uv, "{name}");
    }
}

/// Solid checkers stay put in the world when the flat scene is re-centred on the camera:
/// moved by a whole number of checker periods (3072 = 6144 x 0.5 = 5120 x 0.6), to where the
/// flat scene's origin is (3072, 0, -2048), not a multiple of the brass's 0.6-unit period, the
/// image is the same.
#[test]
fn solid_checkers_stay_put_in_the_world() {
    let near = textured();
    let mut far = near.clone();
    let shift = Vec3::new(3072.0, 0.0, -3072.0);
    far.camera.look_from += shift;
    far.camera.look_at += shift;
    for object in &mut far.objects {
        object.transform.translate += shift;
    }
    let opts = common::opts(32, 24, 256, 6, 1);
    let moved = FlatScene::new(&far, 8, 8).expect("valid").origin;
    assert_eq!(moved, glam::DVec3::new(3072.0, 0.0, -2048.0));
    let verdict = compare(
        &common::render_cpu(&near, &opts),
        &common::render_cpu(&far, &common::opts(32, 24, 256, 6, 2)),
    );
    eprintln!("near vs moved: {verdict:?}");
    assert!(verdict.passed(), "the pattern moved: {verdict:?}");
}

#[cfg(feature = "gpu")]
/// The kernel's texture lookups equal the CPU's at known points and UVs (solid and UV
/// checkers, lambertian and metal): 20 000 random lookups, of which at most 0.1% may differ
/// (a point within rounding of a cell boundary: GPU division may round differently), and every
/// GPU value is one of the checker's two colours; against checkers 2% larger, more differ
/// (negative control).
#[test]
fn gpu_texture_lookups_match_the_cpu() {
    let Some(gpu) = renderer() else { return };
    let scene = textured();
    let flat = FlatScene::new(&scene, 8, 8).expect("valid");
    let textures: Vec<(u32, rt_gpu::assets::texture::Texture)> = flat
        .materials
        .iter()
        .enumerate()
        .filter_map(|(i, m)| match m {
            rt_gpu::scene::Material::Lambertian(l) => Some((i as u32, l.albedo.clone())),
            rt_gpu::scene::Material::Metal(m) => Some((i as u32, m.albedo.clone())),
            _ => None,
        })
        .collect();
    assert_eq!(textures.len(), 4);
    let mut rng = rt_gpu::shared::rng::Rng::for_sample(0, 0, 5);
    let lookups: Vec<(u32, Vec3, glam::Vec2)> = (0..20_000)
        .map(|k| {
            let (material, _) = textures[k % textures.len()];
            let point = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 6.0 - 3.0;
            (
                material,
                point,
                glam::Vec2::new(rng.next_f32(), rng.next_f32()),
            )
        })
        .collect();
    let gpu_values = gpu.look_up_albedo(&flat, &lookups).expect("lookups run");
    let (mut differ, mut differ_from_larger) = (0, 0);
    for ((material, point, uv), gpu_value) in lookups.iter().zip(gpu_values) {
        let (_, texture) = textures.iter().find(|(m, _)| m == material).expect("known");
        let hit = rt_gpu::shared::ray::Hit {
            t: 1.0,
            point: *point,
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
            uv: *uv,
            uv1: *uv,
            color: Vec3::ONE,
        };
        let cpu_value = rt_gpu::material::texture::value(texture, &hit);
        // Negative control: the same comparison against checkers 2% larger must disagree.
        let larger = match texture.clone() {
            rt_gpu::assets::texture::Texture::Checker(c) => {
                rt_gpu::assets::texture::Texture::Checker(rt_gpu::assets::texture::Checker {
                    scale: c.scale * 1.02,
                    ..c
                })
            }
            rt_gpu::assets::texture::Texture::UvChecker(c) => {
                rt_gpu::assets::texture::Texture::UvChecker(rt_gpu::assets::texture::Checker {
                    scale: c.scale * 1.02,
                    ..c
                })
            }
            other => other,
        };
        differ_from_larger +=
            (gpu_value != rt_gpu::material::texture::value(&larger, &hit)) as usize;
        let (even, odd) = match texture {
            rt_gpu::assets::texture::Texture::Checker(c)
            | rt_gpu::assets::texture::Texture::UvChecker(c) => (c.even, c.odd),
            rt_gpu::assets::texture::Texture::Colour(c) => (*c, *c),
            rt_gpu::assets::texture::Texture::Image(_) => unreachable!("no images here"),
        };
        assert!(
            gpu_value == even || gpu_value == odd,
            "{gpu_value} at {point} {uv}"
        );
        differ += (gpu_value != cpu_value) as usize;
    }
    eprintln!(
        "{differ} of {} lookups differ ({differ_from_larger} from checkers 2% larger)",
        lookups.len()
    );
    assert!(differ <= lookups.len() / 1000, "{differ} lookups differ");
    assert!(
        differ_from_larger > lookups.len() / 1000,
        "checkers 2% larger went undetected"
    );
}

/// Images read with every wrap mode and filter (glTF's samplers) give the CPU's values on the
/// GPU, at coordinates well beyond [0, 1]; negative control: read as the default (repeat,
/// linear) the CPU's values differ from the GPU's.
#[cfg(feature = "gpu")]
#[test]
fn gpu_image_lookups_wrap_and_filter_as_the_cpu() {
    use rt_gpu::assets::image_lookup::{Filter, ImageLookup, Wrap};
    use rt_gpu::assets::texture::Texture;
    let Some(gpu) = renderer() else { return };
    let mut text = String::from(
        "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\nvfov = 40\n[materials]\n",
    );
    let mut objects = String::new();
    let wraps = [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror];
    let mut lookups_wanted = Vec::new();
    for wrap_u in wraps {
        for wrap_v in wraps {
            for filter in [Filter::Linear, Filter::Nearest] {
                let k = lookups_wanted.len();
                lookups_wanted.push(ImageLookup {
                    wrap_u,
                    wrap_v,
                    filter,
                    ..ImageLookup::default()
                });
                text += &format!(
                    "m{k} = {{ type = \"lambertian\", albedo = {{ image = \"textures/tiles.png\" }} }}\n"
                );
                objects += &format!(
                    "[[object]]\nquad = {{ q = [{k}, 0, 0], u = [1, 0, 0], v = [0, 1, 0] }}\nmaterial = \"m{k}\"\n"
                );
            }
        }
    }
    let mut scene = textured_lights(&(text + &objects));
    for (material, lookup) in scene.materials.iter_mut().zip(&lookups_wanted) {
        let rt_gpu::scene::Material::Lambertian(l) = material else {
            panic!("lambertian")
        };
        let Texture::Image(image) = &l.albedo else {
            panic!("an image")
        };
        l.albedo = Texture::Image(image.with_lookup(*lookup).shared());
    }
    let flat = FlatScene::new(&scene, 8, 8).expect("valid");
    assert_eq!(flat.materials.len(), lookups_wanted.len());
    let mut rng = rt_gpu::shared::rng::Rng::for_sample(0, 0, 7);
    let lookups: Vec<(u32, Vec3, glam::Vec2)> = (0..18_000)
        .map(|k| {
            let uv = glam::Vec2::new(rng.next_f32(), rng.next_f32()) * 5.0 - 2.0;
            ((k % flat.materials.len()) as u32, Vec3::ZERO, uv)
        })
        .collect();
    let gpu_values = gpu.look_up_albedo(&flat, &lookups).expect("lookups run");
    let (mut worst, mut differ_from_default) = (0.0f32, 0);
    for ((material, point, uv), gpu_value) in lookups.iter().zip(gpu_values) {
        let rt_gpu::scene::Material::Lambertian(l) = &flat.materials[*material as usize] else {
            panic!("lambertian")
        };
        let Texture::Image(image) = &l.albedo else {
            panic!("an image")
        };
        let hit = rt_gpu::shared::ray::Hit {
            t: 1.0,
            point: *point,
            error: 0.0,
            normal: Vec3::Z,
            shading: Vec3::Z,
            coat: Vec3::Z,
            front_face: true,
            material: *material,
            primitive: rt_gpu::shared::primitive::PrimitiveRef::Shape {
                kind: rt_gpu::shape::Quad::KIND,
                index: 0,
            },
            uv: *uv,
            uv1: *uv,
            color: Vec3::ONE,
        };
        let cpu_value = rt_gpu::material::texture::value(&l.albedo, &hit);
        worst = worst.max((gpu_value - cpu_value).abs().max_element());
        let default = image.with_lookup(ImageLookup::default());
        let as_default = rt_gpu::assets::image_lookup::image_at(&default, *uv);
        differ_from_default += ((gpu_value - as_default).abs().max_element() > 1e-3) as usize;
    }
    eprintln!(
        "largest difference {worst:e}; {differ_from_default} of {} differ from the default lookup",
        lookups.len()
    );
    // Bilinear weights may round differently (fused multiply-adds); a wrong texel is off by
    // far more.
    assert!(worst < 1e-5, "GPU and CPU lookups differ by {worst}");
    assert!(
        differ_from_default > lookups.len() / 2,
        "lookups read as the default went undetected"
    );
}

/// A floor of glTF's pbr whose metallic and roughness an image scales point by point (the
/// tiles' blue and green channels: metals and dielectrics, smooth and rough), a textured ball of
/// it, and an area light.
const METALLIC_ROUGHNESS: &str = r#"
[render]
background = [0.05, 0.05, 0.06]

[camera]
look_from = [0, 1.6, 3]
look_at = [0, 0.2, 0]
vfov = 50

[materials]
floor = { type = "pbr", base_color = [0.8, 0.6, 0.3], metallic = 1, roughness = 0.8, metallic_roughness = "textures/tiles.png" }
ball = { type = "pbr", base_color = { image = "textures/planet.png" }, metallic = 0.9, roughness = 1, metallic_roughness = "textures/tiles.png" }
lamp = { type = "light", radiance = [6, 6, 6] }

[[object]]
quad = { q = [-2, 0, 2], u = [4, 0, 0], v = [0, 0, -4] }
material = "floor"

[[object]]
sphere = { center = [0.5, 0.5, 0], radius = 0.5 }
material = "ball"

[[object]]
quad = { q = [-1.5, 2.5, -1], u = [1, 0, 0], v = [0, 0, 1] }
material = "lamp"
"#;

#[cfg(feature = "gpu")]
/// Metallic-roughness images: the kernel renders them as the CPU does (nee, 24x18 at 2 048
/// spp, Welch z + Sidak at family-wise 0.01); negative control: the floor's roughness 2% higher
/// on the GPU is told apart.
#[test]
fn parameter_images_render_alike_on_both_backends() {
    let Some(gpu) = renderer() else { return };
    let scene = textured_lights(METALLIC_ROUGHNESS);
    let flat = FlatScene::new(&scene, 8, 8).expect("valid");
    assert!(flat.materials.iter().any(|m| m.parameter_image().is_some()));
    let opts = |seed| common::nee_opts(24, 18, 2048, 5, seed);
    let cpu = common::render_cpu(&scene, &opts(1));
    assert_eq!(cpu.invalid_samples, 0);
    let gpu_film = render_gpu(&gpu, &scene, &opts(2), &Tuning::default());
    let verdict = compare(&cpu, &gpu_film);
    eprintln!("metallic-roughness, cpu vs gpu: {verdict:?}");
    assert!(verdict.passed(), "CPU and GPU differ: {verdict:?}");
    let rougher =
        textured_lights(&METALLIC_ROUGHNESS.replace("roughness = 0.8", "roughness = 0.816"));
    let verdict = compare(
        &cpu,
        &render_gpu(&gpu, &rougher, &opts(2), &Tuning::default()),
    );
    eprintln!("floor 2% rougher: {verdict:?}");
    assert!(!verdict.passed(), "a 2% rougher floor went undetected");
}

/// Lights with textured radiance: a quad showing an image (scaled by `strength`), a sphere
/// with a UV checker; beside them diffuse surfaces that nee lights.
const TEXTURED_LIGHTS: &str = r#"
[render]
background = [0.02, 0.02, 0.02]

[camera]
look_from = [0, 1.5, 4]
look_at = [0, 0.5, 0]
vfov = 50

[materials]
floor = { type = "lambertian", albedo = [0.7, 0.7, 0.7] }
panel = { type = "light", radiance = { image = "textures/tiles.png" }, strength = 6 }
bulb = { type = "light", radiance = { uv_checker = { scale = 4, even = [1, 0.9, 0.6], odd = [0.1, 0.2, 0.9] } }, strength = 4, two_sided = true }

[[object]]
quad = { q = [-3, 0, 3], u = [6, 0, 0], v = [0, 0, -6] }
material = "floor"

[[object]]
quad = { q = [-1, 0.2, -1], u = [2, 0, 0], v = [0, 1.5, 0] }
material = "panel"

[[object]]
sphere = { center = [1.2, 0.4, 0.8], radius = 0.4 }
material = "bulb"
"#;

fn textured_lights(text: &str) -> Scene {
    let loader = rt_gpu::assets::loader::Loader::new(std::path::Path::new("scenes"));
    rt_gpu::scene::file::parse_with(&loader, text, "lights.toml", "lights")
        .unwrap_or_else(|e| panic!("{e}"))
}

#[cfg(feature = "gpu")]
/// Textured emitters: naive and nee agree (MIS with light sampling by area, whatever the
/// texture), and CPU and GPU agree; the panel 3% brighter is told apart (negative control).
#[test]
fn textured_lights_render_alike_every_way() {
    let scene = textured_lights(TEXTURED_LIGHTS);
    let brighter = textured_lights(&TEXTURED_LIGHTS.replace("strength = 6", "strength = 6.18"));
    let naive = common::render_cpu(&scene, &common::opts(24, 18, 1024, 4, 1));
    let nee = common::render_cpu(&scene, &common::nee_opts(24, 18, 256, 4, 2));
    let verdict = compare(&naive, &nee);
    eprintln!("naive vs nee: {verdict:?}");
    assert!(verdict.passed(), "naive and nee differ: {verdict:?}");
    let verdict = compare(
        &naive,
        &common::render_cpu(&brighter, &common::nee_opts(24, 18, 256, 4, 2)),
    );
    eprintln!("naive vs nee with the panel 3% brighter: {verdict:?}");
    assert!(!verdict.passed(), "a 3% brighter panel went undetected");
    let Some(gpu) = renderer() else { return };
    let gpu_nee = render_gpu(
        &gpu,
        &scene,
        &common::nee_opts(24, 18, 256, 4, 3),
        &Tuning::default(),
    );
    let verdict = compare(&nee, &gpu_nee);
    eprintln!("cpu vs gpu nee: {verdict:?}");
    assert!(verdict.passed(), "CPU and GPU differ: {verdict:?}");
}

/// `specular_image` (linear, its red channel) and `specular_color_image` (a colour image) on a
/// scene file's pbr are its specular's images, with the default specular for them to scale
/// where the file gives none; a specular image above 1 in red is a one-line error naming it.
#[test]
fn specular_images_are_read_from_scene_files() {
    let scene = |material: &str| {
        let text = format!(
            "{}\n[materials]\nglaze = {material}\n[[object]]\nsphere = {{ center = [0, 0, 0], radius = 0.5 }}\nmaterial = \"glaze\"\n",
            "[camera]\nlook_from = [0, 0, 3]\nlook_at = [0, 0, 0]\nvfov = 40\n"
        );
        let loader = rt_gpu::assets::loader::Loader::new(std::path::Path::new("scenes"));
        rt_gpu::scene::file::parse_with(&loader, &text, "glaze.toml", "glaze")
    };
    let s = scene(
        r#"{ type = "pbr", base_color = [0.1, 0.1, 0.1], metallic = 0, specular_image = "textures/tiles.png", specular_color_image = "textures/planet.png" }"#,
    )
    .expect("parses");
    let rt_gpu::scene::Material::Pbr(p) = &s.materials[0] else {
        panic!("{:?}", s.materials[0]);
    };
    assert_eq!(
        p.specular().map(|s| (s.factor, s.color)),
        Some((1.0, Vec3::ONE))
    );
    assert!(
        p.specular_image()
            .is_some_and(|i| i.source.ends_with("tiles.png"))
    );
    assert!(
        p.specular_color_image()
            .is_some_and(|i| i.source.ends_with("planet.png"))
    );
    // Written back, it reads as the same material.
    let loader = rt_gpu::assets::loader::Loader::new(std::path::Path::new("scenes"));
    let again = rt_gpu::scene::file::parse_with(&loader, &to_toml(&s), "again.toml", "glaze")
        .expect("exported scene parses");
    assert_eq!(again.materials, s.materials);
    let error = scene(
        r#"{ type = "pbr", base_color = [0.1, 0.1, 0.1], metallic = 0, specular_image = "textures/sky.hdr" }"#,
    )
    .expect_err("values above 1");
    let error = error.to_string();
    assert!(
        error.contains("specular image") && error.contains("red channel") && !error.contains('\n'),
        "{error}"
    );
}

/// A clear coat's normal map on a scene file's pbr without a clear coat is a one-line error
/// naming it, not a map silently left unused; with the coat, it reads and is written back.
#[test]
fn a_clear_coat_normal_map_needs_a_clear_coat() {
    let text = |coat: &str| {
        format!(
            "[camera]\nlook_from = [0, 0, 3]\nlook_at = [0, 0, 0]\nvfov = 40\n[materials]\nglaze = {{ type = \"pbr\", base_color = [0.5, 0.1, 0.1], metallic = 0{coat}, clearcoat_normal_map = {{ image = \"blender/bumpy-normals.png\", scale = 1 }} }}\n[[object]]\nmesh = {{ file = \"blender/bumpy.glb\", node = \"Cube\" }}\nmaterial = \"glaze\"\n"
        )
    };
    let loader = rt_gpu::assets::loader::Loader::new(std::path::Path::new("scenes"));
    let parse = |t: &str| rt_gpu::scene::file::parse_with(&loader, t, "glaze.toml", "glaze");
    let error = parse(&text("")).expect_err("no coat").to_string();
    assert!(
        error.contains("clearcoat_normal_map") && !error.contains('\n'),
        "{error}"
    );
    let scene = parse(&text(", clearcoat = { factor = 1 }")).expect("parses");
    let again = parse(&to_toml(&scene)).expect("exported scene parses");
    assert_eq!(again.materials, scene.materials);
    let rt_gpu::scene::Material::Pbr(p) = &scene.materials[0] else {
        panic!("{:?}", scene.materials[0]);
    };
    assert!(rt_gpu::material::MaterialModel::coat_normal_map(p).is_some());
}
