//! A material's texture at a hit (twin: `shaders/texture.wgsl`, whose image reading is
//! `assets::image_lookup`'s twin) and the surface coordinates it reads.

use crate::assets::image_lookup::{ImageLookup, UvSet, image_at};
use crate::assets::texture::Texture;
use crate::shared::layout::{GpuMaterial, TEXTURE_CHECKER, TEXTURE_IMAGE, TEXTURE_UV_CHECKER};
use crate::shared::ray::Hit;
use glam::{Vec2, Vec3};

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
    use crate::assets::texture::Checker;
    use crate::shared::primitive::PrimitiveRef;

    fn hit_at(point: Vec3, uv: Vec2) -> Hit {
        Hit {
            t: 1.0,
            point,
            error: 0.0,
            normal: Vec3::Y,
            shading: Vec3::Y,
            coat: Vec3::Y,
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
}
