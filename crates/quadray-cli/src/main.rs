//! `quadray`: renders each technique headless, compares it with its CPU ground truth, and runs the
//! benchmarks. Each subcommand lives in its own module.

mod displace;
mod indirect;
mod merge;
mod provenance;
mod raytrace;
mod scene;
mod smoke;
mod tiles;

use anyhow::{Context, Result};
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use indicatif::ProgressBar;
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "quadray",
    version = provenance::VERSION,
    about = "Reference implementations of three rendering papers"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Read the files a scene or mesh file refers to even where they lie outside its folder
    /// (`..`, an absolute path, a link that points out); without it they are refused, so that a
    /// scene from someone else reads only the files that came with it.
    #[arg(long, global = true)]
    allow_outside_paths: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Print the GPU adapter quadray would use.
    Adapter,
    /// Pyramid displacement mapping and its baselines on one height map.
    Displace(displace::DisplaceArgs),
    /// Whitted ray tracing on a uniform grid with hybrid shadow testing.
    Raytrace(raytrace::RaytraceArgs),
    /// Assemble the tiles of `quadray raytrace --tiles N` (or `--frames A..B`) into pictures.
    Merge(merge::MergeArgs),
    /// Work items of a tiled render: which are missing.
    Tiles(merge::TilesArgs),
    /// One-bounce indirect light from a light quadtree, its baselines and reference.
    Indirect(indirect::IndirectArgs),
    /// Scene files: `quadray scene export IN OUT.gltf` writes a scene as glTF.
    Scene(scene::SceneArgs),
    /// Every GPU pass of every technique at a tiny size, one at a time, each waited for within
    /// the bound: one line a pass, or the error naming where it stopped (a new GPU's first check).
    Smoke(smoke::SmokeArgs),
    /// Open the interactive viewer: runs the `quadray-view` program installed beside this one
    /// (its own crate, so quadray builds without windowing); every argument is passed on.
    View {
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Render the side-by-side pictures of every technique from the bundled assets.
    Demo {
        #[arg(long, default_value = "out/demo")]
        out: PathBuf,
        /// Side of each picture in pixels.
        #[arg(long, default_value_t = 384)]
        size: u32,
    },
    /// Benchmarks: results.json, results.md and plots.
    Bench {
        #[command(subcommand)]
        what: Bench,
    },
}

#[derive(Subcommand)]
enum Bench {
    /// Tables 1-4 and figure 6 of the hybrid shadow testing paper, with SAH BVH shadow rays.
    Shadows {
        /// Small images and one render per measurement.
        #[arg(long)]
        quick: bool,
        #[arg(long, default_value = "out/bench/shadows")]
        out: PathBuf,
    },
    /// Tables 1-2, figures 20-21 and accuracy by view angle of the displacement paper.
    Displace {
        /// Smaller frames and fewer sizes: minutes on a software rasterizer.
        #[arg(long)]
        quick: bool,
        #[arg(long, default_value = "out/bench/displace")]
        out: PathBuf,
    },
    /// Tables 1-3 and the error-vs-time plot of the light-quadtree paper.
    Indirect {
        /// 64x64 image and RSM, 3 frames per median: seconds on a software rasterizer.
        #[arg(long)]
        quick: bool,
        /// Image side (default 512, quick 64).
        #[arg(long)]
        size: Option<u32>,
        /// RSM side (default 512, quick 64; with --equal-error: 256 and 512, quick 64).
        #[arg(long)]
        rsm_size: Option<u32>,
        /// Only the quadtree against RSM sampling at equal error, in VPL evaluations, texel
        /// fetches and time, on every bundled scene (image side 128, quick 64).
        #[arg(long)]
        equal_error: bool,
        /// Only the CPU study of the per-tile cuts: how their error and size depend on the split
        /// criterion (children, grandchildren, an oracle) and the cluster's representative (point,
        /// second order), on the Cornell box or the --scene given (image side 128, RSM 256).
        #[arg(long, conflicts_with = "equal_error")]
        cut_study: bool,
        /// With --equal-error or --cut-study: only this bundled scene (file stem, e.g. cornell;
        /// repeatable).
        #[arg(long = "scene")]
        scenes: Vec<String>,
        #[arg(long, default_value = "out/bench/indirect")]
        out: PathBuf,
    },
}

/// What a long command is doing: a spinner on a terminal; elsewhere (a log, a pipe) a line a step
/// on stderr, after the wall and CPU seconds since the command started.
struct Steps {
    bar: ProgressBar,
    start: std::time::Instant,
    cpu_start: f64,
}

