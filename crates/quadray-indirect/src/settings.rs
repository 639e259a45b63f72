//! What a user configures: the sizes, the method and every method's parameters, and the rule
//! that refuses settings that make no picture. The bottom layer: plain values, no GPU.
//!
//! Each parameter is declared once, here: its field, its doc comment (the `--help` text), its
//! default in [`Settings::DEFAULT`] and its valid values in a [`Limits`] const that both
//! [`Settings::validate`] and the flag's parser use. With the `cli` feature the struct is
//! `quadray indirect`'s clap arguments; `Settings::to_args` spells them back (the viewer's
//! reproducing command line), and a round-trip test parses them again.

use crate::frame::NORMAL_AGREEMENT;
use crate::method::{GBufferLayout, TileCriterion, TilePasses};
use crate::shader_struct::shader_struct;
use quadray_core::settings::{Limits, Size};
use serde::Serialize;

mod cluster;
mod sizes;

pub use cluster::{ClusterSettings, Levels};
use sizes::{check_rsm_size, check_shadow_map_size, check_size};

/// Side of a tile of receivers that shares one per-tile cut (the gather's workgroup).
pub(crate) const TILE: u32 = 8;
/// Nodes a tile's frontier holds in workgroup memory (per-tile cuts, two levels of it): the
/// most a tile's list may hold ([`Settings::tile_capacity`]).
pub(crate) const TILE_FRONTIER: u32 = 1024;

/// Split per-tile passes ([`Settings::tile_passes`]): the words of a tile's shadow record
/// before its targets' visibility words: how many targets, the anchor sets and the shared
/// nodes, then each of the eight anchors' receivers, position and normal (wgsl
/// `TILE_SHADOW_HEADER`, tiles/split.wgsl).
pub(crate) const TILE_SHADOW_HEADER: u32 = 3 + 8 * 6;

