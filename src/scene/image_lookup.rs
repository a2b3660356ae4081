//! How a textured surface reads its image: what lies beyond [0, 1] on each axis and how texels
//! are filtered, as a glTF sampler says (evaluated by `material::texture::image_at`, twin
//! `image_at` in `shaders/texture.wgsl`). It belongs to the image a material holds, as pbrt-v4
//! keys its image textures by file and wrap mode: a file read with two samplers is decoded once
//! and held twice.

/// What an axis's coordinate outside [0, 1] reads (OpenGL's wrap modes, glTF's
/// `wrapS`/`wrapT`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// The image again (glTF's default).
    #[default]
    Repeat,
    /// The edge's texels.
    Clamp,
    /// The image mirrored every other time.
    Mirror,
}

/// How texels are weighed at a point.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Filter {
    /// The four nearest texels, bilinearly (glTF's default where unspecified, and Blender's).
    #[default]
    Linear,
    /// The texel the point lies in (Blender's "Closest").
    Nearest,
}

/// Which of a mesh's texture coordinate sets a surface reads an image at (glTF's `texCoord`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum UvSet {
    /// The first (glTF TEXCOORD_0, OBJ's `vt`); shapes' own coordinates.
    #[default]
    First,
    /// The second (glTF TEXCOORD_1): meshes only; elsewhere it reads the first's value.
    Second,
}

/// An image's wrap modes across (u, `wrap_u`) and up (v, `wrap_v`), its filter, and the texture
/// coordinates it is read at.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ImageLookup {
    pub wrap_u: Wrap,
    pub wrap_v: Wrap,
    pub filter: Filter,
    pub uv_set: UvSet,
}

/// [`ImageLookup::bits`]' codes of the wrap modes (repeat is 0) and its nearest-filter bit.
pub const WRAP_CLAMP: u32 = 1;
pub const WRAP_MIRROR: u32 = 2;
pub const LOOKUP_NEAREST: u32 = 1 << 4;
/// [`ImageLookup::bits`]' bit for the second texture coordinate set.
pub const LOOKUP_UV1: u32 = 1 << 5;

impl Wrap {
    fn bits(self) -> u32 {
        match self {
            Wrap::Repeat => 0,
            Wrap::Clamp => WRAP_CLAMP,
            Wrap::Mirror => WRAP_MIRROR,
        }
    }
}

impl ImageLookup {
    /// Its GPU form (`GpuMaterial::*_lookup`): `wrap_u` in bits 0-1, `wrap_v` in bits 2-3,
    /// nearest in bit 4, the second UV set in bit 5; 0 is the default (repeat, linear, first).
    pub fn bits(&self) -> u32 {
        let nearest = if self.filter == Filter::Nearest {
            LOOKUP_NEAREST
        } else {
            0
        };
        let second = if self.uv_set == UvSet::Second {
            LOOKUP_UV1
        } else {
            0
        };
        self.wrap_u.bits() | self.wrap_v.bits() << 2 | nearest | second
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_is_zero_and_every_lookup_has_its_own_bits() {
        assert_eq!(ImageLookup::default().bits(), 0);
        let wraps = [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror];
        let mut seen = std::collections::HashSet::new();
        for wrap_u in wraps {
            for wrap_v in wraps {
                for filter in [Filter::Linear, Filter::Nearest] {
                    for uv_set in [UvSet::First, UvSet::Second] {
                        let lookup = ImageLookup {
                            wrap_u,
                            wrap_v,
                            filter,
                            uv_set,
                        };
                        assert!(seen.insert(lookup.bits()), "{lookup:?}");
                    }
                }
            }
        }
    }
}
