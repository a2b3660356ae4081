//! Glass (twin: `shaders/materials/dielectric.wgsl`): exact unpolarised Fresnel (pbr's glass:
//! reshaped by glTF's specular, `Dielectric::reflectance`), refraction by
//! Snell's law, total internal reflection; smooth (roughness 0: two delta lobes) or rough, on
//! GGX microfacets (Walter et al. 2007, "Microfacet Models for Refraction through Rough
//! Surfaces"), sampled by their visible normals. Random numbers per sample: 1 when smooth, 3
//! when rough. With a `medium`, the glass is filled with it: subsurface scattering by a
//! volumetric random walk.
//!
//! Radiance is not scaled by the squared ratio of indices where it crosses the surface: in
//! scenes whose camera and lights are outside every object, each path crosses into and out of
//! each object alike, so the factors cancel. The BTDF is then pbrt-v4's in its importance form,
//! the same for light sampling as for sampled directions.

use crate::shared::feature::MaterialFeature;
use super::microfacet::{Frame, Ggx, MIN_ALPHA, MIN_COSINE};
use super::coat::coat_fresnel;
use super::fresnel::{fresnel, refract_cos};
use super::specular::SpecularFresnel;
use super::{BsdfSample, Lobe, MaterialModel, Medium, reflect};
use crate::shared::ray::Hit;
use crate::shared::layout::GpuMaterial;
use crate::shared::params::{MaterialParams, material_params};
use crate::shared::sampler::Sampler;
use crate::params::checked;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// `{ type = "dielectric", ior = 1.5, roughness = 0.25 }`: the index of refraction inside,
/// relative to outside, and the roughness in [0, 1] (default 0: smooth; below 0.01 too), with
/// GGX's alpha = roughness^2; optionally `medium = { density = 0.05, albedo = [0.9, 0.6, 0.3],
/// g = 0.5 }` inside.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Dielectric {
    #[serde(with = "checked::number")]
    pub ior: f32,
    #[serde(default, with = "checked::number", skip_serializing_if = "is_zero")]
    pub roughness: f32,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub medium: Option<Medium>,
    /// Its Fresnel reshaped by glTF's specular strength and colour: pbr's glass only
    /// (`material::specular`; not a scene-file parameter of glass, and not in [`Self::gpu`]'s
    /// parameters: the kernel's pbr passes its own specular to its glass).
    #[serde(skip)]
    pub specular: Option<SpecularFresnel>,
}

/// How near 1 an index is taken as 1 by rough glass (see `samples_lights`).
pub const INDEX_MATCHED: f32 = 1e-3;

impl Dielectric {
    /// Clear glass.
    pub fn clear(ior: f32) -> Self {
        Dielectric {
            ior,
            roughness: 0.0,
            medium: None,
            specular: None,
        }
    }

    /// Clear glass of this roughness.
    pub fn rough(ior: f32, roughness: f32) -> Self {
        Dielectric {
            roughness,
            ..Dielectric::clear(ior)
        }
    }

    /// This glass with its Fresnel reshaped by `specular` (none: exact Fresnel's own).
    pub fn with_specular(self, specular: Option<SpecularFresnel>) -> Self {
        Dielectric { specular, ..self }
    }

    /// What the glass reflects at a (micro)surface where exact Fresnel reflectance is `f` (1
    /// under total internal reflection), and the chance that a sample reflects: `f` and `f`,
    /// or where a specular reshapes it, `factor x Fr` (a colour) and its largest channel; the
    /// glass transmits 1 minus the chance (`material::specular`). Under total internal
    /// reflection it reflects everything, reshaped or not: nothing can cross.
    #[inline]
    pub fn reflectance(&self, f: f32) -> (Vec3, f32) {
        match self.specular {
            Some(s) if f < 1.0 => {
                let r = s.reshaped(f, coat_fresnel(1.0, self.ior));
                (r, r.max_element())
            }
            _ => (Vec3::splat(f), f),
        }
    }

    fn ggx(&self) -> Ggx {
        Ggx {
            alpha: self.roughness * self.roughness,
        }
    }

    /// The index of the side `wo` is on over that of the other side.
    fn eta(&self, hit: &Hit) -> f32 {
        if hit.front_face {
            1.0 / self.ior
        } else {
            self.ior
        }
    }

