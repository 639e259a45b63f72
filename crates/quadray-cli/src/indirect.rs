//! `quadray indirect`: one scene, one method, pictures and stats (and the error against the brute
//! force with `--reference`).

use crate::provenance::recorded;
use anyhow::{Context, Result};
use clap::Args;
use glam::Vec3;
use quadray_bench::indirect::run::{RunOptions, run};
use quadray_core::image_out::{EXPOSURE, output_file};
use quadray_core::mesh::parse_point;
use quadray_core::write_json;
use quadray_gpu::Gpu;
use quadray_indirect::scene::Light;
use quadray_indirect::{Method, Scene, Settings};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct IndirectArgs {
    /// Scene file: TOML, or glTF 2.0 (.gltf, .glb); default: the bundled Cornell box.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// quadtree-tiles (a cut per 8x8 tile, refined where a cluster's estimated error exceeds
    /// --tile-error of the tile's light), quadtree (the paper's cut, compacted once),
    /// quadtree-passes (the paper's per-level passes), rsm (RSM sampling) or reference (every
    /// VPL).
    #[arg(long, default_value_t = Method::DEFAULT)]
    method: Method,
    #[command(flatten)]
    settings: Settings,
    /// Also render the brute force; adds rmse / rel_l1 to the stats and an error heat map
    /// beside --out.
    #[arg(long)]
    reference: bool,
    /// Also compute one bounce from every VPL with exact visibility on the CPU (ray traced);
    /// adds ground_truth {rel_l1, rmse, flip, blockiness, blockiness_bends,
    /// direct_shadows_wrong} to the stats (the error's steps and bends across the 8-pixel tiles'
    /// boundaries over elsewhere, relative to the brute force's, 1 = no tile structure; the share
    /// of the directly lit pixels whose shadow differs from one traced to each light).
    /// Traces a ray per pixel and VPL: small --size and --rsm-size (at most 2^30 rays).
    #[arg(long)]
    ground_truth: bool,
    /// Frames timed per light mode (median); with --light-orbit or --camera-orbit also the
    /// frames of the sequence.
    #[arg(long, default_value_t = 20, value_parser = RunOptions::FRAMES.parser())]
    frames: u32,
    /// Render a sequence of --frames frames with the lights turning DEG a frame about the
    /// vertical axis (a spot and the sun turn, a point light moves round the scene's middle); adds temporal {cut_changed_fraction, flicker_ratio, ...} to the stats, and
    /// with --temporal-weight below 1 temporal_unfiltered: the same frames without the filter.
    #[arg(long, value_name = "DEG", value_parser = RunOptions::ORBIT.parser(), allow_hyphen_values = true)]
    light_orbit: Option<f32>,
    /// In that sequence (or alone), the camera moves DEG a frame along an orbit about its
    /// target's vertical axis; adds temporal {disoccluded_fraction, disoccluded_rel_l1}: the
    /// pixels showing what the last frame did not see, and the error there.
    #[arg(long, value_name = "DEG", value_parser = RunOptions::ORBIT.parser(), allow_hyphen_values = true)]
    camera_orbit: Option<f32>,
    /// Radiance scale before tone mapping (a picture that comes out nearly black or white says
    /// which exposure would show it).
    #[arg(long, default_value_t = 1.0, value_parser = EXPOSURE.parser(), allow_negative_numbers = true)]
    exposure: f32,
    /// Camera position X,Y,Z instead of the scene file's (each within a mesh's coordinate limit,
    /// 1e7).
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true)]
    camera_position: Option<[f32; 3]>,
    /// Camera target X,Y,Z instead of the scene file's (as the position).
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true)]
    camera_target: Option<[f32; 3]>,
    /// A light's position, `[N:]X,Y,Z`, instead of the scene file's (a point or spot light; N
    /// counts the scene's lights from 1, the first by default; once per light).
    #[arg(long, value_parser = numbered(parse_point), allow_hyphen_values = true)]
    light_position: Vec<NumberedVec3>,
    /// A light's direction, `[N:]X,Y,Z`, instead of the scene file's (a spot's axis, the sun's
    /// direction; N as for --light-position).
    #[arg(long, value_parser = numbered(quadray_core::parse_vec3), allow_hyphen_values = true)]
    light_direction: Vec<NumberedVec3>,
    /// The picture (PNG; its direct and indirect light, and the other pictures asked for,
    /// beside it); its folder must exist.
    #[arg(long, value_parser = output_file(&["png"]))]
    out: PathBuf,
    /// Statistics JSON.
    #[arg(long, value_parser = output_file(&[]))]
    stats: Option<PathBuf>,
}

