//! A glTF 2.0 file as a whole scene (`rt-gpu model.glb`): its default scene's meshes with their
//! own materials and its punctual lights, seen by one of its cameras (or by a camera framing
//! it), under a uniform white sky when it carries no punctual lights (its emissive materials
//! glow on top of either).
//!
//! A glTF camera looks down its node's -z with +y up (glTF 2.0, 3.10.1); its `yfov` is the
//! vertical field of view and its `aspectRatio`, where given, the image's default width over
//! height.

use super::mesh;
use super::punctual::Punctual;
use super::{Background, Camera, Object, RenderDefaults, Scene, Shape, Transform};
use crate::assets::environment::Environment;
use crate::assets::image::Image;
use glam::{DMat4, DVec3, Vec3};
use std::path::Path;
use std::sync::Arc;
use std::sync::OnceLock;

/// The default image height of a file's render; its width follows the camera's aspect ratio.
pub const DEFAULT_HEIGHT: u32 = 512;
/// The vertical field of view of the camera that frames a file without one (degrees).
pub const FRAMING_VFOV: f32 = 40.0;

/// A perspective camera of the file, placed by its node.
#[derive(Clone, Debug, PartialEq)]
pub struct FileCamera {
    /// Its name, else its node's, else `camera<index>`.
    pub name: String,
    pub from: DVec3,
    /// Unit view direction and up, in the file's root frame.
    pub forward: DVec3,
    pub up: DVec3,
    pub yfov_radians: f32,
    pub aspect_ratio: Option<f32>,
    /// An orthographic camera, which rt-gpu does not render (refused when chosen).
    pub orthographic: bool,
}

/// What of a file the scene takes besides its meshes.
#[derive(Debug, Default)]
pub struct FileExtras {
    pub cameras: Vec<FileCamera>,
    /// Lights it places (KHR_lights_punctual): their names and the lights, in rt-gpu's
    /// radiometric units.
    pub lights: Vec<String>,
    pub punctual: Vec<Punctual>,
    /// What the user should know of what was left out.
    pub notes: Vec<String>,
}

/// Lumens per watt: glTF's photometric units (candela, lux) over rt-gpu's radiometric ones
/// (W/sr, W/m^2), the factor Blender's exporter multiplies by (683 lm/W, monochromatic at
/// 555 nm).
pub const LUMENS_PER_WATT: f32 = 683.0;

/// The scene of the glTF file at `path` (`source`: the path as the user wrote it), seen by its
/// camera named `camera`, else by its first, else by one that frames it; with notes for the
/// user on what of the file it leaves out.
pub fn load(
    path: &Path,
    source: &str,
    camera: Option<&str>,
) -> Result<(Scene, Vec<String>), String> {
    let (loaded, inputs) =
        crate::assets::inputs::recorded(|| load_unrecorded(path, source, camera));
    loaded.map(|(scene, notes)| (Scene { inputs, ..scene }, notes))
}

