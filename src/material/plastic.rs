//! Plastic (twin: `shaders/materials/plastic.wgsl`): a clear dielectric coat, smooth or on GGX
//! microfacets, over a lambertian base, the light reflected back and forth between the two
//! summed in closed form (the model of Mitsuba 3's `plastic` with `nonlinear`, after Weidlich
//! and Wilkie 2007), two-sided. Random numbers per sample: 3.
//!
//! The coat reflects `F(wo.m) D G2 / (4 cos_o cos_i)` (a mirror's F(cos_o) when smooth). The
//! base, seen through it, is
//!
//! `f_d = albedo (1 - F(cos_o)) (1 - F(cos_i)) / (pi eta^2 (1 - albedo K))`
//!
//! with F the smooth coat's Fresnel reflectance from outside, eta its index and K = 1 - (1 -
//! Fbar) / eta^2 its internal diffuse reflectance (Fbar = the cosine-weighted mean of F over the
//! hemisphere: the identity between a boundary's mean reflectances from both sides). Then a white
//! base under a smooth coat reflects everything: F(cos_o) + (1 - F(cos_o)) = 1, and any albedo
//! <= 1 less. A rough coat's own reflection is taken as reaching no further than the smooth
//! coat's F(cos_o), which the white furnace test checks, so it loses what its microfacets lose
//! and no more. Why closed form rather than pbrt-v4's stochastic layering: `eval` and `pdf` are
//! then exact functions of (wo, wi), as light sampling, MIS and the kernel-against-CPU tests
//! need, at the cost of a lambertian base and a clear coat.

use super::fresnel::{fresnel, refract_cos};
use super::microfacet::{Frame, Ggx, MIN_ALPHA, MIN_COSINE};
use super::{BsdfSample, Lobe, MaterialModel, reflect};
use crate::material::texture;
use crate::scene::file::checked;
use crate::scene::texture::Texture;
use crate::shared::layout::GpuMaterial;
use crate::shared::ray::{Hit, below_surface};
use crate::shared::sampler::Sampler;
use crate::shared::warp::{cosine_pdf, unit_vector};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// `{ type = "plastic", albedo = [0.6, 0.05, 0.05], ior = 1.5, roughness = 0.2 }`: the base's
/// albedo (any texture, in [0, 1]), the coat's index (default 1.5) and roughness in [0, 1]
/// (default 0: smooth; below 0.01 too), GGX alpha = roughness^2.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "PlasticDoc", into = "PlasticDoc")]
pub struct Plastic {
    pub albedo: Texture,
    pub ior: f32,
    pub roughness: f32,
    /// The coat's internal diffuse reflectance K, from `ior`.
    internal_reflectance: f32,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct PlasticDoc {
    albedo: Texture,
    #[serde(default = "default_ior", with = "checked::number")]
    ior: f32,
    #[serde(default, with = "checked::number")]
    roughness: f32,
}

fn default_ior() -> f32 {
    1.5
}

impl TryFrom<PlasticDoc> for Plastic {
    type Error = String;
    fn try_from(doc: PlasticDoc) -> Result<Self, String> {
        if !(doc.ior > 0.0) {
            return Err(format!("ior must be > 0, got {}", doc.ior));
        }
        Ok(Plastic::new(doc.albedo, doc.ior, doc.roughness))
    }
}

impl From<Plastic> for PlasticDoc {
    fn from(p: Plastic) -> Self {
        PlasticDoc {
            albedo: p.albedo,
            ior: p.ior,
            roughness: p.roughness,
        }
    }
}

impl Plastic {
    /// A coat of index `ior` (> 0) and `roughness` over a base of `albedo`.
    pub fn new(albedo: Texture, ior: f32, roughness: f32) -> Self {
        Plastic {
            albedo,
            ior,
            roughness,
            internal_reflectance: 1.0 - (1.0 - fresnel_mean(ior)) / (ior * ior),
        }
    }

    fn ggx(&self) -> Option<Ggx> {
        let alpha = self.roughness * self.roughness;
        (alpha >= MIN_ALPHA).then_some(Ggx { alpha })
    }

    /// The coat's Fresnel reflectance at `cos` from outside.
    fn coat_fresnel(&self, cos: f32) -> f32 {
        coat_fresnel(cos, self.ior)
    }

    /// The chance of sampling the coat rather than the base, at `wo` (local) over `albedo`.
    fn coat_chance(&self, f_o: f32, albedo: Vec3) -> f32 {
        let base = (1.0 - f_o) * (albedo.x + albedo.y + albedo.z) / 3.0;
        if f_o + base > 0.0 { f_o / (f_o + base) } else { 1.0 }
    }

