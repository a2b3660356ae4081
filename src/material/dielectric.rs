//! Smooth glass (twin: `shaders/materials/dielectric.wgsl`): exact unpolarised Fresnel,
//! refraction by Snell's law, total internal reflection. Random numbers per sample: 1. With a
//! `medium`, the glass is filled with it: subsurface scattering by a volumetric random walk.

use super::{BsdfSample, Lobe, MaterialModel, Medium, reflect};
use crate::shared::ray::Hit;
use crate::shared::layout::GpuMaterial;
use crate::shared::sampler::Sampler;
use crate::scene::file::checked;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// `{ type = "dielectric", ior = 1.5 }`: the index of refraction inside, relative to outside;
/// optionally `medium = { density = 0.05, albedo = [0.9, 0.6, 0.3], g = 0.5 }` inside.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Dielectric {
    #[serde(with = "checked::number")]
    pub ior: f32,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub medium: Option<Medium>,
}

impl Dielectric {
    /// Clear glass.
    pub fn clear(ior: f32) -> Self {
        Dielectric { ior, medium: None }
    }
}

impl MaterialModel for Dielectric {
    const FEATURE: &'static str = "DIELECTRIC";
    /// Glass filled with a medium.
    const EXTRA_FEATURES: &'static [&'static str] = &["MEDIA"];

    fn validate(&self) -> Result<(), String> {
        if !(self.ior > 0.0) {
            return Err(format!("ior must be > 0, got {}", self.ior));
        }
        self.medium.as_ref().map_or(Ok(()), Medium::check)
    }

    fn extra_features(&self) -> Vec<&'static str> {
        if self.medium.is_some() {
            Self::EXTRA_FEATURES.to_vec()
        } else {
            Vec::new()
        }
    }

    fn interior(&self) -> Option<&Medium> {
        self.medium.as_ref()
    }

    fn sample(&self, wo: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<BsdfSample> {
        let eta = if hit.front_face {
            1.0 / self.ior
        } else {
            self.ior
        };
        let n = hit.shading;
        let dir_in = -wo;
        let cos_i = wo.dot(n).clamp(0.0, 1.0);
        let u = sampler.next_f32();
        let (wi, lobe) = match refract_cos(cos_i, eta) {
            Some(cos_t) if u >= fresnel(cos_i, cos_t, eta) => {
                (eta * dir_in + (eta * cos_i - cos_t) * n, Lobe::DELTA_TRANSMISSION)
            }
            _ => (reflect(dir_in, n), Lobe::DELTA_REFLECTION),
        };
        let wi = wi.normalize();
        // A shading normal can send a reflection into the surface or a refraction out of it:
        // absorbed (the geometric normal decides sides, as for the medium inside).
        (hit.shading == hit.normal || (wi.dot(hit.normal) > 0.0) != lobe.is_transmission())
            .then_some(BsdfSample {
                weight: Vec3::ONE,
                wi,
                pdf: 0.0,
                lobe,
            })
    }

    /// param: ior; medium_*: the medium inside, if any.
    fn gpu(&self) -> GpuMaterial {
        let glass = GpuMaterial {
            albedo: [1.0; 3],
            param: self.ior,
            ..Default::default()
        };
        Medium::pack(self.medium.as_ref(), glass)
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
