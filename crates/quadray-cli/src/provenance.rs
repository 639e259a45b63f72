//! What a stats file was measured with: the commit `quadray` was built from (`build.rs`) and the
//! GPU adapter, so that a figure copied off a machine still says where it came from.

use quadray_gpu::Gpu;
use serde::Serialize;

/// The commit `quadray` was built from (`-modified` after it when the sources differed from it,
/// `unknown` without git or `QUADRAY_COMMIT`).
pub const COMMIT: &str = env!("QUADRAY_COMMIT");

/// `quadray --version`: the package's version and the commit.
pub const VERSION: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (commit ",
    env!("QUADRAY_COMMIT"),
    ")"
);

/// The adapter a GPU command ran on, as wgpu names it.
#[derive(Serialize)]
pub struct Adapter {
    name: String,
    /// Vulkan, Metal, Dx12 or Gl.
    backend: String,
    driver: String,
    driver_info: String,
    /// DiscreteGpu, IntegratedGpu, Cpu (a software rasterizer), ...
    device_type: String,
}

impl Adapter {
    pub fn of(gpu: &Gpu) -> Self {
        let info = gpu.adapter.get_info();
        Self {
            name: info.name,
            backend: format!("{:?}", info.backend),
            driver: info.driver,
            driver_info: info.driver_info,
            device_type: format!("{:?}", info.device_type),
        }
    }
}

/// The commit and, for a command that ran on the GPU, the adapter.
#[derive(Serialize)]
struct Provenance {
    commit: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    adapter: Option<Adapter>,
}

/// A command's stats with `provenance` before its own fields.
#[derive(Serialize)]
pub struct Recorded<'a, T: Serialize> {
    provenance: Provenance,
    #[serde(flatten)]
    stats: &'a T,
}

/// `stats` as a stats file holds them: with the commit, and the adapter of `gpu` where the
/// command ran on one.
pub fn recorded<'a, T: Serialize>(stats: &'a T, gpu: Option<&Gpu>) -> Recorded<'a, T> {
    Recorded {
        provenance: Provenance {
            commit: COMMIT,
            adapter: gpu.map(Adapter::of),
        },
        stats,
    }
}
