//! Triangle meshes read from OBJ (the `tobj` crate) and glTF 2.0 (the `gltf` crate) files.
//!
//! A file is read once per (file version, node) while its meshes are held, shared: scene
//! objects are plain data holding an `Arc<Mesh>`, as textures hold images. A
//! file becomes one [`Mesh`] per material it uses (a glTF file's own materials; an OBJ file is
//! one part), in the frame of the file's root (glTF node transforms applied). Triangles keep the
//! file's winding: counter-clockwise seen from the front.

use super::Material;
use crate::assets::inputs::InputFile;
use crate::assets::normal_map::NormalMap;
use glam::{DMat3, DMat4, DVec3, Vec2, Vec3, Vec4};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock, Weak};
use std::time::SystemTime;

/// The triangles of one material of a mesh file.
pub struct Mesh {
    /// The file as the scene file wrote it, the node taken from it, and which of its parts
    /// (materials) this is: scene files are written back with them.
    pub source: String,
    pub node: Option<String>,
    pub part: u32,
    pub positions: Vec<Vec3>,
    /// Vertex indices, counter-clockwise seen from the front. Degenerate (zero-area) triangles
    /// are left out at loading.
    pub triangles: Vec<[u32; 3]>,
    /// Per triangle, its corners' shading normals (unit), where the file gives vertex normals;
    /// empty where it gives none. Corners without a usable normal take the face's.
    pub normals: Vec<[Vec3; 3]>,
    /// Per triangle, its corners' texture coordinates (u across an image, v up it), where the
    /// file gives them; empty where it gives none. Corners without them take (0, 0).
    pub uvs: Vec<[Vec2; 3]>,
    /// Per triangle, its corners' second texture coordinates (glTF TEXCOORD_1), where the file
    /// gives them and a material reads them; empty otherwise. Corners without them take their
    /// first set's.
    pub uvs1: Vec<[Vec2; 3]>,
    /// Per triangle, its corners' linear RGB vertex colours (glTF COLOR_0, each channel in
    /// [0, 1]), where the file gives them; empty where it gives none. Corners without them take
    /// white.
    pub colors: Vec<[Vec3; 3]>,
    /// Per triangle, its corners' tangents (xyz unit along +u, w = ±1 the bitangent's sign; see
    /// `scene::tangents`) where the file gives them all (glTF `TANGENT`); empty otherwise.
    pub tangents: Vec<[Vec4; 3]>,
    /// The file's material for this part (glTF), `None` for OBJ or primitives without one.
    pub material: Option<Material>,
    /// Its name in the file, or its index.
    pub material_name: String,
    /// The largest absolute coordinate (for validating placements).
    pub extent: f32,
    /// How many of the file's triangles were left out as degenerate (of no area in f32).
    pub degenerate: usize,
    /// For a part without a material, why a material library its OBJ file names was not read.
    pub library_refused: Option<String>,
}

/// A mesh's attributes per triangle corner as a file gives them, one entry per triangle
/// (`None` where the file gives none for it); see [`Mesh`] for each.
#[derive(Default)]
pub struct Corners {
    pub normals: Vec<Option<[Vec3; 3]>>,
    pub uvs: Vec<Option<[Vec2; 3]>>,
    pub uvs1: Vec<Option<[Vec2; 3]>>,
    pub tangents: Vec<Option<[Vec4; 3]>>,
    pub colors: Vec<Option<[Vec3; 3]>>,
}

impl std::fmt::Debug for Mesh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Mesh({} part {}: {} triangles)",
            self.source,
            self.part,
            self.triangles.len()
        )
    }
}

impl PartialEq for Mesh {
    /// Meshes are loaded once per file and shared: one is equal only to itself.
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self, other)
    }
}

/// Most triangles one file may hold (their indices are packed in 28 bits on the GPU).
pub const MAX_TRIANGLES: usize = 1 << 27;
/// Largest texture coordinate a mesh may have.
pub const MAX_UV: f32 = 1e7;
/// Largest mesh file read (a path may name anything; a file of 2^27 triangles as OBJ text
/// takes about 6 GB).
pub const MAX_MESH_FILE_BYTES: u64 = 8 << 30;

