//! The kernel's bindings, in one table (and after it, one per shape: `shape_binding`): each resource's number (WGSL binds it as
//! `@binding(BINDING_<NAME>)`, a constant generated from this table), what kind of resource it
//! is for a kernel's features (hence the bind group layout), and, by the same names, what the
//! renderer puts in the bind group.

use super::shader::Features;

/// Defines [`Binding`], [`BINDINGS`] and each binding's WGSL constant from one list.
macro_rules! bindings {
    ($($(#[$meta:meta])* $name:ident => $wgsl:literal,)+) => {
        /// Every resource the kernel binds, in group 0, numbered by its position.
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub enum Binding {
            $($(#[$meta])* $name,)+
        }

        /// Every binding, in number order.
        pub const BINDINGS: &[Binding] = &[$(Binding::$name,)+];

        impl Binding {
            /// The WGSL constant holding its number.
            pub fn wgsl_name(self) -> &'static str {
                match self {
                    $(Binding::$name => $wgsl,)+
                }
            }
        }
    };
}

bindings! {
    Params => "BINDING_PARAMS",
    Materials => "BINDING_MATERIALS",
    Accum => "BINDING_ACCUM",
    /// The debug entry points' output (`first_bounce`, `trace_rays`, `look_up_albedo`, ...).
    Bounces => "BINDING_BOUNCES",
    Lights => "BINDING_LIGHTS",
    Dispatch => "BINDING_DISPATCH",
    ImageTexels => "BINDING_IMAGE_TEXELS",
    Triangles => "BINDING_TRIANGLES",
    BvhNodes => "BINDING_BVH_NODES",
    BvhPrimitives => "BINDING_BVH_PRIMITIVES",
    TriangleNormals => "BINDING_TRIANGLE_NORMALS",
    Instances => "BINDING_INSTANCES",
    TriangleUvs => "BINDING_TRIANGLE_UVS",
    TriangleUvs1 => "BINDING_TRIANGLE_UVS1",
    TriangleTangents => "BINDING_TRIANGLE_TANGENTS",
    TriangleColors => "BINDING_TRIANGLE_COLORS",
}

impl Binding {
    pub fn number(self) -> u32 {
        self as u32
    }

    /// What the kernel composed with `features` declares it as: small scenes' arrays and
    /// hierarchies are uniform (fixed capacity), larger ones storage; images and large
    /// hierarchies' nodes are texel textures.
    fn ty(self, features: &Features) -> wgpu::BindingType {
        use wgpu::BufferBindingType::{Storage, Uniform};
        let buffer = |ty| wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let texels = wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Uint,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        };
        let read_only = Storage { read_only: true };
        match self {
            Binding::Params => buffer(Uniform),
            Binding::Materials | Binding::Lights => buffer(if features.uniform_scene {
                Uniform
            } else {
                read_only
            }),
            Binding::Accum | Binding::Bounces => buffer(Storage { read_only: false }),
            Binding::Dispatch
            | Binding::Triangles
            | Binding::TriangleNormals
            | Binding::TriangleUvs
            | Binding::TriangleUvs1
            | Binding::TriangleTangents
            | Binding::TriangleColors
            | Binding::Instances => buffer(read_only),
            Binding::ImageTexels => texels,
            Binding::BvhNodes if features.uniform_bvh => buffer(Uniform),
            Binding::BvhNodes => texels,
            Binding::BvhPrimitives => buffer(if features.uniform_bvh {
                Uniform
            } else {
                read_only
            }),
        }
    }

    fn layout_entry(self, features: &Features) -> wgpu::BindGroupLayoutEntry {
        wgpu::BindGroupLayoutEntry {
            binding: self.number(),
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: self.ty(features),
            count: None,
        }
    }
}

/// The number of the array of the shape at `position` in `shape::KINDS`: after [`BINDINGS`].
pub fn shape_binding(position: usize) -> u32 {
    (BINDINGS.len() + position) as u32
}

/// The bind group layout's entries of a kernel composed with `features`: [`BINDINGS`], then each
/// shape's array, bound as the scene's other arrays are.
pub fn layout_entries(features: &Features) -> Vec<wgpu::BindGroupLayoutEntry> {
    let shapes = (0..crate::shape::KINDS.len()).map(|position| wgpu::BindGroupLayoutEntry {
        binding: shape_binding(position),
        ..Binding::Materials.layout_entry(features)
    });
    BINDINGS
        .iter()
        .map(|b| b.layout_entry(features))
        .chain(shapes)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bindings_are_numbered_by_position() {
        for (i, b) in BINDINGS.iter().enumerate() {
            assert_eq!(b.number(), i as u32, "{b:?}");
        }
    }
}