/// A light's number (from 1) and a vector.
type NumberedVec3 = (usize, [f32; 3]);

/// The parser of `[N:]X,Y,Z`: a light's number (1 when left out) and a vector `parse` reads.
fn numbered(
    parse: fn(&str) -> Result<[f32; 3], String>,
) -> impl Fn(&str) -> Result<NumberedVec3, String> + Clone + Send + Sync + 'static {
    move |s: &str| {
        let (number, v) = match s.split_once(':') {
            Some((n, v)) => match n.trim().parse::<usize>() {
                Ok(n) if n >= 1 => (n, v),
                _ => return Err(format!("`{n}` is not a light's number (1, 2, ...)")),
            },
            None => (1, s),
        };
        Ok((number, parse(v)?))
    }
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
    fn set<T: From<[f32; 3]>>(value: &mut T, given: Option<[f32; 3]>) {
        if let Some(v) = given {
            *value = v.into();
        }
    }
    set(&mut scene.camera.position, args.camera_position);
    set(&mut scene.camera.target, args.camera_target);
    let lights = &mut scene.lights;
    let mut move_lights =
        |flag: &str, given: &[NumberedVec3], apply: fn(&mut Light, Vec3) -> bool| {
            let count = lights.len();
            for &(number, v) in given {
                let light = lights.get_mut(number - 1).with_context(|| {
                    format!("{flag} {number}:...: the scene has {count} light(s)")
                })?;
                if !apply(light, v.into()) {
                    anyhow::bail!(
                        "{flag}: the scene's light {number} is a {}",
                        light.describe()
                    );
                }
            }
            Ok(())
        };
    move_lights("--light-position", &args.light_position, Light::place)?;
    move_lights("--light-direction", &args.light_direction, Light::aim)?;
    scene
        .validate()
        .map_err(|e| anyhow::anyhow!("camera or light options: {e}"))?;
    // a flag that would change nothing is a mistake to report, not to ignore
    for (flag, value) in [
        ("--subsample", args.settings.subsample),
        ("--interleave", args.settings.interleave),
    ] {
        if value > 1 && !args.method.subsamples() {
            anyhow::bail!(
                "{flag} {value} applies to --method {} (the methods that gather at low \
                 resolution or interleaved), not {}",
                Method::subsampling_names().join(" and "),
                args.method
            );
        }
    }
    for (flag, orbit) in [
        ("--light-orbit", args.light_orbit),
        ("--camera-orbit", args.camera_orbit),
    ] {
        if orbit.is_some() && args.frames < 2 {
            anyhow::bail!("{flag} needs --frames 2 or more (a sequence)");
        }
    }
    // the settings' own rules (a power-of-two interleave, interleave or subsample, ...) before
    // any GPU work
    args.settings
        .validate()
        .map_err(|e| anyhow::anyhow!("indirect-light options: {e}"))?;
    let gpu = Gpu::new()?;
    let outcome = run(
        &gpu,
        &scene,
        args.settings,
        &RunOptions {
            method: args.method,
            frames: args.frames,
            reference: args.reference,
            ground_truth: args.ground_truth,
            light_orbit: args.light_orbit,
            camera_orbit: args.camera_orbit,
            exposure: args.exposure,
        },
    )
    .context("rendering")?;
    if let Some(advice) = &outcome.exposure_advice {
        tracing::warn!("{}: {advice}", args.out.display());
    }
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
    let stats = recorded(&outcome.stats, Some(&gpu));
    if let Some(path) = &args.stats {
        write_json(path, &stats)?;
    }
    println!("{}", serde_json::to_string_pretty(&stats)?);
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

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;
    use proptest::prelude::*;
    use quadray_core::settings::{Limits, Size};
    use quadray_indirect::{ClusterSettings, GBufferLayout, TileCriterion, TilePasses, Validity};
    use quadray_test_support::flags::assert_settings_round_trip;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: IndirectArgs,
    }

    /// Valid settings, every field drawn from its declared limits (levels and capacities left to
    /// their rules or given).
    fn valid_settings() -> impl Strategy<Value = Settings> {
        let f = |l: Limits<f32>, lo: f32, hi: f32| {
            (lo..=hi).prop_filter("inside the limits", move |v| l.contains(*v))
        };
        let u = |l: Limits<u32>| l.min..=l.max;
        (
            (
                (8u32..=512, 8u32..=512),
                2u32..=10,
                proptest::option::of(0u32..=10),
                proptest::option::of(0u32..=10),
                f(ClusterSettings::DEPTH_THRESHOLD, 0.0, 10.0),
                f(ClusterSettings::NORMAL_THRESHOLD, -1.0, 1.0),
                proptest::sample::select(Validity::ALL.to_vec()),
                any::<bool>(),
            ),
            (
                u(Settings::SAMPLES),
                f(Settings::RSM_RADIUS, 0.0, 1.0),
                u(Settings::SUBSAMPLE),
                // (powers of two)
                proptest::sample::select(vec![1u32, 2, 4]),
                any::<bool>(),
                u(Settings::SHADOW_STEPS),
                f(Settings::SHADOW_THICKNESS, 0.0, 1.0),
                f(Settings::TEMPORAL_WEIGHT, 0.0, 1.0),
                proptest::sample::select(GBufferLayout::ALL.to_vec()),
            ),
            (
                proptest::option::of(f(Settings::TILE_ERROR, 0.0, 1.0)),
                proptest::sample::select(TileCriterion::ALL.to_vec()),
                proptest::option::of(u(Settings::TILE_CAPACITY)),
                f(Settings::TILE_SHARE, 0.0, 1000.0),
                u(Settings::MAX_LIGHTS),
                u(Settings::SHADOW_GRID),
                u(Settings::TILE_DEBLOCK),
                proptest::option::of(u(Settings::SHADOW_CORNERS)),
                f(Settings::TILE_SHADOW_ANGLE, 0.0, 100.0),
                proptest::option::of(4u32..=13),
                // (powers of two: the shadow corners' and the split tiles' walk lanes)
                (
                    proptest::sample::select(vec![8u32, 16, 32, 64]),
                    proptest::sample::select(vec![4u32, 8, 16, 32, 64]),
                ),
                proptest::sample::select(TilePasses::ALL.to_vec()),
            ),
        )
            .prop_map(
                |(
                    ((w, h), rsm_log, start, limit, depth, normal, validity, flux_weighted),
                    (
                        samples,
                        rsm_radius,
                        subsample,
                        interleave,
                        shadows,
                        steps,
                        thickness,
                        temporal,
                        gbuffer_layout,
                    ),
                    (
                        tile_error,
                        tile_criterion,
                        tile_capacity,
                        tile_share,
                        max_lights,
                        shadow_grid,
                        tile_deblock,
                        shadow_corners,
                        tile_shadow_angle,
                        shadow_map_log,
                        (shadow_corner_lanes, tile_walk_lanes),
                        tile_passes,
                    ),
                )| {
                    // levels within the RSM's, the limit at or below the start (given or not)
                    let start_level = start.map(|l| l.min(rsm_log));
                    let start =
                        start_level.unwrap_or(ClusterSettings::DEFAULT.levels(1 << rsm_log).start);
                    let limit_level = match (start_level, limit) {
                        (Some(_), limit) => Some(limit.unwrap_or(0).min(start)),
                        (None, limit) => limit.map(|l| l.min(start)),
                    };
                    Settings {
                        size: Size::new(w, h),
                        rsm_size: 1 << rsm_log,
                        shadow_map_size: shadow_map_log.map(|l| 1 << l),
                        max_lights,
                        gbuffer_layout,
                        cluster: ClusterSettings {
                            start_level,
                            limit_level,
                            depth_threshold: depth,
                            normal_threshold: normal,
                            validity,
                            flux_weighted,
                        },
                        samples,
                        rsm_radius,
                        subsample,
                        // (the two exclude each other)
                        interleave: if subsample > 1 { 1 } else { interleave },
                        indirect_shadows: shadows,
                        shadow_corners,
                        shadow_corner_lanes,
                        shadow_steps: steps,
                        shadow_thickness: thickness,
                        shadow_grid,
                        shadow_grid_levels: 1,
                        temporal_weight: temporal,
                        tile_error,
                        tile_criterion,
                        tile_capacity,
                        tile_share,
                        tile_shadow_angle,
                        tile_passes,
                        tile_walk_lanes,
                        tile_deblock,
                    }
                },
            )
    }

    /// No flags: the library's defaults.
    #[test]
    fn the_flags_defaults_are_the_settings_defaults() {
        let cli = Cli::try_parse_from(["indirect", "--out=o.png"]).unwrap();
        assert_eq!(cli.args.settings, Settings::DEFAULT);
        assert_eq!(cli.args.method, Method::DEFAULT);
    }

    /// The flags refuse what `validate()` refuses, naming the flag and the same limits.
    #[test]
    fn the_flags_refuse_values_outside_the_limits() {
        let validities: Vec<_> = Validity::ALL.iter().map(|v| v.to_string()).collect();
        for (flag, value, range) in [
            ("--size", "0x10", Settings::SIDE.to_string()),
            ("--rsm-size", "96", Settings::RSM_SIZE.to_string()),
            ("--rsm-size", "2048", Settings::RSM_SIZE.to_string()),
            (
                "--shadow-map-size",
                "3000",
                Settings::SHADOW_MAP_SIZE.to_string(),
            ),
            ("--limit-level", "11", ClusterSettings::LEVEL.to_string()),
            (
                "--normal-threshold",
                "1.5",
                ClusterSettings::NORMAL_THRESHOLD.to_string(),
            ),
            (
                "--depth-threshold",
                "NaN",
                ClusterSettings::DEPTH_THRESHOLD.to_string(),
            ),
            ("--samples", "0", Settings::SAMPLES.to_string()),
            ("--subsample", "65", Settings::SUBSAMPLE.to_string()),
            ("--interleave", "9", Settings::INTERLEAVE.to_string()),
            ("--shadow-steps", "0", Settings::SHADOW_STEPS.to_string()),
            ("--shadow-grid", "513", Settings::SHADOW_GRID.to_string()),
            (
                "--temporal-weight",
                "0",
                Settings::TEMPORAL_WEIGHT.to_string(),
            ),
            (
                "--tile-capacity",
                "2048",
                Settings::TILE_CAPACITY.to_string(),
            ),
            ("--tile-share", "-1", Settings::TILE_SHARE.to_string()),
            ("--tile-deblock", "4", Settings::TILE_DEBLOCK.to_string()),
            (
                "--tile-shadow-angle",
                "-1",
                Settings::TILE_SHADOW_ANGLE.to_string(),
            ),
            ("--validity", "global", validities.join(", ")),
        ] {
            // `=` so that a negative value reaches the flag's parser rather than clap's.
            let argv = ["indirect", "--out=o.png", &format!("{flag}={value}")];
            let e = Cli::try_parse_from(argv).err().expect(flag).to_string();
            assert!(e.contains(flag) && e.contains(&range), "{e}");
        }
    }

    /// The viewer prints `Settings::to_args` beside its screenshots: every valid setting must
    /// come back through the CLI's flags unchanged.
    #[test]
    fn settings_round_trip_through_the_flags() {
        assert_settings_round_trip(
            &["indirect", "--out=o.png"],
            valid_settings(),
            Settings::validate,
            Settings::to_args,
            |args: IndirectArgs| args.settings,
        );
    }
}
