//! `quadray-view` (also started as `quadray view`): fly around the real-time techniques. A window
//! with an egui control panel; the frame is drawn by the same library code as the headless
//! commands, and a key saves it with the command line that renders it headless.

mod app;
mod args;
mod displace_view;
mod indirect_view;
mod legibility;
mod widgets;

use anyhow::{Context, Result};
use args::Args;
use clap::Parser;
use displace_view::MapChoice;
use quadray_displace::scene::SurfaceKind;
use widgets::absolute;

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
