//! Finding an adapter and opening a device, headless.

use std::sync::{Arc, Mutex};

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no GPU adapter found: install a Vulkan driver (on Debian/Ubuntu `apt-get install mesa-vulkan-drivers libvulkan1` gives lavapipe, a software GPU) or use --backend cpu"
    )]
    NoAdapter,
    #[error(
        "no GPU adapter for WGPU_BACKEND={wanted}, though wgpu sees {available} on other backends: unset WGPU_BACKEND or name one of those backends (or use --backend cpu)"
    )]
    NoAdapterForBackend { wanted: String, available: String },
    #[error("no GPU adapter matches '{wanted}' (available: {available}); see `rt-gpu devices`")]
    NoSuchAdapter { wanted: String, available: String },
    #[error("cannot open the GPU device {adapter}: {message}")]
    Device { adapter: String, message: String },
    #[error("shader error: {0}")]
    Shader(String),
    #[error("GPU error: {0}")]
    Runtime(String),
    #[error("the GPU device was lost: {0}")]
    Lost(String),
    #[error("{0}")]
    TooLarge(String),
}

/// A device and queue, with what the renderer needs to know about them (cloned, the same
/// device).
#[derive(Clone)]
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    pub timestamps: bool,
    /// Set by wgpu's error and device-lost callbacks; checked after every submission.
    pub failure: Arc<Mutex<Option<GpuError>>>,
}

/// The instance adapters are found through (`WGPU_BACKEND` may narrow it).
pub fn instance() -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    if wgpu::Backends::from_env().is_none() {
        desc.backends = wgpu::Backends::PRIMARY;
    }
    wgpu::Instance::new(desc)
}

/// Why no adapter was found: none at all, or none on the backends `WGPU_BACKEND` allows.
pub fn no_adapter_error() -> GpuError {
    let Some(wanted) = std::env::var_os("WGPU_BACKEND") else {
        return GpuError::NoAdapter;
    };
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::all();
    let everywhere =
        pollster::block_on(wgpu::Instance::new(desc).enumerate_adapters(wgpu::Backends::all()));
    if everywhere.is_empty() {
        return GpuError::NoAdapter;
    }
    let available: Vec<String> = everywhere
        .iter()
        .map(|a| {
            let info = a.get_info();
            format!("{} ({:?})", info.name, info.backend).to_lowercase()
        })
        .collect();
    GpuError::NoAdapterForBackend {
        wanted: wanted.to_string_lossy().into_owned(),
        available: available.join(", "),
    }
}

/// Every adapter wgpu can see.
pub fn list_adapters() -> Vec<wgpu::AdapterInfo> {
    let instance = instance();
    pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()))
        .iter()
        .map(|a| a.get_info())
        .collect()
}

/// The adapter whose name contains `wanted` (case-insensitive), or the best available: a
/// hardware GPU if there is one, else a software one such as lavapipe.
pub fn choose_adapter(
    instance: &wgpu::Instance,
    wanted: Option<&str>,
) -> Result<wgpu::Adapter, GpuError> {
    match wanted {
        Some(name) => {
            let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
            let needle = name.to_lowercase();
            let available: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
            adapters
                .into_iter()
                .find(|a| a.get_info().name.to_lowercase().contains(&needle))
                .ok_or_else(|| GpuError::NoSuchAdapter {
                    wanted: name.to_string(),
                    available: if available.is_empty() {
                        "none".into()
                    } else {
                        available.join(", ")
                    },
                })
        }
        None => {
            let request = |fallback| {
                pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
                    power_preference: wgpu::PowerPreference::HighPerformance,
                    force_fallback_adapter: fallback,
                    ..Default::default()
                }))
            };
            request(false)
                .or_else(|_| request(true))
                .map_err(|_| no_adapter_error())
        }
    }
}