/// Sizes and the parameters of every method.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Settings {
    /// Picture size in pixels, WxH.
    #[serde(flatten)]
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.size,
        value_parser = Settings::parse_size,
    ))]
    pub size: Size,
    /// Side of the square reflective shadow map in texels (a power of two): how many VPLs a
    /// spot or directional light makes (a point light: six times as many).
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.rsm_size,
        value_parser = Settings::parse_rsm_size,
    ))]
    pub rsm_size: u32,
    /// Side of each light view's shadow map for the direct light's shadows, in texels (a power
    /// of two; a point light has six): the sun's map is fitted to what the camera sees, a spot's
    /// and a point light's faces are their RSM views. Default: twice the picture's longer side
    /// rounded up to a power of two, within 256-2048 (a 512x512 picture's is 1024, a 1920x1080
    /// picture's 2048): the fitted map then spends a texel or more on every pixel of the ground
    /// near the camera, where a pixel covers least of it.
    #[cfg_attr(feature = "cli", arg(long, value_parser = Settings::parse_shadow_map_size))]
    pub shadow_map_size: Option<u32>,
    /// The most lights rendered: the scene's first N, each with its own RSM of --rsm-size^2
    /// texels and light quadtree (a point light six, one per cube face), so the light's work
    /// grows linearly with the count.
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.max_lights,
        value_parser = Settings::MAX_LIGHTS.parser(),
    ))]
    pub max_lights: u32,
    /// How quadray's G-buffer and RSM passes store their targets: compact (position rebuilt
    /// from depth, the normal in 16-bit octahedral, the albedo in 10 bits, the RSM's flux in
    /// 16-bit floats: a sixth of the G-buffer's raster output cycles on NVIDIA, a quarter of the
    /// RSM's) or wide (each in 32-bit floats). A renderer that brings its own G-buffer or RSM
    /// declares its layout in `GBufferViews` and `RsmViews`.
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value_t = Settings::DEFAULT.gbuffer_layout)
    )]
    pub gbuffer_layout: GBufferLayout,
    /// The quadtree's parameters, for the quadtree methods.
    #[cfg_attr(feature = "cli", command(flatten))]
    pub cluster: ClusterSettings,
    /// RSM-sampling samples per pixel.
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.samples,
        value_parser = Settings::SAMPLES.parser(),
    ))]
    pub samples: u32,
    /// RSM sampling's radius as a fraction of the RSM's diagonal.
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.rsm_radius,
        value_parser = Settings::RSM_RADIUS.parser(),
    ))]
    pub rsm_radius: f32,
    /// Indirect at one sample per KxK pixels (1: full resolution), upsampled where the geometry
    /// agrees and the other pixels recomputed at full resolution (quadtree, rsm: the methods
    /// that [`crate::Method::subsamples`]).
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.subsample,
        value_parser = Settings::SUBSAMPLE.parser(),
    ))]
    pub subsample: u32,
    /// Interleaved sampling at full resolution (quadtree, rsm: the methods that
    /// [`crate::Method::subsamples`]): each pixel of an NxN block sums every N^2-th cluster or
    /// sample from its own offset, and a geometry-aware NxN filter rejoins the parts; a pixel
    /// with too few neighbours on its surface sums them all (1: off). Not with `subsample`.
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.interleave,
        value_parser = Settings::INTERLEAVE.parser(),
    ))]
    pub interleave: u32,
    /// Indirect shadows (quadtree methods): test each receiver's view of each cluster, walking
    /// the scene's occupancy grid (--shadow-grid), or marching points against the camera's and
    /// the light's depth (off in the paper). The per-tile cuts test from each tile's four
    /// corner receivers only, and a pixel weighs each cluster by the corners' visibility
    /// interpolated (a pixel off the corners' surface, across a depth edge, tests its own).
    #[cfg_attr(feature = "cli", arg(long))]
    pub indirect_shadows: bool,
    /// The one cut's indirect shadows (method quadtree) tested from corner receivers every K
    /// pixels across and down, each corner walking to every cluster of the cut in a pass of its
    /// own; a pixel weighs each cluster by the visibility of the corners around it on its
    /// surface, interpolated, and walks its own rays only where no corner lies on its surface
    /// (0: every pixel walks to every cluster). Default: the picture's longer side over
    /// [`Self::SHADOW_CORNERS_ACROSS`], rounded (16 at 1920x1080, 4 at 512x512), so that the
    /// corners lie as densely over the scene, and cost as much, at every size; 0 where that is
    /// no more than `interleave` (a pixel that walks to its N^2-th of the cut walks no more than
    /// corners every N pixels would to the whole: 0 at 128x128).
    #[cfg_attr(feature = "cli", arg(long, value_parser = Settings::SHADOW_CORNERS.parser()))]
    pub shadow_corners: Option<u32>,
    /// The threads that walk one shadow corner's rays (a power of two, 8 to 64; 64: a workgroup
    /// a corner). Fewer lanes a corner give each lane more rays to walk, so that a wave's lanes
    /// end closer together, with several corners a workgroup; the picture is the same.
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.shadow_corner_lanes,
        value_parser = Settings::SHADOW_CORNER_LANES.parser(),
    ))]
    pub shadow_corner_lanes: u32,
    /// Points marched per receiver and cluster with --indirect-shadows and --shadow-grid 0.
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.shadow_steps,
        value_parser = Settings::SHADOW_STEPS.parser(),
    ))]
    pub shadow_steps: u32,
    /// Depth behind a seen surface that counts as inside an occluder where the other depth map
    /// does not see the point in front (a fraction of the scene's extent), with
    /// --indirect-shadows; a tenth of it is the depth bias.
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.shadow_thickness,
        value_parser = Settings::SHADOW_THICKNESS.parser(),
    ))]
    pub shadow_thickness: f32,
    /// Cells of the scene's occupancy grid along its longest side, which indirect shadows walk
    /// from each receiver to each cluster, so that a wall, a shelf or a slab blocks whatever the
    /// camera and the light see of it (built from the scene's triangles by quadray's renderer
    /// and the Bevy plugin; another renderer gives the gather its own, `Gather::set_occupancy`);
    /// 0: march the camera's and the light's depth maps instead (--shadow-steps,
    /// --shadow-thickness).
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.shadow_grid,
        value_parser = Settings::SHADOW_GRID.parser(),
    ))]
    pub shadow_grid: u32,
    /// Levels of the occupancy grid (--shadow-grid): 1, a bit a cell; 2, also a bit for each of
    /// the 4x4x4 sub-cells of every set cell, walked where the walk meets a set cell, so that an
    /// opening is narrowed by a sub-cell on each side rather than by a cell (two words a set
    /// cell; at most 128 cells with 2 levels). Two by default: on the visibility scenes tuned on,
    /// the FLIP to the truth 0.084 -> 0.056 (corridor) and 0.020 -> 0.016 (gap) for 10-20% more
    /// fetches, and the deblocking filter (--tile-deblock) takes the tile structure the sharper
    /// visibility gives (BENCHMARKS.md).
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.shadow_grid_levels,
        value_parser = Settings::SHADOW_GRID_LEVELS.parser(),
    ))]
    pub shadow_grid_levels: u32,
    /// Weight of each frame's indirect light in a running average over frames (1: off), every
    /// method but the brute force: damps the cut's popping under a moving light (see
    /// BENCHMARKS.md). Reprojected through the camera's motion (points the last frame did not
    /// see start anew); it restarts when the method or the cluster settings change.
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.temporal_weight,
        value_parser = Settings::TEMPORAL_WEIGHT.parser(),
    ))]
    pub temporal_weight: f32,
    /// quadtree-tiles: split a cluster while a bound of its irradiance at any pixel of the tile
    /// (or its estimated error, --tile-criterion) exceeds this fraction of the tile's estimated
    /// irradiance (0: every VPL); default: [`TileCriterion::default_error`], 0.05 for the bound
    /// and 0.002 for the estimate.
    #[cfg_attr(feature = "cli", arg(long, value_parser = Settings::TILE_ERROR.parser()))]
    pub tile_error: Option<f32>,
    /// quadtree-tiles: what is compared with --tile-error: bound (an upper bound of the
    /// cluster's irradiance at the tile) or estimate (the estimated error of keeping the
    /// cluster rather than its children, the largest |E(node) - sum of E(children)| at a few of
    /// the tile's pixels, where the bound is over the threshold).
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value_t = Settings::DEFAULT.tile_criterion)
    )]
    pub tile_criterion: TileCriterion,
    /// quadtree-tiles: the most clusters a tile's cut holds; past it refinement stops (counted
    /// as [`crate::WorkCounts::refused_splits`]). The lists take 4 bytes a node and tile of GPU
    /// memory (8 with --indirect-shadows, for the shadow rays' targets, 12 and 204 a tile with
    /// --tile-passes split, for their visibility and the tile's anchors), each buffer at most
    /// [`Self::MAX_TILE_LIST_BYTES`]; default: 1024, less where the picture's
    /// lists would take over [`Self::DEFAULT_TILE_LIST_BYTES`] (256 at 1920x1080).
    #[cfg_attr(feature = "cli", arg(long, value_parser = Settings::TILE_CAPACITY.parser()))]
    pub tile_capacity: Option<u32>,
    /// quadtree-tiles: gather a cluster farther from the tile's pixels than this times their
    /// box's diagonal (and in front of the tile's corners) once at each corner of the tile, as
    /// vector irradiance, and interpolate it (a receiver hierarchy, as in Multidimensional
    /// Lightcuts; 0: every pixel evaluates every cluster).
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.tile_share,
        value_parser = Settings::TILE_SHARE.parser(),
    ))]
    pub tile_share: f32,
    /// quadtree-tiles with --indirect-shadows: a cluster takes the visibility of its highest
    /// ancestor whose box's diagonal is at most this times its distance from the tile's pixels
    /// (half this for an ancestor of several surfaces), so that a tile walks once to that
    /// ancestor's mean rather than to each of its listed clusters (0: each cluster its own).
    /// Chosen on the visibility scenes tuned on: from 0.15 to 0.6 their FLIP stays within 2% of
    /// 0.3's and the fetches fall with the angle (BENCHMARKS.md, "Indirect shadows on scenes nobody
    /// tuned on").
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.tile_shadow_angle,
        value_parser = Settings::TILE_SHADOW_ANGLE.parser(),
    ))]
    pub tile_shadow_angle: f32,
    /// quadtree-tiles with --indirect-shadows: fused (one kernel a tile builds the tile's cut in
    /// workgroup memory, walks the shadow rays from the tile's anchors and sums, between
    /// barriers) or split (that kernel builds the cut and its shadow targets into storage, a pass
    /// with almost no workgroup memory walks the rays, several a lane, and a per-pixel pass
    /// sums). The same picture; the split is a candidate for the GPU, where the fused kernel's
    /// walks cost five times a per-pixel pass's a fetch: its kilobytes of workgroup memory leave
    /// few waves resident to hide their latency (docs/known-problems.md). Without indirect
    /// shadows the kernel is fused either way.
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value_t = Settings::DEFAULT.tile_passes)
    )]
    pub tile_passes: TilePasses,
    /// quadtree-tiles with --tile-passes split: the threads that walk one tile's shadow rays (a
    /// power of two, 4 to 64), each whole targets at a time (all their anchors' rays), 64 /
    /// N tiles a workgroup of 64. Fewer lanes a tile give each lane more rays, so that a
    /// wave's lanes end closer together; more spread a tile's walks over more of the GPU. The
    /// same picture.
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.tile_walk_lanes,
        value_parser = Settings::TILE_WALK_LANES.parser(),
    ))]
    pub tile_walk_lanes: u32,
    /// quadtree-tiles: pixels on either side of each tile boundary over which a step in the
    /// indirect light that the neighbours' slopes do not explain is spread, where those pixels
    /// lie on one surface (neighbouring tiles' cuts differ, so their light steps where the truth
    /// is smooth; 0: off).
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.tile_deblock,
        value_parser = Settings::TILE_DEBLOCK.parser(),
    ))]
    pub tile_deblock: u32,
}

