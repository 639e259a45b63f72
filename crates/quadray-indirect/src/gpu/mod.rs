//! The GPU side, one file per pass, each owning its pipelines, layouts, bind groups and
//! recording, all recording into the caller's `wgpu::CommandEncoder` on the caller's device:
//! [`RsmPass`] (the spot's reflective shadow map; or bring your own [`RsmViews`]),
//! [`LightQuadtree`] (pyramid, validity, compacted cut), [`Gather`] (indirect light into the
//! caller's G-buffer from the cut or the paper's per-level passes, the baselines of the same
//! shape, the direct light) and [`OutputPass`] (the radiance into the caller's texture). Bindings
//! are grouped by how often they change: per light update, per frame, per dispatch.
//! [`Renderer`] is quadray's own user of these passes. The Rust <-> WGSL contract (shared
//! structs, the generated WGSL prelude) is in `contract.rs`.

mod contract;
mod gather;
mod gbuffer;
mod light;
mod output;
mod quadtree;
mod renderer;
mod rsm;

pub use gather::{GBufferViews, Gather};
pub use light::Spot;
pub use output::{OutputPass, OutputTerm};
pub use quadtree::LightQuadtree;
pub use renderer::Renderer;
pub use rsm::{FLOAT_FORMAT, RsmPass, RsmViews};

use serde::Serialize;
use std::collections::BTreeMap;

/// Every shader's parts (before the prelude), by pass: what the contract test parses.
#[cfg(test)]
pub(crate) fn shaders() -> Vec<(&'static str, Vec<String>)> {
    let owned = |parts: &[&str]| parts.iter().map(|p| p.to_string()).collect();
    vec![
        ("rsm", owned(&rsm::SOURCES)),
        ("gbuffer", owned(&gbuffer::SOURCES)),
        ("quadtree", owned(&quadtree::SOURCES)),
        ("gather", owned(&gather::SOURCES)),
        ("output", output::sources("rgba16float").to_vec()),
    ]
}

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
    /// (counted in [`WorkCounts::refused_splits`]). The lists take 4 bytes a node and tile of
    /// GPU memory, allocated by a [`Gather`]'s first frame of [`Method::QuadtreeTiles`], at most
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
    pub const MAX_TILE_CAPACITY: u32 = contract::TILE_FRONTIER;

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
        let tiles =
            u64::from(width.div_ceil(contract::TILE)) * u64::from(height.div_ceil(contract::TILE));
        let fits = bytes / 4 / tiles.max(1);
        let capacity = u64::from(Self::MAX_TILE_CAPACITY).min(fits).max(1);
        1 << capacity.ilog2()
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
        let bytes = gather::tile_list_bytes(s);
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

/// The timed passes, in `GpuTimer` order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Pass {
    /// The reflective shadow map from the spot.
    Rsm,
    /// The quadtree's levels: VPL means and spreads, coarser level from finer.
    Pyramid,
    /// Each node's validity under the thresholds.
    Validity,
    /// The cut: the valid clusters that replace the VPLs.
    Cut,
    /// The camera's G-buffer.
    GBuffer,
    /// The gather: each (sub-sampled) pixel sums the cut or its VPL samples.
    Indirect,
    /// Sub-sampled indirect light brought to full resolution.
    Upsample,
    /// The spot's direct light on the G-buffer.
    Direct,
}

impl Pass {
    /// Every pass, in the order a frame records them.
    pub const ALL: [Pass; 8] = [
        Pass::Rsm,
        Pass::Pyramid,
        Pass::Validity,
        Pass::Cut,
        Pass::GBuffer,
        Pass::Indirect,
        Pass::Upsample,
        Pass::Direct,
    ];

    /// The pass's key in [`FrameTiming::passes`] and the stats JSON.
    pub fn name(self) -> &'static str {
        match self {
            Pass::Rsm => "rsm",
            Pass::Pyramid => "pyramid",
            Pass::Validity => "validity",
            Pass::Cut => "cut",
            Pass::GBuffer => "gbuffer",
            Pass::Indirect => "indirect",
            Pass::Upsample => "upsample",
            Pass::Direct => "direct",
        }
    }
}

/// Median GPU time per pass (ms) over some frames; `total_ms` is the sum of the medians.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameTiming {
    /// Median ms of each pass the method ran, by [`Pass::name`].
    pub passes: BTreeMap<&'static str, f64>,
    /// Sum of the passes' medians, ms.
    pub total_ms: f64,
    /// Frames the medians are taken over.
    pub frames: u32,
}

