//! A flat scene packed for the kernel: its primitives, BVH, lights, materials and images as the
//! shared structs of `shared::layout`, the render's parameters, and the WGSL text of the shared
//! declarations and constants.

use crate::assets::image::Image;
use crate::assets::texture::Texture;
use crate::options::RenderOptions;
use crate::scene::Background;
use crate::scene::flat::{FlatScene, Light, LightShape};
use crate::shared::layout::*;
use std::sync::Arc;

/// The kernel's BVH nodes (`accel::quantized`, four wide: `GpuBvhNode`), in the order
/// `FlatScene::kernel_bvh` holds them (the root's first).
pub fn gpu_bvh(bvh: &crate::accel::quantized::QuantizedBvh) -> Vec<GpuBvhNode> {
    let bytes = |q: &[[u8; 4]; 3]| q.map(u32::from_le_bytes);
    (bvh.nodes.iter())
        .map(|n| {
            let [x, y, z] = n.exponents.map(u32::from);
            GpuBvhNode {
                origin: n.origin.to_array(),
                steps: x | y << 8 | z << 16,
                children: n.children,
                low: bytes(&n.low),
                lanes: n.count as u32,
                high: bytes(&n.high),
                _pad: 0,
            }
        })
        .collect()
}

/// Constants the CPU reference and the kernel share, as WGSL `const` declarations.
fn wgsl_constants() -> String {
    use crate::shared::primitive::PRIMITIVE_INDEX_BITS;
    use crate::shared::ray::{
        OFFSET_FLOAT_SCALE, OFFSET_INT_SCALE, OFFSET_NEAR_ORIGIN, POINT_ERROR,
    };
    let kinds = crate::material::KINDS
        .iter()
        .map(|k| (format!("MAT_{}", k.feature), k.kind.literal()));
    let constants = [
        ("WORKGROUP_SIZE", WORKGROUP_SIZE.literal()),
        ("ACCUM_WORDS", ACCUM_WORDS.literal()),
        ("NOT_FINITE_BITS", crate::film::NOT_FINITE_BITS.literal()),
        ("ACCUM_MEAN", ACCUM_MEAN.literal()),
        ("ACCUM_COUNT", ACCUM_COUNT.literal()),
        ("ACCUM_M2", ACCUM_M2.literal()),
        ("ACCUM_INVALID", ACCUM_INVALID.literal()),
        ("ACCUM_M2_EXPONENT", ACCUM_M2_EXPONENT.literal()),
        ("ACCUM_EVEN_SUM", ACCUM_EVEN_SUM.literal()),
        ("ACCUM_ODD_SUM", ACCUM_ODD_SUM.literal()),
        ("PRIMITIVE_INDEX_BITS", PRIMITIVE_INDEX_BITS.literal()),
        ("TEXTURE_NONE", TEXTURE_NONE.literal()),
        ("TEXTURE_CHECKER", TEXTURE_CHECKER.literal()),
        ("TEXTURE_UV_CHECKER", TEXTURE_UV_CHECKER.literal()),
        ("TEXTURE_IMAGE", TEXTURE_IMAGE.literal()),
        (
            "WRAP_CLAMP",
            crate::assets::image_lookup::WRAP_CLAMP.literal(),
        ),
        (
            "WRAP_MIRROR",
            crate::assets::image_lookup::WRAP_MIRROR.literal(),
        ),
        (
            "LOOKUP_NEAREST",
            crate::assets::image_lookup::LOOKUP_NEAREST.literal(),
        ),
        (
            "LOOKUP_UV1",
            crate::assets::image_lookup::LOOKUP_UV1.literal(),
        ),
        (
            "MIN_ALPHA",
            crate::material::microfacet::MIN_ALPHA.literal(),
        ),
        (
            "INDEX_MATCHED",
            crate::material::dielectric::INDEX_MATCHED.literal(),
        ),
        ("ALPHA_MASK", crate::assets::alpha::ALPHA_MASK.literal()),
        (
            "PBR_SAMPLES_LIGHTS",
            crate::material::pbr::PBR_SAMPLES_LIGHTS.literal(),
        ),
        (
            "PBR_TRANSMISSION_IN_RED",
            crate::material::pbr::PBR_TRANSMISSION_IN_RED.literal(),
        ),
        ("ALPHA_BLEND", crate::assets::alpha::ALPHA_BLEND.literal()),
        ("KIND_ENVIRONMENT", KIND_ENVIRONMENT.literal()),
        ("KIND_POINT", KIND_POINT.literal()),
        ("KIND_DIRECTIONAL", KIND_DIRECTIONAL.literal()),
        ("ONE_BELOW", crate::shared::constants::ONE_BELOW.literal()),
        (
            "PARALLEL_DENOMINATOR",
            crate::shared::constants::PARALLEL_DENOMINATOR.literal(),
        ),
        (
            "SUBDIVIDED_MAX_TEXELS",
            crate::assets::environment::SUBDIVIDED_MAX_TEXELS.literal(),
        ),
        (
            "KIND_TRIANGLE",
            crate::shared::primitive::KIND_TRIANGLE.literal(),
        ),
        (
            "KIND_INSTANCE",
            crate::shared::primitive::KIND_INSTANCE.literal(),
        ),
        ("BVH_LEAF", BVH_LEAF.literal()),
        ("BVH_LEAF_COUNT_SHIFT", BVH_LEAF_COUNT_SHIFT.literal()),
        ("BVH_LEAF_OFFSET_LIMIT", BVH_LEAF_OFFSET_LIMIT.literal()),
        ("BOX_FAR_WIDENING", crate::accel::BOX_FAR_WIDENING.literal()),
        ("BVH_EMPTY", crate::accel::quantized::EMPTY.literal()),
        ("BVH_MISSED", crate::accel::quantized::MISSED.literal()),
        ("BVH_NEAREST", crate::accel::quantized::NEAREST.literal()),
        (
            "BVH_GROUP_LANES_SHIFT",
            crate::accel::quantized::GROUP_LANES_SHIFT.literal(),
        ),
        (
            "BVH_GROUP_COUNT_SHIFT",
            crate::accel::quantized::GROUP_COUNT_SHIFT.literal(),
        ),
        (
            "BVH_GROUP_NODE_LIMIT",
            crate::accel::quantized::GROUP_NODE_LIMIT.literal(),
        ),
        ("TEXEL_ROW", TEXEL_ROW.literal()),
        (
            "MAX_SURVIVAL",
            crate::shared::constants::MAX_SURVIVAL.literal(),
        ),
        (
            "MIN_LIGHT_COSINE",
            crate::shared::constants::MIN_LIGHT_COSINE.literal(),
        ),
        ("POINT_ERROR", POINT_ERROR.literal()),
        (
            "MIN_DISTANCE_SQUARED",
            crate::scene::punctual::MIN_DISTANCE_SQUARED.literal(),
        ),
        (
            "MIN_COSINE",
            crate::material::microfacet::MIN_COSINE.literal(),
        ),
        ("OFFSET_NEAR_ORIGIN", OFFSET_NEAR_ORIGIN.literal()),
        ("OFFSET_FLOAT_SCALE", OFFSET_FLOAT_SCALE.literal()),
        ("OFFSET_INT_SCALE", OFFSET_INT_SCALE.literal()),
        ("SKY_ZENITH", crate::shared::constants::SKY_ZENITH.literal()),
        (
            "COAT_TABLE_SIZE",
            (crate::material::coat_table::COAT_TABLE_SIZE as u32).literal(),
        ),
        (
            "NO_COAT_TABLE",
            crate::material::coat_table::NO_COAT_TABLE.literal(),
        ),
        ("REPLICAS", crate::shared::sampler::REPLICAS.literal()),
        (
            "GROUP_DIMENSIONS",
            crate::shared::sampler::GROUP_DIMENSIONS.literal(),
        ),
        (
            "MICROSURFACE_MAX_SCATTERINGS",
            crate::material::microsurface::MAX_SCATTERINGS.literal(),
        ),
        (
            "MICROSURFACE_MIN_SIN",
            crate::material::microsurface::MIN_SIN.literal(),
        ),
        (
            "MICROSURFACE_MIN_COS",
            crate::material::microsurface::MIN_COS.literal(),
        ),
    ]
    .map(|(name, value)| (name.to_string(), value));
    let bindings = super::bindings::BINDINGS
        .iter()
        .map(|b| (b.wgsl_name().to_string(), b.number().literal()));
    let lobes = crate::material::Lobe::wgsl_constants()
        .map(|(name, bits)| (name.to_string(), bits.literal()));
    let shapes = super::shape_dispatch::kind_constants();
    let mut out = String::new();
    for (name, value) in kinds
        .chain(constants)
        .chain(shapes)
        .chain(bindings)
        .chain(lobes)
    {
        let ty = if value.starts_with("vec3f") {
            "vec3f"
        } else if value.ends_with('u') {
            "u32"
        } else {
            "f32"
        };
        out.push_str(&format!("const {name}: {ty} = {value};\n"));
    }
    out
}

