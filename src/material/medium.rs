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

/// `{ type = "medium", density = 0.01, albedo = [1, 1, 1], g = 0, absorption = [0, 0, 0] }`:
/// extinction coefficient sigma_t per unit length (one for all channels; default 0),
/// single-scattering albedo sigma_s / sigma_t per channel (default 1), Henyey-Greenstein
/// asymmetry (0 isotropic, > 0 forward), and `absorption`, a coefficient per channel and unit
/// length on top of them (default 0): Beer-Lambert's attenuation of whatever travels inside,
/// applied as a weight rather than sampled (the colour of tinted glass and liquids, glTF's
/// KHR_materials_volume). A medium has some density or some absorption.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Medium {
    #[serde(default, with = "checked::number")]
    pub density: f32,
    #[serde(default = "white", with = "checked::albedo")]
    pub albedo: Vec3,
    #[serde(default, with = "checked::number")]
    pub g: f32,
    #[serde(default, skip_serializing_if = "is_zero", with = "checked::colour")]
    pub absorption: Vec3,
}

fn white() -> Vec3 {
    Vec3::ONE
}

fn is_zero(v: &Vec3) -> bool {
    *v == Vec3::ZERO
}

impl Medium {
    /// Its parameter ranges; the message names the parameter.
    pub fn check(&self) -> Result<(), String> {
        if !(self.density >= 0.0 && self.density <= MAX_DENSITY) {
            return Err(format!(
                "medium density must be in [0, {MAX_DENSITY:e}], got {}",
                self.density
            ));
        }
        let a = self.absorption;
        if !(a.min_element() >= 0.0 && a.max_element() <= MAX_DENSITY) {
            return Err(format!(
                "medium absorption must be in [0, {MAX_DENSITY:e}] in each channel, got {a}"
            ));
        }
        if self.density == 0.0 && a == Vec3::ZERO {
            return Err("a medium needs a density > 0 or some absorption".into());
        }
        // |g| -> 1 makes the phase function a delta whose pdf overflows f32.
        if !(self.g.abs() <= 0.99) {
            return Err(format!("medium g must be in [-0.99, 0.99], got {}", self.g));
        }
        Ok(())
    }

    /// A purely absorbing medium attenuating to `color` over `distance` (glTF's
    /// attenuationColor and attenuationDistance): absorption -ln(color) / distance per channel,
    /// at most [`MAX_DENSITY`] (a channel of colour 0 absorbs everything in any distance).
    pub fn attenuating(color: Vec3, distance: f32) -> Medium {
        let absorption = Vec3::from_array(color.to_array().map(|c| {
            if c >= 1.0 {
                0.0
            } else {
                (-c.max(0.0).ln() / distance).min(MAX_DENSITY)
            }
        }));
        Medium {
            density: 0.0,
            albedo: Vec3::ONE,
            g: 0.0,
            absorption,
        }
    }

    /// The fraction of light of each channel crossing `distance` of it: its extinction's and
    /// its absorption's.
    #[inline]
    pub fn transmittance(&self, distance: f32) -> Vec3 {
        let sigma = Vec3::splat(self.density) + self.absorption;
        // A channel that nothing attenuates keeps all of its light, however far (0 x infinity
        // is no number).
        Vec3::select(sigma.cmpeq(Vec3::ZERO), Vec3::ONE, (-sigma * distance).exp())
    }

    /// What its absorption leaves of light travelling `distance` (1 without absorption).
    #[inline]
    pub fn absorbed_over(&self, distance: f32) -> Vec3 {
        let a = self.absorption;
        if distance >= f32::MAX {
            // Out of an open mesh: nothing bounds the stretch (and no infinity is computed).
            return Vec3::select(a.cmpeq(Vec3::ZERO), Vec3::ONE, Vec3::ZERO);
        }
        Vec3::select(a.cmpeq(Vec3::ZERO), Vec3::ONE, (-a * distance).exp())
    }

    /// The kernel features it needs: absorption's beside the media's.
    pub fn features(&self) -> Vec<MaterialFeature> {
        let absorbs = (self.absorption != Vec3::ZERO).then_some(MaterialFeature::Absorption);
        std::iter::once(MaterialFeature::Media).chain(absorbs).collect()
    }

    /// Packed into a material's medium slots (`density` and `absorption` 0: no medium).
    pub fn pack(medium: Option<&Medium>, into: GpuMaterial) -> GpuMaterial {
        match medium {
            Some(m) => GpuMaterial {
                medium_albedo: m.albedo.to_array(),
                medium_density: m.density,
                medium_g: m.g,
                medium_absorption: m.absorption.to_array(),
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
    const EXTRA_FEATURES: &'static [MaterialFeature] = &[MaterialFeature::Media, MaterialFeature::Absorption];
    const INVISIBLE: bool = true;

    fn validate(&self) -> Result<(), String> {
        self.check()
    }

    fn extra_features(&self) -> Vec<MaterialFeature> {
        self.features()
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
