//! The GPU's view of a scene: `#[repr(C)]` structs mirrored one-to-one by the WGSL structs in
//! `shaders/common.wgsl` (vec3f is 16-byte aligned there, hence the explicit padding).
//! `tests/gpu_layout.rs` checks sizes and field offsets against naga's layout of the WGSL.

use crate::render::RenderOptions;
use crate::scene::flat::FlatScene;
use crate::scene::{Background, Material};
use bytemuck::{Pod, Zeroable};

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct GpuSphere {
    pub center: [f32; 3],
    pub radius: f32,
    pub material: u32,
    /// 1 + its index in the light list; 0 when it does not emit.
    pub light: u32,
    pub _pad: [u32; 2],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct GpuQuad {
    pub q: [f32; 3],
    pub d: f32,
    pub normal: [f32; 3],
    pub material: u32,
    pub alpha_axis: [f32; 3],
    /// 1 + its index in the light list; 0 when it does not emit.
    pub light: u32,
    pub beta_axis: [f32; 3],
    pub edge_tolerance: f32,
}

/// A light for next-event estimation (see `scene::flat::Light`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct GpuLight {
    pub position: [f32; 3],
    pub cdf: f32,
    pub u: [f32; 3],
    pub pick: f32,
    pub v: [f32; 3],
    pub radius: f32,
    pub normal: [f32; 3],
    pub inv_area: f32,
}

pub const MAT_LAMBERTIAN: u32 = 0;
pub const MAT_METAL: u32 = 1;
pub const MAT_DIELECTRIC: u32 = 2;
pub const MAT_LIGHT: u32 = 3;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct GpuMaterial {
    pub albedo: [f32; 3],
    pub kind: u32,
    pub emission: [f32; 3],
    /// Metal: fuzz; dielectric: ior; light: 1 if two-sided.
    pub param: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct GpuParams {
    pub origin: [f32; 3],
    pub lens_radius: f32,
    pub to_upper_left: [f32; 3],
    pub width: u32,
    pub horizontal: [f32; 3],
    pub height: u32,
    pub vertical: [f32; 3],
    pub max_depth: u32,
    pub right: [f32; 3],
    pub seed: u32,
    pub up: [f32; 3],
    pub first_sample: u32,
    pub background: [f32; 3],
    pub sample_count: u32,
    pub tile_origin: [u32; 2],
    pub tile_size: [u32; 2],
    pub sphere_count: u32,
    pub quad_count: u32,
    pub samples_before: u32,
    pub sky: u32,
    pub light_count: u32,
    /// Russian roulette from this many segments on; 0: off.
    pub roulette_depth: u32,
    pub _pad: [u32; 2],
}

/// The per-pixel accumulator: mean (w: non-finite sample count as bits), Kahan compensation, M2.
pub const ACCUM_BYTES_PER_PIXEL: u64 = 3 * 16;

/// The output of the `first_bounce` debug entry point, per pixel.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct GpuFirstBounce {
    pub point: [f32; 3],
    pub primitive: u32,
    pub normal: [f32; 3],
    pub hit: u32,
    pub dir: [f32; 3],
    pub scattered: u32,
}

/// Scene buffers as uploaded. Empty arrays hold one zeroed element: a binding cannot be empty.
pub struct SceneBuffers {
    pub spheres: Vec<GpuSphere>,
    pub quads: Vec<GpuQuad>,
    pub materials: Vec<GpuMaterial>,
    pub lights: Vec<GpuLight>,
}

impl SceneBuffers {
    pub fn new(scene: &FlatScene) -> Self {
        let mut spheres: Vec<GpuSphere> = scene
            .spheres
            .iter()
            .map(|s| GpuSphere {
                center: s.center.to_array(),
                radius: s.radius,
                material: s.material,
                light: s.light,
                _pad: [0; 2],
            })
            .collect();
        let mut quads: Vec<GpuQuad> = scene
            .quads
            .iter()
            .map(|q| GpuQuad {
                q: q.q.to_array(),
                d: q.d,
                normal: q.normal.to_array(),
                material: q.material,
                alpha_axis: q.alpha_axis.to_array(),
                beta_axis: q.beta_axis.to_array(),
                light: q.light,
                edge_tolerance: q.edge_tolerance,
            })
            .collect();
        let mut materials: Vec<GpuMaterial> = scene.materials.iter().map(gpu_material).collect();
        if spheres.is_empty() {
            spheres.push(GpuSphere::default());
        }
        if quads.is_empty() {
            quads.push(GpuQuad::default());
        }
        if materials.is_empty() {
            materials.push(GpuMaterial::default());
        }
        let mut lights: Vec<GpuLight> = scene
            .lights
            .iter()
            .map(|l| GpuLight {
                position: l.position.to_array(),
                cdf: l.cdf,
                u: l.u.to_array(),
                pick: l.pick,
                v: l.v.to_array(),
                radius: l.radius,
                normal: l.normal.to_array(),
                inv_area: l.inv_area,
            })
            .collect();
        if lights.is_empty() {
            lights.push(GpuLight::default());
        }
        SceneBuffers {
            spheres,
            quads,
            materials,
            lights,
        }
    }
}

fn gpu_material(m: &Material) -> GpuMaterial {
    match *m {
        Material::Lambertian { albedo, emission } => GpuMaterial {
            albedo: albedo.to_array(),
            kind: MAT_LAMBERTIAN,
            emission: emission.to_array(),
            param: 0.0,
        },
        Material::Metal { albedo, fuzz } => GpuMaterial {
            albedo: albedo.to_array(),
            kind: MAT_METAL,
            emission: [0.0; 3],
            param: fuzz,
        },
        Material::Dielectric { ior } => GpuMaterial {
            albedo: [1.0; 3],
            kind: MAT_DIELECTRIC,
            emission: [0.0; 3],
            param: ior,
        },
        Material::Light {
            radiance,
            two_sided,
        } => GpuMaterial {
            albedo: [0.0; 3],
            kind: MAT_LIGHT,
            emission: radiance.to_array(),
            param: if two_sided { 1.0 } else { 0.0 },
        },
    }
}

/// Parameters for a dispatch over the whole image; the renderer sets the tile and sample range.
pub fn base_params(scene: &FlatScene, opts: &RenderOptions) -> GpuParams {
    let c = &scene.camera;
    let (background, sky) = match scene.background {
        Background::Constant(c) => (c.to_array(), 0),
        Background::Sky => ([0.0; 3], 1),
    };
    GpuParams {
        origin: c.origin.to_array(),
        lens_radius: c.lens_radius,
        to_upper_left: c.to_upper_left.to_array(),
        width: opts.width,
        horizontal: c.horizontal.to_array(),
        height: opts.height,
        vertical: c.vertical.to_array(),
        max_depth: opts.max_depth,
        right: c.right.to_array(),
        seed: opts.seed,
        up: c.up.to_array(),
        first_sample: opts.first_sample,
        background,
        sample_count: 0,
        tile_origin: [0, 0],
        tile_size: [opts.width, opts.height],
        sphere_count: scene.spheres.len() as u32,
        quad_count: scene.quads.len() as u32,
        samples_before: 0,
        sky,
        light_count: scene.lights.len() as u32,
        roulette_depth: opts.roulette_depth,
        _pad: [0; 2],
    }
}
