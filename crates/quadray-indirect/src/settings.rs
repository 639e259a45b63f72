//! What a user configures: the sizes, the method and every method's parameters, and the rule
//! that refuses settings that make no picture. The bottom layer: plain values, no GPU.

use serde::Serialize;

/// Side of a tile of receivers that shares one per-tile cut (the gather's workgroup).
pub(crate) const TILE: u32 = 8;
/// Nodes a tile's frontier holds in workgroup memory (per-tile cuts, two levels of it): the
/// most a tile's list may hold ([`Settings::tile_capacity`]).
pub(crate) const TILE_FRONTIER: u32 = 1024;

/// How the indirect term is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Light quadtree, cut compacted once per light update and looped over per pixel.
    Quadtree,
    /// Light quadtree, the paper's one pass per level.
    QuadtreePasses,
    /// Light quadtree, a cut per tile of 8x8 pixels refined where a bound of a cluster's
    /// contribution to the tile exceeds [`Settings::tile_error`] of the tile's irradiance
    /// (Lightcuts with the quadtree as light tree); the validity rule and limit level are not
    /// used.
    QuadtreeTiles,
    /// RSM sampling with N Poisson-disk samples (baseline).
    Rsm,
    /// Every VPL (brute force on the GPU).
    Reference,
}

impl Method {
    /// Every method, in the order the CLI and the benchmark list them.
    pub const ALL: [Method; 5] = [
        Method::Quadtree,
        Method::QuadtreePasses,
        Method::QuadtreeTiles,
        Method::Rsm,
        Method::Reference,
    ];

    /// The method's name on the command line and in the stats (`--method`), kebab-case.
    pub fn name(self) -> &'static str {
        match self {
            Method::Quadtree => "quadtree",
            Method::QuadtreePasses => "quadtree-passes",
            Method::QuadtreeTiles => "quadtree-tiles",
            Method::Rsm => "rsm",
            Method::Reference => "reference",
        }
    }

    /// Whether [`Settings::subsample`] applies: the method can gather at low resolution and
    /// upsample (the compacted cut, and RSM sampling as the fair comparison).
    pub fn subsamples(self) -> bool {
        matches!(self, Method::Quadtree | Method::Rsm)
    }

    /// Whether the method uses the one cut of the light quadtree (so a cluster count means
    /// something for it).
    pub fn uses_quadtree(self) -> bool {
        matches!(self, Method::Quadtree | Method::QuadtreePasses)
    }

    /// Whether the method reads the light quadtree (one cut, or a cut per tile).
    pub fn builds_quadtree(self) -> bool {
        self.uses_quadtree() || self == Method::QuadtreeTiles
    }
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        quadray_core::parse_named(s, &Self::ALL, Self::name, "method")
    }
}

/// When a per-tile cut splits a node ([`Settings::tile_criterion`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TileCriterion {
    /// While an upper bound of its irradiance at any receiver of the tile exceeds
    /// [`Settings::tile_error`] of the tile's estimated irradiance (Lightcuts).
    Bound,
    /// While the estimated error of keeping it, the largest |E(node) - sum of E(children)| at
    /// the tile's sample pixels (those of the tile's estimate), exceeds that; nodes whose bound
    /// is already below it are kept without an estimate.
    Estimate,
}

impl TileCriterion {
    /// Both criteria, in the order the CLI lists them.
    pub const ALL: [TileCriterion; 2] = [TileCriterion::Bound, TileCriterion::Estimate];

    /// The default [`Settings::tile_error`] of the criterion (see BENCHMARKS.md, "Per-tile
    /// cuts"): a node's estimated error is far below its bound.
    pub fn default_error(self) -> f32 {
        match self {
            TileCriterion::Bound => 0.05,
            TileCriterion::Estimate => 0.002,
        }
    }

    /// The criterion's name on the command line and in the stats (`--tile-criterion`).
    pub fn name(self) -> &'static str {
        match self {
            TileCriterion::Bound => "bound",
            TileCriterion::Estimate => "estimate",
        }
    }
}

impl std::str::FromStr for TileCriterion {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        quadray_core::parse_named(s, &Self::ALL, Self::name, "tile criterion")
    }
}

/// Which clusters count as valid (see the spec).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Validity {
    /// The paper's: the 4 children against their mean.
    Local,
    /// Also every child valid.
    Recursive,
}

impl std::str::FromStr for Validity {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "local" => Ok(Validity::Local),
            "recursive" => Ok(Validity::Recursive),
            _ => Err(format!("unknown validity rule `{s}` (local, recursive)")),
        }
    }
}

