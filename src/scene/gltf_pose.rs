//! The pose a glTF file is drawn in: its first animation at time 0 (glTF 2.0, 3.11; a still
//! image shows one moment, and Blender's importer shows the same one at frame 0), morph targets
//! weighted as the node, its mesh or the animation says (3.7.2.2), and skinned meshes moved by
//! their joints (3.7.3). A file without these is drawn as its nodes stand.
//!
//! Nodes' transforms come from here (`local`), and `deform` moves a primitive's vertices,
//! normals and tangents before the node places them, so the flattened mesh holds the pose: the
//! renderer never sees a skin or a target.

use glam::{DMat3, DMat4, DQuat, DVec3};

/// The moment of the first animation drawn (seconds).
pub const TIME: f32 = 0.0;

/// Each node's transform and morph weights as posed.
pub struct Pose {
    /// Each node's transform relative to its parent.
    local: Vec<DMat4>,
    /// Each node's transform relative to the scene (its roots' parents' frame).
    global: Vec<DMat4>,
    /// Each node's morph weights where the animation sets them.
    weights: Vec<Option<Vec<f32>>>,
    /// Each node's parent (`None` for a root).
    parent: Vec<Option<usize>>,
}

/// Where [`Pose::deform`] leaves a primitive's vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Placed {
    /// In its node's coordinates: the node places them.
    ByNode,
    /// In the scene's coordinates, placed by its skin's joints (glTF: the skinned node's own
    /// transform does not apply); `mirrored` where the joints' matrices mirror the mesh (a
    /// negative determinant), which turns its winding around as a mirroring node does.
    BySkin { mirrored: bool },
}

/// A node's translation, rotation and scale, as a file or an animation gives them.
#[derive(Clone, Copy)]
struct Trs {
    translation: DVec3,
    rotation: DQuat,
    scale: DVec3,
}

impl Pose {
    /// The pose of `document` (whose buffers are `buffers`) at [`TIME`] of its first animation;
    /// an error naming `source` and the channel where an animation cannot be read.
    pub fn new(
        document: &gltf::Document,
        buffers: &[gltf::buffer::Data],
        source: &str,
    ) -> Result<Pose, String> {
        let nodes = document.nodes().count();
        let mut trs: Vec<Option<Trs>> = document.nodes().map(node_trs).collect();
        let mut weights: Vec<Option<Vec<f32>>> = vec![None; nodes];
        if let Some(animation) = document.animations().next() {
            let buffer = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
            for channel in animation.channels() {
                let node = channel.target().node().index();
                let at = |what: String| {
                    format!(
                        "mesh {source}: animation {}'s channel {} {what}",
                        animation.index(),
                        channel.index()
                    )
                };
                let (value, property) = channel_value(&channel, buffer, TIME).map_err(at)?;
                match (property, trs.get_mut(node)) {
                    (Property::Weights, _) => weights[node] = Some(value),
                    (_, Some(None)) => {
                        return Err(at(
                            "animates a node given by a matrix, which glTF forbids".into()
                        ));
                    }
                    (property, Some(Some(trs))) => property.set(trs, &value),
                    (_, None) => {}
                }
            }
        }
        let local: Vec<DMat4> = (document.nodes().zip(&trs))
            .map(|(node, trs)| match trs {
                Some(t) => {
                    DMat4::from_scale_rotation_translation(t.scale, t.rotation, t.translation)
                }
                None => matrix_of(&node),
            })
            .collect();
        // Parents before children: from every node no other node names as a child.
        let mut parent = vec![None; nodes];
        for node in document.nodes() {
            for child in node.children() {
                parent[child.index()] = Some(node.index());
            }
        }
        let mut global = vec![DMat4::IDENTITY; nodes];
        let mut stack: Vec<(gltf::Node, DMat4)> = (document.nodes())
            .filter(|n| parent[n.index()].is_none())
            .map(|n| (n, DMat4::IDENTITY))
            .collect();
        // Finite: `gltf_check` found the nodes to be trees.
        while let Some((node, parent)) = stack.pop() {
            let g = parent * local[node.index()];
            global[node.index()] = g;
            stack.extend(node.children().map(|c| (c, g)));
        }
        Ok(Pose {
            local,
            global,
            weights,
            parent,
        })
    }

