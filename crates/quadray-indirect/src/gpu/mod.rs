//! The GPU side, one file per pass, each owning its pipelines, layouts, bind groups and
//! recording, all recording into the caller's `wgpu::CommandEncoder` on the caller's device:
//! [`RsmPass`] (the spot's reflective shadow map; or bring your own [`RsmViews`]),
//! [`LightQuadtree`] (pyramid, validity, compacted cut), [`Gather`] (indirect light into the
//! caller's G-buffer from the cut, the paper's per-level passes or per-tile cuts, the baselines
//! of the same shape, the direct light; one file a pass under `gather/`) and [`OutputPass`] (the
//! radiance into the caller's texture). Bindings are grouped by how often they change: per light
//! update, per frame, per dispatch; the light, the camera and the settings each have their own
//! uniform buffer. [`Renderer`] is quadray's own user of these passes.
//!
//! Layers, bottom first: `contract.rs` (the shared structs, the generated WGSL prelude, the
//! layout and pipeline helpers), `light.rs`, `rsm.rs`, `gbuffer.rs`, `quadtree.rs`, `gather/`,
//! `output.rs`, `renderer.rs`. The shaders are the engine-neutral modules of [`crate::wgsl`]
//! with each pass's bindings file and entry points.

#[cfg(test)]
mod bound_tests;
mod contract;
mod gather;
mod gbuffer;
mod light;
#[cfg(test)]
mod occupancy_tests;
mod output;
mod quadtree;
mod renderer;
mod rsm;
#[cfg(test)]
mod shader_tests;

pub use contract::OutputTerm;
pub(crate) use contract::prelude;
pub use gather::{Gather, ViewMaps};
pub use gbuffer::GBufferViews;
pub use light::{LightView, Projection};
pub use output::OutputPass;
pub use quadtree::LightQuadtree;
pub use renderer::Renderer;
pub use rsm::{FLOAT_FORMAT, RsmPass, RsmViews};

// The settings and read-back types, also at their old paths under `gpu`.
pub use crate::frame::{CutNode, Frame, FrameTiming, Pass, Receiver, Vpl, WorkCounts};
pub use crate::settings::{ClusterSettings, Method, Settings, TileCriterion, Validity};

/// Every shader's parts (before the prelude), by pass: what the contract test parses.
#[cfg(test)]
pub(crate) fn shaders() -> Vec<(&'static str, Vec<String>)> {
    let owned = |parts: &[&str]| parts.iter().map(|p| p.to_string()).collect();
    let mut shaders = vec![
        ("rsm", owned(&rsm::SOURCES)),
        ("gbuffer", owned(&gbuffer::SOURCES)),
        ("quadtree", owned(&quadtree::SOURCES)),
        ("output", output::sources("rgba16float").to_vec()),
    ];
    shaders.extend(
        gather::shaders()
            .into_iter()
            .map(|(name, parts)| (name, owned(&parts))),
    );
    shaders
}