impl Default for Settings {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl Settings {
    /// Every parameter's default (the flags' defaults too).
    pub const DEFAULT: Settings = Settings {
        size: Size::new(512, 512),
        rsm_size: 512,
        shadow_map_size: None,
        max_lights: 4,
        gbuffer_layout: GBufferLayout::Compact,
        cluster: ClusterSettings::DEFAULT,
        samples: 256,
        rsm_radius: 1.0,
        subsample: 1,
        interleave: 1,
        indirect_shadows: false,
        shadow_corners: None,
        shadow_corner_lanes: 64,
        shadow_steps: 8,
        shadow_thickness: 0.03,
        shadow_grid: 64,
        shadow_grid_levels: 2,
        temporal_weight: 1.0,
        tile_error: None,
        tile_criterion: TileCriterion::Estimate,
        tile_capacity: None,
        tile_share: 2.0,
        tile_shadow_angle: 0.3,
        tile_passes: TilePasses::Fused,
        tile_walk_lanes: 16,
        tile_deblock: 3,
    };

    /// Either side of [`Settings::size`].
    pub const SIDE: Limits<u32> = Limits::closed(1, 8192);
    /// [`Settings::rsm_size`] (also a power of two): 1024^2 VPLs make a 67 MB quadtree, within
    /// every adapter's storage-buffer limit.
    pub const RSM_SIZE: Limits<u32> = Limits::closed(4, 1024).interactive(8, 1024);
    /// [`Settings::shadow_map_size`] (also a power of two): an 8192^2 map takes 256 MB.
    pub const SHADOW_MAP_SIZE: Limits<u32> = Limits::closed(16, 8192).interactive(256, 4096);
    /// The range [`Settings::shadow_map_size_or_default`] keeps a derived side within.
    pub const DEFAULT_SHADOW_MAP_SIZES: (u32, u32) = (256, 2048);
    /// [`Settings::max_lights`].
    pub const MAX_LIGHTS: Limits<u32> = Limits::closed(1, 16);
    /// [`Settings::samples`].
    pub const SAMPLES: Limits<u32> = Limits::closed(1, 65536).interactive(1, 2048);
    /// [`Settings::rsm_radius`].
    pub const RSM_RADIUS: Limits<f32> = Limits::above(0.0, 1.0);
    /// [`Settings::subsample`].
    pub const SUBSAMPLE: Limits<u32> = Limits::closed(1, 64).interactive(1, 8);
    /// [`Settings::interleave`] (also a power of two): at 4 a pixel sums 1/16 of the cut (its
    /// parts are the cut's classes, 4x4 of them: `CUT_CLASS_SIDE`); the filter that rejoins the
    /// parts holds its workgroup's pixels and 2 (N - 1) more across and down in workgroup
    /// memory (9.4 KB at 4).
    pub const INTERLEAVE: Limits<u32> = Limits::closed(1, 4);
    /// [`Settings::shadow_corners`].
    pub const SHADOW_CORNERS: Limits<u32> = Limits::closed(0, 64);
    /// The corners across the picture's longer side by default ([`Settings::shadow_corners`]):
    /// at 128x128 with corners every 2 pixels (64 across) the one cut's FLIP to the truth was
    /// its pixels' own walks' within 1% or better on all nine visibility scenes, every 4 pixels
    /// (32 across) 30% worse on the shelf held apart from tuning (BENCHMARKS.md): this is
    /// nearly twice the 64 (at 1920x1080, 8,228 corners).
    pub const SHADOW_CORNERS_ACROSS: u32 = 120;
    /// The clusters of a cut whose visibility each corner of [`Settings::shadow_corners`] keeps
    /// (a pixel walks to those beyond alone): 4096 bits, 512 bytes a corner.
    pub const SHADOW_CORNER_CLUSTERS: u32 = 4096;
    /// [`Settings::tile_walk_lanes`]: a workgroup of 64 threads holds one to sixteen tiles' walks
    /// (wgsl `MOST_WALKED_TILES`, sixteen).
    pub const TILE_WALK_LANES: Limits<u32> = Limits::closed(4, 64);
    /// [`Settings::shadow_corner_lanes`]: a workgroup of 64 threads holds one to eight corners.
    pub const SHADOW_CORNER_LANES: Limits<u32> = Limits::closed(8, 64);
    /// [`Settings::shadow_steps`].
    pub const SHADOW_STEPS: Limits<u32> = Limits::closed(1, 64);
    /// [`Settings::shadow_thickness`].
    pub const SHADOW_THICKNESS: Limits<f32> = Limits::above(0.0, 1.0);
    /// [`Settings::shadow_grid`]: 512 cells a side take 17 MB.
    pub const SHADOW_GRID: Limits<u32> = Limits::closed(0, 512);
    /// [`Settings::shadow_grid_levels`].
    pub const SHADOW_GRID_LEVELS: Limits<u32> = Limits::closed(1, 2);
    /// The most cells of [`Settings::shadow_grid`] with 2 levels: a grid whose every cell is
    /// set takes 2 words a cell, 135^3 cells with the margins, 20 MB.
    pub const MAX_TWO_LEVEL_SHADOW_GRID: u32 = 128;
    /// [`Settings::temporal_weight`].
    pub const TEMPORAL_WEIGHT: Limits<f32> = Limits::above(0.0, 1.0);
    /// [`Settings::tile_error`].
    pub const TILE_ERROR: Limits<f32> = Limits::closed(0.0, f32::MAX).interactive(0.0002, 1.0);
    /// [`Settings::tile_capacity`]: up to what a tile's frontier holds in workgroup memory.
    pub const TILE_CAPACITY: Limits<u32> = Limits::closed(1, TILE_FRONTIER);
    /// [`Settings::tile_share`].
    pub const TILE_SHARE: Limits<f32> = Limits::closed(0.0, 1000.0).interactive(0.0, 8.0);
    /// [`Settings::tile_shadow_angle`].
    pub const TILE_SHADOW_ANGLE: Limits<f32> = Limits::closed(0.0, 100.0).interactive(0.0, 2.0);
    /// [`Settings::tile_deblock`]: a boundary's pixels and the one beyond on either side stay
    /// within its two tiles, so that no two boundaries share a pixel.
    pub const TILE_DEBLOCK: Limits<u32> = Limits::closed(0, TILE / 2 - 1);

