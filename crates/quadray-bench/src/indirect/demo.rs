//! The pictures of `quadray demo`: direct, indirect (the default method) and combined light on the
//! Cornell box with the brute force, the error heat map and the paper's one cut beside them; the
//! one cut and the centre tile's per-tile cut over the RSM; the paper's figure 9 (quadtree against RSM
//! sampling at equal time and at 2040 samples, and the per-tile cuts); the atrium; the leak scene with and without
//! indirect shadows beside the ground truth with visibility; the sunlit courtyard and the room lit
//! by three point lights beside their ground truths; the two visibility scenes held apart from
//! tuning without indirect shadows, with the depth maps marched and with the occupancy grid,
//! beside their ground truths. The pictures beside a ground truth with visibility are half the
//! demo's side, and the point lights' RSMs 16^2 a view: the truths are most of the demo's time.

use quadray_core::image_out::{Rgba8Image, heat_map, montage};
use quadray_gpu::Gpu;
use quadray_indirect::picture::{flip_against, tone_map};
use quadray_indirect::reference::{
    compare, direct_truth, error_map, ground_truth, shadow_mismatch,
};
use quadray_indirect::scene::{LightKind, scenes_dir};
use quadray_indirect::{Frame, IndirectError, Method, Renderer, Scene, Settings};
use std::path::{Path, PathBuf};

const EXPOSURE: f32 = 1.0;
/// Frames a timed picture's median takes (its caption's milliseconds, and RSM sampling's sample
/// count at the quadtree's time).
const FRAMES: u32 = 3;

fn settings(gpu: &Gpu, width: u32, height: u32, samples: u32) -> Settings {
    // the brute force beside every picture costs pixels x VPLs: small RSMs on a CPU rasterizer
    let rsm_size = if gpu.is_software() { 32 } else { 512 };
    Settings {
        samples,
        ..sized(width, height, rsm_size)
    }
}

/// [`Settings::sized`] with the direct light's shadow maps a texel a pixel of the picture's longer
/// side (the default takes two, for the near ground of a large frame): a point light's six maps
/// at twice the demo's side were a tenth of the demo's time on a CPU rasterizer.
fn sized(width: u32, height: u32, rsm_size: u32) -> Settings {
    Settings {
        shadow_map_size: Some(width.max(height).next_power_of_two()),
        ..Settings::sized(width, height, rsm_size)
    }
}

/// The side of a picture beside a ground truth with visibility: half the demo's (at least 16).
/// The truth traces a ray for every pixel and VPL that face each other, the most of the demo's
/// CPU time; a quarter of the pixels is a quarter of it.
fn truth_side(size: u32) -> u32 {
    (size / 2).max(16)
}

/// The RSM side a light view for a ground truth with visibility of `scene`: 32 (1,024 VPLs a
/// view), 16 where a point light's six views would multiply the truth's rays by six or more.
fn truth_rsm_size(scene: &Scene) -> u32 {
    let views: usize = scene
        .lights
        .iter()
        .map(|l| match l.kind {
            LightKind::Point { .. } => 6,
            _ => 1,
        })
        .sum();
    if views > 2 { 16 } else { 32 }
}

fn caption_ms(ms: Option<f64>) -> String {
    ms.map_or(String::new(), |t| format!(" {t:.2}ms"))
}

