//! glTF 2.0's metallic-roughness material (twin: `shaders/materials/pbr.wgsl`), as the
//! specification's appendix B composes it: a mix by `metallic` of a dielectric and a metal, the
//! dielectric itself a mix by `transmission` (KHR_materials_transmission) of a coat over a
//! diffuse base and of rough glass whose transmission the base colour tints. Here the coat is
//! [`Coat`] without saturation (the base's colour kept, as glTF viewers show it) and exact
//! Fresnel of `ior` (KHR_materials_ior) where the appendix allows Schlick's; the metal is GGX
//! with Schlick's Fresnel from F0 = base colour, as the appendix defines it; the glass is
//! `dielectric`'s. A specular (KHR_materials_specular) reshapes the coat's and the glass's
//! Fresnel alike (`specular.rs`).
//! One roughness for all three (alpha = roughness^2). Two-sided but for the glass. A
//! metallic-roughness image (glTF's metallicRoughnessTexture, linear) scales metallic by its
//! blue channel and roughness by its green one, point by point.
//!
//! A clear coat (KHR_materials_clearcoat, `clearcoat.rs`) may lie over the whole mix.
//!
//! Sampling picks a component with its weight in the mix (one number), then samples it: 2
//! more numbers for the metal, 3 for the coat, glass's own (1 smooth, 3 rough). A non-delta
//! direction is weighed by the whole mix over the mix's density (one-sample MIS); a delta one
//! by its component's weight alone.

use crate::shared::feature::MaterialFeature;
use std::sync::Arc;
use super::clearcoat::{Clearcoat, CoatDirection};
use super::sheen::Sheen;
use super::specular::Specular;
use super::coat::Coat;
use super::microfacet::{Frame, Ggx, MIN_ALPHA, MIN_COSINE};
use super::plastic::default_ior;
use super::{BsdfSample, Dielectric, Lobe, MaterialModel, Medium, reflect};
use crate::material::texture;
use crate::assets::alpha::Alpha;
use crate::params::checked;
use crate::assets::image::Image;
use crate::assets::normal_map::NormalMap;
use crate::assets::texture::Texture;
use crate::shared::layout::GpuMaterial;
use crate::shared::params::{MaterialParams, material_params};
use crate::shared::ray::{Hit, below_surface};
use crate::shared::sampler::Sampler;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// `{ type = "pbr", base_color = [0.8, 0.7, 0.2], metallic = 1.0, roughness = 0.35, ior = 1.5,
/// transmission = 0 }`; the defaults are glTF's (metallic 1, roughness 1, ior 1.5,
/// transmission 0); `base_color` may be any texture; `normal_map = { image, scale }` (optional)
/// bends meshes' shading normals (glTF's `normalTexture`; `assets::normal_map`);
/// `metallic_roughness = "file.png"` (optional, linear) scales metallic by its blue channel and
/// roughness by its green one (glTF's metallicRoughnessTexture); `emission = { radiance,
/// strength, two_sided }` (optional, as a `light`'s; a colour or an image) glows on top of
/// what it reflects (glTF's emissive materials); `clearcoat = { factor, roughness }`
/// (optional) a clear coat over it all (glTF's KHR_materials_clearcoat; `material::clearcoat`);
/// `layers = "file.png"` (optional, linear) scales the clear coat's factor by its red channel,
/// its roughness by green and the sheen's roughness by blue, and `sheen_image = "file.png"`
/// (optional, a colour image) the sheen's colour, point by point (glTF's clearcoatTexture,
/// clearcoatRoughnessTexture, sheenRoughnessTexture and sheenColorTexture);
/// `specular = { factor, color }` (optional) reshapes its dielectric's Fresnel (glTF's
/// KHR_materials_specular; `material::specular`), and `specular_image = "file.png"` (optional,
/// linear: its red channel) and `specular_color_image = "file.png"` (optional, a colour image)
/// scale its factor and colour point by point (specularTexture, specularColorTexture);
/// `clearcoat_normal_map = { image, scale }` (optional) bends the clear coat's normal on meshes
/// (glTF's clearcoatNormalTexture; without it the coat is not bent by `normal_map`).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "PbrDoc", into = "PbrDoc")]
pub struct Pbr {
    pub base_color: Texture,
    pub metallic: f32,
    pub roughness: f32,
    pub ior: f32,
    pub transmission: f32,
    pub normal_map: Option<NormalMap>,
    /// Whether the metallic-roughness image's red channel scales `transmission` too (glTF's
    /// transmissionTexture, merged into that image where a file is read:
    /// `FileTextures::transmission`; not in scene files yet).
    pub transmission_in_red: bool,
    /// How rays see through it (glTF's alphaMode; not in scene files yet).
    pub alpha: Option<Alpha>,
    /// Light it emits on top of what it reflects (glTF's emissive factor x texture x
    /// KHR_materials_emissive_strength): a colour or an image, its strength and sidedness, as
    /// a `light` material's (`emission = { radiance = [1, 0.5, 0.2], strength = 4 }`).
    pub emission: Option<super::Light>,
    /// A clear coat over the whole mix (glTF's KHR_materials_clearcoat; `material::clearcoat`);
    /// none where its factor is 0.
    pub clearcoat: Option<Clearcoat>,
    /// Velvet's sheen over the mix, under any clear coat (glTF's KHR_materials_sheen;
    /// `material::sheen`); none where its colour is black.
    pub sheen: Option<Sheen>,
    /// glTF's specular strength and colour on the dielectric's Fresnel (KHR_materials_specular;
    /// `material::specular`), in its coat; none where they change nothing.
    specular: Option<Specular>,
    /// What fills it where light enters through its glass ([`Self::volume`]); boxed, as few
    /// materials have one and every material is as large as the largest.
    volume: Option<Box<Volume>>,
    coat: Coat,
    /// Its images of parameters; boxed, as `volume`.
    images: Option<Box<ParameterImages>>,
}

