//! The kernel's side of the shape registry (`crate::shape`): for the shapes a kernel holds,
//! each one's array binding and WGSL twin, and the functions that pass a primitive to its
//! shape's twin by kind (`consider_shape`, `shape_surface`, `shape_hit_uv`, `shape_light_of`,
//! and with nee `shape_light_sample` and `shape_light_pdf`).

use super::bindings::shape_binding;
use super::shader::{Features, preprocess};
use crate::shape::{KINDS, ShapeKind};

/// The shapes' part of the kernel composed with `features`.
pub fn wgsl(features: &Features) -> Result<String, String> {
    let held: Vec<(usize, &ShapeKind)> = KINDS
        .iter()
        .enumerate()
        .filter(|(_, k)| features.has(k.feature))
        .collect();
    let mut out = String::from("\n// ---- the shapes' arrays and twins, generated ----\n");
    for &(position, kind) in &held {
        let binding = shape_binding(position);
        let (array, element) = (kind.array, kind.wgsl_struct);
        out.push_str(&if features.uniform_scene {
            format!("@group(0) @binding({binding}) var<uniform> {array}: array<{element}, SCENE_CAPACITY>;\n")
        } else {
            format!("@group(0) @binding({binding}) var<storage, read> {array}: array<{element}>;\n")
        });
    }
    for &(_, kind) in &held {
        out.push_str(&format!("\n// ---- shapes/{}.wgsl ----\n", kind.name));
        out.push_str(
            &preprocess(kind.wgsl, features)
                .map_err(|e| format!("shaders/shapes/{}.wgsl: {e}", kind.name))?,
        );
    }
    out.push_str("\n// ---- the shape interface, generated ----\n");
    // Assignments under `if`, not early returns: under divergent control flow lavapipe runs
    // returns with a mask, a cost in every lane.
    let each = |body: &dyn Fn(&ShapeKind) -> String| -> String {
        held.iter().map(|(_, k)| body(k)).collect()
    };
    out.push_str(&format!(
        "fn consider_shape(kind: u32, index: u32, ray: Ray, c: ptr<function, Closest>) {{\n{}}}\n\n",
        each(&|k| format!(
            "    if kind == KIND_{} {{\n        consider_{}({}[index], index, ray, false, c);\n    }}\n",
            k.name.to_uppercase(),
            k.name,
            k.array
        ))
    ));
    let by_kind = |call: &dyn Fn(&ShapeKind) -> String| {
        each(&|k| {
            format!(
                "    if kind == KIND_{} {{\n        out = {};\n    }}\n",
                k.name.to_uppercase(),
                call(k)
            )
        })
    };
    // The last kind held is the default, unconditionally (another primitive's surface replaces
    // it): a scene of one kind then completes its hits without a branch.
    let surface = |k: &ShapeKind| format!("{}_surface(c, along_ray, n)", k.name);
    let (default, others) = match held.split_last() {
        Some(((_, last), others)) => (surface(last), others),
        None => ("Surface(along_ray, 0.0)".to_string(), &held[..0]),
    };
    let others: String = others
        .iter()
        .map(|(_, k)| {
            format!(
                "    if kind == KIND_{} {{\n        out = {};\n    }}\n",
                k.name.to_uppercase(),
                surface(k)
            )
        })
        .collect();
    out.push_str(&format!(
        "fn shape_surface(c: Closest, along_ray: vec3f, n: vec3f) -> Surface {{\n    let kind = primitive_kind(c.primitive);\n    var out = {default};\n{others}    return out;\n}}\n\n"
    ));
    let uv = [
        "UV_CHECKER",
        "IMAGE_TEXTURE",
        "NORMAL_MAPS",
        "METALLIC_ROUGHNESS",
    ];
    let uv_dispatch = if uv.iter().any(|f| features.has(f)) {
        by_kind(&|k| format!("{}_hit_uv(c, point)", k.name))
    } else {
        String::new()
    };
    out.push_str(&format!(
        "fn shape_hit_uv(c: Closest, point: vec3f) -> vec2f {{\n    let kind = primitive_kind(c.primitive);\n    var out = c.uv;\n{uv_dispatch}    return out;\n}}\n\n"
    ));
    out.push_str(&format!(
        "fn shape_light_of(primitive: u32) -> u32 {{\n    let kind = primitive_kind(primitive);\n    let index = primitive_index(primitive);\n    var out = 0u;\n{}    return out;\n}}\n",
        by_kind(&|k| format!("{}[index].light", k.array))
    ));
    if features.nee {
        let by_light_kind = |call: &dyn Fn(&ShapeKind) -> String| {
            by_kind(call).replace("if kind ==", "if l.kind ==")
        };
        out.push_str(&format!(
            "\nfn shape_light_sample(l: Light, x: vec3f, u1: f32, u2: f32) -> LightSample {{\n    var out = LightSample(vec3f(0.0, 1.0, 0.0), 0.0, x);\n{}    return out;\n}}\n",
            by_light_kind(&|k| format!("{}_light_sample(l, x, u1, u2)", k.name))
        ));
        out.push_str(&format!(
            "\nfn shape_light_pdf(l: Light, x: vec3f, p: vec3f, dir: vec3f) -> f32 {{\n    var out = 0.0;\n{}    return out;\n}}\n",
            by_light_kind(&|k| format!("{}_light_pdf(l, x, p, dir)", k.name))
        ));
    }
    Ok(out)
}

/// The shapes' primitive kinds as WGSL constants, `KIND_<NAME>`.
pub fn kind_constants() -> Vec<(String, String)> {
    KINDS
        .iter()
        .map(|k| {
            (
                format!("KIND_{}", k.name.to_uppercase()),
                format!("{}u", k.kind),
            )
        })
        .collect()
}
