//! Measures a GPU frame against the CPU ground truth, pixel by pixel: the CPU builds each
//! pixel's ray itself ([`camera_rays`]), traces it exactly, and a pixel is wrong when the GPU's hit
//! is more than one texel (in uv) from the exact one, or when one of them shows the surface (or
//! hits it) and the other does not. The GPU's own rays are compared with the CPU's separately
//! ([`RayAgreement`]), and so are its self-shadows ([`ShadowAgreement`]).

use crate::Settings;
use crate::gpu::Frame;
use crate::heightmap::HeightMap;
use crate::primary_rays::{MIN_COSINE, PixelRay, camera_rays, camera_rays_as, ray_slope};
use crate::pyramid::Addressing;
use crate::reference::{Hit, Ray, Surface, intersect, intersect_all};
use crate::scene::{SurfaceKind, View};
use glam::{DVec2, DVec3};
use quadray_core::image_out::{Rgba8Image, heat_map};
use rayon::prelude::*;

/// Error given to a pixel whose hit/miss status differs from the truth, in texels.
pub const STATUS_MISMATCH_TEXELS: f32 = 8.0;

#[derive(Clone, Debug, serde::Serialize)]
/// A GPU frame measured against the ground truth.
pub struct Accuracy {
    /// Pixels that show the surface (on the GPU, the CPU or both).
    pub covered: usize,
    /// Covered pixels more than a texel off (or of the wrong hit/miss status).
    pub wrong: usize,
    /// `wrong` / `covered`.
    pub wrong_hit_fraction: f64,
    /// Mean distance to the true hit over covered pixels, in texels.
    pub mean_error_texels: f64,
    /// Largest distance to the true hit, in texels.
    pub max_error_texels: f64,
    /// The GPU's rays against the CPU's (None where the rays came from elsewhere).
    pub rays: Option<RayAgreement>,
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
    /// Measures `frame`, drawn of `map` on `surface` with `s`, against the exact intersections
    /// with `truth` of the rays the CPU builds itself from the camera and the surface. To measure
    /// several frames of one view, trace a [`GroundTruth`] once.
    pub fn measure(
        frame: &Frame,
        map: &HeightMap,
        surface: SurfaceKind,
        s: &Settings,
        truth: Surface,
    ) -> Self {
        GroundTruth::trace(map, surface, s, truth).measure(frame)
    }

    /// Black: exact; white: 2+ texels off or wrong hit/miss status; grey: no surface.
    pub fn heat_map(&self) -> Rgba8Image {
        heat_map(self.width, self.height, &self.error_texels, 2.0)
    }
}

/// The exact hits of one view: each pixel's ray and its first intersection with the truth
/// surface, traced once and measured against every frame drawn from that view (each method at
/// one angle, as the benchmark and the tests compare them).
pub struct GroundTruth<'a> {
    map: &'a HeightMap,
    addressing: Addressing,
    rays: Vec<Option<Ray>>,
    hits: Vec<Option<Hit>>,
    /// The rays are the CPU's own (then each frame's rays are compared with them).
    own_rays: bool,
}

impl<'a> GroundTruth<'a> {
    /// The truth of the view `s` sets up on `surface`, on the CPU's own rays.
    pub fn trace(map: &'a HeightMap, surface: SurfaceKind, s: &Settings, truth: Surface) -> Self {
        let rays = camera_rays_as(surface, s, |pixel| pixel.ray);
        Self {
            own_rays: true,
            ..Self::of_rays(map, surface.addressing(), truth, rays)
        }
    }

    /// The truth on `rays` (one per pixel; None where no surface should show) from elsewhere.
    pub fn of_rays(
        map: &'a HeightMap,
        addressing: Addressing,
        truth: Surface,
        rays: Vec<Option<Ray>>,
    ) -> Self {
        let hits = intersect_all(map, addressing, truth, &rays);
        Self {
            map,
            addressing,
            rays,
            hits,
            own_rays: false,
        }
    }

