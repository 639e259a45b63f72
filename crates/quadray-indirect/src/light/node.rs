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

/// The compacted cut is kept in classes: a node at (x, y) of its level is in class
/// x % `CUT_CLASS_SIDE` + `CUT_CLASS_SIDE` (y % `CUT_CLASS_SIDE`), each class in a segment of its
/// own, so that interleaved sampling's parts are classes (a pixel of an NxN block, N dividing
/// this, sums the classes of its offset): every part an even grid of each level's nodes, and a
/// cluster's part its own, whatever else the cut holds (not its place in an atomically filled
/// list, which moves as the cut changes).
pub(crate) const CUT_CLASS_SIDE: u32 = 4;
const _: () = assert!(crate::Settings::INTERLEAVE.max == CUT_CLASS_SIDE);

/// The cut's counts: its clusters, then each class's.
pub(crate) type CutCounts = [u32; (CUT_CLASS_SIDE * CUT_CLASS_SIDE + 1) as usize];

/// Nodes a class of the cut can hold: those of the class on every level (a cut with the limit
/// at the RSM's texels holds at most that many).
pub(crate) fn cut_class_capacity(rsm_size: u32) -> u64 {
    (0..=rsm_size.ilog2())
        .map(|l| u64::from((rsm_size >> l).div_ceil(CUT_CLASS_SIDE)).pow(2))
        .sum()
}

/// Total nodes of the pyramid of an RSM of side `rsm_size`.
pub(crate) fn node_count(rsm_size: u32) -> u64 {
    level_offset(rsm_size, rsm_size.ilog2() + 1)
}

/// Index of the first node of `level`.
pub(crate) fn level_offset(rsm_size: u32, level: u32) -> u64 {
    (0..level).map(|l| u64::from(rsm_size >> l).pow(2)).sum()
}
