//! `rt-gpu devices`: the GPU adapters wgpu can see.

use anyhow::bail;
use rt_gpu::gpu::list_adapters;
use std::io::Write;

pub fn list_devices() -> anyhow::Result<()> {
    let adapters = list_adapters();
    if adapters.is_empty() {
        bail!("{}", rt_gpu::gpu::context::no_adapter_error());
    }
    for a in adapters {
        say!(
            "{:<40} {:?} {:?}, driver {} {}",
            a.name,
            a.backend,
            a.device_type,
            a.driver,
            a.driver_info
        )?;
    }
    Ok(())
}
