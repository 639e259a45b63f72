//! `quadray indirect`: one scene, one method, pictures and stats (and the error against the brute
//! force with `--reference`).

use anyhow::{Context, Result};
use clap::Args;
use quadray_bench::indirect::run::{RunOptions, run};
use quadray_core::write_json;
use quadray_gpu::Gpu;
use quadray_indirect::{ClusterSettings, Method, Scene, Settings, TileCriterion, Validity};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct IndirectArgs {
    /// Scene file: TOML, or glTF 2.0 (.gltf, .glb); default: the bundled Cornell box.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// quadtree (compacted cut), quadtree-passes (the paper's per-level passes), quadtree-tiles
    /// (a cut per 8x8 tile, refined where a cluster's bound exceeds --tile-error of the
    /// tile's light), rsm (RSM sampling) or reference (every VPL).
    #[arg(long, default_value = "quadtree")]
    method: Method,
    /// Side of the reflective shadow map (power of two).
    #[arg(long, default_value_t = Settings::default().rsm_size)]
    rsm_size: u32,
    /// Level where every cluster is accepted (mip level: 0 = the RSM, each level halves the
    /// side); default: the level of 64x64 nodes.
    #[arg(long)]
    limit_level: Option<u32>,
    /// Level the traversal starts at; default: the level of 8x8 nodes.
    #[arg(long)]
    start_level: Option<u32>,
    /// Max |child depth - mean depth| of a valid cluster (depth in units of the scene's extent).
    #[arg(long, default_value_t = Settings::default().cluster.depth_threshold)]
    depth_threshold: f32,
    /// Min dot(child normal, mean normal) of a valid cluster.
    #[arg(long, default_value_t = Settings::default().cluster.normal_threshold)]
    normal_threshold: f32,
    /// recursive (every child valid too) or local (the paper's).
    #[arg(long, default_value = "recursive")]
    validity: Validity,
    /// Cluster means weighted by texel count instead of flux.
    #[arg(long)]
    unweighted_means: bool,
    /// RSM-sampling samples per pixel.
    #[arg(long, default_value_t = Settings::default().samples)]
    samples: u32,
    /// Indirect at one sample per KxK pixels, upsampled where the geometry agrees (quadtree,
    /// rsm).
    #[arg(long, default_value_t = Settings::default().subsample)]
    subsample: u32,
    /// Indirect shadows (quadtree methods): march between each receiver and cluster against the
    /// camera's and the light's depth.
    #[arg(long)]
    indirect_shadows: bool,
    /// Points marched per receiver and cluster with --indirect-shadows.
    #[arg(long, default_value_t = 8)]
    shadow_steps: u32,
    /// Depth behind a seen surface that counts as inside an occluder (fraction of the scene's
    /// extent), with --indirect-shadows.
    #[arg(long, default_value_t = Settings::default().shadow_thickness)]
    shadow_thickness: f32,
    /// Weight of each frame's indirect light in a running average over frames (1: off), every
    /// method but the brute force: damps the cut's popping under a moving light. Not
    /// reprojected: it restarts when the camera moves.
    #[arg(long, default_value_t = Settings::default().temporal_weight)]
    temporal_weight: f32,
    /// quadtree-tiles: split a cluster while a bound of its irradiance at any pixel of the tile
    /// (or its estimated error, --tile-criterion) exceeds this fraction of the tile's estimated
    /// irradiance (0: every VPL); default: 0.05 for the bound, 0.002 for the estimate.
    #[arg(long)]
    tile_error: Option<f32>,
    /// quadtree-tiles: what is compared with --tile-error: bound (an upper bound of the
    /// cluster's irradiance at the tile) or estimate (the estimated error of keeping the
    /// cluster rather than its children, at a few of the tile's pixels, where the bound is
    /// over the threshold).
    #[arg(long, default_value = Settings::default().tile_criterion.name())]
    tile_criterion: TileCriterion,
    /// quadtree-tiles: gather a cluster farther from the tile's pixels than this times their
    /// extent once at each corner of the tile and interpolate it (a receiver hierarchy; 0:
    /// every pixel evaluates every cluster).
    #[arg(long, default_value_t = Settings::default().tile_share)]
    tile_share: f32,
    /// quadtree-tiles: the most clusters a tile's cut holds (1..1024; past it refinement
    /// stops, counted as refused_splits); default: 1024, less where the picture's lists would
    /// take over 32 MiB (256 at 1920x1080).
    #[arg(long)]
    tile_capacity: Option<u32>,
    /// Image size WxH.
    #[arg(long, default_value = "512x512", value_parser = quadray_core::parse_size)]
    size: (u32, u32),
    /// Also render the brute force; adds rmse / rel_l1 to the stats and an error heat map
    /// beside --out.
    #[arg(long)]
    reference: bool,
    /// Also compute one bounce from every VPL with exact visibility on the CPU (ray traced);
    /// adds ground_truth {rel_l1, rmse, flip} to the stats. Traces a ray per pixel and VPL:
    /// small --size and --rsm-size (at most 2^30 rays).
    #[arg(long)]
    ground_truth: bool,
    /// Frames timed per light mode (median); with --light-orbit also the frames of the sequence.
    #[arg(long, default_value_t = 20)]
    frames: u32,
    /// Render a sequence of --frames frames with the spot turning DEG a frame about the
    /// vertical axis; adds temporal {cut_changed_fraction, flicker_ratio} to the stats.
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    light_orbit: Option<f32>,
    /// Radiance scale before tone mapping.
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// Camera position X,Y,Z instead of the scene file's.
    #[arg(long, value_parser = quadray_core::parse_vec3, allow_hyphen_values = true)]
    camera_position: Option<[f32; 3]>,
    /// Camera target X,Y,Z instead of the scene file's.
    #[arg(long, value_parser = quadray_core::parse_vec3, allow_hyphen_values = true)]
    camera_target: Option<[f32; 3]>,
    /// Spot light position X,Y,Z instead of the scene file's.
    #[arg(long, value_parser = quadray_core::parse_vec3, allow_hyphen_values = true)]
    light_position: Option<[f32; 3]>,
    /// Spot light direction X,Y,Z instead of the scene file's.
    #[arg(long, value_parser = quadray_core::parse_vec3, allow_hyphen_values = true)]
    light_direction: Option<[f32; 3]>,
    #[arg(long)]
    out: PathBuf,
    #[arg(long)]
    stats: Option<PathBuf>,
}