    fn sample_smooth(&self, wo: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<BsdfSample> {
        let eta = self.eta(hit);
        let n = hit.shading;
        let dir_in = -wo;
        let cos_i = wo.dot(n).clamp(0.0, 1.0);
        let u = sampler.next_f32();
        let (f, cos_t) = fresnel_and_cos_t(cos_i, eta);
        let (r, chance) = self.reflectance(f);
        // Reflection with its chance: what it reflects over that, 1 without a specular.
        let (wi, lobe, weight) = match cos_t {
            Some(cos_t) if u >= chance => (
                eta * dir_in + (eta * cos_i - cos_t) * n,
                Lobe::DELTA_TRANSMISSION,
                Vec3::ONE,
            ),
            _ => (reflect(dir_in, n), Lobe::DELTA_REFLECTION, r / chance),
        };
        let wi = wi.normalize();
        on_its_side(hit, wi, lobe).then_some(BsdfSample {
            weight,
            wi,
            pdf: 0.0,
            lobe,
        })
    }
}

fn is_zero(x: &f32) -> bool {
    *x == 0.0
}

/// Whether `wi`, sampled in `lobe`, leaves on that lobe's side of the geometric surface: a
/// shading normal can send a reflection into the surface or a refraction out of it (then
/// absorbed; the geometric normal decides sides, as for the medium inside).
#[inline]
fn on_its_side(hit: &Hit, wi: Vec3, lobe: Lobe) -> bool {
    hit.shading == hit.normal || (wi.dot(hit.normal) > 0.0) != lobe.is_transmission()
}

/// Fresnel reflectance at a (micro)surface whose normal makes cosine `cos_i` with the incident
/// direction, and the refracted direction's cosine (`None`: total internal reflection).
#[inline]
fn fresnel_and_cos_t(cos_i: f32, eta: f32) -> (f32, Option<f32>) {
    match refract_cos(cos_i, eta) {
        Some(cos_t) => (fresnel(cos_i, cos_t, eta), Some(cos_t)),
        None => (1.0, None),
    }
}

/// The Fresnel reflectance of a pair of directions at microfacet normal `m`, from their cosines
/// to it: a refraction's own cos_t, not Snell's law's, which cancels in f32 near the critical
/// angle (where 1 - F is then wrong by up to 10% seen from inside), so that the pair's BSDF is
/// the same from either side.
#[inline]
fn pair_fresnel(cos_o: f32, cos_i: f32, eta: f32, reflected: bool) -> f32 {
    if reflected {
        fresnel_and_cos_t(cos_o, eta).0
    } else {
        fresnel(cos_o, -cos_i, eta)
    }
}

/// `wo` and `wi` in the shading frame and the microfacet normal that takes one to the other
/// (the half vector of a reflection, or Walter's generalised one of a refraction), with the
/// lobe: `None` where no microfacet does (a direction at the horizon, on the wrong side of the
/// geometric surface, or on a microfacet's back).
#[inline]
fn rough_pair(wo: Vec3, wi: Vec3, hit: &Hit, eta: f32) -> Option<(Vec3, Vec3, Vec3, bool)> {
    let frame = Frame::new(hit.shading);
    let (wo_local, wi_local) = (frame.to_local(wo), frame.to_local(wi));
    if !(wo_local.z > MIN_COSINE && wi_local.z.abs() > MIN_COSINE) {
        return None;
    }
    let reflected = wi_local.z > 0.0;
    let lobe = if reflected {
        Lobe::GLOSSY_REFLECTION
    } else {
        Lobe::GLOSSY_TRANSMISSION
    };
    if !on_its_side(hit, wi, lobe) {
        return None;
    }
    // n_i wo + n_t wi, over n_t; toward wo's side.
    let m = if reflected {
        wo_local + wi_local
    } else {
        eta * wo_local + wi_local
    };
    let len2 = m.length_squared();
    if !(len2 > 0.0) {
        return None;
    }
    let m = m / len2.sqrt() * m.z.signum();
    (wo_local.dot(m) > 0.0 && (wi_local.dot(m) > 0.0) == reflected)
        .then_some((wo_local, wi_local, m, reflected))
}

material_params! {
    /// Also the glass of `pbr`'s mix.
    pub struct DielectricParams {
        ior: f32,
        /// GGX alpha; 0: smooth (as any alpha below `MIN_ALPHA`).
        alpha: f32,
    }
}

impl MaterialModel for Dielectric {
    type Params = DielectricParams;
    const FEATURE: MaterialFeature = MaterialFeature::Dielectric;
    /// Glass filled with a medium; rough glass.
    const EXTRA_FEATURES: &'static [MaterialFeature] =
        &[MaterialFeature::Media, MaterialFeature::Absorption, MaterialFeature::Microfacet];
    const SAMPLES_LIGHTS: bool = true;
    const SAMPLES_LIGHTS_PER_INSTANCE: bool = true;

    fn validate(&self) -> Result<(), String> {
        super::fresnel::check_ior(self.ior)?;
        if !(0.0..=1.0).contains(&self.roughness) {
            return Err(format!("roughness must be in [0, 1], got {}", self.roughness));
        }
        self.medium.as_ref().map_or(Ok(()), Medium::check)
    }

    fn extra_features(&self) -> Vec<MaterialFeature> {
        let mut out = self.medium.as_ref().map_or_else(Vec::new, Medium::features);
        if self.samples_lights() {
            out.push(MaterialFeature::Microfacet);
        }
        out
    }

    fn interior(&self) -> Option<&Medium> {
        self.medium.as_ref()
    }

