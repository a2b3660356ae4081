//! Where an object stands: its rigid placement (rotate about +y, then translate), and the
//! limits of the coordinates and sizes f32 geometry handles. Shapes place themselves by it and
//! scenes hold it; it imports neither.

use glam::Vec3;

/// Largest coordinate or size a scene may use: squares of distances stay far from f32 overflow.
pub const MAX_EXTENT: f32 = 1e8;
/// Smallest sphere radius or quad/box edge: squares stay far from f32 underflow.
pub const MIN_SIZE: f32 = 1e-6;

/// Rigid placement of an object: rotate about +y (right-handed, degrees), then translate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Transform {
    pub rotate_y_degrees: f32,
    pub translate: Vec3,
}

impl Transform {
    /// x' = cos(a) x + sin(a) z, z' = -sin(a) x + cos(a) z.
    pub fn rotate_vector(&self, v: Vec3) -> Vec3 {
        self.vector_rotation()(v)
    }

    /// [`Transform::rotate_vector`] with the rotation's sine and cosine worked out once, for
    /// many vectors.
    pub fn vector_rotation(&self) -> impl Fn(Vec3) -> Vec3 + Sync + use<> {
        let (sin, cos) = (self.rotate_y_degrees.to_radians() as f64).sin_cos();
        move |v: Vec3| {
            let (x, z) = (v.x as f64, v.z as f64);
            Vec3::new((cos * x + sin * z) as f32, v.y, (-sin * x + cos * z) as f32)
        }
    }

    pub fn apply_point(&self, p: Vec3) -> Vec3 {
        self.rotate_vector(p) + self.translate
    }

    /// `apply_point` in f64 and then moved by `-origin`, rounded to f32 once: a point far from
    /// the world origin but near `origin` keeps its full precision.
    pub fn apply_point_relative(&self, p: Vec3, origin: glam::DVec3) -> Vec3 {
        self.point_placement(origin)(p)
    }

    /// [`Transform::apply_point_relative`] with the rotation's sine and cosine worked out
    /// once, for many points.
    pub fn point_placement(&self, origin: glam::DVec3) -> impl Fn(Vec3) -> Vec3 + Sync + use<> {
        let (sin, cos) = (self.rotate_y_degrees.to_radians() as f64).sin_cos();
        let translate = self.translate.as_dvec3();
        move |p: Vec3| {
            let (x, z) = (p.x as f64, p.z as f64);
            let rotated = glam::DVec3::new(cos * x + sin * z, p.y as f64, -sin * x + cos * z);
            (rotated + translate - origin).as_vec3()
        }
    }
}
