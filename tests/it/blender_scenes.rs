//! Files Blender 3.4 really wrote (`scripts/blender/make-scenes.py`, committed under
//! scenes/blender/): they load as scenes, and their materials and cameras arrive with the
//! values the script set, field by field.

#[cfg(feature = "gpu")]
use crate::common;

use glam::Vec3;
use rt_gpu::assets::texture::Texture;
use rt_gpu::material::Pbr;
use rt_gpu::scene::gltf_scene::{load, read_extras};
use rt_gpu::scene::punctual::Punctual;
use rt_gpu::scene::{Background, Material, Scene};
use std::path::Path;

fn blender_file(name: &str) -> (Scene, Vec<String>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/blender")
        .join(name);
    load(&path, name, None).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() < 1e-5
}

fn material<'a>(scene: &'a Scene, file: &str, name: &str) -> &'a Material {
    let i = scene
        .material_names
        .iter()
        .position(|n| *n == format!("{file}#{name}"))
        .unwrap_or_else(|| panic!("no material {name} in {:?}", scene.material_names));
    &scene.materials[i]
}

/// (name, base colour, metallic, roughness, transmission) as the script sets them.
const PRINCIPLED: [(&str, [f32; 3], f32, f32, f32); 5] = [
    ("Floor", [0.6, 0.6, 0.6], 0.0, 1.0, 0.0),
    ("Gold", [1.0, 0.77, 0.34], 1.0, 0.3, 0.0),
    ("Chrome", [0.9, 0.9, 0.9], 1.0, 0.05, 0.0),
    ("Glass", [1.0, 1.0, 1.0], 0.0, 0.0, 1.0),
    ("Clay", [0.8, 0.3, 0.2], 0.0, 1.0, 0.0),
];

#[test]
fn blenders_materials_arrive_as_the_script_set_them() {
    for file in ["spheres.glb", "lamps.glb"] {
        let (scene, _) = blender_file(file);
        for (name, colour, metallic, roughness, transmission) in PRINCIPLED {
            let Material::Pbr(pbr) = material(&scene, file, name) else {
                panic!("{file} {name}: not pbr");
            };
            assert_eq!(
                pbr.base_color,
                Texture::Colour(Vec3::from_array(colour)),
                "{name}"
            );
            assert!(close(pbr.metallic, metallic), "{name}: {}", pbr.metallic);
            assert!(close(pbr.roughness, roughness), "{name}: {}", pbr.roughness);
            assert!(close(pbr.transmission, transmission), "{name}");
            assert!(close(pbr.ior, 1.5), "{name}: IOR {}", pbr.ior);
        }
    }
    let (scene, _) = blender_file("spheres.glb");
    let Material::Pbr(Pbr {
        emission: Some(panel),
        ..
    }) = material(&scene, "spheres.glb", "Panel")
    else {
        panic!("the panel does not emit");
    };
    assert_eq!(panel.radiance, Texture::Colour(Vec3::new(1.0, 0.9, 0.8)));
    assert!(close(panel.strength, 8.0), "{}", panel.strength);
    assert!(
        matches!(scene.background, Background::Environment(_)),
        "no lamps: lit by a sky, its panel glowing on top"
    );
}

#[test]
fn blenders_cameras_and_lights_arrive_as_the_script_set_them() {
    // Blender's z-up (x, y, z) is glTF's y-up (x, z, -y).
    let (scene, notes) = blender_file("spheres.glb");
    assert!(notes.is_empty(), "{notes:?}");
    let c = &scene.camera;
    assert!(
        (c.look_from - Vec3::new(0.0, 3.2, 7.0)).length() < 1e-5,
        "{c:?}"
    );
    let toward = (Vec3::new(0.0, 0.6, 0.0) - c.look_from).normalize();
    assert!(
        (c.look_at - c.look_from).normalize().dot(toward) > 1.0 - 1e-6,
        "{c:?}"
    );
    // A 35 mm lens on a 36 mm wide sensor, 4:3: yfov = 2 atan(18 / 35 * 3 / 4).
    let yfov = 2.0 * (18.0f32 / 35.0 * 0.75).atan();
    assert!((c.vfov_degrees - yfov.to_degrees()).abs() < 1e-3, "{c:?}");
    assert_eq!(
        (scene.defaults.width, scene.defaults.height),
        (683, 512),
        "4:3"
    );

    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/blender/lamps.glb");
    let extras = read_extras(&path, "lamps.glb").expect("reads");
    let names: Vec<&str> = extras.cameras.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["Camera", "Closeup"]);
    let closeup = &extras.cameras[1];
    assert!(
        (closeup.from - glam::DVec3::new(3.0, 1.5, 3.0)).length() < 1e-5,
        "{closeup:?}"
    );
    assert_eq!(extras.lights, ["Point", "Spot", "Sun"]);
    // Blender's watts, as its exporter writes them (x 683 / 4 pi in candela for points and
    // spots, x 683 in lux for the sun), back in rt-gpu's W/sr and W/m^2.
    let per_sr = 1.0 / (4.0 * std::f32::consts::PI);
    let near = |a: Vec3, b: Vec3| (a - b).length() <= 1e-4 * b.length().max(1.0);
    let direction = |from: Vec3, to: Vec3| (to - from).normalize();
    match extras.punctual[..] {
        [
            Punctual::Point {
                position,
                intensity,
            },
            Punctual::Spot {
                position: spot_at,
                direction: spot_axis,
                intensity: spot_intensity,
                inner,
                outer,
            },
            Punctual::Directional {
                direction: sun,
                irradiance,
            },
        ] => {
            assert!(near(position, Vec3::new(-2.0, 3.0, 2.0)), "{position}");
            assert!(
                near(intensity, 400.0 * per_sr * Vec3::new(1.0, 0.8, 0.6)),
                "{intensity}"
            );
            assert!(near(spot_at, Vec3::new(2.5, 4.0, 2.5)), "{spot_at}");
            let aim = direction(spot_at, Vec3::new(1.6, 0.7, 0.0));
            assert!(near(spot_axis, aim), "{spot_axis} against {aim}");
            assert!(
                near(spot_intensity, Vec3::splat(800.0 * per_sr)),
                "{spot_intensity}"
            );
            assert!(
                (outer.to_degrees() - 20.0).abs() < 1e-3,
                "outer {}",
                outer.to_degrees()
            );
            // Blender's blend 0.25: the exporter's inner cone is (1 - blend) x the outer.
            assert!(
                (inner.to_degrees() - 15.0).abs() < 1e-3,
                "inner {}",
                inner.to_degrees()
            );
            let aim = direction(Vec3::new(0.0, 10.0, 0.0), Vec3::new(0.5, 0.0, -0.3));
            assert!(near(sun, aim), "{sun} against {aim}");
            assert!(near(irradiance, Vec3::splat(2.0)), "{irradiance}");
        }
        ref other => panic!("lights {other:?}"),
    }
    let (scene, notes) = blender_file("lamps.glb");
    assert!(notes.is_empty(), "{notes:?}");
    assert_eq!(scene.punctual.len(), 3);
    assert_eq!(
        scene.background,
        Background::Constant(Vec3::ZERO),
        "lit by its lamps"
    );
}

