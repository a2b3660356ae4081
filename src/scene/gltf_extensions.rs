//! glTF's material extensions beyond the metallic-roughness core that the `gltf` crate does not
//! parse (KHR_materials_clearcoat, KHR_materials_sheen, KHR_materials_specular), read from a
//! material's extension JSON with the specification's defaults, their textures (the clear
//! coat's factor and roughness, the sheen's colour and roughness, the specular's factor and
//! colour), and what of them is not rendered (for the file's note).

use super::gltf_textures::FileTextures;
use crate::material::clearcoat::Clearcoat;
use crate::material::pbr::ParameterImages;
use crate::material::sheen::Sheen;
use crate::material::specular::Specular;
use serde_json::Value;

pub const CLEARCOAT: &str = "KHR_materials_clearcoat";
pub const SHEEN: &str = "KHR_materials_sheen";
pub const SPECULAR: &str = "KHR_materials_specular";
/// Read through the `gltf` crate (`Material::volume`), whose validation nonetheless refuses it
/// as required.
pub const VOLUME: &str = "KHR_materials_volume";

/// The textures of `m`'s clear coat, sheen and specular that can change how it looks, by
/// property name with their JSON texture info: the coat's where its factor is above 0, the
/// sheen's where its colour is not black, the specular's where its factor is above 0 (a
/// texture scales its factor, and scales 0 to 0). rt-gpu maps these point by point
/// (`layer_images`); the others are not read, nor checked.
pub fn live_textures<'a>(m: &'a gltf::Material<'a>) -> Vec<(&'static str, &'a Value)> {
    let mut out = Vec::new();
    if let Some(ext) = m.extension_value(CLEARCOAT).filter(|ext| coats(ext)) {
        for slot in [
            "clearcoatTexture",
            "clearcoatRoughnessTexture",
            "clearcoatNormalTexture",
        ] {
            out.extend(ext.get(slot).map(|info| (slot, info)));
        }
    }
    if let Some(ext) = m.extension_value(SHEEN).filter(|ext| sheens(ext)) {
        for slot in ["sheenColorTexture", "sheenRoughnessTexture"] {
            out.extend(ext.get(slot).map(|info| (slot, info)));
        }
    }
    if let Some(ext) = m.extension_value(SPECULAR).filter(|ext| reflects(ext)) {
        for slot in SPECULAR_TEXTURES {
            out.extend(ext.get(slot).map(|info| (slot, info)));
        }
    }
    out
}

/// Whether a KHR_materials_specular object lets its textures show: its factor (default 1)
/// above 0 (its colour texture scales a colour that black would leave black, and white is
/// the default colour, so only the factor is asked).
fn reflects(ext: &Value) -> bool {
    ext.get("specularFactor")
        .map_or(Some(1.0), Value::as_f64)
        .is_some_and(|f| f > 0.0)
}

/// Whether a KHR_materials_clearcoat object lays a coat: its factor (default 0) above 0.
fn coats(ext: &Value) -> bool {
    ext.get("clearcoatFactor")
        .and_then(Value::as_f64)
        .is_some_and(|f| f > 0.0)
}

/// Whether a KHR_materials_sheen object lays a sheen: its colour (default black) not black.
fn sheens(ext: &Value) -> bool {
    let colour = ext.get("sheenColorFactor").and_then(Value::as_array);
    colour.is_some_and(|c| c.iter().any(|x| x.as_f64().is_some_and(|x| x > 0.0)))
}

/// The textures of KHR_materials_specular: the factor's (its alpha channel) and the colour's.
const SPECULAR_TEXTURES: [&str; 2] = ["specularTexture", "specularColorTexture"];

/// A number field of extension `name`'s object: its default where absent, an error naming it
/// where it is not a number in [0, 1].
fn unit_factor(
    (name, ext): (&str, &Value),
    field: &str,
    default: f32,
    at: &dyn Fn() -> String,
) -> Result<f32, String> {
    match ext.get(field) {
        None => Ok(default),
        Some(v) => match v.as_f64() {
            Some(x) if (0.0..=1.0).contains(&x) => Ok(x as f32),
            _ => Err(format!(
                "{}: its {name}.{field} is {v}; glTF requires a number in [0, 1]",
                at()
            )),
        },
    }
}

