//! Tiles and frames as independent work items (`quadray raytrace --tiles N --frames A..B`): which
//! item a process renders, where its tile lies, and the EXR file that carries a tile's exact
//! radiance with everything `quadray merge` needs to put it back and to refuse a mismatch.

use anyhow::{Context, bail, ensure};
use exr::meta::attribute::{AttributeValue, IntegerBounds, Text};
use exr::prelude::{
    Encoding, Image, ImageAttributes, Layer, LayerAttributes, ReadChannels, ReadLayers,
    SpecificChannels, Vec2, WritableImage, read,
};
use quadray_shadows::{Radiance, Region, Settings};
use std::fmt::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// The scheduler variables that carry a work item's index, in the order they are consulted
/// after `--tile`: a Kubernetes Indexed Job's, then a Slurm job array's.
pub const INDEX_VARIABLES: [&str; 2] = ["JOB_COMPLETION_INDEX", "SLURM_ARRAY_TASK_ID"];

/// The largest image a tile may claim to belong to (`--size`'s limit).
const MAX_SIDE: usize = Settings::SIDE.max as usize;

/// The work items of a tiled render or a turntable: every frame of `frames` cut into `tiles`
/// horizontal bands, numbered frame by frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WorkItems {
    /// Bands per frame.
    pub tiles: u32,
    /// The frames of the turntable (one frame, 0..1, without one).
    pub frames: Range<u32>,
}

impl WorkItems {
    /// How many items there are.
    pub fn count(&self) -> u64 {
        self.tiles as u64 * self.frames.len() as u64
    }

    /// The frame and the tile of item `index`.
    pub fn item(&self, index: u64) -> (u32, u32) {
        let frame = self.frames.start + (index / self.tiles as u64) as u32;
        (frame, (index % self.tiles as u64) as u32)
    }

    /// The index of this process's item: `flag` (`--tile`), else the first scheduler variable
    /// that is set; an error names where a bad or missing index came from.
    pub fn index_from(&self, flag: Option<u64>) -> anyhow::Result<u64> {
        let (index, source) = match flag {
            Some(i) => (i, "--tile".to_string()),
            None => {
                let Some((name, value)) = INDEX_VARIABLES
                    .iter()
                    .find_map(|&name| std::env::var(name).ok().map(|v| (name, v)))
                else {
                    bail!(
                        "a work item index is needed ({} items): give --tile I or set {} or {}",
                        self.count(),
                        INDEX_VARIABLES[0],
                        INDEX_VARIABLES[1]
                    );
                };
                let index = value.trim().parse().with_context(|| {
                    format!("{name}={value:?} is not a work item index (a number)")
                })?;
                (index, format!("{name}={value}"))
            }
        };
        ensure!(
            index < self.count(),
            "{source}: work item index out of range 0..{} ({} frames x {} tiles)",
            self.count(),
            self.frames.len(),
            self.tiles
        );
        Ok(index)
    }
}

/// Tile `tile` of `tiles` horizontal bands of a `width` x `height` image (`tiles <= height`).
pub fn band(width: u32, height: u32, tile: u32, tiles: u32) -> Region {
    let row = |t: u32| (t as u64 * height as u64 / tiles as u64) as u32;
    Region {
        x: 0,
        y: row(tile),
        width,
        height: row(tile + 1) - row(tile),
    }
}

/// `A..B` (B excluded) as a range of frames.
pub fn parse_frames(text: &str) -> Result<Range<u32>, String> {
    let bad = || format!("{text:?}: expected A..B, the frames A to B-1, with A < B");
    let (a, b) = text.split_once("..").ok_or_else(bad)?;
    let (a, b): (u32, u32) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if a < b { Ok(a..b) } else { Err(bad()) }
}

