//! Materials, one file each: the material's parameters (plain data, and with serde its
//! scene-file syntax), its CPU reference BSDF (the [`MaterialModel`] methods) and how it is
//! packed for the GPU; its WGSL twin is `shaders/materials/<file name>.wgsl`. The path loops on
//! both backends see only the interface below and never name a material.
//!
//! Adding a material: write its file here (with its GPU parameters as a `material_params!`
//! struct) and its WGSL twin, add one line to `registry!` below (which gives it its scene-file
//! `type` name, kernel kind and feature), document it in `scenes/README.md`.

use crate::assets::alpha::Alpha;
use crate::assets::image::Image;
use crate::assets::normal_map::NormalMap;
use crate::assets::texture::Texture;
pub use crate::shared::feature::MaterialFeature;
use crate::shared::layout::GpuMaterial;
use crate::shared::params::MaterialParams;
use crate::shared::ray::Hit;
use crate::shared::sampler::Sampler;
use glam::Vec3;
use std::sync::Arc;

/// What each material provides: pbrt-v4's and Mitsuba 3's BSDF interface (`sample`, `eval`,
/// `pdf`; see [`bsdf`]) and its emission. The CPU methods are the reference twins of the WGSL
/// functions `<name>_sample`, `<name>_eval`, `<name>_pdf`, `<name>_samples_lights` and
/// `<name>_emitted` in `shaders/materials/<name>.wgsl`; both draw the same random numbers in
/// the same order.
pub trait MaterialModel {
    /// Its own GPU parameters (`GpuMaterial::params`), declared with `material_params!`; its
    /// WGSL twin reads them with `<name>_params(m)`.
    type Params: MaterialParams;
    /// The kernel feature that includes its WGSL twin: the file name in upper case.
    const FEATURE: MaterialFeature;
    /// Features its WGSL twin's `//#if` blocks may test beyond [`Self::FEATURE`].
    const EXTRA_FEATURES: &'static [MaterialFeature] = &[];
    /// The feature under which the kernel calls its twin's `<name>_emitted`; `None`: it never
    /// emits, and its twin has no `<name>_emitted`.
    const EMITS_UNDER: Option<MaterialFeature> = None;
    /// Whether next-event estimation may sample lights at it: its BSDF can have a lobe that is
    /// neither a delta (a light sample never picks a mirror's direction) nor absent. Its twin
    /// then has `<name>_eval` and `<name>_pdf`.
    const SAMPLES_LIGHTS: bool = false;
    /// Whether that depends on the instance (a conductor's roughness 0 is a delta): its twin
    /// then has `<name>_samples_lights`.
    const SAMPLES_LIGHTS_PER_INSTANCE: bool = false;
    /// Whether its surface is invisible: rays pass it unchanged (it only bounds a medium), and
    /// neither a path segment nor a shadow ray ends there.
    const INVISIBLE: bool = false;

