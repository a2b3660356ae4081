//! Tangent frames for normal maps: the file's own (glTF `TANGENT`), else MikkTSpace's, computed
//! as Blender and glTF's reference viewers compute them (the `mikktspace` crate), so a normal
//! map baked against Blender's frames bends normals here as it does there.

use crate::assets::image_lookup::UvSet;
use crate::scene::mesh::Mesh;
use glam::{Vec2, Vec3, Vec4};

/// Per triangle of `mesh`, its corners' tangents (xyz along +u; w = ±1, the bitangent being
/// w x normal x tangent, along +v): the mesh's own where it has them, else MikkTSpace's over
/// its positions, corner normals (the face's where it has none) and texture coordinates of
/// `set`, the normal map's (glTF: "the texture coordinates associated with the normal
/// texture"). `None` when the mesh has no texture coordinates, from which tangents follow.
pub fn of(mesh: &Mesh, set: UvSet) -> Option<Vec<[Vec4; 3]>> {
    if !mesh.tangents.is_empty() {
        return Some(mesh.tangents.clone());
    }
    let uvs = match set {
        UvSet::Second if !mesh.uvs1.is_empty() => &mesh.uvs1,
        _ => &mesh.uvs,
    };
    if uvs.is_empty() {
        return None;
    }
    let mut corners = Corners {
        mesh,
        uvs,
        tangents: vec![[Vec4::ZERO; 3]; mesh.triangles.len()],
    };
    // False only for a mesh with no faces, whose tangents are then all zero: never read.
    mikktspace::generate_tangents(&mut corners);
    Some(corners.tangents)
}

/// A mesh as MikkTSpace reads it (triangles of three corners) and where it writes.
struct Corners<'a> {
    mesh: &'a Mesh,
    uvs: &'a [[Vec2; 3]],
    tangents: Vec<[Vec4; 3]>,
}

impl Corners<'_> {
    fn corner(&self, face: usize, vert: usize) -> Vec3 {
        self.mesh.positions[self.mesh.triangles[face][vert] as usize]
    }
}

impl mikktspace::Geometry for Corners<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.triangles.len()
    }
    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.corner(face, vert).to_array()
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        match self.mesh.normals.get(face) {
            Some(normals) => normals[vert].to_array(),
            None => {
                let [a, b, c] = [0, 1, 2].map(|v| self.corner(face, v));
                (b - a).cross(c - a).normalize_or_zero().to_array()
            }
        }
    }
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        self.uvs[face][vert].to_array()
    }
    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        let t = Vec4::from_array(tangent);
        // MikkTSpace gives unit tangents, or zero where the texture coordinates are degenerate.
        self.tangents[face][vert] = if t.is_finite() { t } else { Vec4::ZERO };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square in the xz-plane facing +y, its texture's u along +x and v along -z.
    fn square(uv_flip: bool) -> Mesh {
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(0.0, 0.0, -1.0),
        ];
        let uv = |x: f32, y: f32| Vec2::new(if uv_flip { 1.0 - x } else { x }, y);
        let uvs = [uv(0.0, 0.0), uv(1.0, 0.0), uv(1.0, 1.0), uv(0.0, 1.0)];
        let triangles = vec![[0, 1, 2], [0, 2, 3]];
        let corners = triangles
            .iter()
            .map(|t: &[u32; 3]| Some(t.map(|i| uvs[i as usize])))
            .collect();
        Mesh::with_corners("square", positions, triangles, Vec::new(), corners).unwrap()
    }

    #[test]
    fn tangents_follow_u_and_bitangents_v() {
        let tangents = of(&square(false), UvSet::First).unwrap();
        for corner in tangents.iter().flatten() {
            assert!((corner.truncate() - Vec3::X).length() < 1e-5, "{corner}");
            // Bitangent w (n x t) = w (+y x +x) = -w z: along +v, which runs along -z.
            assert_eq!(corner.w, 1.0);
        }
        // A mirrored texture: tangents along -x, and the bitangent's sign keeps v along -z.
        let mirrored = of(&square(true), UvSet::First).unwrap();
        for corner in mirrored.iter().flatten() {
            assert!((corner.truncate() + Vec3::X).length() < 1e-5, "{corner}");
            assert_eq!(corner.w, -1.0);
        }
    }

    #[test]
    fn no_texture_coordinates_no_tangents() {
        let mesh = Mesh::new(
            "triangle",
            vec![Vec3::ZERO, Vec3::X, Vec3::Z],
            vec![[0, 1, 2]],
        )
        .unwrap();
        assert!(of(&mesh, UvSet::First).is_none());
    }
}