/// What [`GpuContext::new`] with `wanted` would open, without opening it: the adapter and the
/// limits its device is opened with.
pub fn adapter_limits(wanted: Option<&str>) -> Result<(wgpu::AdapterInfo, wgpu::Limits), GpuError> {
    choose_adapter(&instance(), wanted).map(|a| (a.get_info(), a.limits()))
}

impl GpuContext {
    /// Opens the adapter whose name contains `wanted` (case-insensitive), or the best available:
    /// a hardware GPU if there is one, else a software one such as lavapipe.
    pub fn new(wanted: Option<&str>) -> Result<Self, GpuError> {
        Self::open(&choose_adapter(&instance(), wanted)?)
    }

    /// Opens `adapter`'s device (the viewer's, chosen to show its window).
    pub fn open(adapter: &wgpu::Adapter) -> Result<Self, GpuError> {
        let info = adapter.get_info();
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("rt-gpu"),
            required_features: if timestamps {
                wgpu::Features::TIMESTAMP_QUERY
            } else {
                wgpu::Features::empty()
            },
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device {
            adapter: info.name.clone(),
            message: e.to_string(),
        })?;

        let failure: Arc<Mutex<Option<GpuError>>> = Arc::default();
        let on_error = failure.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            let mut slot = on_error.lock().unwrap_or_else(|p| p.into_inner());
            slot.get_or_insert(GpuError::Runtime(e.to_string().replace('\n', " ")));
        }));
        let on_lost = failure.clone();
        device.set_device_lost_callback(move |reason, message| {
            let mut slot = on_lost.lock().unwrap_or_else(|p| p.into_inner());
            slot.get_or_insert(GpuError::Lost(format!("{reason:?}: {message}")));
        });
        Ok(GpuContext {
            device,
            queue,
            info,
            limits,
            timestamps,
            failure,
        })
    }

    /// The first error wgpu reported since the last check, if any.
    pub fn take_failure(&self) -> Option<GpuError> {
        self.failure
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .take()
    }

    /// Waits for all submitted work, surfacing errors instead of hanging or panicking.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: Some(std::time::Duration::from_secs(60)),
            })
            .map_err(|e| GpuError::Runtime(format!("waiting for the GPU: {e}")))?;
        match self.take_failure() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// The first `size` bytes of `staging` (a MAP_READ buffer whose copies have been submitted)
    /// once the GPU has written them; `what` names them in errors.
    pub fn read_staging(
        &self,
        staging: &wgpu::Buffer,
        size: u64,
        what: &str,
    ) -> Result<Vec<u8>, GpuError> {
        self.with_mapped(staging, size, what, <[u8]>::to_vec)
    }

    /// Maps the first `size` bytes of `staging` (a MAP_READ buffer whose copy has been
    /// submitted) once the GPU is done, hands them to `f` where they lie, and unmaps them: a
    /// reader that only converts them need not copy them out first.
    pub fn with_mapped<R>(
        &self,
        staging: &wgpu::Buffer,
        size: u64,
        what: &str,
        f: impl FnOnce(&[u8]) -> R,
    ) -> Result<R, GpuError> {
        let slice = staging.slice(..size);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        let cannot_read =
            |e: &dyn std::fmt::Display| GpuError::Runtime(format!("cannot read {what}: {e}"));
        // Whether the buffer is mapped, or its mapping still pending, when reading ends: then it
        // is unmapped (a staging buffer kept for later reads must not stay so); a mapping that
        // failed left it unmapped, and unmapping it again would be an error of its own.
        let mut to_unmap = true;
        let read = || {
            self.wait()?;
            let mapped = rx
                .recv()
                .map_err(|_| GpuError::Runtime("buffer mapping was dropped".into()))?;
            if let Err(e) = mapped {
                to_unmap = false;
                return Err(cannot_read(&e));
            }
            let range = slice.get_mapped_range().map_err(|e| cannot_read(&e))?;
            Ok(f(&range))
        };
        let out = read();
        if to_unmap {
            staging.unmap();
        }
        out
    }
}