/// Regions of the 160x120 image: (name, rows, columns).
const REGIONS: [(&str, [usize; 2], [usize; 2]); 8] = [
    ("floor, front", [105, 120], [20, 140]),
    ("floor, left", [60, 90], [0, 25]),
    ("gold sphere", [50, 70], [25, 45]),
    ("chrome sphere", [45, 60], [70, 90]),
    ("glass sphere", [45, 65], [115, 135]),
    ("cube, front face", [75, 95], [70, 90]),
    ("panel", [0, 8], [60, 100]),
    ("caustic under glass", [72, 80], [115, 135]),
];

/// Cycles' image `cycles` (in scenes/blender/) and rt-gpu's CPU render of `scene` at its size
/// (512 spp, seed 0, nee): a pixel's (Cycles, rt-gpu) values.
fn beside_cycles(scene: Scene, cycles: &str) -> impl Fn(usize, usize) -> ([f32; 3], [f32; 3]) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/blender");
    let reference = image::open(dir.join(cycles))
        .unwrap_or_else(|e| panic!("{cycles}: {e}"))
        .to_rgb32f();
    let (width, height) = (reference.width(), reference.height());
    let opts = rt_gpu::options::RenderOptions {
        integrator: rt_gpu::render::Integrator::Nee,
        ..rt_gpu::options::RenderOptions::new(width, height, 512, 10)
    };
    let flat = rt_gpu::scene::flat::FlatScene::new(&scene, width, height).expect("valid");
    let ours = rt_gpu::cpu::render(&flat, &opts, &|| {}).mean_rgb();
    move |x, y| {
        (
            reference.get_pixel(x as u32, y as u32).0,
            ours[y * width as usize + x],
        )
    }
}

/// Per region of `regions`, the mean of rt-gpu's CPU render of `scene` over that of Cycles'
/// image `cycles` (see [`beside_cycles`]); printed as a table.
fn ratios_to_cycles(
    scene: Scene,
    cycles: &str,
    regions: &[(&str, [usize; 2], [usize; 2])],
) -> Vec<f64> {
    let pixel = beside_cycles(scene, cycles);
    let grey = |c: [f32; 3]| (c[0] as f64 + c[1] as f64 + c[2] as f64) / 3.0;
    println!("{cycles}: region, Cycles, rt-gpu, ratio");
    regions
        .iter()
        .map(|(name, [y0, y1], [x0, x1])| {
            let (mut theirs, mut mine) = (0.0, 0.0);
            for y in *y0..*y1 {
                for x in *x0..*x1 {
                    let (cycles, rt_gpu) = pixel(x, y);
                    theirs += grey(cycles);
                    mine += grey(rt_gpu);
                }
            }
            let ratio = mine / theirs;
            println!("  {name:<20} {theirs:10.3} {mine:10.3} {ratio:7.3}");
            ratio
        })
        .collect()
}

/// Where both renderers model the same thing (the floor and cube Lambertian on both sides),
/// rt-gpu's image of Blender's file agrees with Cycles' in every region, within 2.5% (at 512
/// spp rt-gpu's own noise in a region is under 1%: a deterministic check at seed 0, with
/// margin for Cycles' noise at 2048 spp and its half floats). Negative controls: the floor's
/// albedo 5% brighter is caught in the floor's regions; and the Principled BSDF's diffuse
/// (Cycles: Disney diffuse with retro-reflection and a specular layer added on top), against
/// glTF's model (rt-gpu's `pbr`), differs by 10% or more on the floor's left and the cube,
/// the known model difference this comparison reports.
#[test]
fn the_file_renders_as_cycles_renders_it_where_the_models_agree() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/blender/spheres-lambert.toml");
    let lambert = rt_gpu::scene::file::load(&path).expect("loads");
    let ratios = ratios_to_cycles(lambert.clone(), "spheres-lambert-cycles.exr", &REGIONS);
    for ((name, ..), ratio) in REGIONS.iter().zip(&ratios) {
        assert!((ratio - 1.0).abs() < 0.025, "{name}: {ratio}");
    }

    let mut brighter = lambert;
    let floor = brighter
        .material_names
        .iter()
        .position(|n| n == "floor")
        .expect("floor");
    let Material::Lambertian(white) = &mut brighter.materials[floor] else {
        panic!("the floor is lambertian");
    };
    white.albedo = Texture::Colour(Vec3::splat(0.63));
    let ratios = ratios_to_cycles(brighter, "spheres-lambert-cycles.exr", &REGIONS);
    assert!(
        ratios[..2].iter().all(|r| (r - 1.0).abs() >= 0.025),
        "a 5% brighter floor went unseen: {ratios:?}"
    );

    let (mut principled, _) = blender_file("spheres.glb");
    // Lit by its panel alone, as Blender's world is black in the reference.
    principled.background = Background::Constant(Vec3::ZERO);
    let ratios = ratios_to_cycles(principled, "spheres-cycles.exr", &REGIONS);
    for i in [1, 5] {
        assert!(ratios[i] < 0.9, "{}: {}", REGIONS[i].0, ratios[i]);
    }
}