/// The light quadtree's parameters. Levels are mip levels: 0 is the RSM itself (one VPL per
/// node), each level halves the side.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ClusterSettings {
    /// The coarsest level a cluster may be: the cut starts from this level's nodes.
    pub start_level: u32,
    /// The finest level a cluster may be: nodes below it are never visited (0: single VPLs).
    pub limit_level: u32,
    /// A node is valid only where each child's depth (along the light's axis, in units of the
    /// spot's extent) is closer than this to the node's mean.
    pub depth_threshold: f32,
    /// A node is valid only where each child's normal has a dot product above this with the
    /// node's mean normal.
    pub normal_threshold: f32,
    /// Which nodes' validity a node's own depends on.
    pub validity: Validity,
    /// Means weighted by flux luminance (else by texel count).
    pub flux_weighted: bool,
}

impl ClusterSettings {
    /// Defaults for a given RSM: the paper's thresholds (depth 0.05, normal 0.9), start at 8x8 as
    /// in the paper, limit at 64x64 (the paper's level 4; its 32x32 limit leaves about 7% rel. L1
    /// error on the Cornell box, most of it at the limit level), and the recursive rule: on a
    /// 512^2 RSM the local rule leaves 5.1% with 360 clusters, the recursive 3.8% with 633, less
    /// than the local rule reaches with the same time at a finer limit (4.4% with 589).
    pub fn defaults(rsm_size: u32) -> Self {
        Self {
            validity: Validity::Recursive,
            ..Self::with_limit_side(rsm_size, 64)
        }
    }

    /// The paper's settings (local rule) with the limit level where nodes are `side` x `side`
    /// (16, 32, 64 in table 1).
    pub fn with_limit_side(rsm_size: u32, side: u32) -> Self {
        let top = rsm_size.ilog2();
        Self {
            start_level: top.saturating_sub(3),
            limit_level: top.saturating_sub(side.max(1).ilog2()),
            depth_threshold: 0.05,
            normal_threshold: 0.9,
            validity: Validity::Local,
            flux_weighted: true,
        }
    }

    /// Every cluster a single VPL: the cut is the whole RSM.
    pub fn every_vpl(rsm_size: u32) -> Self {
        Self {
            limit_level: 0,
            depth_threshold: 0.0,
            ..Self::defaults(rsm_size)
        }
    }
}

/// Sizes and the parameters of every method.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Settings {
    /// Picture width in pixels.
    pub width: u32,
    /// Picture height in pixels.
    pub height: u32,
    /// Side of the square RSM in texels (a power of two): how many VPLs the spot makes.
    pub rsm_size: u32,
    /// The quadtree's parameters, for the quadtree methods.
    pub cluster: ClusterSettings,
    /// RSM-sampling samples per pixel.
    pub samples: u32,
    /// Sampling radius as a fraction of the RSM's diagonal.
    pub rsm_radius: f32,
    /// Indirect at one sample per `subsample`^2 pixels (1: full resolution), for the methods
    /// that [`Method::subsamples`]: the low-resolution samples are upsampled where the
    /// geometry agrees and the other pixels recomputed at full resolution.
    pub subsample: u32,
    /// Indirect shadows for the quadtree methods: points marched between each receiver and
    /// cluster, tested against the camera's and the light's depth (0: none, as in the paper).
    /// The per-tile cuts march from each tile's four corner receivers only, and a pixel weighs
    /// each cluster by the corners' visibility interpolated (a pixel off the corners' surface,
    /// across a depth edge, marches its own).
    pub shadow_steps: u32,
    /// How far behind a surface a depth map sees a marched point counts as inside an occluder,
    /// as a fraction of the scene's extent.
    pub shadow_thickness: f32,
    /// Weight of this frame's indirect light in a running average over frames (1: no filter),
    /// for every method but the brute force. Damps the popping of the cut under a moving light
    /// (see BENCHMARKS.md); the average is not reprojected, so it restarts whenever the camera,
    /// the method or the cluster settings change.
    pub temporal_weight: f32,
    /// Per-tile cuts ([`Method::QuadtreeTiles`]): a node is split while an upper bound of its
    /// irradiance at any pixel of the tile exceeds this fraction of the tile's estimated
    /// irradiance (0: every VPL on its own), or while its estimated error does
    /// ([`Settings::tile_criterion`]).
    pub tile_error: f32,
    /// Per-tile cuts: what is compared with [`Settings::tile_error`] of the tile's irradiance.
    pub tile_criterion: TileCriterion,
    /// Per-tile cuts: the most nodes a tile's cut may hold (1..=1024); past it refinement stops
    /// (counted in [`crate::WorkCounts::refused_splits`]). The lists take 4 bytes a node and tile of
    /// GPU memory, allocated by a [`crate::Gather`]'s first frame of [`Method::QuadtreeTiles`], at most
    /// [`Self::MAX_TILE_LIST_BYTES`] ([`Self::tile_capacity_for`] keeps the default within
    /// [`Self::DEFAULT_TILE_LIST_BYTES`]).
    pub tile_capacity: u32,
    /// Per-tile cuts: a node of a tile's cut farther from the tile's receivers than this times
    /// their box's diagonal (and in front of the tile's corner receivers) is evaluated once at
    /// each corner of the tile, as vector irradiance, and interpolated bilinearly to its pixels
    /// (a receiver hierarchy, as in Multidimensional Lightcuts); pixels off the corners'
    /// surface evaluate it themselves. 0: every pixel evaluates every node.
    pub tile_share: f32,
}

