//! `quadray displace`, and the displacement parts of `quadray demo` and `quadray bench`.

use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use quadray_displace::accuracy::{Accuracy, Cost};
use quadray_displace::heightmap::{Convention, Fit, HeightMap};
use quadray_displace::maps::load_color;
use quadray_displace::pyramid::Addressing;
use quadray_displace::scene::SurfaceKind;
use quadray_displace::{Lod, Method, Renderer, Settings};
use quadray_gpu::Gpu;
use serde::Serialize;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct DisplaceArgs {
    /// Height map: 8/16-bit PNG or float EXR, any size up to 8192x8192.
    #[arg(long)]
    map: PathBuf,
    /// pyramid, pyramid-ascend, pyramid-bilinear, bump, parallax, pom, relief, cone (relaxed cone
    /// stepping; builds its cone map first) or mesh.
    #[arg(long, default_value = "pyramid")]
    method: Method,
    /// Angle between the view direction at the surface centre and the normal (0..89).
    #[arg(long, default_value_t = 45.0)]
    view_angle: f32,
    /// Image size WxH.
    #[arg(long, default_value = "512x512", value_parser = quadray_core::parse_size)]
    size: (u32, u32),
    /// Texture units per unit of depth (Bevy's default 0.1).
    #[arg(long, default_value_t = 0.1)]
    depth_scale: f32,
    /// POM / relief layers MIN,MAX (head-on .. grazing). Bevy: 1,16; Godot: 8,32; three.js: 20,25.
    /// Cone stepping takes MAX as its number of cone steps.
    #[arg(long, default_value = "8,32", value_parser = parse_layers)]
    layers: (u32, u32),
    /// Relief mapping's and cone stepping's binary search steps (three.js: 5).
    #[arg(long, default_value_t = 5)]
    binary_steps: u32,
    /// Finest pyramid level: `auto` (from screen-space derivatives) or a level number.
    #[arg(long, default_value = "0")]
    lod: Lod,
    /// Self-shadowing by tracing from the light.
    #[arg(long)]
    shadows: bool,
    /// Camera azimuth around the surface normal, degrees.
    #[arg(long, default_value_t = 30.0, allow_negative_numbers = true)]
    azimuth: f32,
    /// Camera distance as a multiple of the default.
    #[arg(long, default_value_t = 1.0)]
    zoom: f32,
    /// Light azimuth around the surface normal, degrees.
    #[arg(long, default_value_t = 30.0, allow_negative_numbers = true)]
    light_azimuth: f32,
    /// Colour pixels by the iterations their search took (0..64: black, red, yellow, white).
    #[arg(long)]
    show_iterations: bool,
    /// Compare every pixel with the CPU ground truth; writes an error heat map beside --out.
    #[arg(long)]
    reference: bool,
    /// wall (tiled, rays wrap), terrain (one copy, rays leaving it are discarded) or photo.
    #[arg(long, default_value = "wall")]
    surface: SurfaceKind,
    /// How the map stores its values: height (white = high), depth (white = deep) or depth-photo
    /// (a Kinect/TUM depth image: 0 = no measurement).
    #[arg(long, default_value = "height")]
    convention: Convention,
    /// Resample maps that are not 2^n x 2^n to the nearest square power of two (this changes the
    /// surface; without it, maps of any size are traced exactly as stored).
    #[arg(long)]
    resample: bool,
    /// Albedo image (default: tinted by depth).
    #[arg(long)]
    color: Option<PathBuf>,
    /// Frames to time (median).
    #[arg(long, default_value_t = 30)]
    frames: usize,
    #[arg(long)]
    out: PathBuf,
    #[arg(long)]
    stats: Option<PathBuf>,
}

fn parse_layers(s: &str) -> Result<(u32, u32), String> {
    quadray_core::parse_pair(s, ',', "MIN,MAX")
}

#[derive(Serialize)]
struct Stats<'a> {
    method: Method,
    width: u32,
    height: u32,
    map: &'a Path,
    /// The map's width and height in texels.
    map_size: [u32; 2],
    surface: SurfaceKind,
    view_angle_deg: f32,
    depth_scale: f32,
    adapter: String,
    gpu_time_ms: Option<f64>,
    frames: usize,
    iteration_cap_hits: usize,
    mean_iterations: f64,
    texel_fetches_per_pixel: f64,
    max_iterations: u32,
    /// CPU seconds building the method's data before the first frame (the cone map).
    #[serde(skip_serializing_if = "Option::is_none")]
    preprocess_seconds: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    wrong_hit_fraction: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    accuracy: Option<Accuracy>,
    #[serde(skip_serializing_if = "Option::is_none")]
    error_map: Option<PathBuf>,
}

