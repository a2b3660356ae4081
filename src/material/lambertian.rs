//! Ideal diffuse reflection (twin: `shaders/materials/lambertian.wgsl`). Random numbers per
//! sample: 2.

use crate::shared::feature::MaterialFeature;
use super::{BsdfSample, Lobe, MaterialModel};
use crate::shared::warp::{cosine_direction, cosine_pdf};
use crate::shared::ray::{Hit, below_surface};
use crate::material::texture;
use crate::assets::normal_map::NormalMap;
use crate::assets::texture::Texture;
use crate::shared::layout::GpuMaterial;
use crate::shared::params::{MaterialParams, material_params};
use crate::shared::sampler::Sampler;
use crate::params::checked;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// `{ type = "lambertian", albedo = [r, g, b], emission = [r, g, b], normal_map = { image, scale } }`.
/// `emission` (optional, both faces) makes it glow, as the furnace tests need; `albedo` may be a
/// texture; `normal_map` (optional) bends meshes' shading normals (`assets::normal_map`).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Lambertian {
    pub albedo: Texture,
    #[serde(default, skip_serializing_if = "checked::is_black", with = "checked::colour")]
    pub emission: Vec3,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal_map: Option<NormalMap>,
}

material_params! {
    /// Beside the albedo (`GpuMaterial::with_albedo`).
    pub struct LambertianParams {
        emission: [f32; 3],
    }
}

impl MaterialModel for Lambertian {
    type Params = LambertianParams;
    const FEATURE: MaterialFeature = MaterialFeature::Lambertian;
    /// Lambertian surfaces with emission; textured albedos.
    const EXTRA_FEATURES: &'static [MaterialFeature] = &[MaterialFeature::Emissive, MaterialFeature::Checker, MaterialFeature::UvChecker, MaterialFeature::ImageTexture];

    fn validate(&self) -> Result<(), String> {
        self.albedo.validate_albedo()
    }

    fn relocated(self, origin: glam::DVec3) -> Self {
        Lambertian {
            albedo: self.albedo.relocated(origin),
            ..self
        }
    }
    const EMITS_UNDER: Option<MaterialFeature> = Some(MaterialFeature::Emissive);
    const SAMPLES_LIGHTS: bool = true;

    fn textures(&self) -> Vec<&Texture> {
        vec![&self.albedo]
    }

    fn extra_features(&self) -> Vec<MaterialFeature> {
        let emissive = (self.emission != Vec3::ZERO).then_some(MaterialFeature::Emissive);
        emissive.into_iter().chain(self.albedo.feature()).collect()
    }

    fn emitted(&self, _hit: &Hit) -> Vec3 {
        self.emission
    }

    fn normal_map(&self) -> Option<&NormalMap> {
        self.normal_map.as_ref()
    }

    fn area_light(&self) -> Option<(Vec3, bool)> {
        (self.emission != Vec3::ZERO).then_some((self.emission, true))
    }

    fn reflects_only(&self) -> bool {
        true
    }

    fn sample(&self, _wo: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<BsdfSample> {
        let (u1, u2) = (sampler.next_f32(), sampler.next_f32());
        let wi = cosine_direction(hit.shading, u1, u2);
        (!below_surface(hit, wi)).then(|| BsdfSample {
            weight: texture::albedo(&self.albedo, hit),
            wi,
            pdf: cosine_pdf(hit, wi),
            lobe: Lobe::DIFFUSE_REFLECTION,
        })
    }

    fn eval(&self, _wo: Vec3, wi: Vec3, hit: &Hit) -> Vec3 {
        texture::albedo(&self.albedo, hit) * cosine_pdf(hit, wi)
    }

    fn pdf(&self, _wo: Vec3, wi: Vec3, hit: &Hit) -> f32 {
        cosine_pdf(hit, wi)
    }

    /// albedo (and texture_*); its [`LambertianParams`].
    fn gpu(&self) -> GpuMaterial {
        GpuMaterial {
            params: LambertianParams {
                emission: self.emission.to_array(),
            }
            .words(),
            ..GpuMaterial::with_albedo(&self.albedo)
        }
    }
}
