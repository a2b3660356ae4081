//! EXT_mesh_gpu_instancing: a node that places its mesh many times, each instance's
//! TRANSLATION, ROTATION (a unit quaternion) and SCALE read from accessors of FLOAT and applied
//! before the node's own transform (the node's world matrix x the instance's TRS), as the
//! extension defines. rt-gpu places every instance's triangles into the mesh, as a file that
//! repeated the node would (the file's triangle limit bounds them all).

use glam::{DMat4, DQuat, DVec3};
use gltf::json;
use gltf::json::accessor::{ComponentType, Type};

/// The extension's name.
pub const EXTENSION: &str = "EXT_mesh_gpu_instancing";

/// A node's instancing accessors: TRANSLATION, ROTATION, SCALE (each optional).
type Attributes = [Option<usize>; 3];

/// The attributes' names, their types, and the value each takes where absent.
const ATTRIBUTES: [(&str, Type); 3] = [
    ("TRANSLATION", Type::Vec3),
    ("ROTATION", Type::Vec4),
    ("SCALE", Type::Vec3),
];

/// The instancing accessors of the node whose extensions' JSON is `extension`; `None` where it
/// does not use the extension.
fn attributes(extension: Option<&json::Value>, at: &str) -> Result<Option<Attributes>, String> {
    let Some(extension) = extension else {
        return Ok(None);
    };
    let given = extension.get("attributes").and_then(|a| a.as_object());
    let Some(given) = given else {
        return Err(format!("{at} has no attributes"));
    };
    let mut out = [None; 3];
    for (slot, (name, _)) in out.iter_mut().zip(ATTRIBUTES) {
        if let Some(value) = given.get(name) {
            let index = value.as_u64().filter(|&i| i <= u32::MAX as u64);
            *slot = Some(
                index.ok_or_else(|| format!("{at}'s {name} is {value}, not an accessor index"))?
                    as usize,
            );
        }
    }
    if out.iter().all(Option::is_none) {
        return Err(format!("{at} has none of TRANSLATION, ROTATION and SCALE"));
    }
    Ok(Some(out))
}

/// Where a node's extension is named in messages.
fn named(source: &str, node: usize) -> String {
    format!("mesh {source}: node {node}'s {EXTENSION}")
}

/// Checks every node's instancing before anything is read: accessors of FLOAT of their
/// attribute's type, within their buffers (`gltf_check`'s accessor checks), of one count, on a
/// node with a mesh.
pub fn check(root: &json::Root, buffer_lengths: &[usize], source: &str) -> Result<(), String> {
    for (n, node) in root.nodes.iter().enumerate() {
        let at = named(source, n);
        let extension = node
            .extensions
            .as_ref()
            .and_then(|e| e.others.get(EXTENSION));
        let Some(attributes) = attributes(extension, &at)? else {
            continue;
        };
        let Some(mesh) = node.mesh.and_then(|m| root.meshes.get(m.value())) else {
            return Err(format!("{at}: the node has no mesh to place"));
        };
        let mut count = None;
        for (index, (name, ty)) in attributes.into_iter().zip(ATTRIBUTES) {
            let Some(index) = index else { continue };
            let accessor = super::gltf_check::accessor(root, index, &at)?;
            let (kind, component) = super::gltf_check::kinds(accessor);
            if kind != Some(ty) || component != Some(ComponentType::F32) || accessor.normalized {
                return Err(format!(
                    "{at}: {name} (accessor {index}) is {}; rt-gpu reads {} of FLOAT",
                    super::gltf_check::describe(accessor),
                    format!("{ty:?}").to_uppercase()
                ));
            }
            let this = super::gltf_check::check_accessor(root, buffer_lengths, index, &at)?;
            if count.is_some_and(|c| c != this) {
                return Err(format!(
                    "{at}: its attributes' counts differ ({} and {this})",
                    count.unwrap_or_default()
                ));
            }
            count = Some(this);
        }
        // Every instance's triangles, bounded before any is placed.
        let triangles: u64 = mesh.primitives.iter().map(|p| triangles_of(root, p)).sum();
        let placed = triangles.saturating_mul(count.unwrap_or(0));
        if placed > super::mesh::MAX_TRIANGLES as u64 {
            return Err(format!(
                "{at}: {} instances of {triangles} triangles make {placed}, more than the {} rt-gpu takes",
                count.unwrap_or(0),
                super::mesh::MAX_TRIANGLES
            ));
        }
    }
    Ok(())
}

