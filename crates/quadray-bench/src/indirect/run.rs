//! One measured run, as `quadray indirect` prints it: pictures (direct, indirect, combined,
//! error heat map) and the stats (GPU time per pass with a moving and a static light, clusters in
//! the cut, error against the brute force).

use super::temporal::{self, Temporal};
use quadray_core::image_out::{ExposureAdvice, Rgba8Image, check_exposure, heat_map};
use quadray_core::settings::Limits;
use quadray_gpu::Gpu;
use quadray_indirect::picture::{TONE_MAP_WHITE, flip_against, tone_map};
use quadray_indirect::reference::{self, ImageError};
use quadray_indirect::tiles::blockiness::{Order, TileStructure};
use quadray_indirect::{FrameTiming, IndirectError, Method, Renderer, Scene, Settings, WorkCounts};
use serde::Serialize;

/// What to do besides rendering.
#[derive(Clone, Debug)]
pub struct RunOptions {
    pub method: Method,
    /// Timed frames per light mode (0: no timing).
    pub frames: u32,
    /// Also render the GPU brute force and measure the error against it.
    pub reference: bool,
    /// Also compute the CPU ground truth with visibility and measure the error against it (and
    /// the blockiness, which renders the GPU brute force too).
    pub ground_truth: bool,
    /// Also render a sequence of `frames` frames with the light turning this many degrees a
    /// frame and measure its stability.
    pub light_orbit: Option<f32>,
    /// In that sequence (or alone), the camera orbits its target this many degrees a frame.
    pub camera_orbit: Option<f32>,
    /// Radiance scale before tone mapping.
    pub exposure: f32,
}

impl RunOptions {
    /// [`RunOptions::frames`]: a sequence of a few hundred frames is a turn and more; far more
    /// runs for hours.
    pub const FRAMES: Limits<u32> = Limits::closed(0, 1000);
    /// [`RunOptions::light_orbit`] and [`RunOptions::camera_orbit`], degrees a frame.
    pub const ORBIT: Limits<f32> = Limits::closed(-180.0, 180.0);
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
    /// VPL kernels evaluated per shaded pixel (clusters or RSM samples summed), counted in the
    /// shaders: the hardware-independent cost of the method.
    pub vpl_evaluations_per_pixel: f64,
    /// G-buffer and RSM texels, node records and low-resolution samples read per shaded pixel.
    pub texel_fetches_per_pixel: f64,
    /// Bounds of a cluster's contribution to a tile evaluated per shaded pixel (quadtree-tiles).
    pub bound_evaluations_per_pixel: f64,
    /// Mean clusters of a tile's cut over the tiles that see geometry (quadtree-tiles).
    pub clusters_per_tile: Option<f64>,
    /// The totals the two means come from.
    pub work: WorkCounts,
    /// The light moves: RSM, pyramid, validity and cut rebuilt every frame.
    pub gpu_time_ms_moving: Option<FrameTiming>,
    /// The light stays: those buffers reused.
    pub gpu_time_ms_static: Option<FrameTiming>,
    /// Error of the indirect term against the GPU brute force (with `--reference`).
    pub error: Option<ImageError>,
    /// Mean FLIP of the tone-mapped combined picture against direct + brute-force indirect.
    pub flip: Option<f32>,
    /// Error against one bounce from every VPL with exact visibility (with `--ground-truth`).
    pub ground_truth: Option<TruthError>,
    /// Stability under a turning light (with `--light-orbit`).
    pub temporal: Option<Temporal>,
    /// The same sequence without the temporal filter (with `--temporal-weight` below 1),
    /// against the same brute-force frames: the filter's damping and its cost from one run.
    pub temporal_unfiltered: Option<Temporal>,
}

/// Error of the indirect term against the ground truth with visibility, and the FLIP of the
/// combined picture against direct + that indirect light.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct TruthError {
    /// sum |ours - truth| / sum |truth| over the indirect term.
    pub rel_l1: f64,
    /// Root mean square difference of the indirect term.
    pub rmse: f64,
    /// Mean FLIP of the tone-mapped combined pictures.
    pub flip: f32,
    /// Tile structure in the indirect term's error that the brute force's lacks, by the error's
    /// steps across tile boundaries ([`TileStructure::blockiness`], [`Order::Step`]; 1.0 =
    /// none); `None` where it cannot be measured.
    pub blockiness: Option<f64>,
    /// The same by the bends of the error there ([`Order::Bend`]), which see an error that is
    /// continuous across the boundaries but changes slope there.
    pub blockiness_bends: Option<f64>,
    /// The share of the pixels the direct light reaches whose direct shadow differs from the
    /// traced one ([`reference::shadow_mismatch`]).
    pub direct_shadows_wrong: f64,
}

/// Refuses a ground truth that would trace more than [`reference::MAX_GROUND_TRUTH_RAYS`].
pub fn check_ground_truth_size(settings: &Settings) -> Result<(), IndirectError> {
    let rays = u64::from(settings.size.width)
        * u64::from(settings.size.height)
        * u64::from(settings.rsm_size).pow(2);
    if rays > reference::MAX_GROUND_TRUTH_RAYS {
        return Err(IndirectError::Settings(format!(
            "the ground truth traces a ray per pixel and VPL: {}x{} pixels x {}^2 VPLs is {rays:.3e} rays, over the limit of {:.3e}; use a smaller --size or --rsm-size",
            settings.size.width,
            settings.size.height,
            settings.rsm_size,
            reference::MAX_GROUND_TRUTH_RAYS as f64,
        )));
    }
    Ok(())
}

