//! The scene: plain data shared by every backend.
//!
//! A [`Scene`] is what a user describes (boxes, instances, named materials); [`flat::FlatScene`] is
//! what the backends trace (world-space spheres and quads, resolved material indices).

pub mod builtin;
pub mod file;
pub mod flat;
pub mod gltf_check;
pub mod gltf_extensions;
pub mod gltf_instancing;
pub mod gltf_pose;
pub mod gltf_quantized;
pub mod gltf_scene;
pub mod gltf_textures;
pub mod media;
pub mod mesh;
mod obj_parallel;
pub mod punctual;
pub mod source;
pub mod tangents;

use glam::Vec3;

/// A thin-lens perspective camera. Image x grows to the camera's right, `cross(forward, up)`;
/// row 0 is the top of the image.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub look_from: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub vfov_degrees: f32,
    /// Lens diameter; 0 is a pinhole.
    pub aperture: f32,
    /// Distance to the plane in focus; `None` focuses on `look_at`.
    pub focus_distance: Option<f32>,
}

pub use crate::material::Material;

pub use crate::placement::{MAX_EXTENT, MIN_SIZE, Transform};

#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A sphere, a quad, a disk: a shape of `crate::shape`, as the scene describes it.
    Surface(crate::shape::SurfaceParams),
    /// An axis-aligned box made of six outward-facing quads.
    Cuboid { min: Vec3, max: Vec3 },
    /// A triangle mesh scaled per axis (before the object's rotation and translation).
    Mesh {
        mesh: std::sync::Arc<mesh::Mesh>,
        scale: Vec3,
    },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    pub shape: Shape,
    /// Index into [`Scene::materials`].
    pub material: u32,
    pub transform: Transform,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Background {
    Constant(Vec3),
    /// White at the horizon blending to (0.5, 0.7, 1.0) overhead, by the ray's y.
    Sky,
    /// An equirectangular HDR image, sampled as a light by next-event estimation.
    Environment(crate::assets::environment::Environment),
}

/// Defaults a scene carries for how it is rendered; the CLI may override them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderDefaults {
    pub width: u32,
    pub height: u32,
    /// The number of path segments: emission at the k-th surface hit counts for k <= max_depth.
    pub max_depth: u32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub name: String,
    pub camera: Camera,
    pub background: Background,
    pub materials: Vec<Material>,
    /// A name per material, as scene files refer to them.
    pub material_names: Vec<String>,
    pub objects: Vec<Object>,
    /// Lights of no area: points, spots and the sun (`punctual.rs`).
    pub punctual: Vec<punctual::Punctual>,
    pub defaults: RenderDefaults,
    /// The files the scene read (images, meshes, ...) besides the scene file itself: outputs
    /// must not overwrite them, and films record their digests.
    pub inputs: Vec<crate::assets::inputs::InputFile>,
}

/// Problems in a scene that any source (built-in, file, test) can have.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SceneError {
    #[error(
        "camera look_from equals look_at (or lies within {MIN_SIZE:e} of it): the view direction is undefined"
    )]
    CameraNoDirection,
    #[error(
        "camera up {0:?} is parallel to the view direction: the image orientation is undefined"
    )]
    CameraUpParallel([f32; 3]),
    #[error("camera vfov (vertical field of view) must be in (0, 180) degrees, got {0}")]
    BadFov(f32),
    #[error("{0}")]
    Invalid(String),
}

impl Camera {
    /// Checks what makes the camera frame undefined.
    pub fn validate(&self) -> Result<(), SceneError> {
        if !within_extent(self.look_from) || !within_extent(self.look_at) {
            return Err(SceneError::Invalid(format!(
                "camera positions must lie within {MAX_EXTENT:e} of the origin"
            )));
        }
        // In f64: up is a direction of any length, and lengths of extreme vectors overflow f32.
        let forward = self.look_at.as_dvec3() - self.look_from.as_dvec3();
        if !(forward.length() >= MIN_SIZE as f64) {
            return Err(SceneError::CameraNoDirection);
        }
        let up = self.up.as_dvec3();
        if !up.is_finite() || up == glam::DVec3::ZERO {
            return Err(SceneError::CameraUpParallel(self.up.to_array()));
        }
        let right = forward.normalize().cross(up.normalize());
        if !(right.length() > 1e-6) {
            return Err(SceneError::CameraUpParallel(self.up.to_array()));
        }
        if !(self.vfov_degrees > 0.0 && self.vfov_degrees < 180.0) {
            return Err(SceneError::BadFov(self.vfov_degrees));
        }
        if !(0.0..=MAX_EXTENT).contains(&self.aperture) {
            return Err(SceneError::Invalid(format!(
                "camera aperture must be in [0, {MAX_EXTENT:e}], got {}",
                self.aperture
            )));
        }
        if let Some(d) = self.focus_distance
            && !(MIN_SIZE..=MAX_EXTENT).contains(&d)
        {
            return Err(SceneError::Invalid(format!(
                "camera focus_distance must be in [{MIN_SIZE:e}, {MAX_EXTENT:e}], got {d}"
            )));
        }
        Ok(())
    }
}

