//! Normal maps: an image of tangent-space normals that bends a mesh's shading normal, as glTF's
//! `normalTexture` and Blender's Normal Map node (tangent space) define it. Plain data, and with
//! serde its scene-file syntax `normal_map = { image = "file.png", scale = 1.0 }` on the
//! materials that take one. Applied where a hit is completed (`cpu::intersect::normal_mapped`, twin
//! `shaders/normal_map.wgsl`), with MikkTSpace tangents (`scene::tangents`).

use crate::assets::image::Image;
use crate::params::checked;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Texels hold (x, y, z) of the normal in the tangent frame as `2 * value - 1` (linear 8- or
/// 16-bit values: OpenGL's convention, green toward +v, as glTF and Blender write them); `scale`
/// multiplies x and y (glTF's `normalTexture.scale`).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "NormalMapDoc", into = "NormalMapDoc")]
pub struct NormalMap {
    pub image: Arc<Image>,
    pub scale: f32,
}

/// Largest |scale| accepted: beyond it a map's x and y swamp z everywhere.
pub const MAX_SCALE: f32 = 100.0;

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct NormalMapDoc {
    image: String,
    #[serde(default = "one", with = "checked::number")]
    scale: f32,
}

fn one() -> f32 {
    1.0
}

impl TryFrom<NormalMapDoc> for NormalMap {
    type Error = String;
    fn try_from(d: NormalMapDoc) -> Result<Self, String> {
        let image = crate::assets::loader::data_image(&d.image)?;
        let map = NormalMap {
            image,
            scale: d.scale,
        };
        map.validate()?;
        Ok(map)
    }
}

impl From<NormalMap> for NormalMapDoc {
    fn from(m: NormalMap) -> Self {
        NormalMapDoc {
            image: m.image.source.clone(),
            scale: m.scale,
        }
    }
}

impl NormalMap {
    pub fn validate(&self) -> Result<(), String> {
        if !(self.scale.abs() <= MAX_SCALE) {
            return Err(format!(
                "normal map scale must be within [-{MAX_SCALE}, {MAX_SCALE}], got {}",
                self.scale
            ));
        }
        if self.image.max_value() > 1.0 {
            return Err(format!(
                "normal map {} has values up to {}: a normal map's values lie in [0, 1]",
                self.image.source,
                self.image.max_value()
            ));
        }
        Ok(())
    }
}