/// Renders every demo picture into `out` and returns the files written.
pub fn render_demo(
    gpu: &Gpu,
    out: &Path,
    size: u32,
    mut progress: impl FnMut(&str),
) -> Result<Vec<PathBuf>, IndirectError> {
    let mut files = Vec::new();
    let scene = Scene::cornell();
    progress("cornell: quadtree and brute force");
    let mut r = Renderer::new(gpu, &scene, settings(gpu, size, size, 256))?;
    let brute = r.render_frame(Method::Reference)?.indirect;
    r.render(Method::Quadtree, true, false)?;
    let quadtree_ms = r.time(Method::Quadtree, false, FRAMES)?.map(|t| t.total_ms);
    let frame = r.render_frame(Method::Quadtree)?;
    let clusters = r.clusters_in_cut()?;
    let one_cut = r.cut_view(&r.read_cut()?)?;
    let e = compare(&frame.indirect, &brute);
    // what a user gets: the default method, beside the paper's one cut
    let default_frame = r.render_frame(Method::DEFAULT)?;
    let default_error = compare(&default_frame.indirect, &brute);
    let tile = |v: &[[f32; 3]]| tone_map(size, size, v, EXPOSURE);
    let picture = montage(
        &[
            ("direct".into(), tile(&default_frame.direct)),
            (
                format!("indirect, {}", Method::DEFAULT),
                tile(&default_frame.indirect),
            ),
            ("combined".into(), tile(&default_frame.combined())),
            ("brute force indirect".into(), tile(&brute)),
            (
                format!("error (white 50%), L1 {:.3}", default_error.rel_l1),
                heat_map(size, size, &error_map(&default_frame.indirect, &brute), 0.5),
            ),
            (
                format!("one cut, {clusters} clusters, L1 {:.3}", e.rel_l1),
                tile(&frame.indirect),
            ),
        ],
        3,
    );
    files.push(save(&picture, &out.join("cornell.png"))?);
    progress("figure 9: RSM sampling at equal time, and per-tile cuts");
    r.render(Method::QuadtreeTiles, true, false)?;
    let per_tile_ms = r
        .time(Method::QuadtreeTiles, false, FRAMES)?
        .map(|t| t.total_ms);
    let per_tile = r.read_frame()?.indirect;
    let centre = r.read_tile_cut_at(size / 2, size / 2)?;
    let cut_picture = montage(
        &[
            (
                format!("the one cut over the RSM: {clusters} clusters"),
                one_cut,
            ),
            (
                format!("per-tile cuts, centre tile: {} clusters", centre.len()),
                r.cut_view(&centre)?,
            ),
        ],
        2,
    );
    files.push(save(&cut_picture, &out.join("cornell_cut.png"))?);
    let mut tiles: Vec<(String, Rgba8Image)> = vec![
        (
            format!("quadtree{} L1 {:.3}", caption_ms(quadtree_ms), e.rel_l1),
            tile(&frame.indirect),
        ),
        (
            format!(
                "per-tile cuts{} L1 {:.3}",
                caption_ms(per_tile_ms),
                compare(&per_tile, &brute).rel_l1
            ),
            tile(&per_tile),
        ),
    ];
    let mut rsm_runs = Vec::new();
    for samples in [16, 64, 216, 2040] {
        let mut rs = Renderer::new(gpu, &scene, settings(gpu, size, size, samples))?;
        rs.render(Method::Rsm, true, false)?;
        let ms = rs.time(Method::Rsm, false, FRAMES)?.map(|t| t.total_ms);
        let image = rs.read_frame()?.indirect;
        rsm_runs.push((samples, ms, image));
    }
    // the sample count whose time is closest to the quadtree's (216 without timestamps)
    let equal_time = rsm_runs
        .iter()
        .filter(|(s, _, _)| *s != 2040)
        .min_by(|a, b| {
            let gap = |ms: Option<f64>| match (ms, quadtree_ms) {
                (Some(a), Some(b)) => (a - b).abs(),
                _ => f64::MAX,
            };
            gap(a.1).total_cmp(&gap(b.1))
        })
        .filter(|_| quadtree_ms.is_some())
        .or_else(|| rsm_runs.iter().find(|(s, _, _)| *s == 216));
    for (samples, ms, image) in rsm_runs
        .iter()
        .filter(|run| equal_time.is_some_and(|e| e.0 == run.0) || run.0 == 2040)
    {
        let err = compare(image, &brute).rel_l1;
        tiles.push((
            format!("RSM {samples}{} L1 {err:.3}", caption_ms(*ms)),
            tile(image),
        ));
    }
    files.push(save(
        &montage(&tiles, 2),
        &out.join("figure9_equal_time.png"),
    )?);

    progress("atrium");
    let atrium = Scene::load(&scenes_dir().join("atrium.toml"))?;
    let (w, h) = (size * 16 / 9, size);
    let mut r = Renderer::new(gpu, &atrium, settings(gpu, w, h, 256))?;
    let frame = r.render_frame(Method::DEFAULT)?;
    let combined = frame.combined();
    let pictures = montage(
        &[
            ("direct".into(), tone_map(w, h, &frame.direct, EXPOSURE)),
            (
                "direct + indirect".into(),
                tone_map(w, h, &combined, EXPOSURE),
            ),
        ],
        2,
    );
    files.push(save(&pictures, &out.join("atrium.png"))?);

    progress("leak scene: indirect shadows and the ground truth");
    files.push(leak_picture(gpu, size, &out.join("leak.png"))?);
    for (scene, what) in [
        ("courtyard", "the sun"),
        ("lamplit_room", "three point lights"),
    ] {
        progress(&format!("{scene}: {what} and the ground truth"));
        let path = out.join(format!("{scene}.png"));
        files.push(lights_picture(gpu, size, scene, &path)?);
    }
    for scene in [
        "visibility-shelf",
        "visibility-storeys",
        "visibility-pillars",
        "courtyard",
    ] {
        progress(&format!(
            "{scene}: indirect shadows on a scene nobody tuned on"
        ));
        let path = out.join(format!("{scene}-shadows.png"));
        files.push(held_apart_picture(gpu, size, scene, &path)?);
    }
    Ok(files)
}

