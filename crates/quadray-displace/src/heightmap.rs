//! Height maps in the spec's convention: depth in `[0, 1]` (0 = the polygon's plane, 1 = deepest),
//! any width x height, row-major with row 0 at v = 0.

use quadray_core::image_in::{self, ImageReadError, MAX_SIDE};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// How the file's values map to depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Convention {
    /// White = high: depth = 1 - value.
    Height,
    /// White = deep (Bevy's parallax maps): depth = value.
    Depth,
    /// A depth photograph (TUM/Kinect): larger = farther, 0 = no measurement. Stretched to the
    /// measured range; holes become the deepest value.
    DepthPhoto,
}

impl Convention {
    /// Every convention.
    pub const ALL: [Convention; 3] = [
        Convention::Height,
        Convention::Depth,
        Convention::DepthPhoto,
    ];

    /// The name `--convention` takes.
    pub fn name(self) -> &'static str {
        match self {
            Convention::Height => "height",
            Convention::Depth => "depth",
            Convention::DepthPhoto => "depth-photo",
        }
    }
}

impl std::str::FromStr for Convention {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        quadray_core::parse_named(s, &Self::ALL, Self::name, "convention")
    }
}

/// What to do with a map that is not 2^n x 2^n.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fit {
    /// Keep it as stored: the pyramid pads it and traces it exactly.
    Exact,
    /// Bilinear resampling to the nearest power of two (1025 -> 1024, 348 -> 256, 640x480 -> 512).
    Resample,
}

/// Why a map was refused; every message names the file.
#[derive(Debug, Error)]
#[allow(missing_docs)] // each variant's message says what its fields are
pub enum HeightMapError {
    #[error(transparent)]
    Image(#[from] ImageReadError),
    #[error("{path}: the image is empty (0 texels)")]
    Empty { path: PathBuf },
    #[error("{path}: texel ({x}, {y}) is {value}, not a finite number")]
    NotFinite {
        path: PathBuf,
        x: u32,
        y: u32,
        value: f32,
    },
    #[error("{path}: the depth photo has no valid (non-zero) measurement")]
    NoMeasurement { path: PathBuf },
}

#[derive(Clone, Debug, PartialEq)]
/// A `width` x `height` height field in depth convention; uv [0, 1)^2 spans it once, texel
/// (i, j) covering [i / width, (i + 1) / width) x [j / height, (j + 1) / height).
pub struct HeightMap {
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Depths in [0, 1], row-major, row 0 at v = 0.
    pub depth: Vec<f32>,
}

/// Fails on the first texel of a `width`-wide grid that is NaN or infinite.
fn all_finite(path: &Path, values: &[f32], width: u32) -> Result<(), HeightMapError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(HeightMapError::NotFinite {
            path: path.into(),
            x: i as u32 % width,
            y: i as u32 / width,
            value: values[i],
        }),
        None => Ok(()),
    }
}

impl HeightMap {
    /// The pyramid's storage: width and height rounded up to powers of two.
    pub fn padded_size(&self) -> (u32, u32) {
        (
            self.width.next_power_of_two(),
            self.height.next_power_of_two(),
        )
    }

    /// Pyramid levels above the map's: the root (level `levels()`) is 1x1 over the padded size.
    pub fn levels(&self) -> u32 {
        let (w, h) = self.padded_size();
        w.max(h).ilog2()
    }

    /// Texels per unit of uv on each axis: (width, height).
    pub fn texels_per_uv(&self) -> glam::DVec2 {
        glam::DVec2::new(self.width.into(), self.height.into())
    }

    /// The depth of texel (x, y).
    pub fn at(&self, x: u32, y: u32) -> f32 {
        self.depth[y as usize * self.width as usize + x as usize]
    }

    /// Builds a `width` x `height` map from depths in `[0, 1]`; `name` is used in errors.
    ///
    /// # Panics
    /// If `depth` does not hold `width * height` entries.
    pub fn from_depths(
        name: &Path,
        width: u32,
        height: u32,
        depth: Vec<f32>,
    ) -> Result<Self, HeightMapError> {
        if width == 0 || height == 0 || depth.is_empty() {
            return Err(HeightMapError::Empty { path: name.into() });
        }
        image_in::check_size(name, width, height)?;
        assert_eq!(
            depth.len(),
            width as usize * height as usize,
            "depth buffer size"
        );
        all_finite(name, &depth, width)?;
        Ok(Self {
            width,
            height,
            depth: depth.into_iter().map(|d| d.clamp(0.0, 1.0)).collect(),
        })
    }

    /// Loads an 8- or 16-bit greyscale (or RGB: the first channel) PNG, or a float EXR, of at
    /// most [`MAX_SIDE`] a side.
    pub fn load(path: &Path, convention: Convention, fit: Fit) -> Result<Self, HeightMapError> {
        let img = image_in::open(path)?;
        let (w, h) = (img.width(), img.height());
        // The first channel, normalised to [0,1] for integer formats and as stored for floats.
        let raw: Vec<f32> = img.to_luma32f().into_raw();
        let values = match img.color() {
            c if c.has_color() => img
                .to_rgb32f()
                .into_raw()
                .chunks_exact(3)
                .map(|p| p[0])
                .collect(),
            _ => raw,
        };
        Self::from_values(path, w, h, &values, convention, fit)
    }

