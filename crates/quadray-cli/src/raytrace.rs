//! `quadray raytrace`: the Whitted ray tracer with hybrid shadow testing (quadray-shadows).

use anyhow::{Context, bail};
use indicatif::{ProgressBar, ProgressStyle};
use quadray_shadows::scene::{BUILTINS, Scene};
use quadray_shadows::{Nth, RunOptions, SchemeChoice, cost};
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct RaytraceArgs {
    /// A scene file: TOML, or glTF 2.0 (.gltf, .glb).
    #[arg(long, conflicts_with = "builtin")]
    scene: Option<PathBuf>,
    /// A builtin look-alike of the paper's scenes: glasses, desk, stars, kaist.
    #[arg(long)]
    builtin: Option<String>,
    /// Shadow scheme: hst, volume, conventional, bvh, or embree (built with --features embree).
    #[arg(long, default_value = "hst")]
    shadows: SchemeChoice,
    /// HST threshold: auto (the cost model's prediction) or a number.
    #[arg(long, default_value = "auto")]
    nth: String,
    /// Image size WxH.
    #[arg(long, default_value = "512x480", value_parser = quadray_core::parse_size)]
    size: (u32, u32),
    /// Samples per pixel.
    #[arg(long, default_value_t = 1)]
    spp: u32,
    /// Recursion depth of reflection and refraction.
    #[arg(long, default_value_t = 5)]
    depth: u32,
    /// Output PNG.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Statistics JSON (times, sub-schemes, N_th, p, alpha, ...).
    #[arg(long)]
    stats: Option<PathBuf>,
    /// Also run the conventional test at every shading point and count disagreements.
    #[arg(long)]
    check: bool,
    /// Only measure the machine constants C_s, C_i, C_c, C_o (nanoseconds) and print them.
    #[arg(long)]
    calibrate: bool,
}

pub fn run(args: RaytraceArgs) -> anyhow::Result<()> {
    if args.calibrate {
        let costs = cost::calibrate();
        let text = serde_json::to_string_pretty(&costs)?;
        println!("{text}");
        if let Some(path) = &args.stats {
            quadray_core::write_text(path, &text)?;
        }
        return Ok(());
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
    let source = match &args.scene {
        Some(path) => path.display().to_string(),
        None => format!("builtin scene {:?}", scene.name),
    };
    // Named like the loader's errors: "FILE: reason".
    let invalid = |e: quadray_shadows::BuildError| anyhow::anyhow!("{source}: {e}");
    scene.validate().map_err(invalid)?;
    let out = args.out.context("--out FILE.png is required")?;
    let nth = match args.nth.as_str() {
        "auto" => Nth::Auto,
        n => match n.parse::<f32>() {
            Ok(v) if v >= 0.0 => Nth::Fixed(v),
            _ => bail!("--nth {n:?}: expected auto or a number >= 0"),
        },
    };
    let (width, height) = args.size;
    if width == 0 || height == 0 || width > 16384 || height > 16384 {
        bail!("--size {width}x{height}: each side must be 1..=16384");
    }
    if args.spp == 0 || args.spp > 1024 || args.depth > 64 {
        bail!("--spp must be 1..=1024 and --depth at most 64");
    }
    let opts = RunOptions {
        scheme: args.shadows,
        nth,
        width,
        height,
        spp: args.spp,
        depth: args.depth,
        check: args.check,
        costs: None,
    };
    let tiles = width.div_ceil(16) as u64 * height.div_ceil(16) as u64;
    let bar = ProgressBar::new(tiles).with_style(ProgressStyle::with_template(
        "{bar:40} {pos}/{len} tiles {elapsed}",
    )?);
    let (image, report) = quadray_shadows::run(scene, &opts, &|| bar.inc(1)).map_err(invalid)?;
    bar.finish_and_clear();
    image.save_png(&out)?;
    let t = &report.times_s;
    println!(
        "{} {} {}x{}: preprocess {:.3}s shadow {:.3}s other {:.3}s total {:.3}s, N_th predicted {:.2}{}",
        report.scene,
        report.scheme,
        width,
        height,
        t.preprocess,
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
    if let Some(path) = &args.stats {
        quadray_core::write_json(path, &report)?;
    }
    Ok(())
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
