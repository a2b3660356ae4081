//! Plastic (twin: `shaders/materials/plastic.wgsl`): a clear dielectric coat, smooth or on GGX
//! microfacets, over a lambertian base, the light reflected back and forth between the two
//! summed in closed form (a saturating [`Coat`]; its file gives the model), two-sided. A rough
//! coat lets through what rough glass's transmission lobe does (its `CoatTable`), as Mitsuba 3's
//! `roughplastic` does. Random numbers per sample: 3.
//!
//! Why closed form rather than pbrt-v4's stochastic layering: `eval` and `pdf` are then exact
//! functions of (wo, wi), as light sampling, MIS and the kernel-against-CPU tests need, at the
//! cost of a lambertian base and a clear coat.

use crate::shared::feature::MaterialFeature;
use std::sync::Arc;
use super::coat::Coat;
use super::coat_table::COAT_TABLE_SIZE;
use super::{BsdfSample, MaterialModel};
use crate::material::texture;
use crate::params::checked;
use crate::assets::image::Image;
use crate::assets::texture::Texture;
use crate::shared::layout::GpuMaterial;
use crate::shared::params::{MaterialParams, material_params};
use crate::shared::ray::Hit;
use crate::shared::sampler::Sampler;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// `{ type = "plastic", albedo = [0.6, 0.05, 0.05], ior = 1.5, roughness = 0.2 }`: the base's
/// albedo (any texture, in [0, 1]), the coat's index (default 1.5) and roughness in [0, 1]
/// (default 0: smooth; below 0.01 too), GGX alpha = roughness^2.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "PlasticDoc", into = "PlasticDoc")]
pub struct Plastic {
    pub albedo: Texture,
    pub ior: f32,
    pub roughness: f32,
    coat: Coat,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct PlasticDoc {
    albedo: Texture,
    #[serde(default = "default_ior", with = "checked::number")]
    ior: f32,
    #[serde(default, with = "checked::number")]
    roughness: f32,
}

pub(crate) fn default_ior() -> f32 {
    1.5
}

impl TryFrom<PlasticDoc> for Plastic {
    type Error = String;
    fn try_from(doc: PlasticDoc) -> Result<Self, String> {
        super::fresnel::check_ior(doc.ior)?;
        // Before the coat's table is built from it.
        if !(0.0..=1.0).contains(&doc.roughness) {
            return Err(format!("roughness must be in [0, 1], got {}", doc.roughness));
        }
        Ok(Plastic::new(doc.albedo, doc.ior, doc.roughness))
    }
}

impl From<Plastic> for PlasticDoc {
    fn from(p: Plastic) -> Self {
        PlasticDoc {
            albedo: p.albedo,
            ior: p.ior,
            roughness: p.roughness,
        }
    }
}

impl Plastic {
    /// A coat of index `ior` (> 0) and `roughness` (in [0, 1]) over a base of `albedo`.
    pub fn new(albedo: Texture, ior: f32, roughness: f32) -> Self {
        Plastic {
            albedo,
            ior,
            roughness,
            coat: Coat::new(ior, roughness, true).tabulated(),
        }
    }
}

material_params! {
    /// Beside the albedo (`GpuMaterial::with_albedo`): its coat's.
    pub struct PlasticParams {
        ior: f32,
        /// GGX alpha; 0: smooth.
        alpha: f32,
        /// The coat's K (`Coat::internal_reflectance`).
        internal_reflectance: f32,
    }
}

impl MaterialModel for Plastic {
    type Params = PlasticParams;
    const FEATURE: MaterialFeature = MaterialFeature::Plastic;
    /// Textured albedos and a rough coat's table (shaders/microfacet.wgsl is included for it
    /// without a feature).
    const EXTRA_FEATURES: &'static [MaterialFeature] =
        &[MaterialFeature::Checker, MaterialFeature::UvChecker, MaterialFeature::ImageTexture, MaterialFeature::CoatTable];
    const SAMPLES_LIGHTS: bool = true;

    fn validate(&self) -> Result<(), String> {
        super::fresnel::check_ior(self.ior)?;
        if !(0.0..=1.0).contains(&self.roughness) {
            return Err(format!("roughness must be in [0, 1], got {}", self.roughness));
        }
        self.albedo.validate_albedo()
    }

    fn extra_features(&self) -> Vec<MaterialFeature> {
        let table = self.coat.table.map(|_| MaterialFeature::CoatTable);
        self.albedo.feature().into_iter().chain(table).collect()
    }

    /// A rough coat's table (`CoatTable`).
    fn parameter_image(&self) -> Option<&Arc<Image>> {
        self.coat.table.map(|t| &t.image)
    }

    fn relocated(self, origin: glam::DVec3) -> Self {
        Plastic {
            albedo: self.albedo.relocated(origin),
            ..self
        }
    }

    fn textures(&self) -> Vec<&Texture> {
        vec![&self.albedo]
    }

    fn reflects_only(&self) -> bool {
        true
    }

    fn sample(&self, wo: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<BsdfSample> {
        let numbers = (sampler.next_f32(), sampler.next_f32(), sampler.next_f32());
        self.coat
            .sample(texture::albedo(&self.albedo, hit), wo, hit, numbers)
    }

    fn eval(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> Vec3 {
        self.coat
            .eval(texture::albedo(&self.albedo, hit), wo, wi, hit)
    }

    fn pdf(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> f32 {
        self.coat
            .pdf(texture::albedo(&self.albedo, hit), wo, wi, hit)
    }

    /// albedo (and texture_*); a rough coat's table as its parameter image; its
    /// [`PlasticParams`].
    fn gpu(&self) -> GpuMaterial {
        let table_size = self.coat.table.map_or(0.0, |_| COAT_TABLE_SIZE as f32);
        GpuMaterial {
            parameter_image_size: [table_size, 1.0],
            params: PlasticParams {
                ior: self.ior,
                alpha: self.coat.alpha,
                internal_reflectance: self.coat.internal_reflectance,
            }
            .words(),
            ..GpuMaterial::with_albedo(&self.albedo)
        }
    }
}
