//! A disk (twin: `shaders/shapes/disk.wgsl`), as pbrt-v4's and Mitsuba 3's: a centre, a normal
//! (its front face) and a radius; hit where the ray crosses its plane within the radius, put
//! back onto its plane, sampled as a light uniformly on its area.

use super::{
    LightSample, ShapeParams, SurfaceLight, SurfaceShape, area_pdf, area_sample, pad, plane_surface,
};
use crate::params::checked;
use crate::placement::{MAX_EXTENT, MIN_SIZE, Transform};
use crate::shared::layout::{WgslStruct, WgslType, gpu_struct};
use crate::shared::ray::Ray;
use crate::shared::warp::{basis, unit_disk};
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec2, Vec3};
use std::f32::consts::PI;

/// Its scene syntax: `disk = { center = [x, y, z], normal = [x, y, z], radius = r }`, its front
/// face along `normal` (any length but zero).
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct DiskParams {
    #[serde(with = "checked::vector")]
    pub center: Vec3,
    #[serde(with = "checked::vector")]
    pub normal: Vec3,
    #[serde(with = "checked::number")]
    pub radius: f32,
}

impl ShapeParams for DiskParams {
    type Flat = Disk;
    fn validate(&self) -> Result<(), String> {
        let (center, normal, radius) = (self.center, self.normal, self.radius);
        let length = normal.as_dvec3().length();
        if !center.is_finite() || !(length > 0.0) || !length.is_finite() {
            return Err(format!(
                "disk normal must be finite and non-zero, got {normal:?}"
            ));
        }
        if !(MIN_SIZE..=MAX_EXTENT).contains(&radius) {
            return Err(format!(
                "disk radius {radius} is outside what f32 geometry handles: use sizes between {MIN_SIZE:e} and {MAX_EXTENT:e}"
            ));
        }
        Ok(())
    }
    fn reach(&self) -> (Vec3, Vec3) {
        (self.center, self.center.abs() + Vec3::splat(self.radius))
    }
    /// Its normal normalised before it is turned (a huge one would overflow).
    fn placed(&self, transform: &Transform, origin: DVec3, material: u32) -> Disk {
        let normal = self.normal.as_dvec3().normalize().as_vec3();
        Disk::new(
            transform.apply_point_relative(self.center, origin),
            transform.rotate_vector(normal),
            self.radius,
            material,
        )
    }
}

/// The disk of `radius` about `center` in the plane `normal . p = d`; `tangent` and `bitangent`
/// complete the unit normal to a frame (its texture coordinates' and light samples' axes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    pub center: Vec3,
    pub normal: Vec3,
    pub radius: f32,
    pub d: f32,
    pub tangent: Vec3,
    pub bitangent: Vec3,
    pub material: u32,
    /// 1 + this disk's index in the scene's lights; 0 when it does not emit.
    pub light: u32,
}

gpu_struct! {
    pub struct GpuDisk as "Disk" {
        center: [f32; 3],
        radius: f32,
        normal: [f32; 3],
        material: u32,
        tangent: [f32; 3],
        /// 1 + its index in the light list; 0 when it does not emit.
        light: u32,
        bitangent: [f32; 3],
        /// Plane: dot(normal, p) = d.
        d: f32,
    }
}

impl Disk {
    /// The disk facing along `normal` (any length but zero; normalised in f64, where its
    /// square neither overflows nor underflows).
    pub fn new(center: Vec3, normal: Vec3, radius: f32, material: u32) -> Self {
        let normal = normal.as_dvec3().normalize().as_vec3();
        let (tangent, bitangent) = basis(normal);
        Disk {
            center,
            normal,
            radius,
            d: normal.dot(center),
            tangent,
            bitangent,
            material,
            light: 0,
        }
    }
}

