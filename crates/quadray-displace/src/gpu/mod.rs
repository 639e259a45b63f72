//! The GPU side, one file per pass: the height pyramid resource and its compute build
//! ([`HeightPyramid`], [`PyramidBuilder`]), the engine-neutral tracing module ([`TRACE_WGSL`]),
//! and quadray's own surface pass and [`Renderer`] built on them.

mod height_pyramid;
mod pyramid_build;
mod renderer;
mod surface_pass;
#[cfg(test)]
mod wgsl_contract;

pub use height_pyramid::{HeightPyramid, ITERATION_CAP, PyramidInfo, PyramidKind, REFINE_CAP};
pub use pyramid_build::PyramidBuilder;
pub use renderer::{Frame, Renderer};
pub use surface_pass::Targets;

/// `trace.wgsl`, the engine-neutral tracing module: `pyramid_trace`, `bilinear_trace` (the
/// bilinear refinement), `pyramid_lod`, `shadow_lit` / `pyramid_lit` (self-shadowing) and their
/// helpers, as WGSL functions taking the pyramid texture and plain parameters. Include it by
/// concatenation ahead of your own shader code (quadray's surface shader does); its header says
/// what a caller provides.
pub const TRACE_WGSL: &str = include_str!("trace.wgsl");