/// Exposure of the held-apart scenes' pictures: four times the others', so that the dark rooms
/// can be seen.
const DARK_EXPOSURE: f32 = 4.0 * EXPOSURE;

/// A visibility scene held apart from tuning (`scenes_dir()/NAME.toml`): the default method's
/// bounce without indirect shadows, with the depth maps marched alone, with the occupancy grid
/// (the default), and the bounce from every VPL with exact visibility, each with its FLIP to the
/// last (at [`truth_side`] with a [`truth_rsm_size`] RSM, the ground truth takes seconds).
fn held_apart_picture(
    gpu: &Gpu,
    size: u32,
    name: &str,
    path: &Path,
) -> Result<PathBuf, IndirectError> {
    let scene = Scene::load(&scenes_dir().join(format!("{name}.toml")))?;
    let side = truth_side(size);
    let (w, h) = (side * 4 / 3, side);
    let plain = sized(w, h, truth_rsm_size(&scene));
    let mut r = Renderer::new(gpu, &scene, plain.clone())?;
    let without = r.render_frame(Method::DEFAULT)?;
    let truth = ground_truth(&r.read_vpls()?, &r.read_receivers()?, &scene);
    let shadowed = |shadow_grid| {
        let settings = Settings {
            indirect_shadows: true,
            shadow_grid,
            ..plain.clone()
        };
        Renderer::new(gpu, &scene, settings)?.render_frame(Method::DEFAULT)
    };
    let tile = |v: &[[f32; 3]]| tone_map(w, h, v, DARK_EXPOSURE);
    let mut pictures = Vec::new();
    // (short captions: the demo's smallest pictures are 128 pixels wide)
    for (caption, frame) in [
        ("none", without),
        ("march", shadowed(0)?),
        ("grid", shadowed(Settings::DEFAULT.shadow_grid)?),
    ] {
        let flip = flip_against(&frame, &truth, EXPOSURE);
        pictures.push((format!("{caption}, FLIP {flip:.3}"), tile(&frame.indirect)));
    }
    pictures.push(("true bounce".into(), tile(&truth)));
    save(&montage(&pictures, 2), path)
}

