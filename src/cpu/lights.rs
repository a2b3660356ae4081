//! Light sampling for next-event estimation (twin: `shaders/lights.wgsl`): pick a light in
//! proportion to its power, then a direction toward it, and the solid-angle pdf of both, which
//! multiple importance sampling also needs for directions BSDF sampling found.

use super::environment;
use crate::scene::flat::{FlatScene, Light, LightShape};
use crate::scene::punctual::MIN_DISTANCE_SQUARED;
use crate::shape;
use glam::Vec3;

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

pub use crate::shape::sphere::sphere_cone;
pub use crate::shape::{LightSample, area_pdf as quad_pdf};

/// Solid-angle pdf of light sampling choosing direction toward `light` from `x`, for a
/// direction that reaches the light at `p` (includes the pick probability).
#[inline]
pub fn pdf(light: &Light, x: Vec3, p: Vec3, dir: Vec3) -> f32 {
    match light.shape {
        LightShape::Surface { kind, light: l } => shape::light_pdf(kind, &l, light.pick, x, p, dir),
        LightShape::Triangle {
            normal, inv_area, ..
        } => shape::area_pdf(light.pick, normal, inv_area, x, p, dir),
        LightShape::Environment(ref env) => light.pick * environment::pdf(env, dir),
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

/// A light sample from two uniform numbers; `None` where the light cannot be sampled from `x`.
#[inline]
pub fn sample(light: &Light, x: Vec3, u1: f32, u2: f32) -> Option<LightSample> {
    match light.shape {
        LightShape::Surface { kind, light: l } => {
            shape::sample_light(kind, &l, light.pick, x, u1, u2)
        }
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
            shape::area_sample(light.pick, point, normal, inv_area, x)
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
        LightShape::Environment(ref env) => {
            let (dir, pdf) = environment::sample(env, u1, u2)?;
            let pdf = light.pick * pdf;
            (pdf > 0.0).then_some(LightSample {
                dir,
                pdf,
                point: x + dir,
            })
        }
    }
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
