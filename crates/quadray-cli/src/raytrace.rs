//! `quadray raytrace`: the Whitted ray tracer with hybrid shadow testing (quadray-shadows).

use crate::provenance::recorded;
use crate::tiles::{self, Fingerprint, TileHeader, WorkItems};
use anyhow::{Context, bail, ensure};
use indicatif::{ProgressBar, ProgressStyle};
use quadray_core::image_out::{EXPOSURE, check_exposure};
use quadray_shadows::scene::{BUILTINS, Scene};
use quadray_shadows::{Nth, Region, SchemeChoice, Settings, cost};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// `quadray raytrace`'s flags: the render's [`Settings`], then what is not one: the scene, the
/// files written, the actions that replace the render, and the work items and turntable frames
/// a job splits into.
#[derive(clap::Args)]
pub struct RaytraceArgs {
    #[command(flatten)]
    settings: Settings,
    /// A scene file: TOML, or glTF 2.0 (.gltf, .glb).
    #[arg(long, conflicts_with = "builtin")]
    scene: Option<PathBuf>,
    /// A builtin look-alike of the paper's scenes: glasses, desk, stars, kaist.
    #[arg(long)]
    builtin: Option<String>,
    /// Output PNG, or EXR for the radiance as 32-bit floats; with --tiles or --frames, the folder
    /// the work item's tile goes to (frameFFFF-tileTTTT.exr, its stats beside it).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Radiance scale before the PNG's clamp and gamma (an EXR keeps the radiance as is).
    #[arg(long, default_value_t = 1.0, value_parser = EXPOSURE.parser(), allow_negative_numbers = true)]
    exposure: f32,
    /// Statistics JSON (times, sub-schemes, N_th, p, alpha, ...).
    #[arg(long)]
    stats: Option<PathBuf>,
    /// Only measure the machine constants C_s, C_i, C_c, C_o (nanoseconds) and print them.
    #[arg(long)]
    calibrate: bool,
    /// Only predict HST's N_th (`--nth auto`) and print it: compute it once and give it to every
    /// work item with --nth, so that all tiles make the same shadow decisions.
    #[arg(long)]
    print_nth: bool,
    /// Render one of N horizontal bands of the picture as a work item (see --tile).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    tiles: Option<u32>,
    /// The work item to render, 0-based, frame by frame (item = (frame - A) * N + tile); else
    /// from JOB_COMPLETION_INDEX (Kubernetes Indexed Job) or SLURM_ARRAY_TASK_ID (Slurm array).
    #[arg(long)]
    tile: Option<u64>,
    /// A turntable: frames A to B-1 as work items (with --tiles, every frame's tiles).
    #[arg(long, value_parser = tiles::parse_frames, requires = "orbit")]
    frames: Option<Range<u32>>,
    /// Degrees the camera turns about the scene's centre (around its up axis) per frame.
    #[arg(long, allow_hyphen_values = true)]
    orbit: Option<f32>,
    /// Render this frame of the turntable: in one process, or as --tiles N work items. It
    /// overrides --frames, so that a job's options plus `--frame F` render its frame F alone.
    #[arg(long, requires = "orbit")]
    frame: Option<u32>,
}

/// Whether `path` names an EXR (radiance) rather than a tone-mapped picture.
pub fn is_exr(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
}

/// `scene` seen from its camera turned `degrees` about the centre of its bounds, around the
/// camera's up axis.
fn orbit(mut scene: Scene, degrees: f32) -> Scene {
    if degrees == 0.0 {
        return scene;
    }
    let (lo, hi) = scene.vertices.iter().fold(
        (glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY),
        |(lo, hi), &v| (lo.min(v), hi.max(v)),
    );
    let centre = (lo + hi) * 0.5;
    let turn = glam::Quat::from_axis_angle(scene.camera.up.normalize(), degrees.to_radians());
    let cam = &mut scene.camera;
    cam.position = centre + turn * (cam.position - centre);
    cam.target = centre + turn * (cam.target - centre);
    scene
}

