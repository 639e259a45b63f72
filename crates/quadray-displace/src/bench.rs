//! `quadray bench displace`: the paper's tables 1 and 2 and figures 20 and 21 as GPU-time ratios
//! measured in one run, an accuracy-vs-view-angle table for every method, and how many POM layers
//! it takes to match the pyramid's accuracy. Writes results.json, results.md and SVG plots.

use crate::DisplaceError;
use crate::accuracy::{Accuracy, Cost};
use crate::demo::{bevy_pom, threejs_relief};
use crate::gpu::{Lod, PyramidBuilder, Renderer, Settings};
use crate::heightmap::HeightMap;
use crate::maps::{BUNDLED, BundledMap, resized};
use crate::method::Method;
use crate::pyramid::Addressing;
use crate::pyramid::Pyramid;
use crate::scene::SurfaceKind;
use quadray_core::bench::{PlotSpec, Series, Table, line_plot, write_json, write_text};
use quadray_core::stats::time_cpu;
use quadray_gpu::{Gpu, GpuTimer};
use serde::Serialize;
use std::path::Path;

#[derive(Clone, Copy, Debug)]
pub struct BenchOptions {
    /// Smaller frames, fewer angles and sizes, fewer frames: minutes on a software rasterizer.
    pub quick: bool,
}

#[derive(Serialize)]
pub struct TimingRow {
    pub experiment: String,
    pub map: String,
    pub map_size: u32,
    pub method: String,
    pub width: u32,
    pub height: u32,
    pub view_angle_deg: f32,
    pub gpu_time_ms: Option<f64>,
    pub p10_ms: Option<f64>,
    pub p90_ms: Option<f64>,
    pub frames: usize,
    pub memory_bytes: u64,
}

#[derive(Serialize)]
pub struct AccuracyRow {
    pub map: String,
    pub method: String,
    pub view_angle_deg: f32,
    pub wrong_hit_fraction: f64,
    pub mean_error_texels: f64,
    pub covered: usize,
    pub mean_iterations: f64,
    pub iteration_cap_hits: usize,
}

#[derive(Serialize, Default)]
pub struct Ratios {
    /// pyramid / POM-16 GPU time at 512x512 with a 256^2 map (target <= 1.5).
    pub pyramid_over_pom16_paper_size: Option<f64>,
    /// The same at 1920x1080 with a 1024^2 map.
    pub pyramid_over_pom16_today: Option<f64>,
    /// POM layers needed to reach the pyramid's accuracy on the sharp map at 80 degrees.
    pub pom_layers_to_match: Option<u32>,
    /// POM time at that layer count / pyramid time (target >= 5).
    pub pom_matched_over_pyramid: Option<f64>,
    /// The last POM layer count tried: (layers, wrong-hit fraction, POM time / pyramid time).
    pub pom_most_layers: Option<(u32, f64, Option<f64>)>,
    /// Pyramid time with the 4096^2 map / with the 256^2 map (target <= 1.3).
    pub pyramid_4096_over_256: Option<f64>,
    /// The same with the LOD of section 3.4 chosen from screen-space derivatives.
    pub pyramid_lod_auto_4096_over_256: Option<f64>,
    /// Pyramid with LOD from derivatives / POM-16 at 1920x1080 (POM samples level 0 as here).
    pub pyramid_lod_auto_over_pom16_today: Option<f64>,
}

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

struct Bench<'a> {
    gpu: &'a Gpu,
    frames: usize,
    timings: Vec<TimingRow>,
}

