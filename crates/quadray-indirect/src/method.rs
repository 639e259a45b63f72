//! The named choices of the settings: the method that computes the indirect term, when a
//! per-tile cut splits a node, how the per-tile cuts' passes are laid out, and which clusters
//! count as valid. Each has its name on the command line and in the stats, and its list in the
//! order the CLI gives it.

use serde::Serialize;
use std::fmt;

/// How the indirect term is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Light quadtree, cut compacted once per light update and looped over per pixel.
    Quadtree,
    /// Light quadtree, the paper's one pass per level.
    QuadtreePasses,
    /// Light quadtree, a cut per tile of 8x8 pixels refined where a bound of a cluster's
    /// contribution to the tile exceeds [`crate::Settings::tile_error`] of the tile's irradiance
    /// (Lightcuts with the quadtree as light tree); the validity rule and limit level are not
    /// used.
    QuadtreeTiles,
    /// RSM sampling with N Poisson-disk samples (baseline).
    Rsm,
    /// Every VPL (brute force on the GPU).
    Reference,
}

impl Method {
    /// The method a user gets without choosing: the per-tile cuts (with
    /// [`TileCriterion::Estimate`] and far clusters shared at 2 tile extents, the
    /// [`crate::Settings::DEFAULT`]), which reach a given error with fewer VPL evaluations than the
    /// paper's one cut and than RSM sampling on every bundled scene but the atrium, where they
    /// still beat the one cut (BENCHMARKS.md, "The default method at equal error").
    pub const DEFAULT: Method = Method::QuadtreeTiles;

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

    /// Whether [`crate::Settings::subsample`] applies: the method can gather at low resolution and
    /// upsample (the compacted cut, and RSM sampling as the fair comparison).
    pub fn subsamples(self) -> bool {
        matches!(self, Method::Quadtree | Method::Rsm)
    }

    /// A [`crate::Settings::temporal_weight`] for the method's frames under a moving light and camera:
    /// on the Cornell box and the atrium at 1 degree a frame it brings the image's frame-to-frame
    /// change to the brute force's or below, for at most 15% more error against each frame's
    /// brute force (BENCHMARKS.md, "A moving light", "Light and camera moving"). The per-tile
    /// cuts pop less, so a lighter average does (0.67: flicker ratio 0.87-1.03 at 1.01-1.06x the
    /// error; at 0.5 the lag cost the atrium 1.15x); the one cut needs 0.33 (at 0.5 its flicker
    /// ratio stays at 1.3-1.5).
    pub fn moving_light_temporal_weight(self) -> f32 {
        match self {
            Method::QuadtreeTiles => 0.67,
            _ => 0.33,
        }
    }

    /// The names of the methods that [`Method::subsamples`] (for messages and labels).
    pub fn subsampling_names() -> Vec<&'static str> {
        Method::ALL
            .into_iter()
            .filter(|m| m.subsamples())
            .map(Method::name)
            .collect()
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

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// When a per-tile cut splits a node ([`crate::Settings::tile_criterion`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TileCriterion {
    /// While an upper bound of its irradiance at any receiver of the tile exceeds
    /// [`crate::Settings::tile_error`] of the tile's estimated irradiance (Lightcuts).
    Bound,
    /// While the estimated error of keeping it, the largest |E(node) - sum of E(children)| at
    /// the tile's sample pixels (those of the tile's estimate), exceeds that; nodes whose bound
    /// is already below it are kept without an estimate.
    Estimate,
}

impl TileCriterion {
    /// Both criteria, in the order the CLI lists them.
    pub const ALL: [TileCriterion; 2] = [TileCriterion::Bound, TileCriterion::Estimate];

    /// The [`crate::Settings::tile_error`] of the criterion when none is given (see BENCHMARKS.md,
    /// "Per-tile cuts"): a node's estimated error is far below its bound.
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

impl fmt::Display for TileCriterion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How the per-tile cuts' work is laid out on the GPU with indirect shadows
/// ([`crate::Settings::tile_passes`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TilePasses {
    /// One kernel a tile: it builds the cut in workgroup memory, walks the shadow rays from the
    /// tile's anchors and sums, phases between barriers.
    Fused,
    /// Three passes: the kernel builds the cut and its shadow targets into storage, a walk pass
    /// with almost no workgroup memory walks the anchors' rays to them, several a lane, and a
    /// per-pixel pass sums the list with the visibility the walks left.
    Split,
}

impl TilePasses {
    /// Both, in the order the CLI lists them.
    pub const ALL: [TilePasses; 2] = [TilePasses::Fused, TilePasses::Split];

    /// The layout's name on the command line and in the stats (`--tile-passes`).
    pub fn name(self) -> &'static str {
        match self {
            TilePasses::Fused => "fused",
            TilePasses::Split => "split",
        }
    }
}

impl std::str::FromStr for TilePasses {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        quadray_core::parse_named(s, &Self::ALL, Self::name, "tile passes")
    }
}

impl fmt::Display for TilePasses {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
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

impl Validity {
    /// Both rules, in the order the CLI lists them.
    pub const ALL: [Validity; 2] = [Validity::Local, Validity::Recursive];

    /// The rule's name on the command line and in the stats (`--validity`).
    pub fn name(self) -> &'static str {
        match self {
            Validity::Local => "local",
            Validity::Recursive => "recursive",
        }
    }
}

impl std::str::FromStr for Validity {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        quadray_core::parse_named(s, &Self::ALL, Self::name, "validity rule")
    }
}

impl fmt::Display for Validity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How quadray's raster passes store what they write ([`crate::Settings::gbuffer_layout`]): the
/// camera's G-buffer and each light view's RSM. Raster output units write a 128-bit texel at a
/// quarter of a 32-bit one's rate, so on a GPU with few of them (a datacenter chip) the passes
/// take as long as their targets' widths add up to (docs/known-problems.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum GBufferLayout {
    /// Position rebuilt from the depth buffer (the view's inverse projection), the normal
    /// octahedral in `Rg16Float`, the albedo `Rgb10a2Unorm` and the RSM's flux `Rgba16Float` as
    /// its share of the light's intensity times the texel's measure (8 bytes of colour a pixel,
    /// 12 a texel).
    Compact,
    /// Position, normal and albedo (the RSM: flux) each in `Rgba32Float` (48 bytes of colour
    /// a pixel or texel).
    Wide,
}

impl GBufferLayout {
    /// Both layouts, in the order the CLI lists them.
    pub const ALL: [GBufferLayout; 2] = [GBufferLayout::Compact, GBufferLayout::Wide];

    /// The layout's name on the command line and in the stats (`--gbuffer-layout`).
    pub fn name(self) -> &'static str {
        match self {
            GBufferLayout::Compact => "compact",
            GBufferLayout::Wide => "wide",
        }
    }
}

impl std::str::FromStr for GBufferLayout {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        quadray_core::parse_named(s, &Self::ALL, Self::name, "G-buffer layout")
    }
}

impl fmt::Display for GBufferLayout {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
