//! Pyramid inverse displacement mapping (Oh & Ki, 2007): ray casting a height field through a
//! quadtree of max heights, with node crossing, bilinear refinement, LOD and self-shadowing; the
//! baselines it is compared against (bump, parallax, POM, relief, a real displaced mesh); and the
//! exact CPU ground truth every GPU method is measured against.
//!
//! To displace surfaces in your own renderer: load a [`heightmap::HeightMap`], build a
//! [`HeightPyramid`] on your `wgpu::Device`, and include [`TRACE_WGSL`] in your fragment shader
//! (`examples/displaced_quad.rs` is a whole program). quadray's own [`Renderer`] is built the
//! same way.
//!
//! ```no_run
//! # use quadray_displace::pyramid::Addressing;
//! # use quadray_displace::{HeightPyramid, PyramidKind, TRACE_WGSL, heightmap::HeightMap};
//! # fn build(device: wgpu::Device, queue: wgpu::Queue, map: HeightMap) -> (quadray_displace::PyramidInfo, String) {
//! # const MY_SHADER: &str = "";
//! let pyramid = HeightPyramid::build_gpu(&device, &queue, &map, PyramidKind::Point);
//! let info = pyramid.info(Addressing::Wrap);          // upload it; bind pyramid.view() as texture_2d<f32>
//! let source = format!("{TRACE_WGSL}\n{MY_SHADER}");  // MY_SHADER calls pyramid_trace, pyramid_lit
//! # (info, source)
//! # }
//! ```
//!
//! Data flows one way: [`heightmap`] (load) -> [`pyramid`] (build) -> [`gpu`] (trace and shade)
//! -> [`accuracy`] (measure against [`reference`](mod@reference) on the CPU's own
//! [`primary_rays`]).

#![warn(missing_docs)]

pub mod accuracy;
pub mod cone;
pub mod gpu;
pub mod heightmap;
pub mod maps;
pub mod method;
pub mod primary_rays;
pub mod pyramid;
pub mod reference;
pub mod scene;
pub mod search_cost;
pub mod settings;

/// Anything that can go wrong between a map file and a measured picture.
#[derive(Debug, thiserror::Error)]
pub enum DisplaceError {
    /// The map could not be loaded.
    #[error(transparent)]
    HeightMap(#[from] heightmap::HeightMapError),
    /// The GPU refused the work.
    #[error(transparent)]
    Gpu(#[from] quadray_gpu::GpuError),
    /// An output could not be written.
    #[error(transparent)]
    File(#[from] quadray_core::FileError),
    /// The settings make no picture.
    #[error("invalid parameters: {0}")]
    Settings(String),
}

pub use gpu::{
    Frame, HeightPyramid, PyramidBuilder, PyramidInfo, PyramidKind, Renderer, TRACE_WGSL, Targets,
};
pub use method::Method;
pub use quadray_core::settings::Size;
pub use settings::{Layers, Lod, Settings};