impl Mesh {
    /// A mesh from vertices and triangles: every index must name a vertex, every coordinate be
    /// finite; zero-area triangles are dropped.
    pub fn new(
        source: &str,
        positions: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Self, String> {
        Self::with_normals(source, positions, triangles, Vec::new())
    }

    /// A mesh as [`Mesh::new`], with its triangles' corner normals (`normals`: one entry per
    /// triangle, `None` where the file gives none; all `None` or empty: a flat-shaded mesh).
    pub fn with_normals(
        source: &str,
        positions: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
        normals: Vec<Option<[Vec3; 3]>>,
    ) -> Result<Self, String> {
        Self::with_corners(source, positions, triangles, normals, Vec::new())
    }

    /// A mesh as [`Mesh::with_normals`], with its triangles' corner texture coordinates too
    /// (`uvs`: one entry per triangle, `None` where the file gives none).
    pub fn with_corners(
        source: &str,
        positions: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
        normals: Vec<Option<[Vec3; 3]>>,
        uvs: Vec<Option<[Vec2; 3]>>,
    ) -> Result<Self, String> {
        let corners = Corners {
            normals,
            uvs,
            ..Corners::default()
        };
        Self::with_attributes(source, positions, triangles, corners)
    }

    /// A mesh as [`Mesh::with_corners`], with every attribute of its triangles' corners
    /// (tangents kept only where every triangle has them).
    pub fn with_attributes(
        source: &str,
        positions: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
        corners: Corners,
    ) -> Result<Self, String> {
        let Corners {
            normals,
            uvs,
            uvs1,
            tangents,
            colors,
        } = corners;
        let smooth = normals.iter().any(Option::is_some);
        let textured = uvs.iter().any(Option::is_some);
        let textured1 = uvs1.iter().any(Option::is_some);
        let coloured = colors.iter().any(Option::is_some);
        if let Some(c) = colors.iter().flatten().flatten().find(|c| !c.is_finite()) {
            return Err(format!("mesh {source} has a non-finite vertex colour {c}"));
        }
        let tangent_frames =
            tangents.len() == triangles.len() && tangents.iter().all(Option::is_some);
        let every_uv = || uvs.iter().chain(&uvs1).flatten().flatten();
        if let Some(uv) = every_uv().find(|uv| !uv.is_finite()) {
            return Err(format!(
                "mesh {source} has a non-finite texture coordinate {uv}"
            ));
        }
        // Beyond, f32 resolves no texel and tangents' products overflow.
        if let Some(uv) = every_uv().find(|uv| uv.abs().max_element() > MAX_UV) {
            return Err(format!(
                "mesh {source} has a texture coordinate {uv} (after any KHR_texture_transform) beyond {MAX_UV:e}, where f32 resolves no texel"
            ));
        }
        if let Some(t) = tangents.iter().flatten().flatten().find(|t| !t.is_finite()) {
            return Err(format!("mesh {source} has a non-finite tangent {t}"));
        }
        if let Some(p) = positions.iter().find(|p| !p.is_finite()) {
            return Err(format!("mesh {source} has a non-finite vertex {p}"));
        }
        let n = positions.len() as u32;
        if let Some(t) = triangles.iter().find(|t| t.iter().any(|&i| i >= n)) {
            return Err(format!(
                "mesh {source} has a triangle {t:?} naming a vertex beyond its {n}"
            ));
        }
        let face = |[a, b, c]: [u32; 3]| {
            let [a, b, c] = [a, b, c].map(|i| positions[i as usize].as_dvec3());
            (b - a).cross(c - a)
        };
        let mut kept_normals = Vec::new();
        let mut kept_uvs = Vec::new();
        let mut kept_uvs1 = Vec::new();
        let mut kept_colors = Vec::new();
        let mut kept_tangents = Vec::new();
        let given = triangles.len();
        let triangles: Vec<[u32; 3]> = triangles
            .into_iter()
            .enumerate()
            .filter_map(|(i, t)| {
                let face = face(t);
                if !(face.length_squared() > 0.0) {
                    return None;
                }
                if smooth {
                    let face = face.normalize().as_vec3();
                    let corners = normals.get(i).copied().flatten().unwrap_or([face; 3]);
                    kept_normals.push(corners.map(|n| {
                        let n = n.normalize_or_zero();
                        if n == Vec3::ZERO { face } else { n }
                    }));
                }
                if textured {
                    kept_uvs.push(uvs.get(i).copied().flatten().unwrap_or([Vec2::ZERO; 3]));
                }
                if textured1 {
                    let first = uvs.get(i).copied().flatten();
                    let corners = uvs1.get(i).copied().flatten().or(first);
                    kept_uvs1.push(corners.unwrap_or([Vec2::ZERO; 3]));
                }
                if coloured {
                    let corners = colors.get(i).copied().flatten().unwrap_or([Vec3::ONE; 3]);
                    kept_colors.push(corners.map(|c| c.clamp(Vec3::ZERO, Vec3::ONE)));
                }
                if let Some(Some(corners)) = tangent_frames.then(|| tangents[i]) {
                    // A tangent of no length bends nothing (`cpu::intersect::normal_mapped`).
                    kept_tangents.push(corners.map(|t| {
                        let sign = if t.w < 0.0 { -1.0 } else { 1.0 };
                        t.truncate().normalize_or_zero().extend(sign)
                    }));
                }
                Some(t)
            })
            .collect();
        if triangles.len() > MAX_TRIANGLES {
            return Err(format!(
                "mesh {source} has {} triangles, more than the {MAX_TRIANGLES} rt-gpu takes",
                triangles.len()
            ));
        }
        let degenerate = given - triangles.len();
        let extent = positions
            .iter()
            .fold(0.0f32, |m, p| m.max(p.abs().max_element()));
        Ok(Mesh {
            source: source.to_string(),
            node: None,
            part: 0,
            positions,
            triangles,
            normals: kept_normals,
            uvs: kept_uvs,
            uvs1: kept_uvs1,
            colors: kept_colors,
            tangents: kept_tangents,
            material: None,
            material_name: String::new(),
            extent,
            degenerate,
            library_refused: None,
        })
    }

    pub fn shared(self) -> Arc<Mesh> {
        Arc::new(self)
    }
}

/// Reads the mesh file at `path` (`.obj`, `.gltf` or `.glb`), or one node of a glTF file and its
/// children; `source` is the path as the scene wrote it. Errors are one line naming the file
/// (and for OBJ the line).
pub fn load(path: &Path, source: &str, node: Option<&str>) -> Result<Vec<Arc<Mesh>>, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot read mesh {source}: {e}"))?;
    if !meta.is_file() {
        return Err(format!("mesh {source} is not a file"));
    }
    let canonical = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    let modified = meta.modified().unwrap_or(std::time::UNIX_EPOCH);
    let key = (canonical, meta.len(), modified, node.map(str::to_string));
    let cache = FILES.get_or_init(Default::default);
    let held = cache
        .lock()
        .map_err(|_| "mesh cache poisoned")?
        .get(&key)
        .and_then(|(parts, inputs, versions)| {
            // The files its reading read (an MTL library, a glTF's buffers and images) as they
            // were: one edited since is read again (the viewer's reload shows the edit).
            if !versions
                .iter()
                .all(|v| file_version(&v.0).as_ref() == Some(v))
            {
                return None;
            }
            let parts: Option<Vec<Arc<Mesh>>> = parts.iter().map(Weak::upgrade).collect();
            Some((parts?, inputs.clone()))
        });
    if let Some((parts, inputs)) = held {
        inputs.iter().for_each(crate::assets::inputs::note);
        return Ok(parts);
    }
    let (parts, inputs) = crate::assets::inputs::recorded(|| read_parts(path, source, node));
    let parts = parts?;
    let mut cache = cache.lock().map_err(|_| "mesh cache poisoned")?;
    // Meshes no scene holds any more are gone: so are their entries.
    cache.retain(|_, (parts, ..)| parts.iter().all(|p| p.strong_count() > 0));
    let versions = inputs
        .iter()
        .filter_map(|i| file_version(&i.path))
        .collect();
    cache.insert(
        key,
        (parts.iter().map(Arc::downgrade).collect(), inputs, versions),
    );
    Ok(parts)
}

/// The path, size and modification time of the file at `path`, if it can be read.
fn file_version(path: &Path) -> Option<(PathBuf, u64, std::time::SystemTime)> {
    let meta = std::fs::metadata(path).ok()?;
    Some((path.to_path_buf(), meta.len(), meta.modified().ok()?))
}

/// How many mesh files (or nodes of one) are held by scenes at present: what a reloaded scene
/// frees shows here.
pub fn files_held() -> usize {
    let cache = FILES.get_or_init(Default::default);
    let cache = cache
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    let held = |parts: &Vec<Weak<Mesh>>| parts.iter().all(|p| p.strong_count() > 0);
    cache.values().filter(|(parts, ..)| held(parts)).count()
}

/// A file as it was when read (its path, size and modification time), and the node read.
type FileVersion = (PathBuf, u64, std::time::SystemTime, Option<String>);

/// The parts read from files, while a scene holds them, and the files their reading read (the
/// file, its buffers, its images): a file loaded again while held is not read again, and parts
/// nothing holds are freed.
static FILES: OnceLock<Mutex<Held>> = OnceLock::new();

/// Each file's parts while held, the files their reading read, and those files' versions.
type Held = HashMap<
    FileVersion,
    (
        Vec<Weak<Mesh>>,
        Vec<InputFile>,
        Vec<(PathBuf, u64, SystemTime)>,
    ),
>;

/// The parts of the mesh file at `path` (see [`load`]).
fn read_parts(path: &Path, source: &str, node: Option<&str>) -> Result<Vec<Arc<Mesh>>, String> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let mut parts = match extension.as_deref() {
        Some("obj") => {
            if node.is_some() {
                return Err(format!(
                    "mesh {source}: `node` selects a glTF node; an OBJ file has none"
                ));
            }
            read_obj(path, source)?
        }
        Some("gltf" | "glb") => read_gltf(path, source, node)?,
        _ => {
            return Err(format!(
                "mesh {source}: unknown format (rt-gpu reads .obj, .gltf and .glb)"
            ));
        }
    };
    let degenerate: usize = parts.iter().map(|m| m.degenerate).sum();
    parts.retain(|m| !m.triangles.is_empty());
    if parts.is_empty() && degenerate > 0 {
        return Err(format!(
            "mesh {source} has no triangles of any area: its {degenerate} triangles' corners coincide in f32 (points far from the origin collapse: move the model nearer it)"
        ));
    }
    if parts.is_empty() {
        return Err(format!("mesh {source} has no triangles"));
    }
    let parts: Vec<Arc<Mesh>> = parts
        .into_iter()
        .enumerate()
        .map(|(i, mut m)| {
            m.part = i as u32;
            m.node = node.map(str::to_string);
            m.shared()
        })
        .collect();
    Ok(parts)
}

fn read_obj(path: &Path, source: &str) -> Result<Vec<Mesh>, String> {
    let text = obj_text(path, source)?;
    match super::obj_parallel::read(&text) {
        Some(read) => Ok(vec![subset_mesh(source, read)?]),
        None => read_obj_text(path, source, &text),
    }
}

/// The mesh of a file `obj_parallel` read: one part, without a material, as tobj's path makes
/// it of such a file.
pub(super) fn subset_mesh(
    source: &str,
    read: super::obj_parallel::ObjTriangles,
) -> Result<Mesh, String> {
    let mut mesh = Mesh::with_corners(
        source,
        read.positions,
        read.triangles,
        read.normals,
        read.uvs,
    )?;
    mesh.material_name = "default".into();
    Ok(mesh)
}