/// Ascending `indices` as runs, `0-3,7,9-10`: the form of Slurm's `--array` and of a Kubernetes
/// Indexed Job's `completedIndexes` and `failedIndexes`.
pub fn index_ranges(indices: &[u64]) -> String {
    let mut runs: Vec<(u64, u64)> = Vec::new();
    for &i in indices {
        match runs.last_mut() {
            Some((_, end)) if *end + 1 == i => *end = i,
            _ => runs.push((i, i)),
        }
    }
    let run = |&(a, b): &(u64, u64)| {
        if a == b {
            a.to_string()
        } else {
            format!("{a}-{b}")
        }
    };
    runs.iter().map(run).collect::<Vec<_>>().join(",")
}

/// A 64-bit FNV-1a hash of everything written into it: the fingerprint of a scene and its
/// settings, the same on every machine and build (std's hasher promises neither).
pub struct Fingerprint(u64);

impl Default for Fingerprint {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl std::fmt::Write for Fingerprint {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        for b in s.bytes() {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0100_0000_01b3);
        }
        Ok(())
    }
}

impl Fingerprint {
    /// The fingerprint of `what`'s debug form (floats in it round-trip exactly) and `settings`.
    pub fn of(what: &impl std::fmt::Debug, settings: &str) -> String {
        let mut hash = Self::default();
        write!(hash, "{what:?}\n{settings}").expect("hashing cannot fail");
        format!("{:016x}", hash.0)
    }
}

/// Where a tile goes and what it was rendered from: the EXR header attributes of a tile file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TileHeader {
    /// The whole image's size.
    pub image: (u32, u32),
    /// The tile's rectangle in the image.
    pub region: Region,
    /// Which tile of the frame.
    pub tile: u32,
    /// The items of the whole job.
    pub items: WorkItems,
    /// Which frame.
    pub frame: u32,
    /// The settings that change pixels, readable: their `quadray raytrace` flags and `--orbit`.
    pub settings: String,
    /// [`Fingerprint`] of the scene and the settings.
    pub fingerprint: String,
}

const TILE: &str = "quadray.tile";
const TILES: &str = "quadray.tiles";
const FRAME: &str = "quadray.frame";
const FRAMES_START: &str = "quadray.frames_start";
const FRAMES_END: &str = "quadray.frames_end";
const SETTINGS: &str = "quadray.settings";
const FINGERPRINT: &str = "quadray.fingerprint";

/// The file name of a work item's tile inside the output folder.
pub fn tile_file_name(frame: u32, tile: u32) -> String {
    format!("frame{frame:04}-tile{tile:04}.exr")
}

/// Writes `radiance` as a 32-bit float RGB EXR; the data window is its region, the display
/// window the `image` it belongs to, and a tile's `header` goes into the attributes.
pub fn write_exr(
    path: &Path,
    radiance: &Radiance,
    image: (u32, u32),
    header: Option<&TileHeader>,
) -> anyhow::Result<()> {
    let r = radiance.region;
    let mut attributes = LayerAttributes {
        layer_position: Vec2(r.x as i32, r.y as i32),
        ..LayerAttributes::default()
    };
    if let Some(h) = header {
        let int = |v: u32| AttributeValue::I32(v as i32);
        let text = |s: &str| AttributeValue::Text(Text::from(s));
        for (name, value) in [
            (TILE, int(h.tile)),
            (TILES, int(h.items.tiles)),
            (FRAME, int(h.frame)),
            (FRAMES_START, int(h.items.frames.start)),
            (FRAMES_END, int(h.items.frames.end)),
            (SETTINGS, text(&h.settings)),
            (FINGERPRINT, text(&h.fingerprint)),
        ] {
            attributes.other.insert(Text::from(name), value);
        }
    }
    let width = r.width as usize;
    let pixels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let [red, green, blue] = radiance.pixels[p.y() * width + p.x()];
        (red, green, blue)
    });
    let layer = Layer::new(
        (width, r.height as usize),
        attributes,
        Encoding::SMALL_LOSSLESS,
        pixels,
    );
    let display = IntegerBounds::from_dimensions((image.0 as usize, image.1 as usize));
    let exr = Image::new(ImageAttributes::new(display), layer);
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("{}", dir.display()))?;
    }
    // Written aside and renamed, so that a work item killed while writing (cancelled, out of
    // time) leaves no half file that the merge would take for its tile.
    let mut partial = path.as_os_str().to_owned();
    partial.push(".part");
    let partial = PathBuf::from(partial);
    exr.write()
        .to_file(&partial)
        .with_context(|| format!("{}: cannot write the EXR", partial.display()))?;
    std::fs::rename(&partial, path)
        .with_context(|| format!("{}: cannot write the EXR", path.display()))
}