impl DisplaceArgs {
    /// The library's settings these flags spell (`Settings::to_args` spells them back).
    fn settings(&self) -> Settings {
        Settings {
            method: self.method,
            view_angle_deg: self.view_angle,
            width: self.size.0,
            height: self.size.1,
            depth_scale: self.depth_scale,
            layers: self.layers,
            binary_steps: self.binary_steps,
            lod: self.lod,
            shadows: self.shadows,
            azimuth_deg: self.azimuth,
            zoom: self.zoom,
            light_azimuth_deg: self.light_azimuth,
            show_iterations: self.show_iterations,
        }
    }
}

pub fn run(args: DisplaceArgs) -> Result<()> {
    let settings = args.settings();
    if let Err(e) = settings.validate() {
        bail!("{e}");
    }
    if args.frames == 0 || args.frames > 100_000 {
        bail!("--frames {} is outside 1..100000", args.frames);
    }
    let fit = if args.resample {
        Fit::Resample
    } else {
        Fit::Exact
    };
    let map = HeightMap::load(&args.map, args.convention, fit)?;
    let color = args.color.as_deref().map(load_color).transpose()?;
    let gpu = Gpu::new()?;
    let mut renderer = Renderer::new(&gpu, &map, color.as_ref(), args.surface);
    if settings.method == Method::Cone {
        let bar = ProgressBar::new(u64::from(map.height)).with_style(ProgressStyle::with_template(
            "cone map {bar:40} {pos}/{len} rows {elapsed}, {eta} left",
        )?);
        renderer.build_cone_map(&gpu, || bar.inc(1));
        bar.finish_and_clear();
    }
    let frame = renderer.render(&gpu, &settings)?;
    frame.color.save_png(&args.out)?;
    let timing = renderer.time(&gpu, &settings, args.frames)?;
    let cost = Cost::of(&frame);
    let (accuracy, error_map) = if args.reference && settings.method.traces_rays() {
        let addressing = if args.surface.wraps() {
            Addressing::Wrap
        } else {
            Addressing::Clamp
        };
        let acc = Accuracy::measure(&frame, &map, addressing, settings.method.truth());
        let path = args.out.with_extension("error.png");
        acc.heat_map().save_png(&path)?;
        (Some(acc), Some(path))
    } else {
        if args.reference {
            eprintln!("note: --reference compares traced rays; the mesh baseline is rasterised");
        }
        (None, None)
    };
    let stats = Stats {
        method: settings.method,
        width: settings.width,
        height: settings.height,
        map: &args.map,
        map_size: [map.width, map.height],
        surface: args.surface,
        view_angle_deg: settings.view_angle_deg,
        depth_scale: settings.depth_scale,
        adapter: gpu.describe(),
        gpu_time_ms: timing.map(|t| t.median_ms),
        frames: args.frames,
        iteration_cap_hits: cost.iteration_cap_hits,
        mean_iterations: cost.mean_iterations,
        texel_fetches_per_pixel: cost.texel_fetches_per_pixel,
        max_iterations: cost.max_iterations,
        preprocess_seconds: renderer.cone_build_seconds(),
        wrong_hit_fraction: accuracy.as_ref().map(|a| a.wrong_hit_fraction),
        accuracy,
        error_map,
    };
    let json = serde_json::to_string_pretty(&stats)?;
    match &args.stats {
        Some(path) => {
            std::fs::write(path, json).with_context(|| format!("writing {}", path.display()))?
        }
        None => println!("{json}"),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: DisplaceArgs,
    }

    /// The viewer prints `Settings::to_args` beside its screenshots: every setting must come back
    /// through these flags unchanged, defaults and otherwise.
    #[test]
    fn settings_round_trip_through_the_flags() {
        let changed = Settings {
            method: Method::Relief,
            view_angle_deg: 71.5,
            width: 96,
            height: 64,
            depth_scale: 0.25,
            layers: (3, 40),
            binary_steps: 7,
            lod: Lod::Auto,
            shadows: true,
            azimuth_deg: -12.25,
            zoom: 1.5,
            light_azimuth_deg: -200.0,
            show_iterations: true,
        };
        for settings in [Settings::default(), changed] {
            let mut argv = vec![
                "displace".to_string(),
                "--map=m.png".into(),
                "--out=o.png".into(),
            ];
            argv.extend(settings.to_args());
            let cli = Cli::try_parse_from(&argv).unwrap();
            assert_eq!(cli.args.settings(), settings, "{argv:?}");
        }
    }
}
