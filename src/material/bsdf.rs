//! What sampling a BSDF gives, the same on both backends (the WGSL struct `BsdfSample` is
//! generated from [`BsdfSample`]; `LOBE_*` from [`Lobe`]'s bits). Directions point away from
//! the surface: `wo` toward where the path came from, `wi` toward where it goes (pbrt-v4's and
//! Mitsuba 3's convention).

use crate::shared::layout::{WgslLocalType, kernel_struct};
use glam::Vec3;

/// Which lobe a sampled direction came from, as bits (pbrt-v4's `BxDFFlags`): reflection or
/// transmission, and diffuse, glossy or delta. A delta lobe has no density an integrator could
/// evaluate: light sampling never picks its directions, and `eval` and `pdf` are 0 there.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Lobe(pub u32);

impl Lobe {
    pub const REFLECTION: u32 = 1;
    pub const TRANSMISSION: u32 = 2;
    pub const DIFFUSE: u32 = 4;
    pub const GLOSSY: u32 = 8;
    pub const DELTA: u32 = 16;

    pub const DIFFUSE_REFLECTION: Lobe = Lobe(Self::REFLECTION | Self::DIFFUSE);
    pub const GLOSSY_REFLECTION: Lobe = Lobe(Self::REFLECTION | Self::GLOSSY);
    pub const DELTA_REFLECTION: Lobe = Lobe(Self::REFLECTION | Self::DELTA);
    pub const GLOSSY_TRANSMISSION: Lobe = Lobe(Self::TRANSMISSION | Self::GLOSSY);
    pub const DELTA_TRANSMISSION: Lobe = Lobe(Self::TRANSMISSION | Self::DELTA);

    pub fn is_delta(self) -> bool {
        self.0 & Self::DELTA != 0
    }
    pub fn is_transmission(self) -> bool {
        self.0 & Self::TRANSMISSION != 0
    }

    /// The WGSL constants `LOBE_<NAME>`.
    pub fn wgsl_constants() -> [(&'static str, u32); 5] {
        [
            ("LOBE_REFLECTION", Self::REFLECTION),
            ("LOBE_TRANSMISSION", Self::TRANSMISSION),
            ("LOBE_DIFFUSE", Self::DIFFUSE),
            ("LOBE_GLOSSY", Self::GLOSSY),
            ("LOBE_DELTA", Self::DELTA),
        ]
    }
}

impl WgslLocalType for Lobe {
    const WGSL: &'static str = "u32";
}

kernel_struct! {
    /// A sampled direction. In WGSL a `lobe` of 0 says the path ends here (the CPU returns
    /// `None`).
    pub struct BsdfSample as "BsdfSample" {
        /// BSDF x |cos(wi)| / pdf: the factor the path's throughput takes.
        weight: Vec3,
        /// Unit length, away from the surface.
        wi: Vec3,
        /// Solid-angle density of `wi`; for a delta lobe, not a density (0).
        pdf: f32,
        lobe: Lobe,
    }
}
