//! A metal (twin: `shaders/materials/conductor.wgsl`): exact conductor Fresnel reflectance of a
//! complex index of refraction eta + i k per channel, relative to the outside (taken as air),
//! on a smooth surface (roughness 0: a mirror, a delta lobe) or on GGX microfacets (see
//! [`super::microfacet`]), sampled by their visible normals. Single scattering: energy lost
//! between microfacets at high roughness is not put back (no Kulla-Conty term). Random numbers
//! per sample: 2 when rough, none when smooth.

use crate::shared::feature::MaterialFeature;
use super::microfacet::{Frame, Ggx, MIN_ALPHA, MIN_COSINE};
use super::{BsdfSample, Lobe, MaterialModel, reflect};
use crate::params::checked;
use crate::shared::layout::GpuMaterial;
use crate::shared::params::{MaterialParams, material_params};
use crate::shared::ray::{Hit, below_surface};
use crate::shared::sampler::Sampler;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// `{ type = "conductor", metal = "Au", roughness = 0.3 }` (a measured metal, [`METALS`]) or
/// `{ type = "conductor", eta = [r, g, b], k = [r, g, b], roughness = 0.3 }`; `roughness` in
/// [0, 1], default 0 (a mirror; below 0.01 too), with GGX's alpha = roughness^2.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "ConductorDoc", into = "ConductorDoc")]
pub struct Conductor {
    pub eta: Vec3,
    pub k: Vec3,
    pub roughness: f32,
}

/// The scene-file form: a metal's name or its index.
#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct ConductorDoc {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    metal: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none", with = "optional_colour")]
    eta: Option<Vec3>,
    #[serde(default, skip_serializing_if = "Option::is_none", with = "optional_colour")]
    k: Option<Vec3>,
    #[serde(default, with = "checked::number")]
    roughness: f32,
}

mod optional_colour {
    use super::checked;
    use glam::Vec3;
    use serde::{Deserialize, Deserializer, Serializer};

    #[derive(Deserialize)]
    struct Wrapped(#[serde(with = "checked::colour")] Vec3);

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec3>, D::Error> {
        Option::<Wrapped>::deserialize(d).map(|w| w.map(|w| w.0))
    }
    pub fn serialize<S: Serializer>(v: &Option<Vec3>, s: S) -> Result<S::Ok, S::Error> {
        match v {
            Some(v) => checked::colour::serialize(v, s),
            None => s.serialize_none(),
        }
    }
}

impl TryFrom<ConductorDoc> for Conductor {
    type Error = String;

    fn try_from(doc: ConductorDoc) -> Result<Self, String> {
        let (eta, k) = match (doc.metal, doc.eta, doc.k) {
            (Some(name), None, None) => {
                let (_, eta, k) = METALS
                    .iter()
                    .find(|(known, _, _)| *known == name)
                    .ok_or_else(|| {
                        let known: Vec<&str> = METALS.iter().map(|m| m.0).collect();
                        format!("unknown metal {name:?}: known metals are {}", known.join(", "))
                    })?;
                (Vec3::from(*eta), Vec3::from(*k))
            }
            (None, Some(eta), Some(k)) => (eta, k),
            (Some(_), _, _) => {
                return Err("give a conductor either metal or eta and k, not both".into());
            }
            (None, _, _) => {
                return Err("a conductor needs metal = NAME, or both eta and k".into());
            }
        };
        Ok(Conductor {
            eta,
            k,
            roughness: doc.roughness,
        })
    }
}

impl From<Conductor> for ConductorDoc {
    fn from(c: Conductor) -> Self {
        ConductorDoc {
            metal: None,
            eta: Some(c.eta),
            k: Some(c.k),
            roughness: c.roughness,
        }
    }
}

impl Conductor {
    /// The measured metal `name` of [`METALS`].
    pub fn metal(name: &str, roughness: f32) -> Option<Self> {
        METALS.iter().find(|m| m.0 == name).map(|(_, eta, k)| Conductor {
            eta: Vec3::from(*eta),
            k: Vec3::from(*k),
            roughness,
        })
    }

    fn ggx(&self) -> Ggx {
        Ggx {
            alpha: self.roughness * self.roughness,
        }
    }
}

material_params! {
    pub struct ConductorParams {
        eta: [f32; 3],
        /// GGX alpha; 0: smooth (as any alpha below `MIN_ALPHA`).
        alpha: f32,
        k: [f32; 3],
    }
}

impl MaterialModel for Conductor {
    type Params = ConductorParams;
    const FEATURE: MaterialFeature = MaterialFeature::Conductor;
    /// Rough conductors.
    const EXTRA_FEATURES: &'static [MaterialFeature] = &[MaterialFeature::Microfacet];
    const SAMPLES_LIGHTS: bool = true;
    const SAMPLES_LIGHTS_PER_INSTANCE: bool = true;