    /// Builds a map from a decoded `width` x `height` grid of values (row-major, row 0 at v = 0)
    /// stored in `convention`: what [`HeightMap::load`] does after decoding, for images that
    /// arrive by other means (an engine's asset loader). `path` names the map in errors.
    ///
    /// # Panics
    /// If `values` does not hold `w * h` entries.
    pub fn from_values(
        path: &Path,
        w: u32,
        h: u32,
        values: &[f32],
        convention: Convention,
        fit: Fit,
    ) -> Result<Self, HeightMapError> {
        if w == 0 || h == 0 || values.is_empty() {
            return Err(HeightMapError::Empty { path: path.into() });
        }
        assert_eq!(values.len(), (w as usize) * (h as usize), "value grid size");
        all_finite(path, values, w)?;
        let depth = to_depth(path, values, convention)?;
        if fit == Fit::Exact || (w == h && w.is_power_of_two()) {
            return Self::from_depths(path, w, h, depth);
        }
        let size = nearest_power_of_two(w.max(h));
        tracing::warn!(
            "{}: resampled {w}x{h} to {size}x{size} (--resample): the surface changes",
            path.display()
        );
        Self::from_depths(path, size, size, resample(&depth, w, h, size))
    }
}

fn to_depth(
    path: &Path,
    values: &[f32],
    convention: Convention,
) -> Result<Vec<f32>, HeightMapError> {
    Ok(match convention {
        Convention::Height => values.iter().map(|v| 1.0 - v).collect(),
        Convention::Depth => values.to_vec(),
        Convention::DepthPhoto => {
            let valid = values.iter().copied().filter(|&v| v > 0.0);
            let (lo, hi) = valid.fold((f32::MAX, f32::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
            if lo > hi {
                return Err(HeightMapError::NoMeasurement { path: path.into() });
            }
            let span = (hi - lo).max(f32::EPSILON);
            values
                .iter()
                .map(|&v| if v > 0.0 { (v - lo) / span } else { 1.0 })
                .collect()
        }
    })
}

fn nearest_power_of_two(n: u32) -> u32 {
    let up = n.max(2).next_power_of_two();
    if up - n > n - up / 2 { up / 2 } else { up }.clamp(2, MAX_SIDE)
}

/// Bilinear resampling with texel centres aligned (corners map to corners).
fn resample(src: &[f32], w: u32, h: u32, size: u32) -> Vec<f32> {
    let at = |x: i64, y: i64| {
        src[(y.clamp(0, h as i64 - 1) * w as i64 + x.clamp(0, w as i64 - 1)) as usize]
    };
    let mut out = Vec::with_capacity((size * size) as usize);
    for j in 0..size {
        for i in 0..size {
            let x = (i as f32 + 0.5) * w as f32 / size as f32 - 0.5;
            let y = (j as f32 + 0.5) * h as f32 / size as f32 - 0.5;
            let (x0, y0) = (x.floor(), y.floor());
            let (fx, fy) = (x - x0, y - y0);
            let (x0, y0) = (x0 as i64, y0 as i64);
            let top = at(x0, y0) * (1.0 - fx) + at(x0 + 1, y0) * fx;
            let bottom = at(x0, y0 + 1) * (1.0 - fx) + at(x0 + 1, y0 + 1) * fx;
            out.push(top * (1.0 - fy) + bottom * fy);
        }
    }
    out
}

/// Seeded pseudo-random maps for the crate's unit tests.
#[cfg(test)]
pub(crate) fn random_map(width: u32, height: u32, seed: u64, levels: u32) -> HeightMap {
    let mut s = seed;
    let depth = (0..width * height)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let v = (s >> 40) as f32 / (1u64 << 24) as f32;
            // `levels` distinct depths make flat plateaus and sharp walls; 0: every depth.
            if levels > 0 {
                (v * levels as f32).floor() / (levels - 1).max(1) as f32
            } else {
                v
            }
            .min(1.0)
        })
        .collect();
    HeightMap::from_depths(Path::new("random"), width, height, depth).unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_power_of_two_rounds_both_ways() {
        assert_eq!(nearest_power_of_two(1025), 1024);
        assert_eq!(nearest_power_of_two(348), 256);
        assert_eq!(nearest_power_of_two(640), 512);
        assert_eq!(nearest_power_of_two(800), 1024);
    }

    #[test]
    fn nan_empty_and_oversized_maps_are_refused_with_the_file_name() {
        let p = Path::new("m.exr");
        let err = HeightMap::from_depths(p, 3, 1, vec![0.0, f32::NAN, 0.0]).unwrap_err();
        assert!(err.to_string().contains("m.exr") && err.to_string().contains("(1, 0)"));
        assert!(matches!(
            HeightMap::from_depths(p, 0, 0, vec![]).unwrap_err(),
            HeightMapError::Empty { .. }
        ));
        let err = HeightMap::from_values(
            p,
            MAX_SIDE + 1,
            1,
            &vec![0.0; MAX_SIDE as usize + 1],
            Convention::Depth,
            Fit::Exact,
        )
        .unwrap_err();
        assert!(
            matches!(
                err,
                HeightMapError::Image(ImageReadError::TooLarge { width, .. }) if width == MAX_SIDE + 1
            ),
            "{err}"
        );
    }

    #[test]
    fn odd_sizes_pad_each_side_to_its_own_power_of_two() {
        let p = Path::new("m");
        let size = |w, h| {
            let map = HeightMap::from_depths(p, w, h, vec![0.5; (w * h) as usize]).unwrap();
            (map.padded_size(), map.levels())
        };
        assert_eq!(size(1, 1), ((1, 1), 0));
        assert_eq!(size(3, 5), ((4, 8), 3));
        assert_eq!(size(4096, 16), ((4096, 16), 12));
        assert_eq!(size(348, 348), ((512, 512), 9));
        assert_eq!(size(1000, 777), ((1024, 1024), 10));
    }

    #[test]
    fn resampling_keeps_a_constant_map_constant() {
        let out = resample(&[0.25; 6 * 5], 6, 5, 4);
        assert!(out.iter().all(|&d| (d - 0.25).abs() < 1e-6));
    }
}
