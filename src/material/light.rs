//! A diffuse area light (twin: `shaders/materials/light.wgsl`). It emits from its front face
//! (along the shape's normal) unless `two_sided`, and reflects nothing. Random numbers: 0.

use super::MaterialModel;
use crate::cpu::shapes::Hit;
use crate::gpu::layout::GpuMaterial;
use crate::sampler::Sampler;
use crate::scene::file::checked;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// `{ type = "light", radiance = [r, g, b], two_sided = false }`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Light {
    #[serde(with = "checked::colour")]
    pub radiance: Vec3,
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub two_sided: bool,
}

impl MaterialModel for Light {
    const FEATURE: &'static str = "LIGHT";
    const EMITS_UNDER: Option<&'static str> = Some("LIGHT");

    fn emitted(&self, hit: &Hit) -> Vec3 {
        if hit.front_face || self.two_sided {
            self.radiance
        } else {
            Vec3::ZERO
        }
    }

    fn area_light(&self) -> Option<(Vec3, bool)> {
        (self.radiance != Vec3::ZERO).then_some((self.radiance, self.two_sided))
    }

    fn scatter(&self, _dir_in: Vec3, _hit: &Hit, _sampler: &mut Sampler) -> Option<(Vec3, Vec3)> {
        None
    }

    /// emission: radiance; param: 1 if two-sided.
    fn gpu(&self) -> GpuMaterial {
        GpuMaterial {
            emission: self.radiance.to_array(),
            param: if self.two_sided { 1.0 } else { 0.0 },
            ..Default::default()
        }
    }
}
