//! The kernel's side of the shape registry (`crate::shape`): for the shapes a kernel holds,
//! each one's array binding and WGSL twin, and the functions that pass a primitive to its
//! shape's twin by kind (`consider_shape`, `shape_surface`, `shape_hit_uv`, `shape_light_of`,
//! and with nee `shape_light_sample` and `shape_light_pdf`). Each is a chain of assignments
//! under `if`, not early returns: under divergent control flow lavapipe runs returns with a
//! mask, a cost in every lane.

use super::bindings::shape_binding;
use super::shader::{Features, preprocess};
use crate::shape::{KINDS, ShapeKind};

/// The shapes' part of the kernel composed with `features`.
pub fn wgsl(features: &Features) -> Result<String, String> {
    let held: Vec<(usize, &ShapeKind)> = (KINDS.iter().enumerate())
        .filter(|(_, k)| features.has_shape(k))
        .collect();
    let mut out = String::from("\n// ---- the shapes' arrays and twins, generated ----\n");
    for &(position, kind) in &held {
        out.push_str(&array_declaration(position, kind, features));
    }
    for &(_, kind) in &held {
        let name = format!("shapes/{}.wgsl", kind.name);
        out.push_str(&format!("\n// ---- {name} ----\n"));
        out.push_str(&preprocess(kind.wgsl, &name, features)?);
    }
    let kinds: Vec<&ShapeKind> = held.iter().map(|(_, k)| *k).collect();
    out.push_str("\n// ---- the shape interface, generated ----\n");
    out.push_str(&dispatch_functions(&kinds, features));
    Ok(out)
}

/// The array of shapes of `kind` (at `position` in `KINDS`), uniform or storage as the scene's
/// other arrays.
fn array_declaration(position: usize, kind: &ShapeKind, features: &Features) -> String {
    let binding = shape_binding(position);
    let (array, element) = (kind.array, kind.wgsl_struct);
    if features.uniform_scene {
        format!(
            "@group(0) @binding({binding}) var<uniform> {array}: array<{element}, SCENE_CAPACITY>;\n"
        )
    } else {
        format!("@group(0) @binding({binding}) var<storage, read> {array}: array<{element}>;\n")
    }
}

/// The functions that dispatch on a primitive's kind to the twins of the shapes `held`.
fn dispatch_functions(held: &[&ShapeKind], features: &Features) -> String {
    let mut out = function(
        "consider_shape(kind: u32, index: u32, ray: Ray, c: ptr<function, Closest>)",
        "",
        &by_kind(held, "kind", |k| {
            format!(
                "consider_{}({}[index], index, ray, false, c)",
                k.name, k.array
            )
        }),
        "",
    );
    // The last kind held is the default, unconditionally (another primitive's surface replaces
    // it): a scene of one kind then completes its hits without a branch.
    let surface = |k: &ShapeKind| format!("{}_surface(c, along_ray, n)", k.name);
    let assign_surface = |k: &ShapeKind| assign(surface(k));
    let (default, others) = match held.split_last() {
        Some((last, others)) => (surface(last), others),
        None => ("Surface(along_ray, 0.0)".to_string(), held),
    };
    out.push_str(&function(
        "shape_surface(c: Closest, along_ray: vec3f, n: vec3f) -> Surface",
        &format!("    let kind = primitive_kind(c.primitive);\n    var out = {default};\n"),
        &by_kind(others, "kind", assign_surface),
        "    return out;\n",
    ));
    let uv = features.reads_uvs();
    let uv_dispatch = by_kind(if uv { held } else { &[] }, "kind", |k| {
        assign(format!("{}_hit_uv(c, point)", k.name))
    });
    out.push_str(&function(
        "shape_hit_uv(c: Closest, point: vec3f) -> vec2f",
        "    let kind = primitive_kind(c.primitive);\n    var out = c.uv;\n",
        &uv_dispatch,
        "    return out;\n",
    ));
    out.push_str(&function(
        "shape_light_of(primitive: u32) -> u32",
        "    let kind = primitive_kind(primitive);\n    let index = primitive_index(primitive);\n    var out = 0u;\n",
        &by_kind(held, "kind", |k| assign(format!("{}[index].light", k.array))),
        "    return out;\n",
    ));
    if features.nee {
        out.push_str(&function(
            "shape_light_sample(l: Light, x: vec3f, u1: f32, u2: f32) -> LightSample",
            "    var out = LightSample(vec3f(0.0, 1.0, 0.0), 0.0, x);\n",
            &by_kind(held, "l.kind", |k| {
                assign(format!("{}_light_sample(l, x, u1, u2)", k.name))
            }),
            "    return out;\n",
        ));
        out.push_str(&function(
            "shape_light_pdf(l: Light, x: vec3f, p: vec3f, dir: vec3f) -> f32",
            "    var out = 0.0;\n",
            &by_kind(held, "l.kind", |k| {
                assign(format!("{}_light_pdf(l, x, p, dir)", k.name))
            }),
            "    return out;\n",
        ));
    }
    out
}

/// `if {selector} == KIND_<NAME> { {statement}; }` for each kind.
fn by_kind(
    kinds: &[&ShapeKind],
    selector: &str,
    statement: impl Fn(&ShapeKind) -> String,
) -> String {
    kinds
        .iter()
        .map(|k| {
            format!(
                "    if {selector} == KIND_{} {{\n        {};\n    }}\n",
                k.name.to_uppercase(),
                statement(k)
            )
        })
        .collect()
}

/// `out = {value}` for [`by_kind`].
fn assign(value: String) -> String {
    format!("out = {value}")
}

/// `fn {signature} { {head}{body}{tail} }`.
fn function(signature: &str, head: &str, body: &str, tail: &str) -> String {
    format!("fn {signature} {{\n{head}{body}{tail}}}\n\n")
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
