//! The feature buffers a denoiser reads beside the image (twin: `shaders/aov.wgsl`), as the
//! `albedo` and `normal` integrators: Mitsuba 3's `aov` integrator, Cycles' denoising passes.
//! Open Image Denoise asks for the albedo and shading normal of the first surface that is not a
//! perfect mirror or smooth glass, followed through those (its documentation), so a path here
//! goes on through delta lobes, weighted by them, and ends at the first other event:
//!
//! - a surface that scatters: its directional albedo, estimated by one BSDF sample's weight
//!   (BSDF x cos / pdf, whose mean is exactly the albedo, for every material and texture without
//!   code of its own), or its shading normal facing the ray;
//! - a surface that only emits (a light): its colour, the emission over its largest channel;
//! - the background: its colour likewise; a scattering event in a medium: the medium's albedo;
//!   the normal of both is 0.
//!
//! A normal is stored as (n + 1) / 2, in [0, 1]: the film keeps non-negative samples, and the
//! mean of the stored values maps back exactly (`denoise::normal_from_film`).

use super::background::background;
use super::integrator::{Event, entered, next_event};
use crate::options::{Integrator, RenderOptions};
use crate::scene::flat::FlatScene;
use crate::shared::ray::{Ray, spawn};
use crate::shared::sampler::Sampler;
use glam::Vec3;

/// One sample of the feature buffer `opts.integrator` (albedo or normal) along camera ray `ray`.
/// Random numbers: a BSDF sample per surface, and a free path per stretch in a medium (as the
/// path tracer draws them).
pub fn feature(
    scene: &FlatScene,
    mut ray: Ray,
    opts: &RenderOptions,
    sampler: &mut Sampler,
) -> Vec3 {
    let normal = opts.integrator == Integrator::Normal;
    let mut throughput = Vec3::ONE;
    let mut medium = 0;
    for segment in 0..opts.max_depth {
        let hit = match next_event(scene, &mut ray, &mut medium, &mut throughput, sampler) {
            Event::Escaped => {
                return if normal {
                    NO_NORMAL
                } else {
                    throughput * colour(background(&scene.background, ray.dir))
                };
            }
            Event::Lost => break,
            Event::InMedium(_) => {
                return match scene.medium(medium) {
                    Some(_) if normal => NO_NORMAL,
                    Some(interior) => throughput * interior.albedo,
                    None => break,
                };
            }
            Event::Surface(hit) => hit,
        };
        let material = &scene.materials[hit.material as usize];
        sampler.begin();
        let bounce = material.sample(-ray.dir, &hit, sampler);
        if let Some(b) = &bounce
            && b.lobe.is_delta()
            && segment + 1 < opts.max_depth
        {
            throughput *= b.weight;
            if material.interior().is_some() && b.wi.dot(hit.normal) < 0.0 {
                medium = entered(&hit);
            }
            ray = spawn(&hit, b.wi);
            continue;
        }
        if normal {
            return encode_normal(hit.shading);
        }
        return throughput
            * match bounce {
                Some(b) => b.weight,
                None => colour(material.emitted(&hit)),
            };
    }
    if normal { NO_NORMAL } else { Vec3::ZERO }
}

/// The stored value of "no normal" (a zero normal, encoded).
pub const NO_NORMAL: Vec3 = Vec3::splat(0.5);

/// A unit normal as stored: (n + 1) / 2, clamped to [0, 1] (a shading normal's rounding could
/// leave it a hair outside, which the film would count as an invalid sample).
#[inline]
pub fn encode_normal(n: Vec3) -> Vec3 {
    (0.5 * n + Vec3::splat(0.5)).clamp(Vec3::ZERO, Vec3::ONE)
}

/// A radiance's colour: over its largest channel (black stays black).
#[inline]
fn colour(radiance: Vec3) -> Vec3 {
    let largest = radiance.max_element();
    if largest > 0.0 {
        radiance / largest
    } else {
        Vec3::ZERO
    }
}