/// `lamps.glb` with its floor and cube as rt-gpu's `lambertian`, as Cycles' Diffuse BSDF
/// renders them in the `lamps*-lambert-cycles.exr` references.
fn lamps_lambert() -> Scene {
    let (mut scene, _) = blender_file("lamps.glb");
    for (name, albedo) in [
        ("Floor", Vec3::splat(0.6)),
        ("Clay", Vec3::new(0.8, 0.3, 0.2)),
    ] {
        let i = scene
            .material_names
            .iter()
            .position(|n| *n == format!("lamps.glb#{name}"))
            .expect("material");
        scene.materials[i] = Material::Lambertian(rt_gpu::material::Lambertian {
            albedo: Texture::Colour(albedo),
            emission: Vec3::ZERO,
            normal_map: None,
        });
    }
    scene
}

/// Blender's lamps (a point, a spot and a sun), with the floor and cube Lambertian in both
/// renderers: rt-gpu's image agrees with Cycles' within 2.5% on the floor, the cube and the
/// rough gold sphere, so the lights' units, positions, directions and cones arrive as Blender
/// meant them. Printed, not asserted: where the spot's penumbra shows (the floor beside the
/// glass, and through it) rt-gpu is darker by design: Blender's spot is a smoothstep over
/// `spot_blend` in cos(angle) times cos(angle), which its exporter writes as glTF's inner cone
/// (rt-gpu renders glTF's falloff); with Cycles' falloff swapped in, a throwaway build agreed
/// there (docs/benchmarks.md). The glass region of this reference also holds one firefly
/// (23.4, +16% on the region's mean) and the chrome's region is its lamps' highlights, a
/// fraction of a pixel each: see the test below.
#[test]
fn blenders_lamps_light_the_scene_as_in_cycles() {
    let ratios = ratios_to_cycles(lamps_lambert(), "lamps-lambert-cycles.exr", &REGIONS);
    for i in [0, 1, 2, 5] {
        let (name, ratio) = (REGIONS[i].0, ratios[i]);
        assert!((ratio - 1.0).abs() < 0.025, "{name}: {ratio}");
    }
}

/// The point and the sun alone (the spot, whose falloff differs by design, dropped on both
/// sides; Cycles at 16384 spp): every region agrees within 2.5%, the glass (the lit floor
/// seen through it) and the floor in its shadow included. Not asserted: the near-mirror
/// chrome (GGX 0.05), whose region's light is half in its two lamps' highlights, each on a
/// fraction of a pixel, so that its mean is noise-bound at any affordable count (two rt-gpu
/// seeds at 16384 spp gave 1.06 and 1.26 of Cycles'). Negative control: the floor's albedo 5%
/// brighter is caught in the floor's regions.
#[test]
fn blenders_point_and_sun_light_the_glass_as_in_cycles() {
    let without_spot = |albedo: f32| {
        let mut scene = lamps_lambert();
        scene
            .punctual
            .retain(|light| !matches!(light, Punctual::Spot { .. }));
        assert_eq!(scene.punctual.len(), 2);
        let floor = scene
            .material_names
            .iter()
            .position(|n| n == "lamps.glb#Floor")
            .expect("floor");
        scene.materials[floor] = Material::lambertian(Vec3::splat(albedo));
        scene
    };
    const CHROME: usize = 3;
    const PANEL: usize = 6;
    let reference = "lamps-no-spot-lambert-cycles.exr";
    let ratios = ratios_to_cycles(without_spot(0.6), reference, &REGIONS);
    for (i, ((name, ..), ratio)) in REGIONS.iter().zip(&ratios).enumerate() {
        if i != CHROME && i != PANEL {
            assert!((ratio - 1.0).abs() < 0.025, "{name}: {ratio}");
        }
    }
    let ratios = ratios_to_cycles(without_spot(0.63), reference, &REGIONS);
    assert!(
        ratios[..2].iter().all(|r| (r - 1.0).abs() >= 0.025),
        "a 5% brighter floor went unseen: {ratios:?}"
    );
}

