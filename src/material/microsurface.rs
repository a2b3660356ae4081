//! Shading normals as microfacets: Schüssler, Hanika, Jung, Dachsbacher and Wyman,
//! "Microfacet-based Normal Mapping for Robust Monte Carlo Path Tracing" (SIGGRAPH Asia 2017).
//! Twin: `shaders/microsurface.wgsl`.
//!
//! A normal map's shading normal, which differs from the geometric normal `n`, is not a frame
//! to shade in: a direction can face `n` and not the shading
//! normal, and a BSDF evaluated there returns nothing (the black rims of normal-mapped metal
//! under a sky), or light leaves below the geometric surface and is lost. Here the surface is a
//! microsurface of two facets whose projected areas add up to the geometric surface's: one
//! facing the shading normal `wp`, which scatters with the material's own BSDF, and a
//! perfectly specular one `wt`, perpendicular to `n`, that fills the gap. Light meets `wp`
//! directly or after `wt`, scatters on `wp`, and leaves, possibly by way of `wt`, with the
//! paper's masking `G1`; every direction above `n` reflects, and a lossless material stays
//! lossless (a white furnace renders 1).
//!
//! Chosen over Cycles' valid-reflection correction (which bends the normal so that the mirror
//! direction stays above the surface): that one still loses the light a diffuse or rough lobe
//! sends below the surface, so a furnace is not 1. The paper's own evaluation keeps only the
//! walks of up to two facet events (`wp`, `wp` then `wt`, `wt` then `wp`), which loses a
//! large share of a lambertian's light at steep tilts (docs/benchmarks.md). So `sample`
//! follows the whole walk (up to [`MAX_SCATTERINGS`] scatterings on `wp`) and this splits the
//! BSDF in two: the first-order walks, which `eval` and `pdf` give in closed form and
//! next-event estimation weighs by multiple importance sampling, and the rest, which only
//! `sample` finds and returns with pdf 0 (light it then meets counts in full, as after a
//! mirror). The two estimate disjoint parts of one BSDF, so their sum is unbiased.
//!
//! It applies to normal-mapped materials that only reflect (`Material::has_microsurface`) and
//! have no clear coat: the microsurface is the whole BSDF's, and a coat lies over a mapped base
//! with a normal of its own (`Hit::coat`), outside it. Glass, and a coated base, keep the
//! shading normal as their frame and end paths that would leave on the wrong side; so do a mesh's interpolated vertex normals, whose small tilts Cycles and pbrt-v4 shade
//! as they are (as microsurfaces they moved Blender's smooth spheres away from Cycles:
//! docs/benchmarks.md). A normal map's look departs from Cycles' (which bends the map's normal
//! toward the viewer and lets light below the surface go) where light grazes: a facet tilted
//! toward it is shadowed by its neighbours and one tilted away lit by their mirror.

use super::{BsdfSample, Material, reflect};
use crate::shared::ray::Hit;
use crate::shared::sampler::Sampler;
use glam::Vec3;

/// Scatterings on the shading facet a sampled walk may take before it is given up (its light
/// lost). A walk goes on after a scattering only when light is shadowed twice (by `wt`, then
/// by `wp`), more often the steeper the tilt: enough that a white lambertian keeps its albedo
/// at any tilt a normal map gives (tests/it/bsdfs/microsurface.rs; docs/benchmarks.md).
pub const MAX_SCATTERINGS: u32 = 64;

/// Below this sine of its tilt, a shading normal is the geometric normal (no microsurface).
pub const MIN_SIN: f32 = 1e-5;
/// Below this cosine of its tilt, the shading facet is bent past what f32 resolves: the
/// geometric normal shades.
pub const MIN_COS: f32 = 1e-3;

/// The two facets at a hit whose shading normal differs from its geometric normal.
#[derive(Clone, Copy, Debug)]
pub struct Microsurface {
    /// The geometric normal (facing the incoming ray): the macro surface.
    n: Vec3,
    /// The shading facet's normal.
    wp: Vec3,
    /// The tangent facet's normal: perpendicular to `n`, against `wp`'s tilt.
    wt: Vec3,
    /// Sine and cosine of `wp`'s tilt from `n`.
    sin: f32,
    cos: f32,
    /// The hit as the shading facet sees it: its geometric and shading normal both `wp`.
    facet: Hit,
}

impl Microsurface {
    /// The microsurface at `hit`, `None` where its shading normal is (to f32) its geometric
    /// normal or lies on the far side of it.
    pub fn at(hit: &Hit) -> Option<Self> {
        let (n, wp) = (hit.normal, hit.shading);
        let cos = wp.dot(n);
        let tilt = wp - cos * n;
        let sin = tilt.length();
        if !(sin > MIN_SIN && cos > MIN_COS) {
            return None;
        }
        Some(Microsurface {
            n,
            wp,
            wt: -tilt / sin,
            sin,
            cos,
            facet: Hit {
                normal: wp,
                shading: wp,
                ..*hit
            },
        })
    }