    /// The scene's coordinates as seen from a reader that starts at node `root` with the
    /// identity (as `mesh::load` does for a node picked by name): the inverse of its parent's
    /// transform; the identity for a root of the scene (or a parent that flattens the space).
    pub fn scene_frame(&self, root: &gltf::Node) -> DMat4 {
        let Some(Some(parent)) = self.parent.get(root.index()) else {
            return DMat4::IDENTITY;
        };
        let inverse = self.global[*parent].inverse();
        if inverse.is_finite() && self.global[*parent].determinant() != 0.0 {
            inverse
        } else {
            DMat4::IDENTITY
        }
    }

    /// `node`'s transform relative to its parent, as posed.
    pub fn local(&self, node: &gltf::Node) -> DMat4 {
        self.local
            .get(node.index())
            .copied()
            .unwrap_or_else(|| matrix_of(node))
    }

    /// The morph weights of `node` (which places `mesh`): the animation's, else the node's,
    /// else the mesh's; none where it has none.
    fn morph_weights<'a>(&'a self, node: &'a gltf::Node, mesh: &'a gltf::Mesh) -> &'a [f32] {
        match self.weights.get(node.index()) {
            Some(Some(w)) => w,
            _ => node.weights().or(mesh.weights()).unwrap_or(&[]),
        }
    }

    /// Moves `primitive`'s vertices (`positions`) and their `normals` and `tangents` (where it
    /// has them; tangents' w untouched) into the pose: by its morph targets, then by its node's
    /// skin; says where that leaves them. An error naming `source` where a target's or a skin's
    /// data does not fit the primitive.
    pub fn deform(
        &self,
        node: &gltf::Node,
        primitive: &gltf::Primitive,
        buffers: &[gltf::buffer::Data],
        source: &str,
        vertices: Vertices<'_>,
    ) -> Result<Placed, String> {
        let Some(mesh) = node.mesh() else {
            return Ok(Placed::ByNode);
        };
        let at = |what: String| {
            format!(
                "mesh {source}: mesh {} (node {}) {what}",
                mesh.index(),
                node.index()
            )
        };
        let Vertices {
            positions,
            mut normals,
            mut tangents,
        } = vertices;
        let weights = self.morph_weights(node, &mesh);
        for (k, target) in primitive.morph_targets().enumerate() {
            let w = weights.get(k).copied().unwrap_or(0.0);
            if w == 0.0 {
                continue;
            }
            if !w.is_finite() {
                return Err(at(format!("has a morph weight {w}")));
            }
            add_target(positions, target.positions(), w, buffers)
                .map_err(|e| at(format!("morph target {k}'s POSITION {e}")))?;
            if let Some(normals) = normals.as_deref_mut() {
                add_target(normals, target.normals(), w, buffers)
                    .map_err(|e| at(format!("morph target {k}'s NORMAL {e}")))?;
            }
            if let Some(tangents) = tangents.as_deref_mut() {
                let mut xyz: Vec<[f32; 3]> = tangents.iter().map(|t| [t[0], t[1], t[2]]).collect();
                add_target(&mut xyz, target.tangents(), w, buffers)
                    .map_err(|e| at(format!("morph target {k}'s TANGENT {e}")))?;
                for (t, d) in tangents.iter_mut().zip(xyz) {
                    t[..3].copy_from_slice(&d);
                }
            }
        }
        match node.skin() {
            Some(skin) => {
                let vertices = Vertices {
                    positions,
                    normals,
                    tangents,
                };
                self.skin(&skin, primitive, buffers, vertices)
            }
            None => Ok(Placed::ByNode),
        }
        .map_err(at)
    }

    /// Moves the vertices of `primitive` by the joints of `skin`: each by its joints' matrices
    /// weighed by its weights, into the scene's coordinates (glTF: a skinned mesh is placed by
    /// its joints, not by its node).
    fn skin(
        &self,
        skin: &gltf::Skin,
        primitive: &gltf::Primitive,
        buffers: &[gltf::buffer::Data],
        vertices: Vertices<'_>,
    ) -> Result<Placed, String> {
        let Vertices {
            positions,
            mut normals,
            mut tangents,
        } = vertices;
        let buffer = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
        let reader = primitive.reader(buffer);
        let Some(first) = reader.read_joints(0) else {
            // A skinned node's primitive without joints is drawn as it stands.
            return Ok(Placed::ByNode);
        };
        let inverse_binds: Vec<DMat4> = match skin.reader(buffer).read_inverse_bind_matrices() {
            Some(m) => m
                .map(|m| DMat4::from_cols_array_2d(&m.map(|c| c.map(f64::from))))
                .collect(),
            None => Vec::new(),
        };
        let joints: Vec<DMat4> = (skin.joints().enumerate())
            .map(|(j, joint)| {
                let bind = inverse_binds.get(j).copied().unwrap_or(DMat4::IDENTITY);
                self.global[joint.index()] * bind
            })
            .collect();
        // Every set of four influences (JOINTS_n with WEIGHTS_n).
        let mut influences: Vec<Vec<(usize, f64)>> = vec![Vec::new(); positions.len()];
        let mut sets = Some(first);
        let mut set = 0;
        while let Some(read) = sets {
            let Some(weights) = reader.read_weights(set) else {
                return Err(format!("has JOINTS_{set} without WEIGHTS_{set}"));
            };
            let (joint_sets, weight_sets): (Vec<[u16; 4]>, Vec<[f32; 4]>) =
                (read.into_u16().collect(), weights.into_f32().collect());
            if joint_sets.len() != positions.len() || weight_sets.len() != positions.len() {
                return Err(format!(
                    "has {} JOINTS_{set} and {} WEIGHTS_{set} for {} vertices",
                    joint_sets.len(),
                    weight_sets.len(),
                    positions.len()
                ));
            }
            for ((all, js), ws) in influences.iter_mut().zip(joint_sets).zip(weight_sets) {
                for (j, w) in js.into_iter().zip(ws) {
                    if w == 0.0 {
                        continue;
                    }
                    if !(w.is_finite() && w > 0.0) || j as usize >= joints.len() {
                        return Err(format!(
                            "has a skin influence of joint {j} with weight {w} (the skin has {} joints)",
                            joints.len()
                        ));
                    }
                    all.push((j as usize, w as f64));
                }
            }
            set += 1;
            sets = reader.read_joints(set);
        }
        // Vertices whose joints mirror them, against those they do not.
        let mut mirrored = 0i64;
        for (i, influence) in influences.iter().enumerate() {
            // Weights should sum to 1: they are scaled so; a vertex no joint moves stays.
            let total: f64 = influence.iter().map(|(_, w)| w).sum();
            if !(total > 0.0) {
                continue;
            }
            let m = influence
                .iter()
                .fold(DMat4::ZERO, |m, &(j, w)| m + joints[j] * (w / total));
            mirrored += if m.determinant() < 0.0 { 1 } else { -1 };
            let p = m.transform_point3(DVec3::from_array(positions[i].map(f64::from)));
            positions[i] = p.as_vec3().to_array();
            let linear = DMat3::from_mat4(m);
            if let Some(n) = normals.as_deref_mut().and_then(|n| n.get_mut(i)) {
                let by = normal_matrix(linear);
                *n = (by * DVec3::from_array(n.map(f64::from)))
                    .as_vec3()
                    .to_array();
            }
            if let Some(t) = tangents.as_deref_mut().and_then(|t| t.get_mut(i)) {
                let v = linear * DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64);
                t[..3].copy_from_slice(&v.as_vec3().to_array());
            }
        }
        Ok(Placed::BySkin {
            mirrored: mirrored > 0,
        })
    }
}

