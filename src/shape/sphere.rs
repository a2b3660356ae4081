//! A sphere (twin: `shaders/shapes/sphere.wgsl`): hit by the ray's nearer root ahead, put back
//! onto its surface at its radius, sampled as a light uniformly in the cone it subtends.

use super::{LightSample, ShapeParams, SurfaceLight, SurfaceShape};
use crate::params::checked;
use crate::placement::{MAX_EXTENT, MIN_SIZE, Transform};
use crate::shared::layout::{WgslStruct, WgslType, gpu_struct};
use crate::shared::ray::{POINT_ERROR, Ray};
use crate::shared::warp::basis;
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec2, Vec3};
use std::f32::consts::PI;

/// Its scene syntax: `sphere = { center = [x, y, z], radius = r }`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct SphereParams {
    #[serde(with = "checked::vector")]
    pub center: Vec3,
    /// A negative radius flips the normal inward (a hollow bubble inside glass).
    #[serde(with = "checked::number")]
    pub radius: f32,
}

impl ShapeParams for SphereParams {
    type Flat = Sphere;
    fn validate(&self) -> Result<(), String> {
        let (center, radius) = (self.center, self.radius);
        if !center.is_finite() || !radius.is_finite() || radius == 0.0 {
            return Err(format!(
                "sphere radius must be finite and non-zero, got {radius}"
            ));
        }
        if !(radius.abs() >= MIN_SIZE && radius.abs() <= MAX_EXTENT) {
            return Err(format!(
                "sphere radius {radius} is outside what f32 geometry handles: use sizes between {MIN_SIZE:e} and {MAX_EXTENT:e}"
            ));
        }
        Ok(())
    }
    fn reach(&self) -> (Vec3, Vec3) {
        (
            self.center,
            self.center.abs() + Vec3::splat(self.radius.abs()),
        )
    }
    fn placed(&self, transform: &Transform, origin: DVec3, material: u32) -> Sphere {
        Sphere {
            center: transform.apply_point_relative(self.center, origin),
            radius: self.radius,
            material,
            light: 0,
        }
    }
}

/// `repr(C)`: the centre and radius lead, as the CPU's four-sphere test loads them.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Sphere {
    pub center: Vec3,
    /// Negative for an inward-facing (hollow) sphere.
    pub radius: f32,
    pub material: u32,
    /// 1 + this sphere's index in the scene's lights; 0 when it does not emit.
    pub light: u32,
}

