//! The path tracer (twin: `shaders/integrator.wgsl`): the original project's recursive
//! `ray_color`, made iterative. Segment k (1-based) adds the emission it hits, or the background
//! it escapes to, for k <= max_depth.
//!
//! With next-event estimation (`Integrator::Nee`), each hit on a material that samples lights (a
//! BSDF with a non-delta lobe: lambertian, rough conductors and glass, plastic, pbr) and each
//! scattering event in a medium also samples a light
//! directly with a shadow ray, and light found both ways is weighted by the power heuristic.
//! A light sample taken at the k-th vertex forms a path of k + 1 segments, so it is taken only
//! when k + 1 <= max_depth: both integrators sum over exactly the same paths.
//!
//! Media: the ray knows the medium it travels in (none at the camera) and changes it where it
//! crosses the surface of an object filled with one. In a medium, a free path is sampled: if it
//! ends before the next surface, the path scatters there (a segment ends at a scattering event
//! as at a surface; the phase function takes the BSDF's place); if not, the surface is reached
//! with unchanged weight (the transmittance over its probability is 1). Invisible medium
//! boundaries are stepped through without ending a segment.

use super::background::background;
use super::intersect::{intersect, intersect_light, stopped_before};
use super::lights;
use super::medium::{free_flight, hg_pdf, sample_hg};
use crate::material::Medium;
use crate::options::{Integrator, RenderOptions};
use crate::scene::Material;
use crate::scene::flat::{FlatScene, LightShape};
use crate::shared::constants::MAX_SURVIVAL;
use crate::shared::ray::{Hit, Ray, leave, spawn};
use crate::shared::sampler::Sampler;
use glam::Vec3;

/// Whether light sampling runs: asked for, and the scene has a light to sample.
pub fn uses_nee(scene: &FlatScene, opts: &RenderOptions) -> bool {
    opts.integrator == Integrator::Nee && !scene.lights.is_empty()
}

/// Where a ray's segment ends.
pub(super) enum Event {
    /// Nothing ahead.
    Escaped,
    /// A visible surface.
    Surface(Hit),
    /// A scattering event in the medium the ray travels in, at this point.
    InMedium(Vec3),
    /// More invisible boundaries than the scene can have (a degenerate ray): the path ends.
    Lost,
}

/// Follows `ray` to the end of its segment, through invisible medium boundaries (updating
/// `ray` and `medium`), sampling a free path in each medium of some density on the way, and
/// weighing `throughput` by what the media's absorption leaves of it. Random numbers: 1 per
/// stretch travelled in a medium of some density.
#[inline(always)]
pub(super) fn next_event(
    scene: &FlatScene,
    ray: &mut Ray,
    medium: &mut u32,
    throughput: &mut Vec3,
    sampler: &mut Sampler,
) -> Event {
    if *medium == 0 && scene.medium_crossings == 0 {
        // Nothing to step through or sample on the way: what the loop below does then, without
        // its cost.
        return intersect(scene, ray).map_or(Event::Escaped, Event::Surface);
    }
    for _ in 0..=scene.medium_crossings {
        let hit = intersect(scene, ray);
        if let Some(interior) = scene.medium(*medium) {
            let far = hit.map_or(f32::MAX, |h| h.t);
            if interior.density > 0.0 {
                sampler.begin();
                let distance = free_flight(interior.density, sampler.next_f32());
                if distance < far {
                    *throughput *= interior.absorbed_over(distance);
                    return Event::InMedium(ray.at(distance));
                }
            }
            *throughput *= interior.absorbed_over(far);
        }
        let Some(hit) = hit else {
            return Event::Escaped;
        };
        if !scene.materials[hit.material as usize].is_invisible() {
            return Event::Surface(hit);
        }
        *medium = entered(&hit);
        *ray = spawn(&hit, ray.dir);
    }
    Event::Lost
}

