//! Measures a GPU frame against the CPU ground truth, pixel by pixel, on the very rays the GPU
//! traced: a pixel is wrong when its hit is more than one texel (in uv) from the exact one, or
//! when one of them hits and the other leaves the map.

use crate::gpu::Frame;
use crate::heightmap::HeightMap;
use crate::pyramid::Addressing;
use crate::reference::{Ray, Surface, intersect_all};
use glam::DVec2;
use quadray_core::image_out::{Rgba8Image, heat_map};

/// Error given to a pixel whose hit/miss status differs from the truth, in texels.
pub const STATUS_MISMATCH_TEXELS: f32 = 8.0;

#[derive(Clone, Debug, serde::Serialize)]
/// A GPU frame measured against the ground truth.
pub struct Accuracy {
    /// Pixels that show the surface.
    pub covered: usize,
    /// Covered pixels more than a texel off (or of the wrong hit/miss status).
    pub wrong: usize,
    /// `wrong` / `covered`.
    pub wrong_hit_fraction: f64,
    /// Mean distance to the true hit over covered pixels, in texels.
    pub mean_error_texels: f64,
    /// Largest distance to the true hit, in texels.
    pub max_error_texels: f64,
    #[serde(skip)]
    /// Frame width in pixels.
    pub width: u32,
    #[serde(skip)]
    /// Frame height in pixels.
    pub height: u32,
    /// Per pixel, the distance to the true hit in texels (NaN where there is no surface).
    #[serde(skip)]
    pub error_texels: Vec<f32>,
}

impl Accuracy {
    /// Traces every pixel's ray of `frame` on the CPU against `truth` and compares the hits.
    pub fn measure(frame: &Frame, map: &HeightMap, addressing: Addressing, truth: Surface) -> Self {
        let rays: Vec<Option<Ray>> = frame
            .rays
            .iter()
            .zip(&frame.hits)
            .map(|(r, h)| {
                (h[2] != -2.0).then(|| Ray {
                    p0: DVec2::new(r[0].into(), r[1].into()),
                    e: DVec2::new(r[2].into(), r[3].into()),
                })
            })
            .collect();
        let truth_hits = intersect_all(map, addressing, truth, &rays);
        let texels_per_uv = map.texels_per_uv();
        let error_texels: Vec<f32> = rays
            .iter()
            .zip(&frame.hits)
            .zip(&truth_hits)
            .map(|((ray, gpu), truth)| {
                if ray.is_none() {
                    return f32::NAN;
                }
                let gpu_hit = (gpu[2] >= 0.0).then(|| DVec2::new(gpu[0].into(), gpu[1].into()));
                match (gpu_hit, truth) {
                    (Some(g), Some(t)) => ((g - t.uv) * texels_per_uv).length() as f32,
                    (None, None) => 0.0,
                    _ => STATUS_MISMATCH_TEXELS,
                }
            })
            .collect();
        let errors = error_texels.iter().copied().filter(|e| !e.is_nan());
        let covered = errors.clone().count();
        let wrong = errors.clone().filter(|&e| e > 1.0).count();
        Self {
            covered,
            wrong,
            wrong_hit_fraction: wrong as f64 / covered.max(1) as f64,
            mean_error_texels: errors.clone().map(f64::from).sum::<f64>() / covered.max(1) as f64,
            max_error_texels: errors.fold(0.0, f32::max).into(),
            width: frame.color.width,
            height: frame.color.height,
            error_texels,
        }
    }

    /// Black: exact; white: 2+ texels off or wrong hit/miss status; grey: no surface.
    pub fn heat_map(&self) -> Rgba8Image {
        heat_map(self.width, self.height, &self.error_texels, 2.0)
    }
}

/// Iterations and texel reads per pixel, and how many pixels the iteration cap stopped.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Cost {
    /// Mean iterations over covered pixels.
    pub mean_iterations: f64,
    /// Mean texels the search read (every textureLoad of the trace) over covered pixels.
    pub texel_fetches_per_pixel: f64,
    /// Most iterations any pixel took.
    pub max_iterations: u32,
    /// Pixels a cap stopped (must be 0).
    pub iteration_cap_hits: usize,
}

impl Cost {
    /// The cost of `frame`'s searches.
    pub fn of(frame: &Frame) -> Self {
        let covered = frame
            .hits
            .iter()
            .zip(&frame.fetches)
            .filter(|(h, _)| h[2] != -2.0);
        let (mut sum, mut fetches, mut max, mut caps, mut n) = (0.0, 0.0, 0u32, 0, 0usize);
        for (h, f) in covered {
            let it = h[3].abs();
            sum += f64::from(it);
            fetches += f64::from(*f);
            max = max.max(it as u32);
            caps += usize::from(h[3] < 0.0);
            n += 1;
        }
        Self {
            mean_iterations: sum / n.max(1) as f64,
            texel_fetches_per_pixel: fetches / n.max(1) as f64,
            max_iterations: max,
            iteration_cap_hits: caps,
        }
    }

    /// The iteration-count heat map the viewer can overlay.
    pub fn heat_map(frame: &Frame, max: f32) -> Rgba8Image {
        let values: Vec<f32> = frame
            .hits
            .iter()
            .map(|h| if h[2] == -2.0 { f32::NAN } else { h[3].abs() })
            .collect();
        heat_map(frame.color.width, frame.color.height, &values, max)
    }
}