    /// The base's BSDF as seen through the coat, times pi (`f_d` of the module's comment).
    fn base(&self, albedo: Vec3, f_o: f32, f_i: f32) -> Vec3 {
        albedo * ((1.0 - f_o) * (1.0 - f_i) / (self.ior * self.ior))
            / (Vec3::ONE - albedo * self.internal_reflectance)
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

impl MaterialModel for Plastic {
    const FEATURE: &'static str = "PLASTIC";
    /// Textured albedos (shaders/microfacet.wgsl is included for it without a feature).
    const EXTRA_FEATURES: &'static [&'static str] = &["CHECKER", "UV_CHECKER", "IMAGE_TEXTURE"];
    const SAMPLES_LIGHTS: bool = true;

    fn validate(&self) -> Result<(), String> {
        if !(self.ior > 0.0) {
            return Err(format!("ior must be > 0, got {}", self.ior));
        }
        if !(0.0..=1.0).contains(&self.roughness) {
            return Err(format!("roughness must be in [0, 1], got {}", self.roughness));
        }
        self.albedo.validate_albedo()
    }

    fn extra_features(&self) -> Vec<&'static str> {
        self.albedo.feature().into_iter().collect()
    }

    fn relocated(self, origin: glam::DVec3) -> Self {
        Plastic {
            albedo: self.albedo.relocated(origin),
            ..self
        }
    }

    fn textures(&self) -> Vec<Texture> {
        vec![self.albedo]
    }

    fn sample(&self, wo: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<BsdfSample> {
        let u = sampler.next_f32();
        let (u1, u2) = (sampler.next_f32(), sampler.next_f32());
        let frame = Frame::new(hit.shading);
        let wo_local = frame.to_local(wo);
        if !(wo_local.z > MIN_COSINE) {
            return None;
        }
        let albedo = texture::value(&self.albedo, hit);
        let f_o = self.coat_fresnel(wo_local.z);
        let chance = self.coat_chance(f_o, albedo);
        let coat = u < chance;
        let wi = match (coat, self.ggx()) {
            (true, None) => {
                let wi = reflect(-wo, hit.shading);
                // The smooth coat's mirror: a delta lobe, weighed by its chance alone.
                return (!below_surface(hit, wi)).then(|| BsdfSample {
                    weight: Vec3::splat(f_o / chance),
                    wi,
                    pdf: 0.0,
                    lobe: Lobe::DELTA_REFLECTION,
                });
            }
            (true, Some(ggx)) => {
                let m = ggx.sample_visible(wo_local, u1, u2);
                frame.to_world(reflect(-wo_local, m))
            }
            (false, _) => {
                // normal + a uniform unit vector is cosine-distributed about the normal.
                let d = hit.shading + unit_vector(u1, u2);
                let len2 = d.length_squared();
                if len2 > 1e-12 {
                    d / len2.sqrt()
                } else {
                    hit.shading
                }
            }
        };
        let pdf = self.pdf(wo, wi, hit);
        if !(pdf > 0.0) {
            return None;
        }
        // Either lobe's direction is weighed by both lobes' BSDF over both densities (the
        // one-sample MIS of a mixture).
        Some(BsdfSample {
            weight: self.eval(wo, wi, hit) / pdf,
            wi,
            pdf,
            lobe: if coat {
                Lobe::GLOSSY_REFLECTION
            } else {
                Lobe::DIFFUSE_REFLECTION
            },
        })
    }

    fn eval(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> Vec3 {
        let frame = Frame::new(hit.shading);
        let (wo_local, wi_local) = (frame.to_local(wo), frame.to_local(wi));
        if !(wo_local.z > MIN_COSINE && wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
            return Vec3::ZERO;
        }
        let albedo = texture::value(&self.albedo, hit);
        let f_o = self.coat_fresnel(wo_local.z);
        let base = self.base(albedo, f_o, self.coat_fresnel(wi_local.z))
            * (wi_local.z * std::f32::consts::FRAC_1_PI);
        let Some(ggx) = self.ggx() else {
            return base;
        };
        let m = (wo_local + wi_local).normalize();
        let coat = self.coat_fresnel(wo_local.dot(m)) * ggx.d(m) * ggx.g2(wo_local, wi_local)
            / (4.0 * wo_local.z);
        base + Vec3::splat(coat)
    }

    fn pdf(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> f32 {
        let frame = Frame::new(hit.shading);
        let (wo_local, wi_local) = (frame.to_local(wo), frame.to_local(wi));
        if !(wo_local.z > MIN_COSINE && wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
            return 0.0;
        }
        let albedo = texture::value(&self.albedo, hit);
        let chance = self.coat_chance(self.coat_fresnel(wo_local.z), albedo);
        let base = (1.0 - chance) * cosine_pdf(hit, wi);
        let Some(ggx) = self.ggx() else {
            return base;
        };
        let m = (wo_local + wi_local).normalize();
        base + chance * ggx.reflection_pdf(wo_local, m)
    }

    /// albedo (and texture_*); param: ior; alpha: GGX alpha (0: smooth); internal_reflectance.
    fn gpu(&self) -> GpuMaterial {
        GpuMaterial {
            param: self.ior,
            alpha: self.ggx().map_or(0.0, |g| g.alpha),
            internal_reflectance: self.internal_reflectance,
            ..GpuMaterial::with_albedo(&self.albedo)
        }
    }
}