/// The medium on the far side of `hit`'s surface, for a surface filled with one: its own
/// entering through the front face, none leaving through the back (media do not overlap).
#[inline]
pub(super) fn entered(hit: &Hit) -> u32 {
    if hit.front_face { hit.material + 1 } else { 0 }
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
    // The pdf with which the BSDF (or phase function) chose `ray`, from `origin`; 0 when light
    // sampling could not have chosen it (camera rays, delta BSDFs), so light it finds counts
    // in full.
    let mut bsdf_pdf = 0.0;
    let mut origin = ray.origin;
    // 1 + the index of the material whose medium the ray travels in; 0: none.
    let mut medium = 0;
    for segment in 0..opts.max_depth {
        let hit = match next_event(scene, &mut ray, &mut medium, &mut throughput, sampler) {
            Event::Escaped => {
                total += throughput * escaped(scene, nee, bsdf_pdf, ray.dir);
                break;
            }
            Event::Lost => break,
            Event::InMedium(point) => {
                // Nothing is emitted here; this vertex can only extend the path.
                if segment + 1 == opts.max_depth {
                    break;
                }
                let Some(interior) = scene.medium(medium) else {
                    break;
                };
                throughput *= interior.albedo;
                let (light, dir, phase_pdf) =
                    scatter_in_medium(scene, interior, nee, medium, point, ray.dir, sampler);
                total += throughput * light;
                bsdf_pdf = phase_pdf;
                origin = point;
                ray = Ray { origin: point, dir };
                if !survives_roulette(opts, segment, &mut throughput, sampler) {
                    break;
                }
                continue;
            }
            Event::Surface(hit) => hit,
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
            if let Some(light) = direct_light(scene, material, &hit, ray.dir, medium, u0, u1, u2) {
                total += throughput * light;
            }
        }
        sampler.begin();
        let Some(bounce) = material.sample(-ray.dir, &hit, sampler) else {
            break;
        };
        throughput *= bounce.weight;
        if light_sampled && !bounce.lobe.is_delta() {
            bsdf_pdf = bounce.pdf;
        }
        if material.interior().is_some() && bounce.wi.dot(hit.normal) < 0.0 {
            medium = entered(&hit); // refracted through a surface filled with a medium
        }
        origin = hit.point;
        ray = spawn(&hit, bounce.wi);
        if !survives_roulette(opts, segment, &mut throughput, sampler) {
            break;
        }
    }
    total
}

/// The background a ray escapes to along `dir`, chosen by the BSDF with pdf `bsdf_pdf` (0: not
/// by one that light sampling could match), times its MIS weight against sampling the
/// environment.
#[inline]
fn escaped(scene: &FlatScene, nee: bool, bsdf_pdf: f32, dir: Vec3) -> Vec3 {
    if let Some(index) = scene.environment_light()
        && nee
        && bsdf_pdf > 0.0
        && let LightShape::Environment(env) = &scene.lights[index].shape
    {
        let (radiance, pdf) = super::environment::radiance_and_pdf(env, dir);
        let light_pdf = scene.lights[index].pick * pdf;
        return lights::power_heuristic(bsdf_pdf, light_pdf) * radiance;
    }
    background(&scene.background, dir)
}

/// A scattering event in `interior` (the ray's `medium`) at `point`, reached travelling along
/// `dir`: with nee, one light sample (its contribution per unit throughput); then the phase
/// function sampled. Returns (light sample, new direction, its phase pdf with nee, else 0).
/// Random numbers: with nee 1 + 2 (light pick, point on the light), then 2 (direction).
#[inline(never)]
fn scatter_in_medium(
    scene: &FlatScene,
    interior: &Medium,
    nee: bool,
    medium: u32,
    point: Vec3,
    dir: Vec3,
    sampler: &mut Sampler,
) -> (Vec3, Vec3, f32) {
    let mut light = Vec3::ZERO;
    if nee {
        sampler.begin();
        let u0 = sampler.next_f32();
        sampler.begin();
        let (u1, u2) = (sampler.next_f32(), sampler.next_f32());
        if let Some(arriving) =
            medium_direct_light(scene, point, dir, interior.g, medium, u0, u1, u2)
        {
            light = arriving;
        }
    }
    sampler.begin();
    let (u1, u2) = (sampler.next_f32(), sampler.next_f32());
    let scattered = sample_hg(interior.g, dir, u1, u2);
    let phase_pdf = if nee {
        hg_pdf(interior.g, dir.dot(scattered))
    } else {
        0.0
    };
    (light, scattered, phase_pdf)
}

/// Russian roulette after `segment` (from `opts.roulette_depth` on): whether the path goes on,
/// its throughput divided by the chance that it would. Random numbers: 1 when it plays.
#[inline(always)]
fn survives_roulette(
    opts: &RenderOptions,
    segment: u32,
    throughput: &mut Vec3,
    sampler: &mut Sampler,
) -> bool {
    if opts.roulette_depth > 0 && segment + 1 >= opts.roulette_depth {
        let survival = throughput.max_element().min(MAX_SURVIVAL);
        sampler.begin();
        if !(sampler.next_f32() < survival) {
            return false;
        }
        *throughput /= survival;
    }
    true
}

