//! Rays and what they hit, and leaving a surface without re-hitting it: the one definition both
//! backends use (WGSL twins: `Ray` and `Hit`, generated from these definitions, and `spawn`
//! and `leave` in `shaders/intersect.wgsl`).

use super::layout::kernel_struct;
use super::primitive::PrimitiveRef;
use glam::{Vec2, Vec3};

kernel_struct! {
    /// A ray: its WGSL twin `Ray` is generated from this definition.
    pub struct Ray as "Ray" {
        origin: Vec3,
        /// Always unit length.
        dir: Vec3,
    }
}

impl Ray {
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }
}

kernel_struct! {
    /// What a ray hit: `normal` faces the incoming ray; `front_face` says whether that is the
    /// shape's outward (or `u x v`) side. Its WGSL twin `Hit` is generated from this definition
    /// (the kernel holds `primitive` packed).
    pub struct Hit as "Hit" {
        point: Vec3,
        t: f32,
        /// A bound on the distance from `point` to the true surface point.
        error: f32,
        /// The geometric normal, facing the incoming ray: it decides sides and offsets.
        normal: Vec3,
        /// The normal materials shade with, on `normal`'s side: a mesh's interpolated vertex
        /// normals (see `cpu::intersect::shading_normal`) bent by the material's normal map,
        /// else `normal` itself.
        shading: Vec3,
        /// The normal a clear coat shades with (pbr's, `material::clearcoat`), on `normal`'s
        /// side: a mesh's interpolated vertex normals bent by the material's clear coat normal
        /// map where it has one (glTF's clearcoatNormalTexture), but never by its base's (glTF
        /// draws a coat without one unmapped); else `normal` itself.
        coat: Vec3,
        material: u32,
        front_face: bool,
        /// Which primitive was hit.
        primitive: PrimitiveRef,
        /// Surface coordinates, for textures (zero unless the scene's textures need them): a
        /// sphere's longitude and latitude (`shape::sphere::sphere_uv`), a quad's (a, b).
        uv: Vec2,
        /// A mesh's second texture coordinates (glTF's TEXCOORD_1) where a material reads them
        /// (`ImageLookup::uv_set`), else `uv`.
        uv1: Vec2,
        /// A mesh's vertex colour interpolated (glTF's COLOR_0), which multiplies the
        /// material's colour (`material::texture::value`); 1 elsewhere.
        color: Vec3,
    }
}

/// Whether unit `dir` leaves `hit` below its geometric surface although the shading normal
/// allowed it: such a scattered path ends (shading normals only; see the materials).
#[inline]
pub fn below_surface(hit: &Hit, dir: Vec3) -> bool {
    hit.shading != hit.normal && dir.dot(hit.normal) <= 0.0
}

/// Relative bound on a hit point's error: eight roundings of the coordinates it came from.
pub const POINT_ERROR: f32 = 8.0 * f32::EPSILON;

/// Below this magnitude a coordinate is moved by a fixed amount (`OFFSET_FLOAT_SCALE`), above
/// it by `OFFSET_INT_SCALE` units in its last place (see `offset_origin`).
pub const OFFSET_NEAR_ORIGIN: f32 = 1.0 / 32.0;
pub const OFFSET_FLOAT_SCALE: f32 = 1.0 / 4294967296.0;
pub const OFFSET_INT_SCALE: f32 = 32.0;

/// A ray origin moved off the surface at `p` along `n` by a few units in the last place of each
/// coordinate (Wächter and Binder, "A Fast and Robust Method for Avoiding Self-Intersection",
/// Ray Tracing Gems ch. 6); callers first move it by the point's error bound (see `leave`).
#[inline]
pub fn offset_origin(p: Vec3, n: Vec3) -> Vec3 {
    let offset = |p: f32, n: f32| -> f32 {
        if p.abs() < OFFSET_NEAR_ORIGIN {
            p + OFFSET_FLOAT_SCALE * n
        } else {
            let of_i = (OFFSET_INT_SCALE * n) as i32;
            let of_i = if p < 0.0 { -of_i } else { of_i };
            f32::from_bits((p.to_bits() as i32).wrapping_add(of_i) as u32)
        }
    };
    Vec3::new(offset(p.x, n.x), offset(p.y, n.y), offset(p.z, n.z))
}

/// The origin of a ray leaving `hit` on the side of unit `side` (its normal or the opposite):
/// past the point's error bound, then a few units in the last place further, so it cannot
/// re-hit the surface it leaves, at any scale.
#[inline]
pub fn leave(hit: &Hit, side: Vec3) -> Vec3 {
    offset_origin(hit.point + hit.error * side, side)
}

/// A ray leaving a hit in direction `dir` (unit), started on the side `dir` points to.
#[inline]
pub fn spawn(hit: &Hit, dir: Vec3) -> Ray {
    let side = if dir.dot(hit.normal) >= 0.0 {
        hit.normal
    } else {
        -hit.normal
    };
    Ray {
        origin: leave(hit, side),
        dir,
    }
}