/// [`load`], without the files it reads.
fn load_unrecorded(
    path: &Path,
    source: &str,
    camera: Option<&str>,
) -> Result<(Scene, Vec<String>), String> {
    let parts = mesh::load(path, source, None)?;
    let extras = read_extras(path, source)?;
    let chosen =
        match camera {
            Some(name) if extras.cameras.iter().filter(|c| c.name == name).count() > 1 => {
                return Err(format!(
                    "{source} has several cameras named \"{}\": rename them apart to pick one",
                    super::file::quoted(name)
                ));
            }
            Some(name) => Some(extras.cameras.iter().find(|c| c.name == name).ok_or_else(
                || {
                    let names: Vec<&str> = extras.cameras.iter().map(|c| c.name.as_str()).collect();
                    let name = super::file::quoted(name);
                    if names.is_empty() {
                        format!("{source} has no camera named \"{name}\": it has no cameras")
                    } else {
                        format!(
                            "{source} has no camera named \"{name}\" (cameras: {})",
                            listed(&names)
                        )
                    }
                },
            )?),
            None => extras.cameras.first(),
        };
    let (min, max) = bounds(&parts);
    let (camera, aspect) = match chosen {
        Some(c) => (
            camera_of(c, (min + max) / 2.0).map_err(|e| format!("{source}: {e}"))?,
            c.aspect_ratio,
        ),
        None => (framing_camera(min, max), None),
    };
    let height = DEFAULT_HEIGHT;
    let width = aspect
        .filter(|a| a.is_finite() && *a > 0.0)
        .map_or(height, |a| {
            ((height as f32 * a).round() as u32).clamp(16, 4 * height)
        });
    let mut materials = Vec::new();
    let mut material_names = Vec::new();
    let mut objects = Vec::new();
    for part in &parts {
        let name = format!("{}#{}", source, part.material_name);
        let index = match material_names.iter().position(|n| *n == name) {
            Some(i) => i,
            None => {
                let own = part.material.clone().unwrap_or_else(default_material);
                own.validate()
                    .map_err(|e| format!("{source} material \"{}\": {e}", part.material_name))?;
                materials.push(own);
                material_names.push(name);
                materials.len() - 1
            }
        };
        objects.push(Object {
            shape: Shape::Mesh {
                mesh: part.clone(),
                scale: Vec3::ONE,
            },
            material: index as u32,
            transform: Transform::default(),
        });
    }
    // Light: the file's lamps where it has any, else a uniform sky; emissive materials glow on
    // top of either (a helmet's glowing details do not light the helmet).
    let background = if !extras.punctual.is_empty() {
        Background::Constant(Vec3::ZERO)
    } else {
        Background::Environment(uniform_sky())
    };
    let name = Path::new(source)
        .file_stem()
        .map_or("gltf".into(), |s| s.to_string_lossy().into_owned());
    let scene = Scene {
        name,
        camera,
        background,
        materials,
        material_names,
        objects,
        punctual: extras.punctual.clone(),
        defaults: RenderDefaults {
            width,
            height,
            max_depth: 10,
        },
        inputs: Vec::new(),
    };
    scene.validate().map_err(|e| format!("{source}: {e}"))?;
    let mut notes = extras.notes;
    notes.extend(smooth_sheen_note(&scene.materials, source));
    Ok((scene, notes))
}

/// The note for sheens whose roughness texture (sheenRoughnessTexture, in the layers image's
/// blue channel) takes their roughness below rt-gpu's least in places, where it is taken as the
/// least; a factor already below it is the file note's (`gltf_extensions::unread`).
fn smooth_sheen_note(materials: &[crate::scene::Material], source: &str) -> Option<String> {
    let least = crate::material::sheen::MIN_ROUGHNESS;
    let n = materials
        .iter()
        .filter(|m| {
            let crate::scene::Material::Pbr(p) = m else {
                return false;
            };
            let (Some(sheen), Some(layers)) = (p.sheen, p.layers()) else {
                return false;
            };
            sheen.roughness >= least
                && layers
                    .texels
                    .iter()
                    .skip(2)
                    .step_by(3)
                    .any(|&blue| sheen.roughness * blue < least)
        })
        .count();
    (n > 0).then(|| {
        format!(
            "note: {source}: the sheenRoughnessTexture of {n} material{} takes the sheen's roughness below {least} in places: taken as {least} there",
            if n == 1 { "" } else { "s" }
        )
    })
}

/// The perspective camera named `name` of the glTF file at `path` (`source`: as the scene
/// names it), looking toward the middle of the file's meshes; `Ok(Err(names))`: the file has no
/// camera of that name, and these are its cameras' names.
pub fn named_camera(
    path: &Path,
    source: &str,
    name: &str,
) -> Result<Result<Camera, Vec<String>>, String> {
    let extras = read_extras(path, source)?;
    if extras.cameras.iter().filter(|c| c.name == name).count() > 1 {
        return Err(format!(
            "{source} has several cameras named \"{}\": rename them apart to pick one",
            super::file::quoted(name)
        ));
    }
    let Some(chosen) = extras.cameras.iter().find(|c| c.name == name) else {
        return Ok(Err(extras.cameras.into_iter().map(|c| c.name).collect()));
    };
    let (min, max) = bounds(&mesh::load(path, source, None)?);
    camera_of(chosen, (min + max) / 2.0)
        .map(Ok)
        .map_err(|e| format!("{source}: {e}"))
}

/// What a primitive without a material takes: glTF's default material (white, rough,
/// dielectric: 3.9.6), clamped as rt-gpu's `pbr`.
fn default_material() -> super::Material {
    super::Material::Pbr(crate::material::Pbr::new(
        Vec3::ONE.into(),
        1.0,
        1.0,
        1.5,
        0.0,
    ))
}

/// A sky of radiance 1 from every direction, sampled as a light: what lights a file that
/// carries none (as a glTF viewer's neutral environment does).
pub fn uniform_sky() -> Environment {
    static WHITE: OnceLock<Arc<Image>> = OnceLock::new();
    let image = WHITE.get_or_init(|| {
        Image::from_linear("uniform", 1, 1, vec![1.0; 3])
            .expect("a 1x1 image of ones is valid")
            .shared()
    });
    Environment::new(image.clone(), 1.0, 0.0).expect("strength 1, no rotation")
}

