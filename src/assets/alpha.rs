//! Cut-outs and see-through surfaces: glTF's `alphaMode` (MASK with its `alphaCutoff`, BLEND)
//! on a material, its alpha the base colour's alpha factor times its texture's alpha channel.
//! Plain data; where a ray meets such a surface, the closest-hit search asks it whether the ray
//! passes (`cpu::intersect::passes_through`, twin `shaders/alpha.wgsl`), for camera, bounce and
//! shadow rays alike: a masked texel is a hole, a blended one stops a ray with probability
//! alpha (stochastic opacity, as pbrt-v4 and Cycles render BLEND in a path tracer), decided by a
//! hash of the ray and the primitive ([`crate::shared::rng::alpha_number`]) so that every test of
//! one ray against one surface agrees.

use crate::assets::image::Image;
use std::sync::Arc;

/// How alpha decides whether a ray passes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// Passes where alpha < the cutoff (glTF's MASK; its default cutoff is 0.5).
    Mask { cutoff: f32 },
    /// Passes with probability 1 - alpha (glTF's BLEND).
    Blend,
}

/// A see-through material's alpha: `factor` x the red channel of `image` (the texture's alpha
/// channel, decoded linear into every channel; none: 1), read through the surface's UVs with the
/// image's own lookup.
#[derive(Clone, Debug, PartialEq)]
pub struct Alpha {
    pub mode: AlphaMode,
    pub factor: f32,
    pub image: Option<Arc<Image>>,
}

/// `GpuMaterial::alpha_mode` of opaque materials and of each [`AlphaMode`].
pub const ALPHA_OPAQUE: u32 = 0;
pub const ALPHA_MASK: u32 = 1;
pub const ALPHA_BLEND: u32 = 2;

impl Alpha {
    /// Its mode's GPU code and cutoff (0 for BLEND).
    pub fn gpu_mode(&self) -> (u32, f32) {
        match self.mode {
            AlphaMode::Mask { cutoff } => (ALPHA_MASK, cutoff),
            AlphaMode::Blend => (ALPHA_BLEND, 0.0),
        }
    }

    /// Whether a ray passes where alpha is `alpha`, `u` being its number in [0, 1).
    #[inline]
    pub fn passes(&self, alpha: f32, u: f32) -> bool {
        match self.mode {
            AlphaMode::Mask { cutoff } => alpha < cutoff,
            AlphaMode::Blend => u >= alpha,
        }
    }

    pub fn validate(&self) -> Result<(), String> {
        if !(0.0..=1.0).contains(&self.factor) {
            return Err(format!("alpha must be in [0, 1], got {}", self.factor));
        }
        if let AlphaMode::Mask { cutoff } = self.mode
            && !(cutoff.is_finite() && cutoff >= 0.0)
        {
            return Err(format!(
                "alpha cutoff must be finite and >= 0, got {cutoff}"
            ));
        }
        Ok(())
    }
}