    fn validate(&self) -> Result<(), String> {
        if !(0.0..=1.0).contains(&self.roughness) {
            return Err(format!("roughness must be in [0, 1], got {}", self.roughness));
        }
        // Below, the Fresnel term's squares vanish in f32 (0/0 at normal incidence).
        if !(self.eta.min_element() >= MIN_ETA) {
            return Err(format!(
                "eta must be at least {MIN_ETA:e} in every channel, got {}",
                self.eta
            ));
        }
        if !(self.k.min_element() >= 0.0) {
            return Err(format!("k must be >= 0 in every channel, got {}", self.k));
        }
        // Measured metals lie far below (eta and k within 20); above, the Fresnel term's squares
        // of squares overflow f32.
        if !(self.eta.max_element() <= MAX_INDEX && self.k.max_element() <= MAX_INDEX) {
            return Err(format!(
                "eta and k must be at most {MAX_INDEX:e} in every channel, got eta {} and k {}",
                self.eta, self.k
            ));
        }
        // |eta^2 - 1 + ...|: where it vanishes in f32 the reflectance at grazing incidence is 0/0.
        let grazing = |c: usize| {
            let (eta, k) = (self.eta[c] as f64, self.k[c] as f64);
            (eta * eta - k * k - 1.0).powi(2) + 4.0 * k * k * eta * eta
        };
        if (0..3).any(|c| grazing(c) < 1e-12) {
            return Err(format!(
                "eta {} with k {} is (nearly) no surface: eta 1 with k 0 reflects nothing (its Fresnel reflectance is 0/0 at grazing incidence)",
                self.eta, self.k
            ));
        }
        Ok(())
    }

    fn extra_features(&self) -> Vec<MaterialFeature> {
        if self.samples_lights() {
            Self::EXTRA_FEATURES.to_vec()
        } else {
            Vec::new()
        }
    }

    /// Rough: smooth (alpha below [`MIN_ALPHA`], roughness 0.01) is a delta lobe.
    fn samples_lights(&self) -> bool {
        self.ggx().alpha >= MIN_ALPHA
    }

    fn reflects_only(&self) -> bool {
        true
    }