/// The box around every part's vertices.
fn bounds(parts: &[std::sync::Arc<mesh::Mesh>]) -> (DVec3, DVec3) {
    let mut min = DVec3::splat(f64::INFINITY);
    let mut max = DVec3::splat(f64::NEG_INFINITY);
    for p in parts.iter().flat_map(|m| &m.positions) {
        min = min.min(p.as_dvec3());
        max = max.max(p.as_dvec3());
    }
    (min, max)
}

/// A file camera as rt-gpu's, looking at the point of its view line nearest `center` (where
/// the viewer orbits), at least a unit ahead.
fn camera_of(c: &FileCamera, center: DVec3) -> Result<Camera, String> {
    if c.orthographic {
        return Err(format!(
            "camera \"{}\" is orthographic: rt-gpu renders perspective cameras (pick one with --camera NAME)",
            c.name
        ));
    }
    let ahead = (center - c.from).dot(c.forward).max(1.0);
    let camera = Camera {
        look_from: c.from.as_vec3(),
        look_at: (c.from + ahead * c.forward).as_vec3(),
        up: c.up.as_vec3(),
        vfov_degrees: c.yfov_radians.to_degrees(),
        aperture: 0.0,
        focus_distance: None,
    };
    camera
        .validate()
        .map_err(|e| format!("camera \"{}\": {e}", c.name))?;
    Ok(camera)
}

/// A camera in front of the file's bounds (along +z, glTF's front, a little above), framing
/// their bounding sphere.
fn framing_camera(min: DVec3, max: DVec3) -> Camera {
    let center = (min + max) / 2.0;
    let radius = ((max - min).length() / 2.0).max(super::MIN_SIZE as f64);
    let half = (FRAMING_VFOV as f64 / 2.0).to_radians();
    let distance = 1.1 * radius / half.sin();
    // How far along `direction` the camera may go and stay within the scenes' extent.
    let room = |direction: DVec3| {
        let limit = 0.999 * super::MAX_EXTENT as f64;
        (0..3)
            .filter(|&i| direction[i] != 0.0)
            .map(|i| (limit - center[i] * direction[i].signum()) / direction[i].abs())
            .fold(f64::MAX, f64::min)
    };
    let ahead = DVec3::new(0.0, 0.25, 1.0).normalize();
    let behind = DVec3::new(0.0, 0.25, -1.0).normalize();
    let direction = if room(ahead) >= distance || room(ahead) >= room(behind) {
        ahead
    } else {
        behind
    };
    // A model too large to frame from 40 degrees within the extent is framed from nearer, wider.
    // (A model at the extent's very edge leaves no room: the camera then stands at it, and
    // its check says where.)
    let distance = distance.min(room(direction)).max(super::MIN_SIZE as f64);
    let vfov_degrees = if distance * half.sin() >= 1.1 * radius * (1.0 - 1e-9) {
        FRAMING_VFOV
    } else {
        let wide = (1.1 * radius / distance)
            .min(85f64.to_radians().sin())
            .asin();
        (2.0 * wide.to_degrees()) as f32
    };
    Camera {
        look_from: (center + distance * direction).as_vec3(),
        look_at: center.as_vec3(),
        up: Vec3::Y,
        vfov_degrees,
        aperture: 0.0,
        focus_distance: None,
    }
}

/// The cameras and lights of the file's default scene (the file was checked and its meshes
/// read by `mesh::load` first).
pub fn read_extras(path: &Path, source: &str) -> Result<FileExtras, String> {
    // A panic inside the `gltf` crate (it unwraps some values it validated) is one line too.
    crate::caught_quietly(|| read_checked_extras(path, source)).unwrap_or_else(|| {
        Err(format!(
            "cannot read {source}: the glTF reader failed on it (a malformed file)"
        ))
    })
}

