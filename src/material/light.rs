//! A diffuse area light (twin: `shaders/materials/light.wgsl`). It emits from its front face
//! (along the shape's normal) unless `two_sided`, and reflects nothing. Random numbers: 0.

use crate::shared::feature::MaterialFeature;
use super::{BsdfSample, MaterialModel};
use crate::assets::alpha::Alpha;
use crate::shared::ray::Hit;
use crate::material::texture;
use crate::shared::layout::GpuMaterial;
use crate::shared::params::{MaterialParams, material_params};
use crate::shared::sampler::Sampler;
use crate::assets::texture::{self as textures, Texture};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// `{ type = "light", radiance = [r, g, b], strength = 1, two_sided = false }`; `radiance` may
/// be a texture (whose values `strength` scales).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Light {
    #[serde(with = "textures::radiance")]
    pub radiance: Texture,
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub strength: f32,
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub two_sided: bool,
    /// How rays see through it (glTF's alphaMode, MTL's `d`; not in scene files yet): where a
    /// ray passes, it neither meets the light nor sees its emission, and a shadow ray toward a
    /// point of it passes alike, so light sampling sees the same holes.
    #[serde(skip)]
    pub alpha: Option<Alpha>,
}

fn one() -> f32 {
    1.0
}

fn is_one(x: &f32) -> bool {
    *x == 1.0
}

/// Largest strength accepted.
pub const MAX_STRENGTH: f32 = 1e6;

material_params! {
    /// Beside the radiance (`GpuMaterial::with_albedo`).
    pub struct LightParams {
        strength: f32,
        /// 1: both faces emit.
        two_sided: u32,
    }
}

impl MaterialModel for Light {
    type Params = LightParams;
    const FEATURE: MaterialFeature = MaterialFeature::Light;
    /// Textured radiance.
    const EXTRA_FEATURES: &'static [MaterialFeature] = &[MaterialFeature::Checker, MaterialFeature::UvChecker, MaterialFeature::ImageTexture, MaterialFeature::Alpha];
    const EMITS_UNDER: Option<MaterialFeature> = Some(MaterialFeature::Light);

    fn validate(&self) -> Result<(), String> {
        if !(0.0..=MAX_STRENGTH).contains(&self.strength) {
            return Err(format!(
                "light strength must be in [0, {MAX_STRENGTH:e}], got {}",
                self.strength
            ));
        }
        self.radiance.validate()
    }

    fn relocated(self, origin: glam::DVec3) -> Self {
        Light {
            radiance: self.radiance.relocated(origin),
            ..self
        }
    }

    fn textures(&self) -> Vec<&Texture> {
        vec![&self.radiance]
    }

    fn extra_features(&self) -> Vec<MaterialFeature> {
        let alpha = self.alpha.as_ref().map(|_| MaterialFeature::Alpha);
        self.radiance.feature().into_iter().chain(alpha).collect()
    }

    fn alpha(&self) -> Option<&Alpha> {
        self.alpha.as_ref()
    }

    fn emitted(&self, hit: &Hit) -> Vec3 {
        if hit.front_face || self.two_sided {
            texture::value(&self.radiance, hit) * self.strength
        } else {
            Vec3::ZERO
        }
    }

    fn area_light(&self) -> Option<(Vec3, bool)> {
        let mean = self.radiance.mean() * self.strength;
        (mean != Vec3::ZERO).then_some((mean, self.two_sided))
    }

    fn sample(&self, _wo: Vec3, _hit: &Hit, _sampler: &mut Sampler) -> Option<BsdfSample> {
        None
    }

    /// albedo (and texture_*): radiance; its [`LightParams`].
    fn gpu(&self) -> GpuMaterial {
        GpuMaterial {
            params: LightParams {
                strength: self.strength,
                two_sided: self.two_sided as u32,
            }
            .words(),
            ..GpuMaterial::with_albedo(&self.radiance)
        }
    }
}
