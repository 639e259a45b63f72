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
//! `examples/gi_gbuffer.rs` is a whole program doing that; its heart:
//!
//! ```no_run
//! # use quadray_indirect::scene::Light;
//! # use quadray_indirect::{GBufferViews, Gather, IndirectError, LightQuadtree, LightView};
//! # use quadray_indirect::{Method, RsmPass, Settings, ViewMaps};
//! # #[allow(clippy::too_many_arguments)]
//! # fn record(
//! #     device: wgpu::Device, queue: wgpu::Queue, mut encoder: wgpu::CommandEncoder,
//! #     s: Settings, sun: Light, scene_bounds: (glam::Vec3, glam::Vec3), r_min: f32,
//! #     [position, normal, albedo]: [&wgpu::TextureView; 3], vertices: wgpu::Buffer, vertex_count: u32,
//! # ) -> Result<(), IndirectError> {
//! let light = LightView::of_light(&sun, scene_bounds); // a spot or the sun: one view, a point light six
//! let rsm = RsmPass::new(&device, s.rsm_size);
//! rsm.set_light(&queue, &light[0]);
//! let quadtree = LightQuadtree::new(&device, &queue, s.rsm_size, s.cluster, rsm.views());
//! let maps = [ViewMaps { rsm: rsm.views(), quadtree: &quadtree }];
//! let gather = Gather::new(&device, &s, &maps, GBufferViews { position, normal, albedo })?;
//! gather.set_lights(&queue, &light, r_min);
//! rsm.record(&mut encoder, vertices.slice(..), vertex_count, None);
//! quadtree.record_build(&mut encoder, None);
//! quadtree.record_cut(&mut encoder, None);
//! gather.record_indirect(&mut encoder, Method::DEFAULT, &[&quadtree], None); // per-tile cuts
//! # Ok(())
//! # }
//! ```

#![warn(missing_docs)]

pub mod baselines;
pub mod blockiness;
pub mod deblock;
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