impl Scene {
    /// Where the files it reads are (what outputs must not replace).
    pub fn input_paths(&self) -> impl Iterator<Item = &std::path::Path> {
        self.inputs.iter().map(|f| f.path.as_path())
    }

    /// The whole-scene checks the backends rely on; file loading reports the same problems with
    /// the file's line numbers before it gets here.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.camera.validate()?;
        if self.material_names.len() != self.materials.len() {
            return Err(SceneError::Invalid("every material needs a name".into()));
        }
        for (material, name) in self.materials.iter().zip(&self.material_names) {
            material
                .validate()
                .map_err(|e| SceneError::Invalid(format!("material \"{name}\": {e}")))?;
        }
        for (i, object) in self.objects.iter().enumerate() {
            if object.material as usize >= self.materials.len() {
                return Err(SceneError::Invalid(format!(
                    "object {i} uses material {} but the scene has {}",
                    object.material,
                    self.materials.len()
                )));
            }
            object.shape.validate().map_err(SceneError::Invalid)?;
            // Tangent frames follow from texture coordinates (`scene::tangents`).
            if self.materials[object.material as usize]
                .normal_maps()
                .next()
                .is_some()
            {
                let name = &self.material_names[object.material as usize];
                match object.shape {
                    Shape::Mesh { ref mesh, .. } if mesh.uvs.is_empty() => {
                        return Err(SceneError::Invalid(format!(
                            "material \"{name}\" has a normal map, but mesh {} (part {}) has no texture coordinates to lay it out",
                            mesh.source, mesh.material_name
                        )));
                    }
                    Shape::Mesh { .. } => {}
                    _ => {
                        return Err(SceneError::Invalid(format!(
                            "material \"{name}\" has a normal map, which applies to meshes with texture coordinates only; object {i} is not a mesh"
                        )));
                    }
                }
            }
            if !within_extent(object.transform.translate) {
                return Err(SceneError::Invalid(format!(
                    "object {i} is translated beyond {MAX_EXTENT:e} from the origin"
                )));
            }
        }
        for light in &self.punctual {
            light.validate().map_err(SceneError::Invalid)?;
        }
        media::check(self).map_err(|(i, e)| SceneError::Invalid(format!("object {i}: {e}")))
    }
}

fn within_extent(p: Vec3) -> bool {
    p.is_finite() && p.abs().max_element() <= MAX_EXTENT
}

impl Shape {
    /// The sphere of `radius` (negative: facing inward) about `center`.
    pub fn sphere(center: Vec3, radius: f32) -> Self {
        Shape::Surface(crate::shape::SurfaceParams::Sphere(
            crate::shape::SphereParams { center, radius },
        ))
    }

    /// The parallelogram `q + a u + b v`, a, b in [0, 1]; its front face is along `u x v`.
    pub fn quad(q: Vec3, u: Vec3, v: Vec3) -> Self {
        Shape::Surface(crate::shape::SurfaceParams::Quad(
            crate::shape::QuadParams { q, u, v },
        ))
    }

    pub fn validate(&self) -> Result<(), String> {
        match *self {
            Shape::Surface(params) => params.validate()?,
            Shape::Mesh { ref mesh, scale } => {
                let size = scale.abs() * mesh.extent;
                if !scale.is_finite() || scale.abs().min_element() < MIN_SIZE {
                    return Err(format!(
                        "mesh {} scale {scale} must be finite with every component at least {MIN_SIZE:e} in size",
                        mesh.source
                    ));
                }
                if !within_extent(size) {
                    return Err(format!(
                        "mesh {} scaled by {scale} reaches beyond {MAX_EXTENT:e} from the origin: f32 geometry there is too coarse",
                        mesh.source
                    ));
                }
                return Ok(());
            }
            Shape::Cuboid { min, max } => {
                if !min.is_finite() || !max.is_finite() || !(max.cmpgt(min).all()) {
                    return Err(format!(
                        "box needs max > min on every axis, got min {min:?} max {max:?}"
                    ));
                }
                let size = max - min;
                if !(size.min_element() >= MIN_SIZE && size.max_element() <= MAX_EXTENT) {
                    return Err(format!(
                        "box size {size:?} is outside what f32 geometry handles: use sizes between {MIN_SIZE:e} and {MAX_EXTENT:e}"
                    ));
                }
            }
        }
        let (position, far) = match *self {
            Shape::Surface(params) => params.reach(),
            Shape::Cuboid { min, max } => (min, max),
            Shape::Mesh { .. } => unreachable!("meshes return above"),
        };
        if !within_extent(position) || !within_extent(far) {
            return Err(format!(
                "shape at {position:?} reaches beyond {MAX_EXTENT:e} from the origin: f32 geometry there is too coarse"
            ));
        }
        Ok(())
    }
}
