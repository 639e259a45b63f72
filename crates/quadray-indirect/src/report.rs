//! One measured run, as `quadray indirect` prints it: pictures (direct, indirect, combined,
//! error heat map) and the stats (GPU time per pass with a moving and a static light, clusters in
//! the cut, error against the brute force).

use crate::gpu::{CutNode, Frame, FrameTiming, Method, Renderer, Settings};
use crate::reference::{self, ImageError};
use crate::{IndirectError, Scene};
use quadray_core::image_out::{Rgba8Image, heat_map};
use quadray_gpu::Gpu;
use serde::Serialize;

/// What to do besides rendering.
#[derive(Clone, Debug)]
pub struct RunOptions {
    pub method: Method,
    /// Timed frames per light mode (0: no timing).
    pub frames: u32,
    /// Also render the GPU brute force and measure the error against it.
    pub reference: bool,
    /// Radiance scale before tone mapping.
    pub exposure: f32,
}

#[derive(Clone, Debug, Serialize)]
pub struct Stats {
    pub scene: String,
    pub adapter: String,
    pub method: Method,
    pub width: u32,
    pub height: u32,
    pub rsm_size: u32,
    pub settings: Settings,
    /// Clusters the compacted cut holds (quadtree methods; the per-level passes use the same set).
    pub clusters_in_cut: Option<u32>,
    /// Pixels the upsampler recomputed at full resolution (sub-sampled quadtree).
    pub recomputed_pixels: u32,
    /// The light moves: RSM, pyramid, validity and cut rebuilt every frame.
    pub gpu_time_ms_moving: Option<FrameTiming>,
    /// The light stays: those buffers reused.
    pub gpu_time_ms_static: Option<FrameTiming>,
    /// Error of the indirect term against the GPU brute force (with `--reference`).
    pub error: Option<ImageError>,
    /// Mean FLIP of the tone-mapped combined picture against direct + brute-force indirect.
    pub flip: Option<f32>,
}

pub struct Outcome {
    pub stats: Stats,
    pub direct: Rgba8Image,
    pub indirect: Rgba8Image,
    pub combined: Rgba8Image,
    /// Per-pixel |error| / mean reference radiance, black 0 to white 0.5.
    pub error_map: Option<Rgba8Image>,
    /// The cut over the RSM (quadtree methods), see [`cut_view`].
    pub cut_view: Option<Rgba8Image>,
}