/// `picture.png` -> `picture.SUFFIX.png`.
fn beside(out: &Path, suffix: &str) -> PathBuf {
    let stem = out.file_stem().unwrap_or_default().to_string_lossy();
    out.with_file_name(format!("{stem}.{suffix}.png"))
}

pub fn run_indirect(args: IndirectArgs) -> Result<()> {
    let mut scene = match &args.scene {
        Some(path) => Scene::load(path)?,
        None => Scene::cornell(),
    };
    let overrides = [
        (&mut scene.camera.position, args.camera_position),
        (&mut scene.camera.target, args.camera_target),
        (&mut scene.light.position, args.light_position),
        (&mut scene.light.direction, args.light_direction),
    ];
    for (value, given) in overrides {
        if let Some(v) = given {
            *value = v;
        }
    }
    scene
        .validate()
        .map_err(|e| anyhow::anyhow!("camera or light options: {e}"))?;
    let defaults = ClusterSettings::defaults(args.rsm_size.max(1));
    let settings = Settings {
        width: args.size.0,
        height: args.size.1,
        rsm_size: args.rsm_size,
        cluster: ClusterSettings {
            start_level: args.start_level.unwrap_or(defaults.start_level),
            limit_level: args.limit_level.unwrap_or(defaults.limit_level),
            depth_threshold: args.depth_threshold,
            normal_threshold: args.normal_threshold,
            validity: args.validity,
            flux_weighted: !args.unweighted_means,
        },
        samples: args.samples,
        subsample: args.subsample,
        shadow_steps: if args.indirect_shadows {
            args.shadow_steps
        } else {
            0
        },
        shadow_thickness: args.shadow_thickness,
        temporal_weight: args.temporal_weight,
        tile_error: args
            .tile_error
            .unwrap_or(args.tile_criterion.default_error()),
        tile_criterion: args.tile_criterion,
        tile_share: args.tile_share,
        tile_capacity: args
            .tile_capacity
            .unwrap_or(Settings::tile_capacity_for(args.size.0, args.size.1)),
        ..Settings::default()
    };
    if let Some(degrees) = args.light_orbit {
        if !(degrees.is_finite() && degrees.abs() <= 180.0) {
            anyhow::bail!("--light-orbit {degrees} must be a finite angle within [-180, 180]");
        }
        if args.frames < 2 {
            anyhow::bail!("--light-orbit needs --frames 2 or more (a sequence)");
        }
    }
    if !(args.exposure.is_finite() && args.exposure > 0.0) {
        anyhow::bail!("--exposure {} must be positive", args.exposure);
    }
    let gpu = Gpu::new()?;
    let outcome = run(
        &gpu,
        &scene,
        settings,
        &RunOptions {
            method: args.method,
            frames: args.frames,
            reference: args.reference,
            ground_truth: args.ground_truth,
            light_orbit: args.light_orbit,
            exposure: args.exposure,
        },
    )
    .context("rendering")?;
    outcome.combined.save_png(&args.out)?;
    outcome.direct.save_png(&beside(&args.out, "direct"))?;
    outcome.indirect.save_png(&beside(&args.out, "indirect"))?;
    if let Some(map) = &outcome.error_map {
        map.save_png(&beside(&args.out, "error"))?;
    }
    if let Some(truth) = &outcome.ground_truth {
        truth.save_png(&beside(&args.out, "ground-truth"))?;
    }
    if let Some(cut) = &outcome.cut_view {
        cut.save_png(&beside(&args.out, "cut"))?;
    }
    if let Some(path) = &args.stats {
        write_json(path, &outcome.stats)?;
    }
    println!("{}", serde_json::to_string_pretty(&outcome.stats)?);
    Ok(())
}