    /// Measures `frame` (of this view) against the truth.
    pub fn measure(&self, frame: &Frame) -> Accuracy {
        let (addressing, texels_per_uv) = (self.addressing, self.map.texels_per_uv());
        let error_texels: Vec<f32> = self
            .rays
            .iter()
            .zip(&frame.hits)
            .zip(&self.hits)
            .map(|((ray, gpu), truth)| {
                let shown = gpu[2] != -2.0;
                if ray.is_none() && !shown {
                    return f32::NAN;
                }
                if ray.is_none() == shown {
                    return STATUS_MISMATCH_TEXELS;
                }
                let gpu_hit = (gpu[2] >= 0.0).then(|| DVec2::new(gpu[0].into(), gpu[1].into()));
                match (gpu_hit, truth) {
                    (Some(g), Some(t)) => {
                        (uv_offset(g - t.uv, addressing) * texels_per_uv).length() as f32
                    }
                    (None, None) => 0.0,
                    _ => STATUS_MISMATCH_TEXELS,
                }
            })
            .collect();
        let errors = error_texels.iter().copied().filter(|e| !e.is_nan());
        let covered = errors.clone().count();
        let wrong = errors.clone().filter(|&e| e > 1.0).count();
        Accuracy {
            covered,
            wrong,
            wrong_hit_fraction: wrong as f64 / covered.max(1) as f64,
            mean_error_texels: errors.clone().map(f64::from).sum::<f64>() / covered.max(1) as f64,
            max_error_texels: errors.fold(0.0, f32::max).into(),
            rays: self
                .own_rays
                .then(|| RayAgreement::of(frame, &self.rays, self.map, addressing)),
            width: frame.color.width,
            height: frame.color.height,
            error_texels,
        }
    }
}

/// A difference of two uv points as the surface sees it: on a wrapped map, whole repeats apart
/// is the same point.
fn uv_offset(d: DVec2, addressing: Addressing) -> DVec2 {
    match addressing {
        Addressing::Wrap => d - d.round(),
        Addressing::Clamp => d,
    }
}

/// The rays the GPU reports it traced against the CPU's own for the same pixels.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RayAgreement {
    /// Pixels that show the surface on one side only.
    pub coverage_mismatches: usize,
    /// Pixels both trace.
    pub compared: usize,
    /// Largest distance between the rays' starting points, in texels.
    pub max_start_texels: f64,
    /// Largest angle between the rays' tangent-space directions, in degrees.
    pub max_direction_deg: f64,
    /// The pixel (x, y) of the largest difference of either kind.
    pub worst_pixel: [u32; 2],
}

impl RayAgreement {
    /// Compares `frame`'s rays with `rays` (the CPU's), on a map of `map`'s size.
    pub fn of(
        frame: &Frame,
        rays: &[Option<Ray>],
        map: &HeightMap,
        addressing: Addressing,
    ) -> Self {
        let direction = |e: DVec2| DVec3::new(-e.x, -e.y, 1.0).normalize();
        let mut agreement = Self {
            coverage_mismatches: 0,
            compared: 0,
            max_start_texels: 0.0,
            max_direction_deg: 0.0,
            worst_pixel: [0, 0],
        };
        let mut worst = 0.0;
        for (i, ((gpu, hit), cpu)) in frame.rays.iter().zip(&frame.hits).zip(rays).enumerate() {
            match (hit[2] != -2.0, cpu) {
                (true, Some(cpu)) => {
                    agreement.compared += 1;
                    let p0 = DVec2::new(gpu[0].into(), gpu[1].into());
                    let e = DVec2::new(gpu[2].into(), gpu[3].into());
                    let start = (uv_offset(p0 - cpu.p0, addressing) * map.texels_per_uv()).length();
                    let angle = direction(e).angle_between(direction(cpu.e)).to_degrees();
                    agreement.max_start_texels = agreement.max_start_texels.max(start);
                    agreement.max_direction_deg = agreement.max_direction_deg.max(angle);
                    // One texel off weighs as much as a degree.
                    if start + angle > worst {
                        worst = start + angle;
                        agreement.worst_pixel = pixel(i, frame.color.width);
                    }
                }
                (false, None) => {}
                _ => agreement.coverage_mismatches += 1,
            }
        }
        agreement
    }
}