    /// Rough: smooth (alpha below [`MIN_ALPHA`], roughness 0.01) is two delta lobes, and so
    /// is an index of 1, which refracts every microfacet's light straight on: within
    /// [`INDEX_MATCHED`] of 1, where the microfacet transmission's Jacobian divides by the
    /// vanishing difference (at 1.0000001, NaN samples), the surface is taken as smooth; its
    /// reflectance there is below 3e-7 and its refraction bends light by less than a thousandth.
    fn samples_lights(&self) -> bool {
        self.ggx().alpha >= MIN_ALPHA && (self.ior - 1.0).abs() >= INDEX_MATCHED
    }

    fn sample(&self, wo: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<BsdfSample> {
        if !self.samples_lights() {
            return self.sample_smooth(wo, hit, sampler);
        }
        let (u1, u2) = (sampler.next_f32(), sampler.next_f32());
        let u = sampler.next_f32();
        let frame = Frame::new(hit.shading);
        let wo_local = frame.to_local(wo);
        if !(wo_local.z > MIN_COSINE) {
            return None;
        }
        let (ggx, eta) = (self.ggx(), self.eta(hit));
        let m = ggx.sample_visible(wo_local, u1, u2);
        let cos_i = wo_local.dot(m);
        let (f, cos_t) = fresnel_and_cos_t(cos_i, eta);
        let (r, chance) = self.reflectance(f);
        // Reflection with its chance, F without a specular: the BSDF's and the pdf's cancel in
        // the weight but for the reflectance's colour.
        let (wi_local, lobe, pdf, tint) = match cos_t {
            Some(cos_t) if u >= chance => {
                let wi_local = (eta * cos_i - cos_t) * m - eta * wo_local;
                let denom = wi_local.dot(m) + eta * cos_i;
                let jacobian = wi_local.dot(m).abs() / (denom * denom);
                let pdf = (1.0 - chance) * ggx.visible_pdf(wo_local, m) * jacobian;
                (wi_local, Lobe::GLOSSY_TRANSMISSION, pdf, Vec3::ONE)
            }
            _ => {
                let wi_local = reflect(-wo_local, m);
                let pdf = chance * ggx.reflection_pdf(wo_local, m);
                (wi_local, Lobe::GLOSSY_REFLECTION, pdf, r / chance)
            }
        };
        let wi = frame.to_world(wi_local);
        let on_side = if lobe.is_transmission() {
            wi_local.z < -MIN_COSINE
        } else {
            wi_local.z > MIN_COSINE
        };
        if !(on_side && on_its_side(hit, wi, lobe) && pdf > 0.0) {
            return None;
        }
        // f cos / pdf = G2 / G1 for either lobe (Walter's BTDF over its pdf), tinted.
        Some(BsdfSample {
            weight: tint * (ggx.g2(wo_local, wi_local) / ggx.g1(wo_local)),
            wi,
            pdf,
            lobe,
        })
    }

    fn eval(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> Vec3 {
        if !self.samples_lights() {
            return Vec3::ZERO; // delta lobes only
        }
        let eta = self.eta(hit);
        let Some((wo_local, wi_local, m, reflected)) = rough_pair(wo, wi, hit, eta) else {
            return Vec3::ZERO;
        };
        let ggx = self.ggx();
        let cos_i = wo_local.dot(m);
        let (r, chance) = self.reflectance(pair_fresnel(cos_i, wi_local.dot(m), eta, reflected));
        let dg = ggx.d(m) * ggx.g2(wo_local, wi_local);
        if reflected {
            r * dg / (4.0 * wo_local.z)
        } else {
            let denom = wi_local.dot(m) + eta * cos_i;
            Vec3::splat((1.0 - chance) * dg * wi_local.dot(m).abs() * cos_i / (wo_local.z * denom * denom))
        }
    }

    fn pdf(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> f32 {
        if !self.samples_lights() {
            return 0.0;
        }
        let eta = self.eta(hit);
        let Some((wo_local, wi_local, m, reflected)) = rough_pair(wo, wi, hit, eta) else {
            return 0.0;
        };
        let ggx = self.ggx();
        let cos_i = wo_local.dot(m);
        let (_, chance) = self.reflectance(pair_fresnel(cos_i, wi_local.dot(m), eta, reflected));
        if reflected {
            chance * ggx.reflection_pdf(wo_local, m)
        } else {
            let denom = wi_local.dot(m) + eta * cos_i;
            (1.0 - chance) * ggx.visible_pdf(wo_local, m) * wi_local.dot(m).abs() / (denom * denom)
        }
    }

    /// Its [`DielectricParams`]; medium_*: the medium inside, if any.
    fn gpu(&self) -> GpuMaterial {
        let glass = GpuMaterial {
            albedo: [1.0; 3],
            params: DielectricParams {
                ior: self.ior,
                alpha: if self.samples_lights() { self.ggx().alpha } else { 0.0 },
            }
            .words(),
            ..Default::default()
        };
        Medium::pack(self.medium.as_ref(), glass)
    }
}
