//! What a glTF file must be before the `gltf` crate's readers see it: they trust its accessors
//! (and panic, or read the wrong type, or stop early, on ones that lie) and walk its node
//! graph as given (a cycle or a shared child visits meshes without end). Every problem is one
//! line naming the file and the accessor, node or field.

use gltf::json;
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked;
use std::path::Path;

/// Largest buffer file read (a URI may name anything, `/dev/zero` among them).
pub const MAX_BUFFER_BYTES: u64 = 1 << 31;

/// The first bytes of a binary glTF (`.glb`) file.
const GLB_MAGIC: &[u8; 4] = b"glTF";

/// Checks what can be checked before parsing: a `.glb` starts with its magic, and a binary
/// container's header is whole and its length within the file (the crate subtracts the
/// header's size from it unchecked).
pub fn check_container(bytes: &[u8], path: &Path, source: &str) -> Result<(), String> {
    let is_glb = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    if is_glb && !bytes.starts_with(GLB_MAGIC) {
        return Err(format!(
            "cannot read mesh {source}: not a binary glTF file (it does not start with \"glTF\")"
        ));
    }
    if !bytes.starts_with(GLB_MAGIC) {
        return Ok(());
    }
    let word = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
    };
    match (word(4), word(8)) {
        (Some(2), Some(length)) if (12..=bytes.len() as u64).contains(&(length as u64)) => Ok(()),
        (Some(2), Some(length)) => Err(format!(
            "cannot read mesh {source}: its binary glTF header gives a length of {length} bytes, but the file has {}",
            bytes.len()
        )),
        (Some(version), Some(_)) => Err(format!(
            "cannot read mesh {source}: binary glTF version {version}; rt-gpu reads version 2"
        )),
        _ => Err(format!(
            "cannot read mesh {source}: its binary glTF header is cut short"
        )),
    }
}

/// Checks what the `gltf` crate's validation indexes without checking: every primitive's
/// POSITION accessor exists.
pub fn check_references(root: &json::Root, source: &str) -> Result<(), String> {
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive
                .attributes
                .get(&Checked::Valid(json::mesh::Semantic::Positions));
            if let Some(index) = position {
                accessor(
                    root,
                    index.value(),
                    &format!("mesh {source}: mesh {m} primitive {p}"),
                )?;
            }
        }
    }
    Ok(())
}

/// Checks the buffers' sources: files named by URI are regular files no larger than
/// [`MAX_BUFFER_BYTES`] that hold at least `byteLength` bytes.
pub fn check_buffers(root: &json::Root, base: Option<&Path>, source: &str) -> Result<(), String> {
    for (i, buffer) in root.buffers.iter().enumerate() {
        let Some(uri) = &buffer.uri else { continue };
        if uri.starts_with("data:") {
            continue;
        }
        let path = match base {
            Some(dir) => dir.join(uri),
            None => Path::new(uri).to_path_buf(),
        };
        let meta = std::fs::metadata(&path)
            .map_err(|e| format!("mesh {source}: buffer {i} ({uri}): {e}"))?;
        if !meta.is_file() {
            return Err(format!(
                "mesh {source}: buffer {i} ({uri}) is not a regular file"
            ));
        }
        if meta.len() > MAX_BUFFER_BYTES {
            return Err(format!(
                "mesh {source}: buffer {i} ({uri}) is {} bytes, more than the {MAX_BUFFER_BYTES} rt-gpu reads",
                meta.len()
            ));
        }
        if meta.len() < buffer.byte_length.0 {
            return Err(format!(
                "mesh {source}: buffer {i} ({uri}) holds {} bytes, fewer than its byteLength {}",
                meta.len(),
                buffer.byte_length.0
            ));
        }
    }
    Ok(())
}