/// Blender's OBJ export of the same scene: its .mtl materials arrive as the script set them
/// (Blender writes roughness as Ns = (1 - roughness)^2 x 1000, metal as illum 3, emission as Ke;
/// it does not write transmission).
#[test]
fn blenders_obj_materials_arrive_as_the_script_set_them() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/blender/spheres.obj");
    let parts = rt_gpu::scene::mesh::load(&path, "spheres.obj", None).expect("loads");
    let names: Vec<&str> = parts.iter().map(|p| p.material_name.as_str()).collect();
    assert_eq!(names.len(), 6, "{names:?}");
    for (name, colour, metallic, roughness, _) in PRINCIPLED {
        let part = parts
            .iter()
            .find(|p| p.material_name == name)
            .unwrap_or_else(|| panic!("no part {name} in {names:?}"));
        let Some(Material::Pbr(pbr)) = &part.material else {
            panic!("{name}: {:?}", part.material);
        };
        assert_eq!(
            pbr.base_color,
            Texture::Colour(Vec3::from_array(colour)),
            "{name}"
        );
        assert!(
            (pbr.metallic - metallic).abs() < 1e-6,
            "{name}: {}",
            pbr.metallic
        );
        assert!(
            (pbr.roughness - roughness).abs() < 1e-5,
            "{name}: {}",
            pbr.roughness
        );
    }
    let panel = parts
        .iter()
        .find(|p| p.material_name == "Panel")
        .expect("panel");
    let Some(Material::Light(light)) = &panel.material else {
        panic!("the panel: {:?}", panel.material);
    };
    assert_eq!(light.radiance, Texture::Colour(Vec3::new(8.0, 7.2, 6.4)));
}

/// The quadrant colours of `textured-quadrants.png` as the script writes them (sRGB values):
/// (texel x, texel y from the top, colour).
const QUADRANTS: [(u32, u32, [f32; 3]); 4] = [
    (0, 0, [0.9, 0.2, 0.1]),
    (63, 0, [0.2, 0.8, 0.2]),
    (0, 63, [0.2, 0.3, 0.9]),
    (63, 63, [0.9, 0.9, 0.3]),
];

/// `image`'s corners hold the script's quadrant colours, decoded from sRGB (within 8-bit
/// rounding).
fn assert_quadrants(image: &rt_gpu::assets::image::Image, what: &str) {
    use rt_gpu::assets::image::srgb_to_linear;
    let linear = QUADRANTS.map(|(x, y, srgb)| (x, y, srgb.map(srgb_to_linear)));
    assert_texels(image, &linear, 0.005, what);
}

/// `image` is 64x64 and holds at each (x, y) of `texels` its linear value, within `tolerance`.
fn assert_texels(
    image: &rt_gpu::assets::image::Image,
    texels: &[(u32, u32, [f32; 3])],
    tolerance: f32,
    what: &str,
) {
    assert_eq!((image.width, image.height), (64, 64), "{what}");
    for &(x, y, expected) in texels {
        let texel = image.texel(x, y);
        assert!(
            (texel - Vec3::from_array(expected)).abs().max_element() < tolerance,
            "{what} ({x}, {y}): {texel} against {expected:?}"
        );
    }
}

/// Blender's textured scene: the floor's and the cube's base colour is the image the script
/// made (embedded in the .glb, decoded once for both materials; named by map_Kd in the .mtl),
/// and their meshes carry the UV maps Blender wrote.
#[test]
fn blenders_textures_arrive_as_the_script_set_them() {
    let (scene, _) = blender_file("textured.glb");
    let mut images = Vec::new();
    for name in ["Floor", "Box"] {
        let Material::Pbr(pbr) = material(&scene, "textured.glb", name) else {
            panic!("{name}: not pbr");
        };
        let Texture::Image(image) = &pbr.base_color else {
            panic!("{name}: {:?}", pbr.base_color);
        };
        assert_quadrants(image, name);
        assert!(
            close(pbr.roughness, 1.0) && close(pbr.metallic, 0.0),
            "{name}"
        );
        images.push(image);
    }
    assert!(std::sync::Arc::ptr_eq(images[0], images[1]), "decoded once");
    for object in &scene.objects {
        let rt_gpu::scene::Shape::Mesh { mesh, .. } = &object.shape else {
            panic!("meshes only");
        };
        assert_eq!(mesh.uvs.len(), mesh.triangles.len(), "{mesh:?}");
    }

    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/blender/textured.obj");
    let parts = rt_gpu::scene::mesh::load(&path, "textured.obj", None).expect("loads");
    for name in ["Floor", "Box"] {
        let part = parts
            .iter()
            .find(|p| p.material_name == name)
            .unwrap_or_else(|| panic!("no part {name}"));
        let Some(Material::Pbr(pbr)) = &part.material else {
            panic!("{name}: {:?}", part.material);
        };
        let Texture::Image(image) = &pbr.base_color else {
            panic!("{name}: {:?}", pbr.base_color);
        };
        assert_quadrants(image, &format!("{name} (OBJ)"));
        assert_eq!(part.uvs.len(), part.triangles.len(), "{name} (OBJ)");
    }
}

/// Regions of `textured`'s 160x120 image, each inside one quadrant of the texture: (name,
/// rows, columns, the quadrant's dominant channel).
const TEXTURED_REGIONS: [(&str, [usize; 2], [usize; 2], usize); 5] = [
    ("floor, red quadrant", [50, 64], [10, 70], 0),
    ("floor, green quadrant", [50, 62], [120, 155], 1),
    ("floor, blue quadrant", [85, 118], [10, 70], 2),
    ("floor, yellow quadrant", [72, 84], [130, 158], 0),
    ("cube, top", [50, 58], [85, 105], 1),
];

/// Per region of [`TEXTURED_REGIONS`], rt-gpu's mean of its dominant channel over Cycles' in
/// `textured-lambert-cycles.exr` (see [`beside_cycles`]); printed as a table.
fn textured_ratios(scene: Scene) -> Vec<f64> {
    let pixel = beside_cycles(scene, "textured-lambert-cycles.exr");
    println!("textured-lambert-cycles.exr: region, channel, Cycles, rt-gpu, ratio");
    TEXTURED_REGIONS
        .iter()
        .map(|(name, [y0, y1], [x0, x1], c)| {
            let (mut theirs, mut mine) = (0.0, 0.0);
            for y in *y0..*y1 {
                for x in *x0..*x1 {
                    let (cycles, rt_gpu) = pixel(x, y);
                    theirs += cycles[*c] as f64;
                    mine += rt_gpu[*c] as f64;
                }
            }
            let ratio = mine / theirs;
            println!("  {name:<24} {c} {theirs:10.3} {mine:10.3} {ratio:7.3}");
            ratio
        })
        .collect()
}

