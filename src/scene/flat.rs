//! The form every backend traces: world-space spheres and quads with precomputed planes, the
//! camera as a frame, and resolved materials. Boxes become six quads and instance transforms are
//! applied once here (a rigid motion of a sphere or parallelogram is again one), so no backend
//! transforms rays per hit.

use super::{Background, Material, Scene, SceneError, Shape};
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    /// Negative for an inward-facing (hollow) sphere.
    pub radius: f32,
    pub material: u32,
}

/// The parallelogram `q + a u + b v`, with its plane `normal . p = d` and two axes precomputed
/// so that a hit costs one division and two dot products: for a point p in the plane,
/// a = (p - q) . alpha_axis and b = (p - q) . beta_axis, where with n = u x v and
/// w = n / |n|^2, alpha_axis = v x w and beta_axis = w x u.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quad {
    pub q: Vec3,
    pub u: Vec3,
    pub v: Vec3,
    pub normal: Vec3,
    pub d: f32,
    pub alpha_axis: Vec3,
    pub beta_axis: Vec3,
    pub material: u32,
}

impl Quad {
    pub fn new(q: Vec3, u: Vec3, v: Vec3, material: u32) -> Self {
        let n = u.cross(v);
        let normal = n.normalize();
        let w = n / n.length_squared();
        Quad {
            q,
            u,
            v,
            normal,
            d: normal.dot(q),
            alpha_axis: v.cross(w),
            beta_axis: w.cross(u),
            material,
        }
    }
}

/// The camera reduced to what ray generation needs: a ray for film position (s, t) in [0, 1]^2
/// (t down from the top) aims at `upper_left + s * horizontal - t * vertical`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraFrame {
    pub origin: Vec3,
    pub upper_left: Vec3,
    pub horizontal: Vec3,
    pub vertical: Vec3,
    /// Unit vectors to the camera's right and up, for sampling the lens.
    pub right: Vec3,
    pub up: Vec3,
    pub lens_radius: f32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct FlatScene {
    pub camera: CameraFrame,
    pub background: Background,
    pub materials: Vec<Material>,
    pub spheres: Vec<Sphere>,
    pub quads: Vec<Quad>,
}

impl FlatScene {
    /// Flattens `scene` for an image of `width` x `height` pixels.
    pub fn new(scene: &Scene, width: u32, height: u32) -> Result<Self, SceneError> {
        scene.validate()?;
        let mut spheres = Vec::new();
        let mut quads = Vec::new();
        for object in &scene.objects {
            let t = object.transform;
            let material = object.material;
            match object.shape {
                Shape::Sphere { center, radius } => spheres.push(Sphere {
                    center: t.apply_point(center),
                    radius,
                    material,
                }),
                Shape::Quad { q, u, v } => quads.push(Quad::new(
                    t.apply_point(q),
                    t.rotate_vector(u),
                    t.rotate_vector(v),
                    material,
                )),
                Shape::Cuboid { min, max } => {
                    for [q, u, v] in box_faces(min, max) {
                        quads.push(Quad::new(
                            t.apply_point(q),
                            t.rotate_vector(u),
                            t.rotate_vector(v),
                            material,
                        ));
                    }
                }
            }
        }
        Ok(FlatScene {
            camera: camera_frame(scene, width, height),
            background: scene.background,
            materials: scene.materials.clone(),
            spheres,
            quads,
        })
    }
}

/// The six faces of an axis-aligned box as (corner, u, v), each with u x v pointing outward.
pub fn box_faces(min: Vec3, max: Vec3) -> [[Vec3; 3]; 6] {
    let d = max - min;
    let (dx, dy, dz) = (
        Vec3::new(d.x, 0.0, 0.0),
        Vec3::new(0.0, d.y, 0.0),
        Vec3::new(0.0, 0.0, d.z),
    );
    [
        [Vec3::new(min.x, min.y, max.z), dx, dy],  // front, +z
        [Vec3::new(max.x, min.y, max.z), -dz, dy], // right, +x
        [Vec3::new(max.x, min.y, min.z), -dx, dy], // back, -z
        [Vec3::new(min.x, min.y, min.z), dz, dy],  // left, -x
        [Vec3::new(min.x, max.y, max.z), dx, -dz], // top, +y
        [Vec3::new(min.x, min.y, min.z), dx, dz],  // bottom, -y
    ]
}

fn camera_frame(scene: &Scene, width: u32, height: u32) -> CameraFrame {
    let c = &scene.camera;
    let to_target = c.look_at - c.look_from;
    let forward = to_target.normalize();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward);
    let focus = c.focus_distance.unwrap_or(to_target.length());
    let half_height = (c.vfov_degrees.to_radians() * 0.5).tan();
    let half_width = half_height * width as f32 / height as f32;
    let horizontal = right * (2.0 * half_width * focus);
    let vertical = up * (2.0 * half_height * focus);
    CameraFrame {
        origin: c.look_from,
        upper_left: c.look_from + forward * focus - horizontal * 0.5 + vertical * 0.5,
        horizontal,
        vertical,
        right,
        up,
        lens_radius: c.aperture * 0.5,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_faces_point_outward() {
        let (min, max) = (Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
        let centre = (min + max) * 0.5;
        for [q, u, v] in box_faces(min, max) {
            let face_centre = q + 0.5 * (u + v);
            assert!(
                u.cross(v).dot(face_centre - centre) > 0.0,
                "{q:?} {u:?} {v:?}"
            );
        }
    }
}