    /// Bytes the per-tile cuts' lists may take, a storage buffer every adapter binds.
    pub const MAX_TILE_LIST_BYTES: u64 = 128 << 20;
    /// Bytes the corners of [`Settings::shadow_corners`] may take (the same binding limit).
    pub const MAX_SHADOW_CORNER_BYTES: u64 = 128 << 20;

    /// Bytes the per-tile cuts' lists take by default at most. A large picture's tiles cover
    /// less of the scene and need fewer clusters (BENCHMARKS.md, "Per-tile cuts").
    pub const DEFAULT_TILE_LIST_BYTES: u64 = 32 << 20;

    /// The defaults for a `width` x `height` picture lit through an `rsm_size`^2 RSM.
    pub fn sized(width: u32, height: u32, rsm_size: u32) -> Self {
        Self {
            size: Size::new(width, height),
            rsm_size,
            ..Self::DEFAULT
        }
    }

    /// The levels the cut spans ([`ClusterSettings::levels`] on this RSM).
    pub fn levels(&self) -> Levels {
        self.cluster.levels(self.rsm_size)
    }

    /// The per-tile cuts' threshold: [`Settings::tile_error`], else its criterion's default.
    pub fn tile_error_or_default(&self) -> f32 {
        self.tile_error
            .unwrap_or(self.tile_criterion.default_error())
    }

