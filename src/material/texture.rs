//! Texture lookups (twin: `shaders/texture.wgsl`) and the surface coordinates they use.

use crate::scene::image::Image;
use crate::scene::image_lookup::{Filter, ImageLookup, UvSet, Wrap};
use crate::scene::texture::Texture;
use crate::shared::layout::{GpuMaterial, TEXTURE_CHECKER, TEXTURE_IMAGE, TEXTURE_UV_CHECKER};
use crate::shared::ray::Hit;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// A material's colour (albedo, base colour) from `texture` at `hit`: the texture's value times
/// the hit's vertex colour (glTF's base colour x COLOR_0; twin: albedo_at in
/// shaders/texture.wgsl). Emission is not coloured by vertices (`value`).
#[inline]
pub fn albedo(texture: &Texture, hit: &Hit) -> Vec3 {
    value(texture, hit) * hit.color
}

/// The texture's value at `hit`.
#[inline]
pub fn value(texture: &Texture, hit: &Hit) -> Vec3 {
    match texture {
        Texture::Colour(c) => *c,
        Texture::Checker(c) => {
            let p = (hit.point + c.shift) / c.scale;
            pick(parity(p.x) + parity(p.y) + parity(p.z), c.even, c.odd)
        }
        Texture::UvChecker(c) => {
            let p = hit.uv * c.scale;
            pick(parity(p.x) + parity(p.y), c.even, c.odd)
        }
        // Times the image's factor (glTF's factor x texture), as the kernel's albedo_at.
        Texture::Image(image) => image_at(image, uv_at(image.lookup, hit)) * image.factor,
    }
}

/// The texture coordinates an image read as `lookup` says is read at on `hit`: its UV set's
/// (twin: `uv_at` in shaders/texture.wgsl).
#[inline]
pub fn uv_at(lookup: ImageLookup, hit: &Hit) -> Vec2 {
    match lookup.uv_set {
        UvSet::First => hit.uv,
        UvSet::Second => hit.uv1,
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
/// colour, [`value`], applies).
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

/// floor(x) mod 2, as 0 or 1, in f32 arithmetic (exact below 2^24; no integer conversion,
/// whose overflow WGSL leaves undefined).
#[inline]
fn parity(x: f32) -> f32 {
    let cell = x.floor();
    cell - 2.0 * (cell * 0.5).floor()
}

#[inline]
fn pick(parities: f32, even: Vec3, odd: Vec3) -> Vec3 {
    if parity(parities) == 0.0 { even } else { odd }
}

/// A sphere's surface coordinates at unit outward direction `n` from its centre: u the
/// longitude from -x round through +z... (u = (atan2(-z, x) + pi) / 2 pi), v the latitude from
/// the south pole (v = acos(-y) / pi), as in Ray Tracing: The Next Week.
#[inline]
pub fn sphere_uv(n: Vec3) -> Vec2 {
    let u = (crate::shared::angles::atan2(-n.z, n.x) + PI) / (2.0 * PI);
    let v = crate::shared::angles::acos(-n.y) / PI;
    Vec2::new(u, v)
}

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
                // `texture_image` is set where the scene's images are laid out (SceneBuffers);
                // the albedo is the factor the lookup multiplies by (`image_at`).
                return GpuMaterial {
                    albedo: image.factor.to_array(),
                    texture: TEXTURE_IMAGE,
                    texture_odd: [image.width as f32, image.height as f32, 0.0],
                    texture_lookup: image.lookup.bits(),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::texture::Checker;
    use crate::shared::primitive::PrimitiveRef;

    fn hit_at(point: Vec3, uv: Vec2) -> Hit {
        Hit {
            t: 1.0,
            point,
            error: 0.0,
            normal: Vec3::Y,
            shading: Vec3::Y,
            front_face: true,
            material: 0,
            primitive: PrimitiveRef::Shape {
                kind: crate::shape::Quad::KIND,
                index: 0,
            },
            uv,
            uv1: uv,
            color: Vec3::ONE,
        }
    }

    #[test]
    fn checkers_alternate() {
        let (even, odd) = (Vec3::ONE, Vec3::ZERO);
        let c = Checker {
            scale: 2.0,
            even,
            odd,
            shift: Vec3::ZERO,
        };
        let solid = Texture::Checker(c);
        let at = |x, y, z| value(&solid, &hit_at(Vec3::new(x, y, z), Vec2::ZERO));
        assert_eq!(at(0.5, 0.5, 0.5), even);
        assert_eq!(at(2.5, 0.5, 0.5), odd);
        assert_eq!(at(-0.5, 0.5, 0.5), odd);
        assert_eq!(at(-0.5, -0.5, 0.5), even);
        assert_eq!(at(2.5, 2.5, 2.5), odd);
        let flat = Texture::UvChecker(Checker { scale: 4.0, ..c });
        let uv = |u, v| value(&flat, &hit_at(Vec3::ZERO, Vec2::new(u, v)));
        assert_eq!(uv(0.1, 0.1), even);
        assert_eq!(uv(0.3, 0.1), odd);
        assert_eq!(uv(0.3, 0.3), even);
        assert_eq!(uv(0.99, 0.1), odd);
    }

    #[test]
    fn a_shifted_checker_stays_in_place() {
        let c = Checker {
            scale: 3.0,
            even: Vec3::ONE,
            odd: Vec3::ZERO,
            shift: Vec3::ZERO,
        };
        let origin = glam::DVec3::new(1e7, -2048.0, 5e6 + 1024.0);
        let moved = Texture::Checker(c).relocated(origin);
        for p in [Vec3::new(0.5, 1.5, 2.5), Vec3::new(-4.0, 7.2, 0.1)] {
            let world = (p.as_dvec3() + origin) / 3.0;
            let parity = (world.x.floor() + world.y.floor() + world.z.floor()).rem_euclid(2.0);
            let expected = if parity == 0.0 { c.even } else { c.odd };
            assert_eq!(value(&moved, &hit_at(p, Vec2::ZERO)), expected, "{p}");
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
        use crate::scene::image_lookup::{Filter, ImageLookup, Wrap};
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

    #[test]
    fn sphere_uv_follows_the_book() {
        assert!((sphere_uv(Vec3::X) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!((sphere_uv(Vec3::Y) - Vec2::new(0.5, 1.0)).length() < 1e-6);
        assert!((sphere_uv(Vec3::NEG_Y).y).abs() < 1e-6);
        assert!((sphere_uv(Vec3::NEG_X) - Vec2::new(0.0, 0.5)).length() < 1e-6);
        assert!((sphere_uv(Vec3::Z) - Vec2::new(0.25, 0.5)).length() < 1e-6);
        assert!((sphere_uv(Vec3::NEG_Z) - Vec2::new(0.75, 0.5)).length() < 1e-6);
    }
}
