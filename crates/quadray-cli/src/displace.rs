//! `quadray displace`, and the displacement parts of `quadray demo` and `quadray bench`.

use crate::provenance::recorded;
use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use quadray_core::image_out::output_file;
use quadray_displace::accuracy::{Accuracy, Cost};
use quadray_displace::heightmap::{Convention, Fit, HeightMap};
use quadray_displace::maps::load_color;
use quadray_displace::scene::SurfaceKind;
use quadray_displace::{Method, Renderer, Settings};
use quadray_gpu::Gpu;
use serde::Serialize;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct DisplaceArgs {
    /// Height map: 8/16-bit PNG or float EXR, any size up to 8192x8192.
    #[arg(long)]
    map: PathBuf,
    #[command(flatten)]
    settings: Settings,
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
    #[arg(long, default_value_t = 30, value_parser = Renderer::TIMED_FRAMES.parser())]
    frames: u32,
    /// The picture (PNG; the error heat map beside it); its folder must exist.
    #[arg(long, value_parser = output_file(&["png"]))]
    out: PathBuf,
    /// Statistics JSON.
    #[arg(long, value_parser = output_file(&[]))]
    stats: Option<PathBuf>,
}

/// The stats JSON: the settings' own fields (method, width, height, view_angle_deg, ...), then
/// what was measured.
#[derive(Serialize)]
struct Stats<'a> {
    #[serde(flatten)]
    settings: &'a Settings,
    map: &'a Path,
    /// The map's width and height in texels.
    map_size: [u32; 2],
    surface: SurfaceKind,
    adapter: String,
    gpu_time_ms: Option<f64>,
    frames: u32,
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

pub fn run(args: DisplaceArgs) -> Result<()> {
    let settings = &args.settings;
    if let Err(e) = settings.validate() {
        bail!("{e}");
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
    let frame = renderer.render(&gpu, settings)?;
    frame.color.save_png(&args.out)?;
    let timing = renderer.time(&gpu, settings, args.frames as usize)?;
    let cost = Cost::of(&frame);
    let truth = settings.method.truth().filter(|_| args.reference);
    let (accuracy, error_map) = if let Some(truth) = truth {
        let acc = Accuracy::measure(&frame, &map, args.surface, settings, truth);
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
        settings,
        map: &args.map,
        map_size: [map.width, map.height],
        surface: args.surface,
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
    let json = serde_json::to_string_pretty(&recorded(&stats, Some(&gpu)))?;
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
    use proptest::prelude::*;
    use quadray_displace::{Layers, Lod, Size};
    use quadray_test_support::flags::assert_settings_round_trip;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: DisplaceArgs,
    }

    /// Valid settings, every field drawn from its declared limits.
    fn valid_settings() -> impl Strategy<Value = Settings> {
        let f = |l: quadray_core::settings::Limits<f32>, lo: f32, hi: f32| {
            (lo..=hi).prop_filter("inside the limits", move |v| l.contains(*v))
        };
        let side = Settings::SIDE.min..=Settings::SIDE.max;
        let count = Layers::COUNT.min..=Layers::COUNT.max;
        let lod = prop_oneof![Just(Lod::Auto), (0u32..16).prop_map(Lod::Level)];
        (
            (
                proptest::sample::select(Method::ALL.to_vec()),
                f(Settings::VIEW_ANGLE, 0.0, 89.0),
                (side.clone(), side),
                f(Settings::DEPTH_SCALE, 0.0, 10.0),
                (count.clone(), count),
                Settings::BINARY_STEPS.min..=Settings::BINARY_STEPS.max,
            ),
            (
                lod,
                any::<bool>(),
                f(Settings::AZIMUTH, -1e6, 1e6),
                f(Settings::ZOOM, 0.0, 20.0),
                f(Settings::AZIMUTH, -1e6, 1e6),
                any::<bool>(),
            ),
        )
            .prop_map(
                |(
                    (method, view_angle_deg, (w, h), depth_scale, (a, b), binary_steps),
                    (lod, shadows, azimuth_deg, zoom, light_azimuth_deg, show_iterations),
                )| Settings {
                    method,
                    view_angle_deg,
                    size: Size::new(w, h),
                    depth_scale,
                    layers: Layers {
                        min: a.min(b),
                        max: a.max(b),
                    },
                    binary_steps,
                    lod,
                    shadows,
                    azimuth_deg,
                    zoom,
                    light_azimuth_deg,
                    show_iterations,
                },
            )
    }

    /// No flags: the library's defaults.
    #[test]
    fn the_flags_defaults_are_the_settings_defaults() {
        let cli = Cli::try_parse_from(["displace", "--map=m.png", "--out=o.png"]).unwrap();
        assert_eq!(cli.args.settings, Settings::DEFAULT);
    }

    /// The flags refuse what `validate()` refuses, naming the flag and the same limits.
    #[test]
    fn the_flags_refuse_values_outside_the_limits() {
        let layers = format!(
            "{} <= min <= max <= {}",
            Layers::COUNT.min,
            Layers::COUNT.max
        );
        for (flag, value, range) in [
            ("--view-angle", "89.5", Settings::VIEW_ANGLE.to_string()),
            ("--size", "0x10", Settings::SIDE.to_string()),
            ("--depth-scale", "0", Settings::DEPTH_SCALE.to_string()),
            ("--layers", "9,3", layers),
            ("--binary-steps", "65", Settings::BINARY_STEPS.to_string()),
            ("--zoom", "NaN", Settings::ZOOM.to_string()),
            ("--azimuth", "inf", Settings::AZIMUTH.to_string()),
        ] {
            let argv = ["displace", "--map=m.png", "--out=o.png", flag, value];
            let e = Cli::try_parse_from(argv).err().expect(flag).to_string();
            assert!(e.contains(flag) && e.contains(&range), "{e}");
        }
    }

    /// The viewer prints `Settings::to_args` beside its screenshots: every valid setting must
    /// come back through the CLI's flags unchanged.
    #[test]
    fn settings_round_trip_through_the_flags() {
        assert_settings_round_trip(
            &["displace", "--map=m.png", "--out=o.png"],
            valid_settings(),
            Settings::validate,
            Settings::to_args,
            |args: DisplaceArgs| args.settings,
        );
    }
}
