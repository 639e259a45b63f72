//! `quadray merge`: assembles the tiles of `quadray raytrace --tiles N [--frames A..B]` into the
//! picture (one per frame), bit for bit the render of one process; refuses a missing, duplicate,
//! misplaced or mismatched tile by name. `quadray tiles missing` gives the indices of the items
//! whose tiles are missing, to re-run exactly those.

use crate::tiles::{self, TileHeader};
use anyhow::{Context, bail, ensure};
use quadray_shadows::{Radiance, Region};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct MergeArgs {
    /// Tile files (EXR), or folders whose `.exr` files are all tiles.
    #[arg(required = true)]
    tiles: Vec<PathBuf>,
    /// The picture: PNG (tone-mapped as `quadray raytrace --out F.png`) or EXR (the radiance). A
    /// turntable writes one per frame, the frame number before the extension (F.0003.png).
    #[arg(long)]
    out: PathBuf,
}

pub fn run(args: MergeArgs) -> anyhow::Result<()> {
    let exr = crate::raytrace::is_exr(&args.out);
    let job = Job::read(&args.tiles)?;
    if !job.missing.is_empty() {
        let folders: Vec<String> = args.tiles.iter().map(|p| p.display().to_string()).collect();
        bail!(
            "{} (file names {}); `quadray tiles missing {}` prints their indices, \
             `deploy/slurm/submit.sh --resume DIR` re-runs them on Slurm",
            job.describe_missing(),
            tiles::tile_file_name(0, 0).replace("0000", "NNNN"),
            folders.join(" ")
        );
    }
    let first = &job.first;
    let (width, height) = first.image;
    for (frame, tiles) in &job.plan {
        let mut picture = Radiance {
            region: Region::full(width, height),
            pixels: vec![[0.0; 3]; width as usize * height as usize],
        };
        for (path, header) in tiles {
            let tile = tiles::read_pixels(path, header)?;
            let r = tile.region;
            for (row, pixels) in tile.pixels.chunks_exact(r.width as usize).enumerate() {
                let start = (r.y as usize + row) * width as usize + r.x as usize;
                picture.pixels[start..start + pixels.len()].copy_from_slice(pixels);
            }
        }
        let out = if first.items.frames.len() > 1 || first.items.frames.start > 0 {
            tiles::frame_path(&args.out, *frame)
        } else {
            args.out.clone()
        };
        if exr {
            tiles::write_exr(&out, &picture, first.image, None)?;
        } else {
            picture.to_rgba8(1.0).save_png(&out)?;
        }
        println!("{}", out.display());
    }
    Ok(())
}

/// `quadray tiles`: what a folder of work items holds.
#[derive(clap::Args)]
pub struct TilesArgs {
    #[command(subcommand)]
    command: TilesCommand,
}

#[derive(clap::Subcommand)]
enum TilesCommand {
    /// Print the indices of the work items whose tiles are missing, as runs (`3,5-7`: the form
    /// of `sbatch --array`), nothing when none is; which they are, and the job's settings, go
    /// to stderr. The tiles there must be of one job, as `quadray merge` checks.
    Missing {
        /// Tile files (EXR), or folders whose `.exr` files are all tiles.
        #[arg(required = true)]
        tiles: Vec<PathBuf>,
        /// One index a line instead of runs.
        #[arg(long)]
        list: bool,
    },
}

pub fn run_tiles(args: TilesArgs) -> anyhow::Result<()> {
    let TilesCommand::Missing { tiles, list } = args.command;
    let job = Job::read(&tiles)?;
    if job.missing.is_empty() {
        eprintln!(
            "all {} items are there ({})",
            job.first.items.count(),
            job.first.settings
        );
    } else {
        eprintln!("{} ({})", job.describe_missing(), job.first.settings);
        if list {
            job.missing.iter().for_each(|i| println!("{i}"));
        } else {
            println!("{}", tiles::index_ranges(&job.missing));
        }
    }
    Ok(())
}

