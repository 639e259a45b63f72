//! Pictures are the product: PNG output, error heat maps and labelled side-by-side montages.

use crate::FileError;
use font8x8::UnicodeFonts;
use std::path::Path;

/// An 8-bit RGBA image, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Rgba8Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[u8; 4]>,
}

impl Rgba8Image {
    pub fn new(width: u32, height: u32, fill: [u8; 4]) -> Self {
        Self {
            width,
            height,
            pixels: vec![fill; (width * height) as usize],
        }
    }

    pub fn from_bytes(width: u32, height: u32, bytes: &[u8]) -> Self {
        Self {
            width,
            height,
            pixels: bytes
                .chunks_exact(4)
                .map(|p| [p[0], p[1], p[2], p[3]])
                .collect(),
        }
    }

    pub fn save_png(&self, path: &Path) -> Result<(), FileError> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| FileError::new(dir, e))?;
        }
        image::save_buffer(
            path,
            bytemuck_flat(&self.pixels),
            self.width,
            self.height,
            image::ExtendedColorType::Rgba8,
        )
        .map_err(|e| FileError::new(path, e))
    }

    fn put(&mut self, x: u32, y: u32, c: [u8; 4]) {
        if x < self.width && y < self.height {
            self.pixels[(y * self.width + x) as usize] = c;
        }
    }

    fn blit(&mut self, src: &Rgba8Image, x0: u32, y0: u32) {
        for y in 0..src.height {
            for x in 0..src.width {
                self.put(x0 + x, y0 + y, src.pixels[(y * src.width + x) as usize]);
            }
        }
    }

    /// Draws `text` with the 8x8 public-domain font at integer `scale`, on a dark box for contrast.
    pub fn label(&mut self, x0: u32, y0: u32, text: &str, scale: u32) {
        let w = text.chars().count() as u32 * 8 * scale;
        for y in y0..y0 + 8 * scale + 2 {
            for x in x0..x0 + w + 2 {
                self.put(x, y, [0, 0, 0, 255]);
            }
        }
        for (i, ch) in text.chars().enumerate() {
            let glyph = font8x8::BASIC_FONTS.get(ch).unwrap_or([0; 8]);
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..8u32 {
                    if bits >> col & 1 == 1 {
                        for s in 0..scale * scale {
                            self.put(
                                x0 + 1 + (i as u32 * 8 + col) * scale + s % scale,
                                y0 + 1 + row as u32 * scale + s / scale,
                                [255, 255, 255, 255],
                            );
                        }
                    }
                }
            }
        }
    }
}

fn bytemuck_flat(pixels: &[[u8; 4]]) -> &[u8] {
    pixels.as_flattened()
}

/// How far two pictures of one size are apart, channel value by channel value (8-bit): the mean
/// absolute difference, and the fraction of values that differ by more than `far`. Tests hold
/// two renders of one setup to these two figures.
///
/// # Panics
/// When the two differ in length (pictures of different sizes).
pub fn channel_difference(a: &[u8], b: &[u8], far: u8) -> (f64, f64) {
    assert_eq!(a.len(), b.len(), "pictures of different sizes");
    let diffs = || a.iter().zip(b).map(|(x, y)| x.abs_diff(*y));
    let count = a.len().max(1) as f64;
    let mean = diffs().map(f64::from).sum::<f64>() / count;
    let far_off = diffs().filter(|&d| d > far).count() as f64 / count;
    (mean, far_off)
}

/// Maps `values` (NaN = no data, drawn dark grey) to a heat map: black at 0 through red and
/// yellow to white at `max`.
pub fn heat_map(width: u32, height: u32, values: &[f32], max: f32) -> Rgba8Image {
    let pixels = values
        .iter()
        .map(|&v| {
            if v.is_nan() {
                return [40, 40, 48, 255];
            }
            let t = (v / max).clamp(0.0, 1.0);
            let ch = |a: f32| ((t * 3.0 - a).clamp(0.0, 1.0) * 255.0) as u8;
            [ch(0.0), ch(1.0), ch(2.0), 255]
        })
        .collect();
    Rgba8Image {
        width,
        height,
        pixels,
    }
}

/// Lays `tiles` (caption, image) out in rows of `columns`, each captioned, on a grey background.
pub fn montage(tiles: &[(String, Rgba8Image)], columns: usize) -> Rgba8Image {
    let columns = columns.max(1);
    let tile_w = tiles.iter().map(|(_, t)| t.width).max().unwrap_or(1);
    let tile_h = tiles.iter().map(|(_, t)| t.height).max().unwrap_or(1);
    let caption = 14;
    let gap = 4;
    let rows = tiles.len().div_ceil(columns) as u32;
    let mut out = Rgba8Image::new(
        columns as u32 * (tile_w + gap) + gap,
        rows * (tile_h + caption + gap) + gap,
        [90, 90, 90, 255],
    );
    for (i, (text, tile)) in tiles.iter().enumerate() {
        let x = gap + (i % columns) as u32 * (tile_w + gap);
        let y = gap + (i / columns) as u32 * (tile_h + caption + gap);
        out.label(x, y, text, 1);
        out.blit(tile, x, y + caption);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heat_map_runs_black_to_white_and_marks_missing_data() {
        let img = heat_map(3, 1, &[0.0, 2.0, f32::NAN], 2.0);
        assert_eq!(img.pixels[0], [0, 0, 0, 255]);
        assert_eq!(img.pixels[1], [255, 255, 255, 255]);
        assert_eq!(img.pixels[2], [40, 40, 48, 255]);
    }

    #[test]
    fn montage_places_every_tile_below_its_caption() {
        let red = Rgba8Image::new(4, 4, [255, 0, 0, 255]);
        let m = montage(&[("a".into(), red.clone()), ("b".into(), red)], 2);
        assert_eq!(m.width, 2 * (4 + 4) + 4);
        // first pixel of the first tile sits below the 14-pixel caption band
        assert_eq!(
            m.pixels[((4 + 14) * m.width + 4) as usize],
            [255, 0, 0, 255]
        );
    }
}