fn read_checked_extras(path: &Path, source: &str) -> Result<FileExtras, String> {
    let (bytes, _) = crate::assets::inputs::read(path, source, super::mesh::MAX_MESH_FILE_BYTES)
        .map_err(|e| format!("cannot read {source}: {e}"))?;
    let gltf::Gltf { document, blob } = super::gltf_check::parse(&bytes, source)?;
    // Cameras and lights are posed as the meshes are (`mesh::load` read the buffers once
    // already; they are read again only for an animation).
    let buffers = match document.animations().next() {
        Some(_) => super::gltf_check::read_buffers(&document, blob, path.parent(), source)?,
        None => Vec::new(),
    };
    let pose = super::gltf_pose::Pose::new(&document, &buffers, source)?;
    let Some(scene) = document
        .default_scene()
        .or_else(|| document.scenes().next())
    else {
        return Ok(FileExtras::default());
    };
    let mut extras = FileExtras::default();
    // Lights whose `range` is ignored, for one note.
    let mut ranged: Vec<String> = Vec::new();
    // Depth first in file order (the stack pops the last pushed first): "the first camera" is
    // the first a reader of the file meets.
    let roots: Vec<gltf::Node> = scene.nodes().collect();
    let mut stack: Vec<(gltf::Node, DMat4)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, DMat4::IDENTITY))
        .collect();
    // Finite: `mesh::load` checked that the nodes form trees.
    while let Some((node, parent)) = stack.pop() {
        let world = parent * pose.local(&node);
        if let Some(camera) = node.camera() {
            let name = camera
                .name()
                .or(node.name())
                .map_or(format!("camera{}", camera.index()), str::to_string);
            let (yfov_radians, aspect_ratio, orthographic) = match camera.projection() {
                gltf::camera::Projection::Perspective(p) => (p.yfov(), p.aspect_ratio(), false),
                gltf::camera::Projection::Orthographic(_) => (0.0, None, true),
            };
            let name = super::file::quoted(&name);
            let forward = world.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
            let up = world.transform_vector3(DVec3::Y).normalize_or_zero();
            if forward == DVec3::ZERO || up == DVec3::ZERO {
                return Err(format!(
                    "{source}: camera \"{name}\"'s node has a degenerate transform"
                ));
            }
            // A shear would turn the view sideways of where the image's up points.
            if forward.dot(up).abs() > 1e-3 {
                return Err(format!(
                    "{source}: camera \"{name}\"'s node transform shears it (its view and up are {:.1} degrees from square); glTF places cameras by rotation and translation",
                    (90.0 - forward.dot(up).clamp(-1.0, 1.0).acos().to_degrees()).abs()
                ));
            }
            extras.cameras.push(FileCamera {
                name,
                from: world.transform_point3(DVec3::ZERO),
                forward,
                up,
                yfov_radians,
                aspect_ratio,
                orthographic,
            });
        }
        if let Some(light) = node.light() {
            let name = light
                .name()
                .or(node.name())
                .map_or(format!("light{}", light.index()), str::to_string);
            let name = super::file::quoted(&name);
            // What KHR_lights_punctual's schema forbids is refused, not clamped.
            if !light.color().iter().all(|c| (0.0..=1.0).contains(c)) {
                return Err(format!(
                    "{source}: light \"{name}\" has a color of {:?}; KHR_lights_punctual requires values in [0, 1]",
                    light.color()
                ));
            }
            if !(light.intensity() >= 0.0 && light.intensity().is_finite()) {
                return Err(format!(
                    "{source}: light \"{name}\" has an intensity of {}; KHR_lights_punctual requires a finite number >= 0",
                    light.intensity()
                ));
            }
            let colour = Vec3::from_array(light.color());
            let power = colour * (light.intensity() / LUMENS_PER_WATT);
            let position = world.transform_point3(DVec3::ZERO).as_vec3();
            let direction = world
                .transform_vector3(DVec3::NEG_Z)
                .normalize_or_zero()
                .as_vec3();
            use gltf::khr_lights_punctual::Kind;
            let punctual = match light.kind() {
                Kind::Point => Punctual::Point {
                    position,
                    intensity: power,
                },
                Kind::Spot {
                    inner_cone_angle,
                    outer_cone_angle,
                } => {
                    let right = std::f32::consts::FRAC_PI_2;
                    if !(0.0 <= inner_cone_angle
                        && inner_cone_angle < outer_cone_angle
                        && outer_cone_angle <= right)
                    {
                        return Err(format!(
                            "{source}: spot light \"{name}\" has cone angles {inner_cone_angle} (inner) and {outer_cone_angle} (outer); KHR_lights_punctual requires 0 <= inner < outer <= pi/2"
                        ));
                    }
                    Punctual::Spot {
                        position,
                        direction,
                        intensity: power,
                        inner: inner_cone_angle,
                        outer: outer_cone_angle,
                    }
                }
                Kind::Directional => Punctual::Directional {
                    direction,
                    irradiance: power,
                },
            };
            // A light the file places badly (under a zero scale, say) is left out, not the file.
            match punctual.validate() {
                Err(e) => extras
                    .notes
                    .push(format!("note: {source}: light \"{name}\" is left out: {e}")),
                Ok(()) => {
                    if light.range().is_some() {
                        ranged.push(name.clone());
                    }
                    extras.lights.push(name);
                    extras.punctual.push(punctual);
                }
            }
        }
        let children: Vec<_> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    if let Some(note) = unread_note(&document, source) {
        extras.notes.push(note);
    }
    // One note, however many lights have a range.
    match ranged.as_slice() {
        [] => {}
        [one] => extras.notes.push(format!(
            "note: {source}: light \"{one}\"'s range is ignored (its light falls off with the square of distance alone)"
        )),
        [first, ..] => extras.notes.push(format!(
            "note: {source}: the range of {} lights (\"{first}\" and others) is ignored (their light falls off with the square of distance alone)",
            ranged.len()
        )),
    }
    Ok(extras)
}

