//! The viewer's command line: the technique and the settings it starts with, and the scripted
//! run that saves a screenshot.

use crate::indirect_view::Show;
use clap::Parser;
use quadray_displace::Settings;
use quadray_displace::heightmap::Convention;
use quadray_displace::scene::SurfaceKind;
use std::path::PathBuf;

/// The technique on screen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Technique {
    Displace,
    Indirect,
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
    pub technique: Technique,
    /// A height map of your own (shown beside the bundled ones).
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// How --map stores its values: height, depth or depth-photo.
    #[arg(long, default_value = "height")]
    pub convention: Convention,
    /// Start with this bundled map (tiles, bevy-cube, puget-sound, tum-photo).
    #[arg(long, default_value = "tiles")]
    pub bundled: String,
    #[arg(long)]
    pub surface: Option<SurfaceKind>,
    /// Displacement: the starting settings, `quadray displace`'s flags (`--size` is the 3-D
    /// view's size in a scripted run; the window's otherwise).
    #[command(flatten)]
    pub displace: Settings,
    /// An indirect-light scene file of your own (shown beside the bundled ones).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Indirect light: quadtree-tiles, quadtree, quadtree-passes, rsm or reference.
    #[arg(long, default_value_t = quadray_indirect::Method::DEFAULT)]
    pub indirect_method: quadray_indirect::Method,
    /// Indirect light: what the view shows.
    #[arg(long, value_enum, default_value = "combined")]
    pub show: Show,
    /// Indirect light: side of the RSM (default 512, 128 on a software rasterizer).
    #[arg(long)]
    pub rsm_size: Option<u32>,
    /// Scripted run: turn the camera by this many degrees each frame.
    #[arg(long, default_value_t = 0.0)]
    pub spin: f32,
    /// Indirect light: the light that right drags, L and --light-spin move (from 1).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub light: u32,
    /// Scripted run: turn that light by this many degrees each frame (a spot's or the sun's aim
    /// about the vertical; a point light about the scene's middle).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub light_spin: f32,
    /// Scripted run: draw this many frames, save --screenshot, and exit.
    #[arg(long)]
    pub frames: Option<u32>,
    /// Where P (or a scripted run) saves the frame; the command line goes beside it (.txt).
    #[arg(long, default_value = "quadray-view.png")]
    pub screenshot: PathBuf,
}
