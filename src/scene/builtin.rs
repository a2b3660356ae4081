//! The built-in scenes. Each is also a file in `scenes/` (`rt-gpu scenes --export DIR` writes them)
//! and a test checks the two agree.

use super::{Background, Camera, Material, Object, RenderDefaults, Scene, Shape, Transform};
use crate::rng::Rng;
use glam::Vec3;

/// (name, one-line description) of every built-in scene.
pub const BUILTINS: &[(&str, &str)] = &[
    (
        "cornell",
        "the original project's Cornell box: two rotated boxes and a glass sphere",
    ),
    (
        "cornell-empty",
        "the Cornell box and its light with nothing inside",
    ),
    (
        "spheres",
        "three spheres (diffuse, glass, metal) on a large ground sphere under a sky",
    ),
    (
        "showcase",
        "several hundred random small spheres around three large ones, a rotated metal box and a quad light",
    ),
];

pub fn builtin(name: &str) -> Option<Scene> {
    match name {
        "cornell" => Some(cornell(true)),
        "cornell-empty" => Some(cornell(false)),
        "spheres" => Some(spheres()),
        "showcase" => Some(showcase()),
        _ => None,
    }
}

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

fn object(shape: Shape, material: u32) -> Object {
    Object {
        shape,
        material,
        transform: Transform::default(),
    }
}

/// An axis-aligned box from the origin to `size`, rotated about y and then moved.
fn placed_box(size: Vec3, rotate_y_degrees: f32, translate: Vec3, material: u32) -> Object {
    Object {
        shape: Shape::Cuboid {
            min: Vec3::ZERO,
            max: size,
        },
        material,
        transform: Transform {
            rotate_y_degrees,
            translate,
        },
    }
}

fn quad(q: Vec3, u: Vec3, v: Vec3, material: u32) -> Object {
    object(Shape::Quad { q, u, v }, material)
}

fn sphere(center: Vec3, radius: f32, material: u32) -> Object {
    object(Shape::Sphere { center, radius }, material)
}

/// The Cornell box of the original project's final render, in its 555-unit coordinates.
fn cornell(with_contents: bool) -> Scene {
    let materials = vec![
        Material::lambertian(v(0.65, 0.05, 0.05)), // 0 red
        Material::lambertian(v(0.73, 0.73, 0.73)), // 1 white
        Material::lambertian(v(0.12, 0.45, 0.15)), // 2 green
        Material::Light {
            radiance: v(15.0, 15.0, 15.0),
            two_sided: false,
        }, // 3 light
        Material::Dielectric { ior: 1.5 },         // 4 glass
    ];
    let (red, white, green, light, glass) = (0, 1, 2, 3, 4);
    let mut objects = vec![
        quad(
            v(555.0, 0.0, 0.0),
            v(0.0, 555.0, 0.0),
            v(0.0, 0.0, 555.0),
            green,
        ),
        quad(
            v(0.0, 0.0, 0.0),
            v(0.0, 555.0, 0.0),
            v(0.0, 0.0, 555.0),
            red,
        ),
        // u x v points down (-y): the light faces into the box.
        quad(
            v(213.0, 554.0, 227.0),
            v(130.0, 0.0, 0.0),
            v(0.0, 0.0, 105.0),
            light,
        ),
        quad(
            v(0.0, 0.0, 0.0),
            v(555.0, 0.0, 0.0),
            v(0.0, 0.0, 555.0),
            white,
        ),
        quad(
            v(555.0, 555.0, 555.0),
            v(-555.0, 0.0, 0.0),
            v(0.0, 0.0, -555.0),
            white,
        ),
        quad(
            v(0.0, 0.0, 555.0),
            v(555.0, 0.0, 0.0),
            v(0.0, 555.0, 0.0),
            white,
        ),
    ];
    if with_contents {
        objects.push(placed_box(
            v(165.0, 330.0, 165.0),
            15.0,
            v(265.0, 0.0, 295.0),
            white,
        ));
        objects.push(placed_box(
            v(165.0, 165.0, 165.0),
            -18.0,
            v(130.0, 0.0, 65.0),
            white,
        ));
        objects.push(sphere(v(425.0, 40.0, 70.0), 40.0, glass));
    }
    Scene {
        name: if with_contents {
            "cornell"
        } else {
            "cornell-empty"
        }
        .into(),
        camera: Camera {
            look_from: v(278.0, 278.0, -800.0),
            look_at: v(278.0, 278.0, 0.0),
            up: Vec3::Y,
            // The original's 600-unit-tall viewport at distance 800.
            vfov_degrees: (2.0 * (300.0f64 / 800.0).atan()).to_degrees() as f32,
            aperture: 0.0,
            focus_distance: None,
        },
        background: Background::Constant(Vec3::ZERO),
        materials,
        material_names: ["red", "white", "green", "light", "glass"]
            .map(String::from)
            .to_vec(),
        objects,
        defaults: RenderDefaults {
            width: 512,
            height: 512,
            max_depth: 10,
        },
    }
}