/// One frame read back: linear radiance per pixel, row-major, top row first.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// One-bounce indirect radiance, what the methods differ in.
    pub indirect: Vec<[f32; 3]>,
    /// The spot's direct radiance, the same for every method.
    pub direct: Vec<[f32; 3]>,
    /// Pixels the upsampler recomputed at full resolution.
    pub recomputed: u32,
    /// The work the indirect passes did, counted in the shaders.
    pub counts: WorkCounts,
}

/// The work of a frame's indirect passes, counted by the shaders themselves: hardware-independent
/// figures to compare methods by. Every dispatch's work is counted, so a sum split into slices
/// reads the G-buffer once per slice, and the sub-sampled quadtree counts its low-resolution
/// samples and the pixels the upsampler recomputed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct WorkCounts {
    /// Pixels where the G-buffer has geometry: the ones shaded, what the means are over.
    pub shaded_pixels: u32,
    /// VPL kernels evaluated (a cluster counts one, an RSM sample one where its texel is a
    /// VPL), over all pixels.
    pub vpl_evaluations: u64,
    /// Reads of G-buffer texels, RSM texels, quadtree node records and low-resolution samples,
    /// over all pixels.
    pub texel_fetches: u64,
    /// Upper bounds of a node's contribution to a tile evaluated (per-tile cuts), over all
    /// tiles.
    pub bound_evaluations: u64,
    /// Splits a per-tile cut refused because the tile's list was full, over all tiles.
    pub refused_splits: u64,
}

impl WorkCounts {
    /// Mean VPL evaluations per shaded pixel.
    pub fn vpl_evaluations_per_pixel(&self) -> f64 {
        self.vpl_evaluations as f64 / f64::from(self.shaded_pixels.max(1))
    }

    /// Mean texel fetches per shaded pixel.
    pub fn texel_fetches_per_pixel(&self) -> f64 {
        self.texel_fetches as f64 / f64::from(self.shaded_pixels.max(1))
    }

    /// Mean bound evaluations per shaded pixel.
    pub fn bound_evaluations_per_pixel(&self) -> f64 {
        self.bound_evaluations as f64 / f64::from(self.shaded_pixels.max(1))
    }
}

impl Frame {
    /// Direct plus indirect radiance.
    pub fn combined(&self) -> Vec<[f32; 3]> {
        self.direct
            .iter()
            .zip(&self.indirect)
            .map(|(d, i)| std::array::from_fn(|c| d[c] + i[c]))
            .collect()
    }
}

/// A cluster of the cut: its level (0 = one RSM texel) and its node's column and row there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CutNode {
    /// Quadtree level, 0 being the RSM itself.
    pub level: u32,
    /// Column of the node at its level.
    pub x: u32,
    /// Row of the node at its level.
    pub y: u32,
}

impl CutNode {
    /// The node at `index` of the pyramid of an RSM of side `rsm_size` (finest level first).
    pub fn at(rsm_size: u32, mut index: u32) -> Self {
        let mut level = 0;
        while level < rsm_size.ilog2() && index >= (rsm_size >> level).pow(2) {
            index -= (rsm_size >> level).pow(2);
            level += 1;
        }
        let side = rsm_size >> level;
        Self {
            level,
            x: index % side,
            y: index / side,
        }
    }
}

/// A VPL as the RSM stores it (the CPU reference's input).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vpl {
    /// Flux the VPL's surface reflects (W).
    pub flux: [f32; 3],
    /// World position.
    pub position: [f32; 3],
    /// Unit normal facing the light.
    pub normal: [f32; 3],
}

/// A G-buffer texel (the CPU reference's receivers); `None` where the camera sees nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    /// World position.
    pub position: [f32; 3],
    /// Unit normal facing the camera.
    pub normal: [f32; 3],
    /// Diffuse albedo the gathered light is multiplied by.
    pub albedo: [f32; 3],
}

#[cfg(test)]
mod tests {
    use super::CutNode;

    #[test]
    fn cut_nodes_are_found_from_their_pyramid_index() {
        let size = 16u32;
        let mut index = 0;
        for level in 0..=size.ilog2() {
            let side = size >> level;
            for y in 0..side {
                for x in 0..side {
                    assert_eq!(CutNode::at(size, index), CutNode { level, x, y });
                    index += 1;
                }
            }
        }
    }
}
