//! Mirror reflection perturbed by `fuzz` (twin: `shaders/materials/metal.wgsl`), as the original
//! project's metal; rays fuzzed below the surface are absorbed. Random numbers per sample: 2.

use crate::shared::feature::MaterialFeature;
use super::{BsdfSample, Lobe, MaterialModel, reflect};
use crate::shared::warp::unit_vector;
use crate::shared::ray::Hit;
use crate::material::texture;
use crate::assets::texture::Texture;
use crate::shared::layout::GpuMaterial;
use crate::shared::params::{MaterialParams, material_params};
use crate::shared::sampler::Sampler;
use crate::params::checked;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// `{ type = "metal", albedo = [r, g, b], fuzz = 0.1 }`; `fuzz` in [0, 1], default 0; `albedo`
/// may be a texture.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Metal {
    pub albedo: Texture,
    #[serde(default, with = "checked::number")]
    pub fuzz: f32,
}

material_params! {
    /// Beside the albedo (`GpuMaterial::with_albedo`).
    pub struct MetalParams {
        fuzz: f32,
    }
}

impl MaterialModel for Metal {
    type Params = MetalParams;
    const FEATURE: MaterialFeature = MaterialFeature::Metal;
    /// Textured albedos.
    const EXTRA_FEATURES: &'static [MaterialFeature] = &[MaterialFeature::Checker, MaterialFeature::UvChecker, MaterialFeature::ImageTexture];

    fn validate(&self) -> Result<(), String> {
        if !(0.0..=1.0).contains(&self.fuzz) {
            return Err(format!("fuzz must be in [0, 1], got {}", self.fuzz));
        }
        self.albedo.validate_albedo()
    }

    fn textures(&self) -> Vec<&Texture> {
        vec![&self.albedo]
    }

    fn extra_features(&self) -> Vec<MaterialFeature> {
        self.albedo.feature().into_iter().collect()
    }

    fn relocated(self, origin: glam::DVec3) -> Self {
        Metal {
            albedo: self.albedo.relocated(origin),
            ..self
        }
    }

    /// The fuzzed lobe's density is not evaluated: it counts as a delta, as light sampling
    /// skips it.
    fn reflects_only(&self) -> bool {
        true
    }

    fn sample(&self, wo: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<BsdfSample> {
        let fuzzed =
            reflect(-wo, hit.shading) + self.fuzz * unit_vector(sampler.next_f32(), sampler.next_f32());
        let len2 = fuzzed.length_squared();
        if !(len2 > 1e-12) {
            return None;
        }
        let wi = fuzzed / len2.sqrt();
        // Fuzzed (or, by a shading normal, reflected) below the surface: absorbed.
        (wi.dot(hit.normal) > 0.0).then(|| BsdfSample {
            weight: texture::albedo(&self.albedo, hit),
            wi,
            pdf: 0.0,
            lobe: Lobe::DELTA_REFLECTION,
        })
    }

    /// albedo (and texture_*); its [`MetalParams`].
    fn gpu(&self) -> GpuMaterial {
        GpuMaterial {
            params: MetalParams { fuzz: self.fuzz }.words(),
            ..GpuMaterial::with_albedo(&self.albedo)
        }
    }
}
