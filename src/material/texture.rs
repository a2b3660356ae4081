//! Texture lookups (twin: `shaders/texture.wgsl`) and the surface coordinates they use.

use crate::scene::image::Image;
use crate::scene::texture::Texture;
use crate::shared::layout::{GpuMaterial, TEXTURE_CHECKER, TEXTURE_IMAGE, TEXTURE_UV_CHECKER};
use crate::shared::ray::Hit;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

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
        Texture::Image(image) => bilinear(image, hit.uv.x, 1.0 - hit.uv.y),
    }
}

/// `image` filtered bilinearly at image coordinates (s, t) (s across, t down, [0, 1] spans
/// the image once; texel centres at half-integers), wrapping around both edges.
#[inline]
pub fn bilinear(image: &Image, s: f32, t: f32) -> Vec3 {
    let (w, h) = (image.width as f32, image.height as f32);
    let x = s * w - 0.5;
    let y = t * h - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let (x0, x1) = (wrap(x0, w), wrap(x0 + 1.0, w));
    let (y0, y1) = (wrap(y0, h), wrap(y0 + 1.0, h));
    let top = image.texel(x0, y0) * (1.0 - fx) + image.texel(x1, y0) * fx;
    let bottom = image.texel(x0, y1) * (1.0 - fx) + image.texel(x1, y1) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// Integer-valued `i` wrapped into 0..n, in f32 arithmetic as the kernel does it (clamped,
/// for coordinates so large that rounding leaves them outside).
#[inline]
fn wrap(i: f32, n: f32) -> u32 {
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
    let u = ((-n.z).atan2(n.x) + PI) / (2.0 * PI);
    let v = (-n.y).clamp(-1.0, 1.0).acos() / PI;
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
            primitive: PrimitiveRef::Quad(0),
            uv,
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
