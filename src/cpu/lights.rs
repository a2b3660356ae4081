//! Light sampling for next-event estimation (twin: `shaders/lights.wgsl`): pick a light in
//! proportion to its power, then a direction toward it, and the solid-angle pdf of both, which
//! multiple importance sampling also needs for directions BSDF sampling found.

use super::environment;
use super::shapes::hit_sphere;
use crate::scene::flat::{FlatScene, Light, LightShape, Sphere};
use crate::scene::punctual::MIN_DISTANCE_SQUARED;
use crate::shared::constants::MIN_LIGHT_COSINE;
use crate::shared::ray::Ray;
use crate::shared::warp::basis;
use glam::Vec3;
use std::f32::consts::PI;

/// The light whose cumulative share first exceeds `u` in [0, 1), by binary search (scenes may
/// have thousands of emitting triangles); the last light when none does.
#[inline]
pub fn pick_light(scene: &FlatScene, u: f32) -> usize {
    let last = scene.lights.len() - 1;
    // The same halving steps as the kernel's `pick_light`.
    let (mut lo, mut hi) = (0usize, last);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if u < scene.lights[mid].cdf {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    lo
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

/// Solid-angle pdf of light sampling choosing a quad light's point `p` from `x`, seen along
/// unit `dir`, for a light picked with probability `pick` whose unit normal is `normal` and
/// whose area is 1 / `inv_area`; 0 where light sampling never goes.
#[inline]
pub fn quad_pdf(pick: f32, normal: Vec3, inv_area: f32, x: Vec3, p: Vec3, dir: Vec3) -> f32 {
    let cos_light = normal.dot(dir).abs();
    if !(cos_light > MIN_LIGHT_COSINE) {
        return 0.0;
    }
    let dist2 = (p - x).length_squared();
    pick * inv_area * dist2 / cos_light
}

/// Solid-angle pdf of light sampling choosing direction toward `light` from `x`, for a
/// direction that reaches the light at `p` (includes the pick probability).
#[inline]
pub fn pdf(light: &Light, x: Vec3, p: Vec3, dir: Vec3) -> f32 {
    match light.shape {
        LightShape::Sphere { center, radius } => match sphere_cone(center, radius, x) {
            Some((_, one_minus_cos)) => light.pick / (2.0 * PI * one_minus_cos),
            None => 0.0,
        },
        LightShape::Quad {
            normal, inv_area, ..
        }
        | LightShape::Triangle {
            normal, inv_area, ..
        } => quad_pdf(light.pick, normal, inv_area, x, p, dir),
        LightShape::Environment(env) => light.pick * environment::pdf(&env, dir),
        // A ray never meets a light of no area.
        LightShape::Point { .. } | LightShape::Directional { .. } => 0.0,
    }
}

/// The radiance-like quantity a punctual light sends to `x` (what multiplies BSDF x cos): a
/// point's or spot's intensity times its falloff over the squared distance, the sun's
/// irradiance; zero for lights with area.
#[inline]
pub fn punctual_arriving(light: &Light, x: Vec3) -> Vec3 {
    match light.shape {
        LightShape::Point {
            position,
            intensity,
            axis,
            ramp,
        } => {
            let from_light = x - position;
            let d2 = from_light.length_squared();
            if !(d2 > 0.0) {
                return Vec3::ZERO;
            }
            let cos = axis.dot(from_light) / d2.sqrt();
            let t = (cos * ramp[0] + ramp[1]).clamp(0.0, 1.0);
            intensity * (t * t / d2.max(MIN_DISTANCE_SQUARED))
        }
        LightShape::Directional { irradiance, .. } => irradiance,
        _ => Vec3::ZERO,
    }
}

/// A sample of a light seen from `x`: a unit direction, its solid-angle pdf (with the pick
/// probability), and the point on the light it reaches (where the shadow ray aims; for the
/// environment, which is at infinity, the shadow ray follows `dir` and `point` is unused).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    pub dir: Vec3,
    pub pdf: f32,
    pub point: Vec3,
}

/// A light sample from two uniform numbers; `None` where the light cannot be sampled from `x`.
#[inline]
pub fn sample(light: &Light, x: Vec3, u1: f32, u2: f32) -> Option<LightSample> {
    match light.shape {
        LightShape::Sphere { center, radius } => {
            let (axis, one_minus_cos) = sphere_cone(center, radius, x)?;
            // Uniform in the cone: 1 - cos(theta) uniform in [0, 1 - cos_max]; sin^2 from it
            // directly, so thin cones keep their width.
            let a = u1 * one_minus_cos;
            let cos_theta = 1.0 - a;
            let sin_theta = (a * (2.0 - a)).max(0.0).sqrt();
            let (sin_phi, cos_phi) = (PI * (2.0 * u2 - 1.0)).sin_cos();
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
                pdf: light.pick / (2.0 * PI * one_minus_cos),
                point: x + t * dir,
            })
        }
        LightShape::Quad {
            corner,
            u,
            v,
            normal,
            inv_area,
        } => area_sample(light.pick, corner + u1 * u + u2 * v, normal, inv_area, x),
        LightShape::Triangle {
            corner,
            u,
            v,
            normal,
            inv_area,
        } => {
            // Uniform on the triangle: (1 - sqrt(u1)) on the corner's weight.
            let s = u1.sqrt();
            let point = corner + (s * (1.0 - u2)) * u + (s * u2) * v;
            area_sample(light.pick, point, normal, inv_area, x)
        }
        // Punctual lights: one direction, with the probability of picking the light.
        LightShape::Point { position, .. } => {
            let to_light = position - x;
            let dist2 = to_light.length_squared();
            (dist2 > 0.0 && light.pick > 0.0).then(|| LightSample {
                dir: to_light / dist2.sqrt(),
                pdf: light.pick,
                point: position,
            })
        }
        LightShape::Directional { toward, .. } => (light.pick > 0.0).then_some(LightSample {
            dir: toward,
            pdf: light.pick,
            point: x + toward,
        }),
        LightShape::Environment(env) => {
            let (dir, pdf) = environment::sample(&env, u1, u2)?;
            let pdf = light.pick * pdf;
            (pdf > 0.0).then_some(LightSample {
                dir,
                pdf,
                point: x + dir,
            })
        }
    }
}