/// The data both sides share, as WGSL: the struct declarations and the constants, generated
/// from their Rust definitions; the kernel's modules start after it.
pub fn wgsl_shared() -> String {
    let mut out = String::from(
        "// ---- shared with Rust, generated (src/shared/layout.rs, src/gpu/layout.rs) ----\n",
    );
    out.push_str(&wgsl_constants());
    out.push_str(&wgsl_declarations());
    out.push_str(&crate::shape::wgsl_declarations());
    out.push('\n');
    out.push_str(&crate::material::BsdfSample::wgsl_declaration());
    out.push('\n');
    out.push_str(&super::kernel_state::wgsl_declarations());
    out
}

/// Scene buffers as uploaded. Empty arrays hold one zeroed element: a binding cannot be empty.
pub struct SceneBuffers {
    /// Each shape kind's records (in the order of `shape::KINDS`), as bytes.
    pub shapes: Vec<ShapeRecords>,
    pub triangles: Vec<GpuTriangle>,
    /// Per triangle its three corner normals, nine floats (the kernel's `triangle_normals`),
    /// when the scene has shading normals.
    pub triangle_normals: Vec<f32>,
    /// Per triangle its three corner texture coordinates, six floats (the kernel's
    /// `triangle_uvs`), when the scene's meshes have them and a material reads them.
    pub triangle_uvs: Vec<f32>,
    /// Per triangle its three corner second texture coordinates, six floats (the kernel's
    /// `triangle_uvs1`), when a material reads them.
    pub triangle_uvs1: Vec<f32>,
    /// Per triangle its three corner tangents, twelve floats (the kernel's
    /// `triangle_tangents`), when some mesh is normal-mapped.
    pub triangle_tangents: Vec<f32>,
    /// Per triangle its three corner vertex colours, nine floats (the kernel's
    /// `triangle_colors`), when some mesh has them.
    pub triangle_colors: Vec<f32>,
    pub bvh_nodes: Vec<GpuBvhNode>,
    /// Packed primitive references, in the BVH's leaf order.
    pub bvh_primitives: Vec<u32>,
    pub instances: Vec<GpuInstance>,
    pub materials: Vec<GpuMaterial>,
    pub lights: Vec<GpuLight>,
    pub images: ImageArray,
}