impl Bench<'_> {
    fn time(
        &mut self,
        experiment: &str,
        name: &str,
        map: &HeightMap,
        renderer: &mut Renderer,
        s: &Settings,
    ) -> Result<Option<f64>, DisplaceError> {
        let summary = renderer.time(self.gpu, s, self.frames)?;
        let mut label = match s.method {
            Method::Pom | Method::Relief => format!("{}-{}", s.method, s.layers.1),
            m => m.to_string(),
        };
        if s.lod == Lod::Auto {
            label += " lod-auto";
        }
        self.timings.push(TimingRow {
            experiment: experiment.into(),
            map: name.into(),
            map_size: map.size(),
            method: label,
            width: s.width,
            height: s.height,
            view_angle_deg: s.view_angle_deg,
            gpu_time_ms: summary.map(|t| t.median_ms),
            p10_ms: summary.map(|t| t.p10_ms),
            p90_ms: summary.map(|t| t.p90_ms),
            frames: self.frames,
            memory_bytes: renderer.memory_bytes(s.method),
        });
        Ok(summary.map(|t| t.median_ms))
    }
}

fn fixed_layers(method: Method, layers: u32) -> Settings {
    Settings {
        method,
        layers: (layers, layers),
        binary_steps: 5,
        ..Default::default()
    }
}

fn ms(v: Option<f64>) -> String {
    v.map_or("n/a".into(), |v| format!("{v:.3}"))
}

fn ratio(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    Some(a? / b?)
}

fn ratio_text(v: Option<f64>) -> String {
    v.map_or("n/a".into(), |v| format!("{v:.2}"))
}

fn addressing(b: &BundledMap) -> Addressing {
    if b.surface.wraps() {
        Addressing::Wrap
    } else {
        Addressing::Clamp
    }
}

