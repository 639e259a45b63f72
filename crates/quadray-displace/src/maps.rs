//! The bundled maps the demo and the benchmark use, with the convention each is stored in.

use crate::heightmap::{Convention, Fit, HeightMap, HeightMapError};
use crate::scene::SurfaceKind;
use quadray_core::image_out::Rgba8Image;
use std::path::{Path, PathBuf};

/// A height map bundled under `assets/`, and how quadray shows it.
pub struct BundledMap {
    /// Its short name (the viewer's and the benchmark's).
    pub name: &'static str,
    /// Relative to the assets folder.
    pub file: &'static str,
    /// How the file stores its values.
    pub convention: Convention,
    /// An albedo image beside it, relative to the assets folder.
    pub color: Option<&'static str>,
    /// Sharp maps (steep walls) are where searches by fixed steps fail.
    pub sharp: bool,
    /// The surface it is shown on.
    pub surface: SurfaceKind,
    /// The paper's row this map stands in for (tables 1 and 2).
    pub paper_row: &'static str,
}

/// Every bundled map: tiles (the sharp one), bevy-cube, puget-sound, tum-photo.
pub const BUNDLED: [BundledMap; 4] = [
    BundledMap {
        name: "tiles",
        file: "heightmaps/ambientcg_tiles105/Tiles105_1K_Displacement.png",
        convention: Convention::Height,
        color: None,
        sharp: true,
        surface: SurfaceKind::Wall,
        paper_row: "gravel wall",
    },
    BundledMap {
        name: "bevy-cube",
        file: "heightmaps/bevy_parallax/cube_depth.png",
        convention: Convention::Depth,
        color: Some("heightmaps/bevy_parallax/cube_color.png"),
        sharp: true,
        surface: SurfaceKind::Wall,
        paper_row: "-",
    },
    BundledMap {
        name: "puget-sound",
        file: "heightmaps/puget_sound/ps_height_1k.png",
        convention: Convention::Height,
        color: None,
        sharp: false,
        surface: SurfaceKind::Terrain,
        paper_row: "terrain",
    },
    BundledMap {
        name: "tum-photo",
        file: "heightmaps/depth_tum_rgbd/TUM_depth.png",
        convention: Convention::DepthPhoto,
        color: Some("heightmaps/depth_tum_rgbd/TUM_color.png"),
        sharp: true,
        surface: SurfaceKind::Photo,
        paper_row: "face",
    },
];

/// The repository's `assets/` folder (the binary may run from anywhere inside the clone).
pub fn assets_dir() -> PathBuf {
    let compiled = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    if compiled.exists() {
        compiled
    } else {
        PathBuf::from("assets")
    }
}

impl BundledMap {
    /// Loads the map as stored (any size).
    pub fn load(&self) -> Result<HeightMap, HeightMapError> {
        HeightMap::load(&assets_dir().join(self.file), self.convention, Fit::Exact)
    }

    /// Loads its albedo image, if it has one.
    pub fn load_color(&self) -> Result<Option<Rgba8Image>, HeightMapError> {
        self.color
            .map(|rel| load_color(&assets_dir().join(rel)))
            .transpose()
    }
}

/// Loads an albedo image as 8-bit RGBA.
pub fn load_color(path: &Path) -> Result<Rgba8Image, HeightMapError> {
    let img = quadray_core::image_in::open(path)?.to_rgba8();
    Ok(Rgba8Image::from_bytes(
        img.width(),
        img.height(),
        img.as_raw(),
    ))
}

/// Resamples a map to `size` x `size` (figure 21's map-size sweep).
pub fn resized(map: &HeightMap, size: u32) -> HeightMap {
    let depth = (0..size * size)
        .map(|k| {
            let (i, j) = (k % size, k / size);
            // Nearest texel: keeps the map's sharpness at every size.
            map.at(
                (u64::from(i) * u64::from(map.width) / u64::from(size)) as u32,
                (u64::from(j) * u64::from(map.height) / u64::from(size)) as u32,
            )
        })
        .collect();
    HeightMap::from_depths(Path::new("resized"), size, size, depth).expect("a supported size")
}