/// The textured floor and cube, Lambertian in both renderers with the image as their albedo
/// through the file's UV maps: rt-gpu's image agrees with Cycles' within 2.5% in each
/// quadrant's dominant channel (a deterministic check at seed 0, rt-gpu's noise there under 1%
/// at 512 spp). Negative control: the image turned upside down (the other convention of v) is
/// caught in every floor region.
#[test]
fn blenders_textured_scene_renders_as_in_cycles() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/blender/textured-lambert.toml");
    let scene = rt_gpu::scene::file::load(&path).expect("loads");
    let ratios = textured_ratios(scene.clone());
    for ((name, ..), ratio) in TEXTURED_REGIONS.iter().zip(&ratios) {
        assert!((ratio - 1.0).abs() < 0.025, "{name}: {ratio}");
    }

    let mut flipped = scene;
    let Material::Lambertian(lambertian) = &mut flipped.materials[0] else {
        panic!("lambertian");
    };
    let Texture::Image(image) = &lambertian.albedo else {
        panic!("an image");
    };
    let row = 3 * image.width as usize;
    let texels: Vec<f32> = image
        .texels
        .chunks_exact(row)
        .rev()
        .flatten()
        .copied()
        .collect();
    let upside_down =
        rt_gpu::assets::image::Image::from_linear("flipped", image.width, image.height, texels)
            .expect("valid")
            .shared();
    lambertian.albedo = Texture::Image(upside_down);
    let ratios = textured_ratios(flipped);
    assert!(
        ratios[..4].iter().all(|r| (r - 1.0).abs() >= 0.25),
        "an upside-down texture went unseen: {ratios:?}"
    );
}

/// The textured file as Blender wrote it (pbr with the image as base colour, corner UVs on
/// both backends) renders alike on the CPU and the GPU: Welch z + Sidak at family-wise 0.01
/// (tests/it/common/stats.rs); the image 2% brighter on the GPU is caught by the same test.
#[cfg(feature = "gpu")]
#[test]
fn blenders_textured_file_matches_on_both_backends() {
    let (scene, _) = blender_file("textured.glb");
    let mut brighter = scene.clone();
    for m in &mut brighter.materials {
        if let Material::Pbr(pbr) = m
            && let Texture::Image(image) = &pbr.base_color
        {
            let scaled = image
                .scaled(Vec3::splat(1.02), "2% brighter")
                .expect("valid");
            pbr.base_color = Texture::Image(scaled.shared());
        }
    }
    matches_on_both_backends(&scene, &brighter, "a 2% brighter texture");
}

/// `scene` renders alike on the CPU and the GPU (Welch z + Sidak at family-wise 0.01,
/// tests/it/common/stats.rs; 32x24, 1024 spp, nee), and `altered` on the GPU is told apart from it.
#[cfg(feature = "gpu")]
fn matches_on_both_backends(scene: &Scene, altered: &Scene, what: &str) {
    use common::gpu::{render_gpu, renderer};
    use common::stats::compare;
    let Some(gpu) = renderer() else { return };
    let opts = |seed| common::nee_opts(32, 24, 1024, 4, seed);
    let cpu = common::render_cpu(scene, &opts(1));
    let tuning = rt_gpu::gpu::Tuning::default();
    let verdict = compare(&cpu, &render_gpu(&gpu, scene, &opts(2), &tuning));
    eprintln!("cpu vs gpu: {verdict:?}");
    assert!(verdict.passed(), "{verdict:?}");
    let verdict = compare(&cpu, &render_gpu(&gpu, altered, &opts(2), &tuning));
    eprintln!("gpu with {what}: {verdict:?}");
    assert!(!verdict.passed(), "{what} went undetected");
}

