//! The gather: deferred shading of the caller's G-buffer from the light quadtree (the compacted
//! cut, the paper's one pass per level, per-tile cuts; the cut and RSM sampling optionally at low
//! resolution with geometry-aware upsampling), the baselines of the same shape (RSM sampling,
//! the brute force over every VPL) and the temporal filter; the direct light
//! ([`crate::DirectLight`]) runs over the same resources. Every pass sums the light views (a spot or the sun one, a point light
//! six): the first view writes the radiance, the others add. Writes radiance buffers an
//! [`crate::OutputPass`] copies into the caller's texture.
//!
//! One file a pass, each owning its shader, pipelines and recording, over the resources every
//! pass shares (`resources.rs`, its bindings `shared.wgsl`); [`crate::Gather`] only picks and
//! orders them (`gather.rs`). The baselines' CPU side is [`samples`], RSM sampling's pattern.

mod brute_force;
mod cut;
mod decode;
pub(crate) mod gather;
mod passes;
pub(crate) mod resources;
mod rsm_sampling;
pub mod samples;
