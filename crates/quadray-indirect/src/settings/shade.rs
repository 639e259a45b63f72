//! The settings as the gather's shaders read them: the uniform `Shade`, its WGSL struct generated
//! from the same declaration.

use crate::frame::NORMAL_AGREEMENT;
use crate::method::TileCriterion;
use crate::settings::Settings;
use crate::shader_struct::shader_struct;

shader_struct! {
    /// The settings as the gather's shaders read them (WGSL `Shade`), written once: a gather's
    /// settings are fixed. A setting a shader reads is a field here and nowhere else on the Rust
    /// side; the WGSL struct is generated from this list.
    pub(crate) struct Shade as "Shade" (s: &Settings) {
        sample_count: u32 = s.samples,
        /// Sub-sampled indirect: one sample per `subsample` x `subsample` pixels.
        subsample: u32 = s.subsample,
        /// Interleaved sampling: a pixel sums one of `interleave`^2 parts (1: all).
        interleave: u32 = s.interleave,
        low_width: u32 = s.low_size().0,
        low_height: u32 = s.low_size().1,
        /// Geometry agreement for upsampling, corner sharing and deblocking: normals' dot.
        normal_agreement: f32 = NORMAL_AGREEMENT,
        /// Indirect shadows: points marched between a receiver and a cluster (0: none).
        shadow_steps: u32 = s.march_steps(),
        /// The one cut's indirect shadows from corner receivers every `shadow_corners` pixels
        /// (0: each pixel walks), `corners_x` of them in a row and `corners_y` rows, each keeping
        /// `corner_words` words of visibility bits (shadows/corners.wgsl).
        shadow_corners: u32 = s.shadow_corners_or_off(),
        corners_x: u32 = s.shadow_corner_grid().0,
        corners_y: u32 = s.shadow_corner_grid().1,
        corner_words: u32 = s.shadow_corner_words(),
        /// The threads walking one corner's rays (a workgroup holds 64 / `corner_lanes` corners).
        corner_lanes: u32 = s.shadow_corner_lanes,
        /// Split per-tile passes: the threads walking one tile's shadow rays (a workgroup holds
        /// 64 / `tile_walk_lanes` tiles).
        tile_walk_lanes: u32 = s.tile_walk_lanes,
        /// Weight of this frame in the running average of the indirect light (1: no filter).
        temporal_weight: f32 = s.temporal_weight,
        /// Per-tile cuts: a node is split while its bound (or with `tile_estimate` 1, its
        /// estimated error) exceeds `tile_error` of the tile's irradiance estimated from the
        /// nodes of level `tile_start`; at most `tile_capacity` nodes a tile.
        tile_error: f32 = s.tile_error_or_default(),
        tile_capacity: u32 = s.tile_capacity_or_default(),
        tile_start: u32 = s.tile_start_level(),
        /// Tiles in a row of the picture.
        tiles_x: u32 = s.tiles().0,
        tile_estimate: u32 = u32::from(s.tile_criterion == TileCriterion::Estimate),
        /// Per-tile cuts: nodes farther than this times the tile's receivers' diagonal are
        /// gathered at the tile's corners and interpolated (0: every pixel evaluates every node).
        tile_share: f32 = s.tile_share,
        /// Per-tile cuts: pixels on either side of a tile boundary its unexplained step is
        /// spread over (0: none; deblock.wgsl).
        tile_deblock: u32 = s.tile_deblock,
        /// Per-tile cuts with indirect shadows: a cluster takes the visibility of its highest
        /// ancestor whose box's diagonal is at most this times its distance from the tile's
        /// receivers, `MIXED_TARGET_ANGLE` of it for an ancestor of several surfaces (0: each
        /// its own; tiles/kernel.wgsl).
        tile_shadow_angle: f32 = s.tile_shadow_angle,
    }
}