/// `[camera] gltf = "NAME"` takes a camera of a glTF file the scene places: the scene files of
/// scenes/blender/ use Blender's camera so, as the file itself renders it; an unknown name lists
/// the files' cameras, and a placement given beside it, or no glTF file placed, is refused.
#[test]
fn a_scene_file_takes_a_camera_of_a_gltf_file_it_places() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/blender");
    let (whole, _) = blender_file("lamps.glb");
    let parse = |camera: &str| {
        let text = format!(
            "[camera]\n{camera}\n[materials]\nm = {{ type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }}\n[[object]]\nmesh = {{ file = \"{}\", node = \"Floor\" }}\nmaterial = \"m\"\n",
            dir.join("lamps.glb").display()
        );
        rt_gpu::scene::file::parse(&text, "cam.toml", "cam")
    };
    let closeup =
        rt_gpu::scene::gltf_scene::load(&dir.join("lamps.glb"), "lamps.glb", Some("Closeup"))
            .expect("loads")
            .0
            .camera;
    for (name, expected) in [("Camera", &whole.camera), ("Closeup", &closeup)] {
        let scene = parse(&format!("gltf = \"{name}\"")).expect("parses");
        assert_eq!(scene.camera, *expected, "{name}");
    }
    // Issue 61: placed with the file's object (it stayed where the file alone put it, and the
    // image went black).
    let placed = {
        let text = format!(
            "[camera]\ngltf = \"Camera\"\n[materials]\nm = {{ type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }}\n[[object]]\nmesh = {{ file = \"{}\", node = \"Floor\" }}\nscale = 2\nrotate_y = 90\ntranslate = [10, 0, 0]\nmaterial = \"m\"\n",
            dir.join("lamps.glb").display()
        );
        rt_gpu::scene::file::parse(&text, "cam.toml", "cam").expect("parses")
    };
    let transform = rt_gpu::scene::Transform {
        rotate_y_degrees: 90.0,
        translate: glam::Vec3::new(10.0, 0.0, 0.0),
    };
    let moved = |p: glam::Vec3| transform.apply_point(2.0 * p);
    let c = &whole.camera;
    assert!((placed.camera.look_from - moved(c.look_from)).length() < 1e-4);
    assert!((placed.camera.look_at - moved(c.look_at)).length() < 1e-4);
    assert!(
        (placed.camera.up.normalize() - transform.rotate_vector(c.up).normalize()).length() < 1e-5
    );
    assert_eq!(placed.camera.vfov_degrees, c.vfov_degrees);
    let with_lens = parse("gltf = \"Camera\"\naperture = 0.1").expect("parses");
    assert_eq!(with_lens.camera.aperture, 0.1);
    for (camera, expected) in [
        ("gltf = \"Nope\"", "cameras: "),
        ("gltf = \"Camera\"\nvfov = 30", "leave out look_from"),
        ("vfov = 30", "camera needs look_from, look_at and vfov"),
    ] {
        let err = parse(camera).expect_err(camera).to_string();
        assert!(err.contains(expected), "{camera}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
    }
    let err = parse("gltf = \"Nope\"")
        .expect_err("no such camera")
        .to_string();
    assert!(err.contains("Camera") && err.contains("Closeup"), "{err}");
    let no_file = "[camera]\ngltf = \"Camera\"\n[materials]\nm = { type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }\n[[object]]\nsphere = { center = [0, 0, 0], radius = 1 }\nmaterial = \"m\"\n";
    let err = rt_gpu::scene::file::parse(no_file, "cam.toml", "cam").expect_err("no glTF file");
    assert!(err.to_string().contains("places none"), "{err}");
}

/// The texels of `bumpy-normals.png` as the script writes them (linear): per quadrant (texel x,
/// texel y from the top) the normal tilted 30 degrees toward +u, +v, -v and -u, as `2t - 1`.
const TILTS: [(u32, u32, [f32; 3]); 4] = [
    (0, 0, [0.75, 0.5, 0.933]),
    (63, 0, [0.5, 0.75, 0.933]),
    (0, 63, [0.5, 0.25, 0.933]),
    (63, 63, [0.25, 0.5, 0.933]),
];

fn assert_tilts(map: Option<&rt_gpu::assets::normal_map::NormalMap>, what: &str) {
    let map = map.unwrap_or_else(|| panic!("{what}: no normal map"));
    assert_eq!(map.scale, 1.0, "{what}");
    assert_texels(&map.image, &TILTS, 0.003, what);
}

/// Blender's normal-mapped scene: the floor's and the cube's normal map is the script's image,
/// read as linear data with its strength as `scale`, from the .glb (normalTexture, decoded once
/// for both) and the .mtl (map_Bump -bm); the file has no TANGENT, so the meshes' tangents are
/// MikkTSpace's, one per corner with a handedness of +-1.
#[test]
fn blenders_normal_maps_arrive_as_the_script_set_them() {
    let (scene, _) = blender_file("bumpy.glb");
    let mut images = Vec::new();
    for name in ["Floor", "Box"] {
        let Material::Pbr(pbr) = material(&scene, "bumpy.glb", name) else {
            panic!("{name}: not pbr");
        };
        assert_tilts(pbr.normal_map.as_ref(), name);
        assert_eq!(pbr.base_color, Texture::Colour(Vec3::splat(0.8)), "{name}");
        images.push(pbr.normal_map.clone().expect("a map").image);
    }
    assert!(
        std::sync::Arc::ptr_eq(&images[0], &images[1]),
        "decoded once"
    );
    for object in &scene.objects {
        let rt_gpu::scene::Shape::Mesh { mesh, .. } = &object.shape else {
            panic!("meshes only");
        };
        assert!(mesh.tangents.is_empty(), "no TANGENT in the file");
        let tangents = rt_gpu::scene::tangents::of(mesh, Default::default()).expect("uvs");
        assert_eq!(tangents.len(), mesh.triangles.len());
        for t in tangents.iter().flatten() {
            assert!((t.truncate().length() - 1.0).abs() < 1e-4, "{t}");
            assert_eq!(t.w.abs(), 1.0, "{t}");
        }
    }

    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/blender/bumpy.obj");
    let parts = rt_gpu::scene::mesh::load(&path, "bumpy.obj", None).expect("loads");
    for name in ["Floor", "Box"] {
        let part = parts
            .iter()
            .find(|p| p.material_name == name)
            .unwrap_or_else(|| panic!("no part {name}"));
        let Some(Material::Pbr(pbr)) = &part.material else {
            panic!("{name}: {:?}", part.material);
        };
        assert_tilts(pbr.normal_map.as_ref(), &format!("{name} (OBJ)"));
    }
}

/// Regions of `bumpy`'s 160x120 image: the floor's four quadrants (each tilted one way, see
/// [`TILTS`]; away from the cube's shadow) and the cube's top.
const BUMPY_REGIONS: [(&str, [usize; 2], [usize; 2]); 5] = [
    ("floor, tilted +u", [58, 72], [20, 70]),
    ("floor, tilted +v", [60, 72], [122, 150]),
    ("floor, tilted -v", [96, 118], [10, 60]),
    ("floor, tilted -u", [96, 118], [100, 158]),
    ("cube, top", [50, 57], [88, 104]),
];

