//! glTF's clear coat (KHR_materials_clearcoat) over `pbr` (twin: `shaders/clearcoat.wgsl`): a
//! clear dielectric of index 1.5 (the extension's) with its own GGX roughness, covering the
//! whole of the pbr mix below it. Its BSDF is
//!
//! `f = c fr_coat(wo, wi) + (1 - c F(cos_o)) f_base(wo, wi)`
//!
//! with `c` the clearcoat factor, `F` exact Fresnel at index 1.5 (the extension's appendix
//! writes Schlick's; pbr already uses the exact one for its own ior), `cos_o` the view's
//! cosine and `fr_coat` a GGX reflection `F(wo.m) D G2 / (4 cos_o cos_i)` (a mirror of
//! reflectance `F(cos_o)` when smooth): the extension's `mix(base, coat, c F(cos_o))`, which
//! Cycles' coat also follows (albedo scaling by the view). Chosen over attenuating the base on
//! the way out too, which would make the BSDF reciprocal but lose the light the coat reflects
//! back down (7.5% of a white base's at normal incidence, measured), where real coats let it
//! out after bouncing between coat and base: this way a smooth coat over a lossless base
//! reflects exactly everything, and a rough one loses only what its microfacets lose in
//! single scattering (tests/it/bsdfs/clearcoat.rs). Not reciprocal, as the extension's model
//! is not; a path tracer evaluates it with `wo` toward the eye, both backends alike.
//! The coat shades with a normal of its own, `Hit::coat`: a mesh's interpolated normal bent
//! by the coat's normal map (glTF's clearcoatNormalTexture) where it has one, never by the
//! base's, as glTF draws it. A mapped coat normal is bent further where its mirror would send
//! the view below the surface (`assets::normal_map::valid_reflection`, as Cycles does): the
//! steep slopes of ClearcoatWicker's wrinkles rendered black without it. A mapped base under
//! a coat is no microsurface (`material::microsurface`). The coat's factor and roughness
//! textures scale it point by point (`Pbr::layers`).
//!
//! Sampling picks the coat with chance `c F(cos_o)`, else the base (one number), so that a
//! smooth coat's mirror weighs exactly 1 and the base's deltas their own weight.

use super::coat::{Coat, coat_fresnel};
use super::microfacet::{Frame, Ggx, MIN_COSINE};
use super::reflect;
use crate::params::checked;
use crate::shared::ray::{Hit, below_surface};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// The coat's index of refraction: the extension's fixed 1.5 (F0 = 0.04).
pub const CLEARCOAT_IOR: f32 = 1.5;

/// `clearcoat = { factor = 1, roughness = 0.05 }` on a `pbr` material: glTF's
/// clearcoatFactor (default 1 here, as writing the table asks for a coat; glTF's 0 means none)
/// and clearcoatRoughnessFactor (default 0).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Clearcoat {
    #[serde(default = "one", with = "checked::number")]
    pub factor: f32,
    #[serde(default, with = "checked::number")]
    pub roughness: f32,
}

fn one() -> f32 {
    1.0
}

/// `hit` as the coat sees it: shading with the coat's normal (twin: `on_coat` in
/// shaders/clearcoat.wgsl).
#[inline]
fn on_coat(hit: &Hit) -> Hit {
    Hit {
        shading: hit.coat,
        ..*hit
    }
}

/// Where a sampled coat direction came from.
pub enum CoatDirection {
    /// The smooth coat's mirror direction.
    Mirror(Vec3),
    /// A direction from the rough coat's GGX.
    Rough(Vec3),
}

impl Clearcoat {
    /// Its parameter ranges; the message names the parameter.
    pub fn validate(&self) -> Result<(), String> {
        for (name, v) in [
            ("clearcoat factor", self.factor),
            ("clearcoat roughness", self.roughness),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(format!("{name} must be in [0, 1], got {v}"));
            }
        }
        Ok(())
    }

    /// The GGX alpha of its roughness; 0: smooth.
    #[inline]
    pub fn alpha(&self) -> f32 {
        Coat::alpha_of(self.roughness)
    }

    fn ggx(&self) -> Option<Ggx> {
        let alpha = self.alpha();
        (alpha > 0.0).then_some(Ggx { alpha })
    }

    /// The share of light met at cosine `cos` to the normal (either side) that the coat
    /// reflects: the factor times Fresnel. Also the chance of sampling the coat.
    #[inline]
    pub fn reflectance(&self, cos: f32) -> f32 {
        self.factor * coat_fresnel(cos.abs(), CLEARCOAT_IOR)
    }

    /// What of the mix below is seen through the coat toward `wo`: 1 - its reflectance there.
    #[inline]
    pub fn through(&self, wo: Vec3, hit: &Hit) -> f32 {
        1.0 - self.reflectance(wo.dot(hit.coat))
    }

    /// The rough coat's own BSDF x cos (times the factor) and the density of
    /// [`Self::sample`]'s rough directions at (wo, wi); 0 for a smooth coat.
    pub fn lobe(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> (f32, f32) {
        let Some(ggx) = self.ggx() else {
            return (0.0, 0.0);
        };
        let hit = &on_coat(hit);
        let frame = Frame::new(hit.shading);
        let (wo_local, wi_local) = (frame.to_local(wo), frame.to_local(wi));
        if !(wo_local.z > MIN_COSINE && wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
            return (0.0, 0.0);
        }
        let m = (wo_local + wi_local).normalize();
        let f = self.factor
            * coat_fresnel(wo_local.dot(m), CLEARCOAT_IOR)
            * ggx.d(m)
            * ggx.g2(wo_local, wi_local)
            / (4.0 * wo_local.z);
        (f, ggx.reflection_pdf(wo_local, m))
    }

    /// A direction reflected by the coat toward `wo`, from two numbers; `None` where it would
    /// leave below the surface.
    pub fn sample(&self, wo: Vec3, hit: &Hit, u1: f32, u2: f32) -> Option<CoatDirection> {
        let hit = &on_coat(hit);
        let frame = Frame::new(hit.shading);
        let wo_local = frame.to_local(wo);
        if !(wo_local.z > MIN_COSINE) {
            return None;
        }
        let Some(ggx) = self.ggx() else {
            let wi = reflect(-wo, hit.shading);
            return (!below_surface(hit, wi)).then_some(CoatDirection::Mirror(wi));
        };
        let wi_local = reflect(-wo_local, ggx.sample_visible(wo_local, u1, u2));
        let wi = frame.to_world(wi_local);
        (wi_local.z > MIN_COSINE && !below_surface(hit, wi)).then_some(CoatDirection::Rough(wi))
    }
}