fn pixel(index: usize, width: u32) -> [u32; 2] {
    [index as u32 % width, index as u32 / width]
}

/// Self-shadowing against the ground truth: the CPU follows the light's ray from each pixel's
/// exact hit with the shader's rule (lit when the light's ray first meets the surface within 1.5
/// texels along it, or within 0.002 in depth, of the hit; shadowed when the light is below the
/// polygon), and the GPU's shadow flags are compared with it where the GPU's hit is right.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ShadowAgreement {
    /// Pixels whose GPU hit is within a texel of the truth.
    pub compared: usize,
    /// Of those, the pixels the truth puts in shadow.
    pub shadowed: usize,
    /// Of those compared, the pixels whose shadow flag differs from the truth's.
    pub disagree: usize,
    /// `disagree` / `compared`.
    pub disagree_fraction: f64,
}

impl ShadowAgreement {
    /// Measures `frame` (drawn with `s.shadows`) of `map` on `surface` against the truth.
    pub fn measure(
        frame: &Frame,
        map: &HeightMap,
        surface: SurfaceKind,
        s: &Settings,
        truth: Surface,
    ) -> Self {
        let exact = ExactLight {
            map,
            addressing: surface.addressing(),
            truth,
            light: View::of(surface, s).light.as_dvec3(),
            depth_scale: f64::from(s.depth_scale),
            tile_world: f64::from(surface.tile_world()),
        };
        let texels = map.texels_per_uv();
        // (truth shadowed, GPU shadowed) where the GPU's hit is right.
        let flags: Vec<(bool, bool)> = camera_rays(surface, s)
            .par_iter()
            .zip(&frame.hits)
            .zip(&frame.in_shadow)
            .filter_map(|((ray, gpu), &gpu_shadowed)| {
                let ray = ray.as_ref()?;
                let hit = intersect(map, exact.addressing, truth, ray.ray)?;
                let gpu_hit = DVec2::new(gpu[0].into(), gpu[1].into());
                let off = (uv_offset(gpu_hit - hit.uv, exact.addressing) * texels).length();
                (gpu[2] >= 0.0 && off <= 1.0).then(|| (!exact.reaches(ray, hit), gpu_shadowed))
            })
            .collect();
        let compared = flags.len();
        let disagree = flags.iter().filter(|(t, g)| t != g).count();
        Self {
            compared,
            shadowed: flags.iter().filter(|(t, _)| *t).count(),
            disagree,
            disagree_fraction: disagree as f64 / compared.max(1) as f64,
        }
    }
}

/// The light's rays, traced exactly.
struct ExactLight<'a> {
    map: &'a HeightMap,
    addressing: Addressing,
    truth: Surface,
    light: DVec3,
    depth_scale: f64,
    tile_world: f64,
}

impl ExactLight<'_> {
    /// Whether the light reaches `hit` of `ray` by the rule of `shadow_lit` in `trace.wgsl`.
    fn reaches(&self, ray: &PixelRay, hit: Hit) -> bool {
        let world = ray.world_at(hit, self.depth_scale, self.tile_world);
        let to_light = (self.light - world).normalize();
        let [t, b, n] = ray.frame;
        let l = DVec3::new(to_light.dot(t), to_light.dot(b), to_light.dot(n));
        if l.z <= MIN_COSINE {
            return false;
        }
        let el = ray_slope(l, self.depth_scale);
        let from_light = Ray {
            p0: hit.uv - el * hit.z,
            e: el,
        };
        let Some(first) = intersect(self.map, self.addressing, self.truth, from_light) else {
            return true;
        };
        let short_by = hit.z - first.z;
        short_by * (el * self.map.texels_per_uv()).length() <= 1.5 || short_by <= 2.0e-3
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
