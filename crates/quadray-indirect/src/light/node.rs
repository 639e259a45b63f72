//! The Rust side of the light quadtree's node layout (`node.wgsl`): the pyramid's addressing,
//! levels finest first, and the constants of a node's box and normal cone.

/// An empty box's lo (its hi is the negative): any box joined with it is that box. A tile's
/// uncovered pixel lies there (per-tile cuts), never the one nearest a node.
pub(crate) const EMPTY_BOX: f32 = 1e30;
/// Widens a normal cone's half-angle (radians) past f32's rounding in acos near 1, so that the
/// cone still holds every VPL normal.
pub(crate) const CONE_SLACK: f32 = 1e-3;
/// Bound on the pyramid's levels (a 1024^2 RSM has 11).
pub(crate) const MAX_LEVELS: u32 = 16;

/// Total nodes of the pyramid of an RSM of side `rsm_size`.
pub(crate) fn node_count(rsm_size: u32) -> u64 {
    level_offset(rsm_size, rsm_size.ilog2() + 1)
}

/// Index of the first node of `level`.
pub(crate) fn level_offset(rsm_size: u32, level: u32) -> u64 {
    (0..level).map(|l| u64::from(rsm_size >> l).pow(2)).sum()
}
