//! Ideal diffuse reflection (twin: `shaders/materials/lambertian.wgsl`). Random numbers per
//! scatter: 2.

use super::MaterialModel;
use crate::cpu::sampling::unit_vector;
use crate::cpu::shapes::Hit;
use crate::gpu::layout::GpuMaterial;
use crate::sampler::Sampler;
use crate::scene::file::checked;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// `{ type = "lambertian", albedo = [r, g, b], emission = [r, g, b] }`. `emission` (optional,
/// both faces) makes it glow, as the furnace tests need.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Lambertian {
    #[serde(with = "checked::albedo")]
    pub albedo: Vec3,
    #[serde(default, skip_serializing_if = "checked::is_black", with = "checked::colour")]
    pub emission: Vec3,
}

impl MaterialModel for Lambertian {
    const FEATURE: &'static str = "LAMBERTIAN";
    /// Lambertian surfaces with emission.
    const EXTRA_FEATURES: &'static [&'static str] = &["EMISSIVE"];
    const EMITS_UNDER: Option<&'static str> = Some("EMISSIVE");
    const SAMPLES_LIGHTS: bool = true;

    fn extra_features(&self) -> &'static [&'static str] {
        if self.emission != Vec3::ZERO {
            Self::EXTRA_FEATURES
        } else {
            &[]
        }
    }

    fn emitted(&self, _hit: &Hit) -> Vec3 {
        self.emission
    }

    fn area_light(&self) -> Option<(Vec3, bool)> {
        (self.emission != Vec3::ZERO).then_some((self.emission, true))
    }

    fn bsdf(&self, hit: &Hit, dir: Vec3) -> Option<(Vec3, f32)> {
        // Cosine-weighted: pdf = cos / pi, BSDF x cos / pdf = albedo.
        let cos = hit.normal.dot(dir);
        (cos > 0.0).then_some((self.albedo, cos * std::f32::consts::FRAC_1_PI))
    }

    fn scatter(&self, _dir_in: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<(Vec3, Vec3)> {
        // normal + a uniform unit vector is cosine-distributed about the normal.
        let d = hit.normal + unit_vector(sampler.next_f32(), sampler.next_f32());
        let len2 = d.length_squared();
        let dir = if len2 > 1e-12 {
            d / len2.sqrt()
        } else {
            hit.normal
        };
        Some((self.albedo, dir))
    }

    /// albedo, emission.
    fn gpu(&self) -> GpuMaterial {
        GpuMaterial {
            albedo: self.albedo.to_array(),
            emission: self.emission.to_array(),
            ..Default::default()
        }
    }
}