impl Default for Settings {
    fn default() -> Self {
        Self::sized(512, 512, 512)
    }
}

impl Settings {
    /// The defaults for a `width` x `height` picture lit through an `rsm_size`^2 RSM (the cut's
    /// limits follow the RSM's size).
    pub fn sized(width: u32, height: u32, rsm_size: u32) -> Self {
        Self {
            width,
            height,
            rsm_size,
            cluster: ClusterSettings::defaults(rsm_size),
            samples: 256,
            rsm_radius: 1.0,
            subsample: 1,
            shadow_steps: 0,
            shadow_thickness: 0.1,
            temporal_weight: 1.0,
            tile_error: TileCriterion::Bound.default_error(),
            tile_criterion: TileCriterion::Bound,
            tile_capacity: Self::tile_capacity_for(width, height),
            tile_share: 0.0,
        }
    }

    /// The largest [`Settings::tile_capacity`], what a tile's frontier holds in workgroup memory.
    pub const MAX_TILE_CAPACITY: u32 = TILE_FRONTIER;

    /// Bytes the per-tile cuts' lists may take, a storage buffer every adapter binds.
    pub const MAX_TILE_LIST_BYTES: u64 = 128 << 20;

    /// Bytes the per-tile cuts' lists take by default at most. A large picture's tiles cover
    /// less of the scene and need fewer clusters (BENCHMARKS.md, "Per-tile cuts").
    pub const DEFAULT_TILE_LIST_BYTES: u64 = 32 << 20;

    /// The default [`Settings::tile_capacity`] of a `width` x `height` picture: the largest
    /// power of two up to [`Self::MAX_TILE_CAPACITY`] whose lists fit
    /// [`Self::DEFAULT_TILE_LIST_BYTES`] (1,024 up to 512x512, 256 at 1920x1080).
    pub fn tile_capacity_for(width: u32, height: u32) -> u32 {
        Self::tile_capacity_within(width, height, Self::DEFAULT_TILE_LIST_BYTES)
    }

    /// The largest power of two up to [`Self::MAX_TILE_CAPACITY`] whose lists for a `width` x
    /// `height` picture fit `bytes` (at least 1).
    fn tile_capacity_within(width: u32, height: u32, bytes: u64) -> u32 {
        let tiles = u64::from(width.div_ceil(TILE)) * u64::from(height.div_ceil(TILE));
        let fits = bytes / 4 / tiles.max(1);
        let capacity = u64::from(Self::MAX_TILE_CAPACITY).min(fits).max(1);
        1 << capacity.ilog2()
    }

    /// The low-resolution samples across and down the picture (one per `subsample`^2 pixels).
    pub(crate) fn low_size(&self) -> (u32, u32) {
        (
            self.width.div_ceil(self.subsample),
            self.height.div_ceil(self.subsample),
        )
    }

    /// Tiles of [`TILE`]^2 pixels across and down the picture (per-tile cuts).
    pub(crate) fn tiles(&self) -> (u32, u32) {
        (self.width.div_ceil(TILE), self.height.div_ceil(TILE))
    }

    /// Bytes the per-tile cuts' lists take ([`Settings::tile_capacity`] node indices a tile).
    pub(crate) fn tile_list_bytes(&self) -> u64 {
        let (tx, ty) = self.tiles();
        u64::from(tx) * u64::from(ty) * u64::from(self.tile_capacity) * 4
    }