    /// The per-tile cuts' list capacity: [`Settings::tile_capacity`], else the largest power of
    /// two up to [`Self::TILE_CAPACITY`]'s maximum whose lists fit
    /// [`Self::DEFAULT_TILE_LIST_BYTES`] (1,024 up to 512x512, 256 at 1920x1080).
    pub fn tile_capacity_or_default(&self) -> u32 {
        self.tile_capacity
            .unwrap_or_else(|| Self::tile_capacity_within(self.size, Self::DEFAULT_TILE_LIST_BYTES))
    }

    /// The side of the direct light's shadow maps: [`Settings::shadow_map_size`], else twice
    /// the picture's longer side rounded up to a power of two, within
    /// [`Self::DEFAULT_SHADOW_MAP_SIZES`].
    pub fn shadow_map_size_or_default(&self) -> u32 {
        let (least, most) = Self::DEFAULT_SHADOW_MAP_SIZES;
        self.shadow_map_size.unwrap_or_else(|| {
            (2 * self.size.width.max(self.size.height))
                .next_power_of_two()
                .clamp(least, most)
        })
    }

    /// The corner receivers of the one cut's indirect shadows across and down the picture
    /// ([`Settings::shadow_corners`]; at least 1 each way, zeros when off): one every K pixels
    /// from the first, and the last pixel.
    pub(crate) fn shadow_corner_grid(&self) -> (u32, u32) {
        match self.shadow_corners_or_off() {
            0 => (0, 0),
            k => (
                self.size.width.saturating_sub(1).div_ceil(k) + 1,
                self.size.height.saturating_sub(1).div_ceil(k) + 1,
            ),
        }
    }

