//! The default method, per-tile cuts ([`crate::Method::QuadtreeTiles`]): a workgroup a tile of
//! 8x8 receivers refines its own cut of the light quadtree against a
//! bound of each node's contribution (the rule, `rule.wgsl`; its CPU twin, [`twin`]), its pixels
//! sum the list (the per-tile kernel, `kernel.wgsl` with the shadow rays of `anchors.wgsl`; its
//! pass, `pass.rs`), and the light's steps at the tiles' boundaries are smoothed where the
//! pixels lie on one surface (`deblock.wgsl`; its twin, [`deblock`]); [`blockiness`] measures
//! the steps that are left. The constants here tune the rule and the kernel; the WGSL prelude
//! holds them too.

pub mod blockiness;
pub mod deblock;
pub(crate) mod pass;
pub mod twin;

use crate::settings::{Settings, TILE_FRONTIER};

/// Bits of a per-tile cut's list entry that hold the node's index: a 1024^2 RSM's pyramid of
/// nodes takes 21; with indirect shadows the bits above hold the node's visibility target's slot
/// (at most [`TILE_FRONTIER`] of them) and a flag (wgsl `ENTRY_INDEX`, kernel.wgsl).
pub(crate) const TILE_ENTRY_INDEX_BITS: u32 = 21;
const _: () =
    assert!(4 * Settings::RSM_SIZE.max * Settings::RSM_SIZE.max / 3 < 1 << TILE_ENTRY_INDEX_BITS);
const _: () = assert!(TILE_FRONTIER <= 1 << (31 - TILE_ENTRY_INDEX_BITS));
/// Split per-tile passes: the most tiles a walks' workgroup of 64 threads holds, at the fewest
/// [`Settings::tile_walk_lanes`] (wgsl `MOST_WALKED_TILES`: the workgroup's fetch counters).
pub(crate) const MOST_WALKED_TILES: u32 = 64 / Settings::TILE_WALK_LANES.min;
/// Per-tile cuts: a node more than this many times `r_min` across, with a receiver of the tile
/// within `r_min` of its box, holds the kernel's near field, where its children's sum agrees
/// with it however far both are from its VPLs'; the bound, not the estimate, decides it
/// (`near_field` in rule.wgsl; BENCHMARKS.md, "The default method at equal error").
pub const NEAR_FIELD_SIZE: f32 = 4.0;
/// Indirect shadows, per-tile cuts: a node of several surfaces (not valid) becomes its listed
/// descendants' visibility target at this part of [`Settings::tile_shadow_angle`] (its mean lies
/// off its surfaces, so it stands in for them from farther away only). Chosen on the tuned
/// visibility scenes (BENCHMARKS.md): 0 (valid nodes only) walked 10.9, 7.9 and 5.1 rays a pixel
/// on the door, corridor and gap scenes, 0.5 walks 8.4, 4.9 and 4.8 at the same FLIP and
/// blockiness, 1 walks 6.4, 2.7 and 4.3 but took the gap's blockiness to 1.21 and its FLIP up 4%.
pub(crate) const MIXED_TARGET_ANGLE: f32 = 0.5;
/// Indirect shadows, per-tile cuts: a shadow target of several surfaces whose normals all lie
/// within the cone of this cosine about its mean normal (surfaces facing one way at different
/// depths, such as a box's top and the floor around it) is walked to at its box's farthest face
/// along that normal, from a receiver beyond that face: its mean lies between its surfaces,
/// inside the box, where the box's top hid it from the ceiling while every VPL of the cluster
/// was in view. A cone of about 25 degrees holds surfaces facing one way and leaves out a
/// corner's floor and walls (each 45 degrees from their mean normal), whose box's far corner
/// lies out in the room: walked to for every mixed target, the Cornell box's and the bunny's
/// pictures got worse (BENCHMARKS.md).
pub(crate) const PARALLEL_TARGET_COS: f32 = 0.9;
/// Per-tile cuts: a tile whose coarse estimate is zero (its sample pixels get nothing from the
/// start level's nodes) takes this share of the start level's bounds at its receivers as its
/// estimate, instead of a threshold of zero that split every node that might light it to the
/// list's capacity (a quarter to a third of the listed nodes on the door, gap, shelf and leak
/// scenes, the same pictures to 4 digits of FLIP; BENCHMARKS.md).
pub(crate) const ZERO_ESTIMATE_SHARE: f32 = 0.1;
/// Per-tile cuts order a level's splits by bins of powers of two of how far a node's bound
/// exceeds the threshold, the highest first.
pub(crate) const SPLIT_BINS: u32 = 16;