/// Distance along the ray to `disk` within (t_min, t_max), if any: where it crosses the plane
/// (from the ray's origin to the centre first, as for quads: exact far from the world's
/// origin), if that is within the radius. Rays parallel to its plane miss.
#[inline]
pub fn hit_disk(disk: &Disk, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
    let denom = disk.normal.dot(ray.dir);
    if denom.abs() < crate::shared::constants::PARALLEL_DENOMINATOR {
        return None;
    }
    let to_center = disk.center - ray.origin;
    let t = disk.normal.dot(to_center) / denom;
    if !(t > t_min && t < t_max) {
        return None;
    }
    let planar = t * ray.dir - to_center;
    (planar.dot(planar) <= disk.radius * disk.radius).then_some(t)
}

impl SurfaceShape for Disk {
    type Gpu = GpuDisk;
    const CROSSINGS: u32 = 1;

    fn material(&self) -> u32 {
        self.material
    }
    fn light(&self) -> u32 {
        self.light
    }
    fn set_light(&mut self, light: u32) {
        self.light = light;
    }
    /// Per axis, the radius times the sine of the normal's angle to it: the length of the
    /// axis's part in the disk's plane, from its frame (no cancellation near the normal).
    fn bounds(&self) -> [Vec3; 2] {
        let (t, b) = (self.tangent, self.bitangent);
        let extent = self.radius * (t * t + b * b).powf(0.5);
        [self.center - extent, self.center + extent]
    }
    /// Also by a millionth of its radius: the rounding of the bounds' square root.
    fn padded_bounds(&self) -> [Vec3; 2] {
        let [min, max] = self.bounds();
        pad(min, max, 1e-6 * self.radius)
    }
    #[inline]
    fn hit(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        hit_disk(self, ray, 0.0, t_max)
    }
    #[inline]
    fn outward(&self, _ray: &Ray, _t: f32) -> Vec3 {
        self.normal
    }
    /// Projected onto its plane, as a quad's point.
    fn surface(&self, along_ray: Vec3) -> (Vec3, f32) {
        plane_surface(along_ray, self.normal, self.d)
    }
    /// Polar: the angle from the tangent over 2 pi, in [0, 1), and the distance from the centre
    /// over the radius, of the point along the ray (as the kernel finds them, at the hit test).
    fn uv(&self, _point: Vec3, along_ray: Vec3) -> Vec2 {
        let from_center = along_ray - self.center;
        let (x, y) = (
            from_center.dot(self.tangent),
            from_center.dot(self.bitangent),
        );
        let angle = y.atan2(x);
        let u = if angle < 0.0 { angle + 2.0 * PI } else { angle } / (2.0 * PI);
        Vec2::new(
            u.min(crate::shared::constants::ONE_BELOW),
            from_center.length() / self.radius,
        )
    }
    /// `position` its centre, `u` and `v` its frame's axes times the radius, `size` 1 / area.
    fn as_light(&self) -> (f64, SurfaceLight) {
        let area = std::f64::consts::PI * (self.radius as f64).powi(2);
        let light = SurfaceLight {
            position: self.center,
            u: self.radius * self.tangent,
            v: self.radius * self.bitangent,
            normal: self.normal,
            size: (1.0 / area) as f32,
        };
        (area, light)
    }
    fn sample_light(l: &SurfaceLight, pick: f32, x: Vec3, u1: f32, u2: f32) -> Option<LightSample> {
        let (a, b) = unit_disk(u1, u2);
        area_sample(pick, l.position + a * l.u + b * l.v, l.normal, l.size, x)
    }
    fn light_pdf(l: &SurfaceLight, pick: f32, x: Vec3, p: Vec3, dir: Vec3) -> f32 {
        area_pdf(pick, l.normal, l.size, x, p, dir)
    }
    fn gpu(&self) -> GpuDisk {
        GpuDisk {
            center: self.center.to_array(),
            radius: self.radius,
            normal: self.normal.to_array(),
            material: self.material,
            tangent: self.tangent.to_array(),
            light: self.light,
            bitangent: self.bitangent.to_array(),
            d: self.d,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tilted() -> Disk {
        Disk::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.3, -1.0, 0.5), 0.7, 0)
    }