/// A primitive's vertex data that a pose moves.
pub struct Vertices<'v> {
    pub positions: &'v mut [[f32; 3]],
    pub normals: Option<&'v mut [[f32; 3]]>,
    pub tangents: Option<&'v mut [[f32; 4]]>,
}

/// The matrix that carries normals where `m` carries the surface: its inverse transpose (`m`
/// itself where it flattens the surface, whose normals are then any).
fn normal_matrix(m: DMat3) -> DMat3 {
    let inverse = m.inverse();
    if inverse.is_finite() && m.determinant() != 0.0 {
        inverse.transpose()
    } else {
        m
    }
}

/// Adds `w` x the values of `target` (a morph target's accessor of VEC3 displacements, one per
/// value of `values`) to `values`; why not where it does not fit.
fn add_target(
    values: &mut [[f32; 3]],
    target: Option<gltf::Accessor>,
    w: f32,
    buffers: &[gltf::buffer::Data],
) -> Result<(), String> {
    let Some(target) = target else {
        return Ok(());
    };
    let buffer = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
    let deltas = super::gltf_quantized::vec3(target, buffer).ok_or("cannot be read")?;
    if deltas.len() != values.len() {
        return Err(format!(
            "has {} values for {} vertices",
            deltas.len(),
            values.len()
        ));
    }
    for (v, d) in values.iter_mut().zip(deltas) {
        for c in 0..3 {
            v[c] += w * d[c];
        }
    }
    Ok(())
}

