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

/// Parses a glTF file's `bytes` (its references checked before the crate's validation, which
/// indexes some of them unchecked), accepting as required the extensions rt-gpu reads itself
/// (the crate refuses any it does not know).
pub fn parse(bytes: &[u8], source: &str) -> Result<gltf::Gltf, String> {
    let one_line = |e: &dyn std::fmt::Display| e.to_string().replace('\n', " ");
    let what = format!("mesh {source}");
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| format!("cannot read {what}: {}", one_line(&e)))?;
    check_references(document.as_json(), source)?;
    let mut root = document.into_json();
    root.extensions_required.retain(|e| {
        ![
            super::gltf_instancing::EXTENSION,
            super::gltf_quantized::EXTENSION,
            super::gltf_extensions::CLEARCOAT,
            super::gltf_extensions::VOLUME,
            super::gltf_extensions::SHEEN,
            super::gltf_extensions::SPECULAR,
        ]
        .contains(&e.as_str())
    });
    let document = gltf::Document::from_json(root)
        .map_err(|e| format!("cannot read {what}: {}", one_line(&e)))?;
    Ok(gltf::Gltf { document, blob })
}

/// Whether `q` is a unit quaternion as glTF asks (node rotations, instances' ROTATION), within
/// the rounding a file's writer may leave.
pub(super) fn is_unit_quaternion(q: [f32; 4]) -> bool {
    let length = q.iter().map(|&x| x as f64 * x as f64).sum::<f64>().sqrt();
    (length - 1.0).abs() <= 1e-2
}

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
/// POSITION accessor exists; every animation channel targets a node that exists by a property
/// glTF names (the crate validates channels' samplers only, and unwraps both).
pub fn check_references(root: &json::Root, source: &str) -> Result<(), String> {
    for (a, animation) in root.animations.iter().enumerate() {
        for (c, channel) in animation.channels.iter().enumerate() {
            let at = format!("mesh {source}: animation {a}'s channel {c}");
            let node = channel.target.node.value();
            if node >= root.nodes.len() {
                return Err(format!("{at} targets node {node}, which does not exist"));
            }
            if !matches!(channel.target.path, Checked::Valid(_)) {
                return Err(format!(
                    "{at} animates a property glTF does not name (translation, rotation, scale, weights)"
                ));
            }
        }
    }
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

/// Reads the buffers, each checked as it is read: the binary chunk of a `.glb`, a base64 data
/// URI, or a file named by a relative URI (percent-decoded) that stays inside the glTF file's
/// folder, as images are (`gltf_textures::relative_uri`), and is a regular file of at most
/// [`MAX_BUFFER_BYTES`]; each holds at least its `byteLength`. One decoded path is both checked
/// and read, and the file is recorded as one the scene reads (`inputs`). Padded to a multiple of
/// four bytes, as the `gltf` crate's reader pads them.
pub fn read_buffers(
    document: &gltf::Document,
    mut blob: Option<Vec<u8>>,
    base: Option<&Path>,
    source: &str,
) -> Result<Vec<gltf::buffer::Data>, String> {
    use super::gltf_textures::{beside, relative_uri};
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let i = buffer.index();
        let mut data = match buffer.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                format!(
                    "mesh {source}: buffer {i} names the binary chunk, which the file does not have"
                )
            })?,
            gltf::buffer::Source::Uri(uri) => match uri.strip_prefix("data:") {
                Some(data) => {
                    let Some((_, encoded)) = data.split_once(";base64,") else {
                        return Err(format!(
                            "mesh {source}: buffer {i}: a data URI must be base64 (data:<type>;base64,...)"
                        ));
                    };
                    // Base64 takes 4 characters for 3 bytes: bounded by the file's own size.
                    base64::decode(encoded).map_err(|e| {
                        format!("mesh {source}: buffer {i}: its data URI is not base64: {e}")
                    })?
                }
                None => {
                    let shown_uri = super::file::quoted(uri);
                    let relative = relative_uri(uri).map_err(|why| {
                        format!("mesh {source}: buffer {i}'s URI \"{shown_uri}\" {why}")
                    })?;
                    let path = match base {
                        Some(dir) => dir.join(&relative),
                        None => Path::new(&relative).to_path_buf(),
                    };
                    crate::assets::inputs::read(&path, &beside(source, &relative), MAX_BUFFER_BYTES)
                        .map_err(|e| format!("mesh {source}: buffer {i} ({shown_uri}): {e}"))?
                        .0
                }
            },
        };
        let length = buffer.length() as u64;
        if (data.len() as u64) < length {
            return Err(format!(
                "mesh {source}: buffer {i} holds {} bytes, fewer than its byteLength {length}",
                data.len()
            ));
        }
        while data.len() % 4 != 0 {
            data.push(0);
        }
        buffers.push(gltf::buffer::Data(data));
    }
    Ok(buffers)
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
    let quantized = root
        .extensions_used
        .iter()
        .any(|e| e == super::gltf_quantized::EXTENSION);
    super::gltf_instancing::check(root, buffer_lengths, source)?;
    check_skins_and_animation(root, buffer_lengths, source)?;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let at = format!("mesh {source}: mesh {m} primitive {p}");
            let triangles = matches!(
                primitive.mode,
                Checked::Valid(
                    json::mesh::Mode::Triangles
                        | json::mesh::Mode::TriangleStrip
                        | json::mesh::Mode::TriangleFan
                )
            );
            if !triangles {
                continue;
            }
            let mut position_count = None;
            let mut normal_count = None;
            // Texture coordinates', joints' and weights' counts, which must be the positions'
            // (glTF 2.0, 3.7.2.1).
            let mut counts: Vec<(String, usize, u64)> = Vec::new();
            for (semantic, index) in &primitive.attributes {
                let accessor = accessor(root, index.value(), &at)?;
                let (expected, name) = match semantic {
                    Checked::Valid(json::mesh::Semantic::Positions) => (Type::Vec3, "POSITION"),
                    Checked::Valid(json::mesh::Semantic::Normals) => (Type::Vec3, "NORMAL"),
                    Checked::Valid(json::mesh::Semantic::Tangents) => (Type::Vec4, "TANGENT"),
                    Checked::Valid(json::mesh::Semantic::TexCoords(set)) => {
                        // glTF 2.0, 3.7.2.1: VEC2 of FLOAT, or of normalized unsigned bytes
                        // or shorts (the crate's reader asserts the element's size).
                        if !(quantized && quantized_kind(accessor, Type::Vec2, false)) {
                            check_kinds(
                                accessor,
                                index.value(),
                                &[Type::Vec2],
                                &format!("TEXCOORD_{set}"),
                                &at,
                            )?;
                        }
                        let count = check_accessor(root, buffer_lengths, index.value(), &at)?;
                        counts.push((format!("TEXCOORD_{set}"), index.value(), count));
                        continue;
                    }
                    // Skins' influences (`gltf_pose`): joints as unsigned integers, weights as
                    // FLOAT or normalized unsigned integers (glTF 2.0, 3.7.3.3).
                    Checked::Valid(json::mesh::Semantic::Joints(set)) => {
                        let (ty, component) = kinds(accessor);
                        let integer =
                            matches!(component, Some(ComponentType::U8 | ComponentType::U16));
                        if ty != Some(Type::Vec4) || !integer || accessor.normalized {
                            return Err(format!(
                                "{at}: JOINTS_{set} (accessor {}) is {}, not VEC4 of UNSIGNED_BYTE or UNSIGNED_SHORT",
                                index.value(),
                                describe(accessor)
                            ));
                        }
                        let count = check_accessor(root, buffer_lengths, index.value(), &at)?;
                        counts.push((format!("JOINTS_{set}"), index.value(), count));
                        continue;
                    }
                    Checked::Valid(json::mesh::Semantic::Weights(set)) => {
                        let name = format!("WEIGHTS_{set}");
                        check_kinds(accessor, index.value(), &[Type::Vec4], &name, &at)?;
                        let count = check_accessor(root, buffer_lengths, index.value(), &at)?;
                        counts.push((name, index.value(), count));
                        continue;
                    }
                    Checked::Valid(json::mesh::Semantic::Colors(set)) => {
                        check_kinds(
                            accessor,
                            index.value(),
                            &[Type::Vec3, Type::Vec4],
                            &format!("COLOR_{set}"),
                            &at,
                        )?;
                        check_accessor(root, buffer_lengths, index.value(), &at)?;
                        continue;
                    }
                    _ => {
                        check_accessor(root, buffer_lengths, index.value(), &at)?;
                        continue;
                    }
                };
                let (ty, component) = kinds(accessor);
                // KHR_mesh_quantization: positions of any 8- or 16-bit integers, normals and
                // tangents of normalized signed ones.
                let allowed = quantized && quantized_kind(accessor, expected, name != "POSITION");
                if !allowed
                    && (ty != Some(expected)
                        || component != Some(ComponentType::F32)
                        || accessor.normalized)
                {
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
            for (k, target) in primitive.targets.iter().flatten().enumerate() {
                let attributes = [
                    (&target.positions, "POSITION"),
                    (&target.normals, "NORMAL"),
                    (&target.tangents, "TANGENT"),
                ];
                for (index, name) in attributes {
                    let Some(index) = index else { continue };
                    let name = format!("morph target {k}'s {name}");
                    let accessor = accessor(root, index.value(), &at)?;
                    let (ty, component) = kinds(accessor);
                    let float = ty == Some(Type::Vec3)
                        && component == Some(ComponentType::F32)
                        && !accessor.normalized;
                    let unit = !name.ends_with("POSITION");
                    if !(float || quantized && quantized_kind(accessor, Type::Vec3, unit)) {
                        return Err(format!(
                            "{at}: {name} (accessor {}) is {}, not VEC3 of FLOAT",
                            index.value(),
                            describe(accessor)
                        ));
                    }
                    let count = check_accessor(root, buffer_lengths, index.value(), &at)?;
                    counts.push((name, index.value(), count));
                }
            }
            if let Some((name, index, count)) = counts.iter().find(|(_, _, n)| *n != vertices) {
                return Err(format!(
                    "{at}: {name} (accessor {index}) has {count} values for {vertices} positions"
                ));
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
            let what = if primitive.indices.is_some() {
                "indices"
            } else {
                "vertices"
            };
            let list = matches!(primitive.mode, Checked::Valid(json::mesh::Mode::Triangles));
            if list && corners % 3 != 0 {
                return Err(format!(
                    "{at}: {corners} {what} is not a multiple of 3 (whole triangles)"
                ));
            }
            if !list && corners < 3 {
                return Err(format!(
                    "{at}: a triangle strip or fan of {corners} {what} (at least 3 make a triangle)"
                ));
            }
        }
    }
    Ok(())
}