/// Exposure, then 1 - exp(-x) and the sRGB curve.
pub fn tone_map(width: u32, height: u32, radiance: &[[f32; 3]], exposure: f32) -> Rgba8Image {
    let encode = |v: f32| {
        let x = 1.0 - (-v.max(0.0) * exposure).exp();
        let s = if x <= 0.003_130_8 {
            12.92 * x
        } else {
            1.055 * x.powf(1.0 / 2.4) - 0.055
        };
        (s.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
    };
    Rgba8Image {
        width,
        height,
        pixels: radiance
            .iter()
            .map(|p| [encode(p[0]), encode(p[1]), encode(p[2]), 255])
            .collect(),
    }
}

/// Outline colours of the cut's clusters by level (0 = single VPLs).
const LEVEL_COLOURS: [[u8; 4]; 6] = [
    [255, 255, 255, 255],
    [255, 64, 64, 255],
    [255, 200, 0, 255],
    [64, 220, 64, 255],
    [64, 160, 255, 255],
    [230, 90, 255, 255],
];

/// The selected clusters over the RSM that they cluster: the RSM's flux (exposed by its mean over
/// lit texels), magnified to at least 512 pixels, with every cluster of the cut outlined in a
/// colour by its level (white single VPLs, then red, yellow, green, blue, violet going up).
pub fn cut_view(rsm_size: u32, flux: &[[f32; 3]], cut: &[CutNode]) -> Rgba8Image {
    let zoom = (512 / rsm_size).max(1);
    let side = rsm_size * zoom;
    let luminance = |p: &[f32; 3]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let (sum, lit) = flux
        .iter()
        .map(luminance)
        .filter(|&l| l > 0.0)
        .fold((0.0, 0u32), |(s, n), l| (s + l, n + 1));
    let exposure = if sum > 0.0 { lit as f32 / sum } else { 1.0 };
    let rsm = tone_map(rsm_size, rsm_size, flux, exposure);
    let mut image = Rgba8Image {
        width: side,
        height: side,
        pixels: (0..side * side)
            .map(|i| rsm.pixels[((i / side / zoom) * rsm_size + i % side / zoom) as usize])
            .collect(),
    };
    for node in cut {
        let colour = LEVEL_COLOURS[node.level as usize % LEVEL_COLOURS.len()];
        let n = (1 << node.level) * zoom;
        let (x0, y0) = (node.x * n, node.y * n);
        // top and left edges: neighbours draw the others, so every boundary is drawn once
        for i in 0..n.min(side - x0) {
            image.pixels[(y0 * side + x0 + i) as usize] = colour;
        }
        for i in 0..n.min(side - y0) {
            image.pixels[((y0 + i) * side + x0) as usize] = colour;
        }
    }
    image
}

/// Mean FLIP (NVIDIA's perceptual difference, 0 = identical) of `test` against `reference`.
pub fn mean_flip(reference: &Rgba8Image, test: &Rgba8Image) -> f32 {
    let rgb = |img: &Rgba8Image| -> Vec<u8> {
        img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect()
    };
    let flip_image =
        |img: &Rgba8Image| nv_flip::FlipImageRgb8::with_data(img.width, img.height, &rgb(img));
    let map = nv_flip::flip(
        flip_image(reference),
        flip_image(test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    nv_flip::FlipPool::from_image(&map).mean()
}

/// Renders `options.method` on `scene`, times it and measures it.
pub fn run(
    gpu: &Gpu,
    scene: &Scene,
    settings: Settings,
    options: &RunOptions,
) -> Result<Outcome, IndirectError> {
    let mut renderer = Renderer::new(gpu, scene, settings)?;
    let method = options.method;
    let reference = if options.reference {
        Some(renderer.render_frame(Method::Reference)?.indirect)
    } else {
        None
    };
    // The compacted cut's size is the size of the set both quadtree methods use.
    let (clusters_in_cut, cut) = if method.uses_quadtree() {
        renderer.render(Method::Quadtree, true, false)?;
        let cut = renderer.read_cut()?;
        let rsm_size = renderer.settings().rsm_size;
        let picture = cut_view(rsm_size, &renderer.read_rsm_flux()?, &cut);
        (Some(cut.len() as u32), Some(picture))
    } else {
        (None, None)
    };
    let moving = renderer.time(method, true, options.frames)?;
    let still = renderer.time(method, false, options.frames)?;
    let frame = renderer.render_frame(method)?;
    let s = renderer.settings().clone();
    let (w, h) = (s.width, s.height);
    let combined = frame.combined();
    let error = reference
        .as_ref()
        .map(|r| reference::compare(&frame.indirect, r));
    let error_map = reference
        .as_ref()
        .map(|r| heat_map(w, h, &reference::error_map(&frame.indirect, r), 0.5));
    let combined_image = tone_map(w, h, &combined, options.exposure);
    let flip = reference.as_ref().map(|r| {
        let truth = Frame {
            indirect: r.clone(),
            ..frame.clone()
        };
        mean_flip(
            &tone_map(w, h, &truth.combined(), options.exposure),
            &combined_image,
        )
    });
    Ok(Outcome {
        stats: Stats {
            scene: scene.name.clone(),
            adapter: gpu.describe(),
            method,
            width: w,
            height: h,
            rsm_size: s.rsm_size,
            clusters_in_cut,
            recomputed_pixels: frame.recomputed,
            gpu_time_ms_moving: moving,
            gpu_time_ms_static: still,
            error,
            flip,
            settings: s,
        },
        direct: tone_map(w, h, &frame.direct, options.exposure),
        indirect: tone_map(w, h, &frame.indirect, options.exposure),
        combined: combined_image,
        error_map,
        cut_view: cut,
    })
}
