//! Warping uniform random numbers to directions and points (twin: `shaders/sampling.wgsl`).

use super::angles::sin_cos_pi;
use glam::Vec3;

// Angles are drawn in [-pi, pi): Vulkan only bounds the error of GPU sin and cos in that range.

/// Uniform on the unit sphere.
#[inline]
pub fn unit_vector(u1: f32, u2: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin, cos) = sin_cos_pi(2.0 * u2 - 1.0);
    Vec3::new(r * cos, r * sin, z)
}

/// A direction cosine-distributed about unit `n` from two uniform numbers: `n` plus a
/// uniform unit vector, normalised (`n` itself where they cancel).
#[inline]
pub fn cosine_direction(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let d = n + unit_vector(u1, u2);
    let len2 = d.length_squared();
    if len2 > 1e-12 { d / len2.sqrt() } else { n }
}

/// Uniform on the unit disk, as (x, y).
#[inline]
pub fn unit_disk(u1: f32, u2: f32) -> (f32, f32) {
    let r = u1.sqrt();
    let (sin, cos) = sin_cos_pi(2.0 * u2 - 1.0);
    (r * cos, r * sin)
}

/// Two unit vectors completing unit `n` to an orthonormal basis (Duff et al., "Building an
/// Orthonormal Basis, Revisited", 2017): no branch on a threshold, stable at every direction.
#[inline]
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Cosine-weighted about a hit's shading normal: pdf = cos / pi (so a lambertian BSDF x cos =
/// albedo x pdf), 0 below the surface.
#[inline]
pub fn cosine_pdf(hit: &super::ray::Hit, wi: Vec3) -> f32 {
    let cos = hit.shading.dot(wi);
    if cos > 0.0 && !super::ray::below_surface(hit, wi) {
        cos * std::f32::consts::FRAC_1_PI
    } else {
        0.0
    }
}
