//! How a textured surface reads its image: what lies beyond [0, 1] on each axis and how texels
//! are filtered, as a glTF sampler says, and the reading itself ([`image_at`], [`bilinear`];
//! twins `image_at` and `bilinear` in `shaders/texture.wgsl`). It belongs to the image a material holds, as pbrt-v4
//! keys its image textures by file and wrap mode: a file read with two samplers is decoded once
//! and held twice.

use super::image::Image;
use glam::{Vec2, Vec3};

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

/// Integer-valued texel index `i` of an axis of `n` texels, brought into 0..n by `mode`, in f32
/// arithmetic as the kernel does it.
#[inline]
fn wrapped(mode: Wrap, i: f32, n: f32) -> u32 {
    match mode {
        Wrap::Repeat => wrap(i, n),
        Wrap::Clamp => i.clamp(0.0, n - 1.0) as u32,
        Wrap::Mirror => {
            // Period 2n: the image, then the image reversed.
            let m = i - 2.0 * n * (i / (2.0 * n)).floor();
            let mirrored = if m >= n { 2.0 * n - 1.0 - m } else { m };
            mirrored.clamp(0.0, n - 1.0) as u32
        }
    }
}

/// `image` filtered bilinearly at image coordinates (s, t) (s across, t down, [0, 1] spans
/// the image once; texel centres at half-integers), wrapping around both edges: how
/// environments read their images.
#[inline]
pub fn bilinear(image: &Image, s: f32, t: f32) -> Vec3 {
    filtered(image, ImageLookup::default(), s, t)
}

/// `image` at surface coordinates `uv` (u across, v up; [0, 1] spans the image once) as its
/// lookup says: wrapped on each axis and filtered (without its factor, which only a surface's
/// colour, `material::texture::value`, applies).
#[inline]
pub fn image_at(image: &Image, uv: Vec2) -> Vec3 {
    filtered(image, image.lookup, uv.x, 1.0 - uv.y)
}

/// `image` at image coordinates (s, t), wrapped and filtered as `lookup` says.
#[inline]
fn filtered(image: &Image, lookup: ImageLookup, s: f32, t: f32) -> Vec3 {
    let (w, h) = (image.width as f32, image.height as f32);
    if lookup.filter == Filter::Nearest {
        let x = wrapped(lookup.wrap_u, (s * w).floor(), w);
        let y = wrapped(lookup.wrap_v, (t * h).floor(), h);
        return image.texel(x, y);
    }
    let x = s * w - 0.5;
    let y = t * h - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let (x0, x1) = neighbours(lookup.wrap_u, x0, w);
    let (y0, y1) = neighbours(lookup.wrap_v, y0, h);
    let top = image.texel(x0, y0) * (1.0 - fx) + image.texel(x1, y0) * fx;
    let bottom = image.texel(x0, y1) * (1.0 - fx) + image.texel(x1, y1) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// Integer-valued texel index `i` and the next, each brought into 0..n by `mode` as
/// [`wrapped`] brings them: where both are inside already (nearly every lookup), they are
/// themselves whatever the mode.
#[inline(always)]
fn neighbours(mode: Wrap, i: f32, n: f32) -> (u32, u32) {
    if i >= 0.0 && i + 1.0 < n {
        let i = i as u32;
        return (i, i + 1);
    }
    (wrapped(mode, i, n), wrapped(mode, i + 1.0, n))
}

/// Integer-valued `i` wrapped into 0..n, in f32 arithmetic as the kernel does it (clamped,
/// for coordinates so large that rounding leaves them outside).
#[inline]
fn wrap(i: f32, n: f32) -> u32 {
    // Nearly every index is inside already, where the formula gives i itself: its division
    // was a fifth of a bilinear lookup's time.
    if (0.0..n).contains(&i) {
        return i as u32;
    }
    (i - n * (i / n).floor()).clamp(0.0, n - 1.0) as u32
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

    /// The shortcut for a texel and its neighbour inside the image gives what wrapping each
    /// does, in every mode, at and around both edges.
    #[test]
    fn neighbours_are_the_wrapped_texels() {
        for mode in [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror] {
            for n in [1.0f32, 2.0, 5.0] {
                for i in -7..12 {
                    let i = i as f32;
                    let expected = (wrapped(mode, i, n), wrapped(mode, i + 1.0, n));
                    assert_eq!(neighbours(mode, i, n), expected, "{mode:?} {i} of {n}");
                }
            }
        }
    }

    /// A 3x2 image whose texels hold their own (x, y, 0), read at u beyond [0, 1] each way.
    #[test]
    fn images_wrap_and_filter_as_their_lookup_says() {
        let texels = (0..2)
            .flat_map(|y| (0..3).flat_map(move |x| [x as f32, y as f32, 0.0]))
            .collect();
        let image = Image::from_linear("xy", 3, 2, texels).expect("valid");
        let read = |wrap_u, filter, u: f32| {
            let lookup = ImageLookup {
                wrap_u,
                wrap_v: Wrap::Repeat,
                filter,
                ..ImageLookup::default()
            };
            // v = 0.75: row 0's centre (t = 0.25), so only x varies.
            image_at(&image.with_lookup(lookup), Vec2::new(u, 0.75))
        };
        let x = |wrap, filter, u| read(wrap, filter, u).x;
        // Nearest: u = -0.1 is texel -1, u = 1.2 texel 3 (of 0..3).
        assert_eq!(x(Wrap::Repeat, Filter::Nearest, -0.1), 2.0);
        assert_eq!(x(Wrap::Clamp, Filter::Nearest, -0.1), 0.0);
        assert_eq!(x(Wrap::Mirror, Filter::Nearest, -0.1), 0.0);
        assert_eq!(x(Wrap::Repeat, Filter::Nearest, 1.2), 0.0);
        assert_eq!(x(Wrap::Clamp, Filter::Nearest, 1.2), 2.0);
        assert_eq!(x(Wrap::Mirror, Filter::Nearest, 1.2), 2.0);
        // Mirror's period is twice the image: texel 4 is texel 1, texel 6 texel 0 again.
        assert_eq!(x(Wrap::Mirror, Filter::Nearest, 1.5), 1.0);
        assert_eq!(x(Wrap::Mirror, Filter::Nearest, 2.1), 0.0);
        assert_eq!(x(Wrap::Clamp, Filter::Nearest, 0.5), 1.0);
        // Linear, halfway between texel centres 2 and 3 (u = 1): repeat blends texel 2 with
        // texel 0, clamp and mirror keep texel 2.
        assert_eq!(x(Wrap::Repeat, Filter::Linear, 1.0), 1.0);
        assert_eq!(x(Wrap::Clamp, Filter::Linear, 1.0), 2.0);
        assert_eq!(x(Wrap::Mirror, Filter::Linear, 1.0), 2.0);
        // The default lookup is the bilinear repeat environments use.
        for u in [-0.7, 0.1, 0.5, 1.3] {
            assert_eq!(
                image_at(&image, Vec2::new(u, 0.3)),
                bilinear(&image, u, 0.7),
                "{u}"
            );
        }
    }
}
