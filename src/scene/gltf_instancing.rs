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
        // Every instance's triangles, bounded before any is placed; and the instances
        // themselves, each a pass over the mesh's primitives, by the same limit.
        let count = count.unwrap_or(0);
        let triangles: u64 = mesh.primitives.iter().map(|p| triangles_of(root, p)).sum();
        let passes = (mesh.primitives.len() as u64).max(1).saturating_mul(count);
        if passes > super::mesh::MAX_TRIANGLES as u64 {
            return Err(format!(
                "{at}: {count} instances of {} primitives are more than the {} placements rt-gpu takes",
                mesh.primitives.len(),
                super::mesh::MAX_TRIANGLES
            ));
        }
        let placed = triangles.saturating_mul(count);
        if placed > super::mesh::MAX_TRIANGLES as u64 {
            return Err(format!(
                "{at}: {count} instances of {triangles} triangles make {placed}, more than the {} rt-gpu takes",
                super::mesh::MAX_TRIANGLES
            ));
        }
    }
    Ok(())
}

/// The triangles a primitive draws, from its accessors' counts (0 for points and lines).
fn triangles_of(root: &json::Root, primitive: &json::mesh::Primitive) -> u64 {
    use json::mesh::Semantic;
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
        Checked::Valid(mode) => super::mesh::triangles_drawn(mode, corners),
        Checked::Invalid => 0,
    }
}

/// A node's instances: each one's translation, rotation and scale as the file stores them
/// (40 bytes an instance), made into a transform as the loader places it.
pub struct Instances {
    count: usize,
    translations: Option<Vec<[f32; 3]>>,
    rotations: Option<Vec<[f32; 4]>>,
    scales: Option<Vec<[f32; 3]>>,
    /// Where errors about an instance are located.
    at: String,
}

impl Instances {
    /// No instance: a node with nothing to draw.
    pub fn none() -> Self {
        Instances {
            count: 0,
            translations: None,
            rotations: None,
            scales: None,
            at: String::new(),
        }
    }

    /// One instance, the node itself: a node without the extension.
    fn one() -> Self {
        Instances {
            count: 1,
            ..Instances::none()
        }
    }

    pub fn len(&self) -> usize {
        self.count
    }

    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Instance `i`'s transform, T R S; its rotation must be a unit quaternion.
    pub fn transform(&self, i: usize) -> Result<DMat4, String> {
        let vector = |values: &Option<Vec<[f32; 3]>>, default: DVec3| {
            values
                .as_ref()
                .and_then(|v| v.get(i))
                .map_or(default, |v| DVec3::from_array(v.map(f64::from)))
        };
        let rotation = match self.rotations.as_ref().and_then(|r| r.get(i)) {
            Some(r) => {
                let q = DQuat::from_array(r.map(f64::from));
                if !super::gltf_check::is_unit_quaternion(*r) {
                    return Err(format!(
                        "{}: instance {i}'s ROTATION {r:?} has length {:.3}; the extension requires a unit quaternion",
                        self.at,
                        q.length()
                    ));
                }
                q.normalize()
            }
            None => DQuat::IDENTITY,
        };
        let transform = DMat4::from_scale_rotation_translation(
            vector(&self.scales, DVec3::ONE),
            rotation,
            vector(&self.translations, DVec3::ZERO),
        );
        if !transform.is_finite() {
            return Err(format!(
                "{}: instance {i}'s transform is not finite numbers",
                self.at
            ));
        }
        Ok(transform)
    }
}

/// `node`'s instances (one, the node itself, without the extension), their attributes read
/// from the accessors `check` checked; `buffer` gives a buffer's bytes.
pub fn instances<'a>(
    node: &gltf::Node,
    document: &'a gltf::Document,
    buffer: impl Fn(gltf::Buffer) -> Option<&'a [u8]> + Clone,
    source: &str,
) -> Result<Instances, String> {
    let at = named(source, node.index());
    let Some([t, r, s]) = attributes(node.extension_value(EXTENSION), &at)? else {
        return Ok(Instances::one());
    };
    let accessor = |index: Option<usize>| -> Result<Option<gltf::Accessor>, String> {
        index
            .map(|i| {
                document
                    .accessors()
                    .nth(i)
                    .ok_or_else(|| format!("{at} names accessor {i}, which the file lacks"))
            })
            .transpose()
    };
    // FLOAT, as `check` made sure.
    use super::gltf_quantized::{vec3, vec4};
    let unread = |name: &str| format!("{at}: its {name} cannot be read");
    let read3 = |index, name: &str| -> Result<Option<Vec<[f32; 3]>>, String> {
        (accessor(index)?)
            .map(|a| vec3(a, buffer.clone()).ok_or_else(|| unread(name)))
            .transpose()
    };
    let translations = read3(t, "TRANSLATION")?;
    let scales = read3(s, "SCALE")?;
    let rotations = (accessor(r)?)
        .map(|a| vec4(a, buffer.clone()).ok_or_else(|| unread("ROTATION")))
        .transpose()?;
    let count = [
        translations.as_ref().map(Vec::len),
        rotations.as_ref().map(Vec::len),
        scales.as_ref().map(Vec::len),
    ]
    .into_iter()
    .flatten()
    .max()
    .unwrap_or(0);
    Ok(Instances {
        count,
        translations,
        rotations,
        scales,
        at,
    })
}