/// Whether `accessor` is of `ty` in a kind KHR_mesh_quantization allows: FLOAT, or 8- or 16-bit
/// integers, which must be normalized and signed where `unit` (normals and tangents).
fn quantized_kind(accessor: &json::Accessor, ty: Type, unit: bool) -> bool {
    let (kind, component) = kinds(accessor);
    let integer = match component {
        Some(ComponentType::F32) => return kind == Some(ty) && !accessor.normalized,
        Some(ComponentType::I8 | ComponentType::I16) => true,
        Some(ComponentType::U8 | ComponentType::U16) => !unit,
        _ => false,
    };
    kind == Some(ty) && integer && (accessor.normalized || !unit)
}

/// Checks an attribute the specification allows as `types` of FLOAT, or of normalized unsigned
/// bytes or shorts (texture coordinates, colours).
fn check_kinds(
    accessor: &json::Accessor,
    index: usize,
    types: &[Type],
    name: &str,
    at: &str,
) -> Result<(), String> {
    let (ty, component) = kinds(accessor);
    let component_ok = match component {
        Some(ComponentType::F32) => !accessor.normalized,
        Some(ComponentType::U8 | ComponentType::U16) => accessor.normalized,
        _ => false,
    };
    if ty.is_some_and(|t| types.contains(&t)) && component_ok {
        return Ok(());
    }
    let shapes: Vec<String> = types
        .iter()
        .map(|t| format!("{t:?}").to_uppercase())
        .collect();
    Err(format!(
        "{at}: {name} (accessor {index}) is {}{}, not {} of FLOAT or of normalized UNSIGNED_BYTE or UNSIGNED_SHORT",
        describe(accessor),
        if accessor.normalized {
            " (normalized)"
        } else {
            ""
        },
        shapes.join(" or ")
    ))
}