/// One light sample at `hit`, reached along `dir`: the light arriving times BSDF x cos and the
/// MIS weight over the light pdf; `None` if the BSDF is zero toward it (below the surface) or
/// the light is occluded.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn direct_light(
    scene: &FlatScene,
    material: &Material,
    hit: &Hit,
    dir: Vec3,
    medium: u32,
    u0: f32,
    u1: f32,
    u2: f32,
) -> Option<Vec3> {
    let index = lights::pick_light(scene, u0);
    let sample = lights::sample(&scene.lights[index], hit.point, u1, u2)?;
    let f = material.eval(-dir, sample.dir, hit);
    if f == Vec3::ZERO {
        return None;
    }
    // A punctual light's sample is a direction with probability: no MIS (BSDF sampling never
    // finds it).
    let weight = if scene.lights[index].shape.is_delta() {
        1.0 / sample.pdf
    } else {
        lights::light_sample_weight(sample.pdf, material.pdf(-dir, sample.dir, hit))
    };
    // The shadow ray leaves the offset origin aimed at the sampled point itself, so that a tiny
    // light is not missed by the width of the offset; through the surface (rough glass), into
    // the medium on the other side.
    let (side, medium) = if sample.dir.dot(hit.normal) >= 0.0 {
        (hit.normal, medium)
    } else if material.interior().is_some() {
        (-hit.normal, entered(hit))
    } else {
        (-hit.normal, medium)
    };
    let le = light_arriving(scene, leave(hit, side), &sample, index, medium)?;
    Some(f * (le * weight))
}

/// One light sample at a scattering event at `point` in `medium`, for a ray that travelled
/// along `dir`: the light arriving times the MIS weight and the phase function over the light
/// pdf (the phase function is its own pdf, so its weight is 1).
#[inline]
#[allow(clippy::too_many_arguments)]
fn medium_direct_light(
    scene: &FlatScene,
    point: Vec3,
    dir: Vec3,
    g: f32,
    medium: u32,
    u0: f32,
    u1: f32,
    u2: f32,
) -> Option<Vec3> {
    let index = lights::pick_light(scene, u0);
    let sample = lights::sample(&scene.lights[index], point, u1, u2)?;
    let phase_pdf = hg_pdf(g, dir.dot(sample.dir));
    let le = light_arriving(scene, point, &sample, index, medium)?;
    if scene.lights[index].shape.is_delta() {
        return Some(le * (phase_pdf / sample.pdf));
    }
    Some(le * lights::light_sample_factor(sample.pdf, phase_pdf))
}

/// The radiance light `index` sends to `from` along `sample` (toward its point; the
/// environment and the sun along its direction), where the shadow ray starts in `medium`: what
/// it emits there (a punctual light: what reaches `from`) times the transmittance of the media
/// on the way, stepping through invisible medium boundaries. `None` when anything else is hit
/// first.
#[inline(always)]
pub fn light_arriving(
    scene: &FlatScene,
    from: Vec3,
    sample: &lights::LightSample,
    index: usize,
    mut medium: u32,
) -> Option<Vec3> {
    let light = &scene.lights[index];
    let environment = match light.shape {
        LightShape::Environment(ref env) => Some(env),
        _ => None,
    };
    // A punctual light: what it sends to `from`, reached unless something lies before `reach`.
    let punctual = light
        .shape
        .is_delta()
        .then(|| lights::punctual_arriving(light, from));
    let at_infinity =
        environment.is_some() || matches!(light.shape, LightShape::Directional { .. });
    let (dir, mut reach) = if at_infinity {
        (sample.dir, f32::INFINITY)
    } else {
        let to_light = sample.point - from;
        if !(to_light.length_squared() > 0.0) {
            return None;
        }
        (to_light.normalize(), to_light.length())
    };
    let mut ray = Ray { origin: from, dir };
    // What the ray finds where nothing stops it first: the environment, or nothing.
    let escaped = || environment.map(|env| super::environment::radiance(env, dir));
    if medium == 0 && scene.medium_crossings == 0 {
        // No medium on the way (the loop below, without its cost).
        if at_infinity || punctual.is_some() {
            // A light no primitive is: anything on the way blocks it.
            if stopped_before(scene, &ray, reach) {
                return None;
            }
            return punctual.or_else(escaped);
        }
        let hit = intersect_light(scene, &ray, index as u32 + 1)?;
        return Some(scene.materials[hit.material as usize].emitted(&hit));
    }
    let mut transmitted = Vec3::ONE;
    for _ in 0..=scene.medium_crossings {
        let hit = intersect(scene, &ray);
        if let Some(le) = punctual
            && hit.is_none_or(|h| h.t >= reach)
        {
            if let Some(interior) = scene.medium(medium) {
                transmitted *= interior.transmittance(reach);
            }
            return Some(le * transmitted);
        }
        let Some(hit) = hit else {
            // (Media are closed: a ray that escapes has left every one.)
            return escaped().map(|le| le * transmitted);
        };
        if let Some(interior) = scene.medium(medium) {
            transmitted *= interior.transmittance(hit.t);
        }
        if punctual.is_none() && scene.light_of(hit.primitive) == index as u32 + 1 {
            let le = scene.materials[hit.material as usize].emitted(&hit);
            return Some(le * transmitted);
        }
        if !scene.materials[hit.material as usize].is_invisible() {
            return None;
        }
        medium = entered(&hit);
        ray = spawn(&hit, ray.dir);
        reach -= hit.t;
    }
    None
}
