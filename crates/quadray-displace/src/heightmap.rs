//! Height maps in the spec's convention: depth in `[0, 1]` (0 = the polygon's plane, 1 = deepest),
//! 2^n x 2^n texels, row-major with row 0 at v = 0.

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
    /// Refuse it with an error suggesting `--resample`.
    Refuse,
    /// Bilinear resampling to the nearest power of two (1025 -> 1024, 348 -> 256, 640x480 -> 512).
    Resample,
}

/// Why a map was refused; every message names the file.
#[derive(Debug, Error)]
#[allow(missing_docs)] // each variant's message says what its fields are
pub enum HeightMapError {
    #[error("{path}: cannot read the image: {reason}")]
    Unreadable { path: PathBuf, reason: String },
    #[error("{path}: the image is empty (0 texels)")]
    Empty { path: PathBuf },
    #[error(
        "{path}: {width}x{height} is not 2^n x 2^n; resample it to {suggested}x{suggested} (`--resample` on the command line)"
    )]
    NotPowerOfTwo {
        path: PathBuf,
        width: u32,
        height: u32,
        suggested: u32,
    },
    #[error("{path}: {size}x{size} is outside the supported 2x2 .. {max}x{max}")]
    Size { path: PathBuf, size: u32, max: u32 },
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

/// Largest map side accepted: 8192^2 floats is 256 MiB with its pyramid; beyond that GPUs refuse.
pub const MAX_SIZE: u32 = 8192;

#[derive(Clone, Debug, PartialEq)]
/// A square 2^n x 2^n height field in depth convention.
pub struct HeightMap {
    /// log2 of the side: the pyramid has `levels + 1` levels, the root being 1x1.
    pub levels: u32,
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
    /// Texels per side (2^levels).
    pub fn size(&self) -> u32 {
        1 << self.levels
    }

    /// The depth of texel (x, y).
    pub fn at(&self, x: u32, y: u32) -> f32 {
        self.depth[(y * self.size() + x) as usize]
    }

    /// Builds a map from depths in `[0, 1]`; `name` is used in errors.
    pub fn from_depths(name: &Path, size: u32, depth: Vec<f32>) -> Result<Self, HeightMapError> {
        if size == 0 || depth.is_empty() {
            return Err(HeightMapError::Empty { path: name.into() });
        }
        if !size.is_power_of_two() {
            return Err(HeightMapError::NotPowerOfTwo {
                path: name.into(),
                width: size,
                height: size,
                suggested: nearest_power_of_two(size),
            });
        }
        if !(2..=MAX_SIZE).contains(&size) {
            return Err(HeightMapError::Size {
                path: name.into(),
                size,
                max: MAX_SIZE,
            });
        }
        assert_eq!(depth.len(), (size * size) as usize, "depth buffer size");
        all_finite(name, &depth, size)?;
        Ok(Self {
            levels: size.trailing_zeros(),
            depth: depth.into_iter().map(|d| d.clamp(0.0, 1.0)).collect(),
        })
    }

    /// Loads an 8- or 16-bit greyscale (or RGB: the first channel) PNG, or a float EXR.
    pub fn load(path: &Path, convention: Convention, fit: Fit) -> Result<Self, HeightMapError> {
        let img = image::ImageReader::open(path)
            .and_then(|r| r.with_guessed_format())
            .map_err(|e| HeightMapError::Unreadable {
                path: path.into(),
                reason: e.to_string(),
            })?
            .decode()
            .map_err(|e| HeightMapError::Unreadable {
                path: path.into(),
                reason: e.to_string(),
            })?;
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
        let (size, depth) = if w == h && w.is_power_of_two() {
            (w, depth)
        } else if fit == Fit::Resample {
            let size = nearest_power_of_two(w.max(h));
            tracing::warn!(
                "{}: resampled {w}x{h} to {size}x{size} (not a power of two)",
                path.display()
            );
            (size, resample(&depth, w, h, size))
        } else {
            return Err(HeightMapError::NotPowerOfTwo {
                path: path.into(),
                width: w,
                height: h,
                suggested: nearest_power_of_two(w.max(h)),
            });
        };
        Self::from_depths(path, size, depth)
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
    if up - n > n - up / 2 { up / 2 } else { up }.clamp(2, MAX_SIZE)
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
    fn nan_and_odd_sizes_are_refused_with_the_file_name() {
        let p = Path::new("m.exr");
        let err = HeightMap::from_depths(p, 2, vec![0.0, f32::NAN, 0.0, 0.0]).unwrap_err();
        assert!(err.to_string().contains("m.exr") && err.to_string().contains("(1, 0)"));
        let err = HeightMap::from_depths(p, 3, vec![0.0; 9]).unwrap_err();
        assert!(matches!(err, HeightMapError::NotPowerOfTwo { .. }));
        assert!(matches!(
            HeightMap::from_depths(p, 0, vec![]).unwrap_err(),
            HeightMapError::Empty { .. }
        ));
    }

    #[test]
    fn resampling_keeps_a_constant_map_constant() {
        let out = resample(&[0.25; 6 * 5], 6, 5, 4);
        assert!(out.iter().all(|&d| (d - 0.25).abs() < 1e-6));
    }
}
