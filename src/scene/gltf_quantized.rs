//! KHR_mesh_quantization: vertex attributes stored as 8- or 16-bit integers (as gltfpack and
//! Blender's exporter write them to save space), read into f32 as the extension defines:
//! normalized signed values as max(c / (2^(n-1) - 1), -1), normalized unsigned ones as
//! c / (2^n - 1), others as the integer's value (then placed by the node's transform, which
//! such files use to dequantize positions).

use gltf::accessor::{DataType, Dimensions};

/// The extension's name.
pub const EXTENSION: &str = "KHR_mesh_quantization";

/// Converts a stored component to f32: `bits` wide, `signed` or not, `normalized` or not.
fn component(c: f32, bits: i32, signed: bool, normalized: bool) -> f32 {
    match (normalized, signed) {
        (true, true) => (c / ((1i64 << (bits - 1)) - 1) as f32).max(-1.0),
        (true, false) => c / ((1i64 << bits) - 1) as f32,
        (false, _) => c,
    }
}

/// Readers of accessors of `N` components (VEC2, VEC3, VEC4) into f32, whatever their
/// component type; `None` where the accessor has another shape or 32-bit integers, or its data
/// cannot be read. `buffer` gives a buffer's bytes.
macro_rules! reader {
    ($name:ident, $n:literal, $dimensions:path) => {
        pub fn $name<'a>(
            accessor: gltf::Accessor<'a>,
            buffer: impl Fn(gltf::Buffer) -> Option<&'a [u8]> + Clone,
        ) -> Option<Vec<[f32; $n]>> {
            if accessor.dimensions() != $dimensions {
                return None;
            }
            let normalized = accessor.normalized();
            macro_rules! values {
                ($t:ty, $bits:expr, $signed:expr) => {
                    gltf::accessor::Iter::<[$t; $n]>::new(accessor, buffer)?
                        .map(|v| v.map(|c| component(c as f32, $bits, $signed, normalized)))
                        .collect()
                };
            }
            Some(match accessor.data_type() {
                DataType::F32 => {
                    gltf::accessor::Iter::<[f32; $n]>::new(accessor, buffer)?.collect()
                }
                DataType::I8 => values!(i8, 8, true),
                DataType::U8 => values!(u8, 8, false),
                DataType::I16 => values!(i16, 16, true),
                DataType::U16 => values!(u16, 16, false),
                DataType::U32 => return None,
            })
        }
    };
}

reader!(vec2, 2, Dimensions::Vec2);
reader!(vec3, 3, Dimensions::Vec3);
reader!(vec4, 4, Dimensions::Vec4);

/// COLOR_0's values as linear RGB (its alpha, if VEC4, left out): floats, or normalized
/// unsigned 8- or 16-bit integers, as glTF allows; `None` where the accessor is another kind
/// (`Mesh::with_tangents` refuses values that are not finite, as for the other attributes).
pub fn colors<'a>(
    accessor: gltf::Accessor<'a>,
    buffer: impl Fn(gltf::Buffer) -> Option<&'a [u8]> + Clone,
) -> Option<Vec<[f32; 3]>> {
    let allowed = match accessor.data_type() {
        DataType::F32 => true,
        DataType::U8 | DataType::U16 => accessor.normalized(),
        _ => false,
    };
    if !allowed {
        return None;
    }
    match accessor.dimensions() {
        Dimensions::Vec3 => vec3(accessor, buffer),
        Dimensions::Vec4 => Some(
            vec4(accessor, buffer)?
                .into_iter()
                .map(|[r, g, b, _]| [r, g, b])
                .collect(),
        ),
        _ => None,
    }
}