fn spheres() -> Scene {
    Scene {
        name: "spheres".into(),
        camera: Camera {
            look_from: v(0.0, 0.6, 1.8),
            look_at: v(0.0, 0.0, -1.0),
            up: Vec3::Y,
            vfov_degrees: 40.0,
            aperture: 0.0,
            focus_distance: None,
        },
        background: Background::Sky,
        material_names: ["ground", "blue", "glass", "gold"]
            .map(String::from)
            .to_vec(),
        materials: vec![
            Material::lambertian(v(0.8, 0.8, 0.0)),
            Material::lambertian(v(0.1, 0.2, 0.5)),
            Material::Dielectric { ior: 1.5 },
            Material::Metal {
                albedo: v(0.8, 0.6, 0.2),
                fuzz: 0.0,
            },
        ],
        objects: vec![
            sphere(v(0.0, -100.5, -1.0), 100.0, 0),
            sphere(v(0.0, 0.0, -1.0), 0.5, 1),
            sphere(v(-1.0, 0.0, -1.0), 0.5, 2),
            sphere(v(1.0, 0.0, -1.0), 0.5, 3),
        ],
        defaults: RenderDefaults {
            width: 400,
            height: 225,
            max_depth: 50,
        },
    }
}

/// A field of random small spheres around three large ones (after "Ray Tracing in One Weekend"),
/// with a rotated fuzzy-metal box and a two-sided quad light, so every material and primitive
/// appears. Generated from a fixed seed: the scene is the same on every machine.
fn showcase() -> Scene {
    let mut materials = vec![
        Material::lambertian(v(0.5, 0.5, 0.5)), // 0 ground
        Material::Dielectric { ior: 1.5 },      // 1 glass
        Material::lambertian(v(0.4, 0.2, 0.1)), // 2 brown
        Material::Metal {
            albedo: v(0.7, 0.6, 0.5),
            fuzz: 0.0,
        }, // 3 polished
        Material::Light {
            radiance: v(4.0, 3.8, 3.4),
            two_sided: true,
        }, // 4 warm light
        Material::Metal {
            albedo: v(0.8, 0.85, 0.88),
            fuzz: 0.2,
        }, // 5 brushed steel
    ];
    let mut objects = vec![
        sphere(v(0.0, -1000.0, 0.0), 1000.0, 0),
        sphere(v(0.0, 1.0, 0.0), 1.0, 1),
        sphere(v(0.0, 1.0, 0.0), -0.9, 1), // a hollow glass shell
        sphere(v(-4.0, 1.0, 0.0), 1.0, 2),
        sphere(v(4.0, 1.0, 0.0), 1.0, 3),
        quad(v(-2.0, 5.0, -1.0), v(0.0, 0.0, 2.0), v(4.0, 0.0, 0.0), 4),
        placed_box(v(0.8, 1.2, 0.8), 30.0, v(2.0, 0.0, 2.2), 5),
    ];
    let mut material_names: Vec<String> = [
        "ground",
        "glass",
        "brown",
        "polished",
        "warm_light",
        "steel",
    ]
    .map(String::from)
    .to_vec();
    let mut rng = Rng::for_sample(0, 0, 2024);
    for a in -9..9 {
        for b in -9..9 {
            let center = v(
                a as f32 + 0.9 * rng.next_f32(),
                0.2,
                b as f32 + 0.9 * rng.next_f32(),
            );
            let clear_of_big_ones = [v(4.0, 0.2, 0.0), v(0.0, 0.2, 0.0), v(-4.0, 0.2, 0.0)]
                .iter()
                .all(|c| (center - *c).length() > 1.2)
                && (center - v(2.4, 0.2, 2.6)).length() > 1.0;
            if !clear_of_big_ones {
                continue;
            }
            let choose = rng.next_f32();
            let mut colour = || v(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let material = if choose < 0.75 {
                Material::lambertian(colour() * colour())
            } else if choose < 0.92 {
                let albedo = colour() * 0.5 + Vec3::splat(0.5);
                Material::Metal {
                    albedo,
                    fuzz: 0.5 * rng.next_f32(),
                }
            } else {
                Material::Dielectric { ior: 1.5 }
            };
            materials.push(material);
            material_names.push(format!("small{:03}", materials.len()));
            objects.push(sphere(center, 0.2, materials.len() as u32 - 1));
        }
    }
    Scene {
        name: "showcase".into(),
        camera: Camera {
            look_from: v(13.0, 2.0, 3.0),
            look_at: Vec3::ZERO,
            up: Vec3::Y,
            vfov_degrees: 20.0,
            aperture: 0.1,
            focus_distance: Some(10.0),
        },
        background: Background::Sky,
        materials,
        material_names,
        objects,
        defaults: RenderDefaults {
            width: 600,
            height: 400,
            max_depth: 20,
        },
    }
}