/// A pbr material's images of parameters, each scaling some of them point by point.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParameterImages {
    /// Its metallic-roughness image (linear): blue scales metallic, green roughness (glTF's
    /// metallicRoughnessTexture), red the transmission where `Pbr::transmission_in_red`.
    pub metallic_roughness: Option<Arc<Image>>,
    /// The layers' textures in one image (linear): red scales the clear coat's factor (glTF's
    /// clearcoatTexture), green its roughness (clearcoatRoughnessTexture), blue the sheen's
    /// roughness (sheenRoughnessTexture's alpha); 1 where a file has no such texture.
    pub layers: Option<Arc<Image>>,
    /// The sheen colour's texture (glTF's sheenColorTexture), which scales its colour.
    pub sheen: Option<Arc<Image>>,
    /// The specular strength's image (linear): red scales the specular factor (glTF's
    /// specularTexture, whose alpha channel a file's loader puts there).
    pub specular: Option<Arc<Image>>,
    /// The specular colour's texture (glTF's specularColorTexture), which scales its colour.
    pub specular_color: Option<Arc<Image>>,
    /// The normal map of its clear coat (glTF's clearcoatNormalTexture; `Hit::coat`).
    pub clearcoat_normal_map: Option<NormalMap>,
}

impl ParameterImages {
    /// Whether it holds any image.
    fn any(&self) -> bool {
        let ParameterImages {
            metallic_roughness,
            layers,
            sheen,
            specular,
            specular_color,
            clearcoat_normal_map,
        } = self;
        [metallic_roughness, layers, sheen, specular, specular_color]
            .iter()
            .any(|i| i.is_some())
            || clearcoat_normal_map.is_some()
    }

    /// Whether it holds a specular image.
    fn specular_any(&self) -> bool {
        self.specular.is_some() || self.specular_color.is_some()
    }
}

/// An absorbing medium made from glTF's attenuation colour and distance (KHR_materials_volume;
/// `Medium::attenuating`), with them, as a scene file writes them.
#[derive(Clone, Debug, PartialEq)]
struct Volume {
    medium: Medium,
    color: Vec3,
    distance: f32,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct PbrDoc {
    base_color: Texture,
    #[serde(default = "one", with = "checked::number")]
    metallic: f32,
    #[serde(default = "one", with = "checked::number")]
    roughness: f32,
    #[serde(default = "default_ior", with = "checked::number")]
    ior: f32,
    #[serde(default, with = "checked::number")]
    transmission: f32,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    normal_map: Option<NormalMap>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    metallic_roughness: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    emission: Option<super::Light>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    clearcoat: Option<Clearcoat>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    attenuation: Option<Attenuation>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sheen: Option<Sheen>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    specular: Option<Specular>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    layers: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sheen_image: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    specular_image: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    specular_color_image: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    clearcoat_normal_map: Option<NormalMap>,
}

/// `attenuation = { color = [0.9, 0.6, 0.3], distance = 0.05 }`: the colour white light takes
/// after `distance` inside (glTF's attenuationColor and attenuationDistance).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct Attenuation {
    #[serde(with = "checked::albedo")]
    color: Vec3,
    #[serde(with = "checked::number")]
    distance: f32,
}

fn one() -> f32 {
    1.0
}

impl TryFrom<PbrDoc> for Pbr {
    type Error = String;
    fn try_from(d: PbrDoc) -> Result<Self, String> {
        super::fresnel::check_ior(d.ior)?;
        use crate::assets::loader::{data_image, image};
        // Data images (linear) and colour images (from sRGB), each where the file names one.
        let data = |name: Option<String>| name.as_deref().map(data_image).transpose();
        let colour = |name: Option<String>| name.as_deref().map(image).transpose();
        let metallic_roughness = data(d.metallic_roughness)?;
        let layers = data(d.layers)?;
        let sheen_image = colour(d.sheen_image)?;
        let specular_image = data(d.specular_image)?;
        let specular_color_image = colour(d.specular_color_image)?;
        Pbr::new(d.base_color, d.metallic, d.roughness, d.ior, d.transmission)
            .with_normal_map(d.normal_map)
            .with_metallic_roughness(metallic_roughness)
            .with_emission(d.emission)
            .with_clearcoat(d.clearcoat)
            .with_sheen(d.sheen)
            .with_specular(d.specular)
            .with_layer_images(layers, sheen_image)
            .with_specular_images(specular_image, specular_color_image)
            .with_clearcoat_normal_map(d.clearcoat_normal_map)
            .with_attenuation(d.attenuation.map(|a| (a.color, a.distance)))
    }
}