pub fn run(
    gpu: &Gpu,
    out: &Path,
    opts: BenchOptions,
    mut progress: impl FnMut(&str),
) -> Result<Results, DisplaceError> {
    let quick = opts.quick;
    let frames = if quick { 5 } else { 30 };
    let mut bench = Bench {
        gpu,
        frames,
        timings: Vec::new(),
    };
    let mut tables = Vec::new();
    let mut ratios = Ratios::default();
    let paper = if quick { 256 } else { 512 };
    let paper_view = |s: Settings| Settings {
        width: paper,
        height: paper,
        view_angle_deg: 60.0,
        ..s
    };

    // Tables 1 and 2, figure 20: the paper's screen size and 256^2 maps.
    progress("tables 1, 2 and figure 20");
    let mut t1 = Table::new(
        format!("Table 1: point vs bilinear, GPU ms ({paper}x{paper}, 256^2 maps, 60 deg)"),
        &[
            "map (paper row)",
            "pyramid (point)",
            "pyramid-bilinear",
            "bilinear / point",
        ],
    );
    let mut t2 = Table::new(
        format!(
            "Table 2: POM vs relief vs pyramid, GPU ms ({paper}x{paper}, 256^2 maps, 16 layers)"
        ),
        &[
            "map (paper row)",
            "pom-16",
            "relief-16+5",
            "pyramid",
            "pyramid-ascend",
            "pyramid / pom-16",
        ],
    );
    let mut f20 = Table::new(
        format!(
            "Figure 20: displaced mesh (2 x 256^2 triangles) vs pyramid ({paper}x{paper}, one 256^2 tile)"
        ),
        &["map", "method", "GPU ms", "memory (MB)"],
    );
    for b in BUNDLED.iter().filter(|b| b.paper_row != "-") {
        let map = resized(&b.load()?, 256);
        let mut r = Renderer::new(gpu, &map, None, b.surface);
        let mut time = |experiment, method| {
            let s = paper_view(fixed_layers(method, 16));
            bench.time(experiment, b.name, &map, &mut r, &s)
        };
        let point = time("table1", Method::Pyramid)?;
        let bilinear = time("table1", Method::PyramidBilinear)?;
        let pom = time("table2", Method::Pom)?;
        let relief = time("table2", Method::Relief)?;
        let ascend = time("table2", Method::PyramidAscend)?;
        let row = format!("{} ({})", b.name, b.paper_row);
        t1.row(vec![
            row.clone(),
            ms(point),
            ms(bilinear),
            ratio_text(ratio(bilinear, point)),
        ]);
        t2.row(vec![
            row,
            ms(pom),
            ms(relief),
            ms(point),
            ms(ascend),
            ratio_text(ratio(point, pom)),
        ]);
        if b.name == "tiles" {
            ratios.pyramid_over_pom16_paper_size = ratio(point, pom);
            // One copy of the map, as in the paper's figure: 2 * 256^2 triangles for the mesh.
            let mut one = Renderer::new(gpu, &map, None, SurfaceKind::Terrain);
            for method in [Method::Pyramid, Method::Mesh] {
                let s = paper_view(fixed_layers(method, 16));
                let t = bench.time("figure20", b.name, &map, &mut one, &s)?;
                let mb = one.memory_bytes(method) as f64 / 1e6;
                f20.row(vec![
                    b.name.into(),
                    method.to_string(),
                    ms(t),
                    format!("{mb:.2}"),
                ]);
            }
        }
    }
    tables.extend([t1, t2, f20]);

    // Figure 21: cost against map size.
    progress("figure 21");
    let tiles = BUNDLED[0].load()?;
    let sizes: &[u32] = if quick {
        &[256, 512, 1024]
    } else {
        &[256, 512, 1024, 2048, 4096]
    };
    let mut f21 = Table::new(
        format!("Figure 21: GPU ms by map size ({paper}x{paper}, tiles, 60 deg)"),
        &[
            "map size",
            "pyramid",
            "pyramid-ascend",
            "pyramid lod-auto",
            "pyramid / at 256^2",
            "lod-auto / at 256^2",
        ],
    );
    let variants = [
        ("pyramid", fixed_layers(Method::Pyramid, 16)),
        ("pyramid-ascend", fixed_layers(Method::PyramidAscend, 16)),
        (
            "pyramid lod-auto",
            Settings {
                lod: Lod::Auto,
                ..fixed_layers(Method::Pyramid, 16)
            },
        ),
    ];
    let mut f21_series: Vec<Series> = variants
        .iter()
        .map(|(name, _)| Series {
            name: name.to_string(),
            points: vec![],
        })
        .collect();
    let mut at_256 = [None; 3];
    for &size in sizes {
        let map = resized(&tiles, size);
        let mut r = Renderer::new(gpu, &map, None, BUNDLED[0].surface);
        let mut times = [None; 3];
        for (k, (_, s)) in variants.iter().enumerate() {
            times[k] = bench.time("figure21", "tiles", &map, &mut r, &paper_view(s.clone()))?;
            if let Some(t) = times[k] {
                f21_series[k].points.push((f64::from(size), t));
            }
        }
        if size == 256 {
            at_256 = times;
        }
        if size == 4096 {
            ratios.pyramid_4096_over_256 = ratio(times[0], at_256[0]);
            ratios.pyramid_lod_auto_4096_over_256 = ratio(times[2], at_256[2]);
        }
        let r = |k: usize| ratio_text(ratio(times[k], at_256[k]));
        f21.row(vec![
            format!("{size}^2"),
            ms(times[0]),
            ms(times[1]),
            ms(times[2]),
            r(0),
            r(2),
        ]);
    }
    tables.push(f21);
    if f21_series.iter().all(|s| !s.points.is_empty()) {
        let spec = PlotSpec {
            title: "GPU time by map size (figure 21)",
            x_label: "map side (texels)",
            y_label: "GPU ms",
            log_x: true,
            log_y: false,
        };
        line_plot(&out.join("figure21_map_size.svg"), &spec, &f21_series)?;
    }

    // Section 3.1: building the pyramid, on the CPU (the paper: 2.3 ms for 256^2) and on the GPU.
    progress("pyramid build");
    let mut build = Table::new(
        "Pyramid build (section 3.1): CPU ms (median, one thread) and GPU ms (compute, timestamps)",
        &["map size", "CPU", "GPU"],
    );
    let builder = PyramidBuilder::new(gpu);
    for &size in sizes {
        let map = resized(&tiles, size);
        let (_, cpu) = time_cpu(frames, || Pyramid::build(&map));
        let mut timer = GpuTimer::new(gpu, 1);
        for _ in 0..frames {
            builder.build(gpu, &map, None, Some(&timer));
            timer.collect(gpu)?;
        }
        let gpu_ms = timer.summaries()[0].map(|t| t.median_ms);
        build.row(vec![
            format!("{size}^2"),
            format!("{:.3}", cpu.median_ms),
            ms(gpu_ms),
        ]);
    }
    tables.push(build);

    // Today's frame: 1920x1080 with a 1024^2 map.
    progress("1920x1080");
    let (w, h) = if quick { (480, 270) } else { (1920, 1080) };
    {
        let mut r = Renderer::new(gpu, &tiles, None, BUNDLED[0].surface);
        let today = |s: Settings| Settings {
            width: w,
            height: h,
            view_angle_deg: 60.0,
            ..s
        };
        let columns = [
            ("pom-16", fixed_layers(Method::Pom, 16)),
            ("pyramid", fixed_layers(Method::Pyramid, 16)),
            ("pyramid-ascend", fixed_layers(Method::PyramidAscend, 16)),
            (
                "pyramid-bilinear",
                fixed_layers(Method::PyramidBilinear, 16),
            ),
            (
                "pyramid lod-auto",
                Settings {
                    lod: Lod::Auto,
                    ..fixed_layers(Method::Pyramid, 16)
                },
            ),
        ];
        let mut times = Vec::new();
        for (_, s) in &columns {
            times.push(bench.time("today", "tiles", &tiles, &mut r, &today(s.clone()))?);
        }
        ratios.pyramid_over_pom16_today = ratio(times[1], times[0]);
        ratios.pyramid_lod_auto_over_pom16_today = ratio(times[4], times[0]);
        let mut header: Vec<&str> = columns.iter().map(|(n, _)| *n).collect();
        header.extend(["pyramid / pom-16", "lod-auto / pom-16"]);
        let mut t = Table::new(
            format!("Today's frame: {w}x{h}, tiles 1024^2, 60 deg, GPU ms"),
            &header,
        );
        let mut row: Vec<String> = times.iter().map(|&t| ms(t)).collect();
        for k in [1, 4] {
            row.push(ratio_text(ratio(times[k], times[0])));
        }
        t.row(row);
        tables.push(t);
    }

    // Accuracy against the ground truth by view angle, every method, every map.
    progress("accuracy by view angle");
    let acc_size = if quick { 128 } else { 256 };
    let angles: &[f32] = if quick {
        &[0.0, 45.0, 70.0, 85.0]
    } else {
        &[0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 75.0, 80.0, 85.0]
    };
    let candidates = [
        Settings {
            method: Method::Pyramid,
            ..Default::default()
        },
        Settings {
            method: Method::PyramidAscend,
            ..Default::default()
        },
        Settings {
            method: Method::PyramidBilinear,
            ..Default::default()
        },
        bevy_pom(),
        threejs_relief(),
        Settings {
            method: Method::Parallax,
            ..Default::default()
        },
        Settings {
            method: Method::Bump,
            ..Default::default()
        },
    ];
    let label = |s: &Settings| match s.method {
        Method::Pom | Method::Relief => format!("{} {}-{}", s.method, s.layers.0, s.layers.1),
        m => m.to_string(),
    };
    let mut accuracy = Vec::new();
    for b in &BUNDLED {
        let map = b.load()?;
        let mut r = Renderer::new(gpu, &map, None, b.surface);
        let mut columns = vec!["method".to_string()];
        columns.extend(angles.iter().map(|a| format!("{a:.0} deg")));
        let mut table = Table {
            title: format!(
                "Wrong-hit fraction by view angle: {} ({}^2, {acc_size}x{acc_size})",
                b.name,
                map.size()
            ),
            columns,
            rows: vec![],
        };
        let mut series = Vec::new();
        for c in &candidates {
            let mut row = vec![label(c)];
            let mut points = Vec::new();
            for &angle in angles {
                let s = Settings {
                    view_angle_deg: angle,
                    width: acc_size,
                    height: acc_size,
                    ..c.clone()
                };
                let frame = r.render(gpu, &s)?;
                let acc = Accuracy::measure(&frame, &map, addressing(b), c.method.truth());
                let cost = Cost::of(&frame);
                row.push(format!("{:.4}", acc.wrong_hit_fraction));
                points.push((f64::from(angle), acc.wrong_hit_fraction));
                accuracy.push(AccuracyRow {
                    map: b.name.into(),
                    method: label(c),
                    view_angle_deg: angle,
                    wrong_hit_fraction: acc.wrong_hit_fraction,
                    mean_error_texels: acc.mean_error_texels,
                    covered: acc.covered,
                    mean_iterations: cost.mean_iterations,
                    iteration_cap_hits: cost.iteration_cap_hits,
                });
            }
            table.row(row);
            series.push(Series {
                name: label(c),
                points,
            });
        }
        tables.push(table);
        line_plot(
            &out.join(format!("accuracy_{}.svg", b.name)),
            &PlotSpec {
                title: &format!("Wrong hits by view angle: {}", b.name),
                x_label: "view angle (degrees from the normal)",
                y_label: "wrong-hit fraction",
                log_x: false,
                log_y: false,
            },
            &series,
        )?;
    }

    // How many POM layers match the pyramid on the sharp map at a grazing angle, and at what cost.
    progress("POM layers to match the pyramid");
    {
        let map = resized(&tiles, 256);
        let mut r = Renderer::new(gpu, &map, None, BUNDLED[0].surface);
        let grazing = |s: Settings| Settings {
            width: paper,
            height: paper,
            view_angle_deg: 80.0,
            ..s
        };
        let measure = |r: &mut Renderer, s: &Settings| -> Result<f64, DisplaceError> {
            let frame = r.render(gpu, s)?;
            Ok(
                Accuracy::measure(&frame, &map, Addressing::Wrap, s.method.truth())
                    .wrong_hit_fraction,
            )
        };
        let pyramid_settings = grazing(fixed_layers(Method::Pyramid, 16));
        let pyramid_wrong = measure(&mut r, &pyramid_settings)?;
        let pyramid_time = bench.time("pom-match", "tiles", &map, &mut r, &pyramid_settings)?;
        let target = pyramid_wrong.max(0.001);
        let mut t = Table::new(
            format!(
                "POM layers vs accuracy and time (tiles 256^2, {paper}x{paper}, 80 deg); pyramid: {pyramid_wrong:.4} wrong, {} ms",
                ms(pyramid_time)
            ),
            &[
                "layers",
                "wrong-hit fraction",
                "GPU ms",
                "pom / pyramid time",
            ],
        );
        let mut points = Vec::new();
        for layers in [16, 32, 64, 128, 256, 512, 1024, 2048, 4096] {
            let s = grazing(fixed_layers(Method::Pom, layers));
            let wrong = measure(&mut r, &s)?;
            let time = bench.time("pom-match", "tiles", &map, &mut r, &s)?;
            points.push((f64::from(layers), wrong));
            t.row(vec![
                layers.to_string(),
                format!("{wrong:.4}"),
                ms(time),
                ratio_text(ratio(time, pyramid_time)),
            ]);
            ratios.pom_most_layers = Some((layers, wrong, ratio(time, pyramid_time)));
            if wrong <= target {
                ratios.pom_layers_to_match = Some(layers);
                ratios.pom_matched_over_pyramid = ratio(time, pyramid_time);
                break;
            }
        }
        tables.push(t);
        line_plot(
            &out.join("pom_layers.svg"),
            &PlotSpec {
                title: "POM wrong hits by layer count (tiles, 80 deg)",
                x_label: "layers",
                y_label: "wrong-hit fraction",
                log_x: true,
                log_y: false,
            },
            &[
                Series {
                    name: "pom".into(),
                    points,
                },
                Series {
                    name: "pyramid".into(),
                    points: vec![(16.0, pyramid_wrong), (1024.0, pyramid_wrong)],
                },
            ],
        )?;
    }

    let results = Results {
        adapter: gpu.describe(),
        software_rasterizer: gpu.is_software(),
        quick,
        frames,
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
