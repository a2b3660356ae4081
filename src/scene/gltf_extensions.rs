//! glTF's material extensions beyond the metallic-roughness core that the `gltf` crate does not
//! parse (KHR_materials_clearcoat), read from a material's extension JSON with the
//! specification's defaults, and what of them is not rendered (for the file's note).

use crate::material::clearcoat::Clearcoat;
use serde_json::Value;

pub const CLEARCOAT: &str = "KHR_materials_clearcoat";
/// Read through the `gltf` crate (`Material::volume`), whose validation nonetheless refuses it
/// as required.
pub const VOLUME: &str = "KHR_materials_volume";

/// The textures of KHR_materials_clearcoat, none of which is read yet.
const CLEARCOAT_TEXTURES: [&str; 3] = [
    "clearcoatTexture",
    "clearcoatRoughnessTexture",
    "clearcoatNormalTexture",
];

/// A number field of an extension object: its default where absent, an error naming it where
/// it is not a number in [0, 1].
fn unit_factor(
    ext: &Value,
    field: &str,
    default: f32,
    at: &dyn Fn() -> String,
) -> Result<f32, String> {
    match ext.get(field) {
        None => Ok(default),
        Some(v) => match v.as_f64() {
            Some(x) if (0.0..=1.0).contains(&x) => Ok(x as f32),
            _ => Err(format!(
                "{}: its {CLEARCOAT}.{field} is {v}; glTF requires a number in [0, 1]",
                at()
            )),
        },
    }
}

/// `m`'s clear coat (KHR_materials_clearcoat's clearcoatFactor and clearcoatRoughnessFactor,
/// defaults 0), `None` where it has none or its factor is 0. `at` names the material in
/// errors.
pub fn clearcoat(m: &gltf::Material, at: &dyn Fn() -> String) -> Result<Option<Clearcoat>, String> {
    let Some(ext) = m.extension_value(CLEARCOAT) else {
        return Ok(None);
    };
    if !ext.is_object() {
        return Err(format!("{}: its {CLEARCOAT} is not an object", at()));
    }
    let factor = unit_factor(ext, "clearcoatFactor", 0.0, at)?;
    let roughness = unit_factor(ext, "clearcoatRoughnessFactor", 0.0, at)?;
    Ok((factor > 0.0).then_some(Clearcoat { factor, roughness }))
}

/// What the file's materials ask of the extensions above that rt-gpu does not render, for its
/// note: the clear coat's textures, and a coat over a normal-mapped base (glTF draws such a
/// coat unmapped; here it follows the base's normal map).
pub fn unread(document: &gltf::Document) -> Vec<String> {
    let coated: Vec<(bool, Value)> = document
        .materials()
        .filter_map(|m| {
            let ext = m.extension_value(CLEARCOAT)?;
            let factor = ext
                .get("clearcoatFactor")
                .and_then(Value::as_f64)
                .unwrap_or(0.0);
            (factor > 0.0).then(|| (m.normal_texture().is_some(), ext.clone()))
        })
        .collect();
    let mut out = Vec::new();
    for texture in CLEARCOAT_TEXTURES {
        let n = coated
            .iter()
            .filter(|(_, ext)| ext.get(texture).is_some())
            .count();
        if n > 0 {
            out.push(format!("{CLEARCOAT}.{texture} ({n} material{})", plural(n)));
        }
    }
    let mapped = coated.iter().filter(|(mapped, _)| *mapped).count();
    if mapped > 0 {
        out.push(format!(
            "a clear coat without its base's normal map ({mapped} material{}: the coat follows it)",
            plural(mapped)
        ));
    }
    out
}

fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}