/// Checks the document: its version, its node graph (trees: no node its own ancestor, none
/// with two parents), node matrices (affine), and every accessor a triangle primitive reads.
/// `buffer_lengths` are the loaded buffers' sizes.
pub fn check_document(
    root: &json::Root,
    buffer_lengths: &[usize],
    source: &str,
) -> Result<(), String> {
    let version = &root.asset.version;
    if version.split('.').next() != Some("2") {
        return Err(format!(
            "mesh {source}: glTF version {version}; rt-gpu reads glTF 2.x"
        ));
    }
    check_nodes(root, source)?;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let at = format!("mesh {source}: mesh {m} primitive {p}");
            let triangles = matches!(primitive.mode, Checked::Valid(json::mesh::Mode::Triangles));
            if !triangles {
                continue;
            }
            let mut position_count = None;
            let mut normal_count = None;
            for (semantic, index) in &primitive.attributes {
                let accessor = accessor(root, index.value(), &at)?;
                let (expected, name) = match semantic {
                    Checked::Valid(json::mesh::Semantic::Positions) => (Type::Vec3, "POSITION"),
                    Checked::Valid(json::mesh::Semantic::Normals) => (Type::Vec3, "NORMAL"),
                    Checked::Valid(json::mesh::Semantic::Tangents) => (Type::Vec4, "TANGENT"),
                    _ => {
                        check_accessor(root, buffer_lengths, index.value(), &at)?;
                        continue;
                    }
                };
                let (ty, component) = kinds(accessor);
                if ty != Some(expected) || component != Some(ComponentType::F32) {
                    let shape = if expected == Type::Vec4 {
                        "VEC4"
                    } else {
                        "VEC3"
                    };
                    return Err(format!(
                        "{at}: {name} (accessor {}) is {}, not {shape} of FLOAT",
                        index.value(),
                        describe(accessor)
                    ));
                }
                let count = check_accessor(root, buffer_lengths, index.value(), &at)?;
                match name {
                    "POSITION" => position_count = Some(count),
                    "NORMAL" => normal_count = Some(count),
                    // Fewer or more than the positions: the loader computes its own.
                    _ => {}
                }
            }
            let Some(vertices) = position_count else {
                return Err(format!("{at} has no POSITION"));
            };
            if let Some(normals) = normal_count
                && normals != vertices
            {
                return Err(format!("{at}: {normals} normals for {vertices} positions"));
            }
            let corners = match &primitive.indices {
                Some(index) => {
                    let accessor = accessor(root, index.value(), &at)?;
                    let (ty, component) = kinds(accessor);
                    let integer = matches!(
                        component,
                        Some(ComponentType::U8 | ComponentType::U16 | ComponentType::U32)
                    );
                    if ty != Some(Type::Scalar) || !integer || accessor.normalized {
                        return Err(format!(
                            "{at}: its indices (accessor {}) are {}, not SCALAR unsigned integers",
                            index.value(),
                            describe(accessor)
                        ));
                    }
                    check_accessor(root, buffer_lengths, index.value(), &at)?
                }
                None => vertices,
            };
            if corners % 3 != 0 {
                return Err(format!(
                    "{at}: {corners} {} is not a multiple of 3 (whole triangles)",
                    if primitive.indices.is_some() {
                        "indices"
                    } else {
                        "vertices"
                    }
                ));
            }
        }
    }
    Ok(())
}

fn accessor<'a>(
    root: &'a json::Root,
    index: usize,
    at: &str,
) -> Result<&'a json::Accessor, String> {
    root.accessors.get(index).ok_or_else(|| {
        format!(
            "{at} names accessor {index}, but the file has {}",
            root.accessors.len()
        )
    })
}

fn kinds(accessor: &json::Accessor) -> (Option<Type>, Option<ComponentType>) {
    let ty = match accessor.type_ {
        Checked::Valid(t) => Some(t),
        Checked::Invalid => None,
    };
    let component = match accessor.component_type {
        Checked::Valid(c) => Some(c.0),
        Checked::Invalid => None,
    };
    (ty, component)
}

fn describe(accessor: &json::Accessor) -> String {
    match kinds(accessor) {
        (Some(t), Some(c)) => format!("{} of {c:?}", format!("{t:?}").to_uppercase()),
        _ => "of an unknown type".to_string(),
    }
}