/// A scene lit by other lights than a spot (`scenes_dir()/NAME.toml`): the direct light (with the
/// share of its pixels whose shadow differs from a traced one's), with the default method's
/// bounce (indirect shadows on), and with the bounce from every VPL with exact visibility (the
/// ground truth, at [`truth_side`] with a [`truth_rsm_size`] RSM); below, the method's bounce
/// with its FLIP, the true bounce and the error heat map.
fn lights_picture(gpu: &Gpu, size: u32, name: &str, path: &Path) -> Result<PathBuf, IndirectError> {
    let scene = Scene::load(&scenes_dir().join(format!("{name}.toml")))?;
    let side = truth_side(size);
    let (w, h) = (side * 4 / 3, side);
    let settings = Settings {
        indirect_shadows: true,
        ..sized(w, h, truth_rsm_size(&scene))
    };
    let mut r = Renderer::new(gpu, &scene, settings.clone())?;
    let frame = r.render_frame(Method::DEFAULT)?;
    let receivers = r.read_receivers()?;
    let truth = ground_truth(&r.read_vpls()?, &receivers, &scene);
    let direct = direct_truth(&receivers, &scene, settings.max_lights);
    let off = shadow_mismatch(&frame.direct, &direct);
    let tile = |v: &[[f32; 3]]| tone_map(w, h, v, EXPOSURE);
    let with_truth = Frame {
        indirect: truth.clone(),
        ..frame.clone()
    }
    .combined();
    let flip = flip_against(&frame, &truth, EXPOSURE);
    // (short captions: the demo's smallest pictures are 128 pixels wide)
    let pictures = [
        (
            format!("direct, {:.1}% off", off * 100.0),
            tile(&frame.direct),
        ),
        ("+ bounce".into(), tile(&frame.combined())),
        ("+ true bounce".into(), tile(&with_truth)),
        (format!("FLIP {flip:.3}"), tile(&frame.indirect)),
        ("true bounce".into(), tile(&truth)),
        (
            "error".into(),
            heat_map(w, h, &error_map(&frame.indirect, &truth), 0.5),
        ),
    ];
    save(&montage(&pictures, 3), path)
}

/// The leak scene's indirect light without and with indirect shadows, beside one bounce from
/// every VPL with exact visibility (the ground truth on the CPU, at [`truth_side`] with a
/// [`truth_rsm_size`] RSM): the one cut marching from every pixel, then the per-tile cuts
/// (estimate, far clusters shared) marching from the tiles' corners, with the latter's error
/// against the ground truth.
fn leak_picture(gpu: &Gpu, size: u32, path: &Path) -> Result<PathBuf, IndirectError> {
    let scene = Scene::load(&scenes_dir().join("leak.toml"))?;
    let size = truth_side(size);
    // the defaults: the per-tile cuts with the estimate and far clusters shared
    let settings = sized(size, size, truth_rsm_size(&scene));
    // (a frame first: it renders the RSM and the G-buffer the ground truth reads)
    let mut r = Renderer::new(gpu, &scene, settings.clone())?;
    r.render_frame(Method::Quadtree)?;
    let truth = ground_truth(&r.read_vpls()?, &r.read_receivers()?, &scene);
    let indirect = |method, indirect_shadows| {
        let settings = Settings {
            indirect_shadows,
            ..settings.clone()
        };
        Ok::<_, IndirectError>(
            Renderer::new(gpu, &scene, settings)?
                .render_frame(method)?
                .indirect,
        )
    };
    // (short captions: the demo's smallest pictures are 128 pixels wide)
    let rows = [
        ("one cut", Method::Quadtree),
        ("tiles", Method::QuadtreeTiles),
    ];
    let tile = |v: &[[f32; 3]]| tone_map(size, size, v, EXPOSURE);
    let l1 = |v: &[[f32; 3]]| compare(v, &truth).rel_l1;
    let mut pictures = Vec::new();
    for (name, method) in rows {
        let (leaky, shadowed) = (indirect(method, false)?, indirect(method, true)?);
        pictures.push((format!("{name}, L1 {:.2}", l1(&leaky)), tile(&leaky)));
        pictures.push((format!("shadows, L1 {:.2}", l1(&shadowed)), tile(&shadowed)));
        if method == Method::Quadtree {
            pictures.push(("ground truth".into(), tile(&truth)));
        } else {
            pictures.push((
                "error (shadows)".into(),
                heat_map(size, size, &error_map(&shadowed, &truth), 0.5),
            ));
        }
    }
    save(&montage(&pictures, 3), path)
}

fn save(image: &Rgba8Image, path: &Path) -> Result<PathBuf, IndirectError> {
    image.save_png(path)?;
    Ok(path.to_path_buf())
}