/// Reads a tile's header alone (cheap: the pixels stay on disk), checking that it describes a
/// tile of a sane image.
pub fn read_header(path: &Path) -> anyhow::Result<TileHeader> {
    let name = path.display();
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .with_context(|| format!("{name}: not a readable EXR"))?;
    let [header] = meta.headers.as_slice() else {
        bail!("{name}: a quadray tile has one layer");
    };
    let attrs = &header.own_attributes.other;
    let int = |key: &str| match attrs.get(&Text::from(key)) {
        Some(AttributeValue::I32(v)) if *v >= 0 => Ok(*v as u32),
        _ => Err(anyhow::anyhow!(
            "{name}: not a quadray tile (no attribute {key}; write tiles with quadray raytrace \
             --tiles N)"
        )),
    };
    let text = |key: &str| match attrs.get(&Text::from(key)) {
        Some(AttributeValue::Text(t)) => Ok(String::from(t.clone())),
        _ => Err(anyhow::anyhow!(
            "{name}: not a quadray tile (no attribute {key})"
        )),
    };
    let display = header.shared_attributes.display_window;
    let (position, size) = (header.own_attributes.layer_position, header.layer_size);
    ensure!(
        display.position == Vec2(0, 0)
            && (1..=MAX_SIDE).contains(&display.size.x())
            && (1..=MAX_SIDE).contains(&display.size.y()),
        "{name}: the image size {}x{} is not one quadray renders",
        display.size.x(),
        display.size.y()
    );
    ensure!(
        position.x() >= 0
            && position.y() >= 0
            && position.x() as usize + size.x() <= display.size.x()
            && position.y() as usize + size.y() <= display.size.y(),
        "{name}: the tile's rectangle lies outside its image"
    );
    let items = WorkItems {
        tiles: int(TILES)?,
        frames: int(FRAMES_START)?..int(FRAMES_END)?,
    };
    let (tile, frame) = (int(TILE)?, int(FRAME)?);
    ensure!(
        items.tiles > 0 && tile < items.tiles && items.frames.contains(&frame),
        "{name}: tile {tile} of {} in frame {frame} of {:?} is not a work item",
        items.tiles,
        items.frames
    );
    Ok(TileHeader {
        image: (display.size.x() as u32, display.size.y() as u32),
        region: Region {
            x: position.x() as u32,
            y: position.y() as u32,
            width: size.x() as u32,
            height: size.y() as u32,
        },
        tile,
        items,
        frame,
        settings: text(SETTINGS)?,
        fingerprint: text(FINGERPRINT)?,
    })
}

