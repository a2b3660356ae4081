//! The structs the kernel shares with the host, `#[repr(C)]` and mirrored one-to-one by WGSL
//! declarations generated from them (vec3f is 16-byte aligned there, hence the explicit
//! padding), and the constants of their encodings. `tests/it/gpu_layout.rs` checks sizes and field
//! offsets against naga's layout of the generated WGSL. How a flat scene is packed into them is
//! `gpu::layout`'s.

use super::exact_sum::SUM_WORDS;
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

/// Arrays of `vec4u`: the material parameters' words, and others.
macro_rules! vec4u_arrays {
    ($($n:literal),+) => {$(
        impl WgslType for [[u32; 4]; $n] {
            const WGSL: &'static str = concat!("array<vec4u, ", $n, ">");
            fn literal(&self) -> String {
                let items: Vec<String> = self
                    .iter()
                    .map(|v| format!("vec4u({}u, {}u, {}u, {}u)", v[0], v[1], v[2], v[3]))
                    .collect();
                format!("array<vec4u, {}>({})", $n, items.join(", "))
            }
        }
    )+};
}

vec4u_arrays!(2, 3, 4, 5);

impl WgslType for [u32; 4] {
    const WGSL: &'static str = "vec4u";
    fn literal(&self) -> String {
        format!(
            "vec4u({}u, {}u, {}u, {}u)",
            self[0], self[1], self[2], self[3]
        )
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
/// where WGSL pads implicitly (a vec3f is 16-byte aligned); `tests/it/gpu_layout.rs` checks that
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

/// A Rust type as the WGSL type of a struct the kernel keeps in its own memory (see
/// [`kernel_struct!`]): never in a buffer, so `bool` is allowed, and a primitive reference is
/// the kernel's packed `u32`.
pub trait WgslLocalType {
    const WGSL: &'static str;
}

impl WgslLocalType for f32 {
    const WGSL: &'static str = "f32";
}
impl WgslLocalType for u32 {
    const WGSL: &'static str = "u32";
}
impl WgslLocalType for bool {
    const WGSL: &'static str = "bool";
}
impl WgslLocalType for glam::Vec2 {
    const WGSL: &'static str = "vec2f";
}
impl WgslLocalType for glam::Vec4 {
    const WGSL: &'static str = "vec4f";
}

impl WgslLocalType for glam::Vec3 {
    const WGSL: &'static str = "vec3f";
}
impl WgslLocalType for super::primitive::PrimitiveRef {
    const WGSL: &'static str = "u32";
}

/// Defines a struct both backends use in their own memory (a ray, a hit) and its WGSL
/// declaration from one field list. Unlike [`gpu_struct!`]'s, it is never uploaded, so it has
/// no byte layout to agree on: only its fields, their order and their types.
macro_rules! kernel_struct {
    (
        $(#[$meta:meta])*
        pub struct $name:ident as $wgsl:literal {
            $($(#[$field_meta:meta])* $field:ident: $ty:ty,)*
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct $name {
            $($(#[$field_meta])* pub $field: $ty,)*
        }

        /// Another kernel struct may hold it.
        impl $crate::shared::layout::WgslLocalType for $name {
            const WGSL: &'static str = $wgsl;
        }

        impl $name {
            /// Its WGSL declaration.
            pub fn wgsl_declaration() -> String {
                let mut out = format!("struct {} {{\n", $wgsl);
                $(out.push_str(&format!(
                    "    {}: {},\n",
                    stringify!($field),
                    <$ty as $crate::shared::layout::WgslLocalType>::WGSL
                ));)*
                out.push_str("}\n");
                out
            }
        }
    };
}
pub(crate) use gpu_struct;
pub(crate) use kernel_struct;

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
    /// An interior node of the BVH as the kernel reads it (`accel::quantized::QuantizedNode`,
    /// packed by `gpu_bvh`): its four children's references and their boxes quantized, a byte
    /// per bound, so that one read of four texels decides which children a ray enters, and a
    /// leaf is known as one before it is reached.
    pub struct GpuBvhNode as "BvhNode" {
        /// The grid's origin.
        origin: [f32; 3],
        /// Each axis's step as an f32's biased exponent: x in bits 0-7, y 8-15, z 16-23.
        steps: u32,
        /// `accel::quantized::EMPTY` where unused.
        children: [u32; 4],
        /// The children's minima, in steps: a byte per child (child i in bits 8i up) per axis;
        /// `lanes` is the children in use.
        low: [u32; 3],
        lanes: u32,
        high: [u32; 3],
        _pad: u32,
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
    /// A light for next-event estimation (see `scene::flat::Light`), told apart by `kind`: a
    /// shape's (its `SurfaceLight`, as its file says: a sphere's centre and |radius| in
    /// `position` and `size`; a quad's corner, edges, unit normal and 1 / area; a disk's centre,
    /// axes times radius, normal and 1 / area), a triangle's (as a quad's), a punctual light's,
    /// or the environment's.
    pub struct GpuLight as "Light" {
        position: [f32; 3],
        /// Chance of picking this light or one before it.
        cdf: f32,
        u: [f32; 3],
        /// Chance of picking this light.
        pick: f32,
        v: [f32; 3],
        /// A shape's primitive kind, `KIND_TRIANGLE`, `KIND_POINT`, `KIND_DIRECTIONAL` or
        /// `KIND_ENVIRONMENT`: which light, and so what the other fields mean.
        kind: u32,
        normal: [f32; 3],
        size: f32,
    }
}

gpu_struct! {
    pub struct GpuMaterial as "Material" {
        /// The colour its texture gives where it has none (see `texture`): what the kinds that
        /// read a texture (`albedo_at`) take it from.
        albedo: [f32; 3],
        /// Index in `material::KINDS`; WGSL `MAT_<FEATURE>`.
        kind: u32,
        /// The kind's own parameters (its `material_params!` struct, see `shared::params`),
        /// read in WGSL by `<name>_params(m)`.
        params: [[u32; 4]; super::params::PARAM_WORDS / 4],
        /// The medium inside the object (see `material::Medium`); density 0: none.
        medium_albedo: [f32; 3],
        medium_density: f32,
        medium_g: f32,
        /// The albedo's texture: `TEXTURE_NONE`, `TEXTURE_CHECKER`, `TEXTURE_UV_CHECKER`
        /// (then `albedo` is its even colour) or `TEXTURE_IMAGE` (then `texture_image` is
        /// where its texels start in the images array, `texture_odd` holds its width and
        /// height, and `albedo` the factor its texels are multiplied by).
        texture: u32,
        texture_scale: f32,
        texture_image: u32,
        texture_odd: [f32; 3],
        /// How the albedo's image is read (`ImageLookup::bits`).
        texture_lookup: u32,
        /// See `assets::texture::Checker::shift`.
        texture_shift: [f32; 3],
        /// Its normal map (`assets::normal_map`): where its texels start in the images array,
        /// its width and height (0: none), its scale and how it is read.
        normal_map_image: u32,
        normal_map_size: [f32; 2],
        normal_map_scale: f32,
        normal_map_lookup: u32,
        /// The kind's image of parameters (`MaterialModel::parameter_image`: pbr's
        /// metallic-roughness texture, a rough plastic's coat table): its width and height (0:
        /// none), where its texels start in the images array, and how it is read.
        parameter_image_size: [f32; 2],
        parameter_image: u32,
        parameter_image_lookup: u32,
        /// See-through surfaces (`assets::alpha`): the alpha factor, where the alpha image's
        /// texels start, its size (0: none) and how it is read, the mode (`ALPHA_*`; opaque
        /// 0) and MASK's cutoff.
        alpha_factor: f32,
        alpha_image: u32,
        alpha_size: [f32; 2],
        alpha_lookup: u32,
        alpha_mode: u32,
        alpha_cutoff: f32,
        /// 1 where its normal map's shading normals are microsurfaces
        /// (`Material::has_microsurface`, `shaders/microsurface.wgsl`).
        microsurface: u32,
        /// Emission on top of the surface (glTF's emissive pbr; `MaterialModel::emission`):
        /// its colour (the factor its image's texels are multiplied by, x its strength), where
        /// the image's texels start, its width and height (0: none), how it is read, and 1
        /// where back faces emit too.
        emission: [f32; 3],
        emission_image: u32,
        emission_size: [f32; 2],
        emission_lookup: u32,
        emission_two_sided: u32,
        /// The medium's absorption per channel (`material::Medium::absorption`; 0: none).
        medium_absorption: [f32; 3],
        /// Where pbr's sheen albedo table starts in the images array
        /// (`MaterialModel::table_image`; `material::sheen::albedo_table`).
        sheen_table: u32,
        /// pbr's layers' image (`Pbr::layers`: red scales the clear coat's factor, green its
        /// roughness, blue the sheen's roughness): its width and height (0: none), where its
        /// texels start and how it is read.
        layer_image_size: [f32; 2],
        layer_image: u32,
        layer_image_lookup: u32,
        /// pbr's sheen colour image (`Pbr::sheen_image`, which scales the sheen's colour): the
        /// same.
        sheen_image_size: [f32; 2],
        sheen_image: u32,
        sheen_image_lookup: u32,
        /// pbr's specular strength image (`Pbr::specular_image`: red scales the specular
        /// factor) and specular colour image (`Pbr::specular_color_image`): the same.
        specular_image_size: [f32; 2],
        specular_image: u32,
        specular_image_lookup: u32,
        specular_color_image_size: [f32; 2],
        specular_color_image: u32,
        specular_color_image_lookup: u32,
        /// Its clear coat's normal map (`Material::coat_normal_map`; `Hit::coat`): as
        /// `normal_map_*`.
        coat_normal_map_size: [f32; 2],
        coat_normal_map_image: u32,
        coat_normal_map_scale: f32,
        coat_normal_map_lookup: u32,
        _pad0: u32,
        _pad1: u32,
        _pad2: u32,
    }
}

pub const TEXTURE_NONE: u32 = 0;
pub const TEXTURE_CHECKER: u32 = 1;
pub const TEXTURE_UV_CHECKER: u32 = 2;
pub const TEXTURE_IMAGE: u32 = 3;
/// `GpuLight::kind` of the environment (beside the primitive kinds of spheres and quads).
pub const KIND_ENVIRONMENT: u32 = 15;
/// `GpuLight::kind` of a point or spot light: `position`; `u` its intensity, `normal` its axis,
/// `v.xy` its falloff's scale and offset on cos(angle).
pub const KIND_POINT: u32 = 16;
/// `GpuLight::kind` of a directional light: `normal` toward it, `u` its irradiance.
pub const KIND_DIRECTIONAL: u32 = 17;

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
        /// The environment (see `assets::environment`): cos and sin of its rotation about y,
        environment_rotation: [f32; 2],
        /// where its texels and its CDFs (rows of cells, then each row's cells, with their
        /// densities) start in the images array,
        environment_texels: u32,
        environment_cdfs: u32,
        /// its size and its strength.
        environment_width: u32,
        environment_height: u32,
        environment_strength: f32,
        /// The loop budget of LOOP_BUDGET kernels (BVH kernels on software adapters; see
        /// shaders/accel.wgsl): a bound on the loop
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

gpu_struct! {
    /// The viewer's display pass (shaders/display.wgsl): the film's size and how many window
    /// pixels a film pixel covers each way.
    pub struct GpuDisplay as "Display" {
        film_size: [u32; 2],
        scale: u32,
        _pad: u32,
    }
}

/// A shared struct's WGSL name, Rust size, and the offsets of its fields other than padding.
pub type StructLayout = (&'static str, usize, Vec<(&'static str, usize)>);

pub fn layout_of<T: WgslStruct>() -> StructLayout {
    let (size, fields) = T::rust_layout();
    let fields = fields
        .into_iter()
        .filter(|(name, _)| !name.starts_with("_pad"))
        .collect();
    (T::WGSL_NAME, size, fields)
}

/// Rust's layout of the display pass's struct, for checking against naga's layout of
/// shaders/display.wgsl.
pub fn display_layout() -> StructLayout {
    layout_of::<GpuDisplay>()
}

/// Rust's layout of every struct the kernel shares, for checking against naga's layout of the
/// generated WGSL.
pub fn shared_layouts() -> Vec<StructLayout> {
    vec![
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

/// The WGSL declarations of every struct the kernel shares with the host, and of the ray and
/// the hit both backends use, generated from their Rust definitions.
pub fn wgsl_declarations() -> String {
    let mut out = String::new();
    for declaration in [
        super::ray::Ray::wgsl_declaration(),
        super::ray::Hit::wgsl_declaration(),
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
