//! The GPU backend's host side: device setup (`context`), the buffer layout shared with WGSL
//! (`layout`) and the kernel's own state structs (`kernel_state`), kernel composition
//! (`shader`), dispatch sizing (`dispatch`), buffers, dispatches and readback (`renderer`,
//! `tile`), a render kept on the device (`live`) and the viewer's display pass (`display`). The
//! rendering math itself lives in `shaders/`.

pub mod backend;
pub mod bindings;
pub mod context;
pub mod dispatch;
pub mod display;
pub mod kernel_state;
pub mod layout;
pub mod live;
pub mod renderer;
pub mod shader;
pub mod shape_dispatch;
mod tile;

pub use backend::GpuBackend;
pub use context::{GpuContext, GpuError, list_adapters};
pub use dispatch::Tuning;
pub use live::LiveRender;
pub use renderer::{BsdfAnswer, BsdfQuery, EnvironmentLookup, GpuRenderer, Kernel, Timings};
pub use shader::Features;