/// The radiance of a tile whose header [`read_header`] checked.
pub fn read_pixels(path: &Path, header: &TileHeader) -> anyhow::Result<Radiance> {
    let name = path.display();
    // Indexed by the size the decoder reports, so a file whose pixels are not the size its
    // header claimed is refused below instead of indexing out of bounds.
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |size, _| (size.width(), vec![[0f32; 3]; size.area()]),
            |(width, pixels): &mut (usize, Vec<[f32; 3]>), p, (r, g, b): (f32, f32, f32)| {
                pixels[p.y() * *width + p.x()] = [r, g, b]
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .with_context(|| format!("{name}: cannot read the tile's pixels"))?;
    let layer = image.layer_data;
    let r = header.region;
    ensure!(
        layer.size.x() == r.width as usize && layer.size.y() == r.height as usize,
        "{name}: the tile claims {}x{} pixels but holds {}x{}",
        r.width,
        r.height,
        layer.size.x(),
        layer.size.y()
    );
    Ok(Radiance {
        region: r,
        pixels: layer.channel_data.pixels.1,
    })
}

/// `path` with `.NNNN` (the frame) before its extension: a turntable's frame files.
pub fn frame_path(path: &Path, frame: u32) -> PathBuf {
    let stem = path.file_stem().unwrap_or_default().to_string_lossy();
    let name = match path.extension() {
        Some(ext) => format!("{stem}.{frame:04}.{}", ext.to_string_lossy()),
        None => format!("{stem}.{frame:04}"),
    };
    path.with_file_name(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_cover_the_image_once() {
        for (h, n) in [(40, 3), (7, 7), (480, 16), (5, 1)] {
            let rows: Vec<u32> = (0..n)
                .flat_map(|t| {
                    let b = band(9, h, t, n);
                    b.y..b.y + b.height
                })
                .collect();
            assert_eq!(rows, (0..h).collect::<Vec<_>>(), "{h} rows in {n} bands");
        }
    }

    #[test]
    fn items_run_frame_by_frame() {
        let items = WorkItems {
            tiles: 3,
            frames: 4..6,
        };
        assert_eq!(items.count(), 6);
        assert_eq!(items.item(0), (4, 0));
        assert_eq!(items.item(4), (5, 1));
        assert!(items.index_from(Some(6)).is_err());
        assert_eq!(parse_frames("2..5"), Ok(2..5));
        assert!(parse_frames("5..5").is_err() && parse_frames("x").is_err());
    }

    /// A tile whose pixels are not the size its header gave (the file replaced after its
    /// header was read) is refused by name, not indexed out of bounds.
    #[test]
    fn pixels_of_another_size_than_the_header_claims_are_refused() {
        let dir = std::env::temp_dir().join(format!("quadray-tile-size-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let header = |tile: u32| TileHeader {
            image: (6, 9),
            region: band(6, 9, tile, 2),
            tile,
            items: WorkItems {
                tiles: 2,
                frames: 0..1,
            },
            frame: 0,
            settings: "s".into(),
            fingerprint: "f".into(),
        };
        let path = dir.join("t.exr");
        for tile in [0, 1] {
            let region = band(6, 9, tile, 2);
            let radiance = Radiance {
                region,
                pixels: vec![[0.5; 3]; (region.width * region.height) as usize],
            };
            write_exr(&path, &radiance, (6, 9), Some(&header(tile))).unwrap();
        }
        assert_eq!(read_header(&path).unwrap().region, band(6, 9, 1, 2));
        assert_eq!(read_pixels(&path, &header(1)).unwrap().pixels.len(), 30);
        let e = read_pixels(&path, &header(0)).unwrap_err().to_string();
        assert!(
            e.contains("t.exr") && e.contains("claims 6x4 pixels but holds 6x5"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn indices_print_as_runs() {
        assert_eq!(index_ranges(&[]), "");
        assert_eq!(index_ranges(&[4]), "4");
        assert_eq!(index_ranges(&[0, 1, 2, 3, 7, 9, 10]), "0-3,7,9-10");
    }

    #[test]
    fn fingerprints_tell_settings_apart() {
        assert_eq!(Fingerprint::of(&1.5f32, "a"), Fingerprint::of(&1.5f32, "a"));
        assert_ne!(Fingerprint::of(&1.5f32, "a"), Fingerprint::of(&1.5f32, "b"));
        assert_ne!(
            Fingerprint::of(&1.5f32, "a"),
            Fingerprint::of(&1.25f32, "a")
        );
    }
}