/// `quadray bench indirect`.
pub fn bench(options: quadray_bench::indirect::tables::BenchOptions, out: &Path) -> Result<()> {
    let gpu = Gpu::new()?;
    let bar = crate::spinner("bench indirect");
    let results = quadray_bench::indirect::tables::run(&gpu, out, options, |m| {
        bar.set_message(format!("bench indirect: {m}"))
    })?;
    bar.finish_and_clear();
    println!("{}", std::fs::read_to_string(out.join("results.md"))?);
    println!("ratios: {}", serde_json::to_string_pretty(&results.ratios)?);
    Ok(())
}

/// `quadray bench indirect --equal-error`.
pub fn bench_equal_error(
    options: &quadray_bench::indirect::equal_error::EqualErrorOptions,
    out: &Path,
) -> Result<()> {
    let gpu = Gpu::new()?;
    let bar = crate::spinner("bench indirect --equal-error");
    quadray_bench::indirect::equal_error::run(&gpu, out, options, |m| {
        bar.set_message(format!("bench indirect --equal-error: {m}"))
    })?;
    bar.finish_and_clear();
    println!("{}", std::fs::read_to_string(out.join("equal_error.md"))?);
    Ok(())
}

/// `quadray bench indirect --cut-study`.
pub fn bench_cut_study(size: u32, rsm_size: u32, scenes: &[String], out: &Path) -> Result<()> {
    let gpu = Gpu::new()?;
    let bar = crate::spinner("bench indirect --cut-study");
    quadray_bench::indirect::cut_study::run(&gpu, out, size, rsm_size, scenes, |m| {
        bar.set_message(format!("bench indirect --cut-study: {m}"))
    })?;
    bar.finish_and_clear();
    println!("{}", std::fs::read_to_string(out.join("cut_study.md"))?);
    Ok(())
}

/// The indirect-light pictures of `quadray demo`.
pub fn demo(gpu: &Gpu, out: &Path, size: u32) -> Result<Vec<PathBuf>> {
    let bar = crate::spinner("indirect light");
    let files =
        quadray_bench::indirect::demo::render_demo(gpu, &out.join("indirect"), size, |m| {
            bar.set_message(format!("indirect light: {m}"))
        })?;
    bar.finish_and_clear();
    Ok(files)
}