    /// Its parameter ranges; the message names the parameter.
    fn validate(&self) -> Result<(), String> {
        Ok(())
    }
    /// The [`Self::EXTRA_FEATURES`] this instance needs.
    fn extra_features(&self) -> Vec<MaterialFeature> {
        Vec::new()
    }
    /// This material in a flat scene whose coordinates are relative to `origin` (solid
    /// textures keep their place in the world).
    fn relocated(self, _origin: glam::DVec3) -> Self
    where
        Self: Sized,
    {
        self
    }
    /// The textures it reads (the GPU's image array holds their images).
    fn textures(&self) -> Vec<&Texture> {
        Vec::new()
    }
    /// The medium filling the object it is the surface of, if any.
    fn interior(&self) -> Option<&Medium> {
        None
    }
    /// The normal map that bends its shading normal on meshes, if any (applied where hits are
    /// completed, before any of the methods below sees the hit).
    fn normal_map(&self) -> Option<&NormalMap> {
        None
    }
    /// The normal map that bends its clear coat's normal on meshes (`Hit::coat`; pbr's
    /// clearcoatNormalTexture), if any.
    fn coat_normal_map(&self) -> Option<&NormalMap> {
        None
    }
    /// Whether a layer with a normal of its own (`Hit::coat`) lies over it: then its normal map
    /// bends only what lies below, and is no microsurface (`material::microsurface`).
    fn has_coat(&self) -> bool {
        false
    }
    /// An image of parameters, if it has one (`pbr`'s metallic-roughness texture, per point;
    /// a rough `plastic`'s coat table, per cosine): the GPU's image array holds it.
    fn parameter_image(&self) -> Option<&Arc<Image>> {
        None
    }
    /// `pbr`'s layers' image, sheen colour image, specular strength and colour images
    /// (`GpuMaterial::layer_image`, `sheen_image`, `specular_image`, `specular_color_image`),
    /// where it has them: the GPU's image array holds them.
    fn layer_images(&self) -> [Option<&Arc<Image>>; 4] {
        [None; 4]
    }
    /// A table the kernel reads for every instance alike (`pbr`'s sheen albedo,
    /// `GpuMaterial::sheen_table`): the GPU's image array holds it.
    fn table_image(&self) -> Option<&Arc<Image>> {
        None
    }
    /// How rays see through it, if they may (`assets::alpha`; the closest-hit search asks).
    fn alpha(&self) -> Option<&Alpha> {
        None
    }
    /// Emission on top of its BSDF, if it has some (glTF's emissive pbr): a light's radiance,
    /// strength and sidedness, which its `emitted` and `area_light` give and the kernel reads
    /// from `GpuMaterial::emission*` (the `light` material itself emits through its albedo).
    fn emission(&self) -> Option<&Light> {
        None
    }
    /// Radiance leaving the surface toward the ray.
    fn emitted(&self, _hit: &Hit) -> Vec3 {
        Vec3::ZERO
    }
    /// Radiance and whether both faces emit, if it emits: such surfaces join the light list.
    fn area_light(&self) -> Option<(Vec3, bool)> {
        None
    }
    /// Whether next-event estimation samples lights at this instance: it has a lobe that is
    /// neither a delta nor absent (then [`Self::SAMPLES_LIGHTS`] holds for its kind).
    fn samples_lights(&self) -> bool {
        Self::SAMPLES_LIGHTS
    }
    /// Whether its BSDF only reflects (no transmission lobe): then its normal map's shading
    /// normals make a microsurface of it (`material::microsurface`).
    fn reflects_only(&self) -> bool {
        false
    }
    /// Samples a direction `wi` for light leaving toward `wo` (unit, away from the surface),
    /// or `None` if the path ends here.
    fn sample(&self, wo: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<BsdfSample>;
    /// BSDF x |cos(wi)| for light arriving from `wi` and leaving toward `wo`, over its non-delta
    /// lobes. Called only where [`Self::samples_lights`].
    fn eval(&self, _wo: Vec3, _wi: Vec3, _hit: &Hit) -> Vec3 {
        Vec3::ZERO
    }
    /// The solid-angle density with which `sample` picks `wi`, over its non-delta lobes.
    /// Called only where [`Self::samples_lights`].
    fn pdf(&self, _wo: Vec3, _wi: Vec3, _hit: &Hit) -> f32 {
        0.0
    }
    /// Its GPU form, its [`Self::Params`] packed in `params`; `kind` is filled in from the
    /// registry.
    fn gpu(&self) -> GpuMaterial;
}

/// A material kind as the kernel builder sees it.
#[derive(Clone, Copy, Debug)]
pub struct MaterialKind {
    /// Scene-file `type`, WGSL file name and function-name prefix.
    pub name: &'static str,
    /// `GpuMaterial::kind`; the WGSL constant `MAT_<FEATURE>`.
    pub kind: u32,
    pub feature: MaterialFeature,
    pub extra_features: &'static [MaterialFeature],
    pub emits_under: Option<MaterialFeature>,
    pub samples_lights: bool,
    pub samples_lights_per_instance: bool,
    pub invisible: bool,
    /// The WGSL twin.
    pub wgsl: &'static str,
    /// The WGSL of its parameters' struct, reader and writer (`MaterialParams::wgsl`).
    pub params_wgsl: fn(&str) -> String,
}

macro_rules! registry {
    ($($module:ident :: $ty:ident,)+) => {
        $(pub mod $module; pub use $module::$ty;)+

        /// A material of any kind; scene files name the kind with `type = "<file name>"`.
        #[derive(Clone, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
        #[serde(tag = "type", rename_all = "snake_case")]
        pub enum Material {
            $($ty($ty),)+
        }

        #[repr(u32)]
        enum KindIndex {
            $($ty,)+
        }

        /// Every material kind, in `GpuMaterial::kind` order.
        pub const KINDS: &[MaterialKind] = &[$(MaterialKind {
            name: stringify!($module),
            kind: KindIndex::$ty as u32,
            feature: <$ty as MaterialModel>::FEATURE,
            extra_features: <$ty as MaterialModel>::EXTRA_FEATURES,
            emits_under: <$ty as MaterialModel>::EMITS_UNDER,
            samples_lights: <$ty as MaterialModel>::SAMPLES_LIGHTS,
            samples_lights_per_instance: <$ty as MaterialModel>::SAMPLES_LIGHTS_PER_INSTANCE,
            invisible: <$ty as MaterialModel>::INVISIBLE,
            wgsl: include_str!(concat!("../../shaders/materials/", stringify!($module), ".wgsl")),
            params_wgsl: <<$ty as MaterialModel>::Params as MaterialParams>::wgsl,
        },)+];

        // Each method passes to the material's own.
        impl Material {
            /// Its entry in [`KINDS`].
            pub fn kind(&self) -> &'static MaterialKind {
                match self { $(Material::$ty(_) => &KINDS[KindIndex::$ty as usize],)+ }
            }
            #[inline]
            pub fn samples_lights(&self) -> bool {
                match self { $(Material::$ty(m) => m.samples_lights(),)+ }
            }
            /// Whether rays pass its surface unchanged (see [`MaterialModel::INVISIBLE`]).
            #[inline]
            pub fn is_invisible(&self) -> bool {
                self.kind().invisible
            }
            #[inline]
            pub fn interior(&self) -> Option<&Medium> {
                match self { $(Material::$ty(m) => m.interior(),)+ }
            }
            #[inline]
            pub fn normal_map(&self) -> Option<&NormalMap> {
                match self { $(Material::$ty(m) => m.normal_map(),)+ }
            }
            pub fn validate(&self) -> Result<(), String> {
                if let Some(map) = self.normal_map() {
                    map.validate()?;
                }
                if let Some(map) = self.coat_normal_map() {
                    map.validate().map_err(|e| format!("clear coat's {e}"))?;
                }
                // A mesh's tangents follow one UV set.
                if let (Some(base), Some(coat)) = (self.normal_map(), self.coat_normal_map())
                    && base.image.lookup.uv_set != coat.image.lookup.uv_set
                {
                    return Err("its normal map and its clear coat's read different UV sets; rt-gpu lays both out along one".into());
                }
                if let Some(alpha) = self.alpha() {
                    alpha.validate()?;
                }
                match self { $(Material::$ty(m) => m.validate(),)+ }
            }
            pub fn extra_features(&self) -> Vec<MaterialFeature> {
                match self { $(Material::$ty(m) => m.extra_features(),)+ }
            }
            pub fn textures(&self) -> Vec<&Texture> {
                match self { $(Material::$ty(m) => m.textures(),)+ }
            }
            pub fn parameter_image(&self) -> Option<&Arc<Image>> {
                match self { $(Material::$ty(m) => m.parameter_image(),)+ }
            }
            pub fn table_image(&self) -> Option<&Arc<Image>> {
                match self { $(Material::$ty(m) => m.table_image(),)+ }
            }
            pub fn layer_images(&self) -> [Option<&Arc<Image>>; 4] {
                match self { $(Material::$ty(m) => m.layer_images(),)+ }
            }
            #[inline]
            pub fn alpha(&self) -> Option<&Alpha> {
                match self { $(Material::$ty(m) => m.alpha(),)+ }
            }
            pub fn emission(&self) -> Option<&Light> {
                match self { $(Material::$ty(m) => m.emission(),)+ }
            }
            /// Every image it reads: its textures', its normal maps', its parameter image, its
            /// table, its layer images, its alpha's and its emission's (an image may come more
            /// than once).
            pub fn images(&self) -> Vec<Arc<Image>> {
                let textures = self.textures().into_iter().chain(self.emission().map(|e| &e.radiance));
                let textures = textures.filter_map(|t| match t {
                    Texture::Image(image) => Some(image),
                    _ => None,
                });
                let maps = (self.normal_maps().map(|n| &n.image))
                    .chain(self.parameter_image())
                    .chain(self.table_image())
                    .chain(self.layer_images().into_iter().flatten())
                    .chain(self.alpha().and_then(|a| a.image.as_ref()));
                textures.chain(maps).cloned().collect()
            }
            pub fn relocated(self, origin: glam::DVec3) -> Self {
                match self { $(Material::$ty(m) => Material::$ty(m.relocated(origin)),)+ }
            }
            #[inline]
            pub fn emitted(&self, hit: &Hit) -> Vec3 {
                match self { $(Material::$ty(m) => m.emitted(hit),)+ }
            }
            pub fn area_light(&self) -> Option<(Vec3, bool)> {
                match self { $(Material::$ty(m) => m.area_light(),)+ }
            }
            /// Whether its BSDF only reflects (see [`MaterialModel::reflects_only`]).
            #[inline]
            pub fn reflects_only(&self) -> bool {
                match self { $(Material::$ty(m) => m.reflects_only(),)+ }
            }
            /// Its BSDF on a surface whose normal is `hit.shading` (the geometric one ignored):
            /// the material's own, which [`Self::sample`] uses on each facet of a microsurface.
            #[inline]
            pub fn facet_sample(&self, wo: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<BsdfSample> {
                match self { $(Material::$ty(m) => m.sample(wo, hit, sampler),)+ }
            }
            #[inline]
            pub fn facet_eval(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> Vec3 {
                match self { $(Material::$ty(m) => m.eval(wo, wi, hit),)+ }
            }
            #[inline]
            pub fn facet_pdf(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> f32 {
                match self { $(Material::$ty(m) => m.pdf(wo, wi, hit),)+ }
            }
            /// Whether its normal map's shading normals are microsurfaces
            /// (`material::microsurface`): it has one, only reflects and has no coat over it.
            #[inline]
            pub fn has_microsurface(&self) -> bool {
                self.normal_map().is_some() && self.reflects_only() && !self.has_coat()
            }
            pub fn coat_normal_map(&self) -> Option<&NormalMap> {
                match self { $(Material::$ty(m) => m.coat_normal_map(),)+ }
            }
            pub fn has_coat(&self) -> bool {
                match self { $(Material::$ty(m) => m.has_coat(),)+ }
            }
            /// Its normal maps: its own and its coat's.
            pub fn normal_maps(&self) -> impl Iterator<Item = &NormalMap> {
                self.normal_map().into_iter().chain(self.coat_normal_map())
            }
            /// The microsurface its BSDF sees at `hit`, if [`Self::has_microsurface`] and the
            /// shading normal there is not the geometric one.
            #[inline]
            pub fn microsurface(&self, hit: &Hit) -> Option<Microsurface> {
                if hit.shading == hit.normal || !self.has_microsurface() {
                    return None;
                }
                Microsurface::at(hit)
            }
            /// The path loops' BSDF: the material's own, on a microsurface where it has one.
            #[inline]
            pub fn sample(&self, wo: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<BsdfSample> {
                match self.microsurface(hit) {
                    Some(s) => s.sample(self, wo, sampler),
                    None => self.facet_sample(wo, hit, sampler),
                }
            }
            #[inline]
            pub fn eval(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> Vec3 {
                match self.microsurface(hit) {
                    Some(s) => s.eval(self, wo, wi),
                    None => self.facet_eval(wo, wi, hit),
                }
            }
            #[inline]
            pub fn pdf(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> f32 {
                match self.microsurface(hit) {
                    Some(s) => s.pdf(self, wo, wi),
                    None => self.facet_pdf(wo, wi, hit),
                }
            }
            /// Its GPU form, with its kind and its normal map (whose `normal_map_image` is set
            /// where the scene's images are laid out).
            pub fn gpu(&self) -> GpuMaterial {
                let packed = match self { $(Material::$ty(m) => m.gpu(),)+ };
                let map_of = |map: Option<&NormalMap>| map.map_or(
                    ([0.0; 2], 0.0, 0),
                    |n| ([n.image.width as f32, n.image.height as f32], n.scale, n.image.lookup.bits()),
                );
                let (normal_map_size, normal_map_scale, normal_map_lookup) = map_of(self.normal_map());
                let (coat_normal_map_size, coat_normal_map_scale, coat_normal_map_lookup) =
                    map_of(self.coat_normal_map());
                let (alpha_mode, alpha_cutoff) = self.alpha().map_or((0, 0.0), |a| a.gpu_mode());
                let alpha_image = self.alpha().and_then(|a| a.image.as_ref());
                let (emission, emission_image) = match self.emission().map(|e| (&e.radiance, e.strength)) {
                    Some((Texture::Image(image), strength)) => (image.factor * strength, Some(image)),
                    Some((texture, strength)) => (texture.mean() * strength, None),
                    None => (glam::Vec3::ZERO, None),
                };
                GpuMaterial {
                    kind: self.kind().kind,
                    normal_map_size,
                    normal_map_scale,
                    normal_map_lookup,
                    coat_normal_map_size,
                    coat_normal_map_scale,
                    coat_normal_map_lookup,
                    alpha_mode,
                    alpha_cutoff,
                    alpha_factor: self.alpha().map_or(1.0, |a| a.factor),
                    alpha_size: alpha_image.map_or([0.0; 2], |i| [i.width as f32, i.height as f32]),
                    alpha_lookup: alpha_image.map_or(0, |i| i.lookup.bits()),
                    emission: emission.to_array(),
                    emission_size: emission_image.map_or([0.0; 2], |i| [i.width as f32, i.height as f32]),
                    emission_lookup: emission_image.map_or(0, |i| i.lookup.bits()),
                    emission_two_sided: self.emission().is_some_and(|e| e.two_sided) as u32,
                    microsurface: self.has_microsurface() as u32,
                    ..packed
                }
            }
        }
    };
}

pub mod bsdf;
pub mod clearcoat;
pub mod coat;
pub mod coat_table;
pub mod fresnel;
pub mod microfacet;
pub mod microsurface;
pub mod sheen;
pub mod specular;
pub mod texture;

pub use bsdf::{BsdfSample, Lobe};
pub use microsurface::Microsurface;

registry! {
    lambertian::Lambertian,
    metal::Metal,
    dielectric::Dielectric,
    light::Light,
    medium::Medium,
    conductor::Conductor,
    plastic::Plastic,
    pbr::Pbr,
}

impl Material {
    /// A diffuse reflector that does not glow.
    pub fn lambertian(albedo: Vec3) -> Self {
        Material::Lambertian(Lambertian {
            albedo: albedo.into(),
            emission: Vec3::ZERO,
            normal_map: None,
        })
    }
}

/// Mirror reflection of `d` about unit normal `n`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_names_agree() {
        for kind in KINDS {
            assert_eq!(
                kind.feature.name(),
                kind.name.to_uppercase(),
                "{}",
                kind.name
            );
            assert!(kind.wgsl.contains(&format!("fn {}_sample(", kind.name)));
            assert_eq!(
                kind.emits_under.is_some(),
                kind.wgsl.contains(&format!("fn {}_emitted(", kind.name)),
                "{}: EMITS_UNDER and its twin's {0}_emitted",
                kind.name
            );
            for function in ["eval", "pdf"] {
                assert_eq!(
                    kind.samples_lights,
                    kind.wgsl.contains(&format!("fn {}_{function}(", kind.name)),
                    "{}: SAMPLES_LIGHTS and its twin's {0}_{function}",
                    kind.name
                );
            }
            assert_eq!(
                kind.samples_lights_per_instance,
                kind.wgsl
                    .contains(&format!("fn {}_samples_lights(", kind.name)),
                "{}: SAMPLES_LIGHTS_PER_INSTANCE and its twin's {0}_samples_lights",
                kind.name
            );
            assert!(kind.samples_lights || !kind.samples_lights_per_instance);
        }
    }
}