impl From<Pbr> for PbrDoc {
    fn from(p: Pbr) -> Self {
        let metallic_roughness = p.metallic_roughness().map(|i| i.source.clone());
        let layers = p.layers().map(|i| i.source.clone());
        let sheen_image = p.sheen_image().map(|i| i.source.clone());
        let specular_image = p.specular_image().map(|i| i.source.clone());
        let specular_color_image = p.specular_color_image().map(|i| i.source.clone());
        let clearcoat_normal_map = p.images.as_ref().and_then(|i| i.clearcoat_normal_map.clone());
        PbrDoc {
            base_color: p.base_color,
            metallic: p.metallic,
            roughness: p.roughness,
            ior: p.ior,
            transmission: p.transmission,
            normal_map: p.normal_map,
            metallic_roughness,
            emission: p.emission,
            clearcoat: p.clearcoat,
            sheen: p.sheen,
            specular: p.specular,
            layers,
            sheen_image,
            specular_image,
            specular_color_image,
            clearcoat_normal_map,
            attenuation: p.volume.map(|v| Attenuation {
                color: v.color,
                distance: v.distance,
            }),
        }
    }
}

/// The glass's tint: the base colour on transmission (glTF's `specular_btdf * baseColor`), none
/// on reflection.
#[inline]
fn transmission_tint(base: Vec3, transmitted: bool) -> Vec3 {
    if transmitted { base } else { Vec3::ONE }
}

/// Schlick's Fresnel from `f0` at cosine `cos`.
#[inline]
pub fn schlick(f0: Vec3, cos: f32) -> Vec3 {
    let x = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::ONE - f0) * x
}

impl Pbr {
    pub fn new(base_color: Texture, metallic: f32, roughness: f32, ior: f32, transmission: f32) -> Self {
        Pbr {
            base_color,
            metallic,
            roughness,
            ior,
            transmission,
            normal_map: None,
            transmission_in_red: false,
            alpha: None,
            emission: None,
            clearcoat: None,
            sheen: None,
            specular: None,
            volume: None,
            coat: Coat::new(ior, roughness, false),
            images: None,
        }
    }

    /// This material with its clear coat and sheen scaled point by point by `layers` (see
    /// [`Pbr::layers`]) and its sheen's colour by `sheen_image`.
    pub fn with_layer_images(self, layers: Option<Arc<Image>>, sheen: Option<Arc<Image>>) -> Self {
        let images = ParameterImages {
            layers,
            sheen,
            ..self.images.as_deref().cloned().unwrap_or_default()
        };
        self.with_images(images)
    }

    /// This material with its specular factor scaled point by point by `factor`'s red channel
    /// and its specular colour by `color` (glTF's specularTexture and specularColorTexture): a
    /// specular, the default where it had none, is kept wherever it has either.
    pub fn with_specular_images(self, factor: Option<Arc<Image>>, color: Option<Arc<Image>>) -> Self {
        let images = ParameterImages {
            specular: factor,
            specular_color: color,
            ..self.images.as_deref().cloned().unwrap_or_default()
        };
        let specular = self.specular;
        self.with_images(images).with_specular(specular)
    }

    /// This material with `images` (none where it has none of them).
    fn with_images(self, images: ParameterImages) -> Self {
        Pbr {
            images: images.any().then(|| Box::new(images)),
            ..self
        }
    }

    /// This material with `map` bending its clear coat's normal (glTF's
    /// clearcoatNormalTexture; without one the coat shades with the mesh's interpolated
    /// normal, whatever its base's normal map).
    pub fn with_clearcoat_normal_map(self, map: Option<NormalMap>) -> Self {
        let images = ParameterImages {
            clearcoat_normal_map: map,
            ..self.images.as_deref().cloned().unwrap_or_default()
        };
        self.with_images(images)
    }

    /// Its specular strength's image (see [`ParameterImages::specular`]).
    pub fn specular_image(&self) -> Option<&Arc<Image>> {
        self.images.as_ref()?.specular.as_ref()
    }

    /// Its specular colour's image (see [`ParameterImages::specular_color`]).
    pub fn specular_color_image(&self) -> Option<&Arc<Image>> {
        self.images.as_ref()?.specular_color.as_ref()
    }

    /// Its metallic-roughness image (see [`ParameterImages::metallic_roughness`]).
    pub fn metallic_roughness(&self) -> Option<&Arc<Image>> {
        self.images.as_ref()?.metallic_roughness.as_ref()
    }

    /// Its layers' image (see [`ParameterImages::layers`]).
    pub fn layers(&self) -> Option<&Arc<Image>> {
        self.images.as_ref()?.layers.as_ref()
    }

    /// Its sheen colour's image (see [`ParameterImages::sheen`]).
    pub fn sheen_image(&self) -> Option<&Arc<Image>> {
        self.images.as_ref()?.sheen.as_ref()
    }

    /// This material with `normal_map`.
    pub fn with_normal_map(self, normal_map: Option<NormalMap>) -> Self {
        Pbr { normal_map, ..self }
    }

    /// This material with its metallic and roughness scaled by `image`'s blue and green
    /// channels.
    pub fn with_metallic_roughness(self, image: Option<Arc<Image>>) -> Self {
        let images = ParameterImages {
            metallic_roughness: image,
            ..self.images.as_deref().cloned().unwrap_or_default()
        };
        self.with_images(images)
    }

    /// This material, seen through as `alpha` says.
    pub fn with_alpha(self, alpha: Option<Alpha>) -> Self {
        Pbr { alpha, ..self }
    }

    /// This material, emitting `emission` on top of what it reflects.
    pub fn with_emission(self, emission: Option<super::Light>) -> Self {
        Pbr { emission, ..self }
    }

    /// This material under `clearcoat` (none where its factor is 0).
    pub fn with_clearcoat(self, clearcoat: Option<Clearcoat>) -> Self {
        Pbr {
            clearcoat: clearcoat.filter(|c| c.factor > 0.0),
            ..self
        }
    }

