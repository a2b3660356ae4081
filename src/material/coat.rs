//! A clear dielectric coat over a lambertian base, in closed form (twin: `shaders/coat.wgsl`):
//! `plastic`, and the dielectric part of `pbr`. The coat reflects `F(wo.m) D G2 / (4 cos_o
//! cos_i)` (a mirror's F(cos_o) when smooth); the base, seen through it, is
//!
//! `f_d = albedo (1 - O(cos_o)) (1 - O(cos_i)) / (pi eta^2 (1 - s K))`
//!
//! with eta the coat's index, O its opacity (the share of light met from outside that does not
//! cross it) and K its internal diffuse reflectance. For a smooth coat (and pbr's, rough or not)
//! O is Fresnel's F and K = 1 - (1 - Fbar) / eta^2 (Fbar the cosine-weighted mean of F: the
//! identity between a boundary's mean reflectances from both sides). For plastic's rough coat,
//! 1 - O is the albedo of rough glass's transmission lobe and K the mean albedo of its reflection
//! lobe from inside, both tabulated ([`CoatTable`]), as Mitsuba 3's `roughplastic` has them.
//! `s` is the albedo when the coat *saturates* (light bouncing between coat and base, the
//! geometric series of Mitsuba 3's `plastic` with `nonlinear`, after Weidlich and Wilkie 2007),
//! 1 when it does not (the base's colour kept, as glTF's metallic-roughness model and Mitsuba's
//! default keep it). Either way a white base under a smooth coat reflects everything: F(cos_o) +
//! (1 - F(cos_o)) = 1. Rough, the coat loses what its microfacets lose in single scattering, at
//! each crossing inside it too, which the white furnace tests bound.

use super::coat_table::CoatTable;
use super::fresnel::{fresnel, refract_cos};
use super::microfacet::{Frame, Ggx, MIN_ALPHA, MIN_COSINE};
use super::specular::SpecularFresnel;
use super::{BsdfSample, Lobe, reflect};
use crate::shared::ray::{Hit, below_surface};
use crate::shared::warp::{cosine_direction, cosine_pdf};
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coat {
    pub ior: f32,
    /// GGX alpha; 0: smooth.
    pub alpha: f32,
    /// K, from `ior` (and the table, where there is one).
    pub internal_reflectance: f32,
    pub saturates: bool,
    /// A rough coat's tabulated opacity and K (plastic's), else none: smooth Fresnel's.
    pub table: Option<&'static CoatTable>,
    /// Fresnel reshaped by glTF's specular strength and colour (pbr's; `material::specular`),
    /// else none: Fresnel's own.
    pub specular: Option<SpecularFresnel>,
}

impl Coat {
    /// A coat of index `ior` (> 0) and `roughness` (alpha = roughness^2; below alpha
    /// [`MIN_ALPHA`], smooth).
    pub fn new(ior: f32, roughness: f32, saturates: bool) -> Self {
        Coat {
            ior,
            alpha: Coat::alpha_of(roughness),
            internal_reflectance: 1.0 - (1.0 - fresnel_mean(ior)) / (ior * ior),
            saturates,
            table: None,
            specular: None,
        }
    }

    /// The smooth-Fresnel coat with its Fresnel reshaped by `specular` (none: Fresnel's own),
    /// its K following from its mean opacity as for Fresnel (so that a smooth coat over a white
    /// base reflects everything).
    pub fn with_specular(self, specular: Option<SpecularFresnel>) -> Self {
        let mean = match specular {
            Some(s) => s.mean_opacity(),
            None => fresnel_mean(self.ior),
        };
        Coat {
            internal_reflectance: 1.0 - (1.0 - mean) / (self.ior * self.ior),
            specular,
            ..self
        }
    }

    /// The coat letting through, where rough, what rough glass's transmission lobe does (its
    /// [`CoatTable`]); smooth, it is unchanged.
    pub fn tabulated(self) -> Self {
        match self.ggx() {
            Some(ggx) => {
                let table = CoatTable::of(self.ior, ggx.alpha);
                Coat {
                    internal_reflectance: table.internal_reflectance,
                    table: Some(table),
                    ..self
                }
            }
            None => self,
        }
    }

    /// The coat's opacity at incidence cosine `cos` from outside, the share of light that does
    /// not cross it: its table's, else smooth Fresnel's.
    #[inline]
    fn opacity(&self, cos: f32) -> f32 {
        match (self.table, self.specular) {
            (Some(table), _) => table.opacity(cos),
            (None, Some(specular)) => specular.opacity(cos, self.ior),
            (None, None) => coat_fresnel(cos, self.ior),
        }
    }

    /// What the coat's surface (or a microfacet of it) reflects at cosine `cos`: Fresnel, or
    /// its specular reshaping (a colour).
    #[inline]
    fn reflectance(&self, cos: f32) -> Vec3 {
        match self.specular {
            Some(specular) => specular.reflectance(cos, self.ior),
            None => Vec3::splat(coat_fresnel(cos, self.ior)),
        }
    }

    /// The GGX alpha of `roughness`: roughness^2, or 0 (smooth) below [`MIN_ALPHA`] (twin:
    /// `roughness_alpha` in `shaders/materials/pbr.wgsl`).
    #[inline]
    pub fn alpha_of(roughness: f32) -> f32 {
        let alpha = roughness * roughness;
        if alpha >= MIN_ALPHA { alpha } else { 0.0 }
    }

    fn ggx(&self) -> Option<Ggx> {
        (self.alpha > 0.0).then_some(Ggx { alpha: self.alpha })
    }