pub fn run(args: RaytraceArgs) -> anyhow::Result<()> {
    if args.calibrate {
        let costs = cost::calibrate();
        let text = serde_json::to_string_pretty(&recorded(&costs, None))?;
        println!("{text}");
        if let Some(path) = &args.stats {
            quadray_core::write_text(path, &text)?;
        }
        return Ok(());
    }
    // a work item's --out is the folder of its tiles; a whole picture's is checked before the work
    if let (Some(out), None, None) = (&args.out, args.tiles, &args.frames) {
        quadray_core::image_out::output_file(&["png", "exr"])(&out.to_string_lossy())
            .map_err(|e| anyhow::anyhow!("--out {}: {e}", out.display()))?;
    }
    let scene = match (&args.scene, &args.builtin) {
        (Some(path), None) => Scene::load(path)?,
        (None, Some(name)) => Scene::builtin(name).with_context(|| {
            let names: Vec<&str> = BUILTINS.iter().map(|b| b.0).collect();
            format!(
                "unknown builtin scene {name:?} (one of {})",
                names.join(", ")
            )
        })?,
        _ => bail!("give --scene PATH or --builtin NAME"),
    };
    if let Some(advice) = scene.lighting_advice() {
        tracing::warn!("{}: {advice}", scene.name);
    }
    let source = match &args.scene {
        Some(path) => path.display().to_string(),
        None => format!("builtin scene {:?}", scene.name),
    };
    // Named like the loader's errors: "FILE: reason".
    let invalid = |e: quadray_shadows::BuildError| anyhow::anyhow!("{source}: {e}");
    scene.validate().map_err(invalid)?;
    let settings = args.settings;
    let (width, height) = (settings.size.width, settings.size.height);
    let degrees = args.orbit.unwrap_or(0.0);
    ensure!(
        degrees.is_finite(),
        "--orbit {degrees}: not a number of degrees"
    );
    let frames = match args.frame {
        Some(_) => None,
        None => args.frames.clone(),
    };
    if args.print_nth {
        let frame = frames.as_ref().map_or(args.frame.unwrap_or(0), |f| f.start);
        let prep =
            quadray_shadows::prepare(orbit(scene, degrees * frame as f32), SchemeChoice::Hst)
                .map_err(invalid)?;
        let (predicted, _) = prep.predicted_nth(&cost::calibrate(), settings.depth);
        // Exactly the f32 that --nth auto uses; Display prints it so that it parses back exactly.
        println!("{}", predicted as f32);
        return Ok(());
    }
    let out = args.out.context("--out FILE.png is required")?;
    let job = (args.tiles.is_some() || frames.is_some()).then(|| WorkItems {
        tiles: args.tiles.unwrap_or(1),
        frames: frames.unwrap_or_else(|| {
            let f = args.frame.unwrap_or(0);
            f..f + 1
        }),
    });
    let Some(items) = job else {
        if args.tile.is_some() {
            bail!("--tile needs --tiles N or --frames A..B");
        }
        let scene = orbit(scene, degrees * args.frame.unwrap_or(0) as f32);
        let full = Region::full(width, height);
        let (radiance, report) = render(scene, &settings, full, &invalid)?;
        if is_exr(&out) {
            tiles::write_exr(&out, &radiance, (width, height), None)?;
        } else {
            radiance.to_rgba8(args.exposure).save_png(&out)?;
            // the clamp shows radiance 1 as white
            if let Some(advice) = check_exposure(&radiance.pixels, args.exposure, 1.0) {
                tracing::warn!("{}: {advice}", out.display());
            }
        }
        if let Some(path) = &args.stats {
            quadray_core::write_json(path, &recorded(&report, None))?;
        }
        return Ok(());
    };
    ensure!(
        items.tiles <= height,
        "--tiles {}: at most one tile per row ({height})",
        items.tiles
    );
    ensure!(
        !(settings.scheme == SchemeChoice::Hst && settings.nth == Nth::Auto),
        "work items with --shadows hst need one N_th for all: compute it once with --print-nth \
         and give it with --nth"
    );
    ensure!(
        args.stats.is_none(),
        "--stats: each work item writes its stats beside its tile"
    );
    ensure!(
        out.extension().is_none(),
        "--out {}: with --tiles or --frames, the folder the tiles go to",
        out.display()
    );
    let pixels = format!(
        "{} --orbit {degrees}",
        pixel_settings(&settings).to_args().join(" ")
    );
    let fingerprint = Fingerprint::of(&scene, &pixels);
    let (frame, tile) = items.item(items.index_from(args.tile)?);
    let region = tiles::band(width, height, tile, items.tiles);
    let scene = orbit(scene, degrees * frame as f32);
    let (radiance, report) = render(scene, &settings, region, &invalid)?;
    let header = TileHeader {
        image: (width, height),
        region,
        tile,
        items,
        frame,
        settings: pixels,
        fingerprint,
    };
    let path = out.join(tiles::tile_file_name(frame, tile));
    tiles::write_exr(&path, &radiance, (width, height), Some(&header))?;
    quadray_core::write_json(&path.with_extension("json"), &recorded(&report, None))?;
    println!("{}", path.display());
    Ok(())
}