/// `node`'s translation, rotation and scale; `None` where a matrix gives its transform.
fn node_trs(node: gltf::Node) -> Option<Trs> {
    match node.transform() {
        gltf::scene::Transform::Matrix { .. } => None,
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => Some(Trs {
            translation: DVec3::from_array(translation.map(f64::from)),
            rotation: quaternion(rotation.map(f64::from)),
            scale: DVec3::from_array(scale.map(f64::from)),
        }),
    }
}

/// The unit quaternion of glTF's (x, y, z, w); the identity for one of no length.
fn quaternion([x, y, z, w]: [f64; 4]) -> DQuat {
    let q = DQuat::from_xyzw(x, y, z, w);
    let length = q.length();
    if length > 0.0 && length.is_finite() {
        q / length
    } else {
        DQuat::IDENTITY
    }
}

fn matrix_of(node: &gltf::Node) -> DMat4 {
    DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)))
}

/// What an animation channel sets.
#[derive(Clone, Copy)]
enum Property {
    Translation,
    Rotation,
    Scale,
    Weights,
}

impl Property {
    /// `trs` with this property set to `value`.
    fn set(self, trs: &mut Trs, value: &[f32]) {
        let v = |i: usize| value.get(i).copied().unwrap_or(0.0) as f64;
        match self {
            Property::Translation => trs.translation = DVec3::new(v(0), v(1), v(2)),
            Property::Rotation => trs.rotation = quaternion([v(0), v(1), v(2), v(3)]),
            Property::Scale => trs.scale = DVec3::new(v(0), v(1), v(2)),
            Property::Weights => {}
        }
    }
}

/// The value `channel` gives its property at `time`, and the property; why not where its keys
/// cannot be read or do not fit its values.
fn channel_value<'a>(
    channel: &gltf::animation::Channel<'a>,
    buffer: impl Fn(gltf::Buffer<'a>) -> Option<&'a [u8]> + Clone,
    time: f32,
) -> Result<(Vec<f32>, Property), String> {
    use gltf::animation::Interpolation;
    use gltf::animation::util::ReadOutputs;
    let reader = channel.reader(buffer);
    let times: Vec<f32> = reader
        .read_inputs()
        .ok_or("has key times that cannot be read")?
        .collect();
    let (values, width, property): (Vec<f32>, Option<usize>, Property) = match reader
        .read_outputs()
        .ok_or("has values that cannot be read")?
    {
        ReadOutputs::Translations(t) => (t.flatten().collect(), Some(3), Property::Translation),
        ReadOutputs::Rotations(r) => (
            r.into_f32().flatten().collect(),
            Some(4),
            Property::Rotation,
        ),
        ReadOutputs::Scales(s) => (s.flatten().collect(), Some(3), Property::Scale),
        ReadOutputs::MorphTargetWeights(w) => (w.into_f32().collect(), None, Property::Weights),
    };
    let interpolation = channel.sampler().interpolation();
    // A cubic spline holds three values a key (in-tangent, value, out-tangent).
    let keys = times.len()
        * if interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
    // Weights: as many a key as the targets they weigh.
    let width = width.unwrap_or(values.len().checked_div(keys).unwrap_or(0));
    if keys == 0 || width == 0 || values.len() != keys * width {
        return Err(format!(
            "has {} key times and {} values, which do not fit",
            times.len(),
            values.len()
        ));
    }
    if times[0] < 0.0 {
        return Err(format!(
            "has a key time {} below 0, which glTF forbids",
            times[0]
        ));
    }
    if let Some(bad) = times.windows(2).find(|w| !(w[0] < w[1])) {
        return Err(format!(
            "has key times that do not increase ({} then {})",
            bad[0], bad[1]
        ));
    }
    if values.iter().chain(&times).any(|v| !v.is_finite()) {
        return Err("has a value that is not a finite number".into());
    }
    let rotation = matches!(property, Property::Rotation);
    let sampled = sample(&times, &values, width, interpolation, rotation, time);
    let sampled = sampled.map(Vec::from).unwrap_or_default();
    Ok((sampled, property))
}