/// Every image a scene reads, in one array of vec4f (the kernel's `images`): each image's
/// texels (one vec4f each: RGB and 0, rows from the top), and after them the environment's
/// CDFs (a vec4f per value: the rows of cells', then each row's cells', whose entry k below the
/// row's width holds cell k's density in .z; `assets::environment::Distribution`). Positions
/// count vec4fs.
#[derive(Clone, Debug, Default)]
pub struct ImageArray {
    /// The values, four per vec4f (empty in a plan).
    pub values: Vec<f32>,
    /// (image, where its texels start).
    placed: Vec<(Arc<Image>, u32)>,
    /// Where the environment's texels and its CDFs start.
    pub environment: Option<[u32; 2]>,
    /// How many values it holds (at least 1: a binding cannot be empty).
    len: u64,
}

/// The image of a material's emission on top of its surface, if it has one.
fn emission_image(m: &crate::scene::Material) -> Option<&Arc<Image>> {
    match &m.emission()?.radiance {
        Texture::Image(image) => Some(image),
        _ => None,
    }
}

/// Whether `a` and `b` share their texels (copies read another way or scaled).
fn same_texels(a: &Image, b: &Image) -> bool {
    std::ptr::eq(a.texels.as_ptr(), b.texels.as_ptr())
}

impl ImageArray {
    pub fn new(scene: &FlatScene) -> Self {
        Self::lay_out(scene, true)
    }