    /// The level whose nodes make a tile's coarse estimate of its irradiance (per-tile cuts): the
    /// quadtree's start level, or a coarser one where its nodes would outnumber a tile's list.
    pub(crate) fn tile_start_level(&self) -> u32 {
        let top = self.rsm_size.ilog2();
        (self.cluster.start_level..top)
            .find(|&level| (self.rsm_size >> level).pow(2) <= self.tile_capacity)
            .unwrap_or(top)
    }

    /// A [`Settings::temporal_weight`] for a light that moves under a still camera: on the
    /// Cornell box and the atrium at 1 degree a frame it brings the image's frame-to-frame
    /// change down to the brute force's, for a few percent more error against each frame's
    /// brute force (BENCHMARKS.md, "A moving light").
    pub const MOVING_LIGHT_TEMPORAL_WEIGHT: f32 = 0.33;

    /// Refuses sizes and parameters that would make no picture or an absurd amount of work.
    pub fn validate(&self) -> Result<(), String> {
        let s = self;
        if !(1..=8192).contains(&s.width) || !(1..=8192).contains(&s.height) {
            return Err(format!("size {}x{} is outside 1..8192", s.width, s.height));
        }
        // 1024^2 VPLs make a 67 MB quadtree, within every adapter's storage-buffer limit
        if !s.rsm_size.is_power_of_two() || !(4..=1024).contains(&s.rsm_size) {
            return Err(format!(
                "RSM size {} must be a power of two in 4..1024",
                s.rsm_size
            ));
        }
        let top = s.rsm_size.ilog2();
        let c = &s.cluster;
        if c.start_level > top || c.limit_level > c.start_level {
            return Err(format!(
                "levels must satisfy limit ({}) <= start ({}) <= {top} (the 1x1 level of a {} RSM)",
                c.limit_level, c.start_level, s.rsm_size
            ));
        }
        if !(c.depth_threshold.is_finite() && c.depth_threshold >= 0.0) {
            return Err(format!(
                "depth threshold {} must be >= 0",
                c.depth_threshold
            ));
        }
        if !(c.normal_threshold.is_finite() && (-1.0..=1.0).contains(&c.normal_threshold)) {
            return Err(format!(
                "normal threshold {} is outside [-1, 1]",
                c.normal_threshold
            ));
        }
        if !(1..=65536).contains(&s.samples) {
            return Err(format!("{} samples is outside 1..65536", s.samples));
        }
        if !(s.rsm_radius.is_finite() && s.rsm_radius > 0.0 && s.rsm_radius <= 1.0) {
            return Err(format!("RSM radius {} is outside (0, 1]", s.rsm_radius));
        }
        if !(1..=64).contains(&s.subsample) {
            return Err(format!("subsample {} is outside 1..64", s.subsample));
        }
        if s.shadow_steps > 64 {
            return Err(format!("{} shadow steps is over 64", s.shadow_steps));
        }
        if !(s.shadow_thickness.is_finite()
            && s.shadow_thickness > 0.0
            && s.shadow_thickness <= 1.0)
        {
            return Err(format!(
                "shadow thickness {} is outside (0, 1]",
                s.shadow_thickness
            ));
        }
        if !(s.temporal_weight.is_finite() && s.temporal_weight > 0.0 && s.temporal_weight <= 1.0) {
            return Err(format!(
                "temporal weight {} is outside (0, 1]",
                s.temporal_weight
            ));
        }
        if !(s.tile_error.is_finite() && s.tile_error >= 0.0) {
            return Err(format!("tile error {} must be >= 0", s.tile_error));
        }
        if !(s.tile_share.is_finite() && (0.0..=1000.0).contains(&s.tile_share)) {
            return Err(format!("tile share {} must be in 0..1000", s.tile_share));
        }
        if !(1..=Self::MAX_TILE_CAPACITY).contains(&s.tile_capacity) {
            return Err(format!(
                "tile capacity {} is outside 1..{}",
                s.tile_capacity,
                Self::MAX_TILE_CAPACITY
            ));
        }
        let bytes = s.tile_list_bytes();
        if bytes > Self::MAX_TILE_LIST_BYTES {
            return Err(format!(
                "per-tile cuts of {} nodes for a {}x{} picture take {} MiB, over {} MiB: lower the tile capacity to {} or less",
                s.tile_capacity,
                s.width,
                s.height,
                bytes >> 20,
                Self::MAX_TILE_LIST_BYTES >> 20,
                Self::tile_capacity_within(s.width, s.height, Self::MAX_TILE_LIST_BYTES),
            ));
        }
        Ok(())
    }
}