    /// The chance of sampling the coat rather than the base.
    fn chance(f_o: f32, albedo: Vec3) -> f32 {
        let base = (1.0 - f_o) * (albedo.x + albedo.y + albedo.z) / 3.0;
        if f_o + base > 0.0 {
            f_o / (f_o + base)
        } else {
            1.0
        }
    }

    /// The base's BSDF as seen through the coat, times pi.
    fn base(&self, albedo: Vec3, f_o: f32, f_i: f32) -> Vec3 {
        let s = if self.saturates { albedo } else { Vec3::ONE };
        albedo * ((1.0 - f_o) * (1.0 - f_i) / (self.ior * self.ior))
            / (Vec3::ONE - s * self.internal_reflectance)
    }

    /// A direction for light leaving toward `wo` over a base of `albedo`, from numbers `u`
    /// (which lobe), `u1`, `u2`.
    pub fn sample(
        &self,
        albedo: Vec3,
        wo: Vec3,
        hit: &Hit,
        (u, u1, u2): (f32, f32, f32),
    ) -> Option<BsdfSample> {
        let frame = Frame::new(hit.shading);
        let wo_local = frame.to_local(wo);
        if !(wo_local.z > MIN_COSINE) {
            return None;
        }
        let f_o = self.opacity(wo_local.z);
        let chance = Coat::chance(f_o, albedo);
        let coat = u < chance;
        let wi = match (coat, self.ggx()) {
            (true, None) => {
                let wi = reflect(-wo, hit.shading);
                // The smooth coat's mirror: a delta lobe, weighed by its chance alone.
                let reflected = match self.specular {
                    Some(specular) => specular.reflectance(wo_local.z, self.ior),
                    None => Vec3::splat(f_o),
                };
                return (!below_surface(hit, wi)).then(|| BsdfSample {
                    weight: reflected / chance,
                    wi,
                    pdf: 0.0,
                    lobe: Lobe::DELTA_REFLECTION,
                });
            }
            (true, Some(ggx)) => {
                let m = ggx.sample_visible(wo_local, u1, u2);
                frame.to_world(reflect(-wo_local, m))
            }
            (false, _) => cosine_direction(hit.shading, u1, u2),
        };
        let pdf = self.pdf(albedo, wo, wi, hit);
        if !(pdf > 0.0) {
            return None;
        }
        // Either lobe's direction is weighed by both lobes' BSDF over both densities (the
        // one-sample MIS of a mixture).
        Some(BsdfSample {
            weight: self.eval(albedo, wo, wi, hit) / pdf,
            wi,
            pdf,
            lobe: if coat {
                Lobe::GLOSSY_REFLECTION
            } else {
                Lobe::DIFFUSE_REFLECTION
            },
        })
    }

    /// BSDF x cos over its non-delta lobes.
    pub fn eval(&self, albedo: Vec3, wo: Vec3, wi: Vec3, hit: &Hit) -> Vec3 {
        let frame = Frame::new(hit.shading);
        let (wo_local, wi_local) = (frame.to_local(wo), frame.to_local(wi));
        if !(wo_local.z > MIN_COSINE && wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
            return Vec3::ZERO;
        }
        let f_o = self.opacity(wo_local.z);
        let base = self.base(albedo, f_o, self.opacity(wi_local.z))
            * (wi_local.z * std::f32::consts::FRAC_1_PI);
        let Some(ggx) = self.ggx() else {
            return base;
        };
        let m = (wo_local + wi_local).normalize();
        let coat = self.reflectance(wo_local.dot(m)) * ggx.d(m) * ggx.g2(wo_local, wi_local)
            / (4.0 * wo_local.z);
        base + coat
    }

    /// The density of [`Coat::sample`] over its non-delta lobes.
    pub fn pdf(&self, albedo: Vec3, wo: Vec3, wi: Vec3, hit: &Hit) -> f32 {
        let frame = Frame::new(hit.shading);
        let (wo_local, wi_local) = (frame.to_local(wo), frame.to_local(wi));
        if !(wo_local.z > MIN_COSINE && wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
            return 0.0;
        }
        let chance = Coat::chance(self.opacity(wo_local.z), albedo);
        let base = (1.0 - chance) * cosine_pdf(hit, wi);
        let Some(ggx) = self.ggx() else {
            return base;
        };
        let m = (wo_local + wi_local).normalize();
        base + chance * ggx.reflection_pdf(wo_local, m)
    }
}

/// Smooth Fresnel reflectance from outside into index `ior` at incidence cosine `cos`.
#[inline]
pub fn coat_fresnel(cos: f32, ior: f32) -> f32 {
    let eta = 1.0 / ior;
    let cos = cos.clamp(0.0, 1.0);
    refract_cos(cos, eta).map_or(1.0, |cos_t| fresnel(cos, cos_t, eta))
}

/// The cosine-weighted hemispherical mean of [`coat_fresnel`], 2 int_0^1 F(mu) mu dmu, by
/// Simpson's rule in f64 over 1 000 panels (F is smooth on [0, 1] from outside).
pub fn fresnel_mean(ior: f32) -> f32 {
    const PANELS: usize = 1000;
    let f = |mu: f64| coat_fresnel(mu as f32, ior) as f64 * mu;
    let h = 1.0 / PANELS as f64;
    let mut sum = f(0.0) + f(1.0);
    for i in 1..PANELS {
        sum += f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    (2.0 * sum * h / 3.0) as f32
}