/// An OBJ file's `text` read by tobj, its faces checked beside it; `path` locates its .mtl.
pub(super) fn read_obj_text(path: &Path, source: &str, text: &str) -> Result<Vec<Mesh>, String> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    // The faces' check and tobj's parse read the text side by side, so the check adds no wall
    // time. The check comes first in what a file is told: tobj trusts the indices, so on a
    // file the check refuses its result (or panic) is dropped unread.
    let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    // The material library is read on another thread: what it reads is the scene's too.
    let recorders = crate::assets::inputs::Recorders::current();
    let refused = std::sync::Mutex::new(Vec::new());
    let parse = || {
        recorders.install(|| {
            let mut reader = std::io::Cursor::new(text.as_bytes());
            tobj::load_obj_buf(&mut reader, &options, |mtl| {
                read_mtl(&base_dir, mtl, source, &refused)
            })
        })
    };
    let (checked, parsed) = rayon::join(|| check_obj_faces(text), || crate::caught_quietly(parse));
    checked.map_err(|(line, what)| format!("cannot read mesh {source}:{line}: {what}"))?;
    let parsed = parsed.ok_or_else(|| {
        format!("cannot read mesh {source}: the OBJ reader failed on it (a malformed file)")
    })?;
    let (models, materials) = parsed.map_err(|e| {
        let at = obj_error_line(text, &e).map_or(String::new(), |l| format!(":{l}"));
        format!("cannot read mesh {source}{at}: {}", obj_error(&e))
    })?;
    // A missing or unreadable .mtl leaves the file without materials (the scene names one).
    let materials = materials.unwrap_or_default();
    // Parts by material (None: faces without one), in order of first use.
    let mut parts: Vec<Part> = Vec::new();
    for model in models {
        let mesh = &model.mesh;
        let key = mesh.material_id.filter(|&i| i < materials.len());
        let (scale, offset) = match key {
            Some(k) => mtl_uv_transform(&materials[k], source)?,
            None => (Vec2::ONE, Vec2::ZERO),
        };
        let part = part_of(&mut parts, key);
        let base = part.positions.len() as u32;
        let faces = mesh.indices.len() / 3;
        // Faces name their own normals (`f v//vn`) and texture coordinates (`f v/vt`); `tobj`
        // gives them per corner.
        let vn = |i: u32| {
            let n = mesh.normals.get(3 * i as usize..3 * i as usize + 3)?;
            Some(Vec3::new(n[0], n[1], n[2]))
        };
        if mesh.normal_indices.len() == mesh.indices.len() {
            part.corners
                .normals
                .extend(mesh.normal_indices.chunks_exact(3).map(|c| {
                    let [a, b, c] = [vn(c[0])?, vn(c[1])?, vn(c[2])?];
                    Some([a, b, c])
                }));
        } else {
            part.corners
                .normals
                .extend(std::iter::repeat_n(None, faces));
        }
        let vt = |i: u32| {
            let uv = mesh.texcoords.get(2 * i as usize..2 * i as usize + 2)?;
            Some(Vec2::new(uv[0], uv[1]) * scale + offset)
        };
        if mesh.texcoord_indices.len() == mesh.indices.len() {
            part.corners
                .uvs
                .extend(mesh.texcoord_indices.chunks_exact(3).map(|c| {
                    let [a, b, c] = [vt(c[0])?, vt(c[1])?, vt(c[2])?];
                    Some([a, b, c])
                }));
        } else {
            part.corners.uvs.extend(std::iter::repeat_n(None, faces));
        }
        part.positions.extend(
            mesh.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        part.triangles.extend(
            mesh.indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    let folder = path.parent().unwrap_or(Path::new(""));
    let refused = refused.into_inner().unwrap_or_else(|p| p.into_inner());
    parts
        .into_iter()
        .map(|part| {
            let key = part.key;
            let mut mesh = part.into_mesh(source)?;
            match key.map(|k| &materials[k]) {
                Some(m) => {
                    mesh.material = Some(mtl_material(m, folder, source)?);
                    mesh.material_name = m.name.clone();
                }
                None => {
                    mesh.material_name = "default".into();
                    mesh.library_refused = refused.first().cloned();
                }
            }
            Ok(mesh)
        })
        .collect()
}

/// Largest .mtl file read.
const MAX_MTL_BYTES: u64 = 16 << 20;

/// The material libraries an OBJ file's `mtllib` line names, beside it: a name with spaces if
/// a file has it, else each word a library (OBJ lets one line name several), merged. Only a
/// relative path that stays in the OBJ's folder and names a regular file of at most 16 MiB is
/// opened (an `mtllib` line may name anything, a device or a FIFO among them); why a library
/// is not read goes to `refused`, for the message of a part left without its material.
fn read_mtl(
    base_dir: &Path,
    name: &Path,
    source: &str,
    refused: &std::sync::Mutex<Vec<String>>,
) -> tobj::MTLLoadResult {
    let whole = name.to_string_lossy();
    let names: Vec<&str> = if base_dir.join(name).exists() || !whole.contains(char::is_whitespace) {
        vec![whole.as_ref()]
    } else {
        whole.split_whitespace().collect()
    };
    let mut materials = Vec::new();
    let mut index = tobj::MTLLoadResult::Ok(Default::default())
        .map(|(_, index)| index)
        .unwrap_or_default();
    for library in names {
        match read_one_mtl(base_dir, Path::new(library), source) {
            Ok(Ok((mut read, map))) => {
                let offset = materials.len();
                materials.append(&mut read);
                index.extend(map.into_iter().map(|(k, v)| (k, v + offset)));
            }
            Ok(Err(_)) => {}
            Err(why) => refused
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .push(format!(
                    "its material library \"{}\" {why}",
                    super::file::quoted(library)
                )),
        }
    }
    Ok((materials, index))
}

/// One material library (see [`read_mtl`]), or why it is not read.
fn read_one_mtl(base_dir: &Path, name: &Path, source: &str) -> Result<tobj::MTLLoadResult, String> {
    use std::path::Component;
    if !name.components().all(|c| matches!(c, Component::Normal(_))) {
        return Err(
            "is not a relative path inside the OBJ file's folder (rt-gpu reads libraries beside the file or below it)".into(),
        );
    }
    let path = base_dir.join(name);
    let shown = Path::new(source)
        .parent()
        .unwrap_or(Path::new(""))
        .join(name);
    let (bytes, _) = crate::assets::inputs::read(&path, &shown.to_string_lossy(), MAX_MTL_BYTES)
        .map_err(|e| format!("cannot be read: {e}"))?;
    // tobj panics on some malformed lines (`Kd 1 2`): such a library reads as malformed.
    match crate::caught_quietly(|| tobj::load_mtl_buf(&mut std::io::Cursor::new(bytes))) {
        Some(Ok(read)) => Ok(Ok(read)),
        Some(Err(e)) => Err(format!("is malformed ({e})")),
        None => Err("is malformed (a line the MTL reader cannot read)".into()),
    }
}

/// An MTL material as rt-gpu's, the way Blender's OBJ exporter (3.4) writes its Principled
/// BSDF: emission `Ke` (strength folded in) -> a two-sided `light`; else `pbr` with base colour
/// `Kd`, or the image `map_Kd` (in `folder`, the OBJ file's, or below it: OBJ's `vt` has v up
/// the image), roughness `Pr` or 1 - sqrt(`Ns` / 1000) (Blender writes Ns = (1 - roughness)^2 x
/// 1000), metallic `Pm`, or 1 for `illum 3` (Blender's mark of a metallic surface), ior `Ni`,
/// and a normal map `map_Bump` or `norm` (linear, its `-bm` option the scale: what Blender
/// writes for a Normal Map node), and `d` below 1 as stochastic opacity (glTF's BLEND). Not
/// read: transmission (Blender does not write it), other maps.
fn mtl_material(m: &tobj::Material, folder: &Path, source: &str) -> Result<Material, String> {
    use crate::material::{Light, Pbr};
    let colour = |c: Option<[f32; 3]>| c.map(Vec3::from_array).filter(|c| c.is_finite());
    if let Some(ke) = m.emissive
        && !ke.iter().all(|x| x.is_finite() && *x >= 0.0)
    {
        return Err(format!(
            "mesh {source}: material \"{}\" has an emission Ke of {ke:?}: each must be a finite number >= 0",
            m.name
        ));
    }
    // `d` below 1 (Blender writes the Principled BSDF's alpha there): see-through, as glTF's
    // BLEND, emitters too.
    let dissolve =
        m.dissolve
            .filter(|d| d.is_finite() && *d < 1.0)
            .map(|d| crate::assets::alpha::Alpha {
                mode: crate::assets::alpha::AlphaMode::Blend,
                factor: d.max(0.0),
                image: None,
            });
    let emission = colour(m.emissive).unwrap_or(Vec3::ZERO);
    if emission.max_element() > 0.0 {
        let light = Material::Light(Light {
            radiance: emission.into(),
            strength: 1.0,
            two_sided: true,
            alpha: dissolve,
        });
        light
            .validate()
            .map_err(|e| format!("mesh {source}: material \"{}\"'s emission Ke: {e}", m.name))?;
        return Ok(light);
    }
    let param = |key: &str| {
        m.unknown_param
            .get(key)
            .and_then(|v| v.trim().parse::<f32>().ok())
            .filter(|x| x.is_finite())
    };
    let unit = |x: f32| x.clamp(0.0, 1.0);
    let roughness = param("Pr").unwrap_or_else(|| {
        let ns = m.shininess.filter(|x| x.is_finite()).unwrap_or(0.0);
        1.0 - (ns / 1000.0).clamp(0.0, 1.0).sqrt()
    });
    let metallic = param("Pm").unwrap_or(if m.illumination_model == Some(3) {
        1.0
    } else {
        0.0
    });
    let base = match &m.diffuse_texture {
        Some(map) => crate::assets::texture::Texture::Image(mtl_image(
            map, "map_Kd", true, folder, source, &m.name,
        )?),
        None => colour(m.diffuse)
            .unwrap_or(Vec3::splat(0.8))
            .clamp(Vec3::ZERO, Vec3::ONE)
            .into(),
    };
    let bump = (m.normal_texture.as_ref().map(|map| (map, "map_Bump")))
        .or_else(|| m.unknown_param.get("norm").map(|map| (map, "norm")));
    let normal_map = match bump {
        Some((map, slot)) => {
            let image = mtl_image(map, slot, false, folder, source, &m.name)?;
            // tobj files `bump` height maps under map_Bump too; grey everywhere gives them away.
            if image
                .texels
                .chunks_exact(3)
                .all(|t| t[0] == t[1] && t[1] == t[2])
            {
                return Err(format!(
                    "mesh {source}: material \"{}\"'s {slot} image {} is grey, a height (bump) map: rt-gpu reads tangent-space normal maps only",
                    m.name, image.source
                ));
            }
            let (options, _) = map_options(map)?;
            let scale = match options.iter().find(|(flag, _)| *flag == "-bm") {
                Some((_, values)) => values[0].parse::<f32>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
                    format!(
                        "mesh {source}: material \"{}\"'s {slot} has a -bm (normal map strength) of {}, not a finite number",
                        m.name, values[0]
                    )
                })?,
                None => 1.0,
            };
            let map = NormalMap { image, scale };
            map.validate()
                .map_err(|e| format!("mesh {source}: material \"{}\": {e}", m.name))?;
            Some(map)
        }
        None => None,
    };
    Ok(Material::Pbr(
        Pbr::new(
            base,
            unit(metallic),
            unit(roughness),
            m.optical_density
                .filter(|i| i.is_finite())
                .unwrap_or(1.5)
                .clamp(1.0, 4.0),
            0.0,
        )
        .with_normal_map(normal_map)
        .with_alpha(dissolve),
    ))
}

