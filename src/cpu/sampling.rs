//! Warping uniform random numbers to directions and points (twin: `shaders/sampling.wgsl`).

use glam::Vec3;
use std::f32::consts::PI;

// Angles are drawn in [-pi, pi): Vulkan only bounds the error of GPU sin and cos in that range.

/// Uniform on the unit sphere.
#[inline]
pub fn unit_vector(u1: f32, u2: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin, cos) = (PI * (2.0 * u2 - 1.0)).sin_cos();
    Vec3::new(r * cos, r * sin, z)
}

/// Uniform on the unit disk, as (x, y).
#[inline]
pub fn unit_disk(u1: f32, u2: f32) -> (f32, f32) {
    let r = u1.sqrt();
    let (sin, cos) = (PI * (2.0 * u2 - 1.0)).sin_cos();
    (r * cos, r * sin)
}