/// Checks that accessor `index` lies inside its buffer view and the view inside its buffer;
/// returns its element count.
fn check_accessor(
    root: &json::Root,
    buffer_lengths: &[usize],
    index: usize,
    at: &str,
) -> Result<u64, String> {
    let a = accessor(root, index, at)?;
    let count = a.count.0;
    let (Some(ty), Some(component)) = kinds(a) else {
        return Err(format!("{at}: accessor {index} has an unknown type"));
    };
    let element = (ty.multiplicity() * component.size()) as u64;
    let Some(view_index) = a.buffer_view else {
        // All zeros unless sparse: either way nothing is read out of bounds.
        return Ok(count);
    };
    let view = root.buffer_views.get(view_index.value()).ok_or_else(|| {
        format!(
            "{at}: accessor {index} names buffer view {}, which does not exist",
            view_index.value()
        )
    })?;
    let stride = view
        .byte_stride
        .map_or(element, |s| s.0 as u64)
        .max(element);
    let offset = a.byte_offset.map_or(0, |o| o.0);
    let needed = match count {
        0 => 0,
        n => offset + stride * (n - 1) + element,
    };
    if needed > view.byte_length.0 {
        return Err(format!(
            "{at}: accessor {index} needs {needed} bytes of buffer view {}, which has {}",
            view_index.value(),
            view.byte_length.0
        ));
    }
    let view_end = view.byte_offset.map_or(0, |o| o.0) + view.byte_length.0;
    let buffer = view.buffer.value();
    match buffer_lengths.get(buffer) {
        Some(&len) if view_end <= len as u64 => Ok(count),
        Some(&len) => Err(format!(
            "{at}: buffer view {} ends at byte {view_end} of buffer {buffer}, which has {len}",
            view_index.value()
        )),
        None => Err(format!(
            "{at}: buffer view {} names buffer {buffer}, which does not exist",
            view_index.value()
        )),
    }
}

/// Checks that the nodes form trees: children exist, no node has two parents, and none is its
/// own ancestor; node matrices are affine.
fn check_nodes(root: &json::Root, source: &str) -> Result<(), String> {
    let n = root.nodes.len();
    let name = |i: usize| match root.nodes.get(i).and_then(|node| node.name.as_deref()) {
        Some(name) => format!("node {i} (\"{name}\")"),
        None => format!("node {i}"),
    };
    let mut parent: Vec<Option<usize>> = vec![None; n];
    for (i, node) in root.nodes.iter().enumerate() {
        for child in node.children.iter().flatten() {
            let c = child.value();
            if c >= n {
                return Err(format!(
                    "mesh {source}: {} has child {c}, which does not exist",
                    name(i)
                ));
            }
            if c == i {
                return Err(format!("mesh {source}: {} is its own child", name(i)));
            }
            if let Some(p) = parent[c] {
                return Err(format!(
                    "mesh {source}: {} has two parents, {} and {}: glTF nodes form trees",
                    name(c),
                    name(p),
                    name(i)
                ));
            }
            parent[c] = Some(i);
        }
        if let Some(m) = node.matrix {
            // Column-major: the last row is elements 3, 7, 11, 15.
            if [m[3], m[7], m[11], m[15]] != [0.0, 0.0, 0.0, 1.0] {
                return Err(format!(
                    "mesh {source}: {} has a projective matrix (last row {:?}); node matrices must be affine",
                    name(i),
                    [m[3], m[7], m[11], m[15]]
                ));
            }
        }
    }
    // With one parent each, a cycle is a chain of parents that comes back: walk up from each
    // node until a root or a node already known to reach one (each node walked once).
    const UNKNOWN: u8 = 0;
    const ON_PATH: u8 = 1;
    const REACHES_ROOT: u8 = 2;
    let mut state = vec![UNKNOWN; n];
    let mut path = Vec::new();
    for start in 0..n {
        let mut at = Some(start);
        while let Some(i) = at {
            match state[i] {
                REACHES_ROOT => break,
                ON_PATH => {
                    return Err(format!(
                        "mesh {source}: {} is its own ancestor: the node hierarchy has a cycle",
                        name(i)
                    ));
                }
                _ => {
                    state[i] = ON_PATH;
                    path.push(i);
                    at = parent[i];
                }
            }
        }
        for i in path.drain(..) {
            state[i] = REACHES_ROOT;
        }
    }
    for (s, scene) in root.scenes.iter().enumerate() {
        let mut seen = std::collections::HashSet::new();
        for node in &scene.nodes {
            let i = node.value();
            if i >= n {
                return Err(format!(
                    "mesh {source}: scene {s} names node {i}, which does not exist"
                ));
            }
            if let Some(p) = parent[i] {
                return Err(format!(
                    "mesh {source}: scene {s} lists {} as a root, but it is a child of {}",
                    name(i),
                    name(p)
                ));
            }
            if !seen.insert(i) {
                return Err(format!("mesh {source}: scene {s} lists {} twice", name(i)));
            }
        }
    }
    Ok(())
}
