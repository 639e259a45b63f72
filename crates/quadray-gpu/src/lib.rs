//! Headless wgpu for quadray: one place that finds an adapter, opens a device with the features
//! the techniques need, makes render targets, reads textures back, and times passes with
//! timestamp queries.
//!
//! Every technique takes a [`Gpu`] and never creates its own instance, so the same code runs on
//! Mesa's lavapipe in CI and on a real GPU.

mod readback;
mod target;
mod timer;
pub mod validation;

pub use readback::{read_buffer, read_texture_f32, read_texture_rgba8};
pub use target::{cleared_attachment, nearest_depth, texture_2d, texture_2d_with_data};
pub use timer::{GpuTimer, ResolveEncoder, TimingSummary};

use std::sync::{Arc, Mutex};
use std::time::Duration;
use thiserror::Error;

/// The environment variable that sets the bound on every wait for the GPU, in seconds.
pub const WAIT_BOUND_ENV: &str = "QUADRAY_GPU_WAIT_S";

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
    #[error(
        "the GPU `{adapter}` did not finish {work} within {bound_s} s (waited for: {waited_for}); a \
         pass that never ends or a fault in it: run `scripts/gpu-tables.sh --smoke-only` to find \
         the pass, or raise the bound with {env}=SECONDS",
        env = WAIT_BOUND_ENV
    )]
    Timeout {
        adapter: String,
        work: String,
        waited_for: String,
        bound_s: u64,
    },
    #[error("the GPU `{adapter}` was lost during {work}: {reason}")]
    DeviceLost {
        adapter: String,
        work: String,
        reason: String,
    },
    #[error("GPU validation failed: {0}")]
    Validation(String),
    #[error("{0}")]
    Setting(String),
    #[error("{device} allows {limit} = {have}, but {needed_by} needs {needed}")]
    Limit {
        device: String,
        limit: &'static str,
        have: u64,
        needed: u64,
        needed_by: String,
    },
}

/// An adapter limit that a technique's passes rely on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limit {
    /// The side of a 2-D texture.
    TextureDimension2d,
    /// The bytes of one storage-buffer binding.
    StorageBufferBindingSize,
    /// Storage buffers one shader stage binds.
    StorageBuffersPerShaderStage,
    /// Bytes of workgroup memory one compute workgroup declares.
    ComputeWorkgroupStorageSize,
}

impl Limit {
    /// wgpu's name of the limit.
    pub fn name(self) -> &'static str {
        match self {
            Limit::TextureDimension2d => "max_texture_dimension_2d",
            Limit::StorageBufferBindingSize => "max_storage_buffer_binding_size",
            Limit::StorageBuffersPerShaderStage => "max_storage_buffers_per_shader_stage",
            Limit::ComputeWorkgroupStorageSize => "max_compute_workgroup_storage_size",
        }
    }

    /// Its value in `limits`.
    pub fn of(self, limits: &wgpu::Limits) -> u64 {
        match self {
            Limit::TextureDimension2d => limits.max_texture_dimension_2d.into(),
            Limit::StorageBufferBindingSize => limits.max_storage_buffer_binding_size,
            Limit::StorageBuffersPerShaderStage => {
                limits.max_storage_buffers_per_shader_stage.into()
            }
            Limit::ComputeWorkgroupStorageSize => limits.max_compute_workgroup_storage_size.into(),
        }
    }
}

/// What a setting or a pass needs of one [`Limit`].
#[derive(Clone, Debug)]
pub struct LimitNeed {
    pub limit: Limit,
    pub needed: u64,
    /// The setting or pass that needs it, as the user would recognise it (`--size 9000x9000`).
    pub needed_by: String,
}

/// Checks `needs` against a device's `limits` before anything is created, so that a device
/// below them fails with the limit and the setting named, not with a validation error deep in a
/// pass. `device` names it in the error.
pub fn check_limits(
    limits: &wgpu::Limits,
    device: &str,
    needs: &[LimitNeed],
) -> Result<(), GpuError> {
    match needs.iter().find(|n| n.needed > n.limit.of(limits)) {
        Some(need) => Err(GpuError::Limit {
            device: device.into(),
            limit: need.limit.name(),
            have: need.limit.of(limits),
            needed: need.needed,
            needed_by: need.needed_by.clone(),
        }),
        None => Ok(()),
    }
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
    /// How long a wait for the GPU may take before it is an error ([`Gpu::wait`]).
    wait_bound: Duration,
    /// What was submitted last, for the error of a wait that ran out or a lost device.
    last_work: Mutex<String>,
    /// Why the device was lost, once it was.
    lost: Arc<Mutex<Option<String>>>,
    /// Set when a wait ran out: the device may still be running that work, so it is not
    /// destroyed (see `Drop`).
    stalled: std::sync::atomic::AtomicBool,
}

impl Gpu {
    /// Opens the first high-performance adapter (any backend wgpu was built with; set
    /// `WGPU_BACKEND=vulkan` or `WGPU_ADAPTER_NAME=llvmpipe` to choose).
    pub fn new() -> Result<Self, GpuError> {
        Self::for_surface(&Self::instance(), None)
    }