/// The value of `width` numbers at `time` of keys at `times` holding `values` (for cubic
/// splines, each key's in-tangent, value and out-tangent), interpolated as `interpolation`
/// says (glTF 2.0, Appendix C: a `rotation`'s linear interpolation is the slerp); before the
/// first key the first value, after the last the last.
fn sample(
    times: &[f32],
    values: &[f32],
    width: usize,
    interpolation: gltf::animation::Interpolation,
    rotation: bool,
    time: f32,
) -> Option<Box<[f32]>> {
    use gltf::animation::Interpolation;
    let cubic = interpolation == Interpolation::CubicSpline;
    let stride = if cubic { 3 * width } else { width };
    let value_of = |k: usize| {
        let start = k * stride + if cubic { width } else { 0 };
        values.get(start..start + width)
    };
    let last = times.len().checked_sub(1)?;
    if time <= times[0] {
        return value_of(0).map(Into::into);
    }
    if time >= times[last] {
        return value_of(last).map(Into::into);
    }
    let k = times.partition_point(|&t| t <= time) - 1;
    let (t0, t1) = (times[k], times[k + 1]);
    let s = (time - t0) / (t1 - t0);
    let (a, b) = (value_of(k)?, value_of(k + 1)?);
    Some(match interpolation {
        Interpolation::Step => a.into(),
        Interpolation::Linear if rotation && width == 4 => {
            let q =
                |v: &[f32]| DQuat::from_xyzw(v[0] as f64, v[1] as f64, v[2] as f64, v[3] as f64);
            let q = q(a).normalize().slerp(q(b).normalize(), s as f64);
            [q.x, q.y, q.z, q.w].map(|x| x as f32).into()
        }
        Interpolation::Linear => a.iter().zip(b).map(|(a, b)| a + s * (b - a)).collect(),
        Interpolation::CubicSpline => {
            let dt = t1 - t0;
            let out_tangent = &values[k * stride + 2 * width..k * stride + 3 * width];
            let in_tangent = &values[(k + 1) * stride..(k + 1) * stride + width];
            let (s2, s3) = (s * s, s * s * s);
            (0..width)
                .map(|c| {
                    (2.0 * s3 - 3.0 * s2 + 1.0) * a[c]
                        + (s3 - 2.0 * s2 + s) * dt * out_tangent[c]
                        + (-2.0 * s3 + 3.0 * s2) * b[c]
                        + (s3 - s2) * dt * in_tangent[c]
                })
                .collect()
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use gltf::animation::Interpolation;

    #[test]
    fn keys_are_sampled_as_the_specification_interpolates_them() {
        let times = [1.0, 2.0];
        let values = [0.0, 10.0, 4.0, 20.0];
        let at = |t, i| sample(&times, &values, 2, i, false, t).unwrap().to_vec();
        // Before the first key and after the last: those keys' values.
        assert_eq!(at(0.0, Interpolation::Linear), [0.0, 10.0]);
        assert_eq!(at(3.0, Interpolation::Linear), [4.0, 20.0]);
        assert_eq!(at(1.25, Interpolation::Linear), [1.0, 12.5]);
        assert_eq!(at(1.75, Interpolation::Step), [0.0, 10.0]);
        // A cubic spline of zero tangents eases: 0.5 at the middle, 0.15625 at a quarter.
        let cubic = [0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let c = |t| sample(&times, &cubic, 1, Interpolation::CubicSpline, false, t).unwrap()[0];
        assert!((c(1.5) - 0.5).abs() < 1e-6 && (c(1.25) - 0.15625).abs() < 1e-6);
        // Rotations: the slerp, a quarter of the way from identity to 90 degrees about z.
        let half = std::f32::consts::FRAC_1_SQRT_2;
        let quats = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, half, half];
        let q = sample(&times, &quats, 4, Interpolation::Linear, true, 1.25).unwrap();
        let angle = 2.0 * (q[2] as f64).atan2(q[3] as f64);
        assert!((angle - std::f64::consts::FRAC_PI_8).abs() < 1e-6, "{q:?}");
    }
}