/// `settings` with those that change no pixel at their defaults, so that the tiles of one picture
/// match whatever they were: N_th beside another scheme than HST, and `--check`.
fn pixel_settings(settings: &Settings) -> Settings {
    let defaults = Settings::DEFAULT;
    Settings {
        nth: match settings.scheme {
            SchemeChoice::Hst => settings.nth,
            _ => defaults.nth,
        },
        check: defaults.check,
        ..*settings
    }
}

/// Prepares `scene`, renders `region` of the picture with a progress bar and prints the times.
fn render(
    scene: Scene,
    settings: &Settings,
    region: Region,
    invalid: &dyn Fn(quadray_shadows::BuildError) -> anyhow::Error,
) -> anyhow::Result<(quadray_shadows::Radiance, quadray_shadows::RunReport)> {
    let prep = quadray_shadows::prepare(scene, settings.scheme).map_err(invalid)?;
    let costs = cost::calibrate();
    let tiles = region.width.div_ceil(16) as u64 * region.height.div_ceil(16) as u64;
    let bar = ProgressBar::new(tiles).with_style(ProgressStyle::with_template(
        "{bar:40} {pos}/{len} tiles {elapsed}",
    )?);
    // Without a terminal (a scheduler's log) the bar is hidden: a line every tenth instead.
    let (done, start, log) = (AtomicU64::new(0), Instant::now(), bar.is_hidden());
    let step = || {
        bar.inc(1);
        let n = done.fetch_add(1, Ordering::Relaxed) + 1;
        if log && n * 10 / tiles != (n - 1) * 10 / tiles {
            eprintln!(
                "rows {}..{} of {}: {}% ({n}/{tiles} blocks of 16x16) {:.1}s",
                region.y,
                region.y + region.height,
                settings.size,
                n * 100 / tiles,
                start.elapsed().as_secs_f64()
            );
        }
    };
    let (radiance, report) =
        quadray_shadows::render_prepared_region(&prep, settings, &costs, region, &step);
    bar.finish_and_clear();
    let t = &report.times_s;
    println!(
        "{} {} {}: preprocess {:.3}s (shadow volumes {:.3}s) shadow {:.3}s other {:.3}s total {:.3}s, N_th predicted {:.2}{}",
        report.scene,
        settings.scheme,
        settings.size,
        t.preprocess,
        t.shadow_volumes,
        t.shadow,
        t.other,
        t.total,
        report.nth.predicted,
        report
            .nth
            .used
            .map(|u| format!(" used {u:.2}"))
            .unwrap_or_default()
    );
    if let Some(d) = report.disagreements {
        println!(
            "disagreements with the conventional test: {d} of {} shading points",
            report.shading_points
        );
    }
    Ok((radiance, report))
}

