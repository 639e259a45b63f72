//! Indirect shadows ([`crate::Settings::indirect_shadows`]): the scene's occupancy grid and its
//! walk ([`occupancy`], the CPU twin of `occupancy.wgsl`'s `grid_visibility`), and the march
//! through the camera's and the light's depth maps where the gather has no grid (`march.wgsl`,
//! with `visible`, which picks between them, and the kernel with visibility); the one cut's
//! visibility from corner receivers (`corners.rs`, `corners.wgsl`).

pub(crate) mod corners;
pub mod occupancy;
#[cfg(test)]
mod occupancy_tests;

/// The depth-map march and `visible`, in every gather shader (they read the gather's bindings).
pub(crate) const MARCH_WGSL: &str = include_str!("march.wgsl");