/// The scale and offset (`-s u v`, `-o u v`: what Blender's exporter writes for a Mapping
/// node) that `m`'s maps apply to texture coordinates, `vt * scale + offset`; one for all its
/// maps (an error where they differ, since rt-gpu applies it to the mesh's coordinates).
fn mtl_uv_transform(m: &tobj::Material, source: &str) -> Result<(Vec2, Vec2), String> {
    let option = |options: &[MapOption], flag: &str, default: f32| {
        let (_, values) = options.iter().find(|(f, _)| *f == flag)?;
        let mut values = values.iter().map(|w| w.parse::<f32>().unwrap_or(f32::NAN));
        let u = values.next()?;
        Some(Vec2::new(u, values.next().unwrap_or(default)))
    };
    let maps = [m.diffuse_texture.as_deref(), m.normal_texture.as_deref()]
        .into_iter()
        .chain([m.unknown_param.get("norm").map(String::as_str)])
        .flatten();
    let mut found: Option<(Vec2, Vec2)> = None;
    for map in maps {
        let (options, _) = map_options(map).map_err(|e| {
            format!(
                "mesh {source}: material \"{}\"'s map \"{map}\": {e}",
                m.name
            )
        })?;
        let transform = (
            option(&options, "-s", 1.0).unwrap_or(Vec2::ONE),
            option(&options, "-o", 0.0).unwrap_or(Vec2::ZERO),
        );
        if !(transform.0.is_finite() && transform.1.is_finite()) {
            return Err(format!(
                "mesh {source}: material \"{}\"'s map \"{map}\" has a scale or offset that is not finite",
                m.name
            ));
        }
        match found {
            Some(other) if other != transform => {
                return Err(format!(
                    "mesh {source}: material \"{}\"'s maps scale or offset texture coordinates differently (-s, -o); rt-gpu applies one per material",
                    m.name
                ));
            }
            _ => found = Some(transform),
        }
    }
    Ok(found.unwrap_or((Vec2::ONE, Vec2::ZERO)))
}

/// An option of an MTL map statement: its flag and its values.
type MapOption<'a> = (&'a str, Vec<&'a str>);

/// An MTL map statement's options (each flag with its values) and the file it names: what
/// follows the options, spaces included (`map_Kd -s 2 2 1 my tex.png` names `my tex.png`). The
/// options and their values are the MTL specification's.
fn map_options(map: &str) -> Result<(Vec<MapOption<'_>>, String), String> {
    let words: Vec<&str> = map.split_whitespace().collect();
    let mut options = Vec::new();
    let mut i = 0;
    // Options are known flags: a file name may start with '-' only after them.
    while let Some(&flag) = words
        .get(i)
        .filter(|w| w.starts_with('-') && is_map_flag(w))
    {
        // (least, most) values; numbers beyond the least are taken while they parse.
        let (least, most) = match flag {
            "-blendu" | "-blendv" | "-bm" | "-boost" | "-cc" | "-clamp" | "-imfchan"
            | "-texres" | "-type" => (1, 1),
            "-mm" => (2, 2),
            "-o" | "-s" | "-t" => (1, 3),
            _ => return Err(format!("unknown option {flag}")),
        };
        let mut values = Vec::new();
        while values.len() < most
            && let Some(&value) = words.get(i + 1 + values.len())
            && (values.len() < least || value.parse::<f32>().is_ok())
        {
            values.push(value);
        }
        if values.len() < least {
            return Err(format!("option {flag} lacks its value"));
        }
        i += 1 + values.len();
        options.push((flag, values));
    }
    // The name as written, its inner spaces kept: from its first word's place in `map`.
    let name = match words.get(i) {
        Some(first) => map[first.as_ptr() as usize - map.as_ptr() as usize..].trim_end(),
        None => "",
    };
    Ok((options, name.to_string()))
}

