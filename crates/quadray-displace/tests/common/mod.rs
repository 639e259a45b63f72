//! Maps the tests share: the bundled assets, at sizes that keep lavapipe fast.
// Each test binary uses its own part of this module.
#![allow(dead_code)]

use quadray_displace::heightmap::{Convention, Fit, HeightMap};
use std::path::PathBuf;

pub fn asset(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets")
        .join(rel)
}

/// (name, map, sharp) for every bundled height map.
pub fn bundled_maps() -> Vec<(&'static str, HeightMap, bool)> {
    let load =
        |rel: &str, convention| HeightMap::load(&asset(rel), convention, Fit::Resample).unwrap();
    vec![
        (
            "tiles105",
            load(
                "heightmaps/ambientcg_tiles105/Tiles105_1K_Displacement.png",
                Convention::Height,
            ),
            true,
        ),
        (
            "bevy-cube",
            load("heightmaps/bevy_parallax/cube_depth.png", Convention::Depth),
            true,
        ),
        (
            "puget-sound",
            load(
                "heightmaps/puget_sound/ps_height_1k.png",
                Convention::Height,
            ),
            false,
        ),
        (
            "tum-depth",
            load(
                "heightmaps/depth_tum_rgbd/TUM_depth.png",
                Convention::DepthPhoto,
            ),
            true,
        ),
    ]
}