/// The files named, folders replaced by their `.exr` files in name order.
fn tile_files(args: &[PathBuf]) -> anyhow::Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for arg in args {
        if arg.is_dir() {
            let mut found: Vec<PathBuf> = std::fs::read_dir(arg)
                .with_context(|| format!("{}", arg.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")))
                .collect();
            ensure!(!found.is_empty(), "{}: no .exr tiles in it", arg.display());
            found.sort();
            files.extend(found);
        } else {
            files.push(arg.clone());
        }
    }
    Ok(files)
}

type Plan = BTreeMap<u32, Vec<(PathBuf, TileHeader)>>;

/// The tiles of one job, by frame, and the indices of the items that have none.
struct Job {
    /// The header of the first tile: the job's image, items and settings.
    first: TileHeader,
    plan: Plan,
    missing: Vec<u64>,
}

impl Job {
    /// Reads every header and checks the set: one job (same image, items, settings and scene),
    /// each tile where its index puts it, no item twice.
    fn read(args: &[PathBuf]) -> anyhow::Result<Job> {
        let files = tile_files(args)?;
        let mut seen: BTreeMap<(u32, u32), &Path> = BTreeMap::new();
        let mut plan = Plan::new();
        let mut first: Option<(TileHeader, &Path)> = None;
        for path in &files {
            let header = tiles::read_header(path)?;
            let name = path.display();
            if let Some((f, f_path)) = &first {
                let other = f_path.display();
                ensure!(
                    header.image == f.image && header.items == f.items,
                    "{name}: belongs to another job ({}x{}, {} tiles, frames {:?}) than {other} \
                     ({}x{}, {} tiles, frames {:?})",
                    header.image.0,
                    header.image.1,
                    header.items.tiles,
                    header.items.frames,
                    f.image.0,
                    f.image.1,
                    f.items.tiles,
                    f.items.frames
                );
                ensure!(
                    header.settings == f.settings,
                    "{name}: rendered with other settings ({}) than {other} ({})",
                    header.settings,
                    f.settings
                );
                ensure!(
                    header.fingerprint == f.fingerprint,
                    "{name}: rendered from another scene or settings (fingerprint {}) than \
                     {other} ({})",
                    header.fingerprint,
                    f.fingerprint
                );
            } else {
                first = Some((header.clone(), path));
            }
            let expected = tiles::band(
                header.image.0,
                header.image.1,
                header.tile,
                header.items.tiles,
            );
            ensure!(
                header.region == expected,
                "{name}: tile {} covers {:?}, not its place {expected:?} (it would overlap \
                 others)",
                header.tile,
                header.region
            );
            if let Some(earlier) = seen.insert((header.frame, header.tile), path) {
                bail!(
                    "{name}: duplicate of {} (frame {} tile {})",
                    earlier.display(),
                    header.frame,
                    header.tile
                );
            }
            plan.entry(header.frame)
                .or_default()
                .push((path.clone(), header));
        }
        let (first, _) = first.context("no tiles given")?;
        let missing = (0..first.items.count())
            .filter(|&i| !seen.contains_key(&first.items.item(i)))
            .collect();
        Ok(Job {
            first,
            plan,
            missing,
        })
    }

    /// "2 of 16 items missing: frame 0 tile 3 (item 3), ...", the first eight named.
    fn describe_missing(&self) -> String {
        let items = &self.first.items;
        let named: Vec<String> = self
            .missing
            .iter()
            .take(8)
            .map(|&i| {
                let (frame, tile) = items.item(i);
                format!("frame {frame} tile {tile} (item {i})")
            })
            .collect();
        format!(
            "{} of {} items missing: {}{}",
            self.missing.len(),
            items.count(),
            named.join(", "),
            if self.missing.len() > 8 { ", ..." } else { "" }
        )
    }
}
