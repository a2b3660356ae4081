//! The path tracer (twin: `shaders/integrator.wgsl`): the original project's recursive
//! `ray_color`, made iterative. Segment k (1-based) adds the emission it hits, or the background
//! it escapes to, for k <= max_depth.
//!
//! With next-event estimation (`Integrator::Nee`), each hit on a material that samples lights (a
//! non-delta BSDF: lambertian) also samples a light directly with a shadow ray, and light found
//! both ways is weighted by the power heuristic.
//! A light sample taken at the k-th hit forms a path of k + 1 segments, so it is taken only when
//! k + 1 <= max_depth: both integrators sum over exactly the same paths.

use super::background::background;
use super::lights;
use super::shapes::{Hit, Ray, intersect, leave, spawn};
use crate::options::{Integrator, RenderOptions};
use crate::sampler::Sampler;
use crate::scene::Material;
use crate::scene::flat::FlatScene;
use glam::Vec3;

/// Roulette keeps a path with the probability of its largest throughput component, capped here
/// so bright paths still end eventually.
pub const MAX_SURVIVAL: f32 = 0.95;

/// Whether light sampling runs: asked for, and the scene has a light to sample.
pub fn uses_nee(scene: &FlatScene, opts: &RenderOptions) -> bool {
    opts.integrator == Integrator::Nee && !scene.lights.is_empty()
}

pub fn radiance(
    scene: &FlatScene,
    mut ray: Ray,
    opts: &RenderOptions,
    sampler: &mut Sampler,
) -> Vec3 {
    let nee = uses_nee(scene, opts);
    let mut total = Vec3::ZERO;
    let mut throughput = Vec3::ONE;
    // The pdf with which the BSDF chose `ray`, from `origin`; 0 when light sampling could not
    // have chosen it (camera rays, delta BSDFs), so light it finds counts in full.
    let mut bsdf_pdf = 0.0;
    let mut origin = ray.origin;
    for segment in 0..opts.max_depth {
        let Some(hit) = intersect(scene, &ray) else {
            total += throughput * background(&scene.background, ray.dir);
            break;
        };
        let material = &scene.materials[hit.material as usize];
        let light = scene.light_of(hit.primitive);
        let mut weight = 1.0;
        if nee && bsdf_pdf > 0.0 && light > 0 {
            let l = &scene.lights[light as usize - 1];
            let light_pdf = lights::pdf(l, origin, hit.point, ray.dir);
            weight = lights::power_heuristic(bsdf_pdf, light_pdf);
        }
        total += throughput * weight * material.emitted(&hit);
        if segment + 1 == opts.max_depth {
            break; // no longer path counts
        }
        bsdf_pdf = 0.0;
        let light_sampled = nee && material.samples_lights();
        if light_sampled {
            // Purposes: the light pick (1D), the point on the light (2D).
            sampler.begin();
            let u0 = sampler.next_f32();
            sampler.begin();
            let (u1, u2) = (sampler.next_f32(), sampler.next_f32());
            if let Some((weight, light)) = direct_light(scene, material, &hit, u0, u1, u2) {
                total += throughput * weight * light;
            }
        }
        sampler.begin();
        let Some((attenuation, dir)) = material.scatter(ray.dir, &hit, sampler) else {
            break;
        };
        throughput *= attenuation;
        if light_sampled {
            bsdf_pdf = material.bsdf(&hit, dir).map_or(0.0, |(_, pdf)| pdf);
        }
        origin = hit.point;
        ray = spawn(&hit, dir);
        if opts.roulette_depth > 0 && segment + 1 >= opts.roulette_depth {
            let survival = throughput.max_element().min(MAX_SURVIVAL);
            sampler.begin();
            if !(sampler.next_f32() < survival) {
                break;
            }
            throughput /= survival;
        }
    }
    total
}

/// One light sample at `hit`: the BSDF's weight toward it (BSDF x cos / BSDF pdf) and the light
/// arriving, times the MIS weight and the BSDF pdf over the light pdf, so that their product is
/// the sample's contribution; `None` if the light is below the surface or occluded.
#[inline]
fn direct_light(
    scene: &FlatScene,
    material: &Material,
    hit: &Hit,
    u0: f32,
    u1: f32,
    u2: f32,
) -> Option<(Vec3, Vec3)> {
    let index = lights::pick_light(scene, u0);
    let sample = lights::sample(&scene.lights[index], hit.point, u1, u2)?;
    let (weight, bsdf_pdf) = material.bsdf(hit, sample.dir)?;
    // The shadow ray leaves the offset origin aimed at the sampled point itself, so that a tiny
    // light is not missed by the width of the offset. Whatever it hits first must be that light.
    let origin = leave(hit, hit.normal);
    let to_light = sample.point - origin;
    if !(to_light.length_squared() > 0.0) {
        return None;
    }
    let shadow_ray = Ray {
        origin,
        dir: to_light.normalize(),
    };
    let shadow = intersect(scene, &shadow_ray)?;
    if scene.light_of(shadow.primitive) != index as u32 + 1 {
        return None;
    }
    let le = scene.materials[shadow.material as usize].emitted(&shadow);
    Some((
        weight,
        le * lights::light_sample_factor(sample.pdf, bsdf_pdf),
    ))
}