impl Steps {
    fn new(what: &str) -> Self {
        Self {
            bar: spinner(what),
            start: std::time::Instant::now(),
            cpu_start: quadray_shadows::process_cpu_s(),
        }
    }

    fn step(&self, message: String) {
        if self.bar.is_hidden() {
            let wall = self.start.elapsed().as_secs_f64();
            let cpu = quadray_shadows::process_cpu_s() - self.cpu_start;
            eprintln!("{wall:6.1} s {cpu:7.1} CPU s  {message}");
        } else {
            self.bar.set_message(message);
        }
    }
}

fn spinner(what: &str) -> ProgressBar {
    let bar = ProgressBar::new_spinner().with_message(what.to_string());
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar
}

fn main() -> Result<()> {
    let command = quadray_core::settings::terminal_help(Cli::command());
    let cli = Cli::from_arg_matches(&command.get_matches()).unwrap_or_else(|e| e.exit());
    if !matches!(cli.command, Command::View { .. }) {
        // SAFETY: first thing in main, before any thread starts.
        unsafe { quadray_gpu::skip_display_probing() };
    }
    quadray_core::init_logging();
    quadray_core::mesh::allow_outside_paths(cli.allow_outside_paths);
    match cli.command {
        Command::View { args } => {
            let viewer = std::env::current_exe()?
                .with_file_name(format!("quadray-view{}", std::env::consts::EXE_SUFFIX));
            let status = std::process::Command::new(&viewer)
                .args(args)
                .status()
                .with_context(|| {
                    format!(
                        "cannot start the viewer {} (build it: cargo build --release -p quadray-viewer)",
                        viewer.display()
                    )
                })?;
            std::process::exit(status.code().unwrap_or(1));
        }
        Command::Adapter => {
            let gpu = quadray_gpu::Gpu::new()?;
            println!("{}", gpu.describe());
        }
        Command::Displace(args) => displace::run(args)?,
        Command::Raytrace(args) => raytrace::run(args)?,
        Command::Merge(args) => merge::run(args)?,
        Command::Tiles(args) => merge::run_tiles(args)?,
        Command::Bench {
            what: Bench::Shadows { quick, out },
        } => raytrace::bench(quick, &out)?,
        Command::Indirect(args) => indirect::run_indirect(args)?,
        Command::Scene(args) => scene::run(args)?,
        Command::Smoke(args) => smoke::run(args)?,
        Command::Demo { out, size } => {
            if !(16..=4096).contains(&size) {
                anyhow::bail!("--size {size} is outside 16..4096");
            }
            let gpu = quadray_gpu::Gpu::new()?;
            let steps = Steps::new("demo");
            let mut files = quadray_bench::displace::demo::render_demo(
                &gpu,
                &out.join("displace"),
                size,
                |m| steps.step(format!("displacement: {m}")),
            )?;
            files.extend(quadray_bench::indirect::demo::render_demo(
                &gpu,
                &out.join("indirect"),
                size,
                |m| steps.step(format!("indirect light: {m}")),
            )?);
            files.extend(quadray_bench::shadows::render_demo(
                &out.join("raytrace"),
                size,
                |m| steps.step(format!("ray tracing: {m}")),
            )?);
            steps.step(format!("{} pictures", files.len()));
            steps.bar.finish_and_clear();
            for f in files {
                println!("{}", f.display());
            }
        }
        Command::Bench {
            what: Bench::Displace { quick, out },
        } => {
            let gpu = quadray_gpu::Gpu::new()?;
            let bar = spinner("bench displace");
            let results = quadray_bench::displace::run(
                &gpu,
                &out,
                quadray_bench::displace::BenchOptions { quick },
                |m| bar.set_message(format!("bench displace: {m}")),
            )?;
            bar.finish_and_clear();
            println!("{}", std::fs::read_to_string(out.join("results.md"))?);
            println!("ratios: {}", serde_json::to_string_pretty(&results.ratios)?);
        }
        Command::Bench {
            what:
                Bench::Indirect {
                    quick,
                    size,
                    rsm_size,
                    equal_error,
                    cut_study,
                    scenes,
                    out,
                },
        } => {
            if cut_study {
                indirect::bench_cut_study(
                    size.unwrap_or(128),
                    rsm_size.unwrap_or(256),
                    &scenes,
                    &out,
                )?
            } else if equal_error {
                let options = quadray_bench::indirect::equal_error::EqualErrorOptions::new(
                    quick, size, rsm_size, scenes,
                );
                indirect::bench_equal_error(&options, &out)?
            } else {
                let options = quadray_bench::indirect::tables::BenchOptions {
                    quick,
                    size,
                    rsm_size,
                };
                indirect::bench(options, &out)?
            }
        }
    }
    Ok(())
}
