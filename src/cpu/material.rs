//! Materials (twin: `shaders/materials.wgsl`), as the integrator sees them: what a surface emits
//! (`emitted`), how a path continues (`scatter`, the BSDF sampled), and, for BSDFs that light
//! sampling can reach, their value toward a given direction (`bsdf`). The path loop uses only
//! these; it never names a material. Random numbers drawn per bounce are fixed per material
//! (lambertian 2, metal 2, dielectric 1, light 0) so both backends stay in step.

use super::sampling::unit_vector;
use super::shapes::Hit;
use crate::rng::Rng;
use crate::scene::{Background, Material};
use glam::Vec3;

/// Radiance leaving the surface toward the ray.
#[inline]
pub fn emitted(material: &Material, hit: &Hit) -> Vec3 {
    match *material {
        Material::Lambertian { emission, .. } => emission,
        Material::Light {
            radiance,
            two_sided,
        } if hit.front_face || two_sided => radiance,
        _ => Vec3::ZERO,
    }
}

/// Whether next-event estimation samples lights at this material: its BSDF is not a delta
/// (metal and glass reflect into single directions that a light sample never picks) and not
/// absent (lights).
#[inline]
pub fn samples_lights(material: &Material) -> bool {
    matches!(material, Material::Lambertian { .. })
}

/// The BSDF toward unit direction `dir`, for light sampling and multiple importance sampling:
/// `(weight, pdf)`, where `pdf` is the solid-angle density with which [`scatter`] picks `dir`
/// and `weight` = BSDF x cosine / pdf (the factor a path sampled that way carries). `None` if
/// `scatter` cannot pick `dir` (below the surface; delta or absent BSDFs).
#[inline]
pub fn bsdf(material: &Material, hit: &Hit, dir: Vec3) -> Option<(Vec3, f32)> {
    match *material {
        // Cosine-weighted: pdf = cos / pi, BSDF x cos / pdf = albedo.
        Material::Lambertian { albedo, .. } => {
            let cos = hit.normal.dot(dir);
            (cos > 0.0).then_some((albedo, cos * std::f32::consts::FRAC_1_PI))
        }
        _ => None,
    }
}

/// The throughput factor and direction of the continued path, or `None` if the path ends here.
#[inline]
pub fn scatter(
    material: &Material,
    dir_in: Vec3,
    hit: &Hit,
    rng: &mut Rng,
) -> Option<(Vec3, Vec3)> {
    match *material {
        Material::Lambertian { albedo, .. } => {
            // normal + a uniform unit vector is cosine-distributed about the normal.
            let d = hit.normal + unit_vector(rng.next_f32(), rng.next_f32());
            let len2 = d.length_squared();
            let dir = if len2 > 1e-12 {
                d / len2.sqrt()
            } else {
                hit.normal
            };
            Some((albedo, dir))
        }
        Material::Metal { albedo, fuzz } => {
            let fuzzed =
                reflect(dir_in, hit.normal) + fuzz * unit_vector(rng.next_f32(), rng.next_f32());
            let len2 = fuzzed.length_squared();
            if !(len2 > 1e-12) {
                return None;
            }
            let dir = fuzzed / len2.sqrt();
            // Fuzzed below the surface: absorbed.
            (dir.dot(hit.normal) > 0.0).then_some((albedo, dir))
        }
        Material::Dielectric { ior } => {
            let eta = if hit.front_face { 1.0 / ior } else { ior };
            let cos_i = (-dir_in).dot(hit.normal).clamp(0.0, 1.0);
            let u = rng.next_f32();
            let dir = match refract_cos(cos_i, eta) {
                Some(cos_t) if u >= fresnel(cos_i, cos_t, eta) => {
                    eta * dir_in + (eta * cos_i - cos_t) * hit.normal
                }
                _ => reflect(dir_in, hit.normal),
            };
            Some((Vec3::ONE, dir.normalize()))
        }
        Material::Light { .. } => None,
    }
}

#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Cosine of the refracted angle for incidence cosine `cos_i` and relative index
/// `eta = n_incident / n_transmitted`, or `None` under total internal reflection.
#[inline]
pub fn refract_cos(cos_i: f32, eta: f32) -> Option<f32> {
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    (sin2_t < 1.0).then(|| (1.0 - sin2_t).sqrt())
}

/// Exact unpolarised Fresnel reflectance: the mean of the s and p reflectances.
#[inline]
pub fn fresnel(cos_i: f32, cos_t: f32, eta: f32) -> f32 {
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// The sky background's colour straight up (white at the horizon).
pub const SKY_ZENITH: [f32; 3] = [0.5, 0.7, 1.0];

/// Radiance arriving from the environment along unit direction `dir`.
#[inline]
pub fn background(bg: &Background, dir: Vec3) -> Vec3 {
    match *bg {
        Background::Constant(c) => c,
        Background::Sky => {
            let t = 0.5 * (dir.y + 1.0);
            (1.0 - t) * Vec3::ONE + t * Vec3::from(SKY_ZENITH)
        }
    }
}