    /// This material under `sheen` (none where its colour is black).
    pub fn with_sheen(self, sheen: Option<Sheen>) -> Self {
        Pbr {
            sheen: sheen.filter(|s| s.color.max_element() > 0.0),
            ..self
        }
    }

    /// This material with its dielectric's Fresnel reshaped by `specular` (none where it
    /// changes nothing: the default, unless specular images scale it).
    pub fn with_specular(self, specular: Option<Specular>) -> Self {
        let imaged = self.images.as_ref().is_some_and(|i| i.specular_any());
        let specular = match specular {
            None if imaged => Some(Specular::default()),
            s => s.filter(|s| imaged || !s.is_default()),
        };
        Pbr {
            coat: self.coat.with_specular(specular.map(|s| s.fresnel(self.ior))),
            specular,
            ..self
        }
    }

    /// Its specular strength and colour, where they change anything.
    pub fn specular(&self) -> Option<&Specular> {
        self.specular.as_ref()
    }

    /// This material filled, where light enters through its glass, with a medium that
    /// attenuates light to `color` over `distance` (`None`: a thin surface; a colour of 1 in
    /// every channel fills it with nothing).
    pub fn with_attenuation(self, attenuation: Option<(Vec3, f32)>) -> Result<Self, String> {
        let Some((color, distance)) = attenuation else {
            return Ok(Pbr {
                volume: None,
                ..self
            });
        };
        if !(distance > 0.0 && distance.is_finite()) {
            return Err(format!("attenuation distance must be a finite number > 0, got {distance}"));
        }
        if !(color.min_element() >= 0.0 && color.max_element() <= 1.0) {
            return Err(format!("attenuation color must be in [0, 1] in each channel, got {color}"));
        }
        Ok(Pbr {
            volume: Some(Box::new(Volume {
                medium: Medium::attenuating(color, distance),
                color,
                distance,
            })),
            ..self
        })
    }

    /// What fills it where light enters through its glass (glTF's KHR_materials_volume: an
    /// absorbing medium); none for a thin surface, or where the colour is 1 (nothing absorbs).
    pub fn volume(&self) -> Option<&Medium> {
        let volume = self.volume.as_ref()?;
        (volume.medium.absorption != Vec3::ZERO).then_some(&volume.medium)
    }

    /// Its lobes at `hit`: the base colour looked up, metallic and roughness scaled by its
    /// metallic-roughness image there, its clear coat, sheen and specular by its layer and
    /// specular images, as the kernel's `with_albedo_at` resolves them.
    fn at(&self, hit: &Hit) -> Lobes {
        let lobes = Lobes {
            base: texture::albedo(&self.base_color, hit),
            metallic: self.metallic,
            transmission: self.transmission,
            ior: self.ior,
            roughness: self.roughness,
            coat: self.coat,
            // As the kernel tells them present (a factor or colour above 0), whatever the
            // public fields were set to.
            clearcoat: self.clearcoat.filter(|c| c.factor > 0.0),
            sheen: self.sheen.filter(|s| s.color.max_element() > 0.0),
        };
        let lobes = self.layers_at(lobes, hit);
        let Some(image) = self.metallic_roughness() else {
            return lobes;
        };
        let uv = texture::uv_at(image.lookup, hit);
        let texel = crate::assets::image_lookup::image_at(image, uv);
        let roughness = self.roughness * texel.y;
        Lobes {
            metallic: self.metallic * texel.z,
            transmission: if self.transmission_in_red {
                self.transmission * texel.x
            } else {
                self.transmission
            },
            roughness,
            coat: Coat {
                alpha: Coat::alpha_of(roughness),
                ..lobes.coat
            },
            ..lobes
        }
    }


    fn ggx(&self) -> Option<Ggx> {
        ggx(&self.coat)
    }

    /// `lobes` with the clear coat, sheen and specular its layer and specular images give at
    /// `hit` (as the kernel's `pbr_with_layers`): a coat or sheen a texel takes to 0 is none
    /// there; the specular's changes the coat's K with its mean opacity.
    fn layers_at(&self, mut lobes: Lobes, hit: &Hit) -> Lobes {
        let texel_of = |image: &Image| {
            crate::assets::image_lookup::image_at(image, texture::uv_at(image.lookup, hit))
        };
        if let Some(image) = self.layers() {
            let texel = texel_of(image);
            lobes.clearcoat = lobes.clearcoat.and_then(|c| {
                let factor = c.factor * texel.x;
                (factor > 0.0).then_some(Clearcoat {
                    factor,
                    roughness: c.roughness * texel.y,
                })
            });
            lobes.sheen = lobes.sheen.map(|s| Sheen {
                roughness: s.roughness * texel.z,
                ..s
            });
        }
        if let Some(image) = self.sheen_image() {
            let texel = texel_of(image);
            lobes.sheen = lobes.sheen.and_then(|s| {
                let color = s.color * texel;
                (color.max_element() > 0.0).then_some(Sheen { color, ..s })
            });
        }
        if let Some(specular) = lobes.coat.specular
            && (self.specular_image().is_some() || self.specular_color_image().is_some())
        {
            let factor = self.specular_image().map_or(1.0, |i| texel_of(i).x);
            let color = self.specular_color_image().map_or(Vec3::ONE, |i| texel_of(i));
            lobes.coat = lobes.coat.with_specular(Some(specular.scaled(factor, color)));
        }
        lobes
    }
}

/// `PbrParams::flags`: next-event estimation samples lights here.
pub const PBR_SAMPLES_LIGHTS: u32 = 1;
/// `PbrParams::flags`: the metallic-roughness image's red channel scales the transmission.
pub const PBR_TRANSMISSION_IN_RED: u32 = 2;

