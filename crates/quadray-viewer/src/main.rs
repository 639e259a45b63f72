//! `quadray-view` (also started as `quadray view`): fly around the real-time techniques. A window
//! with an egui control panel; the frame is drawn by the same library code as the headless
//! commands, and a key saves it with the command line that renders it headless.

mod app;
mod displace_view;
mod indirect_view;

use anyhow::{Context, Result};
use clap::Parser;
use displace_view::MapChoice;
use quadray_displace::Settings;
use quadray_displace::heightmap::Convention;
use quadray_displace::scene::SurfaceKind;
use std::path::{Path, PathBuf};

/// The path without `..`, so the screenshot's command line works from any directory.
pub fn absolute(path: PathBuf) -> PathBuf {
    std::fs::canonicalize(&path).unwrap_or(path)
}

/// A path as one POSIX shell word (single-quoted when it holds anything but plain characters).
pub fn shell_word(path: &Path) -> String {
    let text = path.display().to_string();
    let plain = |c: char| c.is_ascii_alphanumeric() || "/._-+,:=@%".contains(c);
    if !text.is_empty() && text.chars().all(plain) {
        text
    } else {
        format!("'{}'", text.replace('\'', r"'\''"))
    }
}

#[derive(Parser)]
#[command(
    name = "quadray-view",
    version,
    about = "Interactive viewer for quadray's real-time techniques"
)]
pub struct Args {
    /// The technique shown first (both are a click apart in the panel).
    #[arg(long, value_enum, default_value = "displace")]
    technique: app::Technique,
    /// A height map of your own (shown beside the bundled ones).
    #[arg(long)]
    map: Option<PathBuf>,
    /// How --map stores its values: height, depth or depth-photo.
    #[arg(long, default_value = "height")]
    convention: Convention,
    /// Start with this bundled map (tiles, bevy-cube, puget-sound, tum-photo).
    #[arg(long, default_value = "tiles")]
    bundled: String,
    #[arg(long)]
    surface: Option<SurfaceKind>,
    /// Displacement: the starting settings, `quadray displace`'s flags (`--size` is the 3-D
    /// view's size in a scripted run; the window's otherwise).
    #[command(flatten)]
    displace: Settings,
    /// An indirect-light scene file of your own (shown beside the bundled ones).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Indirect light: quadtree-tiles, quadtree, quadtree-passes, rsm or reference.
    #[arg(long, default_value_t = quadray_indirect::Method::DEFAULT)]
    indirect_method: quadray_indirect::Method,
    /// Indirect light: what the view shows.
    #[arg(long, value_enum, default_value = "combined")]
    show: indirect_view::Show,
    /// Indirect light: side of the RSM (default 512, 128 on a software rasterizer).
    #[arg(long)]
    rsm_size: Option<u32>,
    /// Scripted run: turn the camera by this many degrees each frame.
    #[arg(long, default_value_t = 0.0)]
    spin: f32,
    /// Scripted run: draw this many frames, save --screenshot, and exit.
    #[arg(long)]
    frames: Option<u32>,
    /// Where P (or a scripted run) saves the frame; the command line goes beside it (.txt).
    #[arg(long, default_value = "quadray-view.png")]
    screenshot: PathBuf,
}

fn main() -> Result<()> {
    quadray_core::init_logging();
    let args = Args::parse();
    let mut maps = MapChoice::bundled();
    let mut start = maps
        .iter()
        .position(|m| m.name == args.bundled)
        .with_context(|| format!("no bundled map `{}`", args.bundled))?;
    if let Some(path) = &args.map {
        maps.push(MapChoice {
            name: path
                .file_name()
                .map_or("map".into(), |n| n.to_string_lossy().into_owned()),
            path: absolute(path.clone()),
            convention: args.convention,
            color: None,
            surface: SurfaceKind::Wall,
        });
        start = maps.len() - 1;
    }
    let settings = args.displace.clone();
    settings.validate().map_err(anyhow::Error::msg)?;
    app::run(args, maps, start, settings)
}
