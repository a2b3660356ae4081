//! The GGX (Trowbridge-Reitz) microfacet distribution with Smith masking-shadowing (twin:
//! `shaders/microfacet.wgsl`), isotropic, in a local frame whose z axis is the shading normal.
//!
//! Masking-shadowing is the height-correlated Smith form G2 = 1 / (1 + Lambda(wo) + Lambda(wi))
//! (Heitz 2014, "Understanding the Masking-Shadowing Function"), as pbrt-v4 and glTF's
//! specification use: it is the exact Smith shadowing of a surface whose heights are
//! uncorrelated with its slopes, and the separable product G1 G1 counts the same occlusion
//! twice. Visible normals are sampled on spherical caps (Dupuy and Benyoub 2023, "Sampling
//! Visible GGX Normals with Spherical Caps"): the distribution of Heitz 2018 with fewer
//! operations and no branch.

use glam::Vec3;
use std::f32::consts::PI;

/// Below this alpha a surface is smooth (a delta lobe): D's peak 1 / (pi alpha^2) would
/// overflow, and flush to zero on a GPU, long before (pbrt-v4's `EffectivelySmooth` is 1e-3).
pub const MIN_ALPHA: f32 = 1e-4;

/// Directions whose cosine to the shading normal is at most this count as below the surface:
/// nearer the horizon tan^2 overflows f32.
pub const MIN_COSINE: f32 = 1e-7;

/// GGX with roughness `alpha` (>= [`MIN_ALPHA`]): glTF's and Blender's alpha = roughness^2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    pub alpha: f32,
}

impl Ggx {
    /// The density of microfacet normals `m` (unit, local) per solid angle, projected: its
    /// integral of D(m) cos(m) over the hemisphere is 1.
    #[inline]
    pub fn d(&self, m: Vec3) -> f32 {
        if !(m.z > 0.0) {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        // 1 / (pi a^2 cos^4 (1 + tan^2 / a^2)^2), written without the tangent.
        let t = (m.x * m.x + m.y * m.y) / a2 + m.z * m.z;
        1.0 / (PI * a2 * t * t)
    }

    /// Smith's Lambda of direction `w` (unit, local, `w.z` > [`MIN_COSINE`]).
    #[inline]
    pub fn lambda(&self, w: Vec3) -> f32 {
        let x = self.alpha * self.alpha * (w.x * w.x + w.y * w.y) / (w.z * w.z);
        0.5 * ((1.0 + x).sqrt() - 1.0)
    }

    /// The fraction of microfacets visible from `w`.
    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// The fraction visible from both `wo` and `wi` (height-correlated).
    #[inline]
    pub fn g2(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// A microfacet normal visible from `wo` (local, `wo.z` > [`MIN_COSINE`]), with density
    /// [`Self::visible_pdf`]. Random numbers: `u1`, `u2`.
    #[inline]
    pub fn sample_visible(&self, wo: Vec3, u1: f32, u2: f32) -> Vec3 {
        // Stretched to the configuration of alpha = 1, where visible normals are the sum of
        // wo and a point uniform on the unit sphere's cap z > -wo.z.
        let v = Vec3::new(self.alpha * wo.x, self.alpha * wo.y, wo.z).normalize();
        let (sin, cos) = crate::shared::angles::sin_cos_pi(2.0 * u1 - 1.0);
        let z = (1.0 - u2) * (1.0 + v.z) - v.z;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let h = Vec3::new(r * cos, r * sin, z) + v;
        let m = Vec3::new(self.alpha * h.x, self.alpha * h.y, h.z.max(0.0));
        let len2 = m.length_squared();
        if len2 > 1e-30 {
            m / len2.sqrt()
        } else {
            Vec3::Z
        }
    }

    /// The density of [`Self::sample_visible`]: G1(wo) max(0, wo.m) D(m) / wo.z.
    #[inline]
    pub fn visible_pdf(&self, wo: Vec3, m: Vec3) -> f32 {
        self.g1(wo) * wo.dot(m).max(0.0) * self.d(m) / wo.z
    }

    /// The density of the reflected direction `wi` = reflect(-wo, m) for m sampled by
    /// [`Self::sample_visible`]: visible_pdf / (4 wo.m) = G1(wo) D(m) / (4 wo.z), with
    /// m = normalize(wo + wi).
    #[inline]
    pub fn reflection_pdf(&self, wo: Vec3, m: Vec3) -> f32 {
        self.g1(wo) * self.d(m) / (4.0 * wo.z)
    }
}

/// Converts directions between world space and the local frame of a hit's shading normal
/// (z), completed by `warp::basis`.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub s: Vec3,
    pub t: Vec3,
    pub n: Vec3,
}

impl Frame {
    #[inline]
    pub fn new(n: Vec3) -> Self {
        let (s, t) = crate::shared::warp::basis(n);
        Frame { s, t, n }
    }
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}
