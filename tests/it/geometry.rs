//! Ray-shape intersection against hand-computed answers.

use crate::common;

use glam::Vec3;
use rt_gpu::cpu::intersect::{hit_quad, hit_sphere, intersect};
use rt_gpu::scene::flat::{FlatScene, Quad, Sphere};
use rt_gpu::scene::{Background, Material, Object, Shape, Transform};
use rt_gpu::shared::ray::Ray;

fn ray(origin: [f32; 3], dir: [f32; 3]) -> Ray {
    Ray {
        origin: Vec3::from(origin),
        dir: Vec3::from(dir).normalize(),
    }
}

fn unit_square_at_z0() -> Quad {
    Quad::new(Vec3::ZERO, Vec3::X, Vec3::Y, 0)
}

#[test]
fn quad_hit_reports_distance_and_miss_outside_edges() {
    let q = unit_square_at_z0();
    assert_eq!(
        hit_quad(
            &q,
            &ray([0.5, 0.5, 2.0], [0.0, 0.0, -1.0]),
            0.0,
            f32::INFINITY
        ),
        Some(2.0)
    );
    // From behind too: quads are hit from both sides.
    assert_eq!(
        hit_quad(
            &q,
            &ray([0.25, 0.75, -3.0], [0.0, 0.0, 1.0]),
            0.0,
            f32::INFINITY
        ),
        Some(3.0)
    );
    assert_eq!(
        hit_quad(
            &q,
            &ray([1.5, 0.5, 2.0], [0.0, 0.0, -1.0]),
            0.0,
            f32::INFINITY
        ),
        None
    );
    assert_eq!(
        hit_quad(
            &q,
            &ray([0.5, -0.01, 2.0], [0.0, 0.0, -1.0]),
            0.0,
            f32::INFINITY
        ),
        None
    );
    // Beyond t_max, or behind the origin.
    assert_eq!(
        hit_quad(&q, &ray([0.5, 0.5, 2.0], [0.0, 0.0, -1.0]), 0.0, 1.5),
        None
    );
    assert_eq!(
        hit_quad(
            &q,
            &ray([0.5, 0.5, 2.0], [0.0, 0.0, 1.0]),
            0.0,
            f32::INFINITY
        ),
        None
    );
    // An oblique hit lands where the hand computation says.
    let r = ray([0.0, 0.0, 1.0], [0.5, 0.5, -1.0]);
    let t = hit_quad(&q, &r, 0.0, f32::INFINITY).expect("hit");
    assert!((r.at(t) - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6);
}

#[test]
fn rays_parallel_to_a_quad_miss_it() {
    let q = unit_square_at_z0();
    for dir in [[1.0, 0.0, 0.0], [-1.0, 0.0, -0.0], [0.0, 1.0, 0.0]] {
        // In the plane itself and just above it.
        for z in [0.0, 1e-3] {
            assert_eq!(
                hit_quad(&q, &ray([-1.0, 0.5, z], dir), 0.0, f32::INFINITY),
                None
            );
        }
    }
}

#[test]
fn sphere_hits_from_outside_and_inside() {
    let s = Sphere {
        center: Vec3::new(0.0, 0.0, -5.0),
        radius: 2.0,
        material: 0,
        light: 0,
    };
    assert_eq!(
        hit_sphere(
            &s,
            &ray([0.0, 0.0, 0.0], [0.0, 0.0, -1.0]),
            0.0,
            f32::INFINITY
        ),
        Some(3.0)
    );
    assert_eq!(
        hit_sphere(
            &s,
            &ray([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
            0.0,
            f32::INFINITY
        ),
        None
    );
    assert_eq!(
        hit_sphere(
            &s,
            &ray([0.0, 2.01, 0.0], [0.0, 0.0, -1.0]),
            0.0,
            f32::INFINITY
        ),
        None
    );
    // From the centre, the far wall at distance r in every direction.
    for dir in [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [1.0, 1.0, 1.0]] {
        let t = hit_sphere(&s, &ray([0.0, 0.0, -5.0], dir), 0.0, f32::INFINITY).expect("hit");
        assert!((t - 2.0).abs() < 1e-5, "{t}");
    }
    // The full hit record from inside: the normal faces the ray, and it is the back face.
    let scene = flat_with(vec![common::object(Shape::sphere(s.center, s.radius), 0)]);
    let hit = intersect(&scene, &ray([0.0, 0.0, -5.0], [0.0, 1.0, 0.0])).expect("hit");
    assert!(!hit.front_face);
    assert!((hit.normal - Vec3::NEG_Y).length() < 1e-6);
    assert!((hit.point - Vec3::new(0.0, 2.0, -5.0)).length() < 1e-5);
}

/// A one-material scene of `objects`, flattened.
fn flat_with(objects: Vec<Object>) -> FlatScene {
    let scene = common::scene(
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::ZERO,
        40.0,
        Background::Constant(Vec3::ZERO),
        vec![Material::lambertian(Vec3::ONE)],
        objects,
    );
    FlatScene::new(&scene, 4, 4).expect("valid")
}

/// The Cornell box's tall box: (0,0,0)-(165,330,165), rotated +15 degrees about y, moved to
/// (265, 0, 295). Box-space point p maps to (cos a p.x + sin a p.z, p.y, -sin a p.x + cos a p.z)
/// plus the translation.
#[test]
fn rotated_translated_box_matches_hand_computed_points() {
    let flat = flat_with(vec![Object {
        shape: Shape::Cuboid {
            min: Vec3::ZERO,
            max: Vec3::new(165.0, 330.0, 165.0),
        },
        material: 0,
        transform: Transform {
            rotate_y_degrees: 15.0,
            translate: Vec3::new(265.0, 0.0, 295.0),
        },
    }]);
    assert_eq!(flat.shapes.quads.len(), 6);
    let (c, s) = (15f32.to_radians().cos(), 15f32.to_radians().sin());
    let world = |x: f32, z: f32| Vec3::new(c * x + s * z + 265.0, 0.0, -s * x + c * z + 295.0);

    // The box-space corner (165, *, 0) is at (424.378, *, 252.295).
    let corner = world(165.0, 0.0);
    assert!(
        (corner - Vec3::new(424.3777, 0.0, 252.2949)).length() < 1e-3,
        "{corner}"
    );

    // Straight down onto the top face, inside the rotated footprint near that corner...
    let inside = world(160.0, 5.0);
    let hit = intersect(&flat, &ray([inside.x, 1000.0, inside.z], [0.0, -1.0, 0.0])).expect("hit");
    assert!((hit.point.y - 330.0).abs() < 1e-3 && (hit.normal - Vec3::Y).length() < 1e-5);
    // ...and 5 units beyond the rotated +x face is a miss.
    let outside = world(170.0, 5.0);
    assert!(
        intersect(
            &flat,
            &ray([outside.x, 1000.0, outside.z], [0.0, -1.0, 0.0])
        )
        .is_none()
    );

    // Horizontally along the box's rotated +x axis at mid height, through its centre: enters the
    // -x face at box-space x = 0 and its normal is the rotated -x axis.
    let centre = world(82.5, 82.5);
    let axis = Vec3::new(c, 0.0, -s);
    let start = centre - 500.0 * axis + Vec3::new(0.0, 100.0, 0.0);
    let hit = intersect(&flat, &ray(start.to_array(), axis.to_array())).expect("hit");
    assert!((hit.t - (500.0 - 82.5)).abs() < 1e-2, "{}", hit.t);
    assert!((hit.normal + axis).length() < 1e-5);
}
