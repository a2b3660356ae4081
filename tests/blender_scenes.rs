//! Files Blender 3.4 really wrote (`scripts/blender/make-scenes.py`, committed under
//! scenes/blender/): they load as scenes, and their materials and cameras arrive with the
//! values the script set, field by field.

use glam::Vec3;
use rt_gpu::scene::gltf_scene::{load, read_extras};
use rt_gpu::scene::punctual::Punctual;
use rt_gpu::scene::texture::Texture;
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
    let Material::Light(panel) = material(&scene, "spheres.glb", "Panel") else {
        panic!("the panel is not a light");
    };
    assert_eq!(panel.radiance, Texture::Colour(Vec3::new(1.0, 0.9, 0.8)));
    assert!(close(panel.strength, 8.0), "{}", panel.strength);
    assert_eq!(
        scene.background,
        Background::Constant(Vec3::ZERO),
        "lit by its panel"
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

/// Per region, the mean of rt-gpu's CPU render of `scene` (512 spp, seed 0) over that of
/// Cycles' image `cycles`, both in scenes/blender/; printed as a table.
fn ratios_to_cycles(scene: Scene, cycles: &str) -> Vec<f64> {
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
    let film = rt_gpu::cpu::render(&flat, &opts, &|| {});
    let grey = |c: [f32; 3]| (c[0] as f64 + c[1] as f64 + c[2] as f64) / 3.0;
    let ours = film.mean_rgb();
    println!("{cycles}: region, Cycles, rt-gpu, ratio");
    REGIONS
        .iter()
        .map(|(name, [y0, y1], [x0, x1])| {
            let (mut theirs, mut mine) = (0.0, 0.0);
            for y in *y0..*y1 {
                for x in *x0..*x1 {
                    theirs += grey(reference.get_pixel(x as u32, y as u32).0);
                    mine += grey(ours[y * width as usize + x]);
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
    let ratios = ratios_to_cycles(lambert.clone(), "spheres-lambert-cycles.exr");
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
    let ratios = ratios_to_cycles(brighter, "spheres-lambert-cycles.exr");
    assert!(
        ratios[..2].iter().all(|r| (r - 1.0).abs() >= 0.025),
        "a 5% brighter floor went unseen: {ratios:?}"
    );

    let (principled, _) = blender_file("spheres.glb");
    let ratios = ratios_to_cycles(principled, "spheres-cycles.exr");
    for i in [1, 5] {
        assert!(ratios[i] < 0.9, "{}: {}", REGIONS[i].0, ratios[i]);
    }
}

/// Blender's lamps (a point, a spot and a sun), with the floor and cube Lambertian in both
/// renderers (`lamps-lambert-cycles.exr`; here the file's materials swapped in code): rt-gpu's
/// image agrees with Cycles' within 2.5% on the floor, the cube and the rough gold sphere, so
/// the lights' units, positions, directions and cones arrive as Blender meant them. Not
/// asserted, printed: the near-mirror chrome (GGX 0.05), the glass and the floor under it are
/// 6-16% darker than Cycles' here, and it is not yet known why (under the area panel of
/// `spheres` they agree within 1%).
#[test]
fn blenders_lamps_light_the_scene_as_in_cycles() {
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
        });
    }
    let ratios = ratios_to_cycles(scene, "lamps-lambert-cycles.exr");
    for i in [0, 1, 2, 5] {
        let (name, ratio) = (REGIONS[i].0, ratios[i]);
        assert!((ratio - 1.0).abs() < 0.025, "{name}: {ratio}");
    }
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
        let Some(Material::Pbr(pbr)) = part.material else {
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
    let Some(Material::Light(light)) = panel.material else {
        panic!("the panel: {:?}", panel.material);
    };
    assert_eq!(light.radiance, Texture::Colour(Vec3::new(8.0, 7.2, 6.4)));
}
