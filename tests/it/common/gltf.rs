//! The glTF files the loader's tests write: one triangle, its buffer beside it, and whatever
//! material, nodes and top-level members a test adds (cameras, lights, textures, images); or
//! any document a test builds, its one buffer written beside it.

use std::path::{Path, PathBuf};

/// Writes the glTF file `name` in `dir`, with its buffer `tri.bin`: one triangle at z = 0 with
/// corners (-1, -1), (1, -1), (0, 1) (accessor 0), and TEXCOORD_0 (0, 1), (1, 1), (0.5, 0)
/// (accessor 1; glTF's v runs down the image), which the primitive reads where `uvs`. Its
/// material is `material` (material 0; none if empty); `nodes` follow the mesh's node (node 0),
/// each a root of the scene; `extra` adds top-level members.
pub fn write_triangle(
    dir: &Path,
    name: &str,
    uvs: bool,
    material: &str,
    nodes: &str,
    extra: &str,
) -> PathBuf {
    let mut bin: Vec<u8> = Vec::new();
    for x in [-1.0f32, -1.0, 0.0, 1.0, -1.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend(x.to_le_bytes());
    }
    for x in [0.0f32, 1.0, 1.0, 1.0, 0.5, 0.0] {
        bin.extend(x.to_le_bytes());
    }
    std::fs::write(dir.join("tri.bin"), &bin).expect("writes");
    let texcoord = if uvs { r#", "TEXCOORD_0": 1"# } else { "" };
    let (materials, reference) = if material.is_empty() {
        (String::new(), "")
    } else {
        (
            format!(r#""materials": [{material}],"#),
            r#", "material": 0"#,
        )
    };
    let (comma, roots) = if nodes.is_empty() {
        ("", "")
    } else {
        (",", ", 1")
    };
    let json = format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "buffers": [{{ "uri": "tri.bin", "byteLength": 60 }}],
  "bufferViews": [{{ "buffer": 0, "byteOffset": 0, "byteLength": 36 }}, {{ "buffer": 0, "byteOffset": 36, "byteLength": 24 }}],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0] }},
    {{ "bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2" }}
  ],
  {materials}
  {extra}
  "meshes": [{{ "primitives": [{{ "attributes": {{ "POSITION": 0{texcoord} }}{reference} }}] }}],
  "nodes": [{{ "name": "Triangle", "mesh": 0 }}{comma}{nodes}],
  "scenes": [{{ "nodes": [0{roots}] }}],
  "scene": 0
}}"#
    );
    let path = dir.join(name);
    std::fs::write(&path, json).expect("writes");
    path
}

/// `doc` (its nodes, meshes, views, accessors and anything else) written as `name`.gltf in
/// `dir`, with its asset version, its one buffer `bin` as `name`.bin beside it, and node 0 its
/// scene unless `doc` names its scenes.
pub fn write_document(dir: &Path, name: &str, mut doc: serde_json::Value, bin: &[u8]) -> PathBuf {
    std::fs::write(dir.join(format!("{name}.bin")), bin).expect("writes");
    doc["asset"] = serde_json::json!({ "version": "2.0" });
    doc["scene"] = 0.into();
    if doc.get("scenes").is_none() {
        doc["scenes"] = serde_json::json!([{ "nodes": [0] }]);
    }
    doc["buffers"] = serde_json::json!([{ "byteLength": bin.len(), "uri": format!("{name}.bin") }]);
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, doc.to_string()).expect("writes");
    path
}
