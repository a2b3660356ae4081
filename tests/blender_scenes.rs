//! Files Blender 3.4 really wrote (`scripts/blender/make-scenes.py`, committed under
//! scenes/blender/): they load as scenes, and their materials and cameras arrive with the
//! values the script set, field by field.

use glam::Vec3;
use rt_gpu::scene::gltf_scene::{load, read_extras};
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
    let (_, notes) = blender_file("lamps.glb");
    assert!(
        notes.len() == 1 && notes[0].contains("Point, Spot, Sun"),
        "{notes:?}"
    );
}
