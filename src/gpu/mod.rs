//! The GPU backend's host side: device setup (`context`), the buffer layout shared with WGSL
//! (`layout`), kernel composition (`shader`), and dispatch (`renderer`). The rendering math
//! itself lives in `shaders/`.

pub mod context;
pub mod layout;
pub mod renderer;
pub mod shader;

pub use context::{GpuContext, GpuError, list_adapters};
pub use renderer::{GpuRenderer, Kernel, Timings, Tuning};
pub use shader::Features;