/// Extensions whose content rt-gpu reads.
const READ_EXTENSIONS: [&str; 12] = [
    "EXT_mesh_gpu_instancing",
    super::gltf_extensions::CLEARCOAT,
    super::gltf_extensions::SHEEN,
    super::gltf_extensions::SPECULAR,
    "KHR_lights_punctual",
    "KHR_mesh_quantization",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_unlit",
    super::gltf_extensions::VOLUME,
    "KHR_texture_transform",
];

/// One note naming what `document` holds that rt-gpu does not render (nothing is dropped
/// silently): primitives of points or lines, vertex colours beyond COLOR_0 (and its alpha
/// where the material is not opaque), texture coordinates beyond TEXCOORD_1, animations'
/// motion and extensions it does not read. `None` when there is nothing.
fn unread_note(document: &gltf::Document, source: &str) -> Option<String> {
    let primitives: Vec<gltf::Primitive> = document.meshes().flat_map(|m| m.primitives()).collect();
    let mut unread: Vec<String> = Vec::new();
    let count =
        |n: usize, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
    let undrawn = primitives
        .iter()
        .filter(|p| !super::mesh::is_triangles(p.mode()))
        .count();
    if undrawn > 0 {
        unread.push(count(
            undrawn,
            "primitive of points or lines",
            "primitives of points or lines",
        ));
    }
    let mut attributes: Vec<String> = primitives
        .iter()
        .flat_map(|p| p.attributes().map(|(semantic, _)| semantic))
        .filter_map(|semantic| match semantic {
            gltf::Semantic::Colors(set) if set > 0 => Some(format!("COLOR_{set}")),
            gltf::Semantic::TexCoords(set) if set > 1 => Some(format!("TEXCOORD_{set}")),
            _ => None,
        })
        .collect();
    // glTF multiplies the base colour's alpha by COLOR_0's too; rt-gpu reads its RGB.
    let color_alpha = primitives.iter().any(|p| {
        p.material().alpha_mode() != gltf::material::AlphaMode::Opaque
            && p.get(&gltf::Semantic::Colors(0))
                .is_some_and(|a| a.dimensions() == gltf::accessor::Dimensions::Vec4)
    });
    if color_alpha {
        attributes.push("COLOR_0's alpha".into());
    }
    attributes.sort();
    attributes.dedup();
    unread.extend(attributes);
    // A still image shows one moment (`gltf_pose`): the motion is what is not rendered.
    match document.animations().count() {
        0 => {}
        1 => unread.push(format!(
            "its animation's motion (posed at {} s)",
            super::gltf_pose::TIME
        )),
        n => unread.push(format!(
            "{n} animations' motion (posed at {} s of the first)",
            super::gltf_pose::TIME
        )),
    }
    unread.extend(super::gltf_extensions::unread(document));
    let extensions: Vec<&str> = document
        .extensions_used()
        .filter(|e| !READ_EXTENSIONS.contains(e))
        .collect();
    if !extensions.is_empty() {
        unread.push(format!(
            "extension{} {}",
            if extensions.len() == 1 { "" } else { "s" },
            listed(&extensions)
        ));
    }
    (!unread.is_empty()).then(|| {
        format!(
            "note: {source}: not rendered: {} (see scenes/README.md's glTF table)",
            unread.join(", ")
        )
    })
}

/// Most names a message lists.
const MAX_LISTED: usize = 8;

/// `names` as a message lists them: the first few, quoted, and how many there are.
pub fn listed(names: &[&str]) -> String {
    let shown: Vec<String> = (names.iter().take(MAX_LISTED))
        .map(|n| super::file::quoted(n))
        .collect();
    if names.len() <= MAX_LISTED {
        shown.join(", ")
    } else {
        format!("{}, ... ({} in all)", shown.join(", "), names.len())
    }
}
