//! Mirror reflection perturbed by `fuzz` (twin: `shaders/materials/metal.wgsl`), as the original
//! project's metal; rays fuzzed below the surface are absorbed. Random numbers per scatter: 2.

use super::{MaterialModel, reflect};
use crate::cpu::sampling::unit_vector;
use crate::cpu::shapes::Hit;
use crate::gpu::layout::GpuMaterial;
use crate::sampler::Sampler;
use crate::scene::file::checked;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// `{ type = "metal", albedo = [r, g, b], fuzz = 0.1 }`; `fuzz` in [0, 1], default 0.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Metal {
    #[serde(with = "checked::albedo")]
    pub albedo: Vec3,
    #[serde(default, with = "checked::number")]
    pub fuzz: f32,
}

impl MaterialModel for Metal {
    const FEATURE: &'static str = "METAL";

    fn validate(&self) -> Result<(), String> {
        if !(0.0..=1.0).contains(&self.fuzz) {
            return Err(format!("fuzz must be in [0, 1], got {}", self.fuzz));
        }
        Ok(())
    }

    fn scatter(&self, dir_in: Vec3, hit: &Hit, sampler: &mut Sampler) -> Option<(Vec3, Vec3)> {
        let fuzzed =
            reflect(dir_in, hit.normal) + self.fuzz * unit_vector(sampler.next_f32(), sampler.next_f32());
        let len2 = fuzzed.length_squared();
        if !(len2 > 1e-12) {
            return None;
        }
        let dir = fuzzed / len2.sqrt();
        // Fuzzed below the surface: absorbed.
        (dir.dot(hit.normal) > 0.0).then_some((self.albedo, dir))
    }

    /// albedo; param: fuzz.
    fn gpu(&self) -> GpuMaterial {
        GpuMaterial {
            albedo: self.albedo.to_array(),
            param: self.fuzz,
            ..Default::default()
        }
    }
}
