//! One-bounce indirect illumination from a light quadtree (Ki & Oh, 2007): a reflective shadow map
//! of a spot light is clustered into a quadtree of VPLs, a cut of valid clusters replaces the
//! hundreds of thousands of VPLs, and deferred shading sums the cut per pixel.
//!
//! Data flows one way: [`scene`] (load) -> [`gpu`] (RSM, quadtree, cut, shading) -> measured
//! against [`reference`] (CPU brute force) and the GPU brute force of [`baselines`].

pub mod baselines;
pub mod bench;
pub mod demo;
pub mod gpu;
pub mod reference;
pub mod report;
pub mod scene;

/// Anything that can go wrong between a scene file and a measured picture.
#[derive(Debug, thiserror::Error)]
pub enum IndirectError {
    #[error(transparent)]
    Gpu(#[from] quadray_gpu::GpuError),
    #[error(transparent)]
    File(#[from] quadray_core::FileError),
    #[error("invalid parameters: {0}")]
    Settings(String),
}

pub use gpu::{
    ClusterSettings, CutNode, Frame, FrameTiming, Method, Pass, Renderer, Settings, Validity,
};
pub use scene::Scene;