/// An image's width and height as the kernel's material holds them (0: none).
fn image_size(image: Option<&Image>) -> [f32; 2] {
    image.map_or([0.0; 2], |i| [i.width as f32, i.height as f32])
}

/// The weights of the coat, the glass and the metal in the mix.
fn weights(metallic: f32, transmission: f32) -> (f32, f32, f32) {
    let dielectric = 1.0 - metallic;
    (
        dielectric * (1.0 - transmission),
        dielectric * transmission,
        metallic,
    )
}

/// The rough lobes' distribution; `None`: smooth.
fn ggx(coat: &Coat) -> Option<Ggx> {
    (coat.alpha > 0.0).then_some(Ggx { alpha: coat.alpha })
}

/// A pbr material's lobes at one hit (textures looked up): what its BSDF evaluates, samples
/// and gives the pdf of.
#[derive(Clone, Copy)]
struct Lobes {
    base: Vec3,
    metallic: f32,
    transmission: f32,
    ior: f32,
    roughness: f32,
    coat: Coat,
    clearcoat: Option<Clearcoat>,
    sheen: Option<Sheen>,
}

impl Lobes {
    fn weights(&self) -> (f32, f32, f32) {
        weights(self.metallic, self.transmission)
    }

    fn ggx(&self) -> Option<Ggx> {
        ggx(&self.coat)
    }

    /// The glass of the mix, its Fresnel reshaped as the coat's by any specular.
    fn glass(&self) -> Dielectric {
        Dielectric::rough(self.ior, self.roughness).with_specular(self.coat.specular)
    }

