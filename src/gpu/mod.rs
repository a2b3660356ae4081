//! The GPU backend's host side: device setup (`context`), the buffer layout shared with WGSL
//! (`layout`), kernel composition (`shader`), dispatch sizing (`dispatch`), and buffers,
//! dispatches and readback (`renderer`). The rendering math
//! itself lives in `shaders/`.

pub mod backend;
pub mod bindings;
pub mod context;
pub mod dispatch;
pub mod layout;
pub mod renderer;
pub mod shader;

pub use backend::GpuBackend;
pub use context::{GpuContext, GpuError, list_adapters};
pub use dispatch::Tuning;
pub use renderer::{BsdfAnswer, BsdfQuery, EnvironmentLookup, GpuRenderer, Kernel, Timings};
pub use shader::Features;
