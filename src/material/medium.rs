//! A homogeneous participating medium and the invisible surface that bounds it (twin:
//! `shaders/materials/medium.wgsl`; the medium's own sampling is `src/cpu/medium.rs`, twin
//! `shaders/medium.wgsl`). As a material, `{ type = "medium", ... }` fills a closed object
//! with smoke or fog: rays pass its surface unchanged (the path loop steps through it without
//! counting a segment) and scatter inside it. A dielectric's `medium` fills the glass instead.

use crate::shared::feature::MaterialFeature;
use super::{BsdfSample, Lobe, MaterialModel};
use crate::shared::ray::Hit;
use crate::shared::layout::GpuMaterial;
use crate::shared::sampler::Sampler;
use crate::params::checked;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Densest medium accepted: mean free paths stay far above f32's spacing at scene scale.
pub const MAX_DENSITY: f32 = 1e8;

/// `{ type = "medium", density = 0.01, albedo = [1, 1, 1], g = 0 }`: extinction coefficient
/// sigma_t per unit length (one for all channels), single-scattering albedo sigma_s / sigma_t
/// per channel, Henyey-Greenstein asymmetry (0 isotropic, > 0 forward).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Medium {
    #[serde(with = "checked::number")]
    pub density: f32,
    #[serde(with = "checked::albedo")]
    pub albedo: Vec3,
    #[serde(default, with = "checked::number")]
    pub g: f32,
}

impl Medium {
    /// Its parameter ranges; the message names the parameter.
    pub fn check(&self) -> Result<(), String> {
        if !(self.density > 0.0 && self.density <= MAX_DENSITY) {
            return Err(format!(
                "medium density must be in (0, {MAX_DENSITY:e}], got {}",
                self.density
            ));
        }
        // |g| -> 1 makes the phase function a delta whose pdf overflows f32.
        if !(self.g.abs() <= 0.99) {
            return Err(format!("medium g must be in [-0.99, 0.99], got {}", self.g));
        }
        Ok(())
    }

    /// Packed into a material's medium slots (`density` 0: no medium).
    pub fn pack(medium: Option<&Medium>, into: GpuMaterial) -> GpuMaterial {
        match medium {
            Some(m) => GpuMaterial {
                medium_albedo: m.albedo.to_array(),
                medium_density: m.density,
                medium_g: m.g,
                ..into
            },
            None => into,
        }
    }
}

impl MaterialModel for Medium {
    type Params = crate::shared::params::NoParams;
    const FEATURE: MaterialFeature = MaterialFeature::Medium;
    /// Any scene with a medium inside some object.
    const EXTRA_FEATURES: &'static [MaterialFeature] = &[MaterialFeature::Media];
    const INVISIBLE: bool = true;

    fn validate(&self) -> Result<(), String> {
        self.check()
    }

    fn extra_features(&self) -> Vec<MaterialFeature> {
        Self::EXTRA_FEATURES.to_vec()
    }

    fn interior(&self) -> Option<&Medium> {
        Some(self)
    }

    /// Straight on, unchanged (the path loops step through it before they would call this).
    fn sample(&self, wo: Vec3, _hit: &Hit, _sampler: &mut Sampler) -> Option<BsdfSample> {
        Some(BsdfSample {
            weight: Vec3::ONE,
            wi: -wo,
            pdf: 0.0,
            lobe: Lobe::DELTA_TRANSMISSION,
        })
    }

    /// medium_*: its own parameters.
    fn gpu(&self) -> GpuMaterial {
        Medium::pack(Some(self), GpuMaterial::default())
    }
}