    /// The spacing of the one cut's shadow corners: [`Settings::shadow_corners`], else the
    /// picture's longer side over [`Self::SHADOW_CORNERS_ACROSS`], rounded, or 0 (each pixel
    /// walks) where that is no more than [`Settings::interleave`].
    pub fn shadow_corners_or_default(&self) -> u32 {
        let across = Self::SHADOW_CORNERS_ACROSS;
        self.shadow_corners.unwrap_or_else(|| {
            let spacing = ((self.size.width.max(self.size.height) + across / 2) / across)
                .min(Self::SHADOW_CORNERS.max);
            if spacing > self.interleave {
                spacing
            } else {
                0
            }
        })
    }

    /// [`Settings::shadow_corners_or_default`] with indirect shadows, else 0.
    pub(crate) fn shadow_corners_or_off(&self) -> u32 {
        if self.indirect_shadows {
            self.shadow_corners_or_default()
        } else {
            0
        }
    }

    /// The words of visibility bits a corner keeps: one a cluster of the cut, up to
    /// [`Settings::SHADOW_CORNER_CLUSTERS`] and the finest cut's size (0 when off).
    pub(crate) fn shadow_corner_words(&self) -> u32 {
        if self.shadow_corners_or_off() == 0 {
            return 0;
        }
        let finest = u64::from(self.rsm_size >> self.levels().limit).pow(2);
        finest
            .min(u64::from(Self::SHADOW_CORNER_CLUSTERS))
            .div_ceil(32) as u32
    }

    /// The bytes of the corners' visibility bits and receivers ([`Settings::shadow_corners`]).
    pub(crate) fn shadow_corner_bytes(&self) -> u64 {
        let (x, y) = self.shadow_corner_grid();
        u64::from(x) * u64::from(y) * (4 * u64::from(self.shadow_corner_words()) + 32)
    }

    /// Points marched per receiver and cluster: [`Settings::shadow_steps`] with indirect
    /// shadows, else 0.
    pub fn march_steps(&self) -> u32 {
        if self.indirect_shadows {
            self.shadow_steps
        } else {
            0
        }
    }

    /// These settings with every default that depends on another setting written out (the
    /// levels, the tile threshold and capacity): what the stats record.
    pub fn resolved(&self) -> Settings {
        let levels = self.levels();
        Settings {
            cluster: ClusterSettings {
                start_level: Some(levels.start),
                limit_level: Some(levels.limit),
                ..self.cluster
            },
            tile_error: Some(self.tile_error_or_default()),
            tile_capacity: Some(self.tile_capacity_or_default()),
            shadow_map_size: Some(self.shadow_map_size_or_default()),
            shadow_corners: Some(self.shadow_corners_or_default()),
            ..self.clone()
        }
    }

    /// The largest power of two up to [`Self::TILE_CAPACITY`]'s maximum whose lists for a
    /// picture of `size` fit `bytes` (at least 1).
    fn tile_capacity_within(size: Size, bytes: u64) -> u32 {
        let tiles = u64::from(size.width.div_ceil(TILE)) * u64::from(size.height.div_ceil(TILE));
        let fits = bytes / 4 / tiles.max(1);
        let capacity = u64::from(Self::TILE_CAPACITY.max).min(fits).max(1);
        1 << capacity.ilog2()
    }

    /// Whether `method` gathers into the low-resolution samples and reconstructs the picture from
    /// them (sub-sampled or interleaved).
    pub fn reconstructs(&self, method: crate::Method) -> bool {
        method.subsamples() && (self.subsample > 1 || self.interleave > 1)
    }

    /// The low-resolution samples across and down the picture (one per `subsample`^2 pixels).
    pub(crate) fn low_size(&self) -> (u32, u32) {
        (
            self.size.width.div_ceil(self.subsample),
            self.size.height.div_ceil(self.subsample),
        )
    }

    /// Tiles of [`TILE`]^2 pixels across and down the picture (per-tile cuts).
    pub(crate) fn tiles(&self) -> (u32, u32) {
        (
            self.size.width.div_ceil(TILE),
            self.size.height.div_ceil(TILE),
        )
    }

    /// Bytes the per-tile cuts' lists take ([`Settings::tile_capacity`] node indices a tile).
    pub(crate) fn tile_list_bytes(&self) -> u64 {
        let (tx, ty) = self.tiles();
        u64::from(tx) * u64::from(ty) * u64::from(self.tile_capacity_or_default()) * 4
    }

    /// Whether the per-tile cuts run as three passes ([`Settings::tile_passes`] split, with
    /// indirect shadows).
    pub(crate) fn splits_tiles(&self) -> bool {
        self.tile_passes == TilePasses::Split && self.march_steps() > 0
    }

