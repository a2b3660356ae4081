//! The GPU's view of a scene: `#[repr(C)]` structs mirrored one-to-one by the WGSL structs in
//! `shaders/common.wgsl` (vec3f is 16-byte aligned there, hence the explicit padding).
//! `tests/gpu_layout.rs` checks sizes and field offsets against naga's layout of the WGSL.

use crate::options::RenderOptions;
use crate::scene::Background;
use crate::scene::flat::{FlatScene, Light, LightShape};
use crate::scene::image::Image;
use crate::scene::texture::Texture;
use bytemuck::{Pod, Zeroable};

/// A Rust type as a WGSL type, and a value of it as a WGSL literal.
pub trait WgslType {
    const WGSL: &'static str;
    fn literal(&self) -> String;
}

/// A WGSL float literal that reads back as exactly `x`.
pub fn float_literal(x: f32) -> String {
    format!("{x:?}")
}

impl WgslType for f32 {
    const WGSL: &'static str = "f32";
    fn literal(&self) -> String {
        float_literal(*self)
    }
}

impl WgslType for u32 {
    const WGSL: &'static str = "u32";
    fn literal(&self) -> String {
        format!("{self}u")
    }
}

impl WgslType for [f32; 3] {
    const WGSL: &'static str = "vec3f";
    fn literal(&self) -> String {
        let [x, y, z] = self.map(float_literal);
        format!("vec3f({x}, {y}, {z})")
    }
}

impl WgslType for [u32; 3] {
    const WGSL: &'static str = "vec3u";
    fn literal(&self) -> String {
        format!("vec3u({}u, {}u, {}u)", self[0], self[1], self[2])
    }
}

impl WgslType for [f32; 4] {
    const WGSL: &'static str = "vec4f";
    fn literal(&self) -> String {
        let [x, y, z, w] = self.map(float_literal);
        format!("vec4f({x}, {y}, {z}, {w})")
    }
}

impl WgslType for [f32; 2] {
    const WGSL: &'static str = "vec2f";
    fn literal(&self) -> String {
        let [x, y] = self.map(float_literal);
        format!("vec2f({x}, {y})")
    }
}

impl WgslType for [u32; 2] {
    const WGSL: &'static str = "vec2u";
    fn literal(&self) -> String {
        format!("vec2u({}u, {}u)", self[0], self[1])
    }
}