gpu_struct! {
    pub struct GpuSphere as "Sphere" {
        center: [f32; 3],
        /// Negative: the normal faces inward.
        radius: f32,
        material: u32,
        /// 1 + its index in the light list; 0 when it does not emit.
        light: u32,
        _pad: [u32; 2],
    }
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

/// The cone a sphere subtends from `x`: its unit axis and 1 - cos(half angle), or `None`
/// when `x` is inside the sphere (or the cone is too thin to represent).
#[inline]
pub fn sphere_cone(center: Vec3, radius: f32, x: Vec3) -> Option<(Vec3, f32)> {
    let to_center = center - x;
    let d2 = to_center.length_squared();
    let r2 = radius * radius;
    if !(d2 > r2) {
        return None;
    }
    let sin2_max = r2 / d2;
    // 1 - sqrt(1 - s) without cancellation for small cones.
    let one_minus_cos = sin2_max / (1.0 + (1.0 - sin2_max).sqrt());
    (one_minus_cos > 0.0).then(|| (to_center / d2.sqrt(), one_minus_cos))
}

impl SurfaceShape for Sphere {
    type Gpu = GpuSphere;
    const CROSSINGS: u32 = 2;

    fn material(&self) -> u32 {
        self.material
    }
    fn light(&self) -> u32 {
        self.light
    }
    fn set_light(&mut self, light: u32) {
        self.light = light;
    }
    fn bounds(&self) -> [Vec3; 2] {
        let r = Vec3::splat(self.radius.abs());
        [self.center - r, self.center + r]
    }
    #[inline]
    fn hit(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        hit_sphere(self, ray, 0.0, t_max)
    }
    #[inline]
    fn outward(&self, ray: &Ray, t: f32) -> Vec3 {
        (ray.at(t) - self.center) / self.radius
    }
    fn as_spheres(shapes: &[Self]) -> Option<&[Sphere]> {
        Some(shapes)
    }
    /// Along the ray's direction from the centre, at the radius.
    fn surface(&self, along_ray: Vec3) -> (Vec3, f32) {
        let from_center = along_ray - self.center;
        let point = self.center + from_center * (self.radius.abs() / from_center.length());
        let scale = self.center.abs().max_element() + self.radius.abs();
        (point, POINT_ERROR * scale)
    }
    fn uv(&self, point: Vec3, _along_ray: Vec3) -> Vec2 {
        sphere_uv((point - self.center) / self.radius.abs())
    }
    /// `position` its centre, `size` |radius| (a hollow sphere emits too).
    fn as_light(&self) -> (f64, SurfaceLight) {
        let r = self.radius.abs();
        let area = 4.0 * std::f64::consts::PI * (r as f64).powi(2);
        let light = SurfaceLight {
            position: self.center,
            size: r,
            ..Default::default()
        };
        (area, light)
    }
    /// Uniform in the cone it subtends: 1 - cos(theta) uniform in [0, 1 - cos_max], sin^2 from
    /// it directly, so thin cones keep their width.
    fn sample_light(l: &SurfaceLight, pick: f32, x: Vec3, u1: f32, u2: f32) -> Option<LightSample> {
        let (center, radius) = (l.position, l.size);
        let (axis, one_minus_cos) = sphere_cone(center, radius, x)?;
        let a = u1 * one_minus_cos;
        let cos_theta = 1.0 - a;
        let sin_theta = (a * (2.0 - a)).max(0.0).sqrt();
        let (sin_phi, cos_phi) = crate::shared::angles::sin_cos_pi(2.0 * u2 - 1.0);
        let (t, b) = basis(axis);
        let dir = (cos_theta * axis + sin_theta * (cos_phi * t + sin_phi * b)).normalize();
        // Where it meets the sphere (a direction in the cone, from outside: the near root;
        // at the cone's rim, where rounding can miss, the closest approach).
        let sphere = Sphere {
            center,
            radius,
            material: 0,
            light: 0,
        };
        let t = hit_sphere(&sphere, &Ray { origin: x, dir }, 0.0, f32::INFINITY)
            .unwrap_or_else(|| dir.dot(center - x));
        Some(LightSample {
            dir,
            pdf: pick / (2.0 * PI * one_minus_cos),
            point: x + t * dir,
        })
    }
    fn light_pdf(l: &SurfaceLight, pick: f32, x: Vec3, _p: Vec3, _dir: Vec3) -> f32 {
        match sphere_cone(l.position, l.size, x) {
            Some((_, one_minus_cos)) => pick / (2.0 * PI * one_minus_cos),
            None => 0.0,
        }
    }
    fn gpu(&self) -> GpuSphere {
        GpuSphere {
            center: self.center.to_array(),
            radius: self.radius,
            material: self.material,
            light: self.light,
            _pad: [0; 2],
        }
    }
}

/// A sphere's surface coordinates at unit outward direction `n` from its centre: u the
/// longitude from -x round through +z... (u = (atan2(-z, x) + pi) / 2 pi), v the latitude from
/// the south pole (v = acos(-y) / pi), as in Ray Tracing: The Next Week.
#[inline]
pub fn sphere_uv(n: Vec3) -> Vec2 {
    let u = (crate::shared::angles::atan2(-n.z, n.x) + PI) / (2.0 * PI);
    let v = crate::shared::angles::acos(-n.y) / PI;
    Vec2::new(u, v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_uv_follows_the_book() {
        assert!((sphere_uv(Vec3::X) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!((sphere_uv(Vec3::Y) - Vec2::new(0.5, 1.0)).length() < 1e-6);
        assert!((sphere_uv(Vec3::NEG_Y).y).abs() < 1e-6);
        assert!((sphere_uv(Vec3::NEG_X) - Vec2::new(0.0, 0.5)).length() < 1e-6);
        assert!((sphere_uv(Vec3::Z) - Vec2::new(0.25, 0.5)).length() < 1e-6);
        assert!((sphere_uv(Vec3::NEG_Z) - Vec2::new(0.75, 0.5)).length() < 1e-6);
    }
}