/// A colour field of extension `name`'s object (three numbers in [0, 1]): its default where
/// absent, an error naming it otherwise.
fn unit_colour(
    (name, ext): (&str, &Value),
    field: &str,
    default: [f32; 3],
    at: &dyn Fn() -> String,
) -> Result<[f32; 3], String> {
    let Some(v) = ext.get(field) else {
        return Ok(default);
    };
    let numbers: Option<Vec<f64>> = v
        .as_array()
        .and_then(|a| a.iter().map(Value::as_f64).collect());
    match numbers.as_deref() {
        Some(&[r, g, b]) if [r, g, b].iter().all(|x| (0.0..=1.0).contains(x)) => {
            Ok([r as f32, g as f32, b as f32])
        }
        _ => Err(format!(
            "{}: its {name}.{field} is {v}; glTF requires three numbers in [0, 1]",
            at()
        )),
    }
}

/// The object of extension `name` on `m`, if it has one; an error if it is not an object.
fn extension<'a>(
    m: &'a gltf::Material,
    name: &str,
    at: &dyn Fn() -> String,
) -> Result<Option<&'a Value>, String> {
    match m.extension_value(name) {
        None => Ok(None),
        Some(ext) if ext.is_object() => Ok(Some(ext)),
        Some(_) => Err(format!("{}: its {name} is not an object", at())),
    }
}

/// `m`'s sheen (KHR_materials_sheen's sheenColorFactor, default black, and
/// sheenRoughnessFactor, default 0; their textures scale them point by point: `layer_images`),
/// `None` where it has none or its colour is black.
pub fn sheen(m: &gltf::Material, at: &dyn Fn() -> String) -> Result<Option<Sheen>, String> {
    let Some(ext) = extension(m, SHEEN, at)? else {
        return Ok(None);
    };
    let color =
        glam::Vec3::from_array(unit_colour((SHEEN, ext), "sheenColorFactor", [0.0; 3], at)?);
    let roughness = unit_factor((SHEEN, ext), "sheenRoughnessFactor", 0.0, at)?;
    Ok((color.max_element() > 0.0).then_some(Sheen { color, roughness }))
}

/// `m`'s layer images (`Pbr::with_layer_images`, `Pbr::with_specular_images`) from its
/// [`live_textures`]: its clearcoatTexture (red channel), clearcoatRoughnessTexture (green) and
/// sheenRoughnessTexture (alpha) in one image, its sheenColorTexture (sRGB), its
/// specularTexture's alpha channel and its specularColorTexture (sRGB), and its
/// clearcoatNormalTexture (linear, with its scale); `name` names the material in errors.
pub fn layer_images(
    m: &gltf::Material,
    textures: &mut FileTextures,
    name: &str,
) -> Result<ParameterImages, String> {
    let live = live_textures(m);
    let mut texture =
        |slot: &str, srgb: bool, alpha: bool| match live.iter().find(|(s, _)| *s == slot) {
            Some((_, info)) => textures.extension_texture(info, srgb, alpha, name, slot),
            None => Ok(None),
        };
    let coat = texture("clearcoatTexture", false, false)?;
    let coat_roughness = texture("clearcoatRoughnessTexture", false, false)?;
    let sheen_roughness = texture("sheenRoughnessTexture", false, true)?;
    let sheen_colour = texture("sheenColorTexture", true, false)?;
    let specular = texture("specularTexture", false, true)?;
    let specular_color = texture("specularColorTexture", true, false)?;
    let coat_normal = match texture("clearcoatNormalTexture", false, false)? {
        None => None,
        Some(image) => {
            // A normalTextureInfo's scale (default 1).
            let info = live.iter().find(|(s, _)| *s == "clearcoatNormalTexture");
            let scale = match info.and_then(|(_, info)| info.get("scale")) {
                None => 1.0,
                Some(v) => match v.as_f64() {
                    Some(x) if x.is_finite() && x.abs() <= f32::MAX as f64 => x as f32,
                    _ => {
                        return Err(format!(
                            "mesh {}: material \"{name}\": its {CLEARCOAT}.clearcoatNormalTexture's scale is {v}; glTF requires a number",
                            textures.source
                        ));
                    }
                },
            };
            Some(crate::assets::normal_map::NormalMap { image, scale })
        }
    };
    let layers = textures.layers([coat, coat_roughness, sheen_roughness], name)?;
    Ok(ParameterImages {
        metallic_roughness: None,
        layers,
        sheen: sheen_colour,
        specular,
        specular_color,
        clearcoat_normal_map: coat_normal,
    })
}

