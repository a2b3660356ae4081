//! A structure-aware mutator of glTF JSON (issue 61): rather than flipping bytes, it edits the
//! document's tree where the loaders have broken before: accessors' counts, views, types and
//! sparse blocks; buffer views' strides, offsets and lengths; buffer and image URIs (devices,
//! `..`, percent-encoding, data URIs); nodes' graphs and transforms; primitive modes; materials'
//! factors and extensions (ior, emissive strength, transmission, texture transforms); punctual
//! lights and cameras at the edges of what the specification allows; morph targets, skins and
//! animations. Shared by
//! tests/it/fuzz_mesh_files.rs (stable, seeded) and fuzz/fuzz_targets/gltf_structure.rs
//! (libFuzzer), which include it by path.

use serde_json::{Value, json};

/// A source of choices: the stable fuzzer's SplitMix64, or libFuzzer's bytes.
pub trait Choices {
    /// A number in 0..n (0 when n is 0).
    fn below(&mut self, n: usize) -> usize;
}

fn pick<'a, T>(c: &mut impl Choices, from: &'a [T]) -> &'a T {
    &from[c.below(from.len())]
}

/// Numbers at the edges of what a field may hold.
const EDGE_NUMBERS: &[f64] = &[
    0.0, -0.0, 1.0, -1.0, 0.5, 2.0, 1e-30, -1e-30, 1.0000001, 0.9999999, 4.0, 10.0, 1e6, 1e30,
    3e38, -3e38, 1e39, 4e9,
];
/// Counts and offsets at the edges (3e9 and 3e8 once aborted and exhausted memory).
const EDGE_COUNTS: &[u64] = &[
    0,
    1,
    2,
    3,
    4,
    255,
    65_536,
    300_000_000,
    3_000_000_000,
    4_294_967_295,
    4_294_967_296,
    9_007_199_254_740_991,
];
const URIS: &[&str] = &[
    "lamp.bin",
    "lamp%2Ebin",
    "lamp%2ebin",
    "%6Camp.bin",
    "../lamp.bin",
    "./lamp.bin",
    "sub/../lamp.bin",
    "/dev/zero",
    "/etc/passwd",
    "file:///dev/zero",
    "file:lamp.bin",
    "http://example.com/lamp.bin",
    "data:application/octet-stream;base64,AAAA",
    "data:application/octet-stream;base64,!!!!",
    "data:image/png;base64,iVBORw0KGgo=",
    "data:,plain",
    "fifo.bin",
    "missing.bin",
    "%ff.bin",
    "",
    "a\nb.bin",
];
const EXTENSIONS: &[&str] = &[
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_emissive_strength",
    "KHR_lights_punctual",
    "KHR_texture_transform",
    "KHR_materials_unlit",
    "KHR_draco_mesh_compression",
    "EXT_mesh_gpu_instancing",
    "KHR_mesh_quantization",
];

fn number(c: &mut impl Choices) -> Value {
    json!(*pick(c, EDGE_NUMBERS))
}

fn count(c: &mut impl Choices) -> Value {
    json!(*pick(c, EDGE_COUNTS))
}

/// An index into an array of `len` (or just past it, or far out).
fn index(c: &mut impl Choices, len: usize) -> Value {
    match c.below(6) {
        0 => json!(len),
        1 => json!(4_294_967_295u64),
        _ => json!(c.below(len.max(1))),
    }
}

fn array_len(doc: &Value, key: &str) -> usize {
    doc.get(key).and_then(Value::as_array).map_or(0, Vec::len)
}

/// An element of the array `key`, to edit (`None` if there is none).
fn element<'a>(doc: &'a mut Value, key: &str, c: &mut impl Choices) -> Option<&'a mut Value> {
    let array = doc.get_mut(key)?.as_array_mut()?;
    if array.is_empty() {
        return None;
    }
    let i = c.below(array.len());
    // Only objects are edited (libFuzzer's byte mutations may leave anything there).
    array.get_mut(i).filter(|v| v.is_object())
}