    fn ray_to(disk: &Disk, target: Vec3) -> Ray {
        let origin = disk.center + 5.0 * disk.normal + Vec3::new(0.1, 0.2, 0.0);
        Ray {
            origin,
            dir: (target - origin).normalize(),
        }
    }

    #[test]
    fn hits_within_its_radius_only() {
        let disk = tilted();
        for (scale, hit) in [
            (0.0, true),
            (0.5, true),
            (0.999, true),
            (1.001, false),
            (2.0, false),
        ] {
            for angle in [0.0f32, 1.0, 2.5, 4.0] {
                let rim = angle.cos() * disk.tangent + angle.sin() * disk.bitangent;
                let target = disk.center + scale * disk.radius * rim;
                let ray = ray_to(&disk, target);
                let t = hit_disk(&disk, &ray, 0.0, f32::INFINITY);
                assert_eq!(t.is_some(), hit, "{scale} {angle}");
                if let Some(t) = t {
                    let (point, error) = disk.surface(ray.at(t));
                    assert!((point - target).length() < 1e-5, "{point} {target}");
                    assert!((point - target).length() <= 4.0 * error.max(1e-6));
                    let uv = disk.uv(point, ray.at(t));
                    assert!((uv.y - scale).abs() < 1e-4, "{uv}");
                    if scale > 0.0 {
                        // Periodic: at angle 0 rounding may put it just below 1.
                        let off = (uv.x - angle / (2.0 * PI)).abs();
                        assert!(off.min(1.0 - off) < 1e-4, "{angle}: {uv}");
                    }
                }
            }
        }
    }

    #[test]
    fn misses_rays_along_its_plane_or_behind_them() {
        // Axis-aligned, so that the ray along its plane is exactly parallel to it.
        let flat = Disk::new(Vec3::new(1.0, 2.0, 3.0), Vec3::Y, 0.7, 0);
        let along = Ray {
            origin: flat.center - 2.0 * Vec3::X,
            dir: Vec3::X,
        };
        assert_eq!(hit_disk(&flat, &along, 0.0, f32::INFINITY), None);
        let disk = tilted();
        let ray = ray_to(&disk, disk.center);
        let behind = Ray {
            origin: ray.origin,
            dir: -ray.dir,
        };
        assert_eq!(hit_disk(&disk, &behind, 0.0, f32::INFINITY), None);
        assert_eq!(hit_disk(&disk, &ray, 0.0, 1.0), None, "beyond t_max");
    }

    #[test]
    fn bounds_hold_its_rim_tightly() {
        for normal in [Vec3::new(0.3, -1.0, 0.5), Vec3::new(1e-4, 1.0, 0.0)] {
            bounds_hold_the_rim(Disk::new(Vec3::new(1.0, 2.0, 3.0), normal, 0.7, 0));
        }
    }

    /// Within the disk's bounds, and reaching them, 3600 points of its rim.
    fn bounds_hold_the_rim(disk: Disk) {
        let [min, max] = disk.bounds();
        let mut reached = [Vec3::MAX, Vec3::MIN];
        for i in 0..3600 {
            let angle = i as f32 / 3600.0 * 2.0 * PI;
            let p = disk.center
                + disk.radius * (angle.cos() * disk.tangent + angle.sin() * disk.bitangent);
            assert!(
                p.cmpge(min - 1e-5).all() && p.cmple(max + 1e-5).all(),
                "{p}"
            );
            reached = [reached[0].min(p), reached[1].max(p)];
        }
        assert!(
            (reached[0] - min).abs().max_element() < 1e-6,
            "{reached:?} {min}"
        );
        assert!(
            (reached[1] - max).abs().max_element() < 1e-6,
            "{reached:?} {max}"
        );
    }
}