/// `bumpy.glb` with its floor and cube Lambertian (albedo 0.8) and their normal map kept, as
/// Cycles' Diffuse BSDF renders them in `bumpy-lambert-cycles.exr`; `normal_map` replaces the
/// map when given.
fn bumpy_lambert(
    normal_map: impl Fn(
        rt_gpu::assets::normal_map::NormalMap,
    ) -> Option<rt_gpu::assets::normal_map::NormalMap>,
) -> Scene {
    let (mut scene, _) = blender_file("bumpy.glb");
    for m in &mut scene.materials {
        if let Material::Pbr(pbr) = m {
            *m = Material::Lambertian(rt_gpu::material::Lambertian {
                albedo: pbr.base_color.clone(),
                emission: Vec3::ZERO,
                normal_map: pbr.normal_map.clone().and_then(&normal_map),
            });
        }
    }
    scene
}

/// The normal map's green channel turned over (DirectX's convention, or a bitangent of the
/// wrong sign).
#[cfg(feature = "gpu")]
fn green_flipped(
    map: rt_gpu::assets::normal_map::NormalMap,
) -> rt_gpu::assets::normal_map::NormalMap {
    let texels = map
        .image
        .texels
        .chunks_exact(3)
        .flat_map(|t| [t[0], 1.0 - t[1], t[2]])
        .collect();
    let image = rt_gpu::assets::image::Image::from_linear(
        "green flipped",
        map.image.width,
        map.image.height,
        texels,
    )
    .expect("valid")
    .shared();
    rt_gpu::assets::normal_map::NormalMap { image, ..map }
}

/// Under a low sun, each quadrant of the normal-mapped floor is as bright as its tilt makes it.
/// rt-gpu shades a normal map as a microsurface (issue 62, `material::microsurface`): a facet
/// tilted toward the grazing sun is shadowed by its neighbours, one tilted away lit by their
/// mirror, where Cycles applies the map as it is (bending normals that face away from the
/// viewer back toward it). So the quadrants are printed against Cycles, not asserted (measured
/// at 512 spp: +u 0.70, +v 0.84, -v 1.40, -u 1.98 of Cycles'; before the microsurface, the
/// front two agreed within 2.5% and the far two were 2.8% and 3.8% brighter), and the cube's
/// top, which the map leaves flat, agrees within 2.5%. `bumpy-lambert.toml`, the same scene in
/// a scene file (`normal_map = { image, scale }`), renders within 0.5% of it. Negative controls
/// against rt-gpu's own image: without the map every quadrant changes by 10% or more (13-15%).
/// Lambertian facets lit only from their own side reflect as the flat floor times the cosine
/// of their tilt, whichever way they tilt (the microsurface keeps the light the geometric
/// surface receives), so a green channel turned over no longer shows here: the tangent frame's
/// handedness is checked on the file's pbr (below) and by `assert_tilts`.
#[test]
fn blenders_normal_mapped_scene_renders_as_in_cycles() {
    let cycles = "bumpy-lambert-cycles.exr";
    let ratios = ratios_to_cycles(bumpy_lambert(Some), cycles, &BUMPY_REGIONS);
    let top = ratios[4];
    assert!((top - 1.0).abs() < 0.025, "cube, top: {top}");
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/blender/bumpy-lambert.toml");
    let file = rt_gpu::scene::file::load(&path).expect("loads");
    let from_file = ratios_to_cycles(file, cycles, &BUMPY_REGIONS);
    for ((name, ..), (a, b)) in BUMPY_REGIONS.iter().zip(ratios.iter().zip(&from_file)) {
        assert!(
            (a / b - 1.0).abs() < 0.005,
            "{name}: {a} in code, {b} from the file"
        );
    }
    let flat = ratios_to_cycles(bumpy_lambert(|_| None), cycles, &BUMPY_REGIONS);
    assert!(
        (0..4).all(|i| (flat[i] / ratios[i] - 1.0).abs() >= 0.1),
        "the normal map's absence went unseen: {flat:?} vs {ratios:?}"
    );
}

/// The normal-mapped file as Blender wrote it (pbr, MikkTSpace tangents) renders alike on the
/// CPU and the GPU: Welch z + Sidak at family-wise 0.01 (tests/it/common/stats.rs); the GPU with
/// the map's green channel turned over is caught by the same test.
#[cfg(feature = "gpu")]
#[test]
fn blenders_normal_mapped_file_matches_on_both_backends() {
    let (scene, _) = blender_file("bumpy.glb");
    let mut flipped = scene.clone();
    for m in &mut flipped.materials {
        if let Material::Pbr(pbr) = m {
            pbr.normal_map = pbr.normal_map.clone().map(green_flipped);
        }
    }
    matches_on_both_backends(&scene, &flipped, "the green channel turned over");
}

/// `worn-metal-rough.png`'s quadrant corners as the script set them (metallic in blue,
/// roughness in green; x from the left, y from the top, as rt-gpu's images run).
const WORN_TEXELS: [(u32, u32, [f32; 3]); 4] = [
    (0, 0, [0.0, 0.3, 1.0]),
    (63, 0, [0.0, 0.3, 0.0]),
    (0, 63, [0.0, 0.8, 1.0]),
    (63, 63, [0.0, 0.9, 0.0]),
];