/// A struct the kernel shares: its WGSL declaration and constructor calls are generated from
/// the Rust definition, so the two cannot drift apart. Fields named `_pad` are explicit padding
/// where WGSL pads implicitly (a vec3f is 16-byte aligned); `tests/gpu_layout.rs` checks that
/// naga lays the generated declaration out exactly as Rust does.
pub trait WgslStruct {
    const WGSL_NAME: &'static str;
    /// (name, WGSL type) of every field, padding included, in order.
    fn wgsl_fields() -> &'static [(&'static str, &'static str)];
    /// Every field's value as a WGSL literal, padding included, in order.
    fn wgsl_values(&self) -> Vec<String>;
    /// Rust's layout: the struct's size and each field's offset, padding included.
    fn rust_layout() -> (usize, Vec<(&'static str, usize)>);

    /// `struct Name { field: type, ... }`, without the padding fields.
    fn wgsl_declaration() -> String {
        let mut out = format!("struct {} {{\n", Self::WGSL_NAME);
        for (name, ty) in Self::wgsl_fields() {
            if !name.starts_with("_pad") {
                out.push_str(&format!("    {name}: {ty},\n"));
            }
        }
        out.push_str("}\n");
        out
    }

    /// `Name(v1, v2, ...)`, a WGSL constructor of this value.
    fn wgsl_constructor(&self) -> String {
        let values: Vec<String> = Self::wgsl_fields()
            .iter()
            .zip(self.wgsl_values())
            .filter(|((name, _), _)| !name.starts_with("_pad"))
            .map(|(_, value)| value)
            .collect();
        format!("{}({})", Self::WGSL_NAME, values.join(", "))
    }
}

/// Defines a `#[repr(C)]` Pod struct and its [`WgslStruct`] description from one field list.
macro_rules! gpu_struct {
    (
        $(#[$meta:meta])*
        pub struct $name:ident as $wgsl:literal {
            $($(#[$field_meta:meta])* $field:ident: $ty:ty,)*
        }
    ) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
        pub struct $name {
            $($(#[$field_meta])* pub $field: $ty,)*
        }

        impl WgslStruct for $name {
            const WGSL_NAME: &'static str = $wgsl;
            fn wgsl_fields() -> &'static [(&'static str, &'static str)] {
                &[$((stringify!($field), <$ty as WgslType>::WGSL),)*]
            }
            fn wgsl_values(&self) -> Vec<String> {
                vec![$(WgslType::literal(&self.$field),)*]
            }
            fn rust_layout() -> (usize, Vec<(&'static str, usize)>) {
                (
                    std::mem::size_of::<$name>(),
                    vec![$((stringify!($field), std::mem::offset_of!($name, $field)),)*],
                )
            }
        }
    };
}

gpu_struct! {
    pub struct GpuSphere as "Sphere" {
        center: [f32; 3],
        /// Negative: the normal faces inward.
        radius: f32,
        material: u32,
        /// 1 + its index in the light list; 0 when it does not emit.
        light: u32,
        _pad: [u32; 2],
    }
}

gpu_struct! {
    /// The parallelogram q + a u + b v, a, b in [0, 1] (see `scene::flat::Quad` for the axes).
    pub struct GpuQuad as "Quad" {
        q: [f32; 3],
        /// Plane: dot(normal, p) = d.
        d: f32,
        normal: [f32; 3],
        material: u32,
        alpha_axis: [f32; 3],
        /// 1 + its index in the light list; 0 when it does not emit.
        light: u32,
        beta_axis: [f32; 3],
        /// Counts as hit this far (a fraction of each edge) past its edges.
        edge_tolerance: f32,
    }
}

gpu_struct! {
    /// A triangle p0 p1 p2, front face counter-clockwise (see `scene::flat::Triangle`).
    pub struct GpuTriangle as "Triangle" {
        p0: [f32; 3],
        material: u32,
        p1: [f32; 3],
        /// 1 + its index in the light list; 0 when it does not emit.
        light: u32,
        p2: [f32; 3],
        _pad: u32,
    }
}

gpu_struct! {
    /// A placed mesh (see `scene::flat::Instance`): rows of its 3x4 affine maps from mesh to
    /// scene coordinates and back, where its mesh's BVH starts, its material.
    pub struct GpuInstance as "Instance" {
        to_world_x: [f32; 4],
        to_world_y: [f32; 4],
        to_world_z: [f32; 4],
        to_local_x: [f32; 4],
        to_local_y: [f32; 4],
        to_local_z: [f32; 4],
        root: u32,
        material: u32,
        _pad: [u32; 2],
    }
}

gpu_struct! {
    /// An interior node of the BVH as the kernel reads it (see `gpu_bvh`): both children's
    /// boxes and references, so that one read of four texels decides which children a ray
    /// enters, and a leaf is known as one before it is reached.
    pub struct GpuBvhNode as "BvhNode" {
        first_min: [f32; 3],
        first: u32,
        first_max: [f32; 3],
        second: u32,
        second_min: [f32; 3],
        _pad0: u32,
        second_max: [f32; 3],
        _pad1: u32,
    }
}

/// A child reference of `GpuBvhNode`: a leaf's has this bit, its primitive count (below
/// `BVH_LEAF_COUNT_LIMIT`) in the bits `BVH_LEAF_COUNT_SHIFT` up and where its primitives
/// start in the reference array below; an interior node's is its index among the kernel's
/// nodes.
pub const BVH_LEAF: u32 = 1 << 31;
pub const BVH_LEAF_COUNT_SHIFT: u32 = 28;
/// Where a leaf's primitives may start: below 2^28 (a quarter of a billion references).
pub const BVH_LEAF_OFFSET_LIMIT: u32 = 1 << BVH_LEAF_COUNT_SHIFT;
/// Leaves of this many primitives or more do not fit a reference's count bits.
pub const BVH_LEAF_COUNT_LIMIT: u32 = 1 << (31 - BVH_LEAF_COUNT_SHIFT);

/// The kernel's BVH: the host's interior nodes, in their order (the root's first), each with
/// its two children's boxes and references (`GpuBvhNode`); the same hierarchy the CPU
/// traverses, with the same decisions, laid out for one read per node entered (a node's own
/// box is read by its parent). Also the reference of every host node, by its index.
pub fn gpu_bvh(bvh: &crate::accel::Bvh) -> (Vec<GpuBvhNode>, Vec<u32>) {
    let mut interior = 0;
    let references: Vec<u32> = bvh
        .nodes
        .iter()
        .map(|n| {
            if n.is_leaf() {
                leaf_reference(n)
            } else {
                interior += 1;
                interior - 1
            }
        })
        .collect();
    let nodes = bvh
        .nodes
        .iter()
        .enumerate()
        .filter(|(_, n)| !n.is_leaf())
        .map(|(i, n)| {
            let (first, second) = (&bvh.nodes[i + 1], &bvh.nodes[n.offset as usize]);
            GpuBvhNode {
                first_min: first.min.to_array(),
                first: references[i + 1],
                first_max: first.max.to_array(),
                second: references[n.offset as usize],
                second_min: second.min.to_array(),
                _pad0: 0,
                second_max: second.max.to_array(),
                _pad1: 0,
            }
        })
        .collect();
    (nodes, references)
}

fn leaf_reference(leaf: &crate::accel::Node) -> u32 {
    const _: () = assert!((crate::accel::MAX_LEAF as u32) < BVH_LEAF_COUNT_LIMIT);
    BVH_LEAF | (leaf.count << BVH_LEAF_COUNT_SHIFT) | leaf.offset
}

/// Where the kernel's traversal of the scene starts: its root's reference (`gpu_bvh`); an
/// empty leaf for an empty hierarchy.
pub fn bvh_root(bvh: &crate::accel::Bvh) -> u32 {
    match bvh.nodes.first() {
        Some(root) if !root.is_leaf() => 0,
        Some(root) => leaf_reference(root),
        None => BVH_LEAF,
    }
}

/// Texels per row of the textures the kernel reads arrays from (`Rgba32Uint`, texel i at
/// column i % TEXEL_ROW of row i / TEXEL_ROW): the BVH's nodes (`bvh_node_texels`, node i is
/// texels 4i to 4i + 3) and the images (`image_texels`, one vec4f
/// of `ImageArray` each). Lavapipe fetches a texel for all its SIMD lanes at once, where it reads
/// a storage buffer at lane-dependent addresses one lane and one word at a time. WebGPU's
/// smallest guaranteed 2D texture (8192 rows) holds 32 M texels: 8 M nodes, 512 MB.
pub const TEXEL_ROW: u32 = 4096;

/// Rows of a texture holding `texels` texels (at least one).
pub fn texel_rows(texels: u64) -> u64 {
    texels.div_ceil(TEXEL_ROW as u64).max(1)
}

gpu_struct! {
    /// A light for next-event estimation (see `scene::flat::Light`): a quad (uniform on its
    /// area) or a sphere (uniform in the cone it subtends), told apart by `kind`.
    pub struct GpuLight as "Light" {
        /// Quad corner, or sphere centre.
        position: [f32; 3],
        /// Chance of picking this light or one before it.
        cdf: f32,
        /// Quad edges.
        u: [f32; 3],
        /// Chance of picking this light.
        pick: f32,
        v: [f32; 3],
        /// `KIND_SPHERE`, `KIND_QUAD` or `KIND_TRIANGLE` (as `PrimitiveRef`), or
        /// `KIND_ENVIRONMENT`: which shape, and so what `size` means.
        kind: u32,
        /// Quad unit normal.
        normal: [f32; 3],
        /// Sphere: |radius|; quad and triangle: 1 / area.
        size: f32,
    }
}

gpu_struct! {
    pub struct GpuMaterial as "Material" {
        // What albedo, emission and param hold is each material's own (its `gpu` method says).
        albedo: [f32; 3],
        /// Index in `material::KINDS`; WGSL `MAT_<FEATURE>`.
        kind: u32,
        emission: [f32; 3],
        param: f32,
        /// The medium inside the object (see `material::Medium`); density 0: none.
        medium_albedo: [f32; 3],
        medium_density: f32,
        medium_g: f32,
        /// The albedo's texture: `TEXTURE_NONE`, `TEXTURE_CHECKER`, `TEXTURE_UV_CHECKER`
        /// (then `albedo` is its even colour) or `TEXTURE_IMAGE` (then `texture_image` is
        /// where its texels start in the images array, and `texture_odd` holds its width and
        /// height).
        texture: u32,
        texture_scale: f32,
        texture_image: u32,
        texture_odd: [f32; 3],
        _pad1: u32,
        /// See `scene::texture::Checker::shift`.
        texture_shift: [f32; 3],
        _pad2: u32,
    }
}

pub const TEXTURE_NONE: u32 = 0;
pub const TEXTURE_CHECKER: u32 = 1;
pub const TEXTURE_UV_CHECKER: u32 = 2;
pub const TEXTURE_IMAGE: u32 = 3;
/// `GpuLight::kind` of the environment (beside the primitive kinds of spheres and quads).
pub const KIND_ENVIRONMENT: u32 = 15;

impl GpuMaterial {
    /// A material whose albedo is `texture`.
    pub fn with_albedo(texture: &Texture) -> Self {
        let (texture, checker) = match texture {
            Texture::Colour(c) => {
                return GpuMaterial {
                    albedo: c.to_array(),
                    ..Default::default()
                };
            }
            Texture::Image(image) => {
                // `texture_image` is set where the scene's images are laid out (SceneBuffers).
                return GpuMaterial {
                    texture: TEXTURE_IMAGE,
                    texture_odd: [image.width as f32, image.height as f32, 0.0],
                    ..Default::default()
                };
            }
            Texture::Checker(c) => (TEXTURE_CHECKER, c),
            Texture::UvChecker(c) => (TEXTURE_UV_CHECKER, c),
        };
        GpuMaterial {
            albedo: checker.even.to_array(),
            texture,
            texture_scale: checker.scale,
            texture_odd: checker.odd.to_array(),
            texture_shift: checker.shift.to_array(),
            ..Default::default()
        }
    }
}

gpu_struct! {
    /// What stays the same for a whole render: a uniform buffer, which drivers such as lavapipe
    /// fold into the kernel (one variant per render: constant loop bounds).
    pub struct GpuParams as "Params" {
        origin: [f32; 3],
        lens_radius: f32,
        to_upper_left: [f32; 3],
        width: u32,
        horizontal: [f32; 3],
        height: u32,
        vertical: [f32; 3],
        max_depth: u32,
        right: [f32; 3],
        _pad0: u32,
        up: [f32; 3],
        _pad1: u32,
        background: [f32; 3],
        light_count: u32,
        /// 1: sky gradient background.
        sky: u32,
        /// Russian roulette from this many segments on; 0: off.
        roulette_depth: u32,
        /// The environment (see `scene::environment`): cos and sin of its rotation about y,
        environment_rotation: [f32; 2],
        /// where its texels and its alias tables (rows, then each row's columns) start in the
        /// images array,
        environment_texels: u32,
        environment_aliases: u32,
        /// its size and its strength.
        environment_width: u32,
        environment_height: u32,
        environment_strength: f32,
        /// The loop budget of BVH kernels (see shaders/accel.wgsl): a bound on the loop
        /// iterations of one sample other than traversals; what each traversal iteration
        /// counts for (the SIMD lanes that wait for each other on lavapipe); and the count at
        /// which an invocation stops taking samples.
        sample_loop_cost: u32,
        traversal_weight: u32,
        loop_budget: u32,
    }
}

gpu_struct! {
    /// What changes from dispatch to dispatch (and the seed, which changes between the renders
    /// of one session): a storage buffer, never folded into the kernel. As uniforms, lavapipe
    /// compiled and kept a kernel variant for every new value: about 1 MB per dispatch.
    pub struct GpuDispatch as "Dispatch" {
        tile_origin: [u32; 2],
        tile_size: [u32; 2],
        /// Random-stream index of the render's first sample: a pixel holding n samples takes
        /// sample first_sample + n next.
        first_sample: u32,
        /// Samples per pixel in this dispatch: each pixel is taken up to `samples_before +
        /// sample_count` samples.
        sample_count: u32,
        /// Samples every pixel held before this dispatch (some may hold more).
        samples_before: u32,
        seed: u32,
    }
}

use crate::exact_sum::SUM_WORDS;

/// The per-pixel accumulator, in u32 words (see shaders/kernel.wgsl): a running f32 mean and the
/// samples taken, M2, the invalid samples and the exponent of M2's scale, the exact sums of the even-index and of the
/// odd-index samples (`SUM_WORDS` words per channel each, word-major: every channel's word 0,
/// then word 1...).
pub const ACCUM_WORDS: u32 = ACCUM_ODD_SUM + 3 * SUM_WORDS as u32;
/// Where each of a pixel's values starts among its words: the running mean (3 words, f32 bits),
/// the samples taken, M2 (3 words, f32 bits), the invalid samples, the exponent M2 is kept at,
/// and the exact sums.
pub const ACCUM_MEAN: u32 = 0;
pub const ACCUM_COUNT: u32 = 3;
pub const ACCUM_M2: u32 = 4;
pub const ACCUM_INVALID: u32 = 7;
/// Per channel (8 bits each), the exponent bits its mean and M2 are scaled by (0 until a
/// non-zero sample; raised with much brighter ones): they are kept of samples scaled by the
/// power of two that brings that exponent near 1, so that f32 squares neither overflow nor
/// underflow at any radiance scale.
pub const ACCUM_M2_EXPONENT: u32 = 8;
pub const ACCUM_EVEN_SUM: u32 = 9;
pub const ACCUM_ODD_SUM: u32 = ACCUM_EVEN_SUM + 3 * SUM_WORDS as u32;
pub const ACCUM_BYTES_PER_PIXEL: u64 = ACCUM_WORDS as u64 * 4;

/// Invocations per workgroup along x and along y.
pub const WORKGROUP_SIZE: u32 = 8;

gpu_struct! {
    /// The output of the `first_bounce` debug entry point, per pixel.
    pub struct GpuFirstBounce as "FirstBounce" {
        point: [f32; 3],
        /// Packed: see `scene::flat::PrimitiveRef::packed`.
        primitive: u32,
        normal: [f32; 3],
        hit: u32,
        /// The scattered direction.
        dir: [f32; 3],
        scattered: u32,
    }
}

/// Constants the CPU reference and the kernel share, as WGSL `const` declarations.
fn wgsl_constants() -> String {
    use crate::cpu::shapes::{OFFSET_FLOAT_SCALE, OFFSET_INT_SCALE, OFFSET_NEAR_ORIGIN};
    use crate::scene::flat::{KIND_QUAD, KIND_SPHERE, PRIMITIVE_INDEX_BITS};
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
        ("KIND_SPHERE", KIND_SPHERE.literal()),
        ("TEXTURE_NONE", TEXTURE_NONE.literal()),
        ("TEXTURE_CHECKER", TEXTURE_CHECKER.literal()),
        ("TEXTURE_UV_CHECKER", TEXTURE_UV_CHECKER.literal()),
        ("TEXTURE_IMAGE", TEXTURE_IMAGE.literal()),
        ("KIND_ENVIRONMENT", KIND_ENVIRONMENT.literal()),
        ("ONE_BELOW", crate::scene::environment::ONE_BELOW.literal()),
        ("KIND_QUAD", KIND_QUAD.literal()),
        ("KIND_TRIANGLE", crate::scene::flat::KIND_TRIANGLE.literal()),
        ("KIND_INSTANCE", crate::scene::flat::KIND_INSTANCE.literal()),
        ("BVH_LEAF", BVH_LEAF.literal()),
        ("BVH_LEAF_COUNT_SHIFT", BVH_LEAF_COUNT_SHIFT.literal()),
        ("BVH_LEAF_OFFSET_LIMIT", BVH_LEAF_OFFSET_LIMIT.literal()),
        ("BOX_FAR_WIDENING", crate::accel::BOX_FAR_WIDENING.literal()),
        ("TEXEL_ROW", TEXEL_ROW.literal()),
        (
            "MAX_SURVIVAL",
            crate::cpu::integrator::MAX_SURVIVAL.literal(),
        ),
        (
            "MIN_LIGHT_COSINE",
            crate::cpu::lights::MIN_LIGHT_COSINE.literal(),
        ),
        ("POINT_ERROR", crate::cpu::shapes::POINT_ERROR.literal()),
        ("OFFSET_NEAR_ORIGIN", OFFSET_NEAR_ORIGIN.literal()),
        ("OFFSET_FLOAT_SCALE", OFFSET_FLOAT_SCALE.literal()),
        ("OFFSET_INT_SCALE", OFFSET_INT_SCALE.literal()),
        ("SKY_ZENITH", crate::cpu::background::SKY_ZENITH.literal()),
        ("REPLICAS", crate::sampler::REPLICAS.literal()),
        (
            "GROUP_DIMENSIONS",
            crate::sampler::GROUP_DIMENSIONS.literal(),
        ),
    ]
    .map(|(name, value)| (name.to_string(), value));
    let mut out = String::new();
    for (name, value) in kinds.chain(constants) {
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

/// A shared struct's WGSL name, Rust size, and the offsets of its fields other than padding.
pub type StructLayout = (&'static str, usize, Vec<(&'static str, usize)>);

fn layout_of<T: WgslStruct>() -> StructLayout {
    let (size, fields) = T::rust_layout();
    let fields = fields
        .into_iter()
        .filter(|(name, _)| !name.starts_with("_pad"))
        .collect();
    (T::WGSL_NAME, size, fields)
}

/// Rust's layout of every struct the kernel shares, for checking against naga's layout of the
/// generated WGSL.
pub fn shared_layouts() -> Vec<StructLayout> {
    vec![
        layout_of::<GpuSphere>(),
        layout_of::<GpuQuad>(),
        layout_of::<GpuTriangle>(),
        layout_of::<GpuBvhNode>(),
        layout_of::<GpuInstance>(),
        layout_of::<GpuLight>(),
        layout_of::<GpuMaterial>(),
        layout_of::<GpuParams>(),
        layout_of::<GpuDispatch>(),
        layout_of::<GpuFirstBounce>(),
    ]
}

/// The data both sides share, as WGSL: the struct declarations and the constants, generated
/// from their Rust definitions; the kernel's modules start after it.
pub fn wgsl_shared() -> String {
    let mut out = String::from("// ---- shared with Rust, generated (src/gpu/layout.rs) ----\n");
    out.push_str(&wgsl_constants());
    for declaration in [
        GpuSphere::wgsl_declaration(),
        GpuQuad::wgsl_declaration(),
        GpuTriangle::wgsl_declaration(),
        GpuBvhNode::wgsl_declaration(),
        GpuInstance::wgsl_declaration(),
        GpuLight::wgsl_declaration(),
        GpuMaterial::wgsl_declaration(),
        GpuParams::wgsl_declaration(),
        GpuDispatch::wgsl_declaration(),
        GpuFirstBounce::wgsl_declaration(),
    ] {
        out.push('\n');
        out.push_str(&declaration);
    }
    out
}

/// Scene buffers as uploaded. Empty arrays hold one zeroed element: a binding cannot be empty.
pub struct SceneBuffers {
    pub spheres: Vec<GpuSphere>,
    pub quads: Vec<GpuQuad>,
    pub triangles: Vec<GpuTriangle>,
    /// Per triangle its three corner normals, nine floats (the kernel's `triangle_normals`),
    /// when the scene has shading normals.
    pub triangle_normals: Vec<f32>,
    pub bvh_nodes: Vec<GpuBvhNode>,
    /// Packed primitive references, in the BVH's leaf order.
    pub bvh_primitives: Vec<u32>,
    pub instances: Vec<GpuInstance>,
    pub materials: Vec<GpuMaterial>,
    pub lights: Vec<GpuLight>,
    pub images: ImageArray,
}

/// Every image a scene reads, in one array of vec4f (the kernel's `images`): each image's
/// texels (one vec4f each: RGB and 0, rows from the top), the environment's with its sampling
/// density as the fourth value, and after them the environment's alias tables (a vec4f per row,
/// then per texel; `scene::environment::Distribution`). Positions count vec4fs.
#[derive(Clone, Debug, Default)]
pub struct ImageArray {
    /// The values, four per vec4f (empty in a plan).
    pub values: Vec<f32>,
    /// (image, where its texels start).
    placed: Vec<(&'static Image, u32)>,
    /// Where the environment's texels and its alias tables start.
    pub environment: Option<[u32; 2]>,
    /// How many values it holds (at least 1: a binding cannot be empty).
    len: u64,
}

impl ImageArray {
    pub fn new(scene: &FlatScene) -> Self {
        Self::lay_out(scene, true)
    }

    /// Where everything goes, without the values.
    pub fn plan(scene: &FlatScene) -> Self {
        Self::lay_out(scene, false)
    }

    fn lay_out(scene: &FlatScene, fill: bool) -> Self {
        let mut out = ImageArray::default();
        // Texels as vec4f (RGB and 0, or for the environment its density): one load each.
        // Counted in u64: many large images overflow u32, and the size checked against the
        // device's binding limit must be the true one. (Past that check, offsets fit in u32.)
        let mut len = 0u64;
        let mut place = |out: &mut ImageArray, image: &Image, w: &dyn Fn(usize) -> f32| {
            let at = len as u32;
            len += image.width as u64 * image.height as u64;
            if fill {
                for (i, rgb) in image.texels.chunks_exact(3).enumerate() {
                    out.values.extend(rgb);
                    out.values.push(w(i));
                }
            }
            at
        };
        for m in &scene.materials {
            for texture in m.textures() {
                if let Texture::Image(image) = texture
                    && !out.placed.iter().any(|(i, _)| std::ptr::eq(*i, image))
                {
                    let at = place(&mut out, image, &|_| 0.0);
                    out.placed.push((image, at));
                }
            }
        }
        if let Background::Environment(env) = scene.background {
            let d = env.distribution();
            let texels = place(&mut out, env.image, &|i| d.density[i]);
            // Its alias tables: the rows' (keep, alias as bits, 0, 0) per row, then each row's
            // columns' (keep, alias as bits, own density, alias's density) per texel.
            let aliases = len as u32;
            let (w, h) = (env.image.width as usize, env.image.height as usize);
            len += (h + w * h) as u64;
            if fill {
                for y in 0..h {
                    let alias = d.rows.alias[y];
                    out.values
                        .extend([d.rows.keep[y], f32::from_bits(alias), 0.0, 0.0]);
                }
                for i in 0..w * h {
                    let alias = d.columns.alias[i] as usize;
                    let row = i - i % w;
                    out.values.extend([
                        d.columns.keep[i],
                        f32::from_bits(alias as u32),
                        d.density[i],
                        d.density[row + alias],
                    ]);
                }
            }
            out.environment = Some([texels, aliases]);
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
            .find(|(i, _)| std::ptr::eq(*i, image))
            .map_or(0, |(_, at)| *at)
    }

    /// Its size in bytes.
    pub fn bytes(&self) -> u64 {
        self.len * 4
    }
}

/// GPU memory a scene's meshes and hierarchy take: triangles, their corner normals, BVH nodes and
/// primitive references, and instances (what `rt-gpu bench` reports per triangle).
pub fn geometry_bytes(scene: &FlatScene) -> usize {
    let buffers = SceneBuffers::new(scene);
    std::mem::size_of_val(&buffers.triangles[..])
        + std::mem::size_of_val(&buffers.triangle_normals[..])
        + std::mem::size_of_val(&buffers.bvh_nodes[..])
        + std::mem::size_of_val(&buffers.bvh_primitives[..])
        + std::mem::size_of_val(&buffers.instances[..])
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
        let (mut bvh_nodes, bvh_references) = gpu_bvh(&scene.bvh);
        let mut bvh_primitives = scene.bvh.primitives.clone();
        let mut instances: Vec<GpuInstance> = scene
            .instances
            .iter()
            .map(|i| {
                let [to_world_x, to_world_y, to_world_z] = i.to_world.map(|r| r.to_array());
                let [to_local_x, to_local_y, to_local_z] = i.to_local.map(|r| r.to_array());
                GpuInstance {
                    to_world_x,
                    to_world_y,
                    to_world_z,
                    to_local_x,
                    to_local_y,
                    to_local_z,
                    root: bvh_references[i.root as usize],
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
            // Only a lone leaf, or nothing, which the kernel never reads as a node.
            bvh_nodes.push(GpuBvhNode::default());
        }
        let mut triangle_normals: Vec<f32> = scene
            .triangle_normals
            .iter()
            .flat_map(|corners| corners.iter().flat_map(|n| n.to_array()))
            .collect();
        if triangle_normals.is_empty() {
            triangle_normals.push(0.0);
        }
        if bvh_primitives.is_empty() {
            bvh_primitives.push(0);
        }
        if spheres.is_empty() {
            spheres.push(GpuSphere::default());
        }
        if quads.is_empty() {
            quads.push(GpuQuad::default());
        }
        if materials.is_empty() {
            materials.push(GpuMaterial::default());
        }
        let mut lights: Vec<GpuLight> = scene.lights.iter().map(gpu_light).collect();
        if lights.is_empty() {
            lights.push(GpuLight::default());
        }
        SceneBuffers {
            spheres,
            quads,
            triangles,
            triangle_normals,
            bvh_nodes,
            bvh_primitives,
            instances,
            materials,
            lights,
            images,
        }
    }
}

/// A light as the kernel reads it: a tagged union of the `LightShape`s.
fn gpu_light(l: &Light) -> GpuLight {
    use crate::scene::flat::{KIND_QUAD, KIND_SPHERE};
    let mut out = GpuLight {
        cdf: l.cdf,
        pick: l.pick,
        ..Default::default()
    };
    match l.shape {
        LightShape::Sphere { center, radius } => {
            out.kind = KIND_SPHERE;
            out.position = center.to_array();
            out.size = radius;
        }
        LightShape::Quad {
            corner,
            u,
            v,
            normal,
            inv_area,
        }
        | LightShape::Triangle {
            corner,
            u,
            v,
            normal,
            inv_area,
        } => {
            out.kind = if matches!(l.shape, LightShape::Quad { .. }) {
                KIND_QUAD
            } else {
                crate::scene::flat::KIND_TRIANGLE
            };
            out.position = corner.to_array();
            out.u = u.to_array();
            out.v = v.to_array();
            out.normal = normal.to_array();
            out.size = inv_area;
        }
        // Its parameters are the render's (GpuParams::environment_*).
        LightShape::Environment(_) => out.kind = KIND_ENVIRONMENT,
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
    if let Background::Environment(env) = scene.background {
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
        environment_aliases: environment.1[1],
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

    /// The kernel's layout is the host's hierarchy: every interior node's children's boxes and
    /// references where the host has them, leaves' ranges intact, from the scene's root and
    /// from an appended mesh's.
    #[test]
    fn the_kernels_bvh_is_the_hosts() {
        for n in [1, 2, 5, 300] {
            let mut bvh = Bvh::build(&mut random_items(n));
            let mesh_root = bvh.append_hierarchy(Bvh::build(&mut random_items(777)));
            let (nodes, references) = gpu_bvh(&bvh);
            assert_eq!(bvh_root(&bvh), references[0]);
            let mut reached = vec![false; bvh.nodes.len()];
            let mut stack = vec![0, mesh_root as usize];
            while let Some(i) = stack.pop() {
                reached[i] = true;
                let host = &bvh.nodes[i];
                let reference = references[i];
                if host.is_leaf() {
                    assert_ne!(reference & BVH_LEAF, 0);
                    assert_eq!(reference & (BVH_LEAF_OFFSET_LIMIT - 1), host.offset);
                    assert_eq!((reference & !BVH_LEAF) >> BVH_LEAF_COUNT_SHIFT, host.count);
                    continue;
                }
                assert_eq!(reference & BVH_LEAF, 0);
                let node = &nodes[reference as usize];
                let (first, second) = (i + 1, host.offset as usize);
                assert_eq!(node.first, references[first]);
                assert_eq!(node.second, references[second]);
                assert_eq!(node.first_min, bvh.nodes[first].min.to_array());
                assert_eq!(node.first_max, bvh.nodes[first].max.to_array());
                assert_eq!(node.second_min, bvh.nodes[second].min.to_array());
                assert_eq!(node.second_max, bvh.nodes[second].max.to_array());
                stack.extend([first, second]);
            }
            assert!(reached.iter().all(|&r| r), "a node is unreachable");
            assert_eq!(
                nodes.len(),
                bvh.nodes.iter().filter(|n| !n.is_leaf()).count()
            );
        }
        assert_eq!(bvh_root(&Bvh::default()), BVH_LEAF);
    }
}