/// `v[key]` (`v` an object), made an object if it is not one.
fn object_at<'a>(v: &'a mut Value, key: &str) -> &'a mut Value {
    if !v[key].is_object() {
        v[key] = json!({});
    }
    &mut v[key]
}

fn vec_of(c: &mut impl Choices, n: usize) -> Value {
    Value::Array((0..n).map(|_| number(c)).collect())
}

/// `doc` with one to four structural mutations.
pub fn mutate(doc: &mut Value, c: &mut impl Choices) {
    if !doc.is_object() {
        return;
    }
    for _ in 0..1 + c.below(4) {
        mutate_once(doc, c);
    }
}

fn mutate_once(doc: &mut Value, c: &mut impl Choices) {
    let views = array_len(doc, "bufferViews");
    let accessors = array_len(doc, "accessors");
    let nodes = array_len(doc, "nodes");
    let materials = array_len(doc, "materials");
    match c.below(13) {
        // Accessors: counts, views, types, sparse blocks.
        0 => {
            let kind = c.below(7);
            let (ty, component) = (
                *pick(c, &["SCALAR", "VEC2", "VEC3", "VEC4", "MAT4"]),
                *pick(c, &[5120, 5121, 5122, 5123, 5125, 5126]),
            );
            let (view, sparse_count) = (index(c, views), count(c));
            let (indices_view, values_view) = (index(c, views), index(c, views));
            let (offset, sparse_offset) = (count(c), count(c));
            let new_count = count(c);
            let Some(a) = element(doc, "accessors", c) else {
                return;
            };
            match kind {
                0 => a["count"] = new_count,
                1 => {
                    if let Some(o) = a.as_object_mut() {
                        o.remove("bufferView");
                    }
                }
                2 => a["bufferView"] = view,
                3 => a["byteOffset"] = offset,
                4 => {
                    a["type"] = json!(ty);
                    a["componentType"] = json!(component);
                }
                5 => a["normalized"] = json!(true),
                _ => {
                    a["sparse"] = json!({
                        "count": sparse_count,
                        "indices": { "bufferView": indices_view, "byteOffset": sparse_offset, "componentType": component },
                        "values": { "bufferView": values_view }
                    })
                }
            }
        }
        // Buffer views: strides, offsets, lengths, buffers.
        1 => {
            let kind = c.below(4);
            let stride = *pick(c, &[0u64, 1, 3, 4, 8, 252, 256]);
            let (offset, length) = (count(c), count(c));
            let buffer = index(c, 1);
            let Some(v) = element(doc, "bufferViews", c) else {
                return;
            };
            match kind {
                0 => v["byteStride"] = json!(stride),
                1 => v["byteOffset"] = offset,
                2 => v["byteLength"] = length,
                _ => v["buffer"] = buffer,
            }
        }
        // Buffers: URIs and lengths.
        2 => {
            let uri = *pick(c, URIS);
            let length = count(c);
            let kind = c.below(3);
            let Some(b) = element(doc, "buffers", c) else {
                return;
            };
            match kind {
                0 => b["uri"] = json!(uri),
                1 => b["byteLength"] = length,
                _ => {
                    if let Some(o) = b.as_object_mut() {
                        o.remove("uri");
                    }
                }
            }
        }
        // Images and textures, and a material that reads them.
        3 => {
            let uri = *pick(c, URIS);
            let image = match c.below(3) {
                0 => json!({ "bufferView": index(c, views), "mimeType": "image/png" }),
                1 => json!({ "uri": uri, "bufferView": index(c, views) }),
                _ => json!({ "uri": uri }),
            };
            doc["images"] = json!([image]);
            doc["textures"] = json!([{ "source": index(c, 1), "sampler": index(c, 1) }]);
            doc["samplers"] = json!([{ "magFilter": *pick(c, &[9728, 9729, 1]), "wrapS": *pick(c, &[33071, 33648, 10497, 7]) }]);
            let slot = *pick(
                c,
                &[
                    "baseColorTexture",
                    "metallicRoughnessTexture",
                    "emissiveTexture",
                    "normalTexture",
                ],
            );
            let info = json!({ "index": index(c, 1), "texCoord": *pick(c, &[0, 0, 1, 7]) });
            if let Some(m) = element(doc, "materials", c) {
                match slot {
                    "emissiveTexture" | "normalTexture" => m[slot] = info,
                    _ => object_at(m, "pbrMetallicRoughness")[slot] = info,
                }
            }
        }
        // Nodes: graphs and transforms.
        4 => {
            let kind = c.below(7);
            let (child, mesh) = (index(c, nodes), index(c, array_len(doc, "meshes")));
            let (translation, scale, rotation) = (vec_of(c, 3), vec_of(c, 3), vec_of(c, 4));
            let matrix = vec_of(c, 16);
            // EXT_mesh_gpu_instancing: some of its attributes, naming any accessor.
            let mut attributes = serde_json::Map::new();
            for name in ["TRANSLATION", "ROTATION", "SCALE"] {
                if c.below(3) > 0 {
                    attributes.insert(name.into(), index(c, accessors));
                }
            }
            let Some(n) = element(doc, "nodes", c) else {
                return;
            };
            match kind {
                0 => n["children"] = json!([child]),
                1 => n["mesh"] = mesh,
                2 => n["translation"] = translation,
                3 => n["scale"] = scale,
                4 => n["rotation"] = rotation,
                5 => n["matrix"] = matrix,
                _ => {
                    object_at(n, "extensions")["EXT_mesh_gpu_instancing"] =
                        json!({ "attributes": attributes })
                }
            }
        }
        // Primitives: modes, attributes, indices, materials.
        5 => {
            let kind = c.below(4);
            let mode = c.below(9);
            let (attribute, accessor) = (
                *pick(
                    c,
                    &[
                        "POSITION",
                        "NORMAL",
                        "TANGENT",
                        "TEXCOORD_0",
                        "TEXCOORD_1",
                        "COLOR_0",
                    ],
                ),
                index(c, accessors),
            );
            let material = index(c, materials);
            let Some(m) = element(doc, "meshes", c) else {
                return;
            };
            let Some(p) = element(m, "primitives", c) else {
                return;
            };
            match kind {
                0 => p["mode"] = json!(mode),
                1 => object_at(p, "attributes")[attribute] = accessor,
                2 => p["indices"] = accessor,
                _ => p["material"] = material,
            }
        }
        // Materials: factors at and past the specification's edges, alpha modes.
        6 => {
            let kind = c.below(7);
            let (x, v3, v4) = (number(c), vec_of(c, 3), vec_of(c, 4));
            let mode = *pick(c, &["OPAQUE", "MASK", "BLEND", "OTHER"]);
            let Some(m) = element(doc, "materials", c) else {
                return;
            };
            match kind {
                0 => object_at(m, "pbrMetallicRoughness")["baseColorFactor"] = v4,
                1 => object_at(m, "pbrMetallicRoughness")["metallicFactor"] = x,
                2 => object_at(m, "pbrMetallicRoughness")["roughnessFactor"] = x,
                3 => m["emissiveFactor"] = v3,
                4 => m["alphaMode"] = json!(mode),
                5 => m["alphaCutoff"] = x,
                _ => m["doubleSided"] = json!(true),
            }
        }
        // Material extensions.
        7 => {
            let kind = c.below(4);
            let (x, offset, scale) = (number(c), vec_of(c, 2), vec_of(c, 2));
            let rotation = number(c);
            let Some(m) = element(doc, "materials", c) else {
                return;
            };
            match kind {
                0 => object_at(m, "extensions")["KHR_materials_ior"] = json!({ "ior": x }),
                1 => {
                    object_at(m, "extensions")["KHR_materials_transmission"] =
                        json!({ "transmissionFactor": x })
                }
                2 => {
                    object_at(m, "extensions")["KHR_materials_emissive_strength"] =
                        json!({ "emissiveStrength": x })
                }
                _ => {
                    let t = json!({ "offset": offset, "scale": scale, "rotation": rotation });
                    let texture =
                        object_at(object_at(m, "pbrMetallicRoughness"), "baseColorTexture");
                    object_at(texture, "extensions")["KHR_texture_transform"] = t;
                }
            }
        }
        // Extensions used and required.
        8 => {
            let name = *pick(c, EXTENSIONS);
            let key = *pick(c, &["extensionsUsed", "extensionsRequired"]);
            doc[key] = json!([name]);
        }
        // Punctual lights, on a node.
        9 => {
            let ty = *pick(c, &["point", "spot", "directional", "area"]);
            let light = json!({
                "name": *pick(c, &["L", "L\nnote: forged", ""]),
                "type": ty,
                "color": vec_of(c, 3),
                "intensity": number(c),
                "range": number(c),
                "spot": { "innerConeAngle": number(c), "outerConeAngle": number(c) }
            });
            object_at(doc, "extensions")["KHR_lights_punctual"] = json!({ "lights": [light] });
            let light_index = index(c, 1);
            if let Some(n) = element(doc, "nodes", c) {
                object_at(n, "extensions")["KHR_lights_punctual"] = json!({ "light": light_index });
            }
        }
        // Cameras, on a node.
        10 => {
            let camera = match c.below(2) {
                0 => json!({ "type": "perspective", "perspective": {
                    "yfov": number(c), "aspectRatio": number(c), "znear": number(c) } }),
                _ => json!({ "type": "orthographic", "orthographic": {
                    "xmag": number(c), "ymag": number(c), "znear": number(c), "zfar": number(c) } }),
            };
            doc["cameras"] = json!([camera]);
            let camera_index = index(c, 1);
            if let Some(n) = element(doc, "nodes", c) {
                n["camera"] = camera_index;
            }
        }
        // The pose (issue 62): morph targets and weights, skins and their joints' influences,
        // an animation's channel.
        11 => {
            let kind = c.below(4);
            let (a, b, d) = (
                index(c, accessors),
                index(c, accessors),
                index(c, accessors),
            );
            let (node, joint) = (index(c, nodes), index(c, nodes));
            let targets = 1 + c.below(3);
            let weights = vec_of(c, targets);
            let path = *pick(c, &["translation", "rotation", "scale", "weights", "other"]);
            let interpolation = *pick(c, &["LINEAR", "STEP", "CUBICSPLINE", "OTHER"]);
            match kind {
                0 => {
                    let Some(m) = element(doc, "meshes", c) else {
                        return;
                    };
                    m["weights"] = weights;
                    if let Some(p) = element(m, "primitives", c) {
                        p["targets"] = json!([{ "POSITION": a, "NORMAL": b, "TANGENT": d }]);
                    }
                }
                1 => {
                    doc["skins"] = json!([{ "joints": [node, joint], "inverseBindMatrices": a }]);
                    if let Some(n) = element(doc, "nodes", c) {
                        n["skin"] = json!(0);
                    }
                    if let Some(m) = element(doc, "meshes", c)
                        && let Some(p) = element(m, "primitives", c)
                    {
                        object_at(p, "attributes")["JOINTS_0"] = b;
                        object_at(p, "attributes")["WEIGHTS_0"] = d;
                    }
                }
                2 => {
                    if let Some(n) = element(doc, "nodes", c) {
                        n["weights"] = weights;
                    }
                }
                _ => {
                    doc["animations"] = json!([{
                        "samplers": [{ "input": a, "output": b, "interpolation": interpolation }],
                        "channels": [{ "sampler": 0, "target": { "node": node, "path": path } }]
                    }]);
                }
            }
        }
        // The scene's roots.
        _ => {
            let root = index(c, nodes);
            doc["scenes"] = json!([{ "nodes": [root] }]);
            doc["scene"] = index(c, 1);
        }
    }
}