    /// The largest of the materials' images (what an error about their size names).
    pub fn largest_texture(&self) -> Option<Arc<Image>> {
        self.placed
            .iter()
            .map(|(image, _)| image.clone())
            .max_by_key(|i| i.width as u64 * i.height as u64)
    }

    /// Where everything goes, without the values.
    pub fn plan(scene: &FlatScene) -> Self {
        Self::lay_out(scene, false)
    }

    fn lay_out(scene: &FlatScene, fill: bool) -> Self {
        let mut out = ImageArray::default();
        // Texels as vec4f (RGB and 0): one load each.
        // Counted in u64: many large images overflow u32, and the size checked against the
        // device's binding limit must be the true one. (Past that check, offsets fit in u32.)
        let mut len = 0u64;
        // Each image's texels once, however many materials (or the environment) read them,
        // through however many lookups and factors.
        let mut place = |out: &mut ImageArray, image: Arc<Image>| {
            if let Some(&(_, at)) = out.placed.iter().find(|(i, _)| same_texels(i, &image)) {
                return at;
            }
            let at = len as u32;
            len += image.width as u64 * image.height as u64;
            if fill {
                for rgb in image.texels.chunks_exact(3) {
                    out.values.extend(rgb);
                    out.values.push(0.0);
                }
            }
            out.placed.push((image, at));
            at
        };
        for image in scene.materials.iter().flat_map(|m| m.images()) {
            place(&mut out, image);
        }
        if let Background::Environment(env) = &scene.background {
            let d = env.distribution();
            let texels = place(&mut out, env.image.clone());
            // Its CDFs, a vec4f per value: (value, the guide's slot as a number, density, 0),
            // the guide 0 past a table's last slot. The rows' table (cells' rows + 1), then each
            // row's cells' (cells across + 1 each), each entry but the last holding its cell's
            // density, so that a pick finds it beside the value it stopped at.
            let cdfs = len as u32;
            len += (d.rows.entries.len() + d.columns.entries.len()) as u64;
            if fill {
                for entry in &d.rows.entries {
                    // The guide is exact as f32: a table has at most 2^15 slots.
                    out.values
                        .extend([entry.value, entry.guide as f32, 0.0, 0.0]);
                }
                for (i, entry) in d.columns.entries.iter().enumerate() {
                    let (row, k) = (i / (d.width + 1), i % (d.width + 1));
                    let density = if k < d.width {
                        d.density[row * d.width + k]
                    } else {
                        0.0
                    };
                    out.values
                        .extend([entry.value, entry.guide as f32, density, 0.0]);
                }
            }
            out.environment = Some([texels, cdfs]);
        }
        out.len = 4 * len.max(1);
        if fill && out.values.is_empty() {
            out.values.resize(4, 0.0);
        }
        out
    }

    /// Where `image`'s texels start (it must have been placed).
    pub fn texels_of(&self, image: &Image) -> u32 {
        self.placed
            .iter()
            .find(|(i, _)| same_texels(i, image))
            .map_or(0, |(_, at)| *at)
    }

    /// Its size in bytes.
    pub fn bytes(&self) -> u64 {
        self.len * 4
    }
}