/// Blender's worn scene: the floor's and the cube's metallic and roughness come from the
/// script's image (linear, shared by both materials and decoded once), their base colour from
/// the quadrant image; the Closest texture arrives nearest, the Extend one clamped to its edges;
/// the Mapping node's scale (KHR_texture_transform, which Blender marks required) is in the
/// meshes' texture coordinates: Blender's 0..1 UVs span 0..2 on the floor, 0..1.5 on the cube.
#[test]
fn blenders_metallic_roughness_and_samplers_arrive_as_the_script_set_them() {
    use rt_gpu::assets::image_lookup::{Filter, ImageLookup, Wrap};
    let (scene, _) = blender_file("worn.glb");
    let nearest = ImageLookup {
        filter: Filter::Nearest,
        ..ImageLookup::default()
    };
    let clamped = ImageLookup {
        wrap_u: Wrap::Clamp,
        wrap_v: Wrap::Clamp,
        filter: Filter::Linear,
        ..ImageLookup::default()
    };
    for (name, lookup, span) in [("Floor", nearest, 2.0), ("Box", clamped, 1.5)] {
        let Material::Pbr(pbr) = material(&scene, "worn.glb", name) else {
            panic!("{name}: not pbr");
        };
        assert!(
            close(pbr.metallic, 1.0) && close(pbr.roughness, 1.0),
            "{name}: the factors"
        );
        let Texture::Image(colours) = &pbr.base_color else {
            panic!("{name}: {:?}", pbr.base_color);
        };
        assert_quadrants(colours, name);
        let metal_rough = pbr
            .metallic_roughness()
            .cloned()
            .expect("a metallic-roughness image");
        assert_texels(&metal_rough, &WORN_TEXELS, 0.005, name);
        assert_eq!(
            (colours.lookup, metal_rough.lookup),
            (lookup, lookup),
            "{name}"
        );
        let object = scene
            .objects
            .iter()
            .find(|o| scene.material_names[o.material as usize] == format!("worn.glb#{name}"))
            .expect("placed");
        let rt_gpu::scene::Shape::Mesh { mesh, .. } = &object.shape else {
            panic!("a mesh");
        };
        let corners = mesh.uvs.iter().flatten();
        let (lo, hi) = corners.fold((f32::MAX, f32::MIN), |(lo, hi), uv| {
            (lo.min(uv.min_element()), hi.max(uv.max_element()))
        });
        assert!(
            close(lo, 0.0) && close(hi, span),
            "{name}: UVs span {lo}..{hi}"
        );
    }
}

/// Regions of `worn`'s 160x120 image, each inside one tile of the floor (the quadrant's
/// metallic and roughness) or on the cube.
const WORN_REGIONS: [(&str, [usize; 2], [usize; 2]); 6] = [
    ("floor, yellow: 0, 0.9", [100, 115], [30, 60]),
    ("floor, blue: 1, 0.8", [100, 115], [83, 95]),
    ("floor, green: 0, 0.3", [75, 88], [35, 65]),
    ("floor, red: 1, 0.3", [76, 88], [3, 20]),
    ("floor, far yellow", [60, 68], [45, 70]),
    ("cube, top", [50, 58], [85, 105]),
];

/// The worn file against Cycles' render of it (Principled BSDF): per region of
/// [`WORN_REGIONS`] rt-gpu's mean over Cycles' (a deterministic check at seed 0, rt-gpu's noise
/// in a region under 1% at 512 spp). The metal tiles, GGX with Schlick's Fresnel in both
/// renderers, agree within 2.5%; the near dielectric tiles within 6%. The far floor and the cube
/// are reported, not asserted: there Cycles' Principled v1 diffuse (Disney's, with its grazing
/// retro-reflection) is brighter than glTF's model, the known difference the spheres scene
/// measures too. Negative control: the metallic-roughness image dropped (metallic 1, roughness
/// 1 everywhere) moves every floor region by a factor of 2 or more.
#[test]
fn blenders_worn_scene_renders_as_in_cycles() {
    let (mut scene, _) = blender_file("worn.glb");
    // Lit by its panel alone, as Blender's world is black in the reference.
    scene.background = Background::Constant(Vec3::ZERO);
    let ratios = ratios_to_cycles(scene.clone(), "worn-cycles.exr", &WORN_REGIONS);
    for (i, tolerance) in [(1, 0.025), (3, 0.025), (0, 0.06), (2, 0.06)] {
        let (name, ..) = WORN_REGIONS[i];
        assert!((ratios[i] - 1.0).abs() < tolerance, "{name}: {}", ratios[i]);
    }
    let mut plain = scene;
    for m in &mut plain.materials {
        if let Material::Pbr(pbr) = m {
            *pbr = pbr.clone().with_metallic_roughness(None);
        }
    }
    let without = ratios_to_cycles(plain, "worn-cycles.exr", &WORN_REGIONS);
    assert!(
        without[..5].iter().all(|r| !(0.5..2.0).contains(r)),
        "the image's absence went unseen: {without:?}"
    );
}

/// The worn file renders alike on the CPU and the GPU (metallic-roughness images, nearest and
/// clamped lookups, transformed UVs; see [`matches_on_both_backends`]); the floor's and the
/// cube's roughness factors 2% lower on the GPU are caught.
#[cfg(feature = "gpu")]
#[test]
fn blenders_worn_file_matches_on_both_backends() {
    let (scene, _) = blender_file("worn.glb");
    let mut rougher = scene.clone();
    for m in &mut rougher.materials {
        if let Material::Pbr(pbr) = m {
            let metal_rough = pbr.metallic_roughness().cloned();
            *pbr = rt_gpu::material::Pbr::new(
                pbr.base_color.clone(),
                pbr.metallic,
                0.98,
                pbr.ior,
                pbr.transmission,
            )
            .with_metallic_roughness(metal_rough);
        }
    }
    matches_on_both_backends(&scene, &rougher, "roughness factors 2% lower");
}