    /// Bytes the split per-tile passes' shadow records take ([`TILE_SHADOW_HEADER`] words a
    /// tile, then a word a list slot; 4 where the passes are fused).
    pub(crate) fn tile_shadow_bytes(&self) -> u64 {
        if !self.splits_tiles() {
            return 4;
        }
        let (tx, ty) = self.tiles();
        let words = u64::from(TILE_SHADOW_HEADER) + u64::from(self.tile_capacity_or_default());
        u64::from(tx) * u64::from(ty) * words * 4
    }

    /// The level whose nodes make a tile's coarse estimate of its irradiance (per-tile cuts): the
    /// quadtree's start level, or a coarser one where its nodes would outnumber a tile's list.
    pub(crate) fn tile_start_level(&self) -> u32 {
        let top = self.rsm_size.ilog2();
        let capacity = self.tile_capacity_or_default();
        (self.levels().start..top)
            .find(|&level| (self.rsm_size >> level).pow(2) <= capacity)
            .unwrap_or(top)
    }

    /// Refuses sizes and parameters that would make no picture or an absurd amount of work.
    pub fn validate(&self) -> Result<(), String> {
        let s = self;
        check_size(&s.size)?;
        check_rsm_size(s.rsm_size)?;
        if let Some(size) = s.shadow_map_size {
            check_shadow_map_size(size)?;
        }
        let c = &s.cluster;
        for (what, level) in [
            ("start level", c.start_level),
            ("limit level", c.limit_level),
        ] {
            if let Some(level) = level {
                ClusterSettings::LEVEL.check(what, level)?;
            }
        }
        let top = s.rsm_size.ilog2();
        let levels = s.levels();
        if levels.start > top || levels.limit > levels.start {
            return Err(format!(
                "levels must satisfy limit ({}) <= start ({}) <= {top} (the 1x1 level of a {} RSM)",
                levels.limit, levels.start, s.rsm_size
            ));
        }
        ClusterSettings::DEPTH_THRESHOLD.check("depth threshold", c.depth_threshold)?;
        ClusterSettings::NORMAL_THRESHOLD.check("normal threshold", c.normal_threshold)?;
        Self::MAX_LIGHTS.check("max lights", s.max_lights)?;
        Self::SAMPLES.check("samples", s.samples)?;
        Self::RSM_RADIUS.check("RSM radius", s.rsm_radius)?;
        Self::SUBSAMPLE.check("subsample", s.subsample)?;
        Self::INTERLEAVE.check("interleave", s.interleave)?;
        if !s.interleave.is_power_of_two() {
            return Err(format!(
                "interleave {} must be a power of two (its parts are classes of the cut's \
                 {side}x{side})",
                s.interleave,
                side = Self::INTERLEAVE.max
            ));
        }
        if s.interleave > 1 && s.subsample > 1 {
            return Err(format!(
                "interleave {} and subsample {} cannot both be above 1: interleaved sampling \
                 rejoins full-resolution pixels",
                s.interleave, s.subsample
            ));
        }
        if let Some(spacing) = s.shadow_corners {
            Self::SHADOW_CORNERS.check("shadow corners", spacing)?;
        }
        Self::TILE_WALK_LANES.check("tile walk lanes", s.tile_walk_lanes)?;
        if !s.tile_walk_lanes.is_power_of_two() {
            return Err(format!(
                "tile walk lanes {} must be a power of two (a workgroup of 64 threads holds a whole number of tiles)",
                s.tile_walk_lanes
            ));
        }
        Self::SHADOW_CORNER_LANES.check("shadow corner lanes", s.shadow_corner_lanes)?;
        if !s.shadow_corner_lanes.is_power_of_two() {
            return Err(format!(
                "shadow corner lanes {} must be a power of two (a workgroup of 64 threads holds a whole number of corners)",
                s.shadow_corner_lanes
            ));
        }
        if s.shadow_corner_bytes() > Self::MAX_SHADOW_CORNER_BYTES {
            return Err(format!(
                "indirect shadows from corners every {} pixels of a {} picture take {} MiB, over {} MiB: raise the shadow corners' spacing",
                s.shadow_corners_or_default(),
                s.size,
                s.shadow_corner_bytes() >> 20,
                Self::MAX_SHADOW_CORNER_BYTES >> 20,
            ));
        }
        Self::SHADOW_STEPS.check("shadow steps", s.shadow_steps)?;
        Self::SHADOW_THICKNESS.check("shadow thickness", s.shadow_thickness)?;
        Self::SHADOW_GRID.check("shadow grid", s.shadow_grid)?;
        Self::SHADOW_GRID_LEVELS.check("shadow grid levels", s.shadow_grid_levels)?;
        if s.shadow_grid_levels > 1 && s.shadow_grid > Self::MAX_TWO_LEVEL_SHADOW_GRID {
            return Err(format!(
                "shadow grid {} with {} levels must be at most {} cells (its sub-cells take two \
                 words a set cell)",
                s.shadow_grid,
                s.shadow_grid_levels,
                Self::MAX_TWO_LEVEL_SHADOW_GRID
            ));
        }
        Self::TEMPORAL_WEIGHT.check("temporal weight", s.temporal_weight)?;
        if let Some(error) = s.tile_error {
            Self::TILE_ERROR.check("tile error", error)?;
        }
        if let Some(capacity) = s.tile_capacity {
            Self::TILE_CAPACITY.check("tile capacity", capacity)?;
        }
        Self::TILE_SHARE.check("tile share", s.tile_share)?;
        Self::TILE_SHADOW_ANGLE.check("tile shadow angle", s.tile_shadow_angle)?;
        Self::TILE_DEBLOCK.check("tile deblock", s.tile_deblock)?;
        let bytes = s.tile_list_bytes();
        if bytes > Self::MAX_TILE_LIST_BYTES {
            return Err(format!(
                "per-tile cuts of {} nodes for a {} picture take {} MiB, over {} MiB: lower the tile capacity to {} or less",
                s.tile_capacity_or_default(),
                s.size,
                bytes >> 20,
                Self::MAX_TILE_LIST_BYTES >> 20,
                Self::tile_capacity_within(s.size, Self::MAX_TILE_LIST_BYTES),
            ));
        }
        if s.tile_shadow_bytes() > Self::MAX_TILE_LIST_BYTES {
            return Err(format!(
                "split per-tile passes' shadow records for {} nodes a tile of a {} picture take {} MiB, over {} MiB: lower the tile capacity",
                s.tile_capacity_or_default(),
                s.size,
                s.tile_shadow_bytes() >> 20,
                Self::MAX_TILE_LIST_BYTES >> 20,
            ));
        }
        Ok(())
    }