    /// The facets' projected area toward `w`, per unit of geometric area: `w . n` where both
    /// facets face `w`.
    fn projected(&self, w: Vec3) -> f32 {
        (w.dot(self.wp).max(0.0) + w.dot(self.wt).max(0.0) * self.sin) / self.cos
    }

    /// The chance that light arriving from `w` meets the shading facet first (else the tangent
    /// facet, which mirrors it onto the shading facet).
    fn meets_shading_facet(&self, w: Vec3) -> f32 {
        let total = self.projected(w);
        if total > 0.0 {
            w.dot(self.wp).max(0.0) / self.cos / total
        } else {
            0.0
        }
    }

    /// The chance that light leaving a facet toward `w` escapes the microsurface (the paper's
    /// G1); 0 below the geometric surface.
    fn escapes(&self, w: Vec3) -> f32 {
        let up = w.dot(self.n);
        if !(up > 0.0) {
            return 0.0;
        }
        (up / self.projected(w)).min(1.0)
    }

    /// `w` after the tangent facet's mirror.
    fn mirrored(&self, w: Vec3) -> Vec3 {
        reflect(w, self.wt)
    }

    /// Samples the walk of light leaving toward `wo`. Random numbers: 1 (which facet `wo`'s
    /// light meets first), then per scattering a new group for the material's own numbers and
    /// one for 2 escape decisions.
    pub fn sample(&self, m: &Material, wo: Vec3, sampler: &mut Sampler) -> Option<BsdfSample> {
        let direct = sampler.next_f32() < self.meets_shading_facet(wo);
        let mut from = if direct { wo } else { self.mirrored(wo) };
        let mut weight = Vec3::ONE;
        for scattering in 0..MAX_SCATTERINGS {
            if !(from.dot(self.wp) > 0.0) {
                return None;
            }
            sampler.begin();
            let s = m.facet_sample(from, &self.facet, sampler)?;
            weight *= s.weight;
            sampler.begin();
            let (u1, u2) = (sampler.next_f32(), sampler.next_f32());
            // Out directly, or by way of the tangent facet; the walks `eval` gives in closed
            // form are the first scattering's, but for one that met the tangent facet both
            // before and after.
            let (wi, first_order) = if u1 < self.escapes(s.wi) {
                (s.wi, scattering == 0)
            } else {
                let after = self.mirrored(s.wi);
                if !(u2 < self.escapes(after)) {
                    from = -after;
                    continue;
                }
                (after, scattering == 0 && direct)
            };
            let pdf = if first_order && !s.lobe.is_delta() {
                self.pdf(m, wo, wi)
            } else {
                0.0
            };
            return Some(BsdfSample {
                weight,
                wi,
                pdf,
                lobe: s.lobe,
            });
        }
        None
    }

    /// BSDF x cos(wi, n) of the first-order walks (see the module's comment).
    pub fn eval(&self, m: &Material, wo: Vec3, wi: Vec3) -> Vec3 {
        self.first_order(wo, wi, |from, to| m.facet_eval(from, to, &self.facet))
    }

    /// The density with which `sample` returns `wi` by a first-order walk.
    pub fn pdf(&self, m: &Material, wo: Vec3, wi: Vec3) -> f32 {
        self.first_order(wo, wi, |from, to| {
            Vec3::splat(m.facet_pdf(from, to, &self.facet))
        })
        .x
    }

    /// The sum over the first-order walks from `wo` to `wi` of `facet(from, to)` (the shading
    /// facet's eval or pdf) times the chances of the facet events: met directly and out
    /// directly, met directly and out by way of the tangent facet, met by way of the tangent
    /// facet and out directly.
    fn first_order(&self, wo: Vec3, wi: Vec3, facet: impl Fn(Vec3, Vec3) -> Vec3) -> Vec3 {
        let out = self.escapes(wi);
        if !(out > 0.0) {
            return Vec3::ZERO;
        }
        let direct = self.meets_shading_facet(wo);
        let mut sum = Vec3::ZERO;
        if direct > 0.0 {
            let after = self.mirrored(wi);
            sum += direct * facet(wo, wi);
            sum += direct * (1.0 - self.escapes(after)) * facet(wo, after);
        }
        let mirrored = self.mirrored(wo);
        if direct < 1.0 && mirrored.dot(self.wp) > 0.0 {
            sum += (1.0 - direct) * facet(mirrored, wi);
        }
        sum * out
    }
}