/// Per triangle its corners' values as floats, one after another (a storage array of the
/// kernel's); one float, never read, where there are none (wgpu binds no empty buffer).
fn corner_floats<T: Copy, const N: usize>(
    corners: &[[T; 3]],
    floats: fn(&T) -> [f32; N],
) -> Vec<f32> {
    let mut out: Vec<f32> = corners.iter().flatten().flat_map(floats).collect();
    if out.is_empty() {
        out.push(0.0);
    }
    out
}

/// GPU memory a scene's meshes and hierarchy take: triangles, their corner normals, BVH nodes and
/// primitive references, and instances (what `rt-gpu bench` reports per triangle).
pub fn geometry_bytes(scene: &FlatScene) -> usize {
    let buffers = SceneBuffers::new(scene);
    std::mem::size_of_val(&buffers.triangles[..])
        + std::mem::size_of_val(&buffers.triangle_normals[..])
        + std::mem::size_of_val(&buffers.triangle_uvs[..])
        + std::mem::size_of_val(&buffers.triangle_uvs1[..])
        + std::mem::size_of_val(&buffers.triangle_tangents[..])
        + std::mem::size_of_val(&buffers.triangle_colors[..])
        + std::mem::size_of_val(&buffers.bvh_nodes[..])
        + std::mem::size_of_val(&buffers.bvh_primitives[..])
        + std::mem::size_of_val(&buffers.instances[..])
}

impl SceneBuffers {
    pub fn new(scene: &FlatScene) -> Self {
        let shapes = ShapeRecords::of(scene);
        // Where each image goes (its values are gathered only for the upload).
        let images = ImageArray::plan(scene);
        let mut materials: Vec<GpuMaterial> = scene
            .materials
            .iter()
            .map(|m| {
                let mut gpu = m.gpu();
                for texture in m.textures() {
                    if let Texture::Image(image) = texture {
                        gpu.texture_image = images.texels_of(image);
                    }
                }
                if let Some(map) = m.normal_map() {
                    gpu.normal_map_image = images.texels_of(&map.image);
                }
                if let Some(map) = m.coat_normal_map() {
                    gpu.coat_normal_map_image = images.texels_of(&map.image);
                }
                if let Some(image) = m.parameter_image() {
                    gpu.parameter_image = images.texels_of(image);
                }
                if let Some(image) = m.table_image() {
                    gpu.sheen_table = images.texels_of(image);
                }
                let [layers, sheen, specular, specular_color] = m.layer_images();
                if let Some(image) = layers {
                    gpu.layer_image = images.texels_of(image);
                }
                if let Some(image) = sheen {
                    gpu.sheen_image = images.texels_of(image);
                }
                if let Some(image) = specular {
                    gpu.specular_image = images.texels_of(image);
                }
                if let Some(image) = specular_color {
                    gpu.specular_color_image = images.texels_of(image);
                }
                if let Some(image) = m.alpha().and_then(|a| a.image.as_ref()) {
                    gpu.alpha_image = images.texels_of(image);
                }
                if let Some(image) = emission_image(m) {
                    gpu.emission_image = images.texels_of(image);
                }
                gpu
            })
            .collect();
        let mut triangles: Vec<GpuTriangle> = scene
            .triangles
            .iter()
            .map(|t| GpuTriangle {
                p0: t.p0.to_array(),
                material: t.material,
                p1: t.p1.to_array(),
                light: t.light,
                p2: t.p2.to_array(),
                _pad: 0,
            })
            .collect();
        let kernel_bvh = scene.kernel_bvh();
        let mut bvh_nodes = gpu_bvh(kernel_bvh);
        let mut bvh_primitives = scene.bvh.primitives.clone();
        let mut instances: Vec<GpuInstance> = (scene.instances.iter().enumerate())
            .map(|(index, i)| {
                let [to_world_x, to_world_y, to_world_z] = i.to_world.map(|r| r.to_array());
                let [to_local_x, to_local_y, to_local_z] = i.to_local.map(|r| r.to_array());
                GpuInstance {
                    to_world_x,
                    to_world_y,
                    to_world_z,
                    to_local_x,
                    to_local_y,
                    to_local_z,
                    root: kernel_bvh.instance_roots[index],
                    material: i.material,
                    _pad: [0; 2],
                }
            })
            .collect();
        if instances.is_empty() {
            instances.push(GpuInstance::default());
        }
        if triangles.is_empty() {
            triangles.push(GpuTriangle::default());
        }
        if bvh_nodes.is_empty() {
            // Only a lone leaf, or nothing: never traversed as a node, but a popped instance's
            // entry may read node 0 (`traverse` in shaders/accel.wgsl), so there is one.
            bvh_nodes.push(GpuBvhNode::default());
        }
        let triangle_normals = corner_floats(&scene.triangle_normals, glam::Vec3::to_array);
        let triangle_uvs = corner_floats(&scene.triangle_uvs, glam::Vec2::to_array);
        let triangle_uvs1 = corner_floats(&scene.triangle_uvs1, glam::Vec2::to_array);
        let triangle_tangents = corner_floats(&scene.triangle_tangents, glam::Vec4::to_array);
        let triangle_colors = corner_floats(&scene.triangle_colors, glam::Vec3::to_array);
        if bvh_primitives.is_empty() {
            bvh_primitives.push(0);
        }
        if materials.is_empty() {
            materials.push(GpuMaterial::default());
        }
        let mut lights: Vec<GpuLight> = scene.lights.iter().map(gpu_light).collect();
        if lights.is_empty() {
            lights.push(GpuLight::default());
        }
        SceneBuffers {
            shapes,
            triangles,
            triangle_normals,
            triangle_uvs,
            triangle_uvs1,
            triangle_tangents,
            triangle_colors,
            bvh_nodes,
            bvh_primitives,
            instances,
            materials,
            lights,
            images,
        }
    }
}