/// The MTL specification's options of a map statement.
fn is_map_flag(word: &str) -> bool {
    matches!(
        word,
        "-blendu"
            | "-blendv"
            | "-bm"
            | "-boost"
            | "-cc"
            | "-clamp"
            | "-imfchan"
            | "-texres"
            | "-type"
            | "-mm"
            | "-o"
            | "-s"
            | "-t"
    )
}

/// The image an MTL map `slot` names (`map` after its options: tobj keeps `-o u v` and the like
/// in the string): a relative path inside the OBJ file's `folder`, decoded from sRGB where
/// `srgb` (colours).
fn mtl_image(
    map: &str,
    slot: &str,
    srgb: bool,
    folder: &Path,
    source: &str,
    material: &str,
) -> Result<std::sync::Arc<crate::assets::image::Image>, String> {
    use std::path::Component;
    let (_, name) = map_options(map)
        .map_err(|e| format!("mesh {source}: material \"{material}\"'s {slot} \"{map}\": {e}"))?;
    let name = name.as_str();
    let relative = Path::new(name);
    if name.is_empty()
        || !relative
            .components()
            .all(|c| matches!(c, Component::Normal(_)))
    {
        return Err(format!(
            "mesh {source}: material \"{material}\"'s {slot} \"{map}\" is not a relative path inside the OBJ file's folder (rt-gpu reads images beside the file or below it)"
        ));
    }
    let shown = Path::new(source)
        .parent()
        .unwrap_or(Path::new(""))
        .join(relative);
    crate::assets::image::load_as(&folder.join(relative), &shown.to_string_lossy(), srgb)
}

/// An OBJ file's text: UTF-8, or Latin-1 (which some exporters write; OBJ's syntax is ASCII, so
/// only names and comments can differ). UTF-16 is refused with what to do.
fn obj_text(path: &Path, source: &str) -> Result<String, String> {
    let (bytes, _) = crate::assets::inputs::read(path, source, MAX_MESH_FILE_BYTES)
        .map_err(|e| format!("cannot read mesh {source}: {e}"))?;
    if bytes.starts_with(&[0xff, 0xfe]) || bytes.starts_with(&[0xfe, 0xff]) {
        return Err(format!(
            "cannot read mesh {source}: it is UTF-16 text; save it as UTF-8 (or ASCII)"
        ));
    }
    Ok(match String::from_utf8(bytes) {
        Ok(text) => text,
        Err(e) => e.into_bytes().iter().map(|&b| b as char).collect(),
    })
}

