//! Pyramid inverse displacement mapping (Oh & Ki, 2007): ray casting a height field through a
//! quadtree of max heights, with node crossing, bilinear refinement, LOD and self-shadowing; the
//! baselines it is compared against (bump, parallax, POM, relief, a real displaced mesh); and the
//! exact CPU ground truth every GPU method is measured against.
//!
//! Data flows one way: [`heightmap`] (load) -> [`pyramid`] (build) -> [`gpu`] (trace and shade)
//! -> [`accuracy`] (measure against [`reference`]).

pub mod accuracy;
pub mod bench;
pub mod demo;
pub mod gpu;
pub mod heightmap;
pub mod maps;
pub mod method;
pub mod pyramid;
pub mod reference;
pub mod scene;

/// Anything that can go wrong between a map file and a measured picture.
#[derive(Debug, thiserror::Error)]
pub enum DisplaceError {
    #[error(transparent)]
    HeightMap(#[from] heightmap::HeightMapError),
    #[error(transparent)]
    Gpu(#[from] quadray_gpu::GpuError),
    #[error(transparent)]
    File(#[from] quadray_core::FileError),
    #[error("invalid parameters: {0}")]
    Settings(String),
}

pub use gpu::{Frame, Lod, Renderer, Settings, Targets};
pub use method::Method;
