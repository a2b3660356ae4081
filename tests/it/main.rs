//! rt-gpu's integration tests, one binary (as pbrt-v4's `pbrt_test`): one module per concern
//! (docs/testing.md lists each, what it checks, its negative control, whether it needs a GPU),
//! `common` their scenes, statistics and helpers. `cargo test --test it MODULE::` runs one
//! module, `cargo test --test it NAME` the tests whose path contains NAME.

mod common;

mod blender_scenes;
mod bsdfs;
mod cli;
mod converge;
mod denoise;
mod determinism;
mod display;
mod environment;
mod furnace;
mod fuzz_mesh_files;
mod fuzz_scene_files;
mod geometry;
mod gltf_scenes;
mod gltf_textures;
mod gpu_equivalence;
mod gpu_layout;
mod hostile_files;
mod instances;
mod long_renders;
mod materials;
mod media;
mod meshes;
mod nee;
mod punctual;
mod radiance_scale;
mod reliability;
mod sampler;
mod scene_files;
mod slurm;
mod stability;
mod textures;
mod traversal;
mod viewer;