/// `quadray bench shadows`: the paper's tables and figure 6 into `out`, the headline ratios printed.
pub fn bench(quick: bool, out: &Path) -> anyhow::Result<()> {
    let results = quadray_bench::shadows::bench_shadows(quick, out, &|msg| eprintln!("{msg}"))?;
    for s in &results.scenes {
        let (conv, hst, bvh) = (&s.schemes[0], &s.schemes[2], &s.schemes[3]);
        let embree = s
            .schemes
            .get(4)
            .map(|e| format!(", hst/embree {:.2}", hst.shadow / e.shadow))
            .unwrap_or_default();
        println!(
            "{}: shadow hst/conventional {:.2}, total {:.2}, hst/bvh {:.2}{embree}; N_th predicted \
             {:.1}, best {:.1} (shadow at predicted / best {:.2})",
            s.scene,
            hst.shadow / conv.shadow,
            hst.total / conv.total,
            hst.shadow / bvh.shadow,
            s.predicted_nth,
            s.best_nth,
            s.predicted_over_best
        );
    }
    println!("wrote {}", out.join("shadows.md").display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;
    use proptest::prelude::*;
    use quadray_core::settings::{Limits, Size};
    use quadray_test_support::flags::assert_settings_round_trip;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: RaytraceArgs,
    }

    /// Valid settings, every field drawn from its declared limits (Embree where this build has
    /// it).
    fn valid_settings() -> impl Strategy<Value = Settings> {
        let schemes: Vec<SchemeChoice> = SchemeChoice::ALL
            .into_iter()
            .filter(|s| s.name().parse::<SchemeChoice>().is_ok())
            .collect();
        let nth = prop_oneof![
            Just(Nth::Auto),
            (0.0f32..=1e6)
                .prop_filter("inside the limits", |n| Settings::NTH.contains(*n))
                .prop_map(Nth::Fixed),
        ];
        let u = |l: Limits<u32>| l.min..=l.max;
        (
            proptest::sample::select(schemes),
            nth,
            (u(Settings::SIDE), u(Settings::SIDE)),
            u(Settings::SPP),
            u(Settings::DEPTH),
            any::<bool>(),
        )
            .prop_map(|(scheme, nth, (w, h), spp, depth, check)| Settings {
                scheme,
                nth,
                size: Size::new(w, h),
                spp,
                depth,
                check,
            })
    }

    /// No flags: the library's defaults.
    #[test]
    fn the_flags_defaults_are_the_settings_defaults() {
        let cli = Cli::try_parse_from(["raytrace", "--builtin=stars"]).unwrap();
        assert_eq!(cli.args.settings, Settings::DEFAULT);
    }

    /// The flags refuse what `validate()` refuses, naming the flag and the same limits.
    #[test]
    fn the_flags_refuse_values_outside_the_limits() {
        let schemes: Vec<_> = SchemeChoice::ALL.iter().map(|s| s.to_string()).collect();
        for (flag, value, range) in [
            ("--shadows", "raster", schemes.join(", ")),
            ("--nth", "-3", Settings::NTH.to_string()),
            ("--nth", "inf", Settings::NTH.to_string()),
            ("--size", "0x10", Settings::SIDE.to_string()),
            ("--size", "16385x16", Settings::SIDE.to_string()),
            ("--spp", "0", Settings::SPP.to_string()),
            ("--depth", "65", Settings::DEPTH.to_string()),
        ] {
            // `=` so that a negative value reaches the flag's parser rather than clap's.
            let argv = ["raytrace", "--builtin=stars", &format!("{flag}={value}")];
            let e = Cli::try_parse_from(argv).err().expect(flag).to_string();
            assert!(e.contains(flag) && e.contains(&range), "{e}");
        }
    }

    /// Tiles of other schemes match whatever N_th they were given, and `--check` changes no
    /// pixel; every other setting tells tiles apart.
    #[test]
    fn only_the_settings_that_change_pixels_tell_tiles_apart() {
        let conventional = Settings {
            scheme: SchemeChoice::Conventional,
            ..Settings::DEFAULT
        };
        let other_nth = Settings {
            nth: Nth::Fixed(3.0),
            check: true,
            ..conventional
        };
        assert_eq!(pixel_settings(&conventional), pixel_settings(&other_nth));
        let hst = Settings {
            nth: Nth::Fixed(3.0),
            ..Settings::DEFAULT
        };
        assert_eq!(pixel_settings(&hst), hst);
    }

    /// The tiles carry `Settings::to_args` as their readable settings: every valid setting
    /// must come back through the CLI's flags unchanged.
    #[test]
    fn settings_round_trip_through_the_flags() {
        assert_settings_round_trip(
            &["raytrace", "--builtin=stars"],
            valid_settings(),
            Settings::validate,
            Settings::to_args,
            |args: RaytraceArgs| args.settings,
        );
    }
}
