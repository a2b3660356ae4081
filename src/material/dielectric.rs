//! Smooth glass (twin: `shaders/materials/dielectric.wgsl`): exact unpolarised Fresnel,
//! refraction by Snell's law, total internal reflection. Random numbers per scatter: 1.

use super::{MaterialModel, reflect};
use crate::cpu::shapes::Hit;
use crate::gpu::layout::GpuMaterial;
use crate::sampler::Sampler;
use crate::scene::file::checked;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// `{ type = "dielectric", ior = 1.5 }`: the index of refraction inside, relative to outside.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Dielectric {
    #[serde(with = "checked::number")]
    pub ior: f32,
}

impl MaterialModel for Dielectric {
    const FEATURE: &'static str = "DIELECTRIC";

    fn validate(&self) -> Result<(), String> {
        if !(self.ior > 0.0) {
            return Err(format!("ior must be > 0, got {}", self.ior));
        }
        Ok(())
    }

    fn scatter(&self, dir_in: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<(Vec3, Vec3)> {
        let eta = if hit.front_face {
            1.0 / self.ior
        } else {
            self.ior
        };
        let cos_i = (-dir_in).dot(hit.normal).clamp(0.0, 1.0);
        let u = sampler.next_f32();
        let dir = match refract_cos(cos_i, eta) {
            Some(cos_t) if u >= fresnel(cos_i, cos_t, eta) => {
                eta * dir_in + (eta * cos_i - cos_t) * hit.normal
            }
            _ => reflect(dir_in, hit.normal),
        };
        Some((Vec3::ONE, dir.normalize()))
    }

    /// param: ior.
    fn gpu(&self) -> GpuMaterial {
        GpuMaterial {
            albedo: [1.0; 3],
            param: self.ior,
            ..Default::default()
        }
    }
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