    /// Under a clear coat, one number picks the coat (with its reflectance at wo) or the
    /// mix below; the mix's deltas keep their weight, and any other direction is weighed by
    /// the whole BSDF over the whole density.
    fn sample(&self, wo: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<BsdfSample> {
        let chosen = match self.clearcoat {
            None => self.sample_below(wo, hit, sampler)?,
            Some(clearcoat) => {
                let chance = clearcoat.reflectance(wo.dot(hit.coat));
                if sampler.next_f32() < chance {
                    let (u1, u2) = (sampler.next_f32(), sampler.next_f32());
                    match clearcoat.sample(wo, hit, u1, u2)? {
                        // The mirror's reflectance over its chance.
                        CoatDirection::Mirror(wi) => {
                            return Some(BsdfSample {
                                weight: Vec3::ONE,
                                wi,
                                pdf: 0.0,
                                lobe: Lobe::DELTA_REFLECTION,
                            });
                        }
                        CoatDirection::Rough(wi) => BsdfSample {
                            weight: Vec3::ZERO,
                            wi,
                            pdf: 0.0,
                            lobe: Lobe::GLOSSY_REFLECTION,
                        },
                    }
                } else {
                    // A delta below keeps its weight: what crosses the coat over the chance of
                    // not sampling it, 1.
                    self.sample_below(wo, hit, sampler)?
                }
            }
        };
        if chosen.lobe.is_delta() {
            return Some(chosen);
        }
        let pdf = self.pdf(wo, chosen.wi, hit);
        (pdf > 0.0).then(|| BsdfSample {
            weight: self.eval(wo, chosen.wi, hit) / pdf,
            pdf,
            ..chosen
        })
    }

    /// A direction from below any clear coat: the sheen's (picked with its reflectance at
    /// wo; cosine-distributed), else the mix's; a delta one weighed (its component's weight
    /// alone), any other for [`Self::sample`] to weigh.
    fn sample_below(&self, wo: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<BsdfSample> {
        let Some(sheen) = self.sheen else {
            return self.sample_mix(wo, hit, sampler);
        };
        let chance = sheen.reflectance(wo.dot(hit.shading));
        if sampler.next_f32() < chance {
            let (u1, u2) = (sampler.next_f32(), sampler.next_f32());
            let wi = crate::shared::warp::cosine_direction(hit.shading, u1, u2);
            return Some(BsdfSample {
                weight: Vec3::ZERO,
                wi,
                pdf: 0.0,
                lobe: Lobe::GLOSSY_REFLECTION,
            });
        }
        // A delta of the mix keeps its weight: what shows through the sheen over the chance of
        // not picking it, 1.
        self.sample_mix(wo, hit, sampler)
    }

    /// The sheen's BSDF x cos and the mix's seen through it.
    fn eval_below(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> Vec3 {
        let mix = self.eval_mix(wo, wi, hit);
        match self.sheen {
            None => mix,
            Some(s) => s.eval(wo, wi, hit) + mix * s.through(wo, hit),
        }
    }

    /// The density of [`Self::sample_below`]'s non-delta directions.
    fn pdf_below(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> f32 {
        let mix = self.pdf_mix(wo, wi, hit);
        match self.sheen {
            None => mix,
            Some(s) => {
                let chance = s.reflectance(wo.dot(hit.shading));
                chance * crate::shared::warp::cosine_pdf(hit, wi) + (1.0 - chance) * mix
            }
        }
    }

    /// A direction from the mix below any sheen and clear coat: a delta one weighed (its
    /// component's weight alone), any other for [`Self::sample`] to weigh.
    fn sample_mix(&self, wo: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<BsdfSample> {
        let (w_coat, w_glass, _) = self.weights();
        let base = self.base;
        let u = sampler.next_f32();
        let chosen = if u < w_coat {
            let numbers = (sampler.next_f32(), sampler.next_f32(), sampler.next_f32());
            self.coat.sample(base, wo, hit, numbers)?
        } else if u < w_coat + w_glass {
            let s = self.glass().sample(wo, hit, sampler)?;
            // A direction within rounding of where the glass's own density vanishes: not one
            // for the other components' densities to weigh.
            if !s.lobe.is_delta() && !(self.glass().pdf(wo, s.wi, hit) > 0.0) {
                return None;
            }
            BsdfSample {
                weight: s.weight * transmission_tint(base, s.lobe.is_transmission()),
                ..s
            }
        } else {
            let (u1, u2) = (sampler.next_f32(), sampler.next_f32());
            let frame = Frame::new(hit.shading);
            let wo_local = frame.to_local(wo);
            if !(wo_local.z > MIN_COSINE) {
                return None;
            }
            let Some(ggx) = self.ggx() else {
                let wi = reflect(-wo, hit.shading);
                return (!below_surface(hit, wi)).then(|| BsdfSample {
                    weight: schlick(base, wo_local.z),
                    wi,
                    pdf: 0.0,
                    lobe: Lobe::DELTA_REFLECTION,
                });
            };
            let m = ggx.sample_visible(wo_local, u1, u2);
            let wi_local = reflect(-wo_local, m);
            let wi = frame.to_world(wi_local);
            // Below the surface the metal's own density is lost mass: the path ends, as a
            // conductor's does, rather than count under the other components' densities.
            if !(wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
                return None;
            }
            BsdfSample {
                weight: Vec3::ZERO,
                wi,
                pdf: 0.0,
                lobe: Lobe::GLOSSY_REFLECTION,
            }
        };
        Some(chosen)
    }

    /// BSDF x cos over its non-delta lobes: the clear coat's, and the mix's seen through it.
    fn eval(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> Vec3 {
        let mix = self.eval_below(wo, wi, hit);
        match self.clearcoat {
            None => mix,
            Some(c) => mix * c.through(wo, hit) + Vec3::splat(c.lobe(wo, wi, hit).0),
        }
    }

    /// The density of [`Self::sample`] over its non-delta lobes.
    fn pdf(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> f32 {
        let mix = self.pdf_below(wo, wi, hit);
        match self.clearcoat {
            None => mix,
            Some(c) => {
                let chance = c.reflectance(wo.dot(hit.coat));
                chance * c.lobe(wo, wi, hit).1 + (1.0 - chance) * mix
            }
        }
    }

    fn eval_mix(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> Vec3 {
        let (w_coat, w_glass, w_metal) = self.weights();
        let base = self.base;
        let mut f = Vec3::ZERO;
        if w_coat > 0.0 {
            f += w_coat * self.coat.eval(base, wo, wi, hit);
        }
        if w_glass > 0.0 {
            let tint = transmission_tint(base, wi.dot(hit.shading) < 0.0);
            f += w_glass * tint * self.glass().eval(wo, wi, hit);
        }
        if w_metal > 0.0 {
            f += w_metal * self.metal(base, wo, wi, hit).0;
        }
        f
    }

    fn pdf_mix(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> f32 {
        let (w_coat, w_glass, w_metal) = self.weights();
        let base = self.base;
        let mut pdf = 0.0;
        if w_coat > 0.0 {
            pdf += w_coat * self.coat.pdf(base, wo, wi, hit);
        }
        if w_glass > 0.0 {
            pdf += w_glass * self.glass().pdf(wo, wi, hit);
        }
        if w_metal > 0.0 {
            pdf += w_metal * self.metal(base, wo, wi, hit).1;
        }
        pdf
    }

    /// The metal's BSDF x cos and pdf at (wo, wi), rough only.
    fn metal(&self, base: Vec3, wo: Vec3, wi: Vec3, hit: &Hit) -> (Vec3, f32) {
        let Some(ggx) = self.ggx() else {
            return (Vec3::ZERO, 0.0);
        };
        let frame = Frame::new(hit.shading);
        let (wo_local, wi_local) = (frame.to_local(wo), frame.to_local(wi));
        if !(wo_local.z > MIN_COSINE && wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
            return (Vec3::ZERO, 0.0);
        }
        let m = (wo_local + wi_local).normalize();
        let f = schlick(base, wo_local.dot(m)) * (ggx.d(m) * ggx.g2(wo_local, wi_local) / (4.0 * wo_local.z));
        (f, ggx.reflection_pdf(wo_local, m))
    }
}

material_params! {
    /// Beside the base colour (`GpuMaterial::with_albedo`), the metallic-roughness image
    /// (`GpuMaterial::parameter_image*`, which the kernel applies per hit: `pbr_with_texel`)
    /// and the layer and specular images (`GpuMaterial::layer_image*`, `sheen_image*`,
    /// `specular_image*`, `specular_color_image*`: `pbr_with_layers`).
    pub struct PbrParams {
        metallic: f32,
        transmission: f32,
        ior: f32,
        /// GGX alpha; 0: smooth.
        alpha: f32,
        /// The coat's K (`Coat::internal_reflectance`).
        internal_reflectance: f32,
        /// Roughness before the metallic-roughness image scales it (`alpha` is what it is
        /// without one).
        roughness: f32,
        /// Bits: `PBR_SAMPLES_LIGHTS` (next-event estimation samples lights here) and
        /// `PBR_TRANSMISSION_IN_RED` (the metallic-roughness image's red channel scales
        /// `transmission`).
        flags: u32,
        /// The mean of the specular's Fresnel shape (`SpecularFresnel::shape_mean`), from
        /// which the coat's K follows where the specular images change it per hit.
        specular_shape_mean: f32,
        /// The clear coat's factor (0: none) and GGX alpha (0: smooth).
        clearcoat: f32,
        clearcoat_alpha: f32,
        /// The sheen's colour (black: none) and roughness (`Sheen::alpha`, whose square is the
        /// distribution's a).
        sheen_color: [f32; 3],
        sheen_roughness: f32,
        /// The specular factor (below 0: none, Fresnel's own) and its colour's tint of F0,
        /// unclamped (`SpecularFresnel`).
        specular_factor: f32,
        specular_tint: [f32; 3],
        /// The clear coat's and the sheen's roughness as given, which the layers' image
        /// scales (`pbr_with_layers`).
        clearcoat_roughness: f32,
        sheen_roughness_factor: f32,
    }
}

impl MaterialModel for Pbr {
    type Params = PbrParams;
    const FEATURE: MaterialFeature = MaterialFeature::Pbr;
    /// Rough; glass in the mix; textured base colours.
    const EXTRA_FEATURES: &'static [MaterialFeature] = &[
        MaterialFeature::Microfacet,
        MaterialFeature::Dielectric,
        MaterialFeature::MetallicRoughness,
        MaterialFeature::LayerImages,
        MaterialFeature::Alpha,
        MaterialFeature::Checker,
        MaterialFeature::UvChecker,
        MaterialFeature::ImageTexture,
        MaterialFeature::PbrEmission,
        MaterialFeature::Clearcoat,
        MaterialFeature::Media,
        MaterialFeature::Absorption,
        MaterialFeature::Sheen,
        MaterialFeature::Specular,
    ];
    /// Emissive pbr.
    const EMITS_UNDER: Option<MaterialFeature> = Some(MaterialFeature::PbrEmission);
    const SAMPLES_LIGHTS: bool = true;
    const SAMPLES_LIGHTS_PER_INSTANCE: bool = true;

    fn validate(&self) -> Result<(), String> {
        for (name, v) in [
            ("metallic", self.metallic),
            ("roughness", self.roughness),
            ("transmission", self.transmission),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(format!("{name} must be in [0, 1], got {v}"));
            }
        }
        super::fresnel::check_ior(self.ior)?;
        if let Some(clearcoat) = &self.clearcoat {
            clearcoat.validate()?;
        }
        if self.clearcoat.is_none() && self.images.as_ref().is_some_and(|i| i.clearcoat_normal_map.is_some()) {
            return Err("clearcoat_normal_map bends a clear coat's normal, but it has no clearcoat".into());
        }
        if let Some(sheen) = &self.sheen {
            sheen.validate()?;
        }
        if let Some(specular) = &self.specular {
            specular.validate()?;
        }
        if let Some(volume) = self.volume() {
            volume.check()?;
        }
        if let Some(emission) = &self.emission {
            if matches!(emission.radiance, Texture::Checker(_) | Texture::UvChecker(_)) {
                return Err("emission must be a colour or an image".into());
            }
            emission.validate()?;
        }
        // Only the specular image's red channel is read.
        if let Some(image) = self.specular_image()
            && image.max_channel().x > 1.0
        {
            return Err(format!(
                "specular image {} has values up to {} in its red channel: they lie in [0, 1]",
                image.source,
                image.max_channel().x
            ));
        }
        for (what, image) in [
            ("metallic-roughness", self.metallic_roughness()),
            ("layers", self.layers()),
            ("sheen", self.sheen_image()),
        ] {
            if let Some(image) = image
                && image.max_value() > 1.0
            {
                return Err(format!(
                    "{what} image {} has values up to {}: its values lie in [0, 1]",
                    image.source,
                    image.max_value()
                ));
            }
        }
        self.base_color.validate_albedo()
    }

    fn extra_features(&self) -> Vec<MaterialFeature> {
        let rough_coat = self.clearcoat.is_some_and(|c| c.alpha() > 0.0);
        let rough = (self.roughness * self.roughness >= MIN_ALPHA || rough_coat).then_some(MaterialFeature::Microfacet);
        let clearcoat = self.clearcoat.map(|_| MaterialFeature::Clearcoat);
        let sheen = self.sheen.map(|_| MaterialFeature::Sheen);
        let specular = self.specular.map(|_| MaterialFeature::Specular);
        let volume = self.volume().map_or_else(Vec::new, Medium::features);
        // A metallic-roughness image may take metallic to 0 anywhere (as `samples_lights`).
        let least_metallic = if self.metallic_roughness().is_some() { 0.0 } else { self.metallic };
        let glass = ((1.0 - least_metallic) * self.transmission > 0.0).then_some(MaterialFeature::Dielectric);
        let image = self.metallic_roughness().map(|_| MaterialFeature::MetallicRoughness);
        let specular_images = self.images.as_ref().is_some_and(|i| i.specular_any());
        let layer_images = (self.layers().is_some() && (self.clearcoat.is_some() || self.sheen.is_some())
            || self.sheen_image().is_some() && self.sheen.is_some()
            || specular_images && self.specular.is_some())
            .then_some(MaterialFeature::LayerImages);
        let alpha = self.alpha.as_ref().map(|_| MaterialFeature::Alpha);
        let emission = self.emission.as_ref().map(|e| {
            let image = matches!(e.radiance, Texture::Image(_)).then_some(MaterialFeature::ImageTexture);
            std::iter::once(MaterialFeature::PbrEmission).chain(image)
        });
        rough
            .into_iter()
            .chain(glass)
            .chain(clearcoat)
            .chain(sheen)
            .chain(specular)
            .chain(volume)
            .chain(image)
            .chain(layer_images)
            .chain(alpha)
            .chain(self.base_color.feature())
            .chain(emission.into_iter().flatten())
            .collect()
    }

    fn relocated(self, origin: glam::DVec3) -> Self {
        Pbr {
            base_color: self.base_color.relocated(origin),
            emission: self.emission.map(|e| e.relocated(origin)),
            ..self
        }
    }

    fn emission(&self) -> Option<&super::Light> {
        self.emission.as_ref()
    }

    fn interior(&self) -> Option<&Medium> {
        self.volume()
    }

    fn emitted(&self, hit: &Hit) -> Vec3 {
        self.emission.as_ref().map_or(Vec3::ZERO, |e| e.emitted(hit))
    }

    fn area_light(&self) -> Option<(Vec3, bool)> {
        self.emission.as_ref().and_then(|e| e.area_light())
    }

    fn textures(&self) -> Vec<&Texture> {
        vec![&self.base_color]
    }

    fn normal_map(&self) -> Option<&NormalMap> {
        self.normal_map.as_ref()
    }

    /// Its clear coat's, where it has a coat.
    fn coat_normal_map(&self) -> Option<&NormalMap> {
        self.clearcoat?;
        self.images.as_ref()?.clearcoat_normal_map.as_ref()
    }

    fn has_coat(&self) -> bool {
        self.clearcoat.is_some()
    }

    /// A lobe that is not a delta: the coat's base, or any rough one, at some point (a
    /// metallic-roughness image may take metallic to 0 anywhere).
    fn samples_lights(&self) -> bool {
        let least_metallic = if self.metallic_roughness().is_some() { 0.0 } else { self.metallic };
        let least_transmission = if self.transmission_in_red { 0.0 } else { self.transmission };
        (1.0 - least_metallic) * (1.0 - least_transmission) > 0.0
            || self.ggx().is_some()
            || self.clearcoat.is_some_and(|c| c.alpha() > 0.0)
            || self.sheen.is_some()
    }

    fn parameter_image(&self) -> Option<&Arc<Image>> {
        self.metallic_roughness()
    }

    fn table_image(&self) -> Option<&Arc<Image>> {
        self.sheen.map(|_| super::sheen::albedo_table())
    }

    fn layer_images(&self) -> [Option<&Arc<Image>>; 4] {
        [self.layers(), self.sheen_image(), self.specular_image(), self.specular_color_image()]
    }

    fn alpha(&self) -> Option<&Alpha> {
        self.alpha.as_ref()
    }

    fn reflects_only(&self) -> bool {
        self.transmission == 0.0
    }

    fn sample(&self, wo: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<BsdfSample> {
        self.at(hit).sample(wo, hit, sampler)
    }

    fn eval(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> Vec3 {
        self.at(hit).eval(wo, wi, hit)
    }

    fn pdf(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> f32 {
        self.at(hit).pdf(wo, wi, hit)
    }

    /// albedo (and texture_*): base colour; metallic_roughness_*: its image; its
    /// [`PbrParams`].
    fn gpu(&self) -> GpuMaterial {
        let size = self
            .metallic_roughness()
            .map_or([0.0; 2], |i| [i.width as f32, i.height as f32]);
        GpuMaterial {
            params: PbrParams {
                metallic: self.metallic,
                transmission: self.transmission,
                ior: self.ior,
                alpha: self.coat.alpha,
                internal_reflectance: self.coat.internal_reflectance,
                roughness: self.roughness,
                flags: if self.samples_lights() { PBR_SAMPLES_LIGHTS } else { 0 }
                    | if self.transmission_in_red { PBR_TRANSMISSION_IN_RED } else { 0 },
                specular_shape_mean: self.coat.specular.map_or(0.0, |s| s.shape_mean),
                clearcoat: self.clearcoat.map_or(0.0, |c| c.factor),
                clearcoat_alpha: self.clearcoat.map_or(0.0, |c| c.alpha()),
                clearcoat_roughness: self.clearcoat.map_or(0.0, |c| c.roughness),
                sheen_color: self.sheen.map_or([0.0; 3], |s| s.color.to_array()),
                sheen_roughness: self.sheen.map_or(0.0, |s| s.alpha()),
                sheen_roughness_factor: self.sheen.map_or(0.0, |s| s.roughness),
                specular_factor: self.coat.specular.map_or(-1.0, |s| s.factor),
                specular_tint: self.coat.specular.map_or([0.0; 3], |s| s.tint.to_array()),
            }
            .words(),
            parameter_image_size: size,
            parameter_image_lookup: self.metallic_roughness().map_or(0, |i| i.lookup.bits()),
            layer_image_size: image_size(self.layers().map(|i| &**i)),
            layer_image_lookup: self.layers().map_or(0, |i| i.lookup.bits()),
            sheen_image_size: image_size(self.sheen_image().map(|i| &**i)),
            sheen_image_lookup: self.sheen_image().map_or(0, |i| i.lookup.bits()),
            specular_image_size: image_size(self.specular_image().map(|i| &**i)),
            specular_image_lookup: self.specular_image().map_or(0, |i| i.lookup.bits()),
            specular_color_image_size: image_size(self.specular_color_image().map(|i| &**i)),
            specular_color_image_lookup: self.specular_color_image().map_or(0, |i| i.lookup.bits()),
            ..Medium::pack(self.volume(), GpuMaterial::with_albedo(&self.base_color))
        }
    }
}