pub struct Outcome {
    pub stats: Stats,
    pub direct: Rgba8Image,
    pub indirect: Rgba8Image,
    pub combined: Rgba8Image,
    /// Per-pixel |error| / mean reference radiance, black 0 to white 0.5.
    pub error_map: Option<Rgba8Image>,
    /// The cut over the RSM (see [`quadray_indirect::picture::cut_view`]): the one cut's
    /// (quadtree methods), or the per-tile cuts' list of the tile at the picture's centre.
    pub cut_view: Option<Rgba8Image>,
    /// The ground truth's indirect light (with `ground_truth`).
    pub ground_truth: Option<Rgba8Image>,
    /// The combined picture is nearly black or white at the exposure given: what would show it.
    pub exposure_advice: Option<ExposureAdvice>,
}

/// Renders `options.method` on `scene`, times it and measures it.
pub fn run(
    gpu: &Gpu,
    scene: &Scene,
    settings: Settings,
    options: &RunOptions,
) -> Result<Outcome, IndirectError> {
    if options.ground_truth {
        check_ground_truth_size(&settings)?;
    }
    let mut renderer = Renderer::new(gpu, scene, settings)?;
    let method = options.method;
    // the ground truth's blockiness holds the method's error to the brute force's
    let brute_force = if options.reference || options.ground_truth {
        Some(renderer.render_frame(Method::Reference)?.indirect)
    } else {
        None
    };
    let reference = brute_force.as_ref().filter(|_| options.reference);
    // The compacted cut's size is the size of the set both quadtree methods use.
    let (clusters_in_cut, mut cut) = if method.uses_quadtree() {
        renderer.render(Method::Quadtree, true, false)?;
        let cut = renderer.read_cut()?;
        (Some(cut.len() as u32), Some(renderer.cut_view(&cut)?))
    } else {
        (None, None)
    };
    let moving = renderer.time(method, true, options.frames)?;
    let still = renderer.time(method, false, options.frames)?;
    let frame = renderer.render_frame(method)?;
    let clusters_per_tile = if method == Method::QuadtreeTiles {
        let cuts = renderer.read_tile_cuts()?;
        let lit: Vec<usize> = cuts.iter().map(Vec::len).filter(|&n| n > 0).collect();
        // the per-tile cuts' view: the list of the tile at the picture's centre
        let size = renderer.settings().size;
        let centre = renderer.read_tile_cut_at(size.width / 2, size.height / 2)?;
        cut = Some(renderer.cut_view(&centre)?);
        Some(lit.iter().sum::<usize>() as f64 / lit.len().max(1) as f64)
    } else {
        None
    };
    let s = renderer.settings().resolved();
    let (w, h) = (s.size.width, s.size.height);
    let combined = frame.combined();
    let error = reference.map(|r| reference::compare(&frame.indirect, r));
    let error_map =
        reference.map(|r| heat_map(w, h, &reference::error_map(&frame.indirect, r), 0.5));
    let combined_image = tone_map(w, h, &combined, options.exposure);
    let exposure_advice = check_exposure(&combined, options.exposure, TONE_MAP_WHITE);
    let flip = reference.map(|r| flip_against(&frame, r, options.exposure));
    let truth = if options.ground_truth {
        let (vpls, receivers) = (renderer.read_vpls()?, renderer.read_receivers()?);
        let direct = reference::direct_truth(&receivers, scene, s.max_lights);
        Some((
            reference::ground_truth(&vpls, &receivers, scene),
            reference::shadow_mismatch(&frame.direct, &direct),
        ))
    } else {
        None
    };
    let temporal = match (options.light_orbit, options.camera_orbit) {
        (None, None) => None,
        (light, camera) => Some(temporal::measure(
            gpu,
            &mut renderer,
            scene,
            method,
            temporal::Orbit {
                light_degrees: light.unwrap_or(0.0),
                camera_degrees: camera.unwrap_or(0.0),
            },
            options.frames,
        )?),
    };
    let ground_truth = truth.as_ref().map(|(truth, direct_shadows_wrong)| {
        let e = reference::compare(&frame.indirect, truth);
        let structure = brute_force.as_deref().and_then(|brute_force| {
            let edges_of = [frame.direct.as_slice(), brute_force];
            Some((TileStructure::new(w, h, truth, &edges_of)?, brute_force))
        });
        let blockiness = |order| {
            let (structure, brute_force) = structure.as_ref()?;
            structure.blockiness(&frame.indirect, brute_force, order)
        };
        TruthError {
            rel_l1: e.rel_l1,
            rmse: e.rmse,
            flip: flip_against(&frame, truth, options.exposure),
            blockiness: blockiness(Order::Step),
            blockiness_bends: blockiness(Order::Bend),
            direct_shadows_wrong: *direct_shadows_wrong,
        }
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
            vpl_evaluations_per_pixel: frame.counts.vpl_evaluations_per_pixel(),
            texel_fetches_per_pixel: frame.counts.texel_fetches_per_pixel(),
            bound_evaluations_per_pixel: frame.counts.bound_evaluations_per_pixel(),
            clusters_per_tile,
            work: frame.counts,
            gpu_time_ms_moving: moving,
            gpu_time_ms_static: still,
            error,
            flip,
            ground_truth,
            temporal: temporal.as_ref().map(|t| t.filtered),
            temporal_unfiltered: temporal.and_then(|t| t.unfiltered),
            settings: s,
        },
        direct: tone_map(w, h, &frame.direct, options.exposure),
        indirect: tone_map(w, h, &frame.indirect, options.exposure),
        combined: combined_image,
        exposure_advice,
        error_map,
        cut_view: cut,
        ground_truth: truth.map(|(t, _)| tone_map(w, h, &t, options.exposure)),
    })
}