/// A sample of a quad or triangle light at `point`, seen from `x`.
#[inline]
fn area_sample(
    pick: f32,
    point: Vec3,
    normal: Vec3,
    inv_area: f32,
    x: Vec3,
) -> Option<LightSample> {
    let to_light = point - x;
    let dist2 = to_light.length_squared();
    if !(dist2 > 0.0) {
        return None;
    }
    let dir = to_light / dist2.sqrt();
    let pdf = quad_pdf(pick, normal, inv_area, x, point, dir);
    (pdf > 0.0).then_some(LightSample { dir, pdf, point })
}

/// The power heuristic (beta = 2) weight of a strategy with pdf `own` against one with pdf
/// `other`, computed on values scaled to at most 1 so neither square can overflow.
#[inline]
pub fn power_heuristic(own: f32, other: f32) -> f32 {
    let m = own.max(other);
    if !(m > 0.0) {
        return 1.0;
    }
    let (a, b) = (own / m, other / m);
    a * a / (a * a + b * b)
}

/// The light sample's power-heuristic weight over its pdf, the factor of BSDF x cos x radiance
/// in its contribution: a / (a^2 + b^2) / m for a, b the two pdfs scaled by their maximum m.
#[inline]
pub fn light_sample_weight(light_pdf: f32, bsdf_pdf: f32) -> f32 {
    let m = light_pdf.max(bsdf_pdf);
    if !(m > 0.0) {
        return 0.0;
    }
    let (a, b) = (light_pdf / m, bsdf_pdf / m);
    a / (a * a + b * b) / m
}

/// What a light sample at a scattering event in a medium contributes per unit of radiance (the
/// phase function is its own pdf): phase_pdf / light_pdf times its power-heuristic weight, i.e.
/// ab / (a^2 + b^2) for a, b the two pdfs scaled by their maximum. At most 1/2, whatever the
/// pdfs' magnitudes.
#[inline]
pub fn light_sample_factor(light_pdf: f32, bsdf_pdf: f32) -> f32 {
    let m = light_pdf.max(bsdf_pdf);
    if !(m > 0.0) {
        return 0.0;
    }
    let (a, b) = (light_pdf / m, bsdf_pdf / m);
    a * b / (a * a + b * b)
}