/// The triangles a primitive draws, from its accessors' counts (0 for points and lines).
fn triangles_of(root: &json::Root, primitive: &json::mesh::Primitive) -> u64 {
    use json::mesh::{Mode, Semantic};
    use json::validation::Checked;
    let count = |index: usize| root.accessors.get(index).map_or(0, |a| a.count.0);
    let corners = match &primitive.indices {
        Some(index) => count(index.value()),
        None => primitive
            .attributes
            .get(&Checked::Valid(Semantic::Positions))
            .map_or(0, |index| count(index.value())),
    };
    match primitive.mode {
        Checked::Valid(Mode::Triangles) => corners / 3,
        Checked::Valid(Mode::TriangleStrip | Mode::TriangleFan) => corners.saturating_sub(2),
        _ => 0,
    }
}

/// The transforms of `node`'s instances, each its TRS (`[IDENTITY]` without the extension);
/// `buffer` gives a buffer's bytes. Rotations must be unit quaternions and every value finite.
pub fn instances<'a>(
    node: &gltf::Node,
    document: &gltf::Document,
    buffer: impl Fn(gltf::Buffer) -> Option<&'a [u8]> + Clone,
    source: &str,
) -> Result<Vec<DMat4>, String> {
    let at = named(source, node.index());
    let Some(attributes) = attributes(node.extension_value(EXTENSION), &at)? else {
        return Ok(vec![DMat4::IDENTITY]);
    };
    let read = |index: Option<usize>, name: &str| -> Result<Option<Vec<Vec<f64>>>, String> {
        let Some(index) = index else { return Ok(None) };
        let accessor = document
            .accessors()
            .nth(index)
            .ok_or_else(|| format!("{at} names accessor {index}, which the file lacks"))?;
        let values: Vec<Vec<f64>> = if name == "ROTATION" {
            gltf::accessor::Iter::<[f32; 4]>::new(accessor, buffer.clone())
                .map(|i| i.map(|v| v.map(f64::from).to_vec()).collect())
        } else {
            gltf::accessor::Iter::<[f32; 3]>::new(accessor, buffer.clone())
                .map(|i| i.map(|v| v.map(f64::from).to_vec()).collect())
        }
        .ok_or_else(|| format!("{at}: its {name} (accessor {index}) cannot be read"))?;
        if let Some(bad) = values.iter().find(|v| !v.iter().all(|x| x.is_finite())) {
            return Err(format!(
                "{at}: its {name} holds {bad:?}, not finite numbers"
            ));
        }
        Ok(Some(values))
    };
    let [t, r, s] = attributes;
    let (t, r, s) = (
        read(t, "TRANSLATION")?,
        read(r, "ROTATION")?,
        read(s, "SCALE")?,
    );
    let count = [&t, &r, &s]
        .iter()
        .filter_map(|v| v.as_ref().map(Vec::len))
        .max()
        .unwrap_or(0);
    (0..count)
        .map(|i| {
            let vector = |values: &Option<Vec<Vec<f64>>>, default: DVec3| {
                values.as_ref().map_or(default, |v| DVec3::new(v[i][0], v[i][1], v[i][2]))
            };
            let rotation = match &r {
                Some(r) => {
                    let q = DQuat::from_xyzw(r[i][0], r[i][1], r[i][2], r[i][3]);
                    if !((q.length() - 1.0).abs() <= 1e-2) {
                        return Err(format!(
                            "{at}: instance {i}'s ROTATION {:?} has length {:.3}; the extension requires a unit quaternion",
                            r[i],
                            q.length()
                        ));
                    }
                    q.normalize()
                }
                None => DQuat::IDENTITY,
            };
            Ok(DMat4::from_scale_rotation_translation(
                vector(&s, DVec3::ONE),
                rotation,
                vector(&t, DVec3::ZERO),
            ))
        })
        .collect()
}
