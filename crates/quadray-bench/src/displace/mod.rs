//! `quadray bench displace`: the paper's tables 1 and 2 and figures 20 and 21 as GPU-time ratios
//! measured in one run, an accuracy-vs-view-angle table for every method, and how many POM layers
//! it takes to match the pyramid's accuracy. Writes results.json, results.md and SVG plots.
//! Each table or figure is one function ([`timing`], [`accuracy`]) on the shared [`measure`]
//! context; [`run`] runs them in order.

pub mod accuracy;
pub mod demo;
pub mod measure;
pub mod timing;

use crate::report::Table;
use measure::{AccuracyRow, Bench, Ratios, TimingRow};
use quadray_core::{write_json, write_text};
use quadray_displace::DisplaceError;
use quadray_gpu::Gpu;
use serde::Serialize;
use std::path::Path;

/// How much to measure.
#[derive(Clone, Copy, Debug)]
pub struct BenchOptions {
    /// Smaller frames, fewer angles and sizes, fewer frames: minutes on a software rasterizer.
    pub quick: bool,
}

/// Everything results.json holds.
#[derive(Serialize)]
pub struct Results {
    pub adapter: String,
    pub software_rasterizer: bool,
    pub quick: bool,
    pub frames: usize,
    pub timings: Vec<TimingRow>,
    pub accuracy: Vec<AccuracyRow>,
    pub ratios: Ratios,
    pub tables: Vec<Table>,
}

/// Runs every table and figure, writes results.json, results.md and the plots into `out`.
pub fn run(
    gpu: &Gpu,
    out: &Path,
    opts: BenchOptions,
    mut progress: impl FnMut(&str),
) -> Result<Results, DisplaceError> {
    let quick = opts.quick;
    let mut bench = Bench {
        gpu,
        quick,
        frames: if quick { 5 } else { 30 },
        paper: if quick { 256 } else { 512 },
        timings: Vec::new(),
    };
    let mut ratios = Ratios::default();
    progress("tables 1, 2 and figure 20");
    let mut tables = timing::tables_1_2_figure_20(&mut bench, &mut ratios)?;
    progress("figure 21");
    let tiles = quadray_displace::maps::BUNDLED[0].load()?;
    tables.push(timing::figure_21(&mut bench, &tiles, out, &mut ratios)?);
    progress("pyramid build");
    tables.push(timing::pyramid_build(&bench, &tiles)?);
    progress("cone map build");
    tables.push(timing::cone_build(&bench, &tiles)?);
    progress("1920x1080");
    tables.extend(timing::todays_frame(&mut bench, &tiles, &mut ratios)?);
    progress("accuracy by view angle");
    let (accuracy_tables, accuracy) = accuracy::by_view_angle(&bench, out)?;
    tables.extend(accuracy_tables);
    progress("POM layers to match the pyramid");
    tables.push(accuracy::pom_layers_to_match(
        &mut bench,
        &tiles,
        out,
        &mut ratios,
    )?);

    let results = Results {
        adapter: gpu.describe(),
        software_rasterizer: gpu.is_software(),
        quick,
        frames: bench.frames,
        timings: bench.timings,
        accuracy,
        ratios,
        tables,
    };
    write_json(&out.join("results.json"), &results)?;
    let mut md = format!(
        "# quadray bench displace\n\nAdapter: {}{}\n\n",
        results.adapter,
        if results.software_rasterizer {
            " (software rasterizer: compare ratios only)"
        } else {
            ""
        }
    );
    md += &format!(
        "Ratios: {}\n\n",
        serde_json::to_string(&results.ratios).unwrap_or_default()
    );
    for t in &results.tables {
        md += &t.to_markdown();
        md.push('\n');
    }
    write_text(&out.join("results.md"), &md)?;
    Ok(results)
}
