//! The GPU side, one file per pass: the height pyramid resource and its compute build
//! ([`HeightPyramid`], [`PyramidBuilder`]), the engine-neutral tracing module ([`TRACE_WGSL`]),
//! and quadray's own surface pass and [`Renderer`] built on them.

mod height_pyramid;
mod pyramid_build;
mod renderer;
mod surface_pass;
mod trace;
#[cfg(test)]
mod wgsl_contract;

pub use height_pyramid::{HeightPyramid, ITERATION_CAP, PyramidInfo, PyramidKind, REFINE_CAP};
pub use pyramid_build::PyramidBuilder;
pub use renderer::{Frame, Renderer};
pub use surface_pass::Targets;
pub use trace::TRACE_WGSL;