/// Checks that every face names vertices, texture coordinates and normals that exist by the
/// time it is read, counting negative (relative) indices back from there: tobj trusts them
/// (and overflows on far negative ones). The error is the 1-based line and what is wrong.
fn check_obj_faces(text: &str) -> Result<(), (usize, String)> {
    let mut counts = [0i64; 3]; // v, vt, vn
    for (number, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => counts[0] += 1,
            Some("vt") => counts[1] += 1,
            Some("vn") => counts[2] += 1,
            Some("f") => {
                for corner in words {
                    for (k, index) in corner.split('/').take(3).enumerate() {
                        if index.is_empty() && k > 0 {
                            continue;
                        }
                        let valid = index
                            .parse::<i64>()
                            .is_ok_and(|i| i != 0 && i.unsigned_abs() <= counts[k] as u64);
                        if !valid {
                            let what = ["vertex (v)", "texture coordinate (vt)", "normal (vn)"][k];
                            return Err((
                                number + 1,
                                format!("a face (f) names a {what} `{index}` that does not exist"),
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

fn obj_error(e: &tobj::LoadError) -> String {
    use tobj::LoadError::*;
    match e {
        OpenFileFailed => "cannot open the file".into(),
        ReadError => "cannot read the file".into(),
        PositionParseError => "a vertex position (v) is not three numbers".into(),
        FaceParseError => "a face (f) is not a list of vertex indices".into(),
        FaceVertexOutOfBounds => "a face (f) names a vertex that does not exist".into(),
        InvalidPolygon => "a face (f) has fewer than three vertices".into(),
        ColorParseError => {
            "a vertex (v) is not x y z or x y z r g b (three numbers, or six with a colour)".into()
        }
        other => other.to_string(),
    }
}

/// The line a tobj error is about, found by reading the file the way tobj does (it reports no
/// line itself): the first position or face line that is malformed.
fn obj_error_line(text: &str, e: &tobj::LoadError) -> Option<usize> {
    use tobj::LoadError::*;
    let mut vertices = 0i64;
    for (number, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match (words.next(), e) {
            (Some("v"), _) => {
                let numbers: Vec<&str> = words.collect();
                let ok = numbers
                    .iter()
                    .take(3)
                    .filter(|w| w.parse::<f32>().is_ok())
                    .count()
                    == 3;
                if !ok && matches!(e, PositionParseError) {
                    return Some(number + 1);
                }
                // tobj takes a fourth number as w, and colours only as three more.
                if matches!(e, ColorParseError) && ![3, 4, 6].contains(&numbers.len()) {
                    return Some(number + 1);
                }
                vertices += 1;
            }
            (Some("f"), FaceParseError | FaceVertexOutOfBounds | InvalidPolygon) => {
                let corners: Vec<&str> = words.collect();
                let bad_index = corners.iter().any(|c| {
                    match c.split('/').next().and_then(|i| i.parse::<i64>().ok()) {
                        None => true,
                        Some(i) => i == 0 || i > vertices || -i > vertices,
                    }
                });
                if corners.len() < 3 || bad_index {
                    return Some(number + 1);
                }
            }
            _ => {}
        }
    }
    None
}

/// The triangles of one material of a file as read, per triangle with its corner normals and
/// texture coordinates where the file gives them.
#[derive(Default)]
struct Part {
    /// The file material's index (`None`: faces without one).
    key: Option<usize>,
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    corners: Corners,
}

impl Part {
    fn into_mesh(self, source: &str) -> Result<Mesh, String> {
        Mesh::with_attributes(source, self.positions, self.triangles, self.corners)
    }
}

/// The part of material `key`, added (empty) on its first use.
fn part_of(parts: &mut Vec<Part>, key: Option<usize>) -> &mut Part {
    let at = match parts.iter().position(|p| p.key == key) {
        Some(at) => at,
        None => {
            parts.push(Part {
                key,
                ..Part::default()
            });
            parts.len() - 1
        }
    };
    &mut parts[at]
}

/// Reads a glTF file, checked first (`gltf_check`); a panic inside the `gltf` crate, which
/// should no longer happen, is one line naming the file too.
fn read_gltf(path: &Path, source: &str, node: Option<&str>) -> Result<Vec<Mesh>, String> {
    crate::caught_quietly(|| read_checked_gltf(path, source, node)).unwrap_or_else(|| {
        Err(format!(
            "cannot read mesh {source}: the glTF reader failed on it (a malformed file)"
        ))
    })
}

fn read_checked_gltf(path: &Path, source: &str, node: Option<&str>) -> Result<Vec<Mesh>, String> {
    use super::gltf_check;
    let (bytes, _) = crate::assets::inputs::read(path, source, MAX_MESH_FILE_BYTES)
        .map_err(|e| format!("cannot read mesh {source}: {e}"))?;
    gltf_check::check_container(&bytes, path, source)?;
    let gltf::Gltf { document, blob } = gltf_check::parse(&bytes, source)?;
    drop(bytes);
    let buffers = gltf_check::read_buffers(&document, blob, path.parent(), source)?;
    let lengths: Vec<usize> = buffers.iter().map(|b| b.0.len()).collect();
    gltf_check::check_document(document.as_json(), &lengths, source)?;
    let pose = super::gltf_pose::Pose::new(&document, &buffers, source)?;
    let roots: Vec<gltf::Node> = match node {
        Some(name) => match document.nodes().find(|n| n.name() == Some(name)) {
            Some(n) if document.nodes().filter(|m| m.name() == Some(name)).count() > 1 => {
                return Err(format!(
                    "mesh {source} has several nodes named \"{}\" (node {} among them): rename them apart to pick one",
                    super::file::quoted(name),
                    n.index()
                ));
            }
            Some(n) => vec![n],
            None => {
                let names: Vec<&str> = document.nodes().filter_map(|n| n.name()).collect();
                return Err(format!(
                    "mesh {source} has no node named \"{}\" (nodes: {})",
                    super::file::quoted(name),
                    super::gltf_scene::listed(&names)
                ));
            }
        },
        None => match document
            .default_scene()
            .or_else(|| document.scenes().next())
        {
            Some(scene) => scene.nodes().collect(),
            None => return Err(format!("mesh {source} has no scene")),
        },
    };
    // Where skinned primitives, posed in the scene's coordinates, lie in the reader's.
    let skin_frame = match (node, roots.first()) {
        (Some(_), Some(root)) => pose.scene_frame(root),
        _ => DMat4::IDENTITY,
    };
    // Parts by glTF material (None: primitives without one), in order of first use.
    let mut parts: Vec<Part> = Vec::new();
    // Vertices and triangles placed so far, in every part: nodes and instances may place one
    // mesh many times, so the file's limits are checked as they grow.
    let (mut placed_vertices, mut placed_triangles) = (0usize, 0usize);
    let mut stack: Vec<(gltf::Node, DMat4)> =
        roots.into_iter().map(|n| (n, DMat4::IDENTITY)).collect();
    // Finite: `check_document` found the nodes to be trees.
    while let Some((n, parent)) = stack.pop() {
        let node_world = parent * pose.local(&n);
        // Points and lines are not drawn (`gltf_scene::read_extras` notes them).
        let drawn: Vec<gltf::Primitive> = n
            .mesh()
            .map(|m| m.primitives().filter(|p| is_triangles(p.mode())).collect())
            .unwrap_or_default();
        // Each instance (EXT_mesh_gpu_instancing; one without it) placed as a node would be.
        let instances = if drawn.is_empty() {
            super::gltf_instancing::Instances::none()
        } else {
            super::gltf_instancing::instances(
                &n,
                &document,
                |b| buffers.get(b.index()).map(|d| &d.0[..]),
                source,
            )?
        };
        for i in 0..instances.len() {
            let world = node_world * instances.transform(i)?;
            let flip = world.determinant() < 0.0;
            for primitive in &drawn {
                let mode = primitive.mode();
                let buffer = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
                let reader = primitive.reader(buffer);
                // Any component type KHR_mesh_quantization allows (`gltf_check` checked which).
                use super::gltf_quantized as quantized;
                let attribute = |semantic| primitive.get(&semantic);
                let unread =
                    |what: &str| format!("mesh {source}: a primitive's {what} cannot be read");
                let Some(read) = attribute(gltf::Semantic::Positions) else {
                    return Err(format!("mesh {source}: a primitive has no positions"));
                };
                let mut read = quantized::vec3(read, buffer).ok_or_else(|| unread("POSITION"))?;
                let mut normals_read = match attribute(gltf::Semantic::Normals) {
                    Some(a) => Some(quantized::vec3(a, buffer).ok_or_else(|| unread("NORMAL"))?),
                    None => None,
                };
                // glTF: TANGENT without NORMAL is to be ignored.
                let mut tangents = match attribute(gltf::Semantic::Tangents) {
                    Some(a) if normals_read.is_some() => {
                        Some(quantized::vec4(a, buffer).ok_or_else(|| unread("TANGENT"))?)
                    }
                    _ => None,
                };
                // Posed (morph targets, skin) before the node places them.
                let vertices = super::gltf_pose::Vertices {
                    positions: &mut read,
                    normals: normals_read.as_deref_mut(),
                    tangents: tangents.as_deref_mut(),
                };
                // A skinned primitive is placed by its joints in the scene, not by its node.
                let (world, flip) = match pose.deform(&n, primitive, &buffers, source, vertices)? {
                    super::gltf_pose::Placed::ByNode => (world, flip),
                    super::gltf_pose::Placed::BySkin { mirrored } => {
                        (skin_frame, (skin_frame.determinant() < 0.0) != mirrored)
                    }
                };
                let key = primitive.material().index();
                let [set0, set1] = super::gltf_textures::uv_sets(&primitive.material(), source)?;
                // Each set the material reads, transformed as it reads it; TEXCOORD_0 also
                // where nothing reads it, as OBJ's coordinates are kept (UV checkers, tangents).
                let read_set = |set: u32, read: Option<super::gltf_textures::UvSetUse>| {
                    let semantic = gltf::Semantic::TexCoords(set);
                    let Some(a) = attribute(semantic.clone()) else {
                        return match read {
                            Some(read) => Err(format!(
                                "mesh {source}: a primitive of mesh {} has no {}, which its material \"{}\"'s {} reads",
                                n.mesh().map_or(0, |m| m.index()),
                                semantic.to_string(),
                                primitive.material().name().unwrap_or(""),
                                read.slot
                            )),
                            None => Ok(None),
                        };
                    };
                    if set > 0 && read.is_none() {
                        return Ok(None);
                    }
                    let transform =
                        read.map_or(super::gltf_textures::UvTransform::IDENTITY, |r| r.transform);
                    let uvs =
                        quantized::vec2(a, buffer).ok_or_else(|| unread(&semantic.to_string()))?;
                    Ok(Some(
                        (uvs.into_iter())
                            .map(|uv| {
                                let [u, v] = transform.apply(uv);
                                Vec2::new(u, 1.0 - v)
                            })
                            .collect::<Vec<Vec2>>(),
                    ))
                };
                let uvs = read_set(0, set0)?;
                let uvs1 = read_set(1, set1)?;
                // COLOR_0 multiplies the base colour (its alpha not read: a note says so).
                let colors = match attribute(gltf::Semantic::Colors(0)) {
                    Some(a) => Some(quantized::colors(a, buffer).ok_or_else(|| unread("COLOR_0"))?),
                    None => None,
                };
                let colors: Option<Vec<Vec3>> =
                    colors.map(|read| read.into_iter().map(Vec3::from_array).collect());
                let Part {
                    positions,
                    triangles,
                    corners,
                    ..
                } = part_of(&mut parts, key);
                let base = positions.len() as u32;
                // Normals transform by the inverse transpose (non-uniform scales bend them).
                let to_world = DMat3::from_mat4(world).inverse().transpose();
                let vertex_normals: Option<Vec<Vec3>> = normals_read.map(|read| {
                    read.into_iter()
                        .map(|n| (to_world * DVec3::from_array(n.map(|x| x as f64))).as_vec3())
                        .collect()
                });
                // Tangents lie along the surface: they transform as its vectors do, and a
                // mirroring placement turns the bitangent around.
                let along = DMat3::from_mat4(world);
                let vertex_tangents: Option<Vec<Vec4>> = tangents.map(|read| {
                    read.into_iter()
                        .map(|[x, y, z, w]| {
                            let t = (along * DVec3::new(x as f64, y as f64, z as f64)).as_vec3();
                            t.extend(if flip { -w } else { w })
                        })
                        .collect()
                });
                let placed: Vec<DVec3> = read
                    .iter()
                    .map(|p| world.transform_point3(DVec3::from_array(p.map(|x| x as f64))))
                    .collect();
                if let Some(far) = placed
                    .iter()
                    .find(|p| !(p.abs().max_element() <= super::MAX_EXTENT as f64))
                {
                    if !far.is_finite() {
                        return Err(format!(
                            "mesh {source}: node {} places a vertex at {far}: a position that is not a finite number (a NaN or infinite value in the file or the node's transform)",
                            n.index()
                        ));
                    }
                    return Err(format!(
                        "mesh {source}: node {} places a vertex at {far}, beyond {:e} from the origin (rt-gpu's limit: scale or move the model)",
                        n.index(),
                        super::MAX_EXTENT
                    ));
                }
                // Nodes (and instances) may place one mesh many times: bounded before it grows.
                placed_vertices += placed.len();
                if placed_vertices > 3 * MAX_TRIANGLES {
                    return Err(format!(
                        "mesh {source}: its nodes place more than {} vertices, more than rt-gpu takes",
                        3 * MAX_TRIANGLES
                    ));
                }
                positions.extend(placed.iter().map(|p| p.as_vec3()));
                let count = positions.len() as u32 - base;
                let indices: Vec<u32> = match reader.read_indices() {
                    Some(i) => i.into_u32().collect(),
                    None => (0..count).collect(),
                };
                if let Some(bad) = indices.iter().find(|&&i| i >= count) {
                    return Err(format!(
                        "mesh {source}: an index {bad} names a vertex beyond its primitive's {count}"
                    ));
                }
                // Counted before a strip or fan is expanded.
                placed_triangles += triangles_drawn(mode, indices.len() as u64) as usize;
                if placed_triangles > MAX_TRIANGLES {
                    return Err(format!(
                        "mesh {source}: its nodes place more than {MAX_TRIANGLES} triangles, more than rt-gpu takes"
                    ));
                }
                let indices = triangle_list(mode, indices);
                triangles.extend(indices.chunks_exact(3).map(|t| {
                    let [a, b, c] = [t[0], t[1], t[2]].map(|i| base + i);
                    if flip { [a, c, b] } else { [a, b, c] }
                }));
                let normals = per_corner(vertex_normals.as_deref(), &indices, flip);
                corners.normals.extend(normals);
                corners
                    .uvs
                    .extend(per_corner(uvs.as_deref(), &indices, flip));
                corners
                    .uvs1
                    .extend(per_corner(uvs1.as_deref(), &indices, flip));
                let tangents = per_corner(vertex_tangents.as_deref(), &indices, flip);
                corners.tangents.extend(tangents);
                corners
                    .colors
                    .extend(per_corner(colors.as_deref(), &indices, flip));
            }
        }
        stack.extend(n.children().map(|c| (c, node_world)));
    }
    let materials: Vec<gltf::Material> = document.materials().collect();
    let mut textures =
        super::gltf_textures::FileTextures::new(&document, &buffers, path.parent(), source);
    parts
        .into_iter()
        .map(|part| {
            let key = part.key;
            let mut mesh = part.into_mesh(source)?;
            if let Some(m) = key.and_then(|k| materials.get(k)) {
                mesh.material = Some(material_of(m, &mut textures)?);
                mesh.material_name = material_name(m, &materials);
            } else {
                mesh.material_name = "default".into();
            }
            Ok(mesh)
        })
        .collect()
}

/// The name a glTF material's parts are known by (in notes, and as the key that merges the
/// parts of one material): its own where no other material of the file has it, else with its
/// index (files such as the sample EnvironmentTest give different materials one name).
fn material_name(m: &gltf::Material, all: &[gltf::Material]) -> String {
    let index = m.index().unwrap_or(0);
    match m.name() {
        Some(name) if all.iter().filter(|o| o.name() == Some(name)).count() == 1 => name.into(),
        Some(name) => format!("{name} (material {index})"),
        None => format!("material{index}"),
    }
}

/// The first of `material`'s textures that reads texture coordinates, by its property name.
/// Per triangle of `indices`, its corners' values of the per-vertex `values` (in the order
/// the triangle is kept: two corners swapped where `flip`); `None` where there are none.
/// Whether a primitive of `mode` is drawn: triangles, as a list, a strip or a fan.
pub fn is_triangles(mode: gltf::mesh::Mode) -> bool {
    use gltf::mesh::Mode;
    matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    )
}

/// The triangles a primitive of `mode` draws from `corners` indices (or vertices): a list's
/// thirds, a strip's or fan's all but two; none for points and lines.
pub fn triangles_drawn(mode: gltf::mesh::Mode, corners: u64) -> u64 {
    use gltf::mesh::Mode;
    match mode {
        Mode::Triangles => corners / 3,
        Mode::TriangleStrip | Mode::TriangleFan => corners.saturating_sub(2),
        _ => 0,
    }
}

/// A triangles primitive's `indices` as a list of triangles, three indices each (glTF 2.0,
/// 3.7.2.1): a strip's triangle i is (v_i, v_{i+1+i%2}, v_{i+2-i%2}), keeping one winding; a
/// fan's is (v_{i+1}, v_{i+2}, v_0).
fn triangle_list(mode: gltf::mesh::Mode, indices: Vec<u32>) -> Vec<u32> {
    use gltf::mesh::Mode;
    let triangles = indices.len().saturating_sub(2);
    match mode {
        Mode::TriangleStrip => (0..triangles)
            .flat_map(|i| [indices[i], indices[i + 1 + i % 2], indices[i + 2 - i % 2]])
            .collect(),
        Mode::TriangleFan => (0..triangles)
            .flat_map(|i| [indices[i + 1], indices[i + 2], indices[0]])
            .collect(),
        _ => indices,
    }
}

fn per_corner<'a, T: Copy>(
    values: Option<&'a [T]>,
    indices: &'a [u32],
    flip: bool,
) -> impl Iterator<Item = Option<[T; 3]>> + 'a {
    indices.chunks_exact(3).map(move |t| {
        let values = values?;
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| values.get(i as usize));
        let [a, b, c] = [*a?, *b?, *c?];
        Some(if flip { [a, c, b] } else { [a, b, c] })
    })
}

/// Refuses a material's values that the glTF specification (and its extensions' schemas)
/// forbid, in one line naming the material and the field, rather than clamping them silently:
/// factors outside [0, 1], a negative emissive strength or alpha cutoff, an index of refraction
/// below 1 (but the extension's 0).
fn check_material_values(m: &gltf::Material, source: &str) -> Result<(), String> {
    let name = super::file::quoted(m.name().unwrap_or(""));
    let at = || match m.index() {
        Some(i) => format!("mesh {source}: material {i} (\"{name}\")"),
        None => format!("mesh {source}: the default material"),
    };
    let pbr = m.pbr_metallic_roughness();
    let unit = |x: f32| (0.0..=1.0).contains(&x);
    let factors = [
        ("baseColorFactor", pbr.base_color_factor().to_vec()),
        ("metallicFactor", vec![pbr.metallic_factor()]),
        ("roughnessFactor", vec![pbr.roughness_factor()]),
        ("emissiveFactor", m.emissive_factor().to_vec()),
        (
            "KHR_materials_transmission.transmissionFactor",
            m.transmission()
                .map(|t| t.transmission_factor())
                .into_iter()
                .collect(),
        ),
    ];
    for (field, values) in factors {
        if !values.iter().all(|&x| unit(x)) {
            return Err(format!(
                "{}: its {field} is {values:?}; glTF requires values in [0, 1]",
                at()
            ));
        }
    }
    if let Some(strength) = m.emissive_strength()
        && !(strength >= 0.0 && strength.is_finite())
    {
        return Err(format!(
            "{}: its KHR_materials_emissive_strength.emissiveStrength is {strength}; it must be a finite number >= 0",
            at()
        ));
    }
    if let Some(cutoff) = m.alpha_cutoff()
        && !(cutoff >= 0.0 && cutoff.is_finite())
    {
        return Err(format!(
            "{}: its alphaCutoff is {cutoff}; glTF requires a number >= 0",
            at()
        ));
    }
    if let Some(ior) = m.ior()
        && !(ior == 0.0 || ior >= 1.0)
    {
        return Err(format!(
            "{}: its KHR_materials_ior.ior is {ior}; the extension takes 1 or more (or 0)",
            at()
        ));
    }
    if let Some(v) = m.volume() {
        let field = |f: &str| format!("{}: its KHR_materials_volume.{f}", at());
        let thickness = v.thickness_factor();
        if !(thickness >= 0.0 && thickness.is_finite()) {
            return Err(format!(
                "{} is {thickness}; glTF requires a number >= 0",
                field("thicknessFactor")
            ));
        }
        let distance = v.attenuation_distance();
        if !(distance > 0.0) {
            return Err(format!(
                "{} is {distance}; glTF requires a number > 0",
                field("attenuationDistance")
            ));
        }
        let color = v.attenuation_color();
        if !color.iter().all(|&c| unit(c)) {
            return Err(format!(
                "{} is {color:?}; glTF requires values in [0, 1]",
                field("attenuationColor")
            ));
        }
    }
    let most = crate::material::fresnel::MAX_IOR;
    if let Some(ior) = m.ior()
        && !(ior <= most)
    {
        return Err(format!(
            "{}: its KHR_materials_ior.ior is {ior}; rt-gpu takes indices up to {most} (ior 0, the extension's fully reflecting limit, is taken as {most})",
            at()
        ));
    }
    Ok(())
}

/// What KHR_materials_volume fills a transmissive material with: the colour white light takes
/// over a distance inside. None for a thin surface (thickness 0, the extension's default), one
/// that transmits nothing, or one whose inside attenuates nothing (the default colour 1 or
/// distance infinity). The thickness is otherwise a rasterizer's stand-in for the geometry a
/// path tracer follows: only whether it is 0 matters here.
fn volume_of(m: &gltf::Material) -> Option<(Vec3, f32)> {
    let v = m.volume()?;
    let transmits = m
        .transmission()
        .is_some_and(|t| t.transmission_factor() > 0.0);
    let (color, distance) = (
        Vec3::from_array(v.attenuation_color()),
        v.attenuation_distance(),
    );
    (transmits && v.thickness_factor() > 0.0 && distance.is_finite() && color != Vec3::ONE)
        .then_some((color, distance))
}

/// A glTF metallic-roughness material as rt-gpu's `pbr`: emitting (on top of what it reflects)
/// its emissive factor x emissiveTexture x KHR_materials_emissive_strength, back faces too when
/// the material is two-sided; the base colour factor x baseColorTexture, the metallic and roughness factors,
/// KHR_materials_ior (default 1.5), KHR_materials_transmission's factor (default 0), the
/// metallic-roughness texture, the normal texture and alphaMode MASK or BLEND (the base
/// colour's alpha factor x its texture's alpha channel). Not read: the occlusion texture.
fn material_of(
    m: &gltf::Material,
    textures: &mut super::gltf_textures::FileTextures,
) -> Result<Material, String> {
    use crate::assets::texture::Texture;
    use crate::material::{Light, Pbr};
    let name = &super::file::quoted(m.name().unwrap_or(""));
    check_material_values(m, textures.source())?;
    let source = textures.source().to_string();
    let at = || match m.index() {
        Some(i) => format!("mesh {source}: material {i} (\"{name}\")"),
        None => format!("mesh {source}: the default material"),
    };
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, _] = pbr.base_color_factor();
    let base = Vec3::new(r, g, b).clamp(Vec3::ZERO, Vec3::ONE);
    let unit = |x: f32| {
        if x.is_finite() {
            x.clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    // Cuts emitters too: a masked texel of an emissive material is a hole.
    let alpha = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => None,
        mode => {
            let image = match pbr.base_color_texture() {
                Some(info) => textures.alpha(&info, name)?,
                None => None,
            };
            let cutoff = m.alpha_cutoff().unwrap_or(0.5);
            Some(crate::assets::alpha::Alpha {
                mode: match mode {
                    gltf::material::AlphaMode::Mask => crate::assets::alpha::AlphaMode::Mask {
                        cutoff: if cutoff.is_finite() {
                            cutoff.max(0.0)
                        } else {
                            0.5
                        },
                    },
                    _ => crate::assets::alpha::AlphaMode::Blend,
                },
                factor: unit(pbr.base_color_factor()[3]),
                image,
            })
        }
    };
    // Emission adds to what the surface reflects (glTF's material model).
    let emissive = Vec3::from_array(m.emissive_factor()).clamp(Vec3::ZERO, Vec3::splat(1e6));
    let strength = m.emissive_strength().unwrap_or(1.0);
    let emission = if emissive.max_element() > 0.0 && strength > 0.0 {
        let radiance = match m.emissive_texture() {
            Some(info) => textures.colour(&info, emissive, name, "emissiveTexture")?,
            None => Texture::Colour(emissive),
        };
        Some(Light {
            radiance,
            strength: strength.clamp(0.0, crate::material::light::MAX_STRENGTH),
            two_sided: m.double_sided(),
            alpha: None,
        })
    } else {
        None
    };
    let base = match pbr.base_color_texture() {
        Some(info) => textures.colour(&info, base, name, "baseColorTexture")?,
        None => Texture::Colour(base),
    };
    // KHR_materials_unlit: the base colour as it is, shaded by nothing. A path tracer shows it
    // as a surface that emits its base colour and reflects nothing (Cycles' import instead
    // shows it to camera rays alone and lets every other ray pass): seen directly it is its
    // colour; it also glows in reflections and on what is near, as an emitter does.
    if m.unlit() {
        return Ok(Material::Light(Light {
            radiance: base,
            strength: 1.0,
            two_sided: m.double_sided(),
            alpha,
        }));
    }
    let normal_map = match m.normal_texture() {
        Some(normal) => Some(textures.normal_map(&normal, name)?),
        None => None,
    };
    let metallic_roughness = match pbr.metallic_roughness_texture() {
        Some(info) => Some(textures.metallic_roughness(&info, name)?),
        None => None,
    };
    // KHR_materials_transmission's texture scales the factor: its red channel, carried in the
    // parameter image's (`Pbr::transmission_in_red`).
    let transmission_texture = m.transmission().and_then(|t| t.transmission_texture());
    let (metallic_roughness, transmission_in_red) = match transmission_texture {
        Some(info) => (
            Some(textures.transmission(&info, metallic_roughness, name)?),
            true,
        ),
        None => (metallic_roughness, false),
    };
    let layer_images = super::gltf_extensions::layer_images(m, textures, name)?;
    let mut out = Pbr::new(
        base,
        unit(pbr.metallic_factor()),
        unit(pbr.roughness_factor()),
        // The extension's 0 is its limit of a fully reflecting dielectric (F0 = 1): the
        // largest index rt-gpu takes, whose F0 is 0.96.
        match m.ior().unwrap_or(1.5) {
            0.0 => crate::material::fresnel::MAX_IOR,
            ior => ior,
        },
        unit(m.transmission().map_or(0.0, |t| t.transmission_factor())),
    )
    .with_normal_map(normal_map)
    .with_metallic_roughness(metallic_roughness)
    .with_alpha(alpha)
    .with_emission(emission)
    .with_clearcoat(super::gltf_extensions::clearcoat(m, &at)?)
    .with_sheen(super::gltf_extensions::sheen(m, &at)?)
    .with_specular(super::gltf_extensions::specular(m, &at)?)
    .with_layer_images(layer_images.layers, layer_images.sheen)
    .with_specular_images(layer_images.specular, layer_images.specular_color)
    .with_clearcoat_normal_map(layer_images.clearcoat_normal_map)
    .with_attenuation(volume_of(m))
    .map_err(|e| format!("{}: {e}", at()))?;
    out.transmission_in_red = transmission_in_red;
    Ok(Material::Pbr(out))
}