    /// The `quadray indirect` flags that render these settings (the viewer prints them beside
    /// its screenshots; the CLI's tests parse them back): every clap argument with its serde
    /// field's value. Defaults left to their rules (`None`) stay unwritten.
    #[cfg(feature = "cli")]
    pub fn to_args(&self) -> Vec<String> {
        // serde flattens the size into `width` and `height`: the flag is `WxH`.
        quadray_core::settings::to_args(self, &[("size", self.size.to_string())])
    }
}

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

#[cfg(test)]
mod rules;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::method::Validity;

    /// Settings with every field off its default, every `Option` given and every switch
    /// flipped, and the defaults, come back through `to_args` and the clap arguments: a field
    /// left out of the flags, or written so that it parses otherwise, fails here (a new field
    /// first fails `flags_at_default` until it is given a value here).
    #[cfg(feature = "cli")]
    #[test]
    fn every_setting_comes_back_through_its_flags() {
        use quadray_core::settings::assert_flags_round_trip;
        let every = Settings {
            size: Size::new(96, 64),
            rsm_size: 256,
            shadow_map_size: Some(512),
            max_lights: 3,
            gbuffer_layout: GBufferLayout::Wide,
            cluster: ClusterSettings {
                start_level: Some(5),
                limit_level: Some(2),
                depth_threshold: 0.125,
                normal_threshold: -0.25,
                validity: Validity::Local,
                flux_weighted: false,
            },
            samples: 100,
            rsm_radius: 0.3,
            subsample: 2,
            interleave: 4,
            indirect_shadows: true,
            shadow_corners: Some(8),
            shadow_corner_lanes: 16,
            shadow_steps: 5,
            shadow_thickness: 0.1,
            shadow_grid: 0,
            shadow_grid_levels: 1,
            temporal_weight: 0.67,
            tile_error: Some(0.01),
            tile_criterion: TileCriterion::Bound,
            tile_capacity: Some(64),
            tile_share: 0.0,
            tile_shadow_angle: 0.5,
            tile_passes: TilePasses::Split,
            tile_walk_lanes: 4,
            tile_deblock: 1,
        };
        // (interleave and subsample exclude each other: each is checked alone)
        for valid in [
            Settings {
                interleave: 1,
                ..every.clone()
            },
            Settings {
                subsample: 1,
                ..every.clone()
            },
        ] {
            assert!(valid.validate().is_ok(), "{valid:?}");
        }
        assert_flags_round_trip(
            every,
            [Settings::DEFAULT, Settings::DEFAULT.resolved()],
            &Settings::DEFAULT.to_args(),
            Settings::to_args,
        );
    }
}