/// One shape kind's array as the kernel reads it.
pub struct ShapeRecords {
    /// The records, or one zeroed record where there are none (a binding cannot be empty).
    pub bytes: Vec<u8>,
    /// How many bytes a record takes.
    pub record: usize,
    /// How many of the records are the scene's.
    pub count: usize,
}

impl ShapeRecords {
    /// Every shape kind's, in the order of `shape::KINDS`.
    fn of(scene: &FlatScene) -> Vec<ShapeRecords> {
        use crate::shape::{ShapeKind, ShapeVisitor, SurfaceShape};
        struct Records(Vec<ShapeRecords>);
        impl ShapeVisitor for Records {
            fn visit<S: SurfaceShape>(&mut self, _: &'static ShapeKind, shapes: &[S]) {
                let mut records: Vec<S::Gpu> = shapes.iter().map(S::gpu).collect();
                if records.is_empty() {
                    records.push(S::Gpu::default());
                }
                self.0.push(ShapeRecords {
                    bytes: bytemuck::cast_slice(&records).to_vec(),
                    record: std::mem::size_of::<S::Gpu>(),
                    count: shapes.len(),
                });
            }
        }
        let mut records = Records(Vec::new());
        scene.shapes.visit(&mut records);
        records.0
    }

    /// Padded with zeroed records to `capacity` (a uniform array's fixed length).
    pub fn resize(&mut self, capacity: usize) {
        self.bytes.resize(capacity * self.record, 0);
    }
}

