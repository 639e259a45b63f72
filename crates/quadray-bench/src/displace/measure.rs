//! What every table of `quadray bench displace` shares: the measuring context (the GPU, how long
//! to time, the timings so far), the rows and ratios results.json holds, and the settings and
//! figures the tables are written with.

use quadray_displace::heightmap::HeightMap;
use quadray_displace::{DisplaceError, Layers, Method, Renderer, Settings, Size};
use quadray_gpu::Gpu;
use serde::Serialize;

/// One timed configuration.
#[derive(Serialize)]
pub struct TimingRow {
    pub experiment: String,
    pub map: String,
    /// The map's width and height in texels.
    pub map_size: [u32; 2],
    pub method: String,
    pub width: u32,
    pub height: u32,
    pub view_angle_deg: f32,
    pub gpu_time_ms: Option<f64>,
    pub p10_ms: Option<f64>,
    pub p90_ms: Option<f64>,
    pub frames: usize,
    pub memory_bytes: u64,
}

/// One method's accuracy on one map at one view angle.
#[derive(Serialize)]
pub struct AccuracyRow {
    pub map: String,
    pub method: String,
    pub view_angle_deg: f32,
    pub wrong_hit_fraction: f64,
    pub mean_error_texels: f64,
    pub covered: usize,
    pub mean_iterations: f64,
    pub texel_fetches_per_pixel: f64,
    pub iteration_cap_hits: usize,
}

/// The paper's claims as ratios.
#[derive(Serialize, Default)]
pub struct Ratios {
    /// pyramid / POM-16 GPU time at 512x512 with a 256^2 map (target <= 1.5).
    pub pyramid_over_pom16_paper_size: Option<f64>,
    /// The same at 1920x1080 with a 1024^2 map.
    pub pyramid_over_pom16_today: Option<f64>,
    /// POM layers needed to reach the pyramid's accuracy on the sharp map at 80 degrees.
    pub pom_layers_to_match: Option<u32>,
    /// POM time at that layer count / pyramid time (target >= 5).
    pub pom_matched_over_pyramid: Option<f64>,
    /// The last POM layer count tried: (layers, wrong-hit fraction, POM time / pyramid time).
    pub pom_most_layers: Option<(u32, f64, Option<f64>)>,
    /// Pyramid time with the 4096^2 map / with the 256^2 map (target <= 1.3).
    pub pyramid_4096_over_256: Option<f64>,
    /// The same with the LOD of section 3.4 chosen from screen-space derivatives.
    pub pyramid_lod_auto_4096_over_256: Option<f64>,
    /// Pyramid with LOD from derivatives / POM-16 at 1920x1080 (POM samples level 0 as here).
    pub pyramid_lod_auto_over_pom16_today: Option<f64>,
}

/// The measuring context every table shares: the GPU, how long to time, and the timings so far.
pub struct Bench<'a> {
    pub gpu: &'a Gpu,
    pub quick: bool,
    /// Frames per median.
    pub frames: usize,
    /// The paper's screen side (smaller when quick).
    pub paper: u32,
    pub timings: Vec<TimingRow>,
}

impl Bench<'_> {
    /// Times `s` on `renderer` and keeps the row; returns the median GPU ms.
    pub fn time(
        &mut self,
        experiment: &str,
        name: &str,
        map: &HeightMap,
        renderer: &mut Renderer,
        s: &Settings,
    ) -> Result<Option<f64>, DisplaceError> {
        let summary = renderer.time(self.gpu, s, self.frames)?;
        self.timings.push(TimingRow {
            experiment: experiment.into(),
            map: name.into(),
            map_size: [map.width, map.height],
            method: s.caption(),
            width: s.size.width,
            height: s.size.height,
            view_angle_deg: s.view_angle_deg,
            gpu_time_ms: summary.map(|t| t.median_ms),
            p10_ms: summary.map(|t| t.p10_ms),
            p90_ms: summary.map(|t| t.p90_ms),
            frames: self.frames,
            memory_bytes: renderer.memory_bytes(s.method),
        });
        Ok(summary.map(|t| t.median_ms))
    }

    /// `s` at the paper's screen size and its 60 degree view.
    pub fn paper_view(&self, s: Settings) -> Settings {
        Settings {
            size: Size::new(self.paper, self.paper),
            view_angle_deg: 60.0,
            ..s
        }
    }
}

/// `method`'s timed settings with a fixed POM / relief layer count.
pub fn fixed_layers(method: Method, layers: u32) -> Settings {
    Settings {
        layers: Layers {
            min: layers,
            max: layers,
        },
        ..method.timed()
    }
}

/// The methods traced per pixel, which every timing and accuracy table compares (the
/// rasterised mesh is figure 20's), with `settings` of each.
pub fn traced(settings: fn(Method) -> Settings) -> Vec<Settings> {
    Method::ALL
        .into_iter()
        .filter(|m| m.truth().is_some())
        .map(settings)
        .collect()
}

pub(super) fn ms(v: Option<f64>) -> String {
    v.map_or("n/a".into(), |v| format!("{v:.3}"))
}

pub(super) fn ratio(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    Some(a? / b?)
}

pub(super) fn ratio_text(v: Option<f64>) -> String {
    v.map_or("n/a".into(), |v| format!("{v:.2}"))
}
