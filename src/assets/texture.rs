//! Textures: what a material's albedo may be besides one colour (evaluated by
//! `src/material/texture.rs`, twin `shaders/texture.wgsl`). Plain data, and with serde its
//! scene-file syntax: `[r, g, b]`, `{ checker = { scale, even, odd } }` (a solid checker in
//! space, as in Ray Tracing: The Next Week) or `{ uv_checker = { scale, even, odd } }` (a
//! checker in the surface's UV coordinates) or `{ image = "file.png" }` (an image in UV
//! coordinates, bilinear, wrapping; see `assets::image` for formats).

use crate::assets::image::Image;
use crate::params::checked;
use crate::shared::feature::MaterialFeature;
use glam::{DVec3, Vec3};
use serde::de::{self, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::sync::Arc;

/// An albedo: every value in [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    Colour(Vec3),
    /// Cubes of edge `scale` (scene units) alternating between `even` and `odd` through space.
    Checker(Checker),
    /// Squares alternating in UV: `scale` of them across u in [0, 1] and as many across v.
    UvChecker(Checker),
    /// An image across u and v in [0, 1] (u along its rows, v up its columns), repeating.
    Image(Arc<Image>),
}

#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Checker {
    #[serde(with = "checked::number")]
    pub scale: f32,
    #[serde(with = "checked::albedo")]
    pub even: Vec3,
    #[serde(with = "checked::albedo")]
    pub odd: Vec3,
    /// Added to (camera-relative) hit points before the solid pattern is looked up: the flat
    /// scene's origin modulo two cells, so the pattern stays where the world puts it (exact in
    /// f64, and small enough for f32 whatever the origin). Not part of the syntax.
    #[serde(skip)]
    pub shift: Vec3,
}

impl From<Vec3> for Texture {
    fn from(c: Vec3) -> Self {
        Texture::Colour(c)
    }
}

/// Largest checker scale accepted (the scene's extent).
pub const MAX_SCALE: f32 = crate::placement::MAX_EXTENT;

impl Texture {
    /// Its parameter ranges (the colours are checked as they are read).
    pub fn validate(&self) -> Result<(), String> {
        match self {
            Texture::Colour(_) | Texture::Image(_) => Ok(()),
            Texture::Checker(c) | Texture::UvChecker(c) => {
                if !(c.scale > 0.0 && c.scale <= MAX_SCALE) {
                    return Err(format!(
                        "checker scale must be in (0, {MAX_SCALE:e}], got {}",
                        c.scale
                    ));
                }
                Ok(())
            }
        }
    }

    /// [`Texture::validate`], and every value within [0, 1], as a reflectance must be.
    pub fn validate_albedo(&self) -> Result<(), String> {
        if let Texture::Image(image) = self
            && image.max_value() > 1.0
        {
            return Err(format!(
                "image {} has values up to {}: an albedo must lie in [0, 1]",
                image.source,
                image.max_value()
            ));
        }
        self.validate()
    }

    /// Its mean value over its surface coordinates (for checkers, of its two colours): what
    /// light picking weighs a textured emitter by.
    pub fn mean(&self) -> Vec3 {
        match self {
            Texture::Colour(c) => *c,
            Texture::Checker(c) | Texture::UvChecker(c) => 0.5 * (c.even + c.odd),
            Texture::Image(image) => image.mean(),
        }
    }

    /// The kernel feature its evaluation needs, if any.
    pub fn feature(&self) -> Option<MaterialFeature> {
        match self {
            Texture::Colour(_) => None,
            Texture::Checker(_) => Some(MaterialFeature::Checker),
            Texture::UvChecker(_) => Some(MaterialFeature::UvChecker),
            Texture::Image(_) => Some(MaterialFeature::ImageTexture),
        }
    }

    /// This texture for a flat scene whose coordinates are relative to `origin`.
    pub fn relocated(self, origin: DVec3) -> Self {
        match self {
            Texture::Checker(c) => {
                let period = 2.0 * c.scale as f64;
                let shift = DVec3::new(
                    origin.x.rem_euclid(period),
                    origin.y.rem_euclid(period),
                    origin.z.rem_euclid(period),
                );
                Texture::Checker(Checker {
                    shift: shift.as_vec3(),
                    ..c
                })
            }
            other => other,
        }
    }
}

impl<'de> Deserialize<'de> for Texture {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(TextureVisitor { radiance: false })
    }
}

/// A light's radiance: a [`Texture`] whose plain colour may exceed 1 (any non-negative).
pub mod radiance {
    use super::*;
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Texture, D::Error> {
        d.deserialize_any(TextureVisitor { radiance: true })
    }
    pub fn serialize<S: Serializer>(t: &Texture, s: S) -> Result<S::Ok, S::Error> {
        match t {
            Texture::Colour(c) => checked::colour::serialize(c, s),
            other => other.serialize(s),
        }
    }
}

const EXPECTED: &str = "a colour [r, g, b], { checker = { scale, even, odd } }, \
    { uv_checker = { scale, even, odd } } or { image = \"file\" }";

/// Reads a texture; `radiance`: a plain colour is any non-negative one, not a reflectance.
struct TextureVisitor {
    radiance: bool,
}

impl<'de> Visitor<'de> for TextureVisitor {
    type Value = Texture;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(EXPECTED)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Texture, A::Error> {
        let colour = de::value::SeqAccessDeserializer::new(seq);
        if self.radiance {
            checked::colour::deserialize(colour).map(Texture::Colour)
        } else {
            checked::albedo::deserialize(colour).map(Texture::Colour)
        }
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Texture, A::Error> {
        let key: String = map.next_key()?.ok_or_else(|| {
            de::Error::custom("empty texture: expected checker, uv_checker or image")
        })?;
        let texture = match key.as_str() {
            "checker" => Texture::Checker(map.next_value()?),
            "uv_checker" => Texture::UvChecker(map.next_value()?),
            "image" => {
                let source: String = map.next_value()?;
                Texture::Image(crate::assets::loader::image(&source).map_err(de::Error::custom)?)
            }
            other => {
                return Err(de::Error::unknown_field(
                    other,
                    &["checker", "uv_checker", "image"],
                ));
            }
        };
        if let Some(extra) = map.next_key::<String>()? {
            return Err(de::Error::custom(format!(
                "a texture is one of checker, uv_checker or image, found `{extra}` too"
            )));
        }
        Ok(texture)
    }
}

impl Serialize for Texture {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        match self {
            Texture::Colour(c) => checked::albedo::serialize(c, s),
            Texture::Image(image) => {
                let mut map = s.serialize_map(Some(1))?;
                map.serialize_entry("image", &image.source)?;
                map.end()
            }
            Texture::Checker(c) | Texture::UvChecker(c) => {
                let key = if matches!(self, Texture::Checker(_)) {
                    "checker"
                } else {
                    "uv_checker"
                };
                let mut map = s.serialize_map(Some(1))?;
                map.serialize_entry(key, c)?;
                map.end()
            }
        }
    }
}
