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

/// An image's wrap modes across (u, `wrap_u`) and up (v, `wrap_v`) and its filter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ImageLookup {
    pub wrap_u: Wrap,
    pub wrap_v: Wrap,
    pub filter: Filter,
}

/// [`ImageLookup::bits`]' codes of the wrap modes (repeat is 0) and its nearest-filter bit.
pub const WRAP_CLAMP: u32 = 1;
pub const WRAP_MIRROR: u32 = 2;
pub const LOOKUP_NEAREST: u32 = 1 << 4;

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
    /// nearest in bit 4; 0 is the default (repeat, linear).
    pub fn bits(&self) -> u32 {
        let nearest = if self.filter == Filter::Nearest {
            LOOKUP_NEAREST
        } else {
            0
        };
        self.wrap_u.bits() | self.wrap_v.bits() << 2 | nearest
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
                    let lookup = ImageLookup {
                        wrap_u,
                        wrap_v,
                        filter,
                    };
                    assert!(seen.insert(lookup.bits()), "{lookup:?}");
                }
            }
        }
    }
}
