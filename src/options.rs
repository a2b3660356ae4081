//! What a render is asked to do: plain data that every backend reads and none defines (this
//! module imports nothing of the crate's).

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel in this render.
    pub spp: u32,
    /// Index of the first sample: a render continuing an earlier one of `n` samples starts at `n`.
    pub first_sample: u32,
    pub seed: u32,
    /// The number of path segments.
    pub max_depth: u32,
    pub integrator: Integrator,
    pub sampler: SamplerKind,
    /// Russian roulette from this many segments on (0: off). Unbiased: a path survives with the
    /// probability of its largest throughput component (at most 0.95) and is reweighted.
    pub roulette_depth: u32,
}

/// Where Russian roulette starts when the user does not say: from the fifth segment, as in
/// Mitsuba 3 and pbrt-v4. Paths that can carry little end early, and the time they would have
/// taken goes to new samples, which lowers the error for the time (docs/convergence.md). Media
/// need it most (`cornell-sss`'s jade sphere is 9 free paths across). The statistical tests set
/// their own depth (`RenderOptions::new`: off).
pub const DEFAULT_ROULETTE_DEPTH: u32 = 5;

impl RenderOptions {
    /// `width` x `height` at `spp` samples, seed 0, the default integrator, independent
    /// samples (whose per-sample variance the statistical tests rely on), no roulette.
    pub fn new(width: u32, height: u32, spp: u32, max_depth: u32) -> Self {
        RenderOptions {
            width,
            height,
            spp,
            first_sample: 0,
            seed: 0,
            max_depth,
            integrator: Integrator::default(),
            sampler: SamplerKind::Independent,
            roulette_depth: 0,
        }
    }
}

/// How a path finds light.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Integrator {
    /// Paths find light only by hitting it (the original project's estimator).
    Naive,
    /// Next-event estimation: each diffuse hit and each scattering event in a medium also
    /// samples a light with a shadow ray, combined with BSDF (or phase function) sampling by
    /// multiple importance sampling (power heuristic).
    #[default]
    Nee,
    /// A feature buffer for a denoiser (Mitsuba 3's `aov`, Cycles' denoising albedo): each
    /// sample the reflectance at the first hit that is not a mirror or smooth glass (followed
    /// through those), a light's or the background's colour where the path ends on one. No
    /// light is transported.
    Albedo,
    /// A feature buffer for a denoiser: each sample the shading normal at the first hit that is
    /// not a mirror or smooth glass, facing the ray, mapped from [-1, 1] to [0, 1] (so the film,
    /// which keeps non-negative samples, holds it, and its image is the usual normal picture);
    /// 0.5 where the path escapes.
    Normal,
}

impl Integrator {
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Naive => "naive",
            Integrator::Nee => "nee",
            Integrator::Albedo => "albedo",
            Integrator::Normal => "normal",
        }
    }

    /// Whether this is a feature buffer (albedo, normal) rather than light transport.
    pub fn is_feature(self) -> bool {
        matches!(self, Integrator::Albedo | Integrator::Normal)
    }
}

/// Where a sample's random numbers come from (see `crate::shared::sampler`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SamplerKind {
    /// Independent uniform numbers: plain Monte Carlo, error falling as 1/sqrt(spp).
    Independent,
    /// Owen-scrambled Sobol points (Burley 2020): stratified in every 2D projection a path
    /// uses, so edges and soft shadows converge faster.
    #[default]
    Sobol,
}

impl SamplerKind {
    pub fn name(self) -> &'static str {
        match self {
            SamplerKind::Independent => "independent",
            SamplerKind::Sobol => "sobol",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// The WGSL compute kernel through wgpu (any Vulkan, Metal or DX12 device, or Mesa lavapipe).
    Gpu,
    /// The CPU reference renderer (rayon over all cores).
    Cpu,
}

impl Backend {
    pub fn name(self) -> &'static str {
        match self {
            Backend::Gpu => "gpu",
            Backend::Cpu => "cpu",
        }
    }
}