    /// The instance every quadray program uses (backends from `WGPU_BACKEND`, else the primary
    /// ones; wgpu's own validation with `WGPU_VALIDATION=1`).
    pub fn instance() -> wgpu::Instance {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
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
        let limits = adapter.limits();
        Self::with_limits(adapter, limits)
    }

    /// As [`Gpu::from_adapter`], with the device held to `limits` (at most the adapter's): a
    /// program that must run where WebGPU's defaults are all there is, checked on a larger GPU.
    pub fn with_limits(adapter: wgpu::Adapter, limits: wgpu::Limits) -> Result<Self, GpuError> {
        let wanted = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::FLOAT32_FILTERABLE;
        let features = adapter.features() & wanted;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("quadray"),
            required_features: features,
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|e| GpuError::NoDevice {
            adapter: adapter.get_info().name,
            reason: e.to_string(),
        })?;
        let has_timestamps = features.contains(wgpu::Features::TIMESTAMP_QUERY);
        let wait_bound = wait_bound(adapter.get_info().device_type)?;
        tracing::info!(adapter = %adapter.get_info().name, backend = ?adapter.get_info().backend, has_timestamps, ?wait_bound, "GPU opened");
        let lost = Arc::new(Mutex::new(None));
        let lost_reason = Arc::clone(&lost);
        device.set_device_lost_callback(move |why, message| {
            // Dropping the device reports a loss too; that one is not an error.
            if why != wgpu::DeviceLostReason::Destroyed {
                *lost_reason.lock().unwrap_or_else(|e| e.into_inner()) =
                    Some(format!("{why:?}: {message}"));
            }
        });
        Ok(Self {
            adapter,
            device,
            queue,
            has_timestamps,
            wait_bound,
            last_work: Mutex::new("nothing yet".into()),
            lost,
            stalled: false.into(),
        })
    }

    /// Submits `commands`, remembering `work` (what they do, e.g. "indirect frame 64x64: rsm,
    /// gather") so that a wait that runs out or a lost device names it.
    pub fn submit(&self, work: impl Into<String>, commands: wgpu::CommandBuffer) {
        *self.last_work.lock().unwrap_or_else(|e| e.into_inner()) = work.into();
        self.queue.submit([commands]);
    }

    /// The bound on every wait: `QUADRAY_GPU_WAIT_S` seconds, else 60 s on a hardware adapter and
    /// 1,800 s on a software one (lavapipe runs a 1920x1080 brute-force frame for minutes). Real
    /// work ends far inside it; only a pass that never ends reaches it.
    pub fn wait_bound(&self) -> Duration {
        self.wait_bound
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

    /// Blocks until all submitted work is done, at most [`Self::wait_bound`]; `waited_for` says
    /// why the caller waits (a readback, a pass), for the error.
    pub fn wait(&self, waited_for: &str) -> Result<(), GpuError> {
        let polled = self.device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: Some(self.wait_bound),
        });
        self.check_lost()?;
        match polled {
            Ok(_) => Ok(()),
            Err(wgpu::PollError::Timeout) => {
                self.stalled
                    .store(true, std::sync::atomic::Ordering::Relaxed);
                Err(GpuError::Timeout {
                    adapter: self.describe(),
                    work: self.last_work(),
                    waited_for: waited_for.into(),
                    bound_s: self.wait_bound.as_secs(),
                })
            }
            Err(e) => Err(GpuError::Readback(format!("{waited_for}: {e}"))),
        }
    }

    /// An error naming the adapter and the last work if the device was lost.
    fn check_lost(&self) -> Result<(), GpuError> {
        match self.lost.lock().unwrap_or_else(|e| e.into_inner()).clone() {
            Some(reason) => Err(GpuError::DeviceLost {
                adapter: self.describe(),
                work: self.last_work(),
                reason,
            }),
            None => Ok(()),
        }
    }

    fn last_work(&self) -> String {
        self.last_work
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone()
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

impl Drop for Gpu {
    fn drop(&mut self) {
        // After a wait ran out the device may still run that work, and destroying it would block
        // on it (or fault): keep it alive, so that the program can report and exit.
        if self.stalled.load(std::sync::atomic::Ordering::Relaxed) {
            std::mem::forget(self.device.clone());
            std::mem::forget(self.queue.clone());
        }
    }
}

/// [`Gpu::wait_bound`] for an adapter of `device_type`.
fn wait_bound(device_type: wgpu::DeviceType) -> Result<Duration, GpuError> {
    if let Some(value) = std::env::var_os(WAIT_BOUND_ENV) {
        let value = value.to_string_lossy();
        return match value.trim().parse::<f64>() {
            Ok(s) if (0.1..=86_400.0).contains(&s) => Ok(Duration::from_secs_f64(s)),
            _ => Err(GpuError::Setting(format!(
                "{WAIT_BOUND_ENV}={value}: the bound on a wait for the GPU is seconds in 0.1..86400"
            ))),
        };
    }
    Ok(Duration::from_secs(
        if device_type == wgpu::DeviceType::Cpu {
            1800
        } else {
            60
        },
    ))
}
