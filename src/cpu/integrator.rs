//! The path tracer (twin: `shaders/integrator.wgsl`): the original project's recursive
//! `ray_color`, made iterative. Segment k (1-based) adds the emission it hits, or the background
//! it escapes to, for k <= max_depth.

use super::material::{background, emitted, scatter};
use super::shapes::{Ray, intersect, spawn};
use crate::rng::Rng;
use crate::scene::flat::FlatScene;
use glam::Vec3;

pub fn radiance(scene: &FlatScene, mut ray: Ray, max_depth: u32, rng: &mut Rng) -> Vec3 {
    let mut total = Vec3::ZERO;
    let mut throughput = Vec3::ONE;
    for _segment in 0..max_depth {
        let Some(hit) = intersect(scene, &ray) else {
            total += throughput * background(&scene.background, ray.dir);
            break;
        };
        let material = &scene.materials[hit.material as usize];
        total += throughput * emitted(material, &hit);
        let Some((attenuation, dir)) = scatter(material, ray.dir, &hit, rng) else {
            break;
        };
        throughput *= attenuation;
        ray = spawn(&hit, dir);
    }
    total
}
