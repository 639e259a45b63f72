//! Maps the tests share: the bundled assets as stored (square powers of two and odd sizes), and
//! procedural maps of any size.

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
        |rel: &str, convention| HeightMap::load(&asset(rel), convention, Fit::Exact).unwrap();
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

/// A `width` x `height` map with both kinds of feature the tracer must get right: sharp-walled
/// tiles (grout 2 texels wide every 23, plateaus at four depths) and smooth bumps between them.
/// Deterministic, so any size can be synthesised instead of stored.
pub fn procedural(width: u32, height: u32) -> HeightMap {
    let depth = (0..height)
        .flat_map(|j| (0..width).map(move |i| (i, j)))
        .map(|(i, j)| {
            if i % 23 < 2 || j % 23 < 2 {
                return 0.9;
            }
            let plateau = ((i / 23 * 7 + j / 23 * 3) % 4) as f32 * 0.15;
            let bump = ((i as f32 * 0.37).sin() * (j as f32 * 0.29).cos() + 1.0) * 0.12;
            plateau + bump
        })
        .collect();
    named_map("procedural", width, height, depth)
}

/// A tiny `width` x `height` map whose every texel differs from its neighbours (eleven depths):
/// each texel is a column with walls, and the map tiles many times across a frame.
pub fn scattered(width: u32, height: u32) -> HeightMap {
    let depth = (0..height)
        .flat_map(|j| (0..width).map(move |i| (i, j)))
        .map(|(i, j)| ((i * 7 + j * 13 + 3) % 11) as f32 / 10.0)
        .collect();
    named_map("scattered", width, height, depth)
}

fn named_map(kind: &str, width: u32, height: u32, depth: Vec<f32>) -> HeightMap {
    let name = format!("{kind} {width}x{height}");
    HeightMap::from_depths(std::path::Path::new(&name), width, height, depth).unwrap()
}
