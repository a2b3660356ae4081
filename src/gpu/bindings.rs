//! The kernel's bindings, in one table: each resource's number (WGSL binds it as
//! `@binding(BINDING_<NAME>)`, a constant generated from this table), what kind of resource it
//! is for a kernel's features (hence the bind group layout), and, by the same names, what the
//! renderer puts in the bind group.

use super::shader::Features;

/// Every resource the kernel binds, in group 0, numbered by its position.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Binding {
    Params,
    Spheres,
    Quads,
    Materials,
    Accum,
    /// The debug entry points' output (`first_bounce`, `trace_rays`, `look_up_albedo`, ...).
    Bounces,
    Lights,
    Dispatch,
    ImageTexels,
    Triangles,
    BvhNodes,
    BvhPrimitives,
    TriangleNormals,
    Instances,
}

/// Every binding, in number order.
pub const BINDINGS: [Binding; 14] = [
    Binding::Params,
    Binding::Spheres,
    Binding::Quads,
    Binding::Materials,
    Binding::Accum,
    Binding::Bounces,
    Binding::Lights,
    Binding::Dispatch,
    Binding::ImageTexels,
    Binding::Triangles,
    Binding::BvhNodes,
    Binding::BvhPrimitives,
    Binding::TriangleNormals,
    Binding::Instances,
];

impl Binding {
    pub fn number(self) -> u32 {
        self as u32
    }

    /// The WGSL constant holding its number.
    pub fn wgsl_name(self) -> &'static str {
        match self {
            Binding::Params => "BINDING_PARAMS",
            Binding::Spheres => "BINDING_SPHERES",
            Binding::Quads => "BINDING_QUADS",
            Binding::Materials => "BINDING_MATERIALS",
            Binding::Accum => "BINDING_ACCUM",
            Binding::Bounces => "BINDING_BOUNCES",
            Binding::Lights => "BINDING_LIGHTS",
            Binding::Dispatch => "BINDING_DISPATCH",
            Binding::ImageTexels => "BINDING_IMAGE_TEXELS",
            Binding::Triangles => "BINDING_TRIANGLES",
            Binding::BvhNodes => "BINDING_BVH_NODES",
            Binding::BvhPrimitives => "BINDING_BVH_PRIMITIVES",
            Binding::TriangleNormals => "BINDING_TRIANGLE_NORMALS",
            Binding::Instances => "BINDING_INSTANCES",
        }
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
            Binding::Spheres | Binding::Quads | Binding::Materials | Binding::Lights => {
                buffer(if features.uniform_scene {
                    Uniform
                } else {
                    read_only
                })
            }
            Binding::Accum | Binding::Bounces => buffer(Storage { read_only: false }),
            Binding::Dispatch
            | Binding::Triangles
            | Binding::TriangleNormals
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

/// The bind group layout's entries of a kernel composed with `features`.
pub fn layout_entries(features: &Features) -> Vec<wgpu::BindGroupLayoutEntry> {
    BINDINGS.iter().map(|b| b.layout_entry(features)).collect()
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