/// `m`'s specular strength and colour (KHR_materials_specular's specularFactor, default 1, in
/// [0, 1]; specularColorFactor, default white, any three numbers >= 0), `None` where it has
/// no such extension.
pub fn specular(m: &gltf::Material, at: &dyn Fn() -> String) -> Result<Option<Specular>, String> {
    let Some(ext) = extension(m, SPECULAR, at)? else {
        return Ok(None);
    };
    let factor = unit_factor((SPECULAR, ext), "specularFactor", 1.0, at)?;
    let color = match ext.get("specularColorFactor") {
        None => glam::Vec3::ONE,
        Some(v) => {
            let numbers: Option<Vec<f64>> = v
                .as_array()
                .and_then(|a| a.iter().map(Value::as_f64).collect());
            match numbers.as_deref() {
                Some(&[r, g, b])
                    if [r, g, b].iter().all(|x| *x >= 0.0 && *x <= f32::MAX as f64) =>
                {
                    glam::Vec3::new(r as f32, g as f32, b as f32)
                }
                _ => {
                    return Err(format!(
                        "{}: its {SPECULAR}.specularColorFactor is {v}; glTF requires three finite numbers >= 0",
                        at()
                    ));
                }
            }
        }
    };
    Ok(Some(Specular { factor, color }))
}

/// `m`'s clear coat (KHR_materials_clearcoat's clearcoatFactor and clearcoatRoughnessFactor,
/// defaults 0), `None` where it has none or its factor is 0. `at` names the material in
/// errors.
pub fn clearcoat(m: &gltf::Material, at: &dyn Fn() -> String) -> Result<Option<Clearcoat>, String> {
    let Some(ext) = extension(m, CLEARCOAT, at)? else {
        return Ok(None);
    };
    let factor = unit_factor((CLEARCOAT, ext), "clearcoatFactor", 0.0, at)?;
    let roughness = unit_factor((CLEARCOAT, ext), "clearcoatRoughnessFactor", 0.0, at)?;
    Ok((factor > 0.0).then_some(Clearcoat { factor, roughness }))
}

/// What the file's materials ask of the extensions above that rt-gpu does not render, for its
/// note: sheens smoother than rt-gpu's least roughness.
pub fn unread(document: &gltf::Document) -> Vec<String> {
    let mut out = Vec::new();
    // Only sheens that are there: glTF's default colour, black, is none.
    let sheened: Vec<Value> = document
        .materials()
        .filter_map(|m| m.extension_value(SHEEN).cloned())
        .filter(sheens)
        .collect();
    let least = crate::material::sheen::MIN_ROUGHNESS as f64;
    let smooth = (sheened.iter())
        .filter(|ext| {
            ext.get("sheenRoughnessFactor")
                .and_then(Value::as_f64)
                .unwrap_or(0.0)
                < least
        })
        .count();
    if smooth > 0 {
        out.push(format!(
            "{SHEEN}.sheenRoughnessFactor below {least} ({smooth} material{}: taken as {least})",
            plural(smooth)
        ));
    }
    out
}

fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}