    fn sample(&self, wo: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<BsdfSample> {
        if !self.samples_lights() {
            let wi = reflect(-wo, hit.shading);
            // Reflected below the surface by a shading normal: absorbed.
            return (wi.dot(hit.normal) > 0.0).then(|| BsdfSample {
                weight: fresnel_conductor(wo.dot(hit.shading), self.eta, self.k),
                wi,
                pdf: 0.0,
                lobe: Lobe::DELTA_REFLECTION,
            });
        }
        let (u1, u2) = (sampler.next_f32(), sampler.next_f32());
        let frame = Frame::new(hit.shading);
        let wo_local = frame.to_local(wo);
        if !(wo_local.z > MIN_COSINE) {
            return None;
        }
        let ggx = self.ggx();
        let m = ggx.sample_visible(wo_local, u1, u2);
        let wi_local = reflect(-wo_local, m);
        let wi = frame.to_world(wi_local);
        if !(wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
            return None;
        }
        // f cos / pdf = F D G2 / (4 cos_o) / (G1 D / (4 cos_o)) = F G2 / G1.
        let weight = fresnel_conductor(wo_local.dot(m), self.eta, self.k)
            * (ggx.g2(wo_local, wi_local) / ggx.g1(wo_local));
        Some(BsdfSample {
            weight,
            wi,
            pdf: ggx.reflection_pdf(wo_local, m),
            lobe: Lobe::GLOSSY_REFLECTION,
        })
    }

    fn eval(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> Vec3 {
        if !self.samples_lights() {
            return Vec3::ZERO; // a delta lobe only
        }
        let Some((wo_local, wi_local, m)) = reflection_half_vector(wo, wi, hit) else {
            return Vec3::ZERO;
        };
        let ggx = self.ggx();
        fresnel_conductor(wo_local.dot(m), self.eta, self.k)
            * (ggx.d(m) * ggx.g2(wo_local, wi_local) / (4.0 * wo_local.z))
    }

    fn pdf(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> f32 {
        if !self.samples_lights() {
            return 0.0;
        }
        reflection_half_vector(wo, wi, hit)
            .map_or(0.0, |(wo_local, _, m)| self.ggx().reflection_pdf(wo_local, m))
    }

    /// Its [`ConductorParams`].
    fn gpu(&self) -> GpuMaterial {
        GpuMaterial {
            params: ConductorParams {
                eta: self.eta.to_array(),
                alpha: if self.samples_lights() { self.ggx().alpha } else { 0.0 },
                k: self.k.to_array(),
            }
            .words(),
            ..Default::default()
        }
    }
}

/// `wo` and `wi` in the shading frame and their half vector, where both are above the shading
/// surface and `wi` above the geometric one; `None` elsewhere (no reflection reaches there).
#[inline]
fn reflection_half_vector(wo: Vec3, wi: Vec3, hit: &Hit) -> Option<(Vec3, Vec3, Vec3)> {
    let frame = Frame::new(hit.shading);
    let (wo_local, wi_local) = (frame.to_local(wo), frame.to_local(wi));
    if !(wo_local.z > MIN_COSINE && wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
        return None;
    }
    let m = wo_local + wi_local;
    let len2 = m.length_squared();
    (len2 > 0.0).then(|| (wo_local, wi_local, m / len2.sqrt()))
}

/// The smallest `eta` a conductor may have (measured metals' lie above 0.03).
pub const MIN_ETA: f32 = 1e-3;
/// The largest `eta` or `k` a conductor may have.
pub const MAX_INDEX: f32 = 1e4;

/// Exact unpolarised Fresnel reflectance from a medium of index 1 into a conductor of complex
/// index eta + i k, per channel, at incidence cosine `cos_i` (the closed form of Mitsuba 3's
/// `fresnel_conductor`; pbrt-v4's `FrComplex` computes the same with complex numbers).
#[inline]
pub fn fresnel_conductor(cos_i: f32, eta: Vec3, k: Vec3) -> Vec3 {
    let c = cos_i.clamp(0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let t1 = eta * eta - k * k - Vec3::splat(s2);
    let a2pb2 = (t1 * t1 + 4.0 * k * k * eta * eta).map(f32::sqrt);
    let a = (0.5 * (a2pb2 + t1)).max(Vec3::ZERO).map(f32::sqrt);
    let term1 = a2pb2 + Vec3::splat(c2);
    let term2 = 2.0 * c * a;
    let rs = (term1 - term2) / (term1 + term2);
    let term3 = a2pb2 * c2 + Vec3::splat(s4);
    let term4 = term2 * s2;
    let rp = rs * (term3 - term4) / (term3 + term4);
    0.5 * (rs + rp)
}

/// Measured metals by chemical symbol: (name, eta, k) per linear-sRGB channel, relative to
/// air. Ag, Al, Au, Cr, Cu, Ni: the spectra Mitsuba 3 ships for its conductors' `material`
/// presets (mitsuba-data `ior/<name>.{eta,k}.spd`, from the Luxpop database, based on Palik,
/// Handbook of Optical Constants of Solids, 1985; Ni is Mitsuba's `Ni_palik`; Cr adds LLNL/CXRO
/// data). Fe, Ti: Johnson and Christy, Phys. Rev. B 9, 5056 (1974), as refractiveindex.info's
/// database tabulates them. Reduced to RGB as Mitsuba 3's RGB variants reduce a `material`
/// preset (so that scenes compare with Mitsuba's): each spectrum weighted by the CIE 1931
/// colour matching functions without an illuminant, then XYZ to linear sRGB;
/// `tools/metals/reduce.py` regenerates the table from the data beside it.
pub const METALS: &[(&str, [f32; 3], [f32; 3])] = &[
    ("Ag", [0.1553, 0.1167, 0.1384], [4.828, 3.122, 2.147]),
    ("Al", [1.658, 0.8804, 0.5212], [9.224, 6.270, 4.837]),
    ("Au", [0.1430, 0.3753, 1.442], [3.983, 2.386, 1.603]),
    ("Cr", [4.370, 2.917, 1.655], [5.207, 4.231, 3.755]),
    ("Cu", [0.2010, 0.9237, 1.102], [3.913, 2.453, 2.142]),
    ("Fe", [3.514, 2.770, 2.302], [3.695, 2.786, 2.493]),
    ("Ni", [2.367, 1.663, 1.467], [4.499, 3.050, 2.345]),
    ("Ti", [3.275, 2.380, 2.025], [4.572, 3.225, 2.728]),
];

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 61: every eta and k the check accepts gives a finite reflectance in [0, 1] at every
    /// incidence, grazing included (k or eta above ~4e9 overflowed; eta 1 with k 1e-30 was 0/0);
    /// the values at the edges of what is accepted are tried, and those just past them refused.
    #[test]
    fn every_accepted_index_reflects_finitely() {
        let edges = [
            0.0, 1e-30, 1e-6, 1e-3, 0.5, 1.0 - 1e-7, 1.0, 1.0 + 1e-7, 1.5, 10.0, 1e3, MAX_INDEX,
            1.5 * MAX_INDEX, 4e9, f32::MAX,
        ];
        let (mut accepted, mut refused) = (0, 0);
        for &eta in &edges {
            for &k in &edges {
                let c = Conductor {
                    eta: Vec3::splat(eta),
                    k: Vec3::splat(k),
                    roughness: 0.0,
                };
                if c.validate().is_err() {
                    refused += 1;
                    continue;
                }
                accepted += 1;
                for cos in [0.0, 1e-30, 1e-8, 1e-3, 0.5, 1.0 - 1e-7, 1.0] {
                    let f = fresnel_conductor(cos, c.eta, c.k);
                    assert!(
                        f.is_finite() && f.min_element() >= 0.0 && f.max_element() <= 1.0 + 1e-5,
                        "eta {eta} k {k} cos {cos}: {f}"
                    );
                }
            }
        }
        assert!(accepted > 100 && refused > 20, "{accepted} {refused}");
        for (eta, k) in [(4e9, 1.0), (1.0, 4e9), (1.0, 1e-30), (1.0, 0.0)] {
            let c = Conductor {
                eta: Vec3::splat(eta),
                k: Vec3::splat(k),
                roughness: 0.0,
            };
            assert!(c.validate().is_err(), "eta {eta} k {k} accepted");
        }
    }
}
