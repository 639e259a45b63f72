//! Headless wgpu for quadray: one place that finds an adapter, opens a device with the features
//! the techniques need, makes render targets, reads textures back, and times passes with
//! timestamp queries.
//!
//! Every technique takes a [`Gpu`] and never creates its own instance, so the same code runs on
//! Mesa's lavapipe in CI and on a real GPU.

mod readback;
mod target;
mod timer;

pub use readback::{read_buffer, read_texture_f32, read_texture_rgba8};
pub use target::{cleared_attachment, nearest_depth, texture_2d, texture_2d_with_data};
pub use timer::{GpuTimer, TimingSummary};

use thiserror::Error;

#[derive(Debug, Error)]
pub enum GpuError {
    #[error(
        "no GPU adapter found ({0}); on Debian install the software Vulkan driver with `scripts/setup.sh` (mesa-vulkan-drivers)"
    )]
    NoAdapter(String),
    #[error("the GPU adapter `{adapter}` refused a device: {reason}")]
    NoDevice { adapter: String, reason: String },
    #[error("GPU readback failed: {0}")]
    Readback(String),
    #[error("GPU validation failed: {0}")]
    Validation(String),
}

/// Keeps Mesa's Vulkan device-selection layer from probing Wayland and X11 when a program that
/// opens no window creates its Vulkan instance. Without a display that probe prints
/// `error: XDG_RUNTIME_DIR is invalid or not set in the environment.` twice, which reads like a
/// failure; the layer only puts the display's GPU first, which a headless program does not need
/// (the adapter is chosen by power preference or `WGPU_ADAPTER_NAME`). A `NODEVICE_SELECT` the
/// user set is left as it is, and errors of the driver itself still print.
///
/// # Safety
/// It sets an environment variable, so, as [`std::env::set_var`] requires, no other thread may
/// run yet: call it first thing in `main`.
pub unsafe fn skip_display_probing() {
    if std::env::var_os("NODEVICE_SELECT").is_none() {
        // SAFETY: the caller guarantees the program is still single-threaded.
        unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
    }
}

/// An adapter, its device and queue, and what they can do.
pub struct Gpu {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// Timestamp queries are optional in WebGPU; timing degrades to `None` without them.
    pub has_timestamps: bool,
}

impl Gpu {
    /// Opens the first high-performance adapter (any backend wgpu was built with; set
    /// `WGPU_BACKEND=vulkan` or `WGPU_ADAPTER_NAME=llvmpipe` to choose).
    pub fn new() -> Result<Self, GpuError> {
        Self::for_surface(&Self::instance(), None)
    }

    /// The instance every quadray program uses (backends from `WGPU_BACKEND`, else the primary
    /// ones).
    pub fn instance() -> wgpu::Instance {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY);
        wgpu::Instance::new(desc)
    }

    /// Opens an adapter that can present to `surface` (a window), or any adapter without one.
    pub fn for_surface(
        instance: &wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self, GpuError> {
        let adapter = pollster::block_on(wgpu::util::initialize_adapter_from_env_or_default(
            instance, surface,
        ))
        .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        Self::from_adapter(adapter)
    }

    /// Opens a device on a given adapter, with timestamp queries when the adapter has them and the
    /// adapter's own limits (ray casting wants large textures and several float render targets).
    pub fn from_adapter(adapter: wgpu::Adapter) -> Result<Self, GpuError> {
        let wanted = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::FLOAT32_FILTERABLE;
        let features = adapter.features() & wanted;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("quadray"),
            required_features: features,
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::NoDevice {
            adapter: adapter.get_info().name,
            reason: e.to_string(),
        })?;
        let has_timestamps = features.contains(wgpu::Features::TIMESTAMP_QUERY);
        tracing::info!(adapter = %adapter.get_info().name, backend = ?adapter.get_info().backend, has_timestamps, "GPU opened");
        Ok(Self {
            adapter,
            device,
            queue,
            has_timestamps,
        })
    }

    /// "NVIDIA H100 (Vulkan, driver 550.x)" — what benchmarks print beside their figures.
    pub fn describe(&self) -> String {
        let info = self.adapter.get_info();
        format!(
            "{} ({:?}, {} {})",
            info.name, info.backend, info.driver, info.driver_info
        )
    }

    /// True on a software rasterizer, where only ratios between methods mean anything.
    pub fn is_software(&self) -> bool {
        self.adapter.get_info().device_type == wgpu::DeviceType::Cpu
    }

    /// Blocks until all submitted work is done.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Readback(e.to_string()))
    }

    /// Runs `f` and turns any wgpu validation error it raised into a `GpuError` instead of a
    /// panic from the default uncaptured-error handler.
    pub fn checked<T>(&self, f: impl FnOnce() -> T) -> Result<T, GpuError> {
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let out = f();
        match pollster::block_on(scope.pop()) {
            Some(err) => Err(GpuError::Validation(err.to_string())),
            None => Ok(out),
        }
    }
}