pub(super) fn accessor<'a>(
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

pub(super) fn kinds(accessor: &json::Accessor) -> (Option<Type>, Option<ComponentType>) {
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

pub(super) fn describe(accessor: &json::Accessor) -> String {
    match kinds(accessor) {
        (Some(t), Some(c)) => format!("{} of {c:?}", format!("{t:?}").to_uppercase()),
        _ => "of an unknown type".to_string(),
    }
}

/// Most elements an accessor without a buffer view (all zeros, or sparse) may have: as many as
/// the corners of the most triangles a mesh may have.
pub const MAX_UNVIEWED_COUNT: u64 = 3 * super::mesh::MAX_TRIANGLES as u64;

/// Bytes an element of a mesh's attribute may take at the peak of loading it (read, converted,
/// kept per corner, placed and put in the hierarchy), against which an accessor's count is
/// checked before anything is allocated.
const PEAK_BYTES_PER_ELEMENT: u64 = 128;

/// Checks that accessor `index` lies inside its buffer view and the view inside its buffer, and
/// its sparse blocks inside theirs; that its count fits the mesh limits and this machine's memory
/// before anything is allocated; returns its element count.
pub(super) fn check_accessor(
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
    // glTF 2.0, 5.1: at least one element (the crate's reader subtracts one from the count).
    if count == 0 {
        return Err(format!(
            "{at}: accessor {index} has a count of 0; glTF requires at least 1"
        ));
    }
    if a.buffer_view.is_none() && count > MAX_UNVIEWED_COUNT {
        return Err(format!(
            "{at}: accessor {index} has a count of {count} and no buffer view: more than the {MAX_UNVIEWED_COUNT} elements rt-gpu reads"
        ));
    }
    crate::film::check_available(count.saturating_mul(PEAK_BYTES_PER_ELEMENT), || {
        format!("{at}: accessor {index} has {count} elements: loading them")
    })?;
    if let Some(view) = a.buffer_view {
        let offset = a.byte_offset.map_or(0, |o| o.0);
        let what = format!("accessor {index}");
        check_view(
            root,
            buffer_lengths,
            view.value(),
            offset,
            Some(element),
            count,
            &what,
            at,
        )?;
    }
    if let Some(sparse) = &a.sparse {
        let n = sparse.count.0;
        if n == 0 {
            return Err(format!(
                "{at}: accessor {index} has a sparse block of 0 values; glTF requires at least 1"
            ));
        }
        if n > count {
            return Err(format!(
                "{at}: accessor {index} has {n} sparse values, more than its count {count}"
            ));
        }
        let index_size = match sparse.indices.component_type {
            Checked::Valid(c) => c.0.size() as u64,
            Checked::Invalid => {
                return Err(format!(
                    "{at}: accessor {index}'s sparse indices have an unknown type"
                ));
            }
        };
        let blocks = [
            (
                "indices",
                &sparse.indices.buffer_view,
                sparse.indices.byte_offset.0,
                index_size,
            ),
            (
                "values",
                &sparse.values.buffer_view,
                sparse.values.byte_offset.0,
                element,
            ),
        ];
        for (name, view, offset, size) in blocks {
            let what = format!("accessor {index}'s sparse {name}");
            // glTF 2.0, 3.6.2.4: their views hold them packed (the crate's reader would step
            // by a stride and panic on one shorter than an element).
            if let Some(stride) = root
                .buffer_views
                .get(view.value())
                .and_then(|v| v.byte_stride)
            {
                return Err(format!(
                    "{at}: {what} lie in buffer view {} with a byteStride ({}), which glTF forbids for sparse blocks",
                    view.value(),
                    stride.0
                ));
            }
            let bytes = n.saturating_mul(size);
            check_view(
                root,
                buffer_lengths,
                view.value(),
                offset,
                None,
                bytes,
                &what,
                at,
            )?;
        }
    }
    Ok(count)
}

/// Checks that `count` elements of `element` bytes (or, where `element` is `None`, `count`
/// bytes packed), from `offset` in buffer view `view_index`, lie inside the view, and the view
/// inside its buffer.
#[allow(clippy::too_many_arguments)]
fn check_view(
    root: &json::Root,
    buffer_lengths: &[usize],
    view_index: usize,
    offset: u64,
    element: Option<u64>,
    count: u64,
    what: &str,
    at: &str,
) -> Result<(), String> {
    let view = root.buffer_views.get(view_index).ok_or_else(|| {
        format!("{at}: {what} names buffer view {view_index}, which does not exist")
    })?;
    let needed = match element {
        None => offset.saturating_add(count),
        Some(_) if count == 0 => 0,
        Some(element) => {
            let stride = view.byte_stride.map_or(element, |s| s.0 as u64);
            if stride < element {
                return Err(format!(
                    "{at}: {what} has elements of {element} bytes, but buffer view {view_index}'s byteStride is {stride}"
                ));
            }
            offset
                .saturating_add(stride.saturating_mul(count - 1))
                .saturating_add(element)
        }
    };
    if needed > view.byte_length.0 {
        return Err(format!(
            "{at}: {what} needs {needed} bytes of buffer view {view_index}, which has {}",
            view.byte_length.0
        ));
    }
    let view_end = view
        .byte_offset
        .map_or(0, |o| o.0)
        .saturating_add(view.byte_length.0);
    let buffer = view.buffer.value();
    match buffer_lengths.get(buffer) {
        Some(&len) if view_end <= len as u64 => Ok(()),
        Some(&len) => Err(format!(
            "{at}: buffer view {view_index} ends at byte {view_end} of buffer {buffer}, which has {len}"
        )),
        None => Err(format!(
            "{at}: buffer view {view_index} names buffer {buffer}, which does not exist"
        )),
    }
}

/// Checks what the pose reads beside primitives (`gltf_pose`): skins' inverse bind matrices
/// (MAT4 of FLOAT, at least one per joint) and joints, and the first animation's key times
/// (SCALAR of FLOAT) and values (the kinds glTF 2.0, 3.11 allows for the property: FLOAT, or
/// normalized integers for rotations and weights).
fn check_skins_and_animation(
    root: &json::Root,
    buffer_lengths: &[usize],
    source: &str,
) -> Result<(), String> {
    for (s, skin) in root.skins.iter().enumerate() {
        let at = format!("mesh {source}: skin {s}");
        if let Some(joint) = skin.joints.iter().find(|j| j.value() >= root.nodes.len()) {
            return Err(format!(
                "{at} names joint node {}, which does not exist",
                joint.value()
            ));
        }
        let Some(index) = &skin.inverse_bind_matrices else {
            continue;
        };
        let accessor = accessor(root, index.value(), &at)?;
        let (ty, component) = kinds(accessor);
        if ty != Some(Type::Mat4) || component != Some(ComponentType::F32) || accessor.normalized {
            return Err(format!(
                "{at}: its inverseBindMatrices (accessor {}) are {}, not MAT4 of FLOAT",
                index.value(),
                describe(accessor)
            ));
        }
        let count = check_accessor(root, buffer_lengths, index.value(), &at)?;
        if count < skin.joints.len() as u64 {
            return Err(format!(
                "{at} has {count} inverseBindMatrices for {} joints",
                skin.joints.len()
            ));
        }
    }
    let Some(animation) = root.animations.first() else {
        return Ok(());
    };
    for (c, channel) in animation.channels.iter().enumerate() {
        let at = format!("mesh {source}: animation 0's channel {c}");
        let Some(sampler) = animation.samplers.get(channel.sampler.value()) else {
            return Err(format!(
                "{at} names sampler {}, which does not exist",
                channel.sampler.value()
            ));
        };
        let input = accessor(root, sampler.input.value(), &at)?;
        if kinds(input) != (Some(Type::Scalar), Some(ComponentType::F32)) || input.normalized {
            return Err(format!(
                "{at}: its key times (accessor {}) are {}, not SCALAR of FLOAT",
                sampler.input.value(),
                describe(input)
            ));
        }
        check_accessor(root, buffer_lengths, sampler.input.value(), &at)?;
        let output = accessor(root, sampler.output.value(), &at)?;
        let (ty, component) = kinds(output);
        use json::animation::Property;
        let (expected, integers) = match channel.target.path {
            Checked::Valid(Property::Translation | Property::Scale) => (Type::Vec3, false),
            Checked::Valid(Property::Rotation) => (Type::Vec4, true),
            _ => (Type::Scalar, true),
        };
        let component_ok = match component {
            Some(ComponentType::F32) => !output.normalized,
            Some(
                ComponentType::I8 | ComponentType::U8 | ComponentType::I16 | ComponentType::U16,
            ) => integers && output.normalized,
            _ => false,
        };
        if ty != Some(expected) || !component_ok {
            return Err(format!(
                "{at}: its values (accessor {}) are {}, not {} of FLOAT{}",
                sampler.output.value(),
                describe(output),
                format!("{expected:?}").to_uppercase(),
                if integers {
                    " or normalized integers"
                } else {
                    ""
                }
            ));
        }
        check_accessor(root, buffer_lengths, sampler.output.value(), &at)?;
    }
    Ok(())
}

/// Checks that the nodes form trees: children exist, no node has two parents, and none is its
/// own ancestor; node matrices are affine.
fn check_nodes(root: &json::Root, source: &str) -> Result<(), String> {
    let n = root.nodes.len();
    let name = |i: usize| match root.nodes.get(i).and_then(|node| node.name.as_deref()) {
        Some(name) => format!("node {i} (\"{}\")", super::file::quoted(name)),
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
        if let Some(r) = &node.rotation {
            let length = r.0.iter().map(|&x| x as f64 * x as f64).sum::<f64>().sqrt();
            if !is_unit_quaternion(r.0) {
                return Err(format!(
                    "mesh {source}: {} has a rotation {:?} of length {length:.3}; glTF requires a unit quaternion",
                    name(i),
                    r.0
                ));
            }
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
