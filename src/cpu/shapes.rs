//! Ray-shape intersection (twin: `shaders/intersect.wgsl`).

use crate::scene::flat::{FlatScene, PrimitiveRef, Quad, Sphere};
use glam::{Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    /// Always unit length.
    pub dir: Vec3,
}

impl Ray {
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }
}

/// What a ray hit: `normal` faces the incoming ray; `front_face` says whether that is the shape's
/// outward (or `u x v`) side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub point: Vec3,
    /// A bound on the distance from `point` to the true surface point.
    pub error: f32,
    pub normal: Vec3,
    pub front_face: bool,
    pub material: u32,
    /// Which primitive was hit.
    pub primitive: PrimitiveRef,
    /// Surface coordinates, for textures (zero unless the scene's textures need them): a
    /// sphere's longitude and latitude (`texture::sphere_uv`), a quad's (a, b).
    pub uv: Vec2,
}

/// Distance along the ray to `sphere` within (t_min, t_max), if any.
#[inline]
pub fn hit_sphere(sphere: &Sphere, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
    let oc = sphere.center - ray.origin;
    let h = ray.dir.dot(oc);
    // r^2 - |oc - h d|^2 rather than h^2 - (|oc|^2 - r^2): no cancellation when the sphere is
    // small or far away (Ray Tracing Gems, chapter 7).
    let perpendicular = oc - h * ray.dir;
    let disc = sphere.radius * sphere.radius - perpendicular.length_squared();
    if disc < 0.0 {
        return None;
    }
    let sq = disc.sqrt();
    let near = h - sq;
    if near > t_min && near < t_max {
        return Some(near);
    }
    let far = h + sq;
    (far > t_min && far < t_max).then_some(far)
}

/// Distance along the ray to `quad` within (t_min, t_max), if any. Rays parallel to its plane
/// miss: they have no single crossing point.
#[inline]
pub fn hit_quad(quad: &Quad, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
    let denom = quad.normal.dot(ray.dir);
    if denom.abs() < 1e-8 {
        return None;
    }
    // From the ray's origin to the quad's corner first: far from the world's origin the two
    // are close and their difference exact, where n . q - n . o would cancel catastrophically.
    let to_corner = quad.q - ray.origin;
    let t = quad.normal.dot(to_corner) / denom;
    if !(t > t_min && t < t_max) {
        return None;
    }
    let planar = t * ray.dir - to_corner;
    let alpha = planar.dot(quad.alpha_axis);
    let beta = planar.dot(quad.beta_axis);
    let (lo, hi) = (-quad.edge_tolerance, 1.0 + quad.edge_tolerance);
    let inside = |a: f32| (lo..=hi).contains(&a);
    (inside(alpha) && inside(beta)).then_some(t)
}

/// The closest hit along `ray` beyond its origin.
pub fn intersect(scene: &FlatScene, ray: &Ray) -> Option<Hit> {
    let mut closest = f32::INFINITY;
    let mut found: Option<(PrimitiveRef, Vec3)> = None;
    for (i, sphere) in scene.spheres.iter().enumerate() {
        if let Some(t) = hit_sphere(sphere, ray, 0.0, closest) {
            closest = t;
            let outward = (ray.at(t) - sphere.center) / sphere.radius;
            found = Some((PrimitiveRef::Sphere(i as u32), outward));
        }
    }
    for (i, quad) in scene.quads.iter().enumerate() {
        if let Some(t) = hit_quad(quad, ray, 0.0, closest) {
            closest = t;
            found = Some((PrimitiveRef::Quad(i as u32), quad.normal));
        }
    }
    let (primitive, outward) = found?;
    let outward = outward.normalize();
    let along_ray = ray.at(closest);
    // The hit point, and a bound on its distance from the true surface point, which the origin
    // of a ray leaving it must clear. o + t d carries the rounding of the ray's origin and of
    // t (which cancels in the sphere's near root), and that can dwarf the point's own
    // coordinates (a floor at y = 0 seen from 1e6 away), so the point is put back onto the
    // surface, whose own rounding follows the shape's coordinates.
    let (material, (point, error)) = match primitive {
        PrimitiveRef::Sphere(i) => {
            let s = &scene.spheres[i as usize];
            (s.material, sphere_surface(s, along_ray))
        }
        PrimitiveRef::Quad(i) => {
            let q = &scene.quads[i as usize];
            (q.material, quad_surface(q, along_ray))
        }
    };
    let front_face = ray.dir.dot(outward) < 0.0;
    let uv = if scene.uv_textures {
        match primitive {
            PrimitiveRef::Sphere(i) => {
                let s = &scene.spheres[i as usize];
                super::texture::sphere_uv((point - s.center) / s.radius.abs())
            }
            PrimitiveRef::Quad(i) => {
                let q = &scene.quads[i as usize];
                let d = along_ray - q.q;
                Vec2::new(d.dot(q.alpha_axis), d.dot(q.beta_axis))
            }
        }
    } else {
        Vec2::ZERO
    };
    Some(Hit {
        t: closest,
        point,
        error,
        normal: if front_face { outward } else { -outward },
        front_face,
        material,
        primitive,
        uv,
    })
}

/// A point near `sphere`'s surface put back onto it, and a bound on the result's error.
#[inline]
pub fn sphere_surface(sphere: &Sphere, along_ray: Vec3) -> (Vec3, f32) {
    let from_center = along_ray - sphere.center;
    let point = sphere.center + from_center * (sphere.radius.abs() / from_center.length());
    let scale = sphere.center.abs().max_element() + sphere.radius.abs();
    (point, POINT_ERROR * scale)
}

/// A point near `quad`'s plane put back onto it, and a bound on the result's error.
#[inline]
pub fn quad_surface(quad: &Quad, along_ray: Vec3) -> (Vec3, f32) {
    let point = along_ray - (quad.normal.dot(along_ray) - quad.d) * quad.normal;
    let scale = point.abs().max_element() + quad.d.abs();
    (point, POINT_ERROR * scale)
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
