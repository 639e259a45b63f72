//! The light quadtree's parameters ([`ClusterSettings`]) and the levels a cut spans
//! ([`Levels`]), part of [`Settings`].

use crate::method::Validity;
#[cfg(doc)]
use crate::settings::Settings;
use quadray_core::settings::Limits;
use serde::Serialize;

/// The levels a cut spans on a given RSM, its settings' choices or their defaults.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Levels {
    /// The coarsest level a cluster may be (the cut starts from its nodes).
    pub start: u32,
    /// The finest level a cluster may be.
    pub limit: u32,
}

/// The light quadtree's parameters. Levels are mip levels: 0 is the RSM itself (one VPL per
/// node), each level halves the side.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct ClusterSettings {
    /// Level the cut starts from (mip level: 0 is the RSM, each level halves the side); default:
    /// the level of 8x8 nodes, as in the paper.
    #[cfg_attr(feature = "cli", arg(long, value_parser = ClusterSettings::LEVEL.parser()))]
    pub start_level: Option<u32>,
    /// Level where every cluster is accepted: nodes below it are never visited (0: single VPLs);
    /// default: the level of 64x64 nodes.
    #[cfg_attr(feature = "cli", arg(long, value_parser = ClusterSettings::LEVEL.parser()))]
    pub limit_level: Option<u32>,
    /// Max |child depth - mean depth| of a valid cluster (depth along the light's axis, in units
    /// of the spot's extent).
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = ClusterSettings::DEFAULT.depth_threshold,
        value_parser = ClusterSettings::DEPTH_THRESHOLD.parser(),
    ))]
    pub depth_threshold: f32,
    /// Min dot(child normal, mean normal) of a valid cluster.
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = ClusterSettings::DEFAULT.normal_threshold,
        value_parser = ClusterSettings::NORMAL_THRESHOLD.parser(),
        allow_negative_numbers = true,
    ))]
    pub normal_threshold: f32,
    /// Which nodes' validity a node's own depends on: recursive (every child valid too) or local
    /// (the paper's).
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value_t = ClusterSettings::DEFAULT.validity)
    )]
    pub validity: Validity,
    /// Cluster means weighted by flux luminance (`--unweighted-means`: by texel count).
    #[cfg_attr(
        feature = "cli",
        arg(long = "unweighted-means", action = clap::ArgAction::SetFalse)
    )]
    pub flux_weighted: bool,
}

impl ClusterSettings {
    /// The defaults: the paper's thresholds (depth 0.05, normal 0.9), start at 8x8 nodes as in
    /// the paper, limit at 64x64 (the paper's level 4; its 32x32 limit leaves about 7% rel. L1
    /// error on the Cornell box, most of it at the limit level), and the recursive rule: on a
    /// 512^2 RSM the local rule leaves 5.1% with 360 clusters, the recursive 3.8% with 633, less
    /// than the local rule reaches with the same time at a finer limit (4.4% with 589); on the
    /// 256^2 RSM of the test that holds the README's figures, 5.1% and 3.7%.
    pub const DEFAULT: ClusterSettings = ClusterSettings {
        start_level: None,
        limit_level: None,
        depth_threshold: 0.05,
        normal_threshold: 0.9,
        validity: Validity::Recursive,
        flux_weighted: true,
    };

    /// Nodes across the default start level.
    pub const DEFAULT_START_NODES: u32 = 8;
    /// Nodes across the default limit level.
    pub const DEFAULT_LIMIT_NODES: u32 = 64;

    /// [`ClusterSettings::start_level`] and [`ClusterSettings::limit_level`] (the RSM's own
    /// levels bound them further in [`Settings::validate`]).
    pub const LEVEL: Limits<u32> = Limits::closed(0, 10);
    /// [`ClusterSettings::depth_threshold`].
    pub const DEPTH_THRESHOLD: Limits<f32> = Limits::closed(0.0, f32::MAX).interactive(0.001, 0.5);
    /// [`ClusterSettings::normal_threshold`].
    pub const NORMAL_THRESHOLD: Limits<f32> = Limits::closed(-1.0, 1.0);

    /// The levels these settings span on an `rsm_size`^2 RSM: the given ones, else the levels of
    /// [`Self::DEFAULT_START_NODES`] and [`Self::DEFAULT_LIMIT_NODES`] nodes across.
    pub fn levels(&self, rsm_size: u32) -> Levels {
        let top = rsm_size.max(1).ilog2();
        let of = |nodes: u32| top.saturating_sub(nodes.ilog2());
        Levels {
            start: self.start_level.unwrap_or(of(Self::DEFAULT_START_NODES)),
            limit: self.limit_level.unwrap_or(of(Self::DEFAULT_LIMIT_NODES)),
        }
    }

    /// The paper's settings (local rule) with the limit level where nodes are `side` x `side`
    /// (16, 32, 64 in table 1).
    pub fn with_limit_side(rsm_size: u32, side: u32) -> Self {
        let top = rsm_size.ilog2();
        Self {
            limit_level: Some(top.saturating_sub(side.max(1).ilog2())),
            validity: Validity::Local,
            ..Self::DEFAULT
        }
    }

    /// Every cluster a single VPL: the cut is the whole RSM.
    pub fn every_vpl() -> Self {
        Self {
            limit_level: Some(0),
            depth_threshold: 0.0,
            ..Self::DEFAULT
        }
    }
}

impl Default for ClusterSettings {
    fn default() -> Self {
        Self::DEFAULT
    }
}
