//! rt-gpu: a physically based path tracer with a WGSL compute kernel (via wgpu) and a CPU
//! reference renderer computing the same estimator. See `docs/architecture.md`.

// `!(x > 0.0)` is deliberate throughout: unlike `x <= 0.0` it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod backend;
pub mod converge;
pub mod cpu;
pub mod film;
pub mod film_file;
pub mod gpu;
pub mod material;
pub mod options;
pub mod output;
#[cfg(feature = "plot")]
pub mod plot;
pub mod progressive;
pub mod render;
pub mod rng;
pub mod sampler;
pub mod scene;
