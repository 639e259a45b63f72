//! One-bounce indirect illumination from a light quadtree (Ki & Oh, 2007): a reflective shadow map
//! of a light is clustered into a quadtree of VPLs, a cut of valid clusters replaces the hundreds
//! of thousands of VPLs, and deferred shading sums the cut per pixel. The paper's light is a spot;
//! a directional light's map is orthographic, a point light's six cube faces, and several lights
//! are the sum of their maps ([`LightView`]).
//!
//! Data flows one way: [`scene`] (load) -> [`gpu`] (RSM, quadtree, cut, shading) -> measured
//! against [`reference`](mod@reference) (CPU brute force) and the GPU brute force of [`baselines`].
//!
//! The modules are layers, each naming only the ones below it (`tests/layers.rs` checks it):
//! the settings ([`Settings`], no GPU) and the read-back types ([`Frame`], ...), the scene, the
//! baselines' sample pattern and the CPU reference, then the GPU side from the Rust <-> WGSL
//! contract and the engine-neutral shader modules ([`wgsl`]) up through the light, the RSM, the
//! G-buffer, the light quadtree, the gather passes and the output to quadray's [`Renderer`].
//!
//! To add the bounce to your own wgpu renderer, record the passes into your encoder:
//! [`RsmPass`] (or your own [`RsmViews`]) -> [`LightQuadtree`] (build, cut) -> [`Gather`] into your
//! [`GBufferViews`] -> [`OutputPass`] into your texture, all configured by one [`Settings`].
//! `examples/gi_gbuffer.rs` is a whole program doing that.

#![warn(missing_docs)]

pub mod baselines;
pub mod blockiness;
mod frame;
pub mod gpu;
pub mod occupancy;
pub mod picture;
pub mod reference;
pub mod scene;
mod settings;
pub mod tile_cut;
pub mod wgsl;

/// Anything that can go wrong between a scene file and a measured picture.
#[derive(Debug, thiserror::Error)]
pub enum IndirectError {
    /// The GPU refused the work (no adapter, a shader or a read-back failed).
    #[error(transparent)]
    Gpu(#[from] quadray_gpu::GpuError),
    /// A scene, mesh or output file could not be read or written.
    #[error(transparent)]
    File(#[from] quadray_core::FileError),
    /// The settings make no picture (a size of 0, an RSM side that is not a power of two, ...).
    #[error("invalid parameters: {0}")]
    Settings(String),
}

pub use frame::{CutNode, Frame, FrameTiming, Pass, Receiver, Vpl, WorkCounts};
pub use gpu::{
    FLOAT_FORMAT, GBufferViews, Gather, LightQuadtree, LightView, OutputPass, OutputTerm,
    Projection, Renderer, RsmPass, RsmViews, ViewMaps,
};
pub use quadray_core::settings::Size;
pub use scene::Scene;
pub use settings::{
    ClusterSettings, Levels, Method, NEAR_FIELD_SIZE, Settings, TileCriterion, Validity,
};
