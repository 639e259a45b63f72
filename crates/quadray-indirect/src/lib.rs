//! One-bounce indirect illumination from a light quadtree (Ki & Oh, 2007): a reflective shadow map
//! of a light is clustered into a quadtree of VPLs, a cut of valid clusters replaces the hundreds
//! of thousands of VPLs, and deferred shading sums the cut per pixel. The paper's light is a spot;
//! a directional light's map is orthographic, a point light's six cube faces, and several lights
//! are the sum of their maps ([`LightView`]).
//!
//! Data flows one way: [`scene`] (load) -> the light (RSM, quadtree, cut) -> the gathers (the
//! default per-tile cuts of [`tiles`], the one cut, the per-level passes and the baselines of
//! [`gathers`], with the indirect [`shadows`]) -> the output -> measured against
//! [`reference`](mod@reference) (CPU brute force) and the GPU brute force.
//!
//! The crate is cut by feature, each folder holding its Rust passes, its WGSL and its CPU twins:
//! `light/` (light views, RSM, pyramid, cut), `tiles/` (the default method: rule, twin, kernel,
//! deblocking, blockiness), `shadows/` (occupancy grid, walk, depth-map march), `gathers/` (the
//! gather's shared resources, the one cut, per-level passes, RSM sampling, brute force),
//! `direct/` (the direct light through shadow maps of its own) and `output/` (upsampling,
//! temporal filter, output pass); [`Settings`] (no GPU) is what
//! a user configures, `contract.rs` the Rust <-> WGSL contract and [`wgsl`] the engine-neutral
//! shader modules, and [`Renderer`] quadray's own frame. The modules are layers, each naming only
//! the ones below it (`tests/layers.rs` lists them).
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
//! let rsm = RsmPass::new(&device, &s); // in the layout s.gbuffer_layout names
//! rsm.set_light(&queue, &light[0]);
//! let quadtree = LightQuadtree::new(&device, &queue, s.rsm_size, s.cluster, rsm.views());
//! let maps = [ViewMaps { rsm: rsm.views(), quadtree: &quadtree }];
//! let gather = Gather::new(&device, &s, &maps, GBufferViews::Wide { position, normal, albedo })?;
//! gather.set_lights(&queue, &light, r_min);
//! rsm.record(&mut encoder, vertices.slice(..), vertex_count, None);
//! quadtree.record_build(&mut encoder, None);
//! quadtree.record_cut(&mut encoder, None);
//! gather.record_indirect(&mut encoder, Method::DEFAULT, &[&quadtree], None); // per-tile cuts
//! # Ok(())
//! # }
//! ```
//!
//! For the direct light too (a renderer without its own), a [`DirectLight`] made for the gather
//! renders each light view a shadow map sized for the picture and lights the G-buffer through
//! them; `examples/gi_gbuffer.rs` records it.

#![warn(missing_docs)]

mod contract;
mod direct;
mod frame;
pub mod gathers;
mod gbuffer;
mod light;
mod method;
mod output;
pub mod picture;
pub mod reference;
mod renderer;
pub mod scene;
mod settings;
mod shader_struct;
#[cfg(test)]
mod shader_tests;
pub mod shadows;
pub mod tiles;
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

pub use contract::OutputTerm;
pub use direct::pass::DirectLight;
pub use frame::{CutNode, Frame, FrameTiming, Pass, Receiver, Vpl, WorkCounts};
pub use gathers::gather::Gather;
pub use gathers::resources::ViewMaps;
pub use gbuffer::GBufferViews;
pub use light::quadtree::LightQuadtree;
pub use light::rsm::{FLOAT_FORMAT, RsmPass, RsmViews, TextureArray};
pub use light::view::{LightView, Projection};
pub use method::{GBufferLayout, Method, TileCriterion, TilePasses, Validity};
pub use output::pass::OutputPass;
pub use quadray_core::settings::Size;
pub use renderer::Renderer;
pub use scene::Scene;
pub use settings::{ClusterSettings, Levels, Settings};
