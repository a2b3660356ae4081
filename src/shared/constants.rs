//! Numbers of the estimator that both backends use (the kernel gets them as WGSL constants,
//! generated in `gpu::layout`).

/// Roulette keeps a path with the probability of its largest throughput component, capped here
/// so bright paths still end eventually.
pub const MAX_SURVIVAL: f32 = 0.95;

/// Quad points seen this close to edge-on are not light-sampled (their solid-angle pdf would
/// overflow); BSDF sampling alone covers them, with full weight.
pub const MIN_LIGHT_COSINE: f32 = 1e-7;

/// Below this |n . d| a ray runs parallel to a plane (a quad's, a disk's) and misses it: it has
/// no single crossing point.
pub const PARALLEL_DENOMINATOR: f32 = 1e-8;

/// The largest f32 below 1 (1 - 2^-24): what keeps a coordinate of [0, 1] below 1.
pub const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// The sky background's colour straight up (white at the horizon).
pub const SKY_ZENITH: [f32; 3] = [0.5, 0.7, 1.0];
