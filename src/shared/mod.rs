//! What both backends share, and the contract between them: rays and hits (`ray`, `primitive`),
//! warps from random numbers to directions (`warp`) and back to angles (`angles`), the sampler
//! and its random streams (`sampler`, `rng`), the film's exact sums (`exact_sum`), the
//! estimator's constants (`constants`), the kernel's material features (`feature`), and the
//! `#[repr(C)]` structs the kernel reads, with their generated WGSL (`layout`). It imports nothing of the crate but `options` (plain data): the
//! CPU reference, the kernel's host side and the materials all build on it.

pub mod angles;
pub mod constants;
pub mod exact_sum;
pub mod feature;
pub mod layout;
pub mod params;
pub mod primitive;
pub mod ray;
pub mod rng;
pub mod sampler;
pub mod warp;