/// A light as the kernel reads it: a tagged union of the `LightShape`s.
fn gpu_light(l: &Light) -> GpuLight {
    let mut out = GpuLight {
        cdf: l.cdf,
        pick: l.pick,
        ..Default::default()
    };
    match l.shape {
        LightShape::Surface { kind, light } => {
            out.kind = kind;
            out.position = light.position.to_array();
            out.u = light.u.to_array();
            out.v = light.v.to_array();
            out.normal = light.normal.to_array();
            out.size = light.size;
        }
        LightShape::Triangle {
            corner,
            u,
            v,
            normal,
            inv_area,
        } => {
            out.kind = crate::shared::primitive::KIND_TRIANGLE;
            out.position = corner.to_array();
            out.u = u.to_array();
            out.v = v.to_array();
            out.normal = normal.to_array();
            out.size = inv_area;
        }
        // Its parameters are the render's (GpuParams::environment_*).
        LightShape::Environment(_) => out.kind = KIND_ENVIRONMENT,
        LightShape::Point {
            position,
            intensity,
            axis,
            ramp,
        } => {
            out.kind = KIND_POINT;
            out.position = position.to_array();
            out.u = intensity.to_array();
            out.normal = axis.to_array();
            out.v = [ramp[0], ramp[1], 0.0];
        }
        LightShape::Directional { toward, irradiance } => {
            out.kind = KIND_DIRECTIONAL;
            out.normal = toward.to_array();
            out.u = irradiance.to_array();
        }
    }
    out
}

/// The per-render parameters of rendering `scene` with `opts`.
pub fn base_params(scene: &FlatScene, opts: &RenderOptions) -> GpuParams {
    let c = &scene.camera;
    let (background, sky) = match scene.background {
        Background::Constant(c) => (c.to_array(), 0),
        Background::Sky => ([0.0; 3], 1),
        Background::Environment(_) => ([0.0; 3], 0),
    };
    let mut environment = ([1.0, 0.0], [0; 2], [0; 2], 0.0);
    if let Background::Environment(env) = &scene.background {
        let slots = ImageArray::plan(scene).environment.unwrap_or_default();
        environment = (
            env.rotation,
            slots,
            [env.image.width, env.image.height],
            env.strength,
        );
    }
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
        _pad0: 0,
        up: c.up.to_array(),
        _pad1: 0,
        background,
        light_count: scene.lights.len() as u32,
        sky,
        roulette_depth: opts.roulette_depth,
        environment_rotation: environment.0,
        environment_texels: environment.1[0],
        environment_cdfs: environment.1[1],
        environment_width: environment.2[0],
        environment_height: environment.2[1],
        environment_strength: environment.3,
        sample_loop_cost: 0,
        traversal_weight: 1,
        loop_budget: u32::MAX,
    }
}

/// A dispatch over the whole image from `opts.first_sample`, no samples yet; the renderer sets
/// the tile and the sample range.
pub fn whole_image_dispatch(opts: &RenderOptions) -> GpuDispatch {
    GpuDispatch {
        tile_origin: [0, 0],
        tile_size: [opts.width, opts.height],
        first_sample: opts.first_sample,
        sample_count: 0,
        samples_before: 0,
        seed: opts.seed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::Bvh;
    use crate::accel::tests::random_items;

    /// The kernel's nodes are the quantized hierarchy's, byte for byte where the kernel reads
    /// them: references, origin, steps and each child's bounds in its lane's byte.
    #[test]
    fn the_kernels_nodes_are_the_quantized_hierarchys() {
        for n in [2, 5, 300] {
            let mut bvh = Bvh::build(&mut random_items(n));
            let mesh_root = bvh.append_hierarchy(Bvh::build(&mut random_items(777)));
            let q = crate::accel::quantized::QuantizedBvh::new(&bvh, [mesh_root]);
            let nodes = gpu_bvh(&q);
            assert_eq!(nodes.len(), q.nodes.len());
            for (packed, node) in nodes.iter().zip(&q.nodes) {
                assert_eq!(packed.children, node.children);
                assert_eq!(packed.origin, node.origin.to_array());
                assert_eq!(packed.lanes, node.count as u32);
                for axis in 0..3 {
                    assert_eq!(
                        (packed.steps >> (8 * axis)) & 0xff,
                        node.exponents[axis] as u32
                    );
                    for lane in 0..4 {
                        let byte = |w: u32| (w >> (8 * lane)) & 0xff;
                        assert_eq!(byte(packed.low[axis]), node.low[axis][lane] as u32);
                        assert_eq!(byte(packed.high[axis]), node.high[axis][lane] as u32);
                    }
                }
            }
        }
    }
}
